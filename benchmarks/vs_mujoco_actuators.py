#!/usr/bin/env python3
"""liemid on a six-axis arm driven by position actuators against MuJoCo 4.0's RK4.

The arm (written below) has six hinges on alternating axes, joint damping, no armature
(armature in maximal coordinates is separate work), no geoms (no contacts), and position
actuators (kp, a forcerange that the first motion saturates) whose keyframe ctrl differs
from the keyframe's qpos, so the arm moves under gravity towards its controls. A second
case gives the servos dampratio 1 (MuJoCo's kv from the reflected inertia at qpos0) and no
forcerange. Both codes start from the keyframe (mj_resetDataKeyframe: qpos and ctrl).

Reference: MuJoCo's RK4 at h = 1e-5 to t = 0.5. Printed: the largest distance between the
two codes' body frame origins (xpos) at t = 0.5, for liemid at h = 1e-4 and 5e-5 (order 2)
and liemid4 at 1e-4.

A third case replaces the servos by motors driven by a PD controller tracking a sine on
every joint, from Python: liemid's `run(control=f)` and MuJoCo's own loop (`d.ctrl` set
from the same `f(t, qpos, qvel)` before each `mj_step`), both at h = 1e-4 (the control held
over each step in both) to t = 2; printed: the largest body-position difference (when the
liemid Python package is importable).

Run:  python benchmarks/vs_mujoco_actuators.py      (LIEMID_BIN to point at the binary)
Peers: pip install mujoco==4.0.0 numpy (in a venv of your own).
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

T_END = 0.5

try:
    import numpy as np
    import mujoco
except ImportError as e:  # pragma: no cover - the skip path
    print(f"vs_mujoco_actuators: skipped, a peer is missing ({e}); pip install mujoco==4.0.0 numpy")
    sys.exit(0)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from liemid_binary import require_liemid  # noqa: E402

AXES = ["0 0 1", "0 1 0", "0 1 0", "1 0 0", "0 1 0", "1 0 0"]
MASSES = [3.0, 2.5, 2.0, 1.0, 0.8, 0.5]
KP = [400, 300, 200, 100, 60, 30]
FORCE = [60, 40, 25, 12, 8, 4]
QPOS = [0.1, 0.4, -0.3, 0.2, 0.5, -0.2]
CTRL = [0.5, 0.1, 0.2, -0.3, 0.1, 0.4]


def arm(servo: str) -> str:
    """The arm's MJCF; `servo` is the position actuators' extra attributes (k: index)."""
    bodies, close = "", ""
    for k, (axis, m) in enumerate(zip(AXES, MASSES)):
        pos = "0 0 0.1" if k == 0 else "0.05 0 0.25"
        bodies += (f'<body name="link{k + 1}" pos="{pos}"><joint name="j{k + 1}" class="arm" axis="{axis}"/>'
                   f'<inertial pos="0.02 0.01 0.12" mass="{m}" diaginertia="{0.02 * m} {0.018 * m} {0.006 * m}"/>')
        close += "</body>"
    acts = "".join(f'<position name="a{k + 1}" joint="j{k + 1}" kp="{KP[k]}" {servo.format(k=k, f=FORCE[k])}/>'
                   for k in range(6))
    return (f'<mujoco model="arm6"><compiler angle="radian"/><option timestep="0.001"/>'
            f'<default><default class="arm"><joint damping="2" armature="0"/></default></default>'
            f'<worldbody>{bodies}{close}</worldbody><actuator>{acts}</actuator>'
            f'<keyframe><key qpos="{" ".join(map(str, QPOS))}" ctrl="{" ".join(map(str, CTRL))}"/></keyframe>'
            f'</mujoco>')


def mujoco_run(text: str, h: float, steps: int | None = None) -> dict[str, np.ndarray]:
    """Body frame origins after `steps` RK4 steps of h (default: to T_END) from the keyframe."""
    m = mujoco.MjModel.from_xml_string(text)
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    m.opt.timestep = h
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    for _ in range(round(T_END / h) if steps is None else steps):
        mujoco.mj_step(m, d)
    mujoco.mj_kinematics(m, d)
    return {m.body(i).name: d.xpos[i].copy() for i in range(1, m.nbody)}


def liemid_run(binary: str, path: Path, method: str, h: float) -> dict[str, np.ndarray]:
    out = subprocess.run([binary, "multibody", str(path), "--method", method, "--step", repr(h),
                          "--t-end", repr(T_END), "--json", "-"], check=True, capture_output=True, text=True)
    s = json.loads(out.stdout)
    return {b["name"]: np.array(b["xpos"]) for b in s["final"]}


def main() -> None:
    binary = require_liemid("vs_mujoco_actuators")
    cases = [("kp + forcerange", 'forcerange="-{f} {f}"'), ("kp + dampratio 1", 'dampratio="1"')]
    with tempfile.TemporaryDirectory() as tmp:
        for name, servo in cases:
            text = arm(servo)
            path = Path(tmp) / "arm6.xml"
            path.write_text(text)
            ref = mujoco_run(text, 1e-5)
            start = mujoco_run(text, 1e-5, 0)
            moved = max(np.linalg.norm(ref[b] - start[b]) for b in ref)
            print(f"{name}: MuJoCo RK4 h = 1e-5 to t = {T_END}; bodies move up to {moved:.3f} m")
            for method, h in [("liemid", 1e-4), ("liemid", 5e-5), ("liemid4", 1e-4), ("rk4", 1e-4)]:
                got = liemid_run(binary, path, method, h)
                err = max(float(np.linalg.norm(got[b] - ref[b])) for b in ref)
                print(f"  {method:8s} h = {h:.0e}: largest body-position difference {err:.2e} m")
    print("PD tracking a sine, motors, MuJoCo RK4 in its own loop at the same step:")
    pd_case()


def pd(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """PD tracking q_ref = 0.3 sin(2 t + k) on joint k."""
    k = np.arange(6)
    ref, dref = 0.3 * np.sin(2 * t + k), 0.6 * np.cos(2 * t + k)
    return np.array(KP) * (ref - q) + 0.1 * np.array(KP) * (dref - v)


def pd_case() -> None:
    try:
        from liemid import multibody
    except ImportError:
        print("PD case: skipped, the liemid Python package is not importable")
        return
    h, t_end = 1e-4, 2.0
    text = arm("").replace("<position", "<motor").replace(' kp="', ' gear="1" data-kp="')
    # The motors carry no kp: strip the attribute left by the substitution.
    text = re.sub(r' data-kp="[^"]*"', "", text)
    m = mujoco.MjModel.from_xml_string(text)
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    m.opt.timestep = h
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    for _ in range(round(t_end / h)):
        d.ctrl[:] = pd(d.time, d.qpos.copy(), d.qvel.copy())
        mujoco.mj_step(m, d)
    mujoco.mj_kinematics(m, d)
    ref = np.array([d.xpos[i] for i in range(1, m.nbody)])
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "arm6_motors.xml"
        path.write_text(text)
        for method in ["liemid", "liemid4", "rk4"]:
            run = multibody.load(path).run(method, step=h, t_end=t_end, every=10**9, control=pd)
            err = float(np.max(np.linalg.norm(run.xpos[-1] - ref, axis=1)))
            print(f"  PD callback, {method:8s} h = {h:.0e} to t = {t_end}: largest body-position difference {err:.2e} m")


if __name__ == "__main__":
    main()
