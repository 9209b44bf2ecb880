#!/usr/bin/env python3
"""liemid on a humanoid with several hinges per body against MuJoCo 4.0's RK4.

The model is examples/multibody/humanoid.xml (MuJoCo's humanoid.xml structure: a free
torso, an abdomen with two hinges through one point and one below, hips with three
hinges, knees, ankles with two, shoulders with two on oblique axes, elbows; no floor,
contacts disabled). liemid merges each body's hinges into a universal or ball joint;
MuJoCo integrates the hinge chain through its massless intermediate frames. Both start
from the file's first keyframe, under gravity, with the hinges' springs and dampers.

Two cases: the file as it is, whose knees and left elbow reach their limits within the
0.5 s (liemid's limits are hard and plastic, MuJoCo's soft, so the two models differ
there); the same file with `limited="false"` in its joint class (no limits: the same
equations of motion in both codes; liemid's dampers are second order in every method, see
rattle.rs, so its compositions lose their order); and without limits and dampers
(springs and gravity only: every method at its order).

Reference: MuJoCo's RK4 at h = 1e-5 to t = 0.5 (checked against h = 2e-5). Printed: the
largest distance between the two codes' body frame origins (`xpos`) at t = 0 (the
keyframe conversion) and at t = 0.5 for liemid at several steps and methods, and the
number of MuJoCo steps with an active joint limit. CPU time is not compared here (see
vs_mujoco.py).

Run:  python benchmarks/vs_mujoco_humanoid.py      (LIEMID_BIN to point at the binary)
Peers: pip install mujoco==4.0.0 numpy (in a venv of your own).
"""

from __future__ import annotations

import csv
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / "examples" / "multibody" / "humanoid.xml"
T_END = 0.5

try:
    import numpy as np
    import mujoco
except ImportError as e:  # pragma: no cover - the skip path
    print(f"vs_mujoco_humanoid: skipped, a peer is missing ({e}); pip install mujoco==4.0.0 numpy")
    sys.exit(0)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from liemid_binary import find_liemid  # noqa: E402


def mujoco_run(model, h):
    """Body frame origins (by name) at t = 0 and t = T_END, and the steps with a limit on."""
    m = mujoco.MjModel.from_xml_path(str(model))
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    m.opt.timestep = h
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    names = [m.body(i).name for i in range(1, m.nbody)]
    x0 = {n: d.xpos[i + 1].copy() for i, n in enumerate(names)}
    limited = 0
    for _ in range(round(T_END / h)):
        mujoco.mj_step(m, d)
        limited += d.nefc > 0
    mujoco.mj_kinematics(m, d)
    x1 = {n: d.xpos[i + 1].copy() for i, n in enumerate(names)}
    return x0, x1, limited


def liemid_run(binary, model, method, h):
    """Body frame origins (by name) at t = 0 and t = T_END from the trajectory file."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "h.csv"
        steps = round(T_END / h)
        subprocess.run(
            [binary, "multibody", str(model), "--method", method, "--step", repr(h), "--t-end", repr(T_END),
             "--every", str(steps), "--out", str(out)],
            check=True, capture_output=True)
        with out.open() as f:
            rows = list(csv.reader(f))
    head, first, last = rows[0], rows[1], rows[-1]
    assert abs(float(last[0]) - T_END) < 1e-9, last[0]
    bodies = [c[:-2] for c in head if c.endswith(".x")]
    pick = lambda row: {b: np.array([float(row[head.index(f"{b}.{a}")]) for a in "xyz"]) for b in bodies}
    return pick(first), pick(last)


def gap(a, b):
    return max(np.abs(a[n] - b[n]).max() for n in a)


def main():
    binary = find_liemid()
    if binary is None:
        print("vs_mujoco_humanoid: skipped, no release liemid binary (cargo build -p liemid-cli --release)")
        return
    text = MODEL.read_text()
    joint_class = '<joint type="hinge" damping=".2" stiffness="1" limited="true"/>'
    assert text.count(joint_class) == 1
    with tempfile.TemporaryDirectory() as tmp:
        free = Path(tmp) / "humanoid_no_limits.xml"
        free_text = text.replace(joint_class, joint_class.replace('"true"', '"false"'))
        free.write_text(free_text)
        undamped = Path(tmp) / "humanoid_no_limits_no_dampers.xml"
        undamped.write_text(free_text.replace('damping=".2"', 'damping="0"').replace('damping="5"', 'damping="0"'))
        for label, model in [("as written (limits)", MODEL), ('limited="false"', free),
                             ('limited="false", damping="0"', undamped)]:
            compare(binary, label, model)


def compare(binary, label, model):
    ref0, ref1, limited = mujoco_run(model, 1e-5)
    _, chk1, _ = mujoco_run(model, 2e-5)
    print(f"model {MODEL.relative_to(ROOT)} {label}, t = {T_END}, from keyframe 0, gravity, no contacts")
    print(f"MuJoCo RK4 h = 1e-5: steps with an active joint limit: {limited}; "
          f"against h = 2e-5: {gap(ref1, chk1):.2e} m")
    print(f"{'method':>8} {'h':>8} {'xpos gap t=0 (m)':>18} {'xpos gap t=0.5 (m)':>19}")
    for method, h in [("liemid", 2e-3), ("liemid", 1e-3), ("liemid", 5e-4), ("liemid", 2.5e-4),
                      ("liemid4", 2e-3), ("liemid4", 1e-3), ("liemid8", 1e-3)]:
        x0, x1 = liemid_run(binary, model, method, h)
        missing = set(ref1) ^ set(x1)
        assert not missing, missing
        print(f"{method:>8} {h:>8.1e} {gap(x0, ref0):>18.2e} {gap(x1, ref1):>19.2e}")
    print()


if __name__ == "__main__":
    main()
