"""The 3-D page of a run, shared by every domain's result: ``view(path)`` writes a
self-contained HTML file (three.js and the data inlined; it loads nothing), and
``_repr_html_`` shows it inline in a notebook (an iframe with ``srcdoc``)."""

from __future__ import annotations

import html
import json
from typing import Any, Dict, Optional

import numpy as np
from numpy.typing import ArrayLike

from . import _liemid


def page(
    scene: Dict[str, Any],
    title: str,
    t: ArrayLike,
    frames: ArrayLike,
    energy_t: ArrayLike,
    energy_e: ArrayLike,
    steps: int,
    path: Optional[str] = None,
) -> str:
    """Write the page to ``path`` and return the path, or return the page's HTML."""

    def flat(a: ArrayLike) -> Any:
        return np.ascontiguousarray(np.asarray(a, dtype=np.float64).reshape(-1))

    return _liemid.view_page(
        json.dumps(scene), title, flat(t), flat(frames), flat(energy_t), flat(energy_e), int(steps), path
    )


def iframe(page_html: str, height: int = 600) -> str:
    """The page inline in a notebook."""
    return f'<iframe srcdoc="{html.escape(page_html, quote=True)}" style="width:100%;height:{height}px;border:0"></iframe>'


def box_of_inertia(moments: ArrayLike) -> list[float]:
    """Half the edges of a uniform box with these principal moments, the largest 1."""
    a, b, c = (float(v) for v in np.asarray(moments, dtype=np.float64).reshape(3))
    s = a + b + c
    h = [max(v, 0.01 * s) ** 0.5 for v in (b + c - a, a + c - b, a + b - c)]
    return [v / max(h) for v in h]
