"""liemid beam against Exudyn on Simo & Vu-Quoc's right-angle cantilever, the frame `liemid beam`
runs by default: legs of length 10 from (0, 10, 0) (clamped) to the elbow (10, 10, 0) and the
tip (10, 0, 0), EA = 1e6, GJ = EI = 1e3, rho A = 1, I_rho = diag(20, 10, 10), 8 elements per
leg, elbow force F_z rising to 50 at t = 1 and gone at t = 2, t_end = 30.

Exudyn builds it from its geometrically exact 3-D beam (ObjectBeamGeometricallyExact: two
rigid-body nodes, SE(3) interpolation, lumped mass like liemid's). That element is shear
deformable; it gets Simo & Vu-Quoc's shear stiffness GA = 1e6 (liemid's corotational element
is Euler-Bernoulli: no shear). Its strain is measured from a straight reference with the node
frames along the axis, so the elbow has one node per leg; they are tied by a GenericJoint (the
root by a GenericJoint to the ground).

Implicit: Exudyn's default generalized-alpha (spectral radius 0.9, modified Newton) with the
sparse solver (EigenSparse), one thread, on Euler-parameter nodes (NodeRigidBodyEP, as
Exudyn's own geometricallyExactBeamTest), Newton's relative tolerance 1e-6. Why the earlier
runs at h <= 0.05 did not finish: on rotation-vector Lie-group nodes (NodeRigidBodyRotVecLG)
the element's Newton converges only linearly (contraction 0.78 to 0.85 per iteration even
with a fresh Jacobian every iteration, also on one straight leg without joints), the default
tolerance 1e-8 is not reached in 25 iterations, the step is rejected and halved, and the
halved steps converge no better, down towards the minimum step. On Euler-parameter nodes a
fresh Jacobian converges in 3 iterations; at 16 and 32 elements per leg the residual's floor
is near 1e-8 of the first residual, hence 1e-6.

Explicit: Exudyn's explicit integrators refuse joints ("object ... contains constraints that
cannot be solved") and Euler-parameter nodes ("node ... contains algebraic variables"),
so they run on Lie-group nodes with the root held by CoordinateConstraints (which they
eliminate) and the elbow tied by a stiff RigidBodySpringDamper (2e6 on the relative
displacement and rotation; with generalized-alpha this penalty elbow moves the elbow at t = 3
by 1e-5 of its value against the joint). They refactorise the dense mass matrix at every stage (the
sparse solver reports it singular after the elimination), so they are timed on a short
horizon, t = 3, with all the others run on that horizon too. Measured: RK44 and VelocityVerlet
agree with each other to 1e-6 but converge to a motion 6.6 % (of the maximum) away from
Exudyn's own generalized-alpha and from liemid; on one straight clamped leg with the same
force at its end they give u_z = 7.763 at t = 2 where generalized-alpha gives 8.017 and
liemid 8.015, so the difference is in Exudyn's explicit path for this element.

Printed: (1) the elbow and tip histories of the two codes' fine runs against each other,
relative to liemid's maxima (acceptance: 2 %), at 8, 16 and 32 elements per leg (the element
formulations differ: the gap is spatial and shrinks 4x per refinement); (2) for t = 30 and (3)
for t = 3, at 8 elements per leg: liemid's explicit splitting (`liemid beam` default),
liemid's Newmark and Exudyn's integrators at a sequence of steps, with the CPU time of the
process (children's rusage for liemid) and the error of the elbow history against the same
code's fine reference (liemid: liemid4 at 0.2 of its critical step; Exudyn: generalized-alpha
at h = 0.003125) and against liemid's; then the CPU time each needs for 1 % and 0.1 %
(log-log interpolation). One thread each.

Installs nothing: needs the `exudyn` package (pip install exudyn numpy) and a built liemid
(`cargo build --release -p liemid-cli`, or LIEMID=/path/to/liemid); skips with a message
when either is missing. `--plot FILE.png` draws both codes' elbow and tip histories
(needs matplotlib).

    python benchmarks/vs_exudyn.py [--quick] [--elements-per-leg N] [--plot docs/vs-exudyn.png]
"""

