#!/usr/bin/env python3
"""liemid's multibody methods against MuJoCo 4.0 on published-style robots (issue 43, item 4).

The models are benchmarks/models/robot_*.xml, inertials only, written after MuJoCo
Menagerie's files (link frames, masses, inertias, joint axes): a Panda-style 7-joint arm
(fixed base, a welded hand, two finger slides: 11 bodies), an H1-style humanoid (free
pelvis, 19 hinges: 20 bodies), a Spot-style quadruped (free body, 12 hinges: 13 bodies) and
an X2-style quadrotor (free frame, four propellers on hinges: 5 bodies; also run with its
propellers still, a variant written to a temporary directory). No geoms (no
contacts), no actuators, no armature, damping, friction or limits: both codes read the same
file and integrate the same equations, gravity only, from the file's keyframe (which gives
every joint a velocity) to t = 0.5 s.

Reference: MuJoCo's RK4 at h = 1e-5 (checked against h = 2e-5, printed). Error: the largest
distance, over the bodies, between a run's final body frame origin (MuJoCo's `xpos`, the
command's `final[].xpos`) and the reference's, in metres. CPU: MuJoCo's
`mj_step(m, d, nstep=N)` by `time.process_time`; liemid's the command's own timer of its
stepping loop (`stepping_seconds` of `liemid multibody FILE --method M --step H --t-end T
--json -`, wall-clock around the loop, so it includes no start-up or model reading; the
loop also evaluates energy and momenta every step, a few per cent of a step). Beside it is
printed the command's CPU (`getrusage(RUSAGE_CHILDREN)`) less the least CPU of the same
command run for one step, as benchmarks/vs_mujoco.py measures: on runs of a few
milliseconds that difference is noisier than the loop's own timer. Runs shorter than
SHORT_RUN seconds are repeated and the least time kept (both codes).

Printed per model: each method's runs (N, h, error, CPU), the CPU to 1e-4, 1e-6 and 1e-8 m
by log-log interpolation between the two runs that bracket the level, the best liemid
method and the ratio liemid best / MuJoCo RK4 (above 1: MuJoCo's RK4 is cheaper), and the
cost of one step at h = 1e-3 (liemid's CPU per step and per body-step, MuJoCo's per step and
per RK4 evaluation) beside liemid's chain-1000 per body-step.

The helpers of vs_mujoco.py are not imported: that script needs Pinocchio and SciPy at
import time (its reference) and exits without them; this one needs only MuJoCo and numpy.

Run:  python benchmarks/vs_mujoco_robots.py [--quick] [--plot FILE.png]   (LIEMID_BIN for the binary)
Writes docs/vs-mujoco-robots.txt (and the figure with --plot, e.g. docs/vs-mujoco-robots.png).
Peers: pip install mujoco==4.0.0 numpy (matplotlib for --plot), in a venv of your own.
"""

from __future__ import annotations

import csv
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "benchmarks" / "models"
DOCS = ROOT / "docs"
QUICK = "--quick" in sys.argv
PLOT = sys.argv[sys.argv.index("--plot") + 1] if "--plot" in sys.argv else None

try:
    import numpy as np
    import mujoco
except ImportError as e:  # pragma: no cover - the skip path
    print(f"vs_mujoco_robots: skipped, a peer is missing ({e}); pip install mujoco==4.0.0 numpy")
    sys.exit(0)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from liemid_binary import require_liemid  # noqa: E402

LIEMID = require_liemid("vs_mujoco_robots")

T_END = 0.5
LEVELS = (1e-4, 1e-6, 1e-8)
ROBOTS = [
    ("arm", "Panda-style arm", "robot_arm.xml"),
    ("humanoid", "H1-style humanoid", "robot_humanoid.xml"),
    ("quadruped", "Spot-style quadruped", "robot_quadruped.xml"),
    ("drone", "X2-style quadrotor", "robot_drone.xml"),
    # The same quadrotor with its propellers still (rotor rates 0 in the keyframe): what the
    # spinning propellers cost each code.
    ("drone-still", "quadrotor, rotors still", "robot_drone.xml:still"),
]
VARIANTS = {"still": ('150 -150 150 -150"', '0 0 0 0"')}
LIE_METHODS = ("liemid", "liemid4", "liemid6", "liemid8")
MJ_INTEGRATORS = ("rk4", "euler", "implicitfast")
# Stages per step of each liemid method, forward evaluations per MuJoCo RK4 step.
STAGES = {"liemid": 1, "liemid4": 5, "liemid6": 9, "liemid8": 17}
SHORT_RUN = 0.5  # CPU seconds: shorter runs are repeated
REPEATS = 2 if QUICK else 4  # more runs of a short case; the least CPU is kept
CPU_CAP = 1.0 if QUICK else float(os.environ.get("VS_MUJOCO_ROBOTS_CAP", "3"))

