"""liemid.integrate: argument forms, dtypes and shapes, errors, the same numbers as the
Rust library (through the CLI), invariants, and the GIL released during a run."""

from __future__ import annotations

import json
import pickle
import subprocess
import threading
import time

import numpy as np
import pytest

import liemid

TOP = liemid.problems.fast_top()


def run_top(**kw):
    args = dict(rotation=TOP.rotation, angular_momentum=TOP.angular_momentum, t_end=0.05, step=1e-4)
    args.update(kw)
    return liemid.integrate(TOP.body, **args)


@pytest.mark.parametrize("method", ["liemid-ea", "liemid-e1", "rk4", "liemid-ea4", "liemid-i"])
def test_same_bits_as_the_rust_library(liemid_cli: str, method: str) -> None:
    out = subprocess.run(
        [liemid_cli, "run", "--problem", "fast-top", "--method", method, "--t-end", "0.05", "--no-output", "--json"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    rust = json.loads(out)
    sol = TOP.integrate(method=method, t_end=0.05)
    assert sol.pi[-1].tolist() == rust["pi"]
    assert sol.rotation[-1].reshape(9).tolist() == rust["rotation"]
    assert sol.steps == rust["steps"]
    assert sol.max_energy_error == rust["max_energy_error"]
    assert sol.max_spatial_momentum_change.tolist() == rust["max_spatial_momentum_change"]


def test_solution_arrays_are_owned_contiguous_float64() -> None:
    sol = run_top(every=7)
    n = len(sol.t)
    assert n == 500 // 7 + 2
    assert sol.t[0] == 0.0 and sol.t[-1] == 0.05
    for name, shape in [("t", (n,)), ("pi", (n, 3)), ("rotation", (n, 3, 3)), ("quaternion", (n, 4)), ("energy", (n,)), ("spatial_momentum", (n, 3))]:
        a = getattr(sol, name)
        assert a.shape == shape, name
        assert a.dtype == np.float64 and a.flags["C_CONTIGUOUS"] and a.flags["WRITEABLE"], name
    arrays = [sol.t, sol.pi, sol.rotation, sol.quaternion, sol.energy, sol.spatial_momentum]
    assert not any(np.shares_memory(x, y) for i, x in enumerate(arrays) for y in arrays[i + 1 :])
    # The quaternion is the attitude.
    w, x, y, z = sol.quaternion[-1]
    assert abs(np.linalg.norm(sol.quaternion[-1]) - 1) < 1e-15
    r = sol.rotation[-1]
    assert abs(r[0, 1] - 2 * (x * y - w * z)) < 1e-14
    # pi = R Pi row by row.
    assert np.allclose(sol.spatial_momentum, np.einsum("nij,nj->ni", sol.rotation, sol.pi), rtol=0, atol=1e-15)
    assert sol.steps == 500 and sol.wall_time > 0
    assert "liemid-ea" in repr(sol)
    assert pickle.loads(pickle.dumps(sol)).pi.tolist() == sol.pi.tolist()


def test_every_attitude_and_momentum_form_agree() -> None:
    from math import cos, sin

    a = 0.3
    rv = [a, 0.0, 0.0]
    q = [cos(a / 2), sin(a / 2), 0.0, 0.0]
    r = [[1, 0, 0], [0, cos(a), -sin(a)], [0, sin(a), cos(a)]]
    body = liemid.RigidBody([1.0, 2.0, 2.5])
    w = [0.3, 4.0, 0.2]
    sols = [
        liemid.integrate(body, rotation_vector=rv, angular_velocity=w, t_end=1.0, step=1e-2),
        liemid.integrate(body, quaternion=q, angular_velocity=w, t_end=1.0, step=1e-2),
        liemid.integrate(body, rotation=r, angular_velocity=w, t_end=1.0, step=1e-2),
        liemid.integrate(body, rotation=r, angular_momentum=[0.3, 8.0, 0.5], t_end=1.0, step=1e-2),
    ]
    for s in sols[1:]:
        assert np.max(np.abs(s.rotation[0] - sols[0].rotation[0])) < 1e-15
        assert np.max(np.abs(s.pi[-1] - sols[0].pi[-1])) < 1e-12
    # Default attitude: the identity.
    s = liemid.integrate(body, angular_velocity=w, t_end=0.1, step=1e-2)
    assert s.rotation[0].tolist() == np.eye(3).tolist()
    # Principal moments and the same diagonal tensor give the same bits.
    d = liemid.integrate(liemid.RigidBody(np.diag([1.0, 2.0, 2.5])), rotation=r, angular_velocity=w, t_end=1.0, step=1e-2)
    assert d.pi.tolist() == sols[2].pi.tolist()


def test_any_dtype_and_memory_order() -> None:
    base = run_top()
    f_order = np.asfortranarray(TOP.rotation)
    strided = np.zeros((3, 6))
    strided[:, ::2] = TOP.rotation
    for rotation in (f_order, strided[:, ::2], TOP.rotation.tolist(), tuple(map(tuple, TOP.rotation))):
        s = run_top(rotation=rotation)
        assert s.pi.tolist() == base.pi.tolist()
    ints = liemid.integrate(liemid.RigidBody([1, 2, 2]), angular_velocity=np.array([1, 2, 3], dtype=np.int32), t_end=1, step=0.01)
    floats = liemid.integrate(liemid.RigidBody([1.0, 2.0, 2.0]), angular_velocity=[1.0, 2.0, 3.0], t_end=1.0, step=0.01)
    assert ints.pi.tolist() == floats.pi.tolist()
    f32 = liemid.integrate(liemid.RigidBody(np.array([1, 2, 2], dtype=np.float32)), angular_velocity=[1.0, 2.0, 3.0], t_end=1.0, step=0.01)
    assert f32.pi.tolist() == floats.pi.tolist()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(rotation=np.eye(2)), "rotation: expected shape (3, 3), found (2, 2)"),
        (dict(rotation=np.diag([2.0, 1.0, 1.0])), "rotation: not a rotation matrix"),
        (dict(rotation=np.diag([-1.0, 1.0, 1.0])), "determinant"),
        (dict(rotation=None, quaternion=[2.0, 0.0, 0.0, 0.0]), "quaternion: must be a unit quaternion"),
        (dict(rotation=None, rotation_vector=[1.0, 2.0]), "rotation_vector: expected shape (3,)"),
        (dict(rotation=None, rotation_vector=[1e300, 0.0, 0.0]), "rotation_vector: its length"),
        (dict(quaternion=[1.0, 0.0, 0.0, 0.0]), "give one of rotation, rotation_vector, quaternion"),
        (dict(angular_velocity=[1.0, 2.0, 3.0]), "give exactly one of angular_velocity"),
        (dict(angular_momentum=[np.nan, 0.0, 0.0]), "angular_momentum: must be finite"),
        (dict(angular_momentum="abc"), "angular_momentum: cannot be read as numbers"),
        (dict(method="euler"), 'method: unknown method "euler"'),
        (dict(step=0.0), "step size h = 0"),
        (dict(step=1e-30), "too small"),
        (dict(t_end=-1.0), "before the start time"),
        (dict(every=0), "every: expected a whole number of at least 1"),
        (dict(t_end=float("nan")), "t_end: must be finite"),
    ],
)
def test_bad_input_raises_value_error_naming_the_argument(kwargs, message) -> None:
    with pytest.raises(ValueError) as e:
        run_top(**kwargs)
    assert message in str(e.value)


