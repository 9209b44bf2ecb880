#!/usr/bin/env python3
"""The eccentric satellite (orbit and attitude, one Molniya orbit) from Python: liemid's
reversible adaptive compositions against scipy's DOP853 (`solve_ivp`), CPU time to a final
attitude error.

The same model on both sides (crates/liemid/src/rigid/satellite.rs, docs/adaptive.md):
inertia diag(100, 200, 300) kg m^2, mass 1000 kg, a = 26 560 km, e = 0.74, inclination
63.4 deg, mu = 3.986004418e14, MacCullagh's potential; start at perigee, attitude
exp((0.3, -0.2, 0.5)), body rate n (1, -0.5, 2). scipy integrates the 15-variable ODE
(position, velocity, the rotation matrix R' = R hat(Omega), body momentum
Pi' = Pi x Omega + T) with per-component absolute tolerances (rtol times each block's
scale); its reference is DOP853 at rtol 1e-13, checked against rtol 1e-12 and against
liemid's EX8 at a small fixed step. Error: ||R - R_ref||_F after one orbit.

Time: scipy's CPU time (`time.process_time`) around `solve_ivp`; liemid's the stepping
loop's own time from the command's summary (`wall_time_seconds` of `liemid run --problem
eccentric-satellite --adaptive EPS --json -`: the steps and the per-step energy and
momentum checks, without the process start-up, which is longer than the run); the least
of 5 runs each, on an otherwise idle machine (wall time is then CPU time).
The project's compiled DOP853 is faster per orbit than liemid (docs/adaptive.md); this
script measures what a Python user who would otherwise call `solve_ivp` gets.

Run:  python benchmarks/vs_scipy_satellite.py      (LIEMID_BIN to point at the binary)
Writes docs/vs-scipy-satellite.txt.
Peers: pip install numpy scipy (in a venv of your own).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from pathlib import Path

try:
    import numpy as np
    from scipy.integrate import solve_ivp
except ImportError as e:  # pragma: no cover - the skip path
    print(f"vs_scipy_satellite: skipped, a peer is missing ({e}); pip install numpy scipy")
    sys.exit(0)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from liemid_binary import require_liemid  # noqa: E402

LIEMID = require_liemid("vs_scipy_satellite")

MU = 3.986004418e14
MASS = 1000.0
INERTIA = np.array([100.0, 200.0, 300.0])
TRACE = INERTIA.sum()
A, E, INC = 26_560e3, 0.74, math.radians(63.4)
N = math.sqrt(MU / A**3)
PERIOD = 2 * math.pi / N


def hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def so3_exp(w):
    th = np.linalg.norm(w)
    k = hat(w / th)
    return np.eye(3) + math.sin(th) * k + (1 - math.cos(th)) * k @ k


def initial_state():
    rp = A * (1 - E)
    vp = math.sqrt(MU * (1 + E) / rp)
    r = np.array([rp, 0.0, 0.0])
    v = np.array([0.0, math.cos(INC), math.sin(INC)]) * vp
    R = so3_exp(np.array([0.3, -0.2, 0.5]))
    pi = INERTIA * (np.array([1.0, -0.5, 2.0]) * N)
    return np.concatenate([r, v, R.ravel(), pi])


def rhs(_t, y):
    r, v, R, pi = y[0:3], y[3:6], y[6:15].reshape(3, 3), y[15:18]
    u = R.T @ r
    r2 = r @ r
    inv_r3 = 1.0 / (r2 * math.sqrt(r2))
    k = 3.0 * MU * inv_r3 / r2
    iu = INERTIA * u
    s = u @ iu
    force = r * (-MU * MASS * inv_r3 + k * (2.5 * s / r2 - 0.5 * TRACE)) - (R @ iu) * k
    torque = np.cross(u, iu) * k
    omega = pi / INERTIA
    return np.concatenate([v, force / MASS, (R @ hat(omega)).ravel(), np.cross(pi, omega) + torque])


Y0 = initial_state()
SCALE = np.concatenate([np.full(3, A), np.full(3, np.linalg.norm(Y0[3:6])), np.ones(9),
                        np.full(3, np.linalg.norm(Y0[15:18]))])


def scipy_run(rtol):
    c0 = time.process_time()
    sol = solve_ivp(rhs, (0.0, PERIOD), Y0, method="DOP853", rtol=rtol, atol=rtol * SCALE)
    cpu = time.process_time() - c0
    return sol.y[6:15, -1].reshape(3, 3), sol.nfev, cpu


def liemid_run(method, args):
    """The final attitude, the steps and the time of the command's stepping loop (its
    `wall_time_seconds`: the steps and their energy/momentum checks, no start-up)."""
    cmd = [LIEMID, "run", "--problem", "eccentric-satellite", "--method", method, *args, "--json", "-"]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True)
    js = json.loads(out.stdout)
    return np.array(js["rotation"]).reshape(3, 3), js["steps"], js["wall_time_seconds"]


def least_cpu(run, *args, repeats=5):
    best = None
    for _ in range(repeats):
        got = run(*args)
        if best is None or got[-1] < best[-1]:
            best = got
    return best


def interp_cpu(points, level):
    """CPU at `level` by log-log interpolation between the neighbouring (error, cpu)."""
    pts = sorted(points, key=lambda p: -p[0])
    for (e0, c0), (e1, c1) in zip(pts, pts[1:]):
        if e0 >= level >= e1 and e0 > 0 and e1 > 0:
            w = math.log(e0 / level) / math.log(e0 / e1)
            return math.exp(math.log(c0) + w * math.log(c1 / c0))
    return None


LINES: list[str] = []


def say(line: str) -> None:
    print(line, flush=True)
    LINES.append(line)


def main():
    say(f"vs_scipy_satellite: liemid ({LIEMID}) against scipy {__import__('scipy').__version__} "
          f"DOP853, numpy {np.__version__}; one orbit ({PERIOD:.1f} s) of the eccentric satellite")
    ref, nfev, cpu = scipy_run(1e-13)
    check, _, _ = scipy_run(1e-12)
    say(f"  reference: DOP853 rtol 1e-13 ({nfev} evaluations, {cpu:.2f} s); rtol 1e-12 differs by "
          f"{np.linalg.norm(check - ref):.1e}")
    ex8, steps, _ = liemid_run("liemid-ex8", ["--step", repr(PERIOD / 20000)])
    say(f"  liemid EX8 at T/20000 ({steps} steps) differs from the reference by {np.linalg.norm(ex8 - ref):.1e}")

    curves = {}
    rows = []
    for rtol in [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]:
        R, nfev, cpu = least_cpu(scipy_run, rtol)
        err = float(np.linalg.norm(R - ref))
        rows.append(("scipy DOP853", f"rtol {rtol:g}", nfev, err, cpu))
        curves.setdefault("scipy DOP853", []).append((err, cpu))
    for method, epss in [("liemid-ea4", [0.1, 0.05, 0.025, 0.0125]),
                         ("liemid-ea8", [0.2, 0.1, 0.05, 0.025, 0.0125])]:
        for eps in epss:
            R, steps, cpu = least_cpu(liemid_run, method, ["--adaptive", repr(eps)])
            err = float(np.linalg.norm(R - ref))
            rows.append((method, f"eps {eps:g}", steps, err, cpu))
            curves.setdefault(method, []).append((err, cpu))
    say(f"  {'method':<14} {'setting':<12} {'evals/steps':>11} {'attitude error':>15} {'time s':>10}")
    for name, setting, n, err, cpu in rows:
        say(f"  {name:<14} {setting:<12} {n:>11d} {err:>15.2e} {cpu:>10.2e}")
    for level in (1e-6, 1e-9):
        sc = interp_cpu(curves["scipy DOP853"], level)
        best = min(((m, interp_cpu(p, level)) for m, p in curves.items() if m != "scipy DOP853"),
                   key=lambda mc: mc[1] if mc[1] is not None else math.inf)
        if sc is None or best[1] is None:
            say(f"  attitude error {level:g}: not bracketed by the runs")
            continue
        say(f"  attitude error {level:g}: scipy DOP853 {sc:.3g} s, best liemid {best[0]} {best[1]:.3g} s:"
              f" scipy / liemid = {sc / best[1]:.1f}x")


if __name__ == "__main__":
    main()
    out = Path(__file__).resolve().parents[1] / "docs" / "vs-scipy-satellite.txt"
    out.write_text("\n".join(LINES) + "\n")
    print(f"wrote {out.relative_to(out.parents[1])}")
