"""liemid.integrate(..., adaptive=eps): the same numbers as the Rust library (through the CLI),
the run landing on t_end, the method's order in eps, a Python torque (GIL held) stepping
like the built-in torque-free body, and the refusals."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import liemid

TOP = liemid.problems.fast_top()


def adaptive_top(eps: float, **kw: object) -> liemid.Solution:
    args: dict[str, object] = dict(rotation=TOP.rotation, angular_momentum=TOP.angular_momentum, t_end=0.05, adaptive=eps)
    args.update(kw)
    return liemid.integrate(TOP.body, **args)


@pytest.mark.parametrize(("method", "rho"), [("liemid-ea", "omega"), ("liemid-ea4", "torque"), ("liemid-ex", "omega")])
def test_same_bits_as_the_rust_library(liemid_cli: str, method: str, rho: str) -> None:
    cmd = [liemid_cli, "run", "--problem", "fast-top", "--method", method, "--t-end", "0.05"]
    cmd += ["--adaptive", "0.3", "--rho", rho, "--no-output", "--json"]
    rust = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    sol = adaptive_top(0.3, method=method, rho=rho)
    assert sol.pi[-1].tolist() == rust["pi"]
    assert sol.rotation[-1].reshape(9).tolist() == rust["rotation"]
    assert sol.steps == rust["steps"]
    assert sol.max_energy_error == rust["max_energy_error"]
    assert sol.adaptive is not None
    a = rust["adaptive"]
    assert (sol.adaptive.eps, sol.adaptive.rho) == (a["eps"], a["rho"])
    assert (sol.adaptive.min_step, sol.adaptive.max_step) == (a["min_step"], a["max_step"])
    assert sol.adaptive.last_step == rust["last_step"]


def test_the_run_lands_on_t_end_and_records_every_kth_step() -> None:
    sol = adaptive_top(0.3, every=10)
    assert sol.adaptive is not None and sol.steps > 100
    assert sol.t[0] == 0.0 and sol.t[-1] == 0.05
    assert len(sol.t) == sol.steps // 10 + 1 + (sol.steps % 10 != 0)
    assert np.all(np.diff(sol.t) > 0.0)
    assert 0.0 < sol.adaptive.last_step <= sol.adaptive.max_step * (1 + 1e-12)
    assert sol.adaptive.min_step <= sol.adaptive.max_step
    # The energy error of EA at h |Omega| = 0.3 is bounded by (h |Omega|)^2 / 24 ~ 4e-3 times
    # the share of the torque; measured 5.6e-10 on this top.
    assert sol.max_energy_error < 1e-8
    assert TOP.integrate(t_end=0.05).adaptive is None


def test_order_in_eps_is_the_methods_order() -> None:
    top = liemid.problems.torque_top()

    def final(method: str, eps: float) -> np.ndarray:
        sol = liemid.integrate(
            top.body,
            t_end=top.t_end,
            adaptive=eps,
            method=method,
            rotation=top.rotation,
            angular_momentum=top.angular_momentum,
        )
        return sol.rotation[-1]

    reference = final("liemid-ea8", 0.005)
    # eps and eps/2 where the errors (EA 1.1e-5, EA4 1.3e-9 at eps) are far above the
    # reference's and round-off.
    for method, order, eps in [("liemid-ea", 2, 0.08), ("liemid-ea4", 4, 0.2)]:
        e1 = np.linalg.norm(final(method, eps) - reference)
        e2 = np.linalg.norm(final(method, eps / 2) - reference)
        assert abs(np.log2(e1 / e2) - order) < 0.2, (method, e1, e2)


def test_a_python_torque_steps_like_the_built_in_one() -> None:
    inertia = np.diag([1.0, 2.0, 3.0])
    free = liemid.RigidBody(inertia)
    zero = liemid.RigidBody(inertia, torque=lambda R, t: np.zeros(3))
    kw: dict[str, object] = dict(t_end=5.0, adaptive=0.05, rotation_vector=[0.3, -0.2, 0.5], angular_velocity=[0.2, -0.3, 0.5])
    a = liemid.integrate(free, **kw)
    b = liemid.integrate(zero, **kw)
    assert a.steps == b.steps
    assert a.rotation[-1].tolist() == b.rotation[-1].tolist()
    assert a.max_spatial_momentum_change.max() < 1e-13


def test_refusals() -> None:
    with pytest.raises(ValueError, match="cannot take reversible adaptive steps"):
        adaptive_top(0.3, method="rk4")
    with pytest.raises(ValueError, match="exactly one of step"):
        adaptive_top(0.3, step=1e-4)
    with pytest.raises(ValueError, match="exactly one of step"):
        liemid.integrate(TOP.body, t_end=0.05, rotation=TOP.rotation, angular_momentum=TOP.angular_momentum)
    for eps in (0.0, -1.0):
        with pytest.raises(ValueError, match="adaptive"):
            adaptive_top(eps)
    with pytest.raises(ValueError, match="rho"):
        adaptive_top(0.3, rho="orbit")
    with pytest.raises(ValueError, match="rho"):
        liemid.integrate(liemid.RigidBody(np.eye(3)), t_end=1.0, adaptive=0.1, angular_velocity=[0.0, 0.0, 0.0])
