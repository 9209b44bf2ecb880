"""Jointed rigid bodies (``liemid multibody``): chains, trees and loops of bodies on ball,
universal, hinge, slide, weld and free joints, read from the MJCF and URDF files people
already have (two or three hinges of one MJCF body merged into a universal or ball joint).

The bodies move in maximal coordinates by RATTLE with EA's rotation (``"liemid"``, order 2,
time-reversible, constraints kept to round-off at every step, momenta kept for a free system)
or its symmetric compositions (``"liemid4"``, ``"liemid6"``, ``"liemid8"``); ``"rk4"`` is
classical RK4 in joint coordinates (the articulated-body algorithm), for comparison.

>>> from liemid import multibody
>>> pendulum = multibody.problem("double-pendulum")
>>> run = pendulum.run(step=1e-3, t_end=1.0, every=100)
>>> run.xpos.shape, run.xquat.shape, run.joints.shape
((11, 2, 3), (11, 2, 4), (11, 2))
>>> bool(run.max_position_constraint_violation < 1e-12)
True

Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
Springer 2006, VII.1 (RATTLE); D. Baraff, "Linear-time dynamics using Lagrange
multipliers", SIGGRAPH 1996.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import NDArray

from . import _liemid, _view
from ._core import _count, _max_steps, _path, _show, _text

__all__ = ["Model", "MultibodyRun", "Simulator", "load", "methods", "problem", "problems"]

FloatArray = NDArray[np.float64]

#: A control: one float per actuator (constant), or ``f(t, qpos, qvel) -> ctrl`` called
#: once per step (its control held over the step).
Control = Union[Sequence[float], FloatArray, Callable[[float, FloatArray, FloatArray], Any]]

_METHODS = [("liemid", 2), ("liemid4", 4), ("liemid6", 6), ("liemid8", 8), ("rk4", 4)]


@dataclass(frozen=True)
class MultibodyRun:
    """A sampled run: ``t`` (n,), ``xpos`` (n, bodies, 3) each body frame's origin,
    ``xquat`` (n, bodies, 4) its attitude ``w, x, y, z`` (MuJoCo's names), ``energy`` (n,),
    ``joints`` (n, k) the hinge angles and slide offsets named by ``joint_names``;
    ``notes`` what the run left out or changed (joint armature dropped by the
    maximal-coordinate methods, limits by the joint-space ones, a start projected onto its
    loop-closing joints), as the command prints them; ``contacts`` the contact statistics
    of a model with contacts run by ``liemid`` (``None`` otherwise), named as in the
    command's JSON summary: ``most_points``, ``deepest_penetration`` (m),
    ``position_iterations``, ``solver_sweeps`` (a solve over free bodies counts the
    most sweeps of its islands), ``split_steps`` (steps whose contact solve
    failed, redone as two half steps), ``frictionless_drifts`` (steps of h/16 whose
    solve still failed, taken with friction in the closing kick only),
    ``loose_steps`` and ``max_loose_violation`` (steps
    taken where a stalled solve held the law to 1e-8 of the contact length)."""

    method: str
    steps: int
    t: FloatArray
    xpos: FloatArray
    xquat: FloatArray
    energy: FloatArray
    joints: FloatArray
    joint_names: List[str]
    max_position_constraint_violation: float
    max_velocity_constraint_violation: float
    notes: List[str] = field(default_factory=list)
    model: Any = field(default=None, repr=False, compare=False)
    contacts: Optional[Dict[str, float]] = None

    def view(self, path: Optional[str] = None) -> str:
        """The run as a self-contained 3-D page (a box per body with its inertia's
        proportions, a line per joint, the energy error): written to ``path`` (returns it),
        or returned as HTML without a path."""

        def flat(a: FloatArray) -> FloatArray:
            return np.ascontiguousarray(np.asarray(a, dtype=np.float64).reshape(-1))

        return str(
            _liemid.multibody_view(
                self.model, flat(self.t), flat(self.xpos), flat(self.xquat), flat(self.relative_energy_error), self.steps, path
            )
        )

    def _repr_html_(self) -> str:
        return _view.iframe(self.view())

    @property
    def relative_energy_error(self) -> FloatArray:
        """``(E - E0) / |E0|`` at the samples."""
        e0 = float(self.energy[0])
        return (self.energy - e0) / max(abs(e0), np.finfo(float).tiny)


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"{name}: expected a number, found {type(value).__name__}")
    return float(value)


class Model:
    """A jointed model: bodies, joints, gravity and its start (the first keyframe, else the
    reference pose). Make one with :func:`load` or :func:`problem`."""

    def __init__(self, core: _liemid.MultibodyModel) -> None:
        self._core = core

    @property
    def name(self) -> str:
        return self._core.name

    @property
    def bodies(self) -> List[str]:
        """The bodies' names, in the order of ``MultibodyRun.xpos``."""
        return list(self._core.bodies)

    @property
    def joints(self) -> List[Tuple[str, str]]:
        """The joints as (name, kind): ball, universal, hinge, slide, weld or free."""
        return list(self._core.joints)

    @property
    def ignored(self) -> List[str]:
        """What the file holds that is not simulated (actuators, contacts, ...)."""
        return list(self._core.ignored)

    @property
    def gravity(self) -> Tuple[float, float, float]:
        return self._core.gravity

    def run(
        self,
        method: str = "liemid",
        *,
        step: Optional[float] = None,
        t_end: Optional[float] = None,
        every: int = 1,
        drift: str = "midpoint",
        max_steps: Optional[int] = None,
        control: Optional[Control] = None,
    ) -> MultibodyRun:
        """Integrate from the model's start to ``t_end`` at ``step`` (defaults: the file's
        ``timestep`` or 1e-3 s; the problem's end time or 1 s), sampling every ``every``
        steps and the last. A failed step raises ``liemid.ConvergenceError``; bad input
        ``ValueError``. Joint armature is not simulated by the maximal-coordinate methods, and
        joint limits are not enforced by the joint-space ones (``rk4``, ``dop853``): the
        run's ``notes`` say so, and each is also issued as a ``UserWarning``. ``drift`` is the
        liemid methods' torque-free rotation: ``"midpoint"`` (EA's) or ``"variational"``
        (LIEMID[EAV]'s, a Lie–Poisson drift). ``control``: ``None`` (the keyframe's ``ctrl``,
        else 0), one float per actuator (constant), or a callable ``f(t, qpos, qvel)``
        returning one float per actuator, called once per step with the hinge and slide
        coordinates and rates (the joints of ``joint_names``), its control held over the
        step (as MuJoCo's ``d.ctrl`` between ``mj_step`` calls); an exception it raises
        stops the run and is raised again. Before the first step, a run of more than
        ``max_steps`` steps (default 10⁹) raises ``ValueError``, and samples that would not
        fit in the memory available ``MemoryError`` (raise ``every``). Ctrl-C stops the run
        with ``KeyboardInterrupt``."""
        h = self._core.default_step if step is None else _number("step", step)
        end = self._core.default_t_end if t_end is None else _number("t_end", t_end)
        if isinstance(every, bool) or not isinstance(every, int) or every < 1:
            raise ValueError(f"every: a whole number of steps, at least 1, found {_show(every)}")
        every = _count("every", every, 1)
        ctl: Any = control
        if control is not None and not callable(control):
            ctl = [float(x) for x in np.asarray(control, dtype=np.float64).ravel()]
        out = _liemid.multibody_run(
            self._core, _text("method", method), h, end, every, _text("drift", drift), _max_steps(max_steps), ctl
        )
        notes = [str(n) for n in out["notes"]]
        for note in notes:
            warnings.warn(f"{self.name}: {note}", UserWarning, stacklevel=2)
        n, bodies = len(out["t"]), len(self._core.bodies)
        names = list(out["joint_names"])
        return MultibodyRun(
            method=str(out["method"]),
            steps=int(out["steps"]),
            t=np.asarray(out["t"]),
            xpos=np.asarray(out["xpos"]).reshape(n, bodies, 3),
            xquat=np.asarray(out["xquat"]).reshape(n, bodies, 4),
            energy=np.asarray(out["energy"]),
            joints=np.asarray(out["joints"]).reshape(n, len(names)),
            joint_names=names,
            max_position_constraint_violation=float(out["max_position_constraint_violation"]),
            max_velocity_constraint_violation=float(out["max_velocity_constraint_violation"]),
            notes=notes,
            model=self._core,
            contacts=out["contacts"],
        )

    def simulator(self, method: str = "liemid", step: Optional[float] = None, drift: str = "midpoint") -> Simulator:
        """A simulator stepped by the caller from the model's start (MuJoCo's ``mj_step``
        loop): set ``sim.ctrl``, call ``sim.step(n)``, read ``sim.qpos``, ``sim.qvel``,
        ``sim.xpos``, ``sim.xquat``, ``sim.time``. The liemid methods only."""
        h = self._core.default_step if step is None else _number("step", step)
        core = _liemid.multibody_simulator(self._core, str(method), h, str(drift))
        for note in core.notes:
            warnings.warn(f"{self.name}: {note}", UserWarning, stacklevel=2)
        return Simulator(core)

    def __repr__(self) -> str:
        return f"liemid.multibody.Model({self.name!r}: {len(self.bodies)} bodies, {len(self.joints)} joints)"


class Simulator:
    """A model stepped by the caller: ``ctrl`` (one value per actuator, named by
    ``actuators``; held until set again), ``step(n)``, and the state: ``time``, ``qpos`` and
    ``qvel`` (the hinge and slide coordinates and rates in joint order), ``xpos``
    (bodies, 3) and ``xquat`` (bodies, 4) as MuJoCo names them. Arrays are copies."""

    def __init__(self, core: _liemid.MultibodySimulator) -> None:
        self._core = core

    def step(self, n: int = 1) -> None:
        """Take ``n`` steps with the current control."""
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise ValueError(f"n: a whole number of steps, found {n!r}")
        self._core.step(n)

    @property
    def ctrl(self) -> FloatArray:
        return np.asarray(self._core.ctrl)

    @ctrl.setter
    def ctrl(self, value: Union[Sequence[float], FloatArray]) -> None:
        self._core.ctrl = [float(x) for x in np.asarray(value, dtype=np.float64).ravel()]

    @property
    def actuators(self) -> List[str]:
        return list(self._core.actuators)

    @property
    def time(self) -> float:
        return float(self._core.time)

    @property
    def timestep(self) -> float:
        return float(self._core.timestep)

    @property
    def qpos(self) -> FloatArray:
        return np.asarray(self._core.qpos)

    @property
    def qvel(self) -> FloatArray:
        return np.asarray(self._core.qvel)

    @property
    def xpos(self) -> FloatArray:
        return np.asarray(self._core.xpos).reshape(-1, 3)

    @property
    def xquat(self) -> FloatArray:
        return np.asarray(self._core.xquat).reshape(-1, 4)

    @property
    def notes(self) -> List[str]:
        return list(self._core.notes)

    def __repr__(self) -> str:
        return f"liemid.multibody.Simulator(t = {self.time}, {len(self.actuators)} actuators)"


def load(path: Union[str, Path]) -> Model:
    """Read an MJCF (``.xml``), URDF (``.urdf``) or scenario (``.toml``) file. A malformed
    or non-physical file raises ``ValueError`` naming the element and line."""
    return Model(_liemid.multibody_load(_path("path", path)))


def problem(name: str) -> Model:
    """A built-in problem (see :func:`problems`)."""
    return Model(_liemid.multibody_problem(_text("name", name)))


def problems() -> List[Tuple[str, str]]:
    """The built-in problems: (name, description)."""
    return list(_liemid.multibody_problems())


def methods() -> List[Tuple[str, int]]:
    """The methods: (name, order)."""
    return list(_METHODS)
