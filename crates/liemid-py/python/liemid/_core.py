"""Bodies, torques, one-body integration and ensembles: the Python face of the Rust core.

Units are SI throughout: inertia in kg m², angular velocity in rad/s, angular momentum in
kg m²/s, torque in N m, time in s, mass in kg, lengths in m, gravity in m/s².
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _liemid, _view

FloatArray = NDArray[np.float64]
TorqueCallable = Callable[[FloatArray, float], ArrayLike]
PotentialCallable = Callable[[FloatArray, float], float]


# The checks every entry point shares: each argument is checked and converted here, with
# errors that name it, before the compiled core sees it (which would otherwise raise
# OverflowError for an integer beyond 64 bits, or echo a 300-digit number).

_LONG_NUMBER = re.compile(r"\d{16,}")


def _show(value: Any) -> str:
    """`value` in an error message: one line of at most about 60 characters, arrays by
    their shape, numbers of more than 15 digits in exponent form."""
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape} ({value.dtype})"
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool) and abs(int(value)) >= 10**15:
        v = int(value)
        if v.bit_length() > 1000:
            return f"an integer of about {int(v.bit_length() * math.log10(2)) + 1} digits"
        return f"{float(v):.3e}"
    try:
        return _short(repr(value))
    except (ValueError, RecursionError):
        return f"a {type(value).__name__}"


def _short(text: str) -> str:
    """`text` on one line, at most about 60 characters, numbers of more than 15 digits in
    exponent form."""
    text = _LONG_NUMBER.sub(lambda m: f"{m.group()[0]}.{m.group()[1:4]}e{len(m.group()) - 1}", " ".join(text.split()))
    return text if len(text) <= 60 else f"{text[:40]}... ({len(text)} characters)"


def _array(name: str, value: ArrayLike, shape: Tuple[int, ...], *, finite: bool = True) -> FloatArray:
    """`value` as a C-contiguous float64 array of `shape`; errors name the argument."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as e:
        raise ValueError(f"{name}: cannot be read as numbers ({_short(str(e))})") from None
    if a.shape != shape:
        expected = "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
        raise ValueError(f"{name}: expected shape {expected}, found {a.shape}")
    if finite and not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: must be finite, found {_show(a.tolist())}")
    return np.ascontiguousarray(a)


def _vec3(name: str, value: ArrayLike) -> Tuple[float, float, float]:
    a = _array(name, value, (3,))
    return (float(a[0]), float(a[1]), float(a[2]))


def _number(name: str, value: Any) -> float:
    """A finite number (an int, a float, a numpy scalar, a numeric string)."""
    if isinstance(value, np.ndarray) and value.shape != ():
        raise ValueError(f"{name}: expected a number, found {_show(value)}")
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name}: expected a number, found {_show(value)}") from None
    if not np.isfinite(x):
        raise ValueError(f"{name}: must be finite, found {x}")
    return x


def _count(name: str, value: Any, minimum: int = 0) -> int:
    """A whole number from `minimum` to 2**64 - 1 (what the core takes): an int, a numpy
    integer or a float with a whole value."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer, float, np.floating)):
        raise TypeError(f"{name}: expected a whole number, found {type(value).__name__}")
    if isinstance(value, (float, np.floating)) and not (math.isfinite(value) and float(value).is_integer()):
        raise ValueError(f"{name}: expected a whole number, found {_show(value)}")
    v = int(value)
    if not minimum <= v < 2**64:
        raise ValueError(f"{name}: expected a whole number from {minimum} to 2**64 - 1, found {_show(value)}")
    return v


def _text(name: str, value: Any) -> str:
    """A string argument (a method, a problem, a kind): no other type is turned into one."""
    if not isinstance(value, str):
        raise TypeError(f"{name}: expected a string, found {type(value).__name__}")
    return value


def _names(name: str, value: Any) -> List[str]:
    """A sequence of strings (a list of methods), not one string."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple, np.ndarray)):
        raise TypeError(f"{name}: expected a list of strings, found {type(value).__name__}")
    return [_text(name, v) for v in value]


