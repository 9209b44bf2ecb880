"""converge and work_precision: the CLI's studies, as dicts."""

from __future__ import annotations

import json
import subprocess

import pytest

import liemid


def test_converge_is_the_cli_study(liemid_cli: str) -> None:
    study = liemid.converge("torque-top", methods=["liemid-ea", "liemid-e1"], steps=[4e-3, 2e-3, 1e-3], t_end=1.0)
    out = subprocess.run(
        [liemid_cli, "converge", "--problem", "torque-top", "--methods", "liemid-ea,liemid-e1", "--steps", "4e-3,2e-3,1e-3", "--t-end", "1", "--no-plot", "--json", "-"],
        check=True, capture_output=True, text=True,
    ).stdout
    assert study == json.loads(out)
    ea = next(m for m in study["methods"] if m["name"] == "liemid-ea")
    assert abs(ea["observed_order_attitude"] - 2.0) < 0.1
    e1 = next(m for m in study["methods"] if m["name"] == "liemid-e1")
    assert abs(e1["observed_order_attitude"] - 1.0) < 0.15


def test_converge_from_a_scenario_and_errors(tmp_path) -> None:
    text = "[body]\ninertia = [1.0, 2.0, 2.5]\n[initial]\nangular_velocity = [0.1, 4.0, 0.3]\n[integrator]\nstep = 1e-2\nt_end = 1.0\n"
    p = tmp_path / "s.toml"
    p.write_text(text)
    a = liemid.converge(scenario=str(p), methods=["liemid-ea"], steps=[1e-2, 5e-3])
    b = liemid.converge(scenario=text, methods=["liemid-ea"], steps=[1e-2, 5e-3])
    assert a["methods"] == b["methods"]
    with pytest.raises(ValueError, match="unknown method"):
        liemid.converge(methods=["nope"])
    with pytest.raises(ValueError, match="unknown problem"):
        liemid.converge("moon")


def test_work_precision_returns_points_and_targets() -> None:
    wp = liemid.work_precision(methods=["liemid-ea", "dop853"], budget=0.02, max_points=3)
    names = [m["name"] for m in wp["methods"]]
    assert names == ["liemid-ea", "dop853"]
    assert all(len(m["points"]) >= 1 for m in wp["methods"])
    assert [t["attitude_error"] for t in wp["targets"]] == [1e-3, 1e-6, 1e-9]
    with pytest.raises(ValueError, match="repetitions"):
        liemid.work_precision(repetitions=2)
