"""liemid.ensemble and liemid.dask.ensemble: the same bits for any thread count, as
liemid.integrate body by body, and over a Dask cluster of two processes."""

from __future__ import annotations

import numpy as np
import pytest

import liemid

TOP = liemid.problems.fast_top()


def states(n: int, seed: int = 7):
    rng = np.random.default_rng(seed)
    rv = rng.normal(size=(n, 3)) * 0.05
    w = np.zeros((n, 3))
    w[:, 2] = 983.3185 * (0.9 + 0.2 * rng.random(n))
    return rv, w


def test_bit_identical_for_any_thread_count_and_to_integrate() -> None:
    rv, w = states(300)
    runs = [liemid.ensemble(TOP.body, rotation_vectors=rv, angular_velocities=w, t_end=0.01, step=1e-4, threads=k) for k in (1, 2, 3, 0)]
    for r in runs[1:]:
        assert r.pi.tobytes() == runs[0].pi.tobytes()
        assert r.rotation.tobytes() == runs[0].rotation.tobytes()
    for i in (0, 63, 64, 299):
        s = liemid.integrate(TOP.body, rotation_vector=rv[i], angular_velocity=w[i], t_end=0.01, step=1e-4)
        assert s.pi[-1].tobytes() == runs[0].pi[i].tobytes()
        assert s.rotation[-1].tobytes() == runs[0].rotation[i].tobytes()
    assert runs[0].pi.shape == (300, 3) and runs[0].rotation.shape == (300, 3, 3) and runs[0].t == 0.01


def test_broadcasting_and_forms() -> None:
    rv, w = states(5)
    one = liemid.ensemble(TOP.body, rotation_vectors=rv[0], angular_velocities=w, t_end=0.005, step=1e-4)
    assert one.pi.shape == (5, 3)
    r0 = liemid.integrate(TOP.body, rotation_vector=rv[0], angular_velocity=w[3], t_end=0.005, step=1e-4)
    assert one.pi[3].tolist() == r0.pi[-1].tolist()
    # Rotation matrices, positionally, and angular momenta.
    mats = np.broadcast_to(TOP.rotation, (5, 3, 3))
    a = liemid.ensemble(TOP.body, mats, angular_momenta=np.tile(TOP.angular_momentum, (5, 1)), t_end=0.005, step=1e-4)
    b = TOP.integrate(t_end=0.005)
    assert a.pi[4].tolist() == b.pi[-1].tolist()
    # Non-contiguous and integer input.
    big = np.zeros((5, 6))
    big[:, ::2] = rv
    c = liemid.ensemble(TOP.body, rotation_vectors=big[:, ::2], angular_velocities=w, t_end=0.005, step=1e-4)
    d = liemid.ensemble(TOP.body, rotation_vectors=rv, angular_velocities=w, t_end=0.005, step=1e-4)
    assert c.pi.tobytes() == d.pi.tobytes()
    q = liemid.ensemble(liemid.RigidBody([1, 2, 2]), quaternions=[[1, 0, 0, 0]] * 2, angular_velocities=np.array([[1, 2, 3]] * 2), t_end=1, step=0.01)
    assert q.pi.shape == (2, 3)


def test_ensemble_errors() -> None:
    rv, w = states(4)
    with pytest.raises(ValueError, match=r"angular_velocities: 3 rows, but the other arrays have 4"):
        liemid.ensemble(TOP.body, rotation_vectors=rv, angular_velocities=w[:3], t_end=0.01, step=1e-4)
    with pytest.raises(ValueError, match=r"rotation_vectors: expected shape \(N, 3\)"):
        liemid.ensemble(TOP.body, rotation_vectors=np.zeros((4, 2)), angular_velocities=w, t_end=0.01, step=1e-4)
    bad = np.broadcast_to(np.eye(3), (4, 3, 3)).copy()
    bad[2] *= 2
    with pytest.raises(ValueError, match="body 2: rotation: not a rotation matrix"):
        liemid.ensemble(TOP.body, bad, w, t_end=0.01, step=1e-4)
    with pytest.raises(liemid.ConvergenceError) as e:
        liemid.ensemble(TOP.body, rotation_vectors=rv, angular_velocities=w, t_end=0.1, step=0.01)
    assert "body 0" in str(e.value) and e.value.h == 0.01
    with pytest.raises(ValueError, match="not a Python callable"):
        liemid.ensemble(liemid.RigidBody([1, 2, 2], torque=lambda R, t: [0, 0, 0]), angular_velocities=w, t_end=1, step=0.1)


def test_dask_cluster_of_two_processes_gives_the_same_bits() -> None:
    distributed = pytest.importorskip("dask.distributed")
    import liemid.dask

    rv, w = states(1000, seed=3)
    local = liemid.ensemble(TOP.body, rotation_vectors=rv, angular_velocities=w, t_end=0.01, step=1e-4)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            remote = liemid.dask.ensemble(client, TOP.body, rotation_vectors=rv, angular_velocities=w, t_end=0.01, step=1e-4, chunk_size=128)
            workers = client.run(lambda: __import__("os").getpid())
    assert len(set(workers.values())) == 2
    assert remote.pi.tobytes() == local.pi.tobytes()
    assert remote.rotation.tobytes() == local.rotation.tobytes()
