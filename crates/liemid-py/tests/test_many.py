"""liemid.many: bodies from arrays, the dipolar fluid, conservation and determinism, and the
CLI's extended XYZ trajectory read by ASE."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

import liemid
from liemid import many

TOP = liemid.problems.fast_top()


def test_one_rotor_is_liemid_ea() -> None:
    g = TOP.body.torque
    assert isinstance(g, liemid.Gravity)
    moments = np.diag(TOP.body.inertia)
    sys_ = many.System(
        [g.mass], moments, np.zeros((1, 3)), TOP.rotation[np.newaxis], TOP.angular_momentum[np.newaxis],
        free=False, model=many.Independent(gravity=g.gravity, center_of_mass=g.center_of_mass),
    )
    sys_.step(1e-4, 100)
    ea = TOP.integrate(t_end=0.01)
    _, _, r, pi = sys_.arrays()
    # The same operations up to the order of the impulse sums, and the driver's last step
    # lands on t_end (it differs from h in the last bits): the Rust test's bound, 1e-15.
    norm = np.linalg.norm(ea.pi[-1])
    assert np.max(np.abs(pi[0] - ea.pi[-1])) <= 1e-15 * norm
    assert np.max(np.abs(r[0] - ea.rotation[-1])) <= 1e-15
    assert abs(sys_.t - 0.01) < 1e-15 and len(sys_) == 1


def test_dipolar_fluid_keeps_momenta_and_is_thread_independent() -> None:
    a = many.System.dipolar_fluid(216, density=0.3, seed=2)
    b = many.System.dipolar_fluid(216, density=0.3, seed=2)
    t0 = a.totals()
    a.step(1e-3, 50, threads=1)
    b.step(1e-3, 50, threads=2)
    for x, y in zip(a.arrays(), b.arrays()):
        assert x.tobytes() == y.tobytes()
    t1 = a.totals()
    assert np.max(np.abs(t1.linear_momentum - t0.linear_momentum)) < 1e-12
    assert abs(t1.energy - t0.energy) < 1e-3 * abs(t0.energy)


def test_isolated_dipoles_from_arrays_keep_angular_momentum() -> None:
    rng = np.random.default_rng(4)
    n = 8
    x = np.array([[i % 2, (i // 2) % 2, i // 4] for i in range(n)], dtype=float) * 1.3
    r = np.broadcast_to(np.eye(3), (n, 3, 3))
    sys_ = many.System(np.ones(n), [0.1, 0.1, 0.1], x, r, rng.normal(size=(n, 3)) * 0.1, momenta=rng.normal(size=(n, 3)) * 0.1, model=many.Dipoles())
    t0 = sys_.totals()
    sys_.step(1e-3, 200)
    t1 = sys_.totals()
    assert np.max(np.abs(t1.angular_momentum - t0.angular_momentum)) < 1e-13
    assert np.max(np.abs(t1.linear_momentum - t0.linear_momentum)) < 1e-13


def test_many_errors_name_the_argument() -> None:
    with pytest.raises(ValueError, match=r"positions: 3 rows, but the other arrays have 2"):
        many.System([1.0, 1.0], [1, 1, 1], np.zeros((3, 3)), np.eye(3), np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"rotations: expected shape \(N, 3, 3\)"):
        many.System([1.0, 1.0], [1, 1, 1], np.zeros((2, 3)), np.eye(2), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="body 0: .*triangle inequality"):
        many.System([1.0], [1, 1, 3], np.zeros(3), np.eye(3), np.zeros(3))
    with pytest.raises(ValueError, match="density"):
        many.System.dipolar_fluid(10, density=-1.0)


def test_exact_rotation_is_liemid_ex_and_thread_independent() -> None:
    g = TOP.body.torque
    assert isinstance(g, liemid.Gravity)
    moments = np.diag(TOP.body.inertia)
    sys_ = many.System(
        [g.mass], moments, np.zeros((1, 3)), TOP.rotation[np.newaxis], TOP.angular_momentum[np.newaxis],
        free=False, model=many.Independent(gravity=g.gravity, center_of_mass=g.center_of_mass),
        rotation="exact",
    )
    assert sys_.rotation == "exact"
    sys_.step(1e-3, 100)
    ex = TOP.integrate(t_end=0.1, method="liemid-ex", step=1e-3)
    _, _, r, pi = sys_.arrays()
    norm = np.linalg.norm(ex.pi[-1])
    assert np.max(np.abs(pi[0] - ex.pi[-1])) <= 1e-14 * norm
    assert np.max(np.abs(r[0] - ex.rotation[-1])) <= 1e-14
    a = many.System.dipolar_fluid(216, density=0.3, seed=2, rotation="exact")
    b = many.System.dipolar_fluid(216, density=0.3, seed=2)
    b.rotation = "exact"
    a.step(1e-3, 20, threads=1)
    b.step(1e-3, 20, threads=2)
    for x, y in zip(a.arrays(), b.arrays()):
        assert x.tobytes() == y.tobytes()
    with pytest.raises(ValueError, match=r'rotation: unknown rotation "spline"'):
        b.rotation = "spline"


def test_variational_rotation_is_liemid_eav_and_thread_independent() -> None:
    g = TOP.body.torque
    assert isinstance(g, liemid.Gravity)
    moments = np.diag(TOP.body.inertia)
    sys_ = many.System(
        [g.mass], moments, np.zeros((1, 3)), TOP.rotation[np.newaxis], TOP.angular_momentum[np.newaxis],
        free=False, model=many.Independent(gravity=g.gravity, center_of_mass=g.center_of_mass),
        rotation="variational",
    )
    assert sys_.rotation == "variational"
    sys_.step(1e-4, 100)
    eav = TOP.integrate(t_end=0.01, method="liemid-eav", step=1e-4)
    _, _, r, pi = sys_.arrays()
    norm = np.linalg.norm(eav.pi[-1])
    assert np.max(np.abs(pi[0] - eav.pi[-1])) <= 1e-14 * norm
    assert np.max(np.abs(r[0] - eav.rotation[-1])) <= 1e-14
    a = many.System.dipolar_fluid(216, density=0.3, seed=2, rotation="variational")
    b = many.System.dipolar_fluid(216, density=0.3, seed=2)
    b.rotation = "variational"
    a.step(1e-3, 20, threads=1)
    b.step(1e-3, 20, threads=2)
    for x, y in zip(a.arrays(), b.arrays()):
        assert x.tobytes() == y.tobytes()
    with pytest.raises(ValueError, match="midpoint.*exact.*variational"):
        b.rotation = "cayley"


def test_the_extended_xyz_trajectory_opens_in_ase(tmp_path: Path, liemid_cli: str) -> None:
    ase_io = pytest.importorskip("ase.io")
    out = tmp_path / "fluid.xyz"
    subprocess.run(
        [liemid_cli, "many", "--model", "dipoles", "--bodies", "216", "--density", "0.3", "--t-end", "0.02",
         "--trajectory", str(out), "--trajectory-every", "5"],
        check=True,
        capture_output=True,
    )
    frames = ase_io.read(str(out), index=":", format="extxyz")
    assert len(frames) == 5
    first, last = frames[0], frames[-1]
    assert len(first) == 216 and first.pbc.all()
    assert first.cell.lengths()[0] == pytest.approx((216 / 0.3) ** (1 / 3))
    q = last.arrays["orientation"]
    assert q.shape == (216, 4) and np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-14)
    assert last.arrays["velo"].shape == (216, 3) and last.arrays["angmom"].shape == (216, 3)
    assert float(last.info["Time"]) == pytest.approx(0.02)
    # The bodies moved.
    assert not np.allclose(first.positions, last.positions)


def test_the_shifted_force_cutoff_is_lammps_lj_sf_dipole_sf() -> None:
    # Two parallel dipoles (along z) 1.5 apart along x, cutoff 2.5, no WCA overlap:
    # U = S U_dd with U_dd = 1/r^3 and LAMMPS's S = 1 - 4 x^3 + 3 x^4, x = r/r_c.
    x = 1.5 / 2.5
    expected = (1.0 - 4.0 * x**3 + 3.0 * x**4) / 1.5**3
    positions = [[1.0, 3.0, 3.0], [2.5, 3.0, 3.0]]
    rotations = np.broadcast_to(np.eye(3), (2, 3, 3))
    for form, value in [("shifted-force", expected), ("switched", 1.0 / 1.5**3)]:
        sys_ = many.System(
            [1.0, 1.0], [0.1, 0.1, 0.1], positions, rotations, np.zeros((2, 3)),
            model=many.Dipoles(cutoff=2.5, box_length=6.0, cutoff_form=form),
        )
        assert abs(sys_.totals().energy - value) < 1e-14, form
    with pytest.raises(ValueError, match="cutoff_form"):
        many.System(
            [1.0, 1.0], [0.1, 0.1, 0.1], positions, rotations, np.zeros((2, 3)),
            model=many.Dipoles(cutoff=2.5, box_length=6.0, cutoff_form="smooth"),
        )
