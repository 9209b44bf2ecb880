"""liemid beam against Exudyn on Simo & Vu-Quoc's right-angle cantilever, the frame `liemid beam`
runs by default: legs of length 10 from (0, 10, 0) (clamped) to the elbow (10, 10, 0) and the
tip (10, 0, 0), EA = GA = 1e6, GJ = EI = 1e3, rho A = 1, I_rho = diag(20, 10, 10), 8 elements
per leg, elbow force F_z rising to 50 at t = 1 and gone at t = 2, t_end = 30.

Exudyn builds it from its geometrically exact 3-D beam (ObjectBeamGeometricallyExact: two
rigid-body nodes, SE(3) interpolation, shear deformable with GA = 1e6, lumped mass like
liemid's) on NodeRigidBodyRotVecLG nodes. Its element takes the node frames as the section
frames, so the elbow has one node per leg tied by a GenericJoint; the root is held by six
CoordinateConstraints. It runs with its default implicit integrator (generalized-alpha,
spectral radius 0.9, modified Newton). Its explicit integrators (RK44, ...) refuse the
elbow's joint ("explicit integrator detected object ... which contains constraints that
cannot be solved"), so there is no Exudyn explicit row.

Printed: (1) the elbow and tip displacement histories of the two codes' finest runs against
each other, relative to their maxima (acceptance: 2 %); (2) for liemid's explicit splitting
(`liemid`, `liemid-mts`), liemid's Newmark (exact tangent) and Exudyn's generalized-alpha at
a sequence of steps: the CPU time of the process (children's rusage for liemid) and the
error of the elbow history against the same code's fine reference (liemid: liemid4 at 0.2
of its critical step; Exudyn: generalized-alpha at h = 0.003125, 0.0125 with --quick); then the CPU time each
needs for 1 % and 0.1 % (log-log interpolation). One thread each.

Installs nothing: needs the `exudyn` package (pip install exudyn numpy) and a built liemid
(`cargo build --release -p liemid-cli`, or LIEMID=/path/to/liemid); skips with a message
when either is missing.

    python benchmarks/vs_exudyn.py [--quick] [--elements-per-leg N]
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
        MarkerNodeCoordinate,
        MarkerNodeRigid,
        NodePointGround,
        NodeRigidBodyRotVecLG,
        ObjectBeamGeometricallyExact,
        SensorNode,
    )
    from exudyn.rigidBodyUtilities import RotationMatrix2RotationVector
except ImportError:
    print("vs_exudyn: the exudyn package is not installed (pip install exudyn); skipping")
    sys.exit(0)

ROOT = Path(__file__).resolve().parent.parent
LIEMID = os.environ.get("LIEMID") or str(ROOT / "target" / "release" / "liemid")
if not (Path(LIEMID).exists() or shutil.which(LIEMID)):
    print(f"vs_exudyn: no liemid binary at {LIEMID} (cargo build --release -p liemid-cli); skipping")
    sys.exit(0)

QUICK = "--quick" in sys.argv
PER_LEG = 8
if "--elements-per-leg" in sys.argv:
    PER_LEG = int(sys.argv[sys.argv.index("--elements-per-leg") + 1])
T_END, SAMPLE = 30.0, 0.05
EA, GA, GJ, EI, RHO_A = 1e6, 1e6, 1e3, 1e3, 1.0
ROTARY = (20.0, 10.0, 10.0)


def load(t: float) -> float:
    return 50.0 * t if t < 1.0 else (50.0 * (2.0 - t) if t < 2.0 else 0.0)


def exudyn_run(h: float) -> tuple[float, dict[str, np.ndarray]]:
    """Generalized-alpha at step h: CPU seconds and the elbow and tip displacements on the
    sample grid (rows t, ux, uy, uz)."""
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
        rv = list(RotationMatrix2RotationVector(rot))
        nodes = [
            mbs.AddNode(NodeRigidBodyRotVecLG(referenceCoordinates=list(a + (b - a) * k / PER_LEG) + rv))
            for k in range(PER_LEG + 1)
        ]
        for k in range(PER_LEG):
            mbs.AddObject(
                ObjectBeamGeometricallyExact(nodeNumbers=[nodes[k], nodes[k + 1]], length=10.0 / PER_LEG, sectionData=sec)
            )
        legs.append((nodes, rot))
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    for c in range(6):
        m = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=legs[0][0][0], coordinate=c))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, m]))
    e1, e2 = legs[0][0][-1], legs[1][0][0]
    m1 = mbs.AddMarker(MarkerNodeRigid(nodeNumber=e1))
    m2 = mbs.AddMarker(MarkerNodeRigid(nodeNumber=e2))
    mbs.AddObject(
        GenericJoint(
            markerNumbers=[m1, m2], constrainedAxes=[1] * 6, rotationMarker0=np.eye(3), rotationMarker1=legs[1][1].T
        )
    )
    mbs.AddLoad(Force(markerNumber=m1, loadVector=[0, 0, 0], loadVectorUserFunction=lambda mbs, t, v: [0, 0, load(t)]))
    sensors = {
        name: mbs.AddSensor(
            SensorNode(
                nodeNumber=n, storeInternal=True, writeToFile=False, outputVariableType=exu.OutputVariableType.Displacement
            )
        )
        for name, n in (("elbow", e1), ("tip", legs[1][0][-1]))
    }
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.timeIntegration.numberOfSteps = int(round(T_END / h))
    s.timeIntegration.endTime = T_END
    s.timeIntegration.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.writePeriod = SAMPLE
    start = time.process_time()
    mbs.SolveDynamic(s)
    cpu = time.process_time() - start
    return cpu, {k: np.array(mbs.GetSensorStoredData(v)) for k, v in sensors.items()}


def liemid_run(method: str, h: float) -> tuple[float, dict[str, np.ndarray]]:
    """`liemid beam` at step h: CPU seconds of the process and the histories."""
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "run.json"
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        cmd = [LIEMID, "beam", "--elements-per-member", str(PER_LEG), "--method", method, "--step", repr(h)]
        cmd += ["--sample", repr(SAMPLE), "--threads", "1", "--force-step", "--json", str(out)]
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
    """CPU time to reach `target` (log-log interpolation between neighbouring points)."""
    p = sorted(points)
    if not p:
        return "-"
    if p[0][1] <= target:
        return f"<= {p[0][0]:.3f} s (cheapest point already below)"
    for (ca, ea), (cb, eb) in zip(p, p[1:]):
        if ea > target >= eb:
            f = (math.log(target) - math.log(ea)) / (math.log(eb) - math.log(ea))
            return f"{math.exp(math.log(ca) + f * (math.log(cb) - math.log(ca))):.3f} s"
    return "not reached"


def main() -> None:
    print(f"right-angle cantilever, {PER_LEG} elements per leg, t = {T_END}; Exudyn {exu.__version__}")
    # Critical steps of liemid's explicit methods on this frame (from a 1-step run's summary).
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "s.json"
        subprocess.run(
            [LIEMID, "beam", "--elements-per-member", str(PER_LEG), "--t-end", "0.01", "--json", str(out)],
            check=True,
            capture_output=True,
        )
        critical = json.loads(out.read_text())["critical_step"]
    print(f"liemid's critical step (splitting): {critical:.4e}")

    def grid_step(h: float) -> float:
        return SAMPLE / math.ceil(SAMPLE / h)

    # References: each code's own fine run; liemid4's critical step is 1.57x the splitting's.
    _, ref_l = liemid_run("liemid4", grid_step(0.2 * 1.5708 * critical))
    _, ref_x = exudyn_run(0.0125 if QUICK else 0.003125)
    print()
    print("(1) the two codes' histories (their fine runs), difference relative to the maximum:")
    for name in ("elbow", "tip"):
        d = difference(ref_x[name], ref_l[name])
        peak = max(np.linalg.norm(v) for v in on_grid(ref_l[name]).values())
        print(f"    {name:5s}: {100 * d:.2f} % of {peak:.3f}")
    print()
    print("(2) CPU time against the error of the elbow history (each against its own reference)")
    print(f"{'code':8s} {'method':18s} {'step':>10s} {'CPU s':>8s} {'error':>10s}")
    runs: dict[str, list[tuple[float, float]]] = {}

    def record(code: str, method: str, h: float, cpu: float, hist: dict, ref: dict) -> None:
        e = difference(hist["elbow"], ref["elbow"])
        runs.setdefault(f"{code} {method}", []).append((cpu, e))
        print(f"{code:8s} {method:18s} {h:10.4e} {cpu:8.3f} {e:10.3e}", flush=True)

    for method, fractions in (("liemid", (0.9, 0.45)), ("liemid-mts", (1.0,))):
        for f in fractions:
            # liemid-mts: 0.9 of its critical step pi/omega_axial = (pi/2) x the splitting's.
            h = grid_step(f * critical * (1.0 if method == "liemid" else 0.9 * math.pi / 2))
            cpu, hist = liemid_run(method, h)
            record("liemid", method, h, cpu, hist, ref_l)
    for h in (0.1, 0.05, 0.025) if QUICK else (0.2, 0.1, 0.05, 0.025, 0.0125):
        try:
            cpu, hist = liemid_run("newmark", h)
        except subprocess.CalledProcessError:
            print(f"liemid   newmark            {h:10.4e}   (Newton did not converge)")
            continue
        record("liemid", "newmark", h, cpu, hist, ref_l)
    for h in (0.1, 0.05) if QUICK else (0.1, 0.05, 0.025, 0.0125):
        cpu, hist = exudyn_run(h)
        record("exudyn", "generalized-alpha", h, cpu, hist, ref_x)
    print()
    for target in (1e-2, 1e-3):
        for key, pts in runs.items():
            print(f"CPU time to {target:.0e}: {key:26s} {time_to(pts, target)}")
    print("(CPU times of a shared 2-core machine under load; liemid's include process start-up)")


if __name__ == "__main__":
    main()
