"""liemid.integrate against scipy.integrate.solve_ivp(method="DOP853") on the paper's fast
top to t = 0.8, at an attitude error of 1e-6; the Python overhead of liemid.integrate over
its Rust run; the cost of a Python callable torque per step; liemid.ensemble on 1 and 2
threads. Installs nothing: without numpy or the liemid package the script skips with a
message; without scipy, the solve_ivp comparison is skipped with a message.

Run: python benchmarks/vs_scipy.py
"""

from __future__ import annotations

import statistics
import sys
import time

try:
    import numpy as np
except ImportError:
    print("vs_scipy: numpy is not installed; skipping")
    sys.exit(0)
try:
    import liemid
except ImportError:
    print("vs_scipy: the liemid package is not installed (pip install ./crates/liemid-py); skipping")
    sys.exit(0)

TOP = liemid.problems.fast_top()
T_END = 0.8
TARGET = 1e-6


def timed(f, repeat=5):
    f()  # warm-up
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def attitude_error(r, ref):
    return float(np.max(np.abs(r - ref)))


def main() -> None:
    ref = TOP.integrate(method="liemid-ea8", step=2e-5, t_end=T_END, every=10**9).rotation[-1]
    check = TOP.integrate(method="liemid-ea8", step=1e-5, t_end=T_END, every=10**9).rotation[-1]
    print(f"reference: LIEMID[EA]8 at h = 2e-5 (agrees with h = 1e-5 to {attitude_error(ref, check):.1e})")

    # liemid: the fastest method and step reaching the target.
    best = None
    for method in ("liemid-ea", "liemid-ea4", "liemid-ea6", "liemid-ea8", "liemid-ex", "liemid-ex4", "liemid-ex6", "liemid-ex8"):
        h = 0.1 if "-ex" in method else 8e-3
        while h > 1e-6:
            try:
                sol = TOP.integrate(method=method, step=h, t_end=T_END, every=10**9)
            except liemid.ConvergenceError:
                h /= 1.25
                continue
            if attitude_error(sol.rotation[-1], ref) <= TARGET:
                # The largest step in (h, 1.25 h) that still meets the target, to 1%.
                for f in (1.2, 1.15, 1.1, 1.05, 1.02, 1.01):
                    try:
                        if attitude_error(TOP.integrate(method=method, step=h * f, t_end=T_END, every=10**9).rotation[-1], ref) <= TARGET:
                            h *= f
                            break
                    except liemid.ConvergenceError:
                        pass
                seconds, _ = timed(lambda: TOP.integrate(method=method, step=h, t_end=T_END, every=10**9))
                if best is None or seconds < best[0]:
                    best = (seconds, method, h)
                break
            h /= 1.25
    assert best is not None
    print(f"liemid  {best[1]} h = {best[2]:.3e}: {best[0] * 1e3:.3f} ms to attitude error <= {TARGET:g}")

    try:
        from scipy.integrate import solve_ivp
    except ImportError:
        print("scipy is not installed: the solve_ivp comparison is skipped (pip install scipy)")
    else:
        inertia = TOP.body.inertia
        inv = np.linalg.inv(inertia)
        g = TOP.body.torque
        weight = g.mass * np.array(g.gravity)
        com = np.array(g.center_of_mass)

        def quat_to_matrix(q):
            w, x, y, z = q / np.linalg.norm(q)
            return np.array([
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ])

        def rhs(t, y):
            pi, q = y[:3], y[3:]
            w_ = inv @ pi
            r = quat_to_matrix(q)
            dpi = np.cross(pi, w_) + np.cross(com, r.T @ weight)
            qw, qx, qy, qz = q
            dq = 0.5 * np.array([
                -qx * w_[0] - qy * w_[1] - qz * w_[2],
                qw * w_[0] + qy * w_[2] - qz * w_[1],
                qw * w_[1] + qz * w_[0] - qx * w_[2],
                qw * w_[2] + qx * w_[1] - qy * w_[0],
            ])
            return np.concatenate([dpi, dq])

        q0 = TOP.integrate(t_end=0.0).quaternion[0]
        y0 = np.concatenate([TOP.angular_momentum, q0])
        found = None
        for rtol in (1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 1e-8, 1e-9, 1e-10):
            t = time.perf_counter()
            out = solve_ivp(rhs, (0.0, T_END), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-3)
            seconds = time.perf_counter() - t
            err = attitude_error(quat_to_matrix(out.y[3:, -1]), ref)
            print(f"scipy   DOP853 rtol = {rtol:.0e}: attitude error {err:.2e}, {seconds:.3f} s, {out.nfev} evaluations")
            if err <= TARGET:
                found = (seconds, rtol)
                break
        if found is None:
            print("scipy did not reach the target")
        else:
            print(f"ratio   scipy / liemid at attitude error {TARGET:g}: {found[0] / best[0]:,.0f}x")

    # Python overhead of integrate over its own Rust run (runs of 10 ms and more). The
    # results are kept, so that freeing the previous one (13 MB for 80,001 rows) is not
    # counted in the next call.
    for h, every in ((1e-5, 10**9), (1e-5, 1), (4e-6, 100)):
        kept = []
        totals = []
        for _ in range(6):
            t = time.perf_counter()
            sol = TOP.integrate(method="liemid-ea", step=h, t_end=T_END, every=every)
            totals.append((time.perf_counter() - t, sol.wall_time))
            kept.append(sol)
        total, rust = sorted(totals[1:])[2]
        print(
            f"overhead EA h = {h:g}, {len(sol.t)} rows: {total * 1e3:.2f} ms in Python, "
            f"{rust * 1e3:.2f} ms in the Rust run: {100 * (total - rust) / rust:.1f}%"
        )
        del kept

    # The callable-torque path.
    def torque(R, t):
        return np.cross(com_, R.T @ weight_)

    g_ = TOP.body.torque
    weight_ = g_.mass * np.array(g_.gravity)
    com_ = np.array(g_.center_of_mass)
    n = 20000
    t_fast, _ = timed(lambda: TOP.integrate(step=T_END / n, t_end=T_END, every=10**9), repeat=3)
    for label, f in (("a constant torque in Python", lambda R, t: (0.0, 0.0, 0.0)), ("gravity with numpy", torque)):
        body = liemid.RigidBody(TOP.body.inertia, torque=f)
        t_slow, _ = timed(
            lambda: liemid.integrate(body, rotation=TOP.rotation, angular_momentum=TOP.angular_momentum, t_end=T_END, step=T_END / n, every=10**9),
            repeat=3,
        )
        print(
            f"callable torque ({label}): {t_slow / n * 1e6:.2f} us per EA step (one call) against "
            f"{t_fast / n * 1e9:.0f} ns built in"
        )

    # Ensembles on 1 and 2 threads.
    N = 100_000
    rng = np.random.default_rng(1)
    rv = rng.normal(size=(N, 3)) * 0.05
    w = np.zeros((N, 3))
    w[:, 2] = 983.3185
    res = {}
    for threads in (1, 2):
        res[threads] = timed(lambda: liemid.ensemble(TOP.body, rotation_vectors=rv, angular_velocities=w, t_end=0.01, step=1e-4, threads=threads), repeat=3)
    same = res[1][1].pi.tobytes() == res[2][1].pi.tobytes() and res[1][1].rotation.tobytes() == res[2][1].rotation.tobytes()
    print(
        f"ensemble of {N:,} heavy tops, 100 steps: 1 thread {res[1][0]:.3f} s, 2 threads {res[2][0]:.3f} s: "
        f"{res[1][0] / res[2][0]:.2f}x, same bits: {same}"
    )


if __name__ == "__main__":
    main()