from __future__ import annotations

import json
import math
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

try:
    import numpy as np
except ImportError:
    print("vs_exudyn: numpy is not installed; skipping")
    sys.exit(0)
try:
    import exudyn as exu
    from exudyn.itemInterface import (
        CoordinateConstraint,
        Force,
        GenericJoint,
        MarkerBodyRigid,
        MarkerNodeCoordinate,
        MarkerNodeRigid,
        NodePointGround,
        NodeRigidBodyEP,
        NodeRigidBodyRotVecLG,
        ObjectBeamGeometricallyExact,
        ObjectGround,
        RigidBodySpringDamper,
        SensorNode,
    )
    from exudyn.rigidBodyUtilities import RotationMatrix2EulerParameters, RotationMatrix2RotationVector
except ImportError:
    print("vs_exudyn: the exudyn package is not installed (pip install exudyn); skipping")
    sys.exit(0)

warnings.filterwarnings("ignore", category=DeprecationWarning)
ROOT = Path(__file__).resolve().parent.parent
LIEMID = os.environ.get("LIEMID") or str(ROOT / "target" / "release" / "liemid")
if not (Path(LIEMID).exists() or shutil.which(LIEMID)):
    print(f"vs_exudyn: no liemid binary at {LIEMID} (cargo build --release -p liemid-cli); skipping")
    sys.exit(0)

QUICK = "--quick" in sys.argv
PLOT = sys.argv[sys.argv.index("--plot") + 1] if "--plot" in sys.argv else None
PER_LEG = 8
if "--elements-per-leg" in sys.argv:
    PER_LEG = int(sys.argv[sys.argv.index("--elements-per-leg") + 1])
T_END, T_SHORT, SAMPLE = 30.0, 3.0, 0.05
EA, GA, GJ, EI, RHO_A = 1e6, 1e6, 1e3, 1e3, 1.0
ROTARY = (20.0, 10.0, 10.0)
PENALTY = 2e6
EXUDYN_REF = 0.0125 if QUICK else 0.003125


def load(t: float) -> float:
    return 50.0 * t if t < 1.0 else (50.0 * (2.0 - t) if t < 2.0 else 0.0)


