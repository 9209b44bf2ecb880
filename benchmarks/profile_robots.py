#!/usr/bin/env python3
"""Where the time of one liemid multibody step goes on the robots of vs_mujoco_robots.py
against the long chain (issue 43, item 1).

Each case runs `examples/profile_multibody.rs` (the library alone, no command, no per-step
diagnostics) twice: once for its own figures (CPU per step and per body-stage from the
process clock, quasi-Newton iterations and factorizations per stage, the constraint
solve's share from the library's timers), and once under `perf record --call-graph dwarf`
(inlined frames resolved by `perf script --inline`). Each sample inside a stage
(`Workspace::stage`) is given to the first of these kernels found anywhere on its stack,
in this order:

  drift Jacobian   the exact drift Jacobian's products (`drift_jacobian`) of the refinement
  factorization    the block Cholesky of G M^-1 G^T over the tree (`Workspace::factor`)
  tree solves      solves with the factor (`TreeSolver::solve`)
  midpoint solves  the drift's two midpoint solves per body (`liemid::midpoint`)
  drift, other     the rest of the drift (positions, rotations: `drift`, `drift_pair`)
  impulses         G^T lambda onto the bodies (`add_impulse`)
  row products     G v and its kin (`dot_row`, `for_each_rate`, `dot6`)
  rows             the joint rows and gradients at a configuration (`JointGeometry`, `rows_at`)
  forces           gravity, springs, actuators (`forces`)
  dampers, limits, friction   their checks and kicks (the implicit damper half-kick's
                   conjugate gradients: their own arithmetic; the tree solves inside them count
                   as tree solves)
  predictor        the extrapolated start of lambda (`start_multipliers`)
  copies           memcpy / memset
  timers           the library's timers (the timed run only)
  bookkeeping      anything else in the stage (residual norms, updates, loop control)

and, by phase, to the position solve (`solve_positions`, the drift included), the velocity
solve (`solve_velocities`, its factorization included) or the rest of the stage.

Run:  python benchmarks/profile_robots.py      (needs perf and the example:
      cargo build --release -p liemid --example profile_multibody; PROFILE_MULTIBODY=path)
Writes docs/profile-robots.txt.
"""

from __future__ import annotations

import collections
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "benchmarks" / "models"
DOCS = ROOT / "docs"


def find_example():
    cands = [os.environ.get("PROFILE_MULTIBODY")]
    if os.environ.get("CARGO_TARGET_DIR"):
        cands.append(Path(os.environ["CARGO_TARGET_DIR"]) / "release" / "examples" / "profile_multibody")
    cands.append(ROOT / "target" / "release" / "examples" / "profile_multibody")
    for c in cands:
        if c and Path(c).is_file() and os.access(c, os.X_OK):
            return str(c)
    return None


