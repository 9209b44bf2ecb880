"""The paper's Figure 1 from Python: the errors of every method at t = 0.8 on the fast
top against the step, from liemid.converge (the same study as `liemid converge`).

Run: python examples/python/figure1.py [OUTPUT.png]   (matplotlib is optional: without
it the table is printed and no figure drawn)
"""

from __future__ import annotations

import sys
from typing import Any, List

import liemid


def main(argv: List[str]) -> None:
    study = liemid.converge("fast-top")
    ref = study["reference"]
    print(f"fast top to t = {study['t_end']}; reference: {ref['method']} at h = {ref['step']:.3g}")
    for m in study["methods"]:
        errors = ", ".join("failed" if e is None else f"{e:.2e}" for e in m["attitude_error"])
        order = m["observed_order_attitude"]
        print(f"{m['label']:<12} attitude errors {errors}  observed order {order if order is None else round(order, 2)}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no figure (pip install matplotlib)")
        return
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for m in study["methods"]:
        pts: List[Any] = [(h, pe, re) for h, pe, re in zip(m["steps"], m["momentum_error"], m["attitude_error"]) if pe is not None]
        if not pts:
            continue
        hs, pes, res = zip(*pts)
        axes[0].loglog(hs, pes, "o-", label=m["label"])
        axes[1].loglog(hs, res, "o-", label=m["label"])
    for ax, what in zip(axes, ("momentum", "attitude")):
        ax.set_xlabel("step h (s)")
        ax.set_ylabel(f"{what} error at t = {study['t_end']}")
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=8)
    fig.suptitle("Fast Lagrangian top: error against step (Krysl 2005, Figure 1)")
    fig.tight_layout()
    out = argv[1] if len(argv) > 1 else "figure1.png"
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv)
