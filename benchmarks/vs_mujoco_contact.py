#!/usr/bin/env python3
"""Contact with friction: liemid's hard impulses against MuJoCo 4.0's soft contacts (issue 45).

Both codes read the same MJCF files (written to a temporary directory, the quadruped from
benchmarks/models/quadruped.xml). liemid runs `--method liemid` at h = 1e-3 (the only
method with contacts). MuJoCo's options are set on the compiled model, the file left as it
is: its integrator stays the default (Euler), its solver the default (Newton), its contact
softness the default (solref 0.02 1, solimp 0.9 0.95 0.001), and each question runs a grid
of what MuJoCo offers against slip and sinking: the default pyramidal cone, the elliptic
cone, impratio 1 and 100 (Menagerie's Go2 and ANYmal use elliptic, impratio 100), the
noslip post-processor (noslip_iterations 10), each at h = 1e-3 and 1e-4 (MuJoCo's own
default timestep is 2e-3; the files set 1e-3).

1. Slope creep: a 1 kg box (half-edge 0.1) at rest on a plane tilted by 20 deg, friction 0.5
   on both geoms (tan 20 deg = 0.364 < 0.5: Coulomb says it sticks), 10 s: distance moved
   along the slope.
2. Sliding distance: the same box launched at 2 m/s on a flat floor with friction 0.4:
   distance to rest against v0^2 / (2 mu g) = 0.5097 m.
3. Resting depth: the box released at its exact height 0.1 on the floor, after 1 s: how far
   its centre is below 0.1 (and MuJoCo's own contact distance).
4. A quadruped standing (benchmarks/models/quadruped.xml, Go2-style, position servos holding
   the keyframe, feet exactly on the floor at the start), 5 s: base height (final, least),
   foot slip (the largest horizontal displacement of each foot within a stretch of contact)
   and whether it stays up (base above half its start height).
5. A pile: 100 boxes and spheres (sizes 0.05-0.1 m) dropped from a grid into a bin (a floor
   plane and four static walls), 2 s: CPU per step (MuJoCo: mj_step(m, d, nstep) in one
   call; liemid: stepping_seconds / steps from its JSON) and liemid's deepest penetration.
   liemid's run is capped (LIEMID_PILE_CAP seconds of wall clock, default 900): when the
   cap or a failed step stops it, what happened is printed. `--pile-seed N` draws the
   piles' tilts and offsets from seed N (default 1; with 2 and 3 liemid's mixed pile
   stopped at t = 0.908 and 0.858 s before the sliding solve and the rescue of stalled
   islands, and completes since, docs/multibody.md).

Timings are CPU of one run on a shared machine: rough. The accuracy numbers are the point.

Run:  python benchmarks/vs_mujoco_contact.py      (LIEMID_BIN to point at the binary)
Peers: pip install mujoco==4.0.0 numpy (in a venv of your own).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

try:
    import numpy as np
    import mujoco
except ImportError as e:  # pragma: no cover - the skip path
    print(f"vs_mujoco_contact: skipped, a peer is missing ({e}); pip install mujoco==4.0.0 numpy")
    sys.exit(0)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from liemid_binary import require_liemid  # noqa: E402

G = 9.81
H = 1e-3
HERE = Path(__file__).resolve().parent
QUADRUPED = HERE / "models" / "quadruped.xml"
PILE_CAP = float(os.environ.get("LIEMID_PILE_CAP", "900"))

# MuJoCo's settings: (label, cone, impratio, noslip_iterations).
SETTINGS = [
    ("pyramidal", mujoco.mjtCone.mjCONE_PYRAMIDAL, 1.0, 0),
    ("elliptic", mujoco.mjtCone.mjCONE_ELLIPTIC, 1.0, 0),
    ("elliptic impratio 100", mujoco.mjtCone.mjCONE_ELLIPTIC, 100.0, 0),
    ("elliptic impratio 100 noslip 10", mujoco.mjtCone.mjCONE_ELLIPTIC, 100.0, 10),
]
MJ_STEPS = [1e-3, 1e-4]


# ---------------------------------------------------------------------------- the models

def box_xml(mu: float, slope_deg: float = 0.0, v0: float = 0.0) -> str:
    """A 1 kg box of half-edge 0.1 on a plane tilted by `slope_deg` about y (x downhill),
    friction `mu` on both geoms, at rest on the plane at its exact height, launched at `v0`
    down the slope."""
    th = math.radians(slope_deg)
    s, c = math.sin(th), math.cos(th)
    qw, qy = math.cos(th / 2), math.sin(th / 2)
    return (
        '<mujoco model="box"><option timestep="0.001"/><worldbody>'
        f'<geom name="floor" type="plane" size="0 0 1" euler="0 {slope_deg!r} 0" friction="{mu}"/>'
        f'<body name="box"><freejoint/><geom name="box" type="box" size="0.1 0.1 0.1" mass="1" friction="{mu}"/>'
        '</body></worldbody>'
        f'<keyframe><key qpos="{0.1 * s!r} 0 {0.1 * c!r} {qw!r} 0 {qy!r} 0" '
        f'qvel="{v0 * c!r} 0 {-v0 * s!r} 0 0 0"/></keyframe></mujoco>')


def pile_xml(n: int = 100, seed: int = 1, spheres_only: bool = False) -> str:
    """`n` boxes and spheres (only spheres with `spheres_only`) (full sizes 0.05-0.1 m, density 1000) on a grid above a bin of
    inner half-width 0.4 m (a floor plane and four static walls of height 0.5), with small
    random tilts and offsets."""
    rng = np.random.default_rng(seed)
    half, wall = 0.4, 0.02
    walls = "".join(
        f'<geom name="wall{k}" type="box" size="{sx} {sy} 0.25" pos="{px} {py} 0.25"/>'
        for k, (sx, sy, px, py) in enumerate([
            (wall, half + 2 * wall, half + wall, 0), (wall, half + 2 * wall, -half - wall, 0),
            (half, wall, 0, half + wall), (half, wall, 0, -half - wall)]))
    side = math.ceil(math.sqrt(n / 4))
    spacing = 2 * half / side
    bodies = []
    for k in range(n):
        layer, cell = divmod(k, side * side)
        i, j = divmod(cell, side)
        x = -half + spacing * (i + 0.5) + rng.uniform(-0.01, 0.01)
        y = -half + spacing * (j + 0.5) + rng.uniform(-0.01, 0.01)
        z = 0.2 + 0.14 * layer
        r = rng.uniform(0.025, 0.05)
        ax = rng.normal(size=3)
        ax /= np.linalg.norm(ax)
        a = rng.uniform(0, 0.5)
        q = [math.cos(a / 2)] + list(math.sin(a / 2) * ax)
        quat = " ".join(f"{v:.6f}" for v in q)
        b = rng.uniform(0.6, 1.0, size=2) * r
        if k % 2 == 0 and not spheres_only:
            geom = f'<geom type="box" size="{r:.4f} {b[0]:.4f} {b[1]:.4f}" density="1000" friction="0.6"/>'
        else:
            geom = f'<geom type="sphere" size="{r:.4f}" density="1000" friction="0.6"/>'
        bodies.append(f'<body name="b{k}" pos="{x:.4f} {y:.4f} {z:.4f}" quat="{quat}"><freejoint/>{geom}</body>')
    return (f'<mujoco model="pile{n}"><option timestep="0.001"/><worldbody>'
            f'<geom name="floor" type="plane" size="0 0 1" friction="0.6"/>{walls}'
            f'{"".join(bodies)}</worldbody></mujoco>')


# ---------------------------------------------------------------------------- the two codes

def mj_model(path: Path, h: float, cone=None, impratio: float = 1.0, noslip: int = 0) -> mujoco.MjModel:
    m = mujoco.MjModel.from_xml_path(str(path))
    m.opt.timestep = h
    if cone is not None:
        m.opt.cone = cone
    m.opt.impratio = impratio
    m.opt.noslip_iterations = noslip
    return m


def mj_box(path: Path, h: float, t_end: float, setting) -> tuple[np.ndarray, np.ndarray, float]:
    """The box's centre at the start and at t_end, and the largest contact penetration at
    t_end (MuJoCo's contact distance, negative inside)."""
    _, cone, imp, noslip = setting
    m = mj_model(path, h, cone, imp, noslip)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    start = d.qpos[:3].copy()
    mujoco.mj_step(m, d, nstep=round(t_end / h))
    mujoco.mj_forward(m, d)
    depth = max((-d.contact[i].dist for i in range(d.ncon)), default=0.0)
    return start, d.qpos[:3].copy(), depth


def liemid(binary: str, path: Path, t_end: float, h: float = H, out: Path | None = None,
           timeout: float | None = None) -> dict:
    cmd = [binary, "multibody", str(path), "--method", "liemid", "--step", repr(h),
           "--t-end", repr(t_end), "--json", "-"]
    if out is not None:
        cmd += ["--out", str(out), "--every", "1"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if p.returncode != 0:
        raise RuntimeError(f"exit {p.returncode}: {p.stderr.strip().replace(str(path.parent) + '/', '')}")
    return json.loads(p.stdout)


def body_pos(summary: dict, name: str) -> np.ndarray:
    return np.array(next(b["xpos"] for b in summary["final"] if b["name"] == name))


def along(v: np.ndarray, slope_deg: float) -> float:
    """The component of a displacement along the slope's downhill direction."""
    th = math.radians(slope_deg)
    return float(v[0] * math.cos(th) - v[2] * math.sin(th))


# ---------------------------------------------------------------------------- 1-3: the box

def box_cases(binary: str, tmp: Path) -> list[tuple[str, str, str]]:
    rows = []
    # 1. slope creep
    slope = tmp / "box_slope.xml"
    slope.write_text(box_xml(0.5, 20.0))
    t_end = 10.0
    print("1. Slope creep: 1 kg box, 20 deg, friction 0.5 (Coulomb: sticks), 10 s; distance moved along the slope")
    s = liemid(binary, slope, t_end)
    start = np.array([0.1 * math.sin(math.radians(20)), 0, 0.1 * math.cos(math.radians(20))])
    moved = body_pos(s, "box") - start
    print(f"  liemid h = 1e-3: {abs(along(moved, 20)):.2e} m (total {np.linalg.norm(moved):.2e} m; "
          f"deepest penetration {s['contacts']['deepest_penetration']:.1e} m)")
    rows.append(("slope creep, 10 s", f"{abs(along(moved, 20)):.1e} m", ""))
    best = None
    for setting in SETTINGS:
        for h in MJ_STEPS:
            a, b, _ = mj_box(slope, h, t_end, setting)
            creep = abs(along(b - a, 20))
            print(f"  MuJoCo {setting[0]:32s} h = {h:.0e}: {creep:.2e} m")
            if best is None or creep < best[0]:
                best = (creep, f"{setting[0]}, h = {h:.0e}")
    rows[-1] = (rows[-1][0], rows[-1][1], f"{best[0]:.1e} m ({best[1]})")

    # 2. sliding distance
    flat = tmp / "box_slide.xml"
    mu, v0 = 0.4, 2.0
    flat.write_text(box_xml(mu, 0.0, v0))
    exact = v0 * v0 / (2 * mu * G)
    t_end = 1.5
    print(f"2. Sliding distance: launched at {v0} m/s, friction {mu}; closed form v0^2/(2 mu g) = {exact:.6f} m "
          f"(stops at t = {v0 / (mu * G):.3f} s; run to {t_end} s)")
    s = liemid(binary, flat, t_end)
    dist = float(body_pos(s, "box")[0])
    print(f"  liemid h = 1e-3: {dist:.6f} m, error {dist - exact:+.2e} m")
    rows.append(("sliding distance - v0^2/(2 mu g)", f"{dist - exact:+.1e} m", ""))
    best = None
    for setting in SETTINGS:
        for h in MJ_STEPS:
            a, b, _ = mj_box(flat, h, t_end, setting)
            err = float(b[0] - a[0]) - exact
            print(f"  MuJoCo {setting[0]:32s} h = {h:.0e}: {b[0] - a[0]:.6f} m, error {err:+.2e} m")
            if best is None or abs(err) < abs(best[0]):
                best = (err, f"{setting[0]}, h = {h:.0e}")
    rows[-1] = (rows[-1][0], rows[-1][1], f"{best[0]:+.1e} m ({best[1]})")

    # 3. resting depth
    rest = tmp / "box_rest.xml"
    rest.write_text(box_xml(0.4))
    print("3. Resting depth: the box released at its exact height 0.1 on the floor, after 1 s")
    s = liemid(binary, rest, 1.0)
    depth = 0.1 - float(body_pos(s, "box")[2])
    print(f"  liemid h = 1e-3: centre {depth:+.2e} m below 0.1 (JSON deepest penetration "
          f"{s['contacts']['deepest_penetration']:.1e} m)")
    rows.append(("resting depth after 1 s", f"{depth:.1e} m", ""))
    best = None
    for setting in SETTINGS:
        for h in MJ_STEPS:
            _, b, pen = mj_box(rest, h, 1.0, setting)
            dd = 0.1 - float(b[2])
            print(f"  MuJoCo {setting[0]:32s} h = {h:.0e}: centre {dd:+.2e} m below 0.1 (contact distance "
                  f"{-pen:+.2e} m)")
            if best is None or abs(dd) < abs(best[0]):
                best = (dd, f"{setting[0]}, h = {h:.0e}")
    rows[-1] = (rows[-1][0], rows[-1][1], f"{best[0]:.1e} m ({best[1]})")
    return rows


# ---------------------------------------------------------------------------- 4: the quadruped

FOOT_OFFSET = np.array([0.0, 0.0, -0.213])
FOOT_R = 0.022
LEGS = ["FL", "FR", "RL", "RR"]


def quat_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate v by the unit quaternions q (..., 4: w, x, y, z)."""
    w, u = q[..., :1], q[..., 1:]
    t = 2 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def slips(feet: np.ndarray, quats: np.ndarray, touching: np.ndarray) -> tuple[float, float]:
    """Over each stretch of contact of a foot (feet: (T, 3) sphere centres, quats: (T, 4) its
    attitudes, touching: (T,) bool): the largest horizontal displacement of the centre from
    where the stretch began (rolling included), and the largest horizontal slip of the
    contact point, the sum over steps of the displacement of the material point that touches
    at the step's start, c + R(t+h) R(t)^T (-r z) - (c - r z) (rolling excluded)."""
    down = np.array([0.0, 0.0, -FOOT_R])
    conj = quats * np.array([1.0, -1.0, -1.0, -1.0])
    centre, point, anchor, acc = 0.0, 0.0, None, None
    for k, on in enumerate(touching):
        if on:
            if anchor is None:
                anchor, acc = feet[k, :2], np.zeros(2)
            elif touching[k - 1]:
                turn = quat_mul(quats[k], conj[k - 1])
                acc = acc + (feet[k] + quat_rotate(turn, down) - feet[k - 1] - down)[:2]
            centre = max(centre, float(np.linalg.norm(feet[k, :2] - anchor)))
            point = max(point, float(np.linalg.norm(acc)))
        else:
            anchor = None
    return centre, point


def quad_summary(t: np.ndarray, base_z: np.ndarray, feet: dict, quats: dict, touching: dict) -> dict:
    sl = {leg: slips(feet[leg], quats[leg], touching[leg]) for leg in LEGS}
    return {
        "final": float(base_z[-1]), "least": float(base_z.min()), "t_least": float(t[np.argmin(base_z)]),
        "roll": {leg: sl[leg][0] for leg in LEGS}, "slip": {leg: sl[leg][1] for leg in LEGS},
        "up": bool(base_z.min() > 0.5 * base_z[0]),
        "contact_fraction": {leg: float(touching[leg].mean()) for leg in LEGS},
    }


def mj_quadruped(h: float, t_end: float, setting) -> dict:
    _, cone, imp, noslip = setting
    m = mj_model(QUADRUPED, h, cone, imp, noslip)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    foot_geom = {leg: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"{leg}_foot") for leg in LEGS}
    n = round(t_end / h)
    t, base_z = np.empty(n + 1), np.empty(n + 1)
    feet = {leg: np.empty((n + 1, 3)) for leg in LEGS}
    quats = {leg: np.empty((n + 1, 4)) for leg in LEGS}
    touching = {leg: np.zeros(n + 1, bool) for leg in LEGS}
    for k in range(n + 1):
        if k:
            mujoco.mj_step(m, d)
        t[k], base_z[k] = d.time, d.qpos[2]
        geoms = set()
        for i in range(d.ncon):
            geoms.add(d.contact[i].geom1)
            geoms.add(d.contact[i].geom2)
        for leg in LEGS:
            feet[leg][k] = d.geom_xpos[foot_geom[leg]]
            mujoco.mju_mat2Quat(quats[leg][k], d.geom_xmat[foot_geom[leg]])
            # A foot touches when MuJoCo has an active contact for it at a distance <= 0
            # (its contacts within the margin 0: any contact reported).
            touching[leg][k] = foot_geom[leg] in geoms
    cpu = mj_cpu_per_step(m, t_end)
    return quad_summary(t, base_z, feet, quats, touching) | {"cpu": cpu}


def mj_cpu_per_step(m: mujoco.MjModel, t_end: float) -> float:
    """CPU per step of mj_step(m, d, nstep) from the keyframe (no Python per step)."""
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    n = round(t_end / m.opt.timestep)
    c0 = time.process_time()
    mujoco.mj_step(m, d, nstep=n)
    return (time.process_time() - c0) / n


def liemid_quadruped(binary: str, t_end: float, tmp: Path) -> tuple[dict, dict]:
    out = tmp / "quadruped.csv"
    s = liemid(binary, QUADRUPED, t_end, out=out)
    header = out.read_text().split("\n", 1)[0].split(",")
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    col = {name: k for k, name in enumerate(header)}
    t, base_z = data[:, col["t"]], data[:, col["base.z"]]
    feet, quats, touching = {}, {}, {}
    for leg in LEGS:
        xyz = data[:, [col[f"{leg}_calf.{c}"] for c in "xyz"]]
        q = data[:, [col[f"{leg}_calf.q{c}"] for c in "wxyz"]]
        feet[leg] = xyz + quat_rotate(q, FOOT_OFFSET)
        quats[leg] = q
        # liemid's contacts are hard: a foot touches when its gap is at most 1e-6 m.
        touching[leg] = feet[leg][:, 2] - FOOT_R <= 1e-6
    return quad_summary(t, base_z, feet, quats, touching), s


def quadruped_case(binary: str, tmp: Path) -> list[tuple[str, str, str]]:
    t_end = 5.0
    z0 = float(mujoco.MjModel.from_xml_path(str(QUADRUPED)).key_qpos[0][2])
    print(f"4. Quadruped standing ({QUADRUPED.name}: Go2-style, 15.2 kg, position servos kp 100 kv 3 holding "
          f"the keyframe, feet on the floor at the start, base at {z0:.4f} m), {t_end} s")

    def show(label: str, r: dict) -> None:
        sl = ", ".join(f"{leg} {r['slip'][leg]:.1e}" for leg in LEGS)
        rl = ", ".join(f"{r['roll'][leg]:.1e}" for leg in LEGS)
        cpu = f"; {r['cpu'] * 1e6:.0f} us per step (rough)" if "cpu" in r else ""
        print(f"  {label}: base final {r['final']:.5f} m, least {r['least']:.5f} m (t = {r['t_least']:.3f}), "
              f"{'stays up' if r['up'] else 'FALLS'}{cpu}\n"
              f"    contact-point slip {sl} m; foot-centre travel (rolling included) {rl} m")

    rows = []
    lr, s = liemid_quadruped(binary, t_end, tmp)
    lr["cpu"] = s["stepping_seconds"] / s["steps"]
    show("liemid h = 1e-3", lr)
    c = s["contacts"]
    print(f"    liemid contacts: most points {c['most_points']}, deepest penetration {c['deepest_penetration']:.1e} m, "
          f"position iterations {c['position_iterations'] / s['steps']:.2f} per step, "
          f"{c['solver_sweeps'] / s['steps']:.1f} cone sweeps per step")
    results = []
    for setting in SETTINGS:
        for h in MJ_STEPS:
            r = mj_quadruped(h, t_end, setting)
            show(f"MuJoCo {setting[0]}, h = {h:.0e}", r)
            results.append((setting[0], h, r))
    ref = next(r for name, h, r in results if name == "elliptic impratio 100" and h == 1e-3)
    pyr = next(r for name, h, r in results if name == "pyramidal" and h == 1e-3)
    best = min(results, key=lambda x: max(x[2]["slip"].values()))
    rows.append(("quadruped base height, 5 s (final / least)", f"{lr['final']:.4f} / {lr['least']:.4f} m",
                 f"{ref['final']:.4f} / {ref['least']:.4f} m (elliptic impratio 100, 1e-3); "
                 f"{pyr['final']:.4f} / {pyr['least']:.4f} m (pyramidal, 1e-3)"))
    rows.append(("quadruped largest contact-point slip", f"{max(lr['slip'].values()):.1e} m",
                 f"{max(ref['slip'].values()):.1e} m (elliptic impratio 100, 1e-3); "
                 f"{max(pyr['slip'].values()):.1e} m (pyramidal, 1e-3); "
                 f"least {max(best[2]['slip'].values()):.1e} m ({best[0]}, {best[1]:.0e})"))
    rows.append(("quadruped CPU per step (rough)", f"{lr['cpu'] * 1e6:.0f} us",
                 f"{ref['cpu'] * 1e6:.0f} us (elliptic impratio 100, 1e-3)"))
    return rows


# ---------------------------------------------------------------------------- 5: the pile

def mj_pile(path: Path, t_end: float, setting) -> tuple[float, int, float]:
    """MuJoCo on the pile from rest to t_end: CPU per step (one mj_step call of nstep), the
    contacts at the end and its deepest contact penetration."""
    m = mj_model(path, H, setting[1], setting[2], setting[3])
    d = mujoco.MjData(m)
    n = round(t_end / H)
    c0 = time.process_time()
    mujoco.mj_step(m, d, nstep=n)
    cpu = (time.process_time() - c0) / n
    mujoco.mj_forward(m, d)
    return cpu, d.ncon, max((-d.contact[i].dist for i in range(d.ncon)), default=0.0)


def pile_case(binary: str, tmp: Path, seed: int = 1) -> list[tuple[str, str, str]]:
    t_end = 2.0
    rows = []
    piles = [("100 boxes and spheres", pile_xml(seed=seed)), ("100 spheres", pile_xml(seed=seed, spheres_only=True))]
    for label, text in piles:
        path = tmp / "pile.xml"
        path.write_text(text)
        print(f"5. Pile: {label} (0.05-0.1 m) dropped into a bin, {t_end} s; CPU per step (rough, shared machine)")
        mj = {}
        for setting in [SETTINGS[0], SETTINGS[2]]:
            cpu, ncon, pen = mj_pile(path, t_end, setting)
            print(f"  MuJoCo {setting[0]}, h = 1e-3: {cpu * 1e6:.0f} us per step, {ncon} contacts at the end, "
                  f"deepest contact penetration {pen:.1e} m")
            mj[setting[0]] = cpu
        mj_text = f"{mj['pyramidal'] * 1e6:.0f} us (pyramidal), {mj['elliptic impratio 100'] * 1e6:.0f} us (elliptic impratio 100)"
        t_run, failure = t_end, None
        try:
            s = liemid(binary, path, t_end, timeout=PILE_CAP)
        except subprocess.TimeoutExpired:
            print(f"  liemid: stopped by the cap ({PILE_CAP:.0f} s wall) before t = {t_end}")
            rows.append((f"pile of {label}, CPU per step", f"over the {PILE_CAP:.0f} s cap", mj_text))
            continue
        except RuntimeError as e:
            failure = str(e)
            print(f"  liemid h = 1e-3 FAILED: {failure}")
            # The state just before: run again to the last step that completed.
            t_fail = float(failure.split("at t = ")[1].split(":")[0])
            t_run = round(t_fail / H) * H
            s = liemid(binary, path, t_run, timeout=PILE_CAP)
        per = s["stepping_seconds"] / s["steps"]
        c = s["contacts"]
        print(f"  liemid h = 1e-3 to t = {t_run:.3f}{' (the last step that completed)' if failure else ''}: "
              f"{per * 1e6:.0f} us per step, most points {c['most_points']}, deepest penetration "
              f"{c['deepest_penetration']:.1e} m, {c['position_iterations'] / s['steps']:.2f} position iterations "
              f"and {c['solver_sweeps'] / s['steps']:.0f} cone sweeps per step; {c['loose_steps']} steps taken at the "
              f"acceptance (worst {c['max_loose_violation']:.1e} of the length), {c['split_steps']} split, "
              f"{c['frictionless_drifts']} with friction in the closing kick only")
        if failure:
            cpu, ncon, _ = mj_pile(path, t_run, SETTINGS[0])
            print(f"  MuJoCo pyramidal over the same {t_run:.3f} s: {cpu * 1e6:.0f} us per step ({ncon} contacts at the end)")
            rows.append((f"pile of {label}: liemid fails at t = {t_fail:.3f}",
                         f"{per * 1e6:.0f} us to {t_run:.3f} s, {c['most_points']} points, pen. {c['deepest_penetration']:.0e} m",
                         f"{cpu * 1e6:.0f} us to {t_run:.3f} s (pyramidal); to 2 s: {mj_text}"))
        else:
            rows.append((f"pile of {label}, CPU per step", f"{per * 1e6:.0f} us, penetration {c['deepest_penetration']:.0e} m",
                         mj_text))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--pile-seed", type=int, default=1, help="the seed of the piles' tilts and offsets (default 1)")
    args = parser.parse_args()
    binary = require_liemid("vs_mujoco_contact")
    print(f"MuJoCo {mujoco.__version__}; liemid {binary} --method liemid at h = 1e-3; pile seed {args.pile_seed}")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        rows = box_cases(binary, tmp)
        rows += quadruped_case(binary, tmp)
        rows += pile_case(binary, tmp, args.pile_seed)
    print()
    w = max(len(r[0]) for r in rows)
    print(f"{'question':{w}s} | {'liemid (h = 1e-3)':28s} | MuJoCo (its best setting)")
    for q, a, b in rows:
        print(f"{q:{w}s} | {a:28s} | {b}")


if __name__ == "__main__":
    main()