def _path(name: str, value: Any) -> str:
    """A file path: a string or an os.PathLike."""
    if isinstance(value, os.PathLike):
        value = os.fspath(value)
    if not isinstance(value, str):
        raise TypeError(f"{name}: expected a path (str or os.PathLike), found {type(value).__name__}")
    return value


def _max_steps(value: Any) -> Optional[int]:
    """The step bound of a run: None (the default bound, 10⁹ steps) or a whole number of at
    least 1."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"max_steps: expected a whole number of steps or None, found {type(value).__name__}")
    return _count("max_steps", value, 1)


class _Torque:
    """A torque model that can be summed with `+`."""

    def __add__(self, other: "_Torque") -> "TorqueSum":
        if not isinstance(other, _Torque):
            return NotImplemented
        return TorqueSum(_terms(self) + _terms(other))


def _terms(t: "_Torque") -> Tuple["_Torque", ...]:
    return t.terms if isinstance(t, TorqueSum) else (t,)


@dataclass(frozen=True)
class Gravity(_Torque):
    """Uniform gravity on a body with a fixed point (a heavy top).

    The body torque is ``T = X × (Rᵀ m g)`` with ``X`` the centre of mass in the body
    frame, measured from the fixed point, and ``g`` the spatial gravity vector; the
    potential is ``V = −m g · (R X)``. The component of the spatial angular momentum
    along ``g`` is conserved (and kept to round-off by the LIEMID methods).

    Parameters
    ----------
    mass : float
        Mass ``m`` (kg), finite and non-negative.
    center_of_mass : (3,) array_like
        ``X``, body frame, from the fixed point (m).
    gravity : (3,) array_like
        ``g``, spatial frame (m/s²); default ``(0, 0, -9.81)``.
    """

    mass: float
    center_of_mass: Tuple[float, float, float]
    gravity: Tuple[float, float, float] = (0.0, 0.0, -9.81)

    def __post_init__(self) -> None:
        m = _number("mass", self.mass)
        if m < 0:
            raise ValueError(f"mass: must be non-negative, found {_show(m)}")
        object.__setattr__(self, "mass", m)
        object.__setattr__(self, "center_of_mass", _vec3("center_of_mass", self.center_of_mass))
        object.__setattr__(self, "gravity", _vec3("gravity", self.gravity))


@dataclass(frozen=True)
class ConstantTorque(_Torque):
    """A constant torque: ``body`` fixed in the body frame plus ``spatial`` fixed in space
    (N m), i.e. ``T = body + Rᵀ spatial``. It does work, so energy is not conserved.
    """

    body: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    spatial: Tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "body", _vec3("body", self.body))
        object.__setattr__(self, "spatial", _vec3("spatial", self.spatial))


@dataclass(frozen=True)
class TorqueSum(_Torque):
    """The sum of built-in torques, made with ``+``: ``Gravity(...) + ConstantTorque(...)``."""

    terms: Tuple[_Torque, ...]


@dataclass(frozen=True)
class CallableTorque(_Torque):
    """A torque given by a Python function ``torque(R, t) -> (3,)`` (body frame, N m),
    with ``R`` the (3, 3) attitude (body to space) and ``t`` the time; and optionally its
    potential ``potential(R, t) -> float`` (J) for the energy diagnostic.

    The slow path: every evaluation calls Python (about 1.5 µs; see the README). The GIL
    is held during such a run.
    """

    torque: TorqueCallable
    potential: Optional[PotentialCallable] = None


def _torque_adapter(f: TorqueCallable) -> Callable[[List[float], float], Tuple[float, float, float]]:
    def call(r9: List[float], t: float) -> Tuple[float, float, float]:
        out = np.asarray(f(np.array(r9, dtype=np.float64).reshape(3, 3), t), dtype=np.float64)
        if out.shape != (3,):
            raise ValueError(f"torque: the callable returned shape {out.shape}, expected (3,)")
        return (float(out[0]), float(out[1]), float(out[2]))

    return call


def _potential_adapter(f: PotentialCallable) -> Callable[[List[float], float], Tuple[float, float, float]]:
    def call(r9: List[float], t: float) -> Tuple[float, float, float]:
        return (float(f(np.array(r9, dtype=np.float64).reshape(3, 3), t)), 0.0, 0.0)

    return call


TorqueLike = Union[None, _Torque, TorqueCallable]


@dataclass(frozen=True, eq=False)
class RigidBody:
    """A rigid body with a fixed point (or a free body, with no torque).

    Parameters
    ----------
    inertia : (3,) or (3, 3) array_like
        Principal moments ``(I₁, I₂, I₃)`` or the full body inertia tensor (kg m²):
        symmetric positive definite, with the triangle inequality ``I_i ≤ I_j + I_k``
        of every physical body.
    torque : Gravity, ConstantTorque, a sum of them, or a callable ``torque(R, t)``
        The torque model; ``None`` for a torque-free body.
    potential : callable ``potential(R, t) -> float``, optional
        The potential of a callable torque, for the energy diagnostic.

    Equations of motion (body frame): ``Π' = Π × Ω + T(R, t)``, ``Ω = I⁻¹ Π``,
    ``R' = R hat(Ω)``.
    """

    inertia: Any
    torque: TorqueLike = None
    potential: Optional[PotentialCallable] = None
    _model: Any = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        try:
            shape = np.shape(self.inertia)
        except (TypeError, ValueError):
            shape = ()
        if shape == (3,):
            m = np.diag(_array("inertia", self.inertia, (3,)))
        elif shape == (3, 3):
            m = _array("inertia", self.inertia, (3, 3))
        else:
            raise ValueError(f"inertia: expected principal moments of shape (3,) or a tensor of shape (3, 3), found {shape}")
        object.__setattr__(self, "inertia", m)
        torque = self.torque
        if torque is not None and not isinstance(torque, _Torque):
            if not callable(torque):
                raise ValueError(f"torque: expected Gravity, ConstantTorque, a sum of them or a callable, found {_show(torque)}")
            torque = CallableTorque(torque, self.potential)
        elif self.potential is not None:
            raise ValueError("potential: only a callable torque takes a potential (Gravity has its own)")
        gravity: List[Any] = []
        constant: List[Any] = []
        calls: List[CallableTorque] = []
        for t in _terms(torque) if torque is not None else ():
            if isinstance(t, Gravity):
                gravity.append((t.mass, t.center_of_mass, t.gravity))
            elif isinstance(t, ConstantTorque):
                constant.append((t.body, t.spatial))
            elif isinstance(t, CallableTorque):
                calls.append(t)
        if len(calls) > 1:
            raise ValueError("torque: at most one callable torque per body")
        adapter = _torque_adapter(calls[0].torque) if calls else None
        pot = _potential_adapter(calls[0].potential) if calls and calls[0].potential is not None else None
        _liemid.check_body(m.reshape(9).tolist(), gravity, constant)
        object.__setattr__(self, "_model", (m.reshape(9).tolist(), gravity, constant, adapter, pot))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, RigidBody):
            return NotImplemented
        return bool(np.array_equal(self.inertia, other.inertia)) and self.torque == other.torque and self.potential is other.potential

    def __hash__(self) -> int:
        return hash((self.inertia.tobytes(), repr(self.torque)))

    @property
    def has_callable(self) -> bool:
        """Whether a Python function gives (part of) the torque."""
        return bool(self._model[3] is not None)

    def __reduce__(self) -> Tuple[Any, Tuple[Any, ...]]:
        return (RigidBody, (self.inertia, self.torque, self.potential))


def _one_of(named: Sequence[Tuple[str, Any]], default: Tuple[str, Any]) -> Tuple[str, Any]:
    """The one argument of `named` that is given, or `default`; an error names two given."""
    given = [(k, v) for k, v in named if v is not None]
    if len(given) > 1:
        names = ", ".join(k for k, _ in named)
        raise ValueError(f"give one of {names}, not {given[0][0]} and {given[1][0]}")
    return given[0] if given else default


def _attitude(rotation: Any, rotation_vector: Any, quaternion: Any) -> Tuple[str, FloatArray]:
    """The one attitude given (default identity), as (kind, values)."""
    named = (("rotation", rotation), ("rotation_vector", rotation_vector), ("quaternion", quaternion))
    name, value = _one_of(named, ("rotation", np.eye(3)))
    shape = {"rotation": (3, 3), "rotation_vector": (3,), "quaternion": (4,)}[name]
    kind = "matrix" if name == "rotation" else name
    return kind, _array(name, value, shape).reshape(-1)


def _momentum(angular_velocity: Any, angular_momentum: Any) -> Tuple[str, Any]:
    if (angular_velocity is None) == (angular_momentum is None):
        raise ValueError("give exactly one of angular_velocity (rad/s, body frame) or angular_momentum (kg m²/s, body frame)")
    if angular_velocity is not None:
        return "angular_velocity", angular_velocity
    return "angular_momentum", angular_momentum


@dataclass(frozen=True)
class AdaptiveSteps:
    """How an adaptive run stepped (``integrate(..., adaptive=eps)``).

    Attributes
    ----------
    eps : the accuracy parameter (h = eps / z, z following the step density)
    rho : the step density, ``omega`` (|Ω|) or ``torque`` ((|Ω|² + |T|/I_min)^½)
    min_step, max_step : the smallest and largest step (s), the last one excluded
    last_step : the last step (s), shortened to land on ``t_end``
    """

    eps: float
    rho: str
    min_step: float
    max_step: float
    last_step: float


@dataclass(frozen=True)
class Solution:
    """A trajectory and its summary. Every array is an owned, C-contiguous float64 array
    with one row per recorded step (the first, every ``every``-th and the last).

    Attributes
    ----------
    t : (n,) times (s)
    pi : (n, 3) body angular momentum Π (kg m²/s)
    rotation : (n, 3, 3) attitude R, body to space
    quaternion : (n, 4) the attitude as a unit quaternion [w, x, y, z]
    energy : (n,) total energy ½ Π·I⁻¹Π + V (J)
    spatial_momentum : (n, 3) π = R Π (kg m²/s)
    steps : steps taken
    max_energy_error : largest |E − E₀| / |E₀| over every step
    max_spatial_momentum_change : (3,) largest |π_i − π_i(t₀)| over every step
    max_body_momentum_norm_change : largest ||Π| − |Π₀|| over every step
    max_orthogonality_defect : largest ‖RᵀR − I‖_F over every step
    wall_time : seconds spent stepping
    method : the method's key
    adaptive : how the steps were chosen (an ``AdaptiveSteps``), or None at a fixed step
    """

    t: FloatArray
    pi: FloatArray
    rotation: FloatArray
    quaternion: FloatArray
    energy: FloatArray
    spatial_momentum: FloatArray
    steps: int
    max_energy_error: float
    max_spatial_momentum_change: FloatArray
    max_body_momentum_norm_change: float
    max_orthogonality_defect: float
    wall_time: float
    method: str
    inertia: FloatArray = field(default_factory=lambda: np.ones(3))
    adaptive: Optional[AdaptiveSteps] = None

    def view(self, path: Optional[str] = None) -> str:
        """The run as a self-contained 3-D page (the body as a box with its principal axes
        and the angular momentum; the relative energy error beside it): written to ``path``
        (returns it), or returned as HTML without a path."""
        frames = np.concatenate([self.rotation.reshape(-1, 9), self.spatial_momentum.reshape(-1, 3)], axis=1)
        e0 = float(self.energy[0])
        error = (self.energy - e0) / (abs(e0) if e0 != 0.0 else 1.0)
        scene = {"kind": "rigid_body", "half_extents": _view.box_of_inertia(self.inertia)}
        return _view.page(scene, f"rigid body ({self.method})", self.t, frames, self.t, error, self.steps, path)

    def _repr_html_(self) -> str:
        return _view.iframe(self.view())

    def __repr__(self) -> str:
        return (
            f"Solution(method={self.method!r}, steps={self.steps}, t=[{self.t[0]}, {self.t[-1]}], rows={len(self.t)}, "
            f"max_energy_error={self.max_energy_error:.3e}, max_orthogonality_defect={self.max_orthogonality_defect:.3e})"
        )


def integrate(
    body: RigidBody,
    *,
    t_end: float,
    step: Optional[float] = None,
    method: str = "liemid-ea",
    rotation: Optional[ArrayLike] = None,
    rotation_vector: Optional[ArrayLike] = None,
    quaternion: Optional[ArrayLike] = None,
    angular_velocity: Optional[ArrayLike] = None,
    angular_momentum: Optional[ArrayLike] = None,
    t0: float = 0.0,
    every: int = 1,
    adaptive: Optional[float] = None,
    rho: str = "omega",
    max_steps: Optional[int] = None,
) -> Solution:
    """Integrate a rigid body from ``t0`` to ``t_end`` with the fixed step ``step``, or with
    reversible adaptive steps of accuracy ``adaptive``.

    The default method, LIEMID[EA], is the explicit midpoint Lie rule with alternating
    impulses (Krysl 2005): per step, ``P = Π + (h/2) T``; solve ``(2/h) I Ψ₁ =
    exp(−Ψ₁/2) P`` and set ``R½ = R exp(Ψ₁)``, ``Π½ = exp(−Ψ₁) P``; solve again for
    ``Ψ₂``, ``R⁺ = R½ exp(Ψ₂)``, ``Π⁺ = exp(−Ψ₂) Π½ + (h/2) T(R⁺)``. Second order,
    time-reversible (not symplectic: a Lie–Poisson defect of O(h³) per step; the
    variational ``liemid-eav`` is Lie–Poisson); keeps ``|Π|`` and ``π`` torque-free and ``π·g`` under
    gravity to round-off; the energy error stays bounded; one torque evaluation per
    step. See ``liemid.methods()`` for the others.

    Parameters
    ----------
    body : RigidBody
    t_end, step : float
        End time and step (s); the last step lands on ``t_end``.
    method : str
        A key of ``liemid.methods()``: ``liemid-ea`` (default), ``liemid-e1``, ``liemid-e2``,
        ``liemid-i``, ``akw``, ``simo-wong``, ``nmb``, ``rk4``, ``rkmk4``, ``liemid-ea4``,
        ``-ea4y``, ``-ea6``, ``-ea8``, and ``liemid-ex`` (impulses around the exact
        torque-free flow: exact torque-free, far more accurate on fast spinning bodies),
        ``-ex4``, ``-ex6``, ``-ex8``.
    rotation, rotation_vector, quaternion : array_like, optional
        The initial attitude, one of: a (3, 3) rotation matrix (orthogonality defect at most
        1e-6), a (3,) rotation vector (rad), a (4,) unit quaternion [w, x, y, z]; default the
        identity.
    angular_velocity, angular_momentum : (3,) array_like
        Exactly one: body-frame Ω (rad/s) or Π (kg m²/s).
    t0 : float
        Start time (s).
    every : int
        Record every ``every``-th step (the first and last states always).
    adaptive : float, optional
        Instead of ``step``: reversible adaptive steps (Hairer and Söderlind 2005) with
        accuracy ``eps = adaptive``: ``h = eps / z`` with ``z`` following the step density
        ``rho`` by a symmetric recursion, so the run stays time-reversible and its energy
        error bounded; symmetric methods only (the ``liemid-ea``, ``-ex``, ``-fs`` families
        and their compositions, which keep their order in ``eps``). The last step lands on
        ``t_end``. Use it when the pace of the motion changes along the run (see
        docs/adaptive.md); ``Solution.adaptive`` tells the steps taken.
    rho : str
        The step density of ``adaptive``: ``omega`` (|Ω|, default: a step turns the body by
        about ``eps`` radians) or ``torque`` ((|Ω|² + |T|/I_min)^½, two more torque
        evaluations per step).
    max_steps : int, optional
        The most steps the run may take (default 10⁹), checked before the first step; an
        adaptive run's steps are estimated at the start's pace, and it stops there if the
        pace slows (``RuntimeError``).

    Returns
    -------
    Solution

    Raises
    ------
    ValueError
        Bad input; the message names the argument. A run of more than ``max_steps`` steps.
    MemoryError
        The samples the run would keep do not fit in the memory available (before anything
        is allocated; the message gives both sizes): raise ``every``.
    ConvergenceError
        A step too large for the rotation rate (with ``t`` and ``h``).
    KeyboardInterrupt
        Ctrl-C during the run (no result is returned).
    """
    if not isinstance(body, RigidBody):
        raise ValueError(f"body: expected a liemid.RigidBody, found {type(body).__name__}")
    kind, values = _attitude(rotation, rotation_vector, quaternion)
    mkind, mvalue = _momentum(angular_velocity, angular_momentum)
    if not isinstance(every, (int, np.integer)) or isinstance(every, bool) or every < 1:
        raise ValueError(f"every: expected a whole number of at least 1, found {_show(every)}")
    every = _count("every", every, 1)
    if (step is None) == (adaptive is None):
        raise ValueError("give exactly one of step (s, a fixed step) or adaptive (eps, reversible adaptive steps)")
    eps = None if adaptive is None else _number("adaptive", adaptive)
    if eps is not None and not eps > 0.0:
        raise ValueError(f"adaptive: expected a positive accuracy eps, found {_show(adaptive)}")
    if rho not in ("omega", "torque"):
        raise ValueError(f"rho: expected 'omega' or 'torque', found {_show(rho)}")
    inertia9, gravity, constant, torque, potential = body._model
    d = _liemid.integrate(
        inertia9,
        gravity,
        constant,
        torque,
        potential,
        kind,
        values.tolist(),
        (mkind, _vec3(mkind, mvalue)),
        _number("t0", t0),
        _number("t_end", t_end),
        0.0 if step is None else _number("step", step),
        _text("method", method),
        every,
        eps,
        rho if eps is not None else None,
        _max_steps(max_steps),
    )
    n = len(d["t"])
    a = d.get("adaptive")
    return Solution(
        t=d["t"],
        pi=d["pi"].reshape(n, 3),
        rotation=d["rotation"].reshape(n, 3, 3),
        quaternion=d["quaternion"].reshape(n, 4),
        energy=d["energy"],
        spatial_momentum=d["spatial_momentum"].reshape(n, 3),
        steps=int(d["steps"]),
        max_energy_error=float(d["max_energy_error"]),
        max_spatial_momentum_change=np.array(d["max_spatial_momentum_change"], dtype=np.float64),
        max_body_momentum_norm_change=float(d["max_body_momentum_norm_change"]),
        max_orthogonality_defect=float(d["max_orthogonality_defect"]),
        wall_time=float(d["wall_time"]),
        method=str(d["method"]),
        inertia=np.diag(body.inertia).copy(),
        adaptive=None if a is None else AdaptiveSteps(float(a[0]), str(a[1]), float(a[2]), float(a[3]), float(a[4])),
    )


@dataclass(frozen=True)
class EnsembleState:
    """Final states of an ensemble: ``pi`` (N, 3) body angular momenta (kg m²/s),
    ``rotation`` (N, 3, 3) attitudes, at time ``t``."""

    t: float
    pi: FloatArray
    rotation: FloatArray


def _broadcast(name: str, value: ArrayLike, row: Tuple[int, ...], n: Optional[int]) -> FloatArray:
    """`value` of shape `row` or (N, *row), broadcast to (n, *row)."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name}: cannot be read as numbers ({e})") from None
    if a.shape == row:
        a = a[np.newaxis]
    if a.ndim != len(row) + 1 or a.shape[1:] != row:
        raise ValueError(f"{name}: expected shape (N, {', '.join(map(str, row))}) or {row}, found {a.shape}")
    if n is not None and a.shape[0] not in (1, n):
        raise ValueError(f"{name}: {a.shape[0]} rows, but the other arrays have {n}")
    if n is not None:
        a = np.broadcast_to(a, (n,) + row)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: must be finite")
    return np.ascontiguousarray(a, dtype=np.float64)