def exudyn_run(h: float, t_end: float, explicit: str = "") -> tuple[float, dict, str]:
    """One Exudyn run: CPU seconds, the elbow and tip displacements on the sample grid (rows
    t, ux, uy, uz) and a note on the solver's work. Implicit: generalized-alpha on
    Euler-parameter nodes with joints; explicit: RK44 on Lie-group nodes with the penalty
    elbow."""
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    sec = exu.BeamSection()
    sec.stiffnessMatrix = np.diag([EA, GA, GA, GJ, EI, EI])
    sec.inertia = np.diag(ROTARY)
    sec.massPerLength = RHO_A
    root, elbow, tip = np.array([0, 10, 0.0]), np.array([10, 10, 0.0]), np.array([10, 0, 0.0])
    legs = []
    for a, b in [(root, elbow), (elbow, tip)]:
        ex = (b - a) / np.linalg.norm(b - a)
        ez = np.array([0, 0, 1.0])
        rot = np.column_stack([ex, np.cross(ez, ex), ez])
        if explicit:
            node, rp = NodeRigidBodyRotVecLG, list(RotationMatrix2RotationVector(rot))
        else:
            node, rp = NodeRigidBodyEP, list(RotationMatrix2EulerParameters(rot))
        nodes = [
            mbs.AddNode(node(referenceCoordinates=list(a + (b - a) * k / PER_LEG) + rp)) for k in range(PER_LEG + 1)
        ]
        for k in range(PER_LEG):
            mbs.AddObject(
                ObjectBeamGeometricallyExact(
                    nodeNumbers=[nodes[k], nodes[k + 1]], physicsLength=10.0 / PER_LEG, sectionData=sec
                )
            )
        legs.append((nodes, rot))
    if explicit:
        ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
        mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
        for c in range(6):
            m = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=legs[0][0][0], coordinate=c))
            mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, m]))
    else:
        ground = mbs.AddObject(ObjectGround())
        mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=list(root)))
        m0 = mbs.AddMarker(MarkerNodeRigid(nodeNumber=legs[0][0][0]))
        mbs.AddObject(GenericJoint(markerNumbers=[mg, m0], constrainedAxes=[1] * 6))
    e1, e2 = legs[0][0][-1], legs[1][0][0]
    m1 = mbs.AddMarker(MarkerNodeRigid(nodeNumber=e1))
    m2 = mbs.AddMarker(MarkerNodeRigid(nodeNumber=e2))
    if explicit:
        mbs.AddObject(
            RigidBodySpringDamper(
                markerNumbers=[m1, m2],
                stiffness=np.diag([PENALTY] * 6),
                rotationMarker0=np.eye(3),
                rotationMarker1=legs[1][1].T,
            )
        )
    else:
        mbs.AddObject(
            GenericJoint(
                markerNumbers=[m1, m2], constrainedAxes=[1] * 6, rotationMarker0=np.eye(3), rotationMarker1=legs[1][1].T
            )
        )
    mbs.AddLoad(Force(markerNumber=m1, loadVector=[0, 0, 0], loadVectorUserFunction=lambda mbs, t, v: [0, 0, load(t)]))
    sensors = {
        name: mbs.AddSensor(
            SensorNode(
                nodeNumber=n,
                storeInternal=True,
                writeToFile=False,
                outputVariableType=exu.OutputVariableType.Displacement,
            )
        )
        for name, n in (("elbow", e1), ("tip", legs[1][0][-1]))
    }
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.timeIntegration.numberOfSteps = int(round(t_end / h))
    s.timeIntegration.endTime = t_end
    s.timeIntegration.verboseMode = 0
    # 1e-6 of the first residual: the default 1e-8 is below the residual's round-off floor at 16
    # elements per leg (Newton stalls near 1e-8 there and the step is halved without end); at 8
    # per leg it changes the elbow history by 2e-7 of its maximum and saves a fifth of the CPU.
    s.timeIntegration.newton.relativeTolerance = 1e-6
    s.solution.file.write = False
    s.solution.sensors.writePeriod = SAMPLE
    s.parallel.numberOfThreads = 1
    s.linearSolver.solverType = exu.LinearSolverType.EXUdense if explicit else exu.LinearSolverType.EigenSparse
    solver = getattr(exu.DynamicSolverType, explicit or "GeneralizedAlpha")
    start = time.process_time()
    try:
        mbs.SolveDynamic(s, solverType=solver)
    except (exu.SolverError, RuntimeError) as e:
        return time.process_time() - start, {}, f"failed: {e}"
    cpu = time.process_time() - start
    it = mbs.sys["dynamicSolver"].it
    steps = max(it.currentStepIndex - 1, 1)
    note = "" if explicit else f"{it.newtonStepsCount / steps:.1f} Newton it./step, {it.newtonJacobiCount} Jacobians"
    hist = {k: np.array(mbs.GetSensorStoredData(v)) for k, v in sensors.items()}
    if any(not np.all(np.isfinite(a)) for a in hist.values()):
        return cpu, {}, "unstable (NaN)"
    return cpu, hist, note


