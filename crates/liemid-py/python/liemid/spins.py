"""Atomistic spin dynamics: classical unit spins on a lattice (``liemid spins``).

``E = -J sum_<ij> S_i.S_j - K sum (S_i.n)^2 - mu_s mu_B B.sum S_i`` (meV, T, ps, each pair
once), integrated by the explicit symplectic bond-colour splitting (``"split"``, and
``"split4"``, ``"split6"``, ``"split8"``), the implicit midpoint rule (``"midpoint"``: energy
exact, damping) or the field's baselines (``"heun"``, ``"depondt"``, ``"rk4"``).

>>> from liemid import spins
>>> system, start = spins.problem("square-64")
>>> run = spins.integrate(system, start, t_end=1.0, step=1e-2)
>>> bool(abs(run.energy[-1] - run.energy[0]) < 1e-6 * abs(run.energy[0]))
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _liemid, _view
from ._core import _array, _count, _max_steps, _number, _show, _text

__all__ = ["System", "SpinRun", "integrate", "methods", "near_z", "problem"]

FloatArray = NDArray[np.float64]


class System:
    """A lattice of unit spins and its Hamiltonian.

    Parameters
    ----------
    kind : {"chain", "square", "cubic"}
    size : sequence of int
        Sites along each axis (1, 2 or 3 numbers for the kind); site index
        ``x + nx * (y + ny * z)``.
    periodic : bool
    exchange, anisotropy : float
        ``J`` and ``K`` in meV.
    anisotropy_axis, field : array_like of 3
        ``n`` (normalised) and ``B`` in tesla.
    mu_s : float
        Moment per spin in Bohr magnetons.
    damping : float
        Gilbert ``alpha`` (every method, the splitting by the exact damped flows of its parts).
    dmi : float
        Dzyaloshinskii-Moriya strength ``D`` in meV, each bond ``-D_ij . (S_i x S_j)``.
    dmi_kind : {"interfacial", "bulk"}
        ``D_ij = D (z x r_ij)`` (a film: Neel skyrmions; Spirit's ``dm_chirality -2``) or
        ``D_ij = D r_ij`` (B20 magnets: Bloch skyrmions; Spirit's ``1``).
    """

    def __init__(
        self,
        kind: str = "square",
        size: Sequence[int] = (64, 64),
        *,
        periodic: bool = True,
        exchange: float = 1.0,
        anisotropy: float = 0.0,
        anisotropy_axis: ArrayLike = (0.0, 0.0, 1.0),
        field: ArrayLike = (0.0, 0.0, 0.0),
        mu_s: float = 1.0,
        damping: float = 0.0,
        dmi: float = 0.0,
        dmi_kind: str = "interfacial",
    ) -> None:
        if not isinstance(kind, str):
            raise TypeError(f"kind: expected a string, found {type(kind).__name__}")
        if isinstance(size, (str, bytes)) or not isinstance(size, (list, tuple, np.ndarray)):
            raise TypeError(f"size: expected a sequence of sites along each axis, found {type(size).__name__}")
        sizes = [_count("size", s) for s in size]
        if any(s < 1 for s in sizes):
            raise ValueError(f"size: every axis needs at least one site, found {_show(sizes)}")
        n = _array("anisotropy_axis", anisotropy_axis, (3,))
        b = _array("field", field, (3,))
        self._inner = _liemid.Spins(
            kind,
            sizes,
            bool(periodic),
            _number("exchange", exchange),
            _number("anisotropy", anisotropy),
            (float(n[0]), float(n[1]), float(n[2])),
            (float(b[0]), float(b[1]), float(b[2])),
            _number("mu_s", mu_s),
            _number("damping", damping),
            _number("dmi", dmi),
            _text("dmi_kind", dmi_kind),
        )

    def __len__(self) -> int:
        return int(self._inner.len)

    @property
    def size(self) -> Tuple[int, int, int]:
        """Sites along each axis (1 for missing axes)."""
        s = self._inner.size
        return (int(s[0]), int(s[1]), int(s[2]))

    def energy(self, spins: ArrayLike) -> float:
        """The energy (meV) of ``spins``, shape (N, 3) (each row normalised first)."""
        return float(self._inner.energy(self._flat(spins)))

    def _flat(self, spins: ArrayLike) -> FloatArray:
        return _array("spins", spins, (len(self), 3)).reshape(-1)


@dataclass(frozen=True)
class SpinRun:
    """A run: the observed times (ps), energies (meV), mean spin (K, 3), the final spins
    (N, 3) and the stepping time (s)."""

    t: FloatArray
    energy: FloatArray
    magnetisation: FloatArray
    final: FloatArray
    seconds: float

    def view(self, system: System, path: Optional[str] = None) -> str:
        """The final spins of the run on ``system``'s lattice as a self-contained 3-D page
        (arrows coloured by S_z) with the relative energy error along the run: written to
        ``path`` (returns it), or returned as HTML without a path."""
        if not isinstance(system, System):
            raise TypeError(f"system: expected liemid.spins.System, found {type(system).__name__}")
        if len(system) != len(self.final):
            raise ValueError(f"system: {len(system)} sites, but the run has {len(self.final)} spins")
        nx, ny, _ = system.size
        n = len(system)
        i = np.arange(n)
        sites = np.stack([i % nx, (i // nx) % ny, i // (nx * ny)], axis=1).astype(float).tolist()
        e0 = float(self.energy[0])
        error = (self.energy - e0) / (abs(e0) if e0 != 0.0 else 1.0)
        t = float(self.t[-1])
        return _view.page({"kind": "spins", "sites": sites}, f"{n} spins at t = {t:g} ps", [t], self.final, self.t, error, 0, path)

    @property
    def max_relative_energy_error(self) -> float:
        """Largest ``|E - E0| / |E0|`` over the observations."""
        e0 = self.energy[0]
        return float(np.max(np.abs(self.energy - e0)) / (abs(e0) if e0 != 0.0 else 1.0))


def integrate(
    system: System,
    spins: ArrayLike,
    *,
    t_end: float,
    step: float,
    method: str = "split",
    every: int = 10,
    threads: int = 0,
    max_steps: Optional[int] = None,
) -> SpinRun:
    """Integrate from ``spins`` (N, 3) to ``t_end`` (ps) with ``step``; observe every
    ``every`` steps. ``threads`` 0 uses all cores; results are the same for any count. The
    GIL is released while stepping. Before the first step, a run of more than
    ``max_steps`` steps (default 10⁹) raises ``ValueError``, and observations that would
    not fit in the memory available ``MemoryError``. Ctrl-C stops the run with
    ``KeyboardInterrupt``."""
    if not isinstance(system, System):
        raise TypeError(f"system: expected liemid.spins.System, found {type(system).__name__}")
    t, e, m, final, seconds = system._inner.integrate(
        system._flat(spins),
        _text("method", method),
        _number("step", step),
        _number("t_end", t_end),
        _count("every", every, 1),
        _count("threads", threads),
        _max_steps(max_steps),
    )
    return SpinRun(t, e, m.reshape(-1, 3), final.reshape(-1, 3), float(seconds))


def problem(name: str) -> Tuple[System, FloatArray]:
    """The built-in problem ``name`` (``"square-64"``, ``"chain-64"``, ``"skyrmion"``): its system and start."""
    inner, flat, _step, _t_end = _liemid.Spins.problem(_text("name", name))
    system = System.__new__(System)
    system._inner = inner
    return system, flat.reshape(-1, 3)


def near_z(n: int, *, max_tilt: float = 0.3, seed: int = 1) -> FloatArray:
    """``n`` spins tilted from +z by angles uniform in ``[0, max_tilt]`` rad (seeded)."""
    return _liemid.spins_near_z(_count("n", n), _number("max_tilt", max_tilt), _count("seed", seed)).reshape(-1, 3)


def methods() -> List[Tuple[str, int, bool, str]]:
    """``(name, order, handles damping, description)`` of every spin method."""
    return [(str(a), int(b), bool(c), str(d)) for a, b, c, d in _liemid.spin_methods()]
