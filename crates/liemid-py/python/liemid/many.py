"""Many interacting rigid bodies (``liemid::many``): the splitting integrator built from
the paper's pieces, one force and torque evaluation per step,

    p ← p + (h/2) F,  Π ← Π + (h/2) T;   x ← x + h p/m;
    (Π, R) ← torque-free midpoint Lie rotation over h (two half-step solves, as EA);
    F, T ← forces and torques at the new configuration;   p, Π ← same half impulses,

time-reversible, keeping total linear and angular momentum of
translation- and rotation-invariant interactions to round-off; bit-identical for any
thread count. For one body it is LIEMID[EA].
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Tuple, Union

import numpy as np
from numpy.typing import ArrayLike

from . import _liemid, _view
from ._core import FloatArray, _array, _broadcast, _count, _max_steps, _number, _text, _vec3

__all__ = ["Dipoles", "Independent", "System", "Totals"]


@dataclass(frozen=True)
class Independent:
    """Bodies that do not interact: rotors about their own pivots in uniform ``gravity``
    (m/s²) with centre of mass ``center_of_mass`` (body frame, m), or torque-free bodies
    with the defaults."""

    gravity: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    center_of_mass: Tuple[float, float, float] = (0.0, 0.0, 0.0)

    def _spec(self) -> Tuple[Any, ...]:
        return ("independent", _vec3("gravity", self.gravity), _vec3("center_of_mass", self.center_of_mass))


@dataclass(frozen=True)
class Dipoles:
    """Point dipoles ``moment`` (body frame) with WCA repulsion (``sigma``, ``epsilon``), an
    optional ``cutoff`` (the dipole energy switched off smoothly from ``switch_start``,
    default 0.8 cutoff, or with ``cutoff_form="shifted-force"`` LAMMPS's ``lj/sf/dipole/sf``
    form) and periodic box of side ``box_length`` (at least twice the cutoff).
    """

    moment: Tuple[float, float, float] = (0.0, 0.0, 1.0)
    sigma: float = 1.0
    epsilon: float = 1.0
    cutoff: Optional[float] = None
    box_length: Optional[float] = None
    switch_start: Optional[float] = None
    cutoff_form: str = "switched"

    def _spec(self) -> Tuple[Any, ...]:
        def opt(name: str, v: Optional[float]) -> Optional[float]:
            return None if v is None else _number(name, v)

        return (
            "dipoles",
            _vec3("moment", self.moment),
            _number("sigma", self.sigma),
            _number("epsilon", self.epsilon),
            opt("cutoff", self.cutoff),
            opt("box_length", self.box_length),
            opt("switch_start", self.switch_start),
            _text("cutoff_form", self.cutoff_form),
        )


@dataclass(frozen=True)
class Totals:
    """Total energy (kinetic plus potential), linear momentum Σp and angular momentum
    Σ (x × p + R Π) about the origin."""

    energy: float
    linear_momentum: FloatArray
    angular_momentum: FloatArray


class System:
    """N rigid bodies and their interaction, stepped in place.

    Parameters
    ----------
    masses : (N,) array_like
    inertia : (N, 3) or (3,) array_like
        Principal moments of each body (broadcast from one row).
    positions, rotations, angular_momenta : (N, 3), (N, 3, 3), (N, 3) array_like
        Centres of mass (pivots of rotors), attitudes, body angular momenta.
    momenta : (N, 3) array_like, optional
        Linear momenta (default zero).
    free : bool or (N,) array_like of bool
        Free bodies translate; rotors turn about a fixed pivot (default: free).
    model : Independent or Dipoles
    rotation : {"midpoint", "exact", "variational"}
        How each body turns between the impulses: the torque-free midpoint Lie rule in two
        half steps (as LIEMID[EA], the default), the exact torque-free flow (as
        LIEMID[EX]: no error in the free spin, no Newton solve; costlier per step for
        asymmetric bodies) or two half steps of the variational equation (as
        LIEMID[EAV]: a Lie–Poisson rotation, so the step keeps the symplectic form; no
        SIMD lanes).
    """

    def __init__(
        self,
        masses: ArrayLike,
        inertia: ArrayLike,
        positions: ArrayLike,
        rotations: ArrayLike,
        angular_momenta: ArrayLike,
        *,
        momenta: Optional[ArrayLike] = None,
        free: Union[bool, ArrayLike] = True,
        model: Union[Independent, Dipoles] = Independent(),
        rotation: str = "midpoint",
    ) -> None:
        if not isinstance(model, (Independent, Dipoles)):
            raise TypeError(f"model: expected liemid.many.Independent or Dipoles, found {type(model).__name__}")
        m = _masses(masses)
        if m.ndim != 1:
            raise ValueError(f"masses: expected shape (N,), found {m.shape}")
        n = m.shape[0]
        free_arr = np.broadcast_to(np.asarray(free, dtype=bool), (n,))
        self._inner = _liemid.ManyBodies(
            _array("masses", m, (n,)).tolist(),
            _broadcast("inertia", inertia, (3,), n).reshape(-1).tolist(),
            [bool(f) for f in free_arr],
            _broadcast("positions", positions, (3,), n).reshape(-1).tolist(),
            _broadcast("momenta", np.zeros(3) if momenta is None else momenta, (3,), n).reshape(-1).tolist(),
            _broadcast("rotations", rotations, (3, 3), n).reshape(-1).tolist(),
            _broadcast("angular_momenta", angular_momenta, (3,), n).reshape(-1).tolist(),
            model._spec(),
        )
        self.rotation = rotation

    @classmethod
    def dipolar_fluid(
        cls, n: int, *, density: float = 0.3, seed: int = 1, cutoff: float = 3.0, rotation: str = "midpoint"
    ) -> "System":
        """The built-in dipolar fluid of ``liemid many --model dipoles``: ``n`` bodies at
        number ``density`` in a periodic box, random orientations and momenta from
        ``seed``."""
        self = cls.__new__(cls)
        self._inner = _liemid.ManyBodies.dipolar_fluid(
            _count("n", n), _number("density", density), _count("seed", seed), _number("cutoff", cutoff)
        )
        self.rotation = rotation
        return self

    @property
    def rotation(self) -> str:
        """The free rotation between the impulses, ``"midpoint"``, ``"exact"`` or
        ``"variational"``."""
        return str(self._inner.rotation)

    @rotation.setter
    def rotation(self, kind: str) -> None:
        if not isinstance(kind, str):
            raise TypeError(
                f"rotation: expected \"midpoint\", \"exact\" or \"variational\", found {type(kind).__name__}"
            )
        self._inner.set_rotation(kind)

    def step(self, h: float, steps: int = 1, *, threads: int = 0, max_steps: Optional[int] = None) -> None:
        """Take ``steps`` steps of ``h`` (GIL released; ``threads`` 0 for all cores). More
        than ``max_steps`` steps (default 10⁹) raise ``ValueError`` before the first; Ctrl-C
        stops the run with ``KeyboardInterrupt`` (the bodies are then left where it
        stopped)."""
        self._inner.step(_number("h", h), _count("steps", steps), _count("threads", threads), _max_steps(max_steps))

    def totals(self) -> Totals:
        """Energy and total momenta now."""
        e, p, l_ = self._inner.totals()
        return Totals(float(e), np.array(p), np.array(l_))

    @property
    def t(self) -> float:
        """The current time."""
        return float(self._inner.t)

    def __len__(self) -> int:
        return int(self._inner.len)

    def view(self, path: Optional[str] = None, *, box_length: Optional[float] = None) -> str:
        """The current state as a self-contained 3-D page (one frame: each body an arrow
        along its body z axis, in the periodic box of edge ``box_length`` if given): written
        to ``path`` (returns it), or returned as HTML without a path."""
        x, _, r, _ = self.arrays()
        frame = np.concatenate([x, _quaternions(r)], axis=1)
        scene = {"kind": "bodies", "count": len(self), "box_length": box_length, "axis": [0.0, 0.0, 1.0], "length": 0.9}
        e = self.totals().energy
        return _view.page(scene, f"{len(self)} bodies at t = {self.t:g}", [self.t], frame, [self.t], [0.0 * e], 0, path)

    def _repr_html_(self) -> str:
        return _view.iframe(self.view())

    def arrays(self) -> Tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Copies of ``(positions (N, 3), momenta (N, 3), rotations (N, 3, 3),
        angular_momenta (N, 3))``."""
        x, p, r, pi = self._inner.arrays()
        n = len(self)
        return x.reshape(n, 3), p.reshape(n, 3), r.reshape(n, 3, 3), pi.reshape(n, 3)


def _masses(masses: ArrayLike) -> FloatArray:
    try:
        return np.asarray(masses, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"masses: cannot be read as numbers, found {type(masses).__name__}") from None


def _quaternions(r: FloatArray) -> FloatArray:
    """Unit quaternions ``w, x, y, z`` of rotation matrices (N, 3, 3)."""
    w = np.sqrt(np.maximum(0.0, 1.0 + r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2])) / 2
    x = np.copysign(np.sqrt(np.maximum(0.0, 1.0 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2])) / 2, r[:, 2, 1] - r[:, 1, 2])
    y = np.copysign(np.sqrt(np.maximum(0.0, 1.0 - r[:, 0, 0] + r[:, 1, 1] - r[:, 2, 2])) / 2, r[:, 0, 2] - r[:, 2, 0])
    z = np.copysign(np.sqrt(np.maximum(0.0, 1.0 - r[:, 0, 0] - r[:, 1, 1] + r[:, 2, 2])) / 2, r[:, 1, 0] - r[:, 0, 1])
    return np.stack([w, x, y, z], axis=1)