def liemid_run(method: str, h: float, t_end: float) -> tuple[float, dict]:
    """`liemid beam` at step h: CPU seconds of the process and the histories."""
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "run.json"
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        cmd = [LIEMID, "beam", "--elements-per-member", str(PER_LEG), "--method", method, "--step", repr(h)]
        cmd += ["--t-end", repr(t_end), "--sample", repr(SAMPLE), "--threads", "1", "--force-step", "--json", str(out)]
        subprocess.run(cmd, check=True, capture_output=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        run = json.loads(out.read_text())
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    hist = {}
    for name in ("elbow", "tip"):
        tr = run["tracked"][name]
        hist[name] = np.column_stack([np.array(tr["t"]), np.array(tr["u"])])
    return cpu, hist


def on_grid(a: np.ndarray) -> dict[int, np.ndarray]:
    return {int(round(row[0] / SAMPLE)): row[1:4] for row in a}


def difference(a: np.ndarray, ref: np.ndarray) -> float:
    """max_t |u - u_ref| / max_t |u_ref| over the samples both have."""
    ga, gr = on_grid(a), on_grid(ref)
    scale = max(np.linalg.norm(v) for v in gr.values())
    common = sorted(set(ga) & set(gr))
    return max(np.linalg.norm(ga[k] - gr[k]) for k in common) / scale


def time_to(points: list[tuple[float, float]], target: float) -> str:
    """CPU time to reach `target` along the runs ordered by cost (log-log interpolation
    between the last run above and the first below)."""
    p = sorted(points)
    if not p:
        return "-"
    if p[0][1] <= target:
        return f"<= {p[0][0]:.3f} s (cheapest run already below)"
    for (ca, ea), (cb, eb) in zip(p, p[1:]):
        if ea > target >= eb:
            f = (math.log(target) - math.log(ea)) / (math.log(eb) - math.log(ea))
            return f"{math.exp(math.log(ca) + f * (math.log(cb) - math.log(ca))):.3f} s"
    return "not reached"


def work_precision(t_end: float, critical: float, explicit_exudyn: bool) -> None:
    """Every code at a sequence of steps on [0, t_end]; returns the fine references."""

    def grid_step(h: float) -> float:
        return SAMPLE / math.ceil(SAMPLE / h)

    # References: each code's own fine run; liemid4's critical step is 1.57x the splitting's.
    _, ref_l = liemid_run("liemid4", grid_step(0.2 * 1.5708 * critical), t_end)
    cpu_x, ref_x, note_x = exudyn_run(EXUDYN_REF, t_end)
    print(f"{'code':7s} {'method':18s} {'step':>10s} {'CPU s':>8s} {'error':>9s} {'vs liemid':>9s}  notes")
    cross_x = difference(ref_x["elbow"], ref_l["elbow"])
    print(f"exudyn  {'gen.-alpha (ref)':18s} {EXUDYN_REF:10.4e} {cpu_x:8.3f} {'':9s} {cross_x:9.2e}  {note_x}")
    runs: dict[str, list[tuple[float, float]]] = {}

    def record(code: str, method: str, h: float, cpu: float, hist: dict, ref: dict, note: str = "") -> None:
        if not hist:
            print(f"{code:7s} {method:18s} {h:10.4e} {cpu:8.3f}  {note}", flush=True)
            return
        e = difference(hist["elbow"], ref["elbow"])
        cross = difference(hist["elbow"], ref_l["elbow"])
        runs.setdefault(f"{code} {method}", []).append((cpu, e))
        print(f"{code:7s} {method:18s} {h:10.4e} {cpu:8.3f} {e:9.2e} {cross:9.2e}  {note}", flush=True)

    for f in (0.9, 0.45):
        h = grid_step(f * critical)
        cpu, hist = liemid_run("liemid", h, t_end)
        record("liemid", "explicit", h, cpu, hist, ref_l, f"{f} of critical")
    for h in (0.1, 0.05, 0.025) if QUICK else (0.1, 0.05, 0.025, 0.0125):
        try:
            cpu, hist = liemid_run("newmark", h, t_end)
        except subprocess.CalledProcessError:
            print(f"liemid  newmark            {h:10.4e}   (Newton did not converge)")
            continue
        record("liemid", "newmark", h, cpu, hist, ref_l)
    for h in (0.1, 0.05) if QUICK else (0.1, 0.05, 0.025, 0.0125, 0.00625):
        cpu, hist, note = exudyn_run(h, t_end)
        record("exudyn", "gen.-alpha", h, cpu, hist, ref_x, note)
    if explicit_exudyn:
        for method in ("VelocityVerlet", "RK44"):
            prev: dict = {}
            for h in (5e-4, 2.5e-4):
                cpu, hist, note = exudyn_run(h, t_end, explicit=method)
                record("exudyn", method, h, cpu, hist, ref_x, note)
                if hist and h == 2.5e-4 and prev:
                    d = difference(prev["elbow"], hist["elbow"])
                    print(f"        ({method} h = 5e-4 against h = 2.5e-4: {d:.2e})")
                prev = hist
    print()
    for target in (1e-2, 1e-3):
        for key, pts in runs.items():
            print(f"CPU time to {target:.0e}: {key:20s} {time_to(pts, target)}")


def critical_step() -> float:
    """liemid's critical step (splitting) on the frame, from a short run's summary."""
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "s.json"
        subprocess.run(
            [LIEMID, "beam", "--elements-per-member", str(PER_LEG), "--t-end", "0.01", "--json", str(out)],
            check=True,
            capture_output=True,
        )
        return json.loads(out.read_text())["critical_step"]


def main() -> None:
    global PER_LEG
    print(f"right-angle cantilever, t = {T_END}; Exudyn {exu.__version__} (generalized-alpha: Euler-parameter")
    print("nodes, EigenSparse, modified Newton, relative tolerance 1e-6, spectral radius 0.9, 1 thread)")
    print("error: elbow history against the code's own fine reference; vs liemid: against liemid's;")
    print("both max_t |u - u_ref| / max_t |u_ref|")
    print()
    print(f"(1) the two codes' histories, difference relative to liemid's maximum (Exudyn generalized-alpha")
    print("    at h = 0.0125, liemid4 at 0.2 of its critical step), by elements per leg:")
    base, plot_runs = PER_LEG, {}
    # The sweep only from the default 8 per leg (at 32 per leg it would run 128).
    for n in (base,) if QUICK or base != 8 else (base, 2 * base, 4 * base):
        PER_LEG = n
        crit = critical_step()
        _, rl = liemid_run("liemid4", SAMPLE / math.ceil(SAMPLE / (0.2 * 1.5708 * crit)), T_END)
        cpu, rx, note = exudyn_run(0.0125, T_END)
        if not rx:
            print(f"    {n:3d} per leg: Exudyn {note}")
            continue
        parts = []
        for name in ("elbow", "tip"):
            peak = max(np.linalg.norm(v) for v in on_grid(rl[name]).values())
            parts.append(f"{name} {100 * difference(rx[name], rl[name]):5.2f} % of {peak:.3f}")
        print(f"    {n:3d} per leg: {', '.join(parts)}   (Exudyn {cpu:.2f} s CPU, {note})", flush=True)
        plot_runs[n] = (rl, rx)
    PER_LEG = base
    critical = critical_step()
    print()
    print(f"(2) t = {T_END}, {PER_LEG} elements per leg; liemid's critical step {critical:.4e}")
    work_precision(T_END, critical, explicit_exudyn=False)
    print()
    print(f"(3) t = {T_SHORT}, {PER_LEG} elements per leg (Exudyn's explicit runs refactorise the dense mass")
    print("    matrix at every stage, too slow for t = 30; its explicit rows use the penalty elbow)")
    if PER_LEG > 8:
        print("    (Exudyn's explicit rows skipped above 8 elements per leg: their dense mass matrix)")
    work_precision(T_SHORT, critical, explicit_exudyn=PER_LEG <= 8)
    print()
    print("(process CPU times on a shared 2-core machine under load; liemid's include process start-up)")
    if PLOT and plot_runs:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        shown = sorted({min(plot_runs), max(plot_runs)})
        fig, axes = plt.subplots(len(shown), 1, figsize=(8, 3.6 * len(shown)), sharex=True, squeeze=False)
        for ax, n in zip(axes[:, 0], shown):
            ref_l, ref_x = plot_runs[n]
            for name, c in (("elbow", "C0"), ("tip", "C1")):
                a, b = ref_l[name], ref_x[name]
                ax.plot(a[:, 0], a[:, 3], c, lw=1.5, label=f"{name} u_z, liemid")
                ax.plot(b[:, 0], b[:, 3], c + "--", lw=1.2, label=f"{name} u_z, Exudyn")
            ax.set_ylabel("out-of-plane displacement")
            ax.set_title(f"right-angle cantilever, {n} elements per leg", fontsize=10)
            ax.legend(fontsize=8, ncol=2)
        axes[-1, 0].set_xlabel("t")
        fig.tight_layout()
        fig.savefig(PLOT, dpi=100)

if __name__ == "__main__":
    main()
