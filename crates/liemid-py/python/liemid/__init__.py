"""liemid: structure-preserving time integration of rigid-body rotation.

The explicit midpoint Lie family of P. Krysl (LIEMID[E1], LIEMID[E2] and their
alternating, second-order, time-reversible, momentum-conserving composition LIEMID[EA],
one torque evaluation per step; LIEMID[EAV], its Lie–Poisson variant on the variational
torque-free step), the paper's comparison line-up (LIEMID[I], AKW, Simo-Wong, NMB), RK4
and high-order compositions, with numpy in and out.

>>> import liemid
>>> top = liemid.problems.fast_top()
>>> sol = liemid.integrate(top.body, rotation=top.rotation,
...                        angular_momentum=top.angular_momentum, t_end=0.8, step=1e-4)
>>> bool(abs(sol.spatial_momentum[-1, 2] - sol.spatial_momentum[0, 2]) < 1e-13)
True

- ``RigidBody(inertia, torque)`` with ``Gravity``, ``ConstantTorque``, sums of them or a
  Python callable; ``integrate`` returns a ``Solution`` of numpy arrays;
- ``ensemble`` steps N bodies on all cores (bit-identical for any thread count),
  ``liemid.dask.ensemble`` on a Dask cluster;
- ``liemid.many``: interacting bodies (the dipolar fluid); ``liemid.spins``: spin dynamics on lattices;
  ``liemid.beam``: flexible 3-D beams; ``liemid.multibody``: jointed bodies from MJCF and
  URDF files;
- ``methods``, ``problems``, ``converge``, ``work_precision``: what the CLI offers.

Reference: P. Krysl, Explicit momentum-conserving integrator for dynamics of rigid bodies
approximating the midpoint Lie algorithm, Int. J. Numer. Meth. Engng 63 (2005).
"""

from __future__ import annotations

from . import beam, many, multibody, problems, spins
from ._core import (
    AdaptiveSteps,
    CallableTorque,
    ConstantTorque,
    EnsembleState,
    Gravity,
    RigidBody,
    Solution,
    TorqueSum,
    converge,
    ensemble,
    integrate,
    methods,
    work_precision,
)
from ._errors import ConvergenceError

__version__ = "0.1.0"

__all__ = [
    "AdaptiveSteps",
    "CallableTorque",
    "ConstantTorque",
    "ConvergenceError",
    "EnsembleState",
    "Gravity",
    "RigidBody",
    "Solution",
    "TorqueSum",
    "beam",
    "converge",
    "ensemble",
    "integrate",
    "many",
    "methods",
    "multibody",
    "problems",
    "spins",
    "work_precision",
]