# (label, problem or model file, method, h, steps per run, runs)
CASES = [
    ("arm", str(MODELS / "robot_arm.xml"), "liemid", 1e-3, 500, 120),
    ("humanoid", str(MODELS / "robot_humanoid.xml"), "liemid", 1e-3, 500, 80),
    ("quadruped", str(MODELS / "robot_quadruped.xml"), "liemid", 1e-3, 500, 140),
    ("drone", str(MODELS / "robot_drone.xml"), "liemid", 1e-3, 500, 300),
    ("chain-10", "chain-10", "liemid", 1e-3, 500, 140),
    ("chain-1000", "chain-1000", "liemid", 1e-3, 500, 2),
    ("arm", str(MODELS / "robot_arm.xml"), "liemid", 1e-4, 5000, 16),
    ("humanoid", str(MODELS / "robot_humanoid.xml"), "liemid", 1e-4, 5000, 10),
    ("quadruped", str(MODELS / "robot_quadruped.xml"), "liemid", 1e-4, 5000, 16),
    ("drone", str(MODELS / "robot_drone.xml"), "liemid", 1e-4, 5000, 40),
    ("chain-10", "chain-10", "liemid", 1e-4, 5000, 16),
    ("chain-1000", "chain-1000", "liemid", 1e-4, 1000, 1),
    # liemid4 over t = 0.5 at about the step where it reaches 1e-8 m (vs-mujoco-robots.txt:
    # 8.6e-9 m at 0.5/160 on the arm; the interpolated steps 0.5/61 and 0.5/36; 1.2e-8 m at 0.5/320)
    ("arm", str(MODELS / "robot_arm.xml"), "liemid4", 0.5 / 160, 160, 100),
    ("humanoid", str(MODELS / "robot_humanoid.xml"), "liemid4", 0.5 / 62, 62, 160),
    ("quadruped", str(MODELS / "robot_quadruped.xml"), "liemid4", 0.5 / 36, 36, 400),
    ("drone", str(MODELS / "robot_drone.xml"), "liemid4", 0.5 / 320, 320, 100),
    # Menagerie's own joint classes put damping 1 (panda, H1) and armature 0.1 on every hinge:
    # the same models with them (written to a temporary directory)
    ("arm, damping 1", "robot_arm.xml:damping", "liemid", 1e-3, 500, 60),
    ("arm, damping 1", "robot_arm.xml:damping", "liemid", 1e-4, 5000, 6),
    ("arm, damping 1, armature 0.1", "robot_arm.xml:armature", "liemid", 1e-3, 500, 40),
    ("humanoid, damping 1", "robot_humanoid.xml:damping", "liemid", 1e-3, 500, 40),
    ("humanoid, damping 1, armature 0.1", "robot_humanoid.xml:armature", "liemid", 1e-3, 500, 30),
]
VARIANTS = {"damping": 'armature="0" damping="1"', "armature": 'armature="0.1" damping="1"'}


def variant(problem, tmp):
    """A model file with its joint class's damping (and armature) switched on, or the problem."""
    if ":" not in problem:
        return problem
    name, kind = problem.split(":")
    text = (MODELS / name).read_text()
    assert text.count('armature="0" damping="0"') == 1, name
    out = Path(tmp) / f"{kind}_{name}"
    out.write_text(text.replace('armature="0" damping="0"', VARIANTS[kind]))
    return str(out)

KERNELS = [
    ("timers", ("clock_gettime", "Instant")),
    ("drift Jacobian", ("drift_jacobian",)),
    ("factorization", ("Workspace::factor", "SymmetricTree::factor", "factor_symmetric", "factor_loops")),
    ("tree solves", ("TreeSolver::solve", "SymmetricTree::solve", "tree_solve")),
    ("midpoint solves", ("liemid::midpoint::",)),
    ("drift, other", ("W::drift", "drift_pair")),
    ("impulses", ("add_impulse",)),
    ("row products", ("dot_row", "for_each_rate", "dot6")),
    ("rows", ("JointGeometry::", "rows_at", "end_rows")),
    ("forces", ("::forces", "gravity")),
    ("dampers", ("damper",)),
    ("limits", ("limit",)),
    ("friction", ("friction",)),
    ("predictor", ("start_multipliers", "predictor::")),
    ("copies", ("memcpy", "memset", "memmove")),
]
PHASES = [("position solve", "solve_positions"), ("velocity solve", "solve_velocities")]

OUT: list[str] = []


def say(line=""):
    print(line, flush=True)
    OUT.append(line)


def clean(frame):
    f = re.sub(r"::h[0-9a-f]{16}", "", frame).replace(" (inlined)", "")
    return f.replace("<impl liemid::multibody::workspace::Workspace>", "W")


def stacks(data):
    text = subprocess.run(["perf", "script", "-i", data, "-F", "ip,sym", "--inline"],
                          capture_output=True, text=True).stdout
    for block in text.split("\n\n"):
        frames = [clean(line.strip().split(" ", 1)[1]) for line in block.strip().split("\n")
                  if " " in line.strip()]
        if frames:
            yield frames  # leaf first


