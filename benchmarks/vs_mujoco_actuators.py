#!/usr/bin/env python3
"""liemid on arms driven by actuators, with armature, against MuJoCo 4.0's RK4.

The six-axis arm (written below) has six hinges on alternating axes, joint damping and
armature set by a default class (armature 0.1, as published arms have it; the same arm
without armature is kept as a second row), no geoms (no contacts), and position actuators
(kp, a forcerange that the first motion saturates) whose keyframe ctrl differs from the
keyframe's qpos, so the arm moves under gravity towards its controls. A second servo case
gives the servos dampratio 1 (MuJoCo's kv from the reflected inertia at qpos0, armature
included) and no forcerange. Both codes start from the keyframe (mj_resetDataKeyframe:
qpos and ctrl).

Reference: MuJoCo's RK4 at h = 1e-5 to t = 0.5. Printed: the largest distance between the
two codes' body frame origins (xpos) at t = 0.5, for liemid at h = 1e-4 and 5e-5 (order 2),
liemid4 at 1e-4 and liemid's joint-space rk4 at 1e-4 (which keeps armature in joint
space, as MuJoCo does). Bound (issue 47): 1e-6 m for liemid at h = 1e-4.

A third case is a seven-axis arm with armature 0.1 whose joints are driven by motors from
a PD controller tracking a sine on every joint, from Python: liemid's `run(control=f)` and
MuJoCo's own loop (`d.ctrl` set from the same `f(t, qpos, qvel)` before each `mj_step`),
both at h = 1e-4 (the control held over each step in both) to t = 2; printed: the largest
body-position difference (when the liemid Python package is importable). Bound: 1e-5 m.

A fourth case is a UR10e-style arm (examples/multibody/ur10e_inertial.xml: the link
frames, inertials, classes and servos of Menagerie's ur10e.xml, no meshes; armature 0.1
and damping 350/200/30, the wrists' 30) from a keyframe near home, to t = 0.2 against
MuJoCo's RK4 at h = 1e-5: liemid and liemid4 at the model's own step 2e-3 (MuJoCo's
default timestep; the file sets none) halved twice, with the observed orders.

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

AXES = ["0 0 1", "0 1 0", "0 1 0", "1 0 0", "0 1 0", "1 0 0", "0 0 1"]
MASSES = [3.0, 2.5, 2.0, 1.0, 0.8, 0.5, 0.3]
KP = [400, 300, 200, 100, 60, 30, 20]
FORCE = [60, 40, 25, 12, 8, 4, 2]
QPOS = [0.1, 0.4, -0.3, 0.2, 0.5, -0.2, 0.3]
CTRL = [0.5, 0.1, 0.2, -0.3, 0.1, 0.4, -0.2]
ARMATURE = 0.1
ROOT = Path(__file__).resolve().parents[1]
UR10E = ROOT / "examples" / "multibody" / "ur10e_inertial.xml"


def arm(servo: str, armature: float = ARMATURE, joints: int = 6) -> str:
    """The arm's MJCF with `joints` hinges; `servo` is the position actuators' extra
    attributes (k: index, f: force limit)."""
    bodies, close = "", ""
    for k, (axis, m) in enumerate(zip(AXES[:joints], MASSES)):
        pos = "0 0 0.1" if k == 0 else "0.05 0 0.25"
        bodies += (f'<body name="link{k + 1}" pos="{pos}"><joint name="j{k + 1}" class="arm" axis="{axis}"/>'
                   f'<inertial pos="0.02 0.01 0.12" mass="{m}" diaginertia="{0.02 * m} {0.018 * m} {0.006 * m}"/>')
        close += "</body>"
    acts = "".join(f'<position name="a{k + 1}" joint="j{k + 1}" kp="{KP[k]}" {servo.format(k=k, f=FORCE[k])}/>'
                   for k in range(joints))
    return (f'<mujoco model="arm{joints}"><compiler angle="radian"/><option timestep="0.001"/>'
            f'<default><default class="arm"><joint damping="2" armature="{armature}"/></default></default>'
            f'<worldbody>{bodies}{close}</worldbody><actuator>{acts}</actuator>'
            f'<keyframe><key qpos="{" ".join(map(str, QPOS[:joints]))}" '
            f'ctrl="{" ".join(map(str, CTRL[:joints]))}"/></keyframe>'
            f'</mujoco>')


def mujoco_model(text: str, h: float) -> mujoco.MjModel:
    m = mujoco.MjModel.from_xml_string(text)
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    m.opt.timestep = h
    # Contacts off (the models have no geoms that collide; said for the record).
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    return m


def mujoco_run(text: str, h: float, steps: int | None = None, t_end: float = T_END) -> dict[str, np.ndarray]:
    """Body frame origins after `steps` RK4 steps of h (default: to t_end) from the keyframe."""
    m = mujoco_model(text, h)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    for _ in range(round(t_end / h) if steps is None else steps):
        mujoco.mj_step(m, d)
    mujoco.mj_kinematics(m, d)
    return {m.body(i).name: d.xpos[i].copy() for i in range(1, m.nbody)}


def liemid_run(binary: str, path: Path, method: str, h: float, t_end: float = T_END) -> dict[str, np.ndarray]:
    out = subprocess.run([binary, "multibody", str(path), "--method", method, "--step", repr(h),
                          "--t-end", repr(t_end), "--json", "-"], check=True, capture_output=True, text=True)
    s = json.loads(out.stdout)
    return {b["name"]: np.array(b["xpos"]) for b in s["final"]}


def largest(got: dict[str, np.ndarray], ref: dict[str, np.ndarray]) -> float:
    return max(float(np.linalg.norm(got[b] - ref[b])) for b in ref)


def main() -> None:
    binary = require_liemid("vs_mujoco_actuators")
    forcerange, dampratio = 'forcerange="-{f} {f}"', 'dampratio="1"'
    cases = [
        (f"armature {ARMATURE}, kp + forcerange", arm(forcerange)),
        (f"armature {ARMATURE}, kp + dampratio 1", arm(dampratio)),
        ("armature 0, kp + forcerange", arm(forcerange, 0.0)),
        ("armature 0, kp + dampratio 1", arm(dampratio, 0.0)),
    ]
    with tempfile.TemporaryDirectory() as tmp:
        for name, text in cases:
            path = Path(tmp) / "arm6.xml"
            path.write_text(text)
            ref = mujoco_run(text, 1e-5)
            start = mujoco_run(text, 1e-5, 0)
            moved = max(np.linalg.norm(ref[b] - start[b]) for b in ref)
            print(f"{name}: MuJoCo RK4 h = 1e-5 to t = {T_END}; bodies move up to {moved:.3f} m")
            if "dampratio" in name:
                kv = -mujoco_model(text, 1e-5).actuator_biasprm[:, 2]
                print(f"  MuJoCo's kv from dampratio 1: {np.array2string(kv, precision=6)}")
            for method, h in [("liemid", 1e-4), ("liemid", 5e-5), ("liemid4", 1e-4), ("rk4", 1e-4)]:
                err = largest(liemid_run(binary, path, method, h), ref)
                bound = "  (bound 1e-6: " + ("met)" if err <= 1e-6 else "MISSED)") if (method, h) == (
                    "liemid", 1e-4) else ""
                print(f"  {method:8s} h = {h:.0e}: largest body-position difference {err:.2e} m{bound}")
    print(f"PD tracking a sine, motors, 7-axis arm with armature {ARMATURE}, "
          "MuJoCo RK4 in its own loop at the same step:")
    pd_case()
    ur10e_case(binary)


def pd(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """PD tracking q_ref = 0.3 sin(2 t + k) on joint k."""
    k = np.arange(len(q))
    kp = np.array(KP[:len(q)], dtype=float)
    ref, dref = 0.3 * np.sin(2 * t + k), 0.6 * np.cos(2 * t + k)
    return kp * (ref - q) + 0.1 * kp * (dref - v)


def pd_case() -> None:
    try:
        from liemid import multibody
    except ImportError:
        print("PD case: skipped, the liemid Python package is not importable")
        return
    h, t_end = 1e-4, 2.0
    text = arm("", joints=7).replace("<position", "<motor").replace(' kp="', ' gear="1" data-kp="')
    # The motors carry no kp: strip the attribute left by the substitution.
    text = re.sub(r' data-kp="[^"]*"', "", text)
    m = mujoco_model(text, h)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    for _ in range(round(t_end / h)):
        d.ctrl[:] = pd(d.time, d.qpos.copy(), d.qvel.copy())
        mujoco.mj_step(m, d)
    mujoco.mj_kinematics(m, d)
    ref = np.array([d.xpos[i] for i in range(1, m.nbody)])
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "arm7_motors.xml"
        path.write_text(text)
        for method in ["liemid", "liemid4", "rk4"]:
            run = multibody.load(path).run(method, step=h, t_end=t_end, every=10**9, control=pd)
            err = float(np.max(np.linalg.norm(run.xpos[-1] - ref, axis=1)))
            bound = "  (bound 1e-5: " + ("met)" if err <= 1e-5 else "MISSED)") if method == "liemid" else ""
            print(f"  PD callback, {method:8s} h = {h:.0e} to t = {t_end}: largest body-position difference "
                  f"{err:.2e} m{bound}")


def ur10e_case(binary: str) -> None:
    t_end = 0.2
    text = UR10E.read_text()
    ref = mujoco_run(text, 1e-5, t_end=t_end)
    start = mujoco_run(text, 1e-5, 0)
    moved = max(np.linalg.norm(ref[b] - start[b]) for b in ref)
    print(f"UR10e-style arm ({UR10E.name}: armature 0.1, damping 350/200/30, servos), "
          f"MuJoCo RK4 h = 1e-5 to t = {t_end}; bodies move up to {moved:.3f} m")
    for method, steps in [("liemid", [2e-3, 1e-3, 5e-4]), ("liemid4", [2e-3, 1e-3, 5e-4])]:
        errs = [largest(liemid_run(binary, UR10E, method, h, t_end), ref) for h in steps]
        orders = [np.log2(a / b) for a, b in zip(errs, errs[1:])]
        print(f"  {method:8s} h = " + " / ".join(f"{h:.0e}" for h in steps) + ": "
              + " / ".join(f"{e:.2e}" for e in errs) + " m, observed orders "
              + ", ".join(f"{o:.2f}" for o in orders))


if __name__ == "__main__":
    main()
