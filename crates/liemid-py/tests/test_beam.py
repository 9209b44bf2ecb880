"""liemid.beam: the same histories as the CLI, the benchmarks' physics, the variational drift,
errors."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import liemid
from liemid import beam

ROOT = Path(__file__).resolve().parents[3]


def test_the_right_angle_cantilever_matches_the_cli_bit_for_bit(liemid_cli: str) -> None:
    run = beam.run("right-angle-cantilever", elements_per_member=4, t_end=2.0, sample=0.1)
    assert run.t.shape == (21,) and run.tracked["tip"].shape == (21, 3) and run.energy.shape == (21,)
    assert run.step <= run.critical_step and run.newton_iterations is None
    out = subprocess.run(
        [liemid_cli, "beam", "--elements-per-member", "4", "--t-end", "2", "--sample", "0.1", "--json", "-"],
        check=True,
        capture_output=True,
        text=True,
    )
    cli = json.loads(out.stdout)
    assert np.array_equal(run.tracked["elbow"], np.array(cli["tracked"]["elbow"]["u"]))
    assert np.array_equal(run.energy, np.array(cli["energy"]))


def test_the_structure_file_and_newmark_agree_with_the_built_in_problem() -> None:
    path = ROOT / "examples" / "right_angle_cantilever.toml"
    a = beam.run(file=path, elements_per_member=4, t_end=3.0, sample=0.05)
    b = beam.run("right-angle-cantilever", elements_per_member=4, t_end=3.0, sample=0.05)
    assert np.array_equal(a.tracked["elbow"], b.tracked["elbow"])
    n = beam.run("right-angle-cantilever", elements_per_member=4, t_end=3.0, method="newmark", sample=0.05)
    assert n.newton_iterations is not None and n.energy.size == 0
    # Newmark's own error at dt = 0.05 (measured 0.03 over t = 30) against the explicit run.
    assert np.max(np.abs(n.tracked["elbow"] - a.tracked["elbow"])) < 0.06


def test_the_flying_beam_keeps_its_energy_after_the_loads() -> None:
    run = beam.run("flying-beam", elements_per_member=6, t_end=20.0, sample=0.5)
    after = run.energy[run.t >= 5.0]
    assert np.max(np.abs(after - after[0])) < 1e-4 * abs(after[0])


def test_errors_name_the_cause() -> None:
    with pytest.raises(ValueError, match="right-angle-cantilever"):
        beam.run("bridge")
    with pytest.raises(ValueError, match="critical step"):
        beam.run("right-angle-cantilever", step=0.1, t_end=1.0)
    with pytest.raises(ValueError, match="unknown beam method"):
        beam.run("right-angle-cantilever", method="rk4", t_end=1.0)
    with pytest.raises(ValueError, match="one of"):
        beam.run("flying-beam", text="[run]\nt_end = 1.0\n")
    with pytest.raises(TypeError, match="step"):
        beam.run("flying-beam", step="fast")  # type: ignore[arg-type]
    with pytest.raises(liemid.ConvergenceError):
        beam.run("right-angle-cantilever", elements_per_member=16, method="newmark", step=0.2)
    assert ("liemid", 2) in beam.methods() and any(n == "flying-beam" for n, _ in beam.problems())


def test_the_variational_drift_matches_the_cli_bit_for_bit(liemid_cli: str) -> None:
    run = beam.run("right-angle-cantilever", elements_per_member=4, t_end=2.0, sample=0.1, drift="variational")
    assert run.drift == "variational"
    out = subprocess.run(
        [
            liemid_cli, "beam", "--elements-per-member", "4", "--t-end", "2", "--sample", "0.1", "--drift",
            "variational", "--json", "-",
        ],
        check=True,
        capture_output=True,
        text=True,
    )
    cli = json.loads(out.stdout)
    assert cli["drift"] == "variational"
    assert np.array_equal(run.tracked["elbow"], np.array(cli["tracked"]["elbow"]["u"]))
    midpoint = beam.run("right-angle-cantilever", elements_per_member=4, t_end=2.0, sample=0.1)
    assert midpoint.drift == "midpoint"
    # Both drifts second order: close, not equal.
    d = np.max(np.abs(run.tracked["elbow"] - midpoint.tracked["elbow"]))
    assert 0.0 < d < 1e-3
    assert beam.run("right-angle-cantilever", t_end=0.5, method="newmark", step=0.05).drift is None
    with pytest.raises(ValueError, match="newmark has none"):
        beam.run("right-angle-cantilever", t_end=0.5, method="newmark", drift="variational")
    with pytest.raises(ValueError, match="unknown drift"):
        beam.run("right-angle-cantilever", t_end=0.5, drift="cayley")
