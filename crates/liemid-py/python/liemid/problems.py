"""The built-in problems, as in ``liemid problems``: the paper's fast and slow Lagrangian
tops, a torque-dominated symmetric and an asymmetric top and a free asymmetric body (the tennis-racket flip)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from . import _liemid
from ._core import FloatArray, Gravity, RigidBody, Solution, integrate

__all__ = ["Problem", "fast_top", "slow_top", "torque_top", "asymmetric_top", "free_body", "get", "NAMES"]

NAMES = ("fast-top", "slow-top", "free-body", "torque-top", "asymmetric-top")


@dataclass(frozen=True)
class Problem:
    """A body, its initial state and the default end time and step."""

    name: str
    description: str
    body: RigidBody
    rotation: FloatArray
    angular_momentum: FloatArray
    t_end: float
    step: float

    def integrate(
        self,
        *,
        method: str = "liemid-ea",
        step: Optional[float] = None,
        t_end: Optional[float] = None,
        every: int = 1,
        max_steps: Optional[int] = None,
    ) -> Solution:
        """``liemid.integrate`` from this problem's initial state."""
        return integrate(
            self.body,
            t_end=self.t_end if t_end is None else t_end,
            step=self.step if step is None else step,
            method=method,
            rotation=self.rotation,
            angular_momentum=self.angular_momentum,
            every=every,
            max_steps=max_steps,
        )


def get(name: str) -> Problem:
    """The built-in problem ``name`` (one of ``NAMES``)."""
    description, inertia, gravity, rotation, pi, t_end, step = _liemid.problem(name)
    torque: Any = None
    if gravity:
        mass, com, g = gravity[0]
        torque = Gravity(mass, com, g)
    return Problem(
        name=name,
        description=description,
        body=RigidBody(np.array(inertia).reshape(3, 3), torque),
        rotation=np.array(rotation, dtype=np.float64).reshape(3, 3),
        angular_momentum=np.array(pi, dtype=np.float64),
        t_end=float(t_end),
        step=float(step),
    )


def fast_top() -> Problem:
    """The fast Lagrangian top of the paper (an aluminium block spinning at 313π rad/s)."""
    return get("fast-top")


def slow_top() -> Problem:
    """The same top spinning slowly."""
    return get("slow-top")


def torque_top() -> Problem:
    """A torque-dominated top, where first-order methods show their order."""
    return get("torque-top")


def asymmetric_top() -> Problem:
    """A torque-dominated asymmetric top (I = diag(5, 4, 1.5), spin 30 rad/s)."""
    return get("asymmetric-top")


def free_body() -> Problem:
    """A torque-free asymmetric body spinning near its intermediate axis (the flip)."""
    return get("free-body")