def _rows(*arrays: Any) -> int:
    sizes = [np.shape(a)[0] for a, ndim in arrays if a is not None and np.ndim(a) == ndim]
    return max(sizes) if sizes else 1


def _ensemble_states(
    rotations: Optional[ArrayLike],
    rotation_vectors: Optional[ArrayLike],
    quaternions: Optional[ArrayLike],
    angular_velocities: Optional[ArrayLike],
    angular_momenta: Optional[ArrayLike],
) -> Tuple[str, FloatArray, str, FloatArray]:
    """The attitudes and momenta of an ensemble, broadcast to N rows: (attitude argument
    name, (N, ...) array, momentum argument name, (N, 3) array)."""
    named = (("rotations", rotations), ("rotation_vectors", rotation_vectors), ("quaternions", quaternions))
    name, value = _one_of(named, ("rotations", np.eye(3)))
    if (angular_velocities is None) == (angular_momenta is None):
        raise ValueError("give exactly one of angular_velocities (rad/s, body frame) or angular_momenta (kg m²/s, body frame)")
    mom_name = "angular_velocities" if angular_momenta is None else "angular_momenta"
    mvalue = angular_velocities if angular_momenta is None else angular_momenta
    row = {"rotations": (3, 3), "rotation_vectors": (3,), "quaternions": (4,)}[name]
    n = _rows((value, len(row) + 1), (mvalue, 2))
    assert mvalue is not None
    return name, _broadcast(name, value, row, n), mom_name, _broadcast(mom_name, mvalue, (3,), n)