OUT: list[str] = []


def say(line=""):
    print(line, flush=True)
    OUT.append(line)


def geometric(n0, count, factor=2.0):
    return [int(round(n0 * factor**k)) for k in range(count)]


# Steps N over t = 0.5 for each method, refined until the error is below 1e-8 / 3 or a run
# costs more than CPU_CAP.
NS = {
    "liemid": geometric(50, 12),  # h = 1e-2 ... 4.9e-6
    "liemid4": geometric(10, 11),  # h = 5e-2 ... 4.9e-5
    "liemid6": [2] + geometric(5, 11),  # h = 0.25, then 0.1 ... 9.8e-5
    "liemid8": [2] + geometric(5, 11),
    "rk4": [2] + geometric(5, 14),  # h = 0.25, then 0.1 ... 1.2e-5
    "euler": geometric(250, 14),  # h = 2e-3 ... 2.4e-7
    "implicitfast": geometric(250, 14),
}


def load_average():
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


# ----------------------------------------------------------------------------------------
# MuJoCo.

INTEGRATORS = {"rk4": mujoco.mjtIntegrator.mjINT_RK4, "euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}


def mj_names(m):
    return [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(1, m.nbody)]


def mj_run(m, integ, n, t_end=T_END):
    """Final body frame origins (nbody-1, 3) and the CPU of the mj_step loop."""
    m.opt.integrator = INTEGRATORS[integ]
    m.opt.timestep = t_end / n
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    t0 = time.process_time()
    mujoco.mj_step(m, d, nstep=n)
    cpu = time.process_time() - t0
    mujoco.mj_kinematics(m, d)
    return np.array(d.xpos[1:]), cpu


# ----------------------------------------------------------------------------------------
# liemid through its command.


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def liemid_run(model, method, h, t_end):
    """(json summary or None, child CPU seconds, stderr)."""
    model = str(model)
    cmd = [LIEMID, "multibody"]
    cmd += ["--problem", model[1:]] if model.startswith(":") else [model]
    cmd += ["--method", method, "--step", repr(h), "--t-end", repr(t_end), "--json", "-"]
    c0 = child_cpu()
    r = subprocess.run(cmd, capture_output=True, text=True)
    cpu = child_cpu() - c0
    if r.returncode != 0:
        return None, cpu, r.stderr.strip()
    return json.loads(r.stdout), cpu, r.stderr.strip()


_BASE: dict = {}


def liemid_base(model, method):
    """CPU of the same command for one step: start-up and model reading."""
    key = (str(model), method)
    if key not in _BASE:
        _BASE[key] = min(liemid_run(model, method, 1e-5, 1e-5)[1] for _ in range(5))
    return _BASE[key]


def liemid_xpos(js, names):
    by = {b["name"]: b for b in js["final"]}
    return np.array([by[n]["xpos"] for n in names])


def liemid_start(path, names):
    """Body frame origins at t = 0, the first row of the command's trajectory."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "start.csv"
        subprocess.run([LIEMID, "multibody", str(path), "--step", "1e-3", "--t-end", "1e-3", "--every", "1",
                        "--out", str(out)], check=True, capture_output=True)
        with out.open() as f:
            rows = list(csv.reader(f))
    head, first = rows[0], rows[1]
    return np.array([[float(first[head.index(f"{n}.{a}")]) for a in "xyz"] for n in names])


def err(x, ref):
    return float(np.max(np.linalg.norm(x - ref, axis=1)))


# ----------------------------------------------------------------------------------------
# Work-precision.


def interp_cpu(points, level):
    """CPU at `level` by log-log interpolation between the two runs (sorted by CPU) that
    bracket it; (None, reason) when none do."""
    pts = sorted((c, e) for c, e, *_ in points if e > 0 and math.isfinite(e) and c > 0)
    for (c1, e1), (c2, e2) in zip(pts, pts[1:]):
        if (e1 - level) * (e2 - level) <= 0 and e1 != e2:
            s = (math.log(level) - math.log(e1)) / (math.log(e2) - math.log(e1))
            return math.exp(math.log(c1) + s * (math.log(c2) - math.log(c1))), ""
    if pts and pts[0][1] <= level:
        return pts[0][0], "<="  # reached by the cheapest run: an upper bound
    return None, "not reached"


def interp_steps(points, level):
    """Steps N at `level` by log-log interpolation between the two runs that bracket it."""
    pts = sorted((n, e) for _c, e, n, *_ in points if e > 0 and math.isfinite(e))
    for (n1, e1), (n2, e2) in zip(pts, pts[1:]):
        if (e1 - level) * (e2 - level) <= 0 and e1 != e2:
            s = (math.log(level) - math.log(e1)) / (math.log(e2) - math.log(e1))
            return math.exp(math.log(n1) + s * (math.log(n2) - math.log(n1)))
    return None


def sweep(label, runner, ns):
    """runner(n) -> (err, cpu, extra); (cpu, err, n, extra) per run."""
    pts = []
    for n in ns:
        e, c, extra = runner(n)
        pts.append((c, e, n, extra))
        note = f"  {extra}" if extra else ""
        say(f"    {label:<18} N = {n:>8d}  h = {T_END / n:.3e}  err = {e:.3e} m  cpu = {c:.4f} s{note}")
        if math.isfinite(e) and e < min(LEVELS) / 3:
            break
        if c > CPU_CAP:
            break
    return pts


def liemid_curve(path, names, ref, method):
    base = liemid_base(path, method)

    def runner(n):
        h = T_END / n
        js, cpu, errtxt = liemid_run(path, method, h, T_END)
        if js is None:
            why = errtxt.splitlines()[-1].replace(str(ROOT) + "/", "")[:100]
            return float("nan"), max(cpu - base, 1e-6), "failed: " + why
        wall = js["stepping_seconds"]
        for _ in range(REPEATS if wall < SHORT_RUN else 0):
            js2, c2, _ = liemid_run(path, method, h, T_END)
            if js2 is not None:
                cpu, wall = min(cpu, c2), min(wall, js2["stepping_seconds"])
        cpu = max(cpu - base, 1e-6)
        return err(liemid_xpos(js, names), ref), wall, f"({wall / n * 1e6:.1f} us/step; CPU less start-up {cpu:.4f} s)"

    return sweep(method, runner, NS[method])


def mujoco_curve(m, ref, integ):
    def runner(n):
        x, cpu = mj_run(m, integ, n)
        for _ in range(REPEATS if cpu < SHORT_RUN else 0):
            cpu = min(cpu, mj_run(m, integ, n)[1])
        e = err(x, ref)
        return (e if math.isfinite(e) else float("nan")), cpu, f"({cpu / n * 1e6:.2f} us/step)"

    return sweep("mujoco " + integ, runner, NS[integ])


def fmt_cpu(v):
    c, flag = v
    if c is None:
        return "-"
    return f"{flag}{c:.2e}"


def model_path(fname, tmp):
    """The model file, or a variant of it (`FILE:VARIANT`) written into `tmp`."""
    if ":" not in fname:
        return MODELS / fname
    name, kind = fname.split(":")
    text = (MODELS / name).read_text()
    a, b = VARIANTS[kind]
    assert text.count(a) == 1, (name, a)
    out = Path(tmp) / f"{kind}_{name}"
    out.write_text(text.replace(a, b))
    return out


def robot_case(key, title, fname, tmp):
    path = model_path(fname, tmp)
    m = mujoco.MjModel.from_xml_path(str(path))
    names = mj_names(m)
    say(f"\n== {title} ({fname}): {m.nbody - 1} bodies, nq {m.nq}, nv {m.nv}, t = {T_END} s, {load_average()}")
    ref, cpu_ref = mj_run(m, "rk4", round(T_END / 1e-5))
    chk, _ = mj_run(m, "rk4", round(T_END / 2e-5))
    say(f"  reference MuJoCo RK4 h = 1e-5 ({cpu_ref:.2f} s); against h = 2e-5: {err(chk, ref):.2e} m")
    js0, _, e0 = liemid_run(path, "liemid", 1e-3, 1e-3)
    if js0 is None:
        say(f"  liemid cannot run the model: {e0}")
        return None
    m.opt.timestep = 1e-3
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_kinematics(m, d)
    say(f"  start: the codes' body positions at t = 0 differ by"
        f" {err(liemid_start(path, names), np.array(d.xpos[1:])):.1e} m; ignored by liemid: {js0['ignored']}")
    curves = {}
    for meth in LIE_METHODS:
        curves[meth] = liemid_curve(path, names, ref, meth)
    for integ in MJ_INTEGRATORS:
        curves["mujoco-" + integ] = mujoco_curve(m, ref, integ)
    table = {}
    say(f"  CPU seconds to a final body-position error (t = {T_END}; '<=' reached at the coarsest run,"
        " '-' not reached within the runs):")
    say(f"    {'level (m)':<10}" + "".join(f"{k:>20}" for k in curves) + f"{'liemid best':>20}{'best/RK4':>10}")
    for level in LEVELS:
        row = {k: interp_cpu(pts, level) for k, pts in curves.items()}
        lie = [(row[k][0], k) for k in LIE_METHODS if row[k][0] is not None]
        best = min(lie) if lie else (None, "-")
        rk = row["mujoco-rk4"][0]
        ratio = f"{best[0] / rk:.2f}" if best[0] and rk else "-"
        table[level] = (best, rk, row)
        say(f"    {level:<10.0e}" + "".join(f"{fmt_cpu(row[k]):>20}" for k in curves)
            + f"{best[1] + (f' {best[0]:.2e}' if best[0] else ''):>20}{ratio:>10}")
    return {"title": title, "curves": curves, "table": table, "bodies": m.nbody - 1, "path": path, "m": m}


# ----------------------------------------------------------------------------------------
# Cost of one step.


def liemid_step_cost(path, method, h, steps, rounds):
    """Least stepping_seconds per step and least CPU (less start-up) per step over rounds."""
    base = liemid_base(path, method)
    cpus, walls = [], []
    for _ in range(rounds):
        js, cpu, errtxt = liemid_run(path, method, h, steps * h)
        if js is None:
            return None, None
        cpus.append((cpu - base) / steps)
        walls.append(js["stepping_seconds"] / steps)
    return min(walls), min(cpus)


def mujoco_step_cost(m, integ, h, steps, rounds):
    m.opt.integrator = INTEGRATORS[integ]
    m.opt.timestep = h
    best = float("inf")
    for _ in range(rounds):
        d = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, d, 0)
        mujoco.mj_forward(m, d)
        t0 = time.process_time()
        mujoco.mj_step(m, d, nstep=steps)
        best = min(best, (time.process_time() - t0) / steps)
    return best


def cost_table(results):
    rounds = 2 if QUICK else 5
    h = 1e-3
    steps = 100 if QUICK else 2000
    say(f"\nCost of one step at h = {h:g} ({steps} steps from the keyframe, least of {rounds};"
        f" liemid: its stepping_seconds, [CPU of the command less start-up]; {load_average()}):")
    say(f"  {'model':<22}{'bodies':>7}{'liemid us/step':>16}{'us/body-step':>14}{'[CPU us/body]':>16}"
        f"{'liemid4 us/step':>17}{'RK4 us/step':>13}{'us/RK4 eval':>13}{'Euler us/step':>15}")
    for r in results:
        c, w = liemid_step_cost(r["path"], "liemid", h, steps, rounds)
        c4, _ = liemid_step_cost(r["path"], "liemid4", h, steps // 5 if not QUICK else steps, rounds)
        rk = mujoco_step_cost(r["m"], "rk4", h, steps, rounds)
        eu = mujoco_step_cost(r["m"], "euler", h, steps, rounds)
        nb = r["bodies"]
        r["cost"] = (c, w, rk)
        say(f"  {r['title']:<22}{nb:>7}{c * 1e6:>16.2f}{c / nb * 1e6:>14.3f}{w / nb * 1e6:>16.3f}"
            f"{(c4 or float('nan')) * 1e6:>17.2f}{rk * 1e6:>13.2f}{rk / 4 * 1e6:>13.2f}{eu * 1e6:>15.2f}")
    n = 1000
    h_chain = 1e-4
    steps = 20 if QUICK else 500
    c, w = liemid_step_cost(":chain-1000", "liemid", h_chain, steps, rounds)
    say(f"  {'chain-1000 (h = 1e-4)':<22}{n:>7}{c * 1e6:>16.1f}{c / n * 1e6:>14.3f}{w / n * 1e6:>16.3f}")
    c3, w3 = liemid_step_cost(":chain-1000", "liemid", 1e-3, steps, rounds)
    if c3:
        say(f"  {'chain-1000 (h = 1e-3)':<22}{n:>7}{c3 * 1e6:>16.1f}{c3 / n * 1e6:>14.3f}{w3 / n * 1e6:>16.3f}")


def summary(results):
    say(f"\nSummary: CPU seconds to the final body-position error at t = {T_END} (liemid's best method;"
        " MuJoCo RK4; ratio liemid best / RK4, above 1 = RK4 cheaper):")
    say(f"  {'model':<22}" + "".join(f"{f'{lv:.0e} m':>38}" for lv in LEVELS))
    for r in results:
        cells = []
        for lv in LEVELS:
            (bc, bk), rk, _ = r["table"][lv]
            if bc and rk:
                cells.append(f"{bk} {bc:.2e} / {rk:.2e} = {bc / rk:.1f}")
            else:
                cells.append(f"{bk} {'-' if bc is None else f'{bc:.2e}'} / {'-' if rk is None else f'{rk:.2e}'}")
        say(f"  {r['title']:<22}" + "".join(f"{c:>38}" for c in cells))
    say("\nWhere the ratio comes from at 1e-8 m: steps to the level (log-log interpolation), a liemid"
        " stage (one RATTLE step: 1, 5, 9, 17 a step for liemid, liemid4, liemid6, liemid8) against a"
        " MuJoCo RK4 forward evaluation (4 a step):")
    for r in results:
        lv = 1e-8
        (bc, bk), rk, _ = r["table"][lv]
        n_rk = interp_steps(r["curves"]["mujoco-rk4"], lv)
        if not (bc and rk and n_rk) or bk not in STAGES:
            continue
        n_l = interp_steps(r["curves"][bk], lv)
        if not n_l:
            continue
        stages, evals = STAGES[bk] * n_l, 4 * n_rk
        say(f"  {r['title']:<22} {bk} {n_l:.0f} steps (h = {T_END / n_l:.2e}) = {stages:.0f} stages of"
            f" {bc / stages * 1e6:.1f} us; RK4 {n_rk:.0f} steps (h = {T_END / n_rk:.2e}) = {evals:.0f}"
            f" evaluations of {rk / evals * 1e6:.2f} us; stages / evaluations {stages / evals:.2f},"
            f" stage cost / evaluation cost {(bc / stages) / (rk / evals):.1f}")


def figure(results, path):
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        say(f"  figure: skipped (matplotlib missing), not written to {path}")
        return
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5))
    style = {"liemid": ("C0", "o-"), "liemid4": ("C1", "s-"), "liemid6": ("C2", "^-"), "liemid8": ("C3", "v-"),
             "mujoco-rk4": ("k", "D--"), "mujoco-euler": ("0.5", "x--"), "mujoco-implicitfast": ("C5", "+--")}
    for ax, r in zip(axes.ravel(), results):
        for k, pts in r["curves"].items():
            p = sorted((c, e) for c, e, *_ in pts if math.isfinite(e) and e > 0)
            if not p:
                continue
            colour, marker = style[k]
            ax.loglog([c for c, _ in p], [e for _, e in p], marker, color=colour, label=k, ms=4)
        for lv in LEVELS:
            ax.axhline(lv, color="0.85", lw=0.8, zorder=0)
        ax.set_title(f"{r['title']} ({r['bodies']} bodies)")
        ax.set_xlabel("CPU time (s)")
        ax.set_ylabel(f"final body-position error at t = {T_END} (m)")
        ax.grid(True, which="major", alpha=0.3)
    for ax in axes.ravel()[len(results):]:
        ax.set_visible(False)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("liemid against MuJoCo 4.0 on published-style robots (no contacts, actuators off;"
                 " reference MuJoCo RK4 h = 1e-5)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    say(f"  figure: {path}")


def main():
    DOCS.mkdir(exist_ok=True)
    say(f"vs_mujoco_robots.py: liemid ({LIEMID}) against MuJoCo {mujoco.__version__}, numpy {np.__version__};"
        f" {os.cpu_count()} cores, {load_average()} at the start")
    say("Times: MuJoCo the process CPU of its mj_step loop; liemid the command's stepping_seconds (its loop, no start-up)."
        f" Runs below {SHORT_RUN} s are repeated ({REPEATS} more) and the least kept.")
    only = os.environ.get("VS_MUJOCO_ROBOTS", "")
    results = []
    with tempfile.TemporaryDirectory(prefix="vs_mujoco_robots_") as tmp:
        for key, title, fname in ROBOTS:
            if only and key not in only.split(","):
                continue
            r = robot_case(key, title, fname, tmp)
            if r:
                results.append(r)
        summary(results)
        cost_table(results)
    say(f"\n{load_average()} at the end")
    if PLOT:
        figure(results, PLOT)
    if not QUICK and not only:
        (DOCS / "vs-mujoco-robots.txt").write_text("\n".join(OUT) + "\n")


if __name__ == "__main__":
    main()
