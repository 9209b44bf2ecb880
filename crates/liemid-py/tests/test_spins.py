"""liemid.spins: the lattice system, runs, conservation, determinism, errors, and the CLI."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from liemid import spins


def test_the_splitting_keeps_spin_lengths_and_sz_and_bounds_the_energy() -> None:
    system, start = spins.problem("square-64")
    assert len(system) == 4096 and system.size == (64, 64, 1)
    run = spins.integrate(system, start, t_end=1.0, step=1e-2, every=10)
    assert run.t.shape == (11,) and run.magnetisation.shape == (11, 3) and run.final.shape == (4096, 3)
    assert np.max(np.abs(np.linalg.norm(run.final, axis=1) - 1.0)) < 1e-14
    sz = run.magnetisation[:, 2] * len(system)
    assert np.max(np.abs(sz - sz[0])) < 1e-13 * abs(sz[0])
    # Second order: the energy error at h/2 is a quarter of that at h.
    coarse = spins.integrate(system, start, t_end=1.0, step=2e-2).max_relative_energy_error
    fine = spins.integrate(system, start, t_end=1.0, step=1e-2).max_relative_energy_error
    assert 3.5 < coarse / fine < 4.5
    assert abs(system.energy(run.final) - run.energy[-1]) < 1e-12 * abs(run.energy[-1])


def test_threads_do_not_change_the_result_and_midpoint_keeps_the_energy() -> None:
    system, start = spins.problem("square-64")
    one = spins.integrate(system, start, t_end=0.2, step=1e-2, threads=1)
    two = spins.integrate(system, start, t_end=0.2, step=1e-2, threads=2)
    assert one.final.tobytes() == two.final.tobytes()
    mid = spins.integrate(system, start, t_end=0.2, step=1e-2, method="midpoint")
    assert mid.max_relative_energy_error < 1e-13


def test_damping_lowers_the_energy_and_errors_name_the_argument() -> None:
    system = spins.System("square", (8, 8), exchange=1.0, anisotropy=0.1, damping=0.1)
    start = spins.near_z(64, max_tilt=1.0, seed=5)
    run = spins.integrate(system, start, t_end=5.0, step=1e-2, method="midpoint", every=1)
    assert np.all(np.diff(run.energy) <= 1e-12 * abs(run.energy[0]))
    # The splitting takes damping too (exact damped sub-flows): the energy falls as well.
    split = spins.integrate(system, start, t_end=5.0, step=1e-2, method="split", every=1)
    assert np.all(np.diff(split.energy) <= 1e-12 * abs(split.energy[0]))
    assert abs(split.energy[-1] - run.energy[-1]) < 1e-3 * abs(run.energy[0])
    with pytest.raises(ValueError, match="method: unknown spin method"):
        spins.integrate(system, start, t_end=1.0, step=1e-2, method="leapfrog")
    with pytest.raises(ValueError, match=r"spins: expected shape \(64, 3\)"):
        spins.integrate(system, np.zeros((10, 3)), t_end=1.0, step=1e-2)
    with pytest.raises(ValueError, match="size"):
        spins.System("square", (4,))
    with pytest.raises(ValueError, match="mu_s"):
        spins.System("chain", (8,), mu_s=-1.0)
    names = [m[0] for m in spins.methods()]
    assert "split" in names and "midpoint" in names and "rk4" in names


def test_dmi_enters_the_energy_by_its_kind_and_bad_kinds_are_named() -> None:
    # One bond along x, S_0 = x, S_1 = z: S_0 x S_1 = -y. Interfacial D_01 = D (z x x) = D y
    # gives -D_01 . (S_0 x S_1) = +-D; bulk D_01 = D x is perpendicular to it: no energy.
    spins_xz = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    plain = spins.System("chain", (2,), periodic=False).energy(spins_xz)
    chiral = spins.System("chain", (2,), periodic=False, dmi=0.3).energy(spins_xz)
    bulk = spins.System("chain", (2,), periodic=False, dmi=0.3, dmi_kind="bulk").energy(spins_xz)
    assert plain == 0.0
    assert abs(abs(chiral - plain) - 0.3) < 1e-15
    assert abs(bulk - plain) < 1e-15
    with pytest.raises(ValueError, match="dmi_kind"):
        spins.System("chain", (2,), dmi=0.3, dmi_kind="helical")
    # The splitting with DMI keeps |S| and bounds the energy on a chiral lattice.
    system = spins.System("square", (8, 8), dmi=0.5, field=(0.0, 0.0, 0.5))
    start = spins.near_z(64, max_tilt=0.5, seed=3)
    run = spins.integrate(system, start, t_end=1.0, step=1e-2, method="split4", every=10)
    assert np.max(np.abs(np.linalg.norm(run.final, axis=1) - 1.0)) < 1e-13
    assert np.max(np.abs(run.energy - run.energy[0])) < 1e-6 * abs(run.energy[0])


def test_the_python_run_equals_the_cli_run(tmp_path: Path, liemid_cli: str) -> None:
    system, start = spins.problem("square-64")
    run = spins.integrate(system, start, t_end=0.5, step=1e-2, method="split4")
    out = tmp_path / "final.npy"
    subprocess.run(
        [liemid_cli, "spins", "--problem", "square-64", "--method", "split4", "--t-end", "0.5", "--final", str(out), "--json", "-"],
        check=True,
        capture_output=True,
    )
    assert np.load(out).tobytes() == run.final.tobytes()
    summary = subprocess.run(
        [liemid_cli, "spins", "--problem", "square-64", "--t-end", "0.1", "--json", "-"], check=True, capture_output=True, text=True
    )
    assert json.loads(summary.stdout)["steps"] == 10