def ensemble(
    body: RigidBody,
    rotations: Optional[ArrayLike] = None,
    angular_velocities: Optional[ArrayLike] = None,
    *,
    rotation_vectors: Optional[ArrayLike] = None,
    quaternions: Optional[ArrayLike] = None,
    angular_momenta: Optional[ArrayLike] = None,
    t_end: float,
    step: float,
    method: str = "liemid-ea",
    t0: float = 0.0,
    threads: int = 0,
    max_steps: Optional[int] = None,
) -> EnsembleState:
    """Integrate N independent copies of ``body`` from N initial states, on ``threads``
    threads (0: all cores) with the GIL released; the result is bit-for-bit the same for
    any thread count, and each body's is bit-for-bit that of ``integrate`` from its state.

    Attitudes: ``rotations`` (N, 3, 3), ``rotation_vectors`` (N, 3) or ``quaternions``
    (N, 4) (default identity); momenta: ``angular_velocities`` or ``angular_momenta``
    (N, 3), body frame. A single row (shape (3, 3), (3,) or (4,)) is broadcast to N.
    Only built-in torques (Gravity, ConstantTorque and sums): a Python callable would
    hold the GIL at every step. Each body's steps are held to ``max_steps`` (default 10⁹)
    before the first (``ValueError``); Ctrl-C stops the bodies within a few steps and raises
    ``KeyboardInterrupt``.
    """
    if not isinstance(body, RigidBody):
        raise ValueError(f"body: expected a liemid.RigidBody, found {type(body).__name__}")
    if body.has_callable:
        raise ValueError("body: an ensemble needs a built-in torque (Gravity, ConstantTorque or sums), not a Python callable")
    if not isinstance(threads, (int, np.integer)) or threads < 0:
        raise ValueError(f"threads: expected a whole number >= 0, found {_show(threads)}")
    threads = _count("threads", threads)
    name, att, mom_name, mom = _ensemble_states(rotations, rotation_vectors, quaternions, angular_velocities, angular_momenta)
    n = att.shape[0]
    mkind = "angular_velocity" if mom_name == "angular_velocities" else "angular_momentum"
    kind = {"rotations": "matrix", "rotation_vectors": "rotation_vector", "quaternions": "quaternion"}[name]
    inertia9, gravity, constant, _, _ = body._model
    pi, r = _liemid.ensemble(
        inertia9,
        gravity,
        constant,
        kind,
        att.reshape(-1),
        mom.reshape(-1),
        mkind,
        _number("t0", t0),
        _number("t_end", t_end),
        _number("step", step),
        _text("method", method),
        threads,
        _max_steps(max_steps),
    )
    return EnsembleState(t=float(t_end), pi=pi.reshape(n, 3), rotation=r.reshape(n, 3, 3))


