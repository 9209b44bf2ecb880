"""Flexible 3-D beams (``liemid beam``): corotational elements whose nodes are rigid bodies.

Translations by Verlet, nodal rotations by the explicit midpoint Lie splitting (``"liemid"``,
order 2, time-reversible, momenta kept for a free structure; ``"liemid4"``, order 4;
``"liemid-mts"``, axial forces in substeps; ``"liemid-sms"``, selective mass scaling of the
axial waves for a 5.7x larger step on the right-angle cantilever), or the
implicit Newmark baseline (``"newmark"``), on a built-in benchmark or a structure file
(the TOML format of ``liemid beam``). The liemid methods' nodes turn by EA's midpoint half
steps (``drift="midpoint"``, the default) or by LIEMID[EAV]'s variational ones
(``drift="variational"``, a Lie–Poisson rotation: the step then keeps the symplectic form).

>>> from liemid import beam
>>> run = beam.run("right-angle-cantilever", elements_per_member=4, t_end=3.0, sample=0.1)
>>> run.tracked["elbow"].shape
(31, 3)
>>> bool(run.tracked["elbow"][10, 2] > 0.5)
True
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Tuple, Union

import numpy as np
from numpy.typing import NDArray

from . import _liemid, _view
from ._core import _count, _max_steps, _path, _text

__all__ = ["BeamRun", "methods", "problems", "run"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class BeamRun:
    """A sampled run: ``t`` (n,), ``tracked[name]`` (n, 3) displacements of the named
    nodes, ``energy`` (n,) (empty for Newmark), and what it cost."""

    method: str
    drift: Optional[str]
    t: FloatArray
    tracked: Dict[str, FloatArray]
    energy: FloatArray
    steps: int
    step: float
    critical_step: float
    elements: int
    wall_seconds: float
    element_steps_per_second: float
    newton_iterations: Optional[int]
    page: Optional[str] = field(default=None, repr=False)

    def view(self, path: Optional[str] = None) -> str:
        """The run as a self-contained 3-D page (the deformed centre line and the nodes'
        section frames at every sample, and the energy): written to ``path`` (returns it),
        or returned as HTML without a path. Needs a run made with ``view=True``."""
        if self.page is None:
            raise ValueError("this run kept no frames: run it with beam.run(..., view=True)")
        if path is None:
            return self.page
        return str(_liemid.write_output("view", _path("path", path), self.page))

    def _repr_html_(self) -> Optional[str]:
        return None if self.page is None else _view.iframe(self.page)


def _optional_number(name: str, value: Optional[float]) -> Optional[float]:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"{name}: expected a number, found {type(value).__name__}")
    return float(value)


def run(
    problem: Optional[str] = None,
    *,
    file: Union[str, Path, None] = None,
    text: Optional[str] = None,
    elements_per_member: Optional[int] = None,
    method: Optional[str] = None,
    step: Optional[float] = None,
    t_end: Optional[float] = None,
    sample: Optional[float] = None,
    force_step: bool = False,
    view: bool = False,
    drift: Optional[str] = None,
    max_steps: Optional[int] = None,
) -> BeamRun:
    """Run a benchmark (``problems()``) or a structure (``file`` path or its ``text``).

    ``step`` defaults to 0.9 of the critical step (explicit) or 0.05 (Newmark); an explicit
    step above the critical one raises ``ValueError`` unless ``force_step``. ``sample`` is
    the output interval (default ``t_end/600``). A failed Newton iteration raises
    ``liemid.ConvergenceError``. With ``view=True`` the run keeps its 3-D page
    (``BeamRun.view``). ``drift`` is the liemid methods' node rotation, ``"midpoint"`` or
    ``"variational"`` (default: the file's, else midpoint; ``BeamRun.drift`` is ``None``
    for Newmark, which refuses ``"variational"``). Once the step is known and before the
    first, a run of more than ``max_steps`` steps (default 10⁹) raises ``ValueError``, and
    samples that would not fit in the memory available ``MemoryError`` (raise ``sample``).
    Ctrl-C stops the run with ``KeyboardInterrupt``.
    """
    sources = [s is not None for s in (problem, file, text)]
    if sum(sources) > 1:
        raise ValueError("give one of problem, file, text")
    if file is not None:
        text = _liemid.read_input("file", _path("file", file))
    if problem is None and text is None:
        problem = "right-angle-cantilever"
    out = _liemid.beam_run(
        None if problem is None else _text("problem", problem),
        None if text is None else _text("text", text),
        None if elements_per_member is None else _count("elements_per_member", elements_per_member, 1),
        None if method is None else _text("method", method),
        _optional_number("step", step),
        _optional_number("t_end", t_end),
        _optional_number("sample", sample),
        bool(force_step),
        bool(view),
        None if drift is None else _text("drift", drift),
        _max_steps(max_steps),
    )
    tracked = {name: np.asarray(out["tracked"][name]).reshape(-1, 3) for name in out["names"]}
    return BeamRun(
        method=str(out["method"]),
        drift=None if out["drift"] is None else str(out["drift"]),
        t=np.asarray(out["t"]),
        tracked=tracked,
        energy=np.asarray(out["energy"]),
        steps=int(out["steps"]),
        step=float(out["step"]),
        critical_step=float(out["critical_step"]),
        elements=int(out["elements"]),
        wall_seconds=float(out["wall_seconds"]),
        element_steps_per_second=float(out["element_steps_per_second"]),
        newton_iterations=None if out["newton_iterations"] is None else int(out["newton_iterations"]),
        page=None if out["page"] is None else str(out["page"]),
    )


def problems() -> List[Tuple[str, str]]:
    """The built-in benchmarks: (name, description)."""
    return list(_liemid.beam_problems())


def methods() -> List[Tuple[str, int]]:
    """The beam methods: (name, order)."""
    return list(_liemid.beam_methods())