def classify(data):
    kernels, phases, n = collections.Counter(), collections.Counter(), 0
    for frames in stacks(data):
        if not any("W::stage" in f for f in frames):
            continue
        n += 1
        joined = "\n".join(frames)
        for name, pats in KERNELS:
            if any(p in joined for p in pats):
                kernels[name] += 1
                break
        else:
            kernels["bookkeeping"] += 1
        for name, pat in PHASES:
            if pat in joined:
                phases[name] += 1
                break
        else:
            phases["rest of the stage"] += 1
    return n, kernels, phases


def main():
    example = find_example()
    if example is None:
        print("profile_robots: skipped, no example binary "
              "(cargo build --release -p liemid --example profile_multibody, or PROFILE_MULTIBODY)")
        return
    if shutil.which("perf") is None:
        print("profile_robots: skipped, perf is not installed")
        return
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    say(f"profile_robots.py: {example}; load average {load} at the start")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, problem, method, h, steps, runs in CASES:
            args = [example, variant(problem, tmp), method, repr(h), str(steps), str(runs)]
            own = subprocess.run(args, capture_output=True, text=True, check=True).stdout
            m = re.search(r"([\d.]+) us/step,\s+([\d.]+) us/stage,\s+([\d.]+) us/body-stage; iterations/stage ([\d.]+),"
                          r" factorizations/stage ([\d.]+)", own)
            share = re.search(r"constraint solve ([\d.]+) %", own)
            data = str(Path(tmp) / "perf.data")
            rec = subprocess.run(["perf", "record", "-q", "-F", "1500", "--call-graph", "dwarf,16384", "-o", data,
                                  "--", *args], capture_output=True, text=True)
            if rec.returncode != 0:
                say(f"  perf record failed on {label}: {rec.stderr.strip()[:200]}")
                return
            n, kernels, phases = classify(data)
            rows.append((label, method, h, m.groups(), share.group(1), n, kernels, phases))
            say(f"  {label} {method} h = {h:.4g}: {m.group(1)} us/step, {m.group(3)} us/body-stage,"
                f" {m.group(4)} iterations/stage, {n} samples in the stage")
    say(f"\nThe step in the library (examples/profile_multibody.rs; CPU per step from the process clock;"
        f" load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} at the end):")
    say(f"  {'case':<44}{'us/step':>9}{'us/stage':>10}{'us/body-stage':>15}{'iter/stage':>12}{'solve % (timers)':>18}")
    for label, method, h, g, share, *_ in rows:
        say(f"  {f'{label} {method} h = {h:.4g}':<44}{g[0]:>9}{g[1]:>10}{g[2]:>15}{g[3]:>12}{share:>18}")
    names = [k for k, _ in KERNELS] + ["bookkeeping"]
    say("\nShare of a stage's samples by kernel (perf, first kernel on the stack in the docstring's order), %:")
    short = {"drift Jacobian": "dJac", "factorization": "factor", "tree solves": "solves", "midpoint solves": "midpt",
             "drift, other": "drift", "impulses": "impulse", "row products": "Gv", "rows": "rows", "forces": "forces",
             "dampers": "damp", "limits": "limits", "friction": "fric", "predictor": "pred", "copies": "copies",
             "timers": "timers", "bookkeeping": "other"}
    say(f"  {'case':<44}" + "".join(f"{short[k]:>8}" for k in names))
    for label, method, h, _g, _s, n, kernels, _p in rows:
        say(f"  {f'{label} {method} h = {h:.4g}':<44}" + "".join(f"{100 * kernels[k] / n:>8.1f}" for k in names))
    say("\nBy phase (the position solve includes its drifts, the velocity solve its factorization), %:")
    pn = [p for p, _ in PHASES] + ["rest of the stage"]
    say(f"  {'case':<44}" + "".join(f"{p:>20}" for p in pn))
    for label, method, h, _g, _s, n, _k, phases in rows:
        say(f"  {f'{label} {method} h = {h:.4g}':<44}" + "".join(f"{100 * phases[p] / n:>20.1f}" for p in pn))
    (DOCS / "profile-robots.txt").write_text("\n".join(OUT) + "\n")


if __name__ == "__main__":
    sys.exit(main())