def methods() -> List[Dict[str, Any]]:
    """Every integrator: a list of dicts with ``key``, ``name``, ``order``,
    ``torque_evaluations`` (per step) and ``description`` (what it conserves)."""
    return [
        {"key": k, "name": n, "order": o, "torque_evaluations": e, "description": d}
        for k, n, o, e, d in _liemid.methods()
    ]


def _scenario_text(scenario: Any) -> Optional[str]:
    """A scenario's text: given as text, or read from a ``.toml`` file (a regular file of at
    most 16 MiB, as the command reads it: a FIFO is refused, not waited on)."""
    if scenario is None:
        return None
    text = _path("scenario", scenario)
    if isinstance(scenario, os.PathLike) or ("\n" not in text and text.endswith(".toml")):
        return _liemid.read_input("scenario", text)
    return text


def converge(
    problem: str = "fast-top",
    *,
    scenario: Optional[str] = None,
    methods: Optional[Sequence[str]] = None,
    steps: Optional[Sequence[float]] = None,
    t_end: Optional[float] = None,
    max_steps: Optional[int] = None,
) -> Dict[str, Any]:
    """The convergence study of ``liemid converge`` (the paper's Figure 1): the errors at
    ``t_end`` of every method for a sequence of steps against a reference computed with
    it (RK4 at h/64 of the smallest step, with a Richardson estimate of its own error).
    Returns the same data as the CLI's JSON. ``scenario``: a TOML file name or text
    instead of a built-in ``problem``. The steps of all its runs together are held to
    ``max_steps`` (default 10⁹) before the first; Ctrl-C stops it between runs."""
    if steps is not None and (isinstance(steps, (str, bytes)) or not isinstance(steps, (list, tuple, np.ndarray))):
        raise TypeError(f"steps: expected a list of steps, found {type(steps).__name__}")
    text = json.loads(
        _liemid.converge(
            _text("problem", problem),
            _scenario_text(scenario),
            None if methods is None else _names("methods", methods),
            None if steps is None else [_number("steps", h) for h in steps],
            None if t_end is None else _number("t_end", t_end),
            _max_steps(max_steps),
        )
    )
    assert isinstance(text, dict)
    return text


def work_precision(
    problem: str = "fast-top",
    *,
    scenario: Optional[str] = None,
    methods: Optional[Sequence[str]] = None,
    t_end: Optional[float] = None,
    repetitions: int = 5,
    budget: float = 0.5,
    min_error: float = 1e-11,
    max_points: int = 16,
    max_steps: Optional[int] = None,
) -> Dict[str, Any]:
    """The work-precision study of ``liemid work-precision``: attitude error at ``t_end``
    against the median CPU time of ``repetitions`` runs, for every method and the DOP853
    (``dop853``) and RK4 baselines. Returns the same data as the CLI's JSON. A study whose
    coarsest run (a step turning the body by about 64 rad) would take more than
    ``max_steps`` steps (default 10⁹) raises ``ValueError`` before the first run; Ctrl-C
    stops it between runs and within its references."""
    text = json.loads(
        _liemid.work_precision(
            _text("problem", problem),
            _scenario_text(scenario),
            None if methods is None else _names("methods", methods),
            None if t_end is None else _number("t_end", t_end),
            _count("repetitions", repetitions),
            _number("budget", budget),
            _number("min_error", min_error),
            _count("max_points", max_points),
            _max_steps(max_steps),
        )
    )
    assert isinstance(text, dict)
    return text