def test_bad_bodies_are_refused_when_built() -> None:
    for inertia, message in [
        ([1.0, 1.0, 3.0], "triangle inequality"),
        ([1.0, -1.0, 1.0], "I2 = -1"),
        ([[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "not symmetric"),
        ([1.0, 2.0], "inertia: expected principal moments of shape (3,) or a tensor of shape (3, 3)"),
        ([1.0, np.inf, 1.0], "inertia: must be finite"),
    ]:
        with pytest.raises(ValueError, match="inertia") as e:
            liemid.RigidBody(inertia)
        assert message in str(e.value)
    with pytest.raises(ValueError, match="mass: must be non-negative"):
        liemid.Gravity(-1.0, (0, 0, 1))
    with pytest.raises(ValueError, match="center_of_mass: expected shape"):
        liemid.Gravity(1.0, (0, 1))
    with pytest.raises(ValueError, match="torque: expected Gravity"):
        liemid.RigidBody([1, 2, 2], torque=3)
    with pytest.raises(ValueError, match="body: expected a liemid.RigidBody"):
        liemid.integrate("top", t_end=1, step=1, angular_velocity=[1, 2, 3])  # type: ignore[arg-type]


def test_a_step_too_large_raises_convergence_error_with_t_and_h() -> None:
    with pytest.raises(liemid.ConvergenceError) as e:
        run_top(step=0.01)
    assert e.value.t == 0.0 and e.value.h == 0.01
    assert "reduce the step" in str(e.value)
    assert isinstance(e.value, RuntimeError)
    again = pickle.loads(pickle.dumps(e.value))
    assert (again.t, again.h) == (0.0, 0.01)


def test_callable_torque_matches_the_built_in_gravity_and_raises_its_own_errors() -> None:
    g = TOP.body.torque
    assert isinstance(g, liemid.Gravity)
    weight = g.mass * np.array(g.gravity)
    com = np.array(g.center_of_mass)

    def torque(R, t):
        return np.cross(com, R.T @ weight)

    def potential(R, t):
        return -float(weight @ (R @ com))

    body = liemid.RigidBody(TOP.body.inertia, torque=torque, potential=potential)
    a = liemid.integrate(body, rotation=TOP.rotation, angular_momentum=TOP.angular_momentum, t_end=0.05, step=1e-4)
    b = run_top()
    assert np.max(np.abs(a.pi - b.pi)) < 1e-12
    assert np.max(np.abs(a.energy - b.energy)) < 1e-9 * abs(b.energy[0])
    assert abs(a.spatial_momentum[-1, 2] - a.spatial_momentum[0, 2]) < 1e-13

    def broken(R, t):
        raise KeyError("no torque here")

    with pytest.raises(KeyError, match="no torque here"):
        liemid.integrate(liemid.RigidBody([1, 2, 2], torque=broken), angular_velocity=[1, 2, 3], t_end=1, step=1e-2)
    with pytest.raises(ValueError, match=r"torque: the callable returned shape \(2,\), expected \(3,\)"):
        liemid.integrate(liemid.RigidBody([1, 2, 2], torque=lambda R, t: [1.0, 2.0]), angular_velocity=[1, 2, 3], t_end=1, step=1e-2)


def test_sums_of_torques() -> None:
    g = liemid.Gravity(1.0, (0.0, 0.0, 0.1))
    c = liemid.ConstantTorque(spatial=(0.0, 0.0, 0.5))
    both = liemid.RigidBody([1.0, 1.0, 0.5], torque=g + c)
    s = liemid.integrate(both, rotation_vector=[0.1, 0, 0], angular_velocity=[0, 0, 20], t_end=1.0, step=1e-3)
    # The spatial torque about z is the constant's alone (gravity has none about g):
    # pi_z grows by 0.5 t, to round-off.
    assert abs(s.spatial_momentum[-1, 2] - s.spatial_momentum[0, 2] - 0.5) < 1e-12
    assert isinstance(g + c, liemid.TorqueSum) and len((g + c + g).terms) == 3


def test_torque_free_invariants_to_round_off() -> None:
    body = liemid.RigidBody([1.0, 2.0, 2.5])
    s = liemid.integrate(body, rotation_vector=[0.3, -0.2, 0.1], angular_velocity=[0.1, 4.0, 0.3], t_end=100.0, step=1e-2)
    norms = np.linalg.norm(s.pi, axis=1)
    assert np.max(np.abs(norms - norms[0])) < 1e-13 * norms[0]
    assert np.max(np.abs(s.spatial_momentum - s.spatial_momentum[0])) < 1e-13 * norms[0]
    assert s.max_orthogonality_defect < 1e-13


def test_the_gil_is_released_during_a_run() -> None:
    ticks = []
    done = threading.Event()

    def count() -> None:
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    time.sleep(0.01)
    before = len(ticks)
    start = time.perf_counter()
    sol = run_top(t_end=60.0, every=1000)  # 600,000 steps, about 0.1 s
    end = time.perf_counter()
    done.set()
    t.join()
    during = [x for x in ticks[before:] if start < x < end]
    assert sol.steps == 600_000
    assert len(during) >= 10, f"the other thread ticked {len(during)} times in {end - start:.3f} s"


def test_methods_and_problems() -> None:
    ms = liemid.methods()
    keys = [m["key"] for m in ms]
    assert keys[:3] == ["liemid-e1", "liemid-e2", "liemid-ea"] and "rk4" in keys and "liemid-ex" in keys and "liemid-fs" in keys and "liemid-eav" in keys and len(ms) == 25
    ea = ms[2]
    assert ea["name"] == "LIEMID[EA]" and ea["order"] == 2 and ea["torque_evaluations"] == "1"
    for name in liemid.problems.NAMES:
        p = liemid.problems.get(name)
        assert p.t_end > 0 and p.rotation.shape == (3, 3)
    with pytest.raises(ValueError, match="unknown problem"):
        liemid.problems.get("moon")
    free = liemid.problems.free_body()
    assert free.body.torque is None
    body = pickle.loads(pickle.dumps(TOP.body))
    assert body == TOP.body and body != liemid.RigidBody(TOP.body.inertia)
    a = liemid.integrate(body, rotation=TOP.rotation, angular_momentum=TOP.angular_momentum, t_end=0.01, step=1e-4)
    assert a.pi.tolist() == run_top(t_end=0.01).pi.tolist()
