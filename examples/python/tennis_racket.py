"""The tennis-racket (Dzhanibekov) flip: a free body spun about its intermediate axis
turns over again and again, while LIEMID[EA] keeps |Π|, the spatial momentum and (to a
bounded error) the energy.

Run: python examples/python/tennis_racket.py [OUTPUT.png]   (matplotlib optional)
"""

from __future__ import annotations

import sys
from typing import List

import numpy as np

import liemid


def main(argv: List[str]) -> None:
    body = liemid.RigidBody([1.0, 2.0, 3.0])  # kg m^2; the intermediate axis is the second
    sol = liemid.integrate(
        body,
        angular_velocity=[1e-3, 2.0, 1e-3],  # rad/s, almost about the intermediate axis
        t_end=60.0,
        step=1e-3,
        every=10,
    )
    pi2 = sol.pi[:, 1]
    flips = np.nonzero(np.diff(np.sign(pi2)) != 0)[0]
    times = sol.t[flips]
    print(f"{sol.steps} steps of 1 ms in {sol.wall_time * 1e3:.1f} ms; the body turns over at t = {np.round(times, 2).tolist()} s")
    if len(times) > 1:
        print(f"period of the flip: {np.mean(np.diff(times)):.3f} s")
    norm = np.linalg.norm(sol.pi, axis=1)
    print(f"largest change of |Pi|: {np.max(np.abs(norm - norm[0])):.1e}; of the spatial momentum: {np.max(np.abs(sol.spatial_momentum - sol.spatial_momentum[0])):.1e}")
    print(f"largest relative energy error: {sol.max_energy_error:.1e}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no figure (pip install matplotlib)")
        return
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for k in range(3):
        ax.plot(sol.t, sol.pi[:, k], label=f"Pi{k + 1}")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("body angular momentum (kg m^2/s)")
    ax.legend()
    fig.tight_layout()
    out = argv[1] if len(argv) > 1 else "tennis_racket.png"
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv)
