"""liemid.multibody: the same run as the CLI, the files users have, orders, errors."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import liemid
from liemid import multibody

ROOT = Path(__file__).resolve().parents[3]


def test_the_double_pendulum_matches_the_cli_bit_for_bit(liemid_cli: str) -> None:
    run = multibody.problem("double-pendulum").run(step=1e-3, t_end=1.0, every=100)
    assert run.t.shape == (11,) and run.xpos.shape == (11, 2, 3) and run.joints.shape == (11, 2)
    assert run.max_position_constraint_violation <= 1e-12
    out = subprocess.run(
        [liemid_cli, "multibody", "--problem", "double-pendulum", "--step", "1e-3", "--t-end", "1", "--json", "-"],
        check=True,
        capture_output=True,
        text=True,
    )
    cli = json.loads(out.stdout)
    assert np.array_equal(run.xpos[-1], np.array([b["xpos"] for b in cli["final"]]))
    assert np.array_equal(run.xquat[-1], np.array([b["xquat"] for b in cli["final"]]))
    assert np.array_equal(run.joints[-1], np.array([j["value"] for j in cli["joints"]]))


def test_second_and_fourth_order_against_the_joint_space_rk4() -> None:
    model = multibody.problem("test-chain")
    reference = model.run("liemid8", step=1e-3, t_end=0.5, every=500).xpos[-1]
    rk4 = model.run("rk4", step=1e-4, t_end=0.5, every=5000).xpos[-1]
    assert np.max(np.abs(rk4 - reference)) < 1e-9
    for method, order in [("liemid", 2), ("liemid4", 4)]:
        errors = [
            np.max(np.abs(model.run(method, step=h, t_end=0.5, every=10**6).xpos[-1] - reference))
            for h in (4e-3, 2e-3, 1e-3)
        ]
        observed = np.log2(errors[-2] / errors[-1])
        assert abs(observed - order) < 0.1, (method, errors, observed)


def test_files_load_with_what_they_ignore() -> None:
    arm = multibody.load(ROOT / "examples" / "multibody" / "arm.xml")
    assert any("sensor" in k for k in arm.ignored)
    assert not any("actuator" in k for k in arm.ignored)
    assert len(arm.bodies) >= 3 and all(kind in {"ball", "hinge", "slide", "weld", "free"} for _, kind in arm.joints)
    urdf = multibody.load(ROOT / "examples" / "multibody" / "double_pendulum.urdf")
    xml = multibody.load(ROOT / "examples" / "multibody" / "double_pendulum.xml")
    a = urdf.run(step=1e-3, t_end=0.5, every=500)
    b = xml.run(step=1e-3, t_end=0.5, every=500)
    assert a.joints.shape == b.joints.shape == (2, 2)
    energy = a.relative_energy_error
    assert energy[0] == 0.0 and abs(energy[-1]) < 1e-4
    # A scene that includes the arm, and a four-bar closed by an equality `connect`.
    scene = multibody.load(ROOT / "examples" / "multibody" / "arm_scene.xml")
    assert scene.bodies == arm.bodies and scene.joints == arm.joints
    four_bar = multibody.load(ROOT / "examples" / "multibody" / "four_bar.xml")
    assert four_bar.joints[-1] == ("D", "ball")
    run = four_bar.run(step=1e-3, t_end=0.2, every=100)
    assert run.max_position_constraint_violation < 1e-12


def test_bad_input_raises(tmp_path: Path) -> None:
    bad = tmp_path / "bad.xml"
    bad.write_text(
        '<mujoco><worldbody><body name="a"><joint type="hinge" axis="0 0 0"/>\n'
        '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body></worldbody></mujoco>'
    )
    with pytest.raises(ValueError, match="bad.xml:1"):
        multibody.load(bad)
    with pytest.raises(ValueError, match="unknown problem"):
        multibody.problem("nope")
    model = multibody.problem("double-pendulum")
    with pytest.raises(ValueError, match="method"):
        model.run("euler")
    with pytest.raises(ValueError, match="step"):
        model.run(step=-1.0)
    with pytest.raises(ValueError, match="every"):
        model.run(every=0)
    with pytest.raises(TypeError, match="t_end"):
        model.run(t_end="1")  # type: ignore[arg-type]
    with pytest.raises(liemid.ConvergenceError):
        model.run(step=2.0, t_end=10.0)


def test_the_module_example_runs() -> None:
    import doctest

    result = doctest.testmod(multibody)
    assert result.attempted > 0 and result.failed == 0


def test_the_run_says_what_the_model_policy_left_out_as_the_cli_does(tmp_path: Path) -> None:
    # An armature the maximal-coordinate methods drop (on a slide; a hinge's is kept exactly),
    # a range the joint-space RK4 ignores: both said in the run's notes and as a warning,
    # each by the method it concerns.
    xml = tmp_path / "arm.xml"
    xml.write_text(
        """<mujoco model="noted"><worldbody><body name="arm">
        <joint name="shoulder" type="slide" axis="1 0 0" armature="0.1" range="-1 1" limited="true"/>
        <inertial pos="0.1 0 0" mass="0.1" diaginertia="1e-4 1e-4 1e-4"/>
        </body></worldbody></mujoco>"""
    )
    model = multibody.load(xml)
    with pytest.warns(UserWarning, match="armature"):
        maximal = model.run("liemid", step=1e-3, t_end=0.01)
    assert len(maximal.notes) == 1 and "armature" in maximal.notes[0]
    with pytest.warns(UserWarning, match="joint limits"):
        joint_space = model.run("rk4", step=1e-3, t_end=0.01)
    assert len(joint_space.notes) == 1 and "joint limits" in joint_space.notes[0]
    assert multibody.problem("double-pendulum").run(step=1e-3, t_end=0.01).notes == []


def test_the_variational_drift_is_a_choice_of_the_liemid_methods() -> None:
    model = multibody.problem("chain-10")
    midpoint = model.run(step=1e-3, t_end=0.1, every=100)
    variational = model.run(step=1e-3, t_end=0.1, every=100, drift="variational")
    difference = float(np.max(np.abs(midpoint.xpos[-1] - variational.xpos[-1])))
    assert 1e-12 < difference < 1e-4
    assert variational.max_position_constraint_violation < 1e-12
    with pytest.raises(ValueError, match="drift"):
        model.run(t_end=0.01, drift="cayley")
    with pytest.raises(ValueError, match="drift"):
        model.run("rk4", t_end=0.01, drift="variational")


def test_the_view_page_never_replaces_a_file_the_model_was_read_from(tmp_path: Path) -> None:
    # The scene includes arm.xml: a page written over it (or over the scene) is refused.
    for name in ["arm_scene.xml", "arm.xml"]:
        (tmp_path / name).write_bytes((ROOT / "examples" / "multibody" / name).read_bytes())
    run = multibody.load(tmp_path / "arm_scene.xml").run(step=1e-3, t_end=0.01, every=5)
    for target in ["arm.xml", "arm_scene.xml"]:
        before = (tmp_path / target).read_bytes()
        with pytest.raises(ValueError, match="input"):
            run.view(str(tmp_path / target))
        assert (tmp_path / target).read_bytes() == before


def test_a_run_with_contacts_says_its_contact_statistics(tmp_path: Path) -> None:
    # A box (half-edge 0.1 m) dropped flat from 1 cm onto a floor lands on its four corners
    # and rests at its exact height; the run's contact statistics are the command's.
    xml = tmp_path / "box.xml"
    xml.write_text(
        """<mujoco model="box"><worldbody><geom name="floor" type="plane" size="0 0 1"/>
        <body name="box" pos="0 0 0.11"><freejoint/>
        <geom type="box" size="0.1 0.1 0.1" mass="1"/></body></worldbody></mujoco>"""
    )
    run = multibody.load(xml).run("liemid", step=1e-3, t_end=0.5, every=500)
    c = run.contacts
    assert c is not None
    assert c["most_points"] >= 4
    assert 0.0 <= c["deepest_penetration"] <= 1e-9
    assert c["position_iterations"] > 0 and c["solver_sweeps"] > 0
    assert c["split_steps"] == 0 and c["loose_steps"] == 0 and c["max_loose_violation"] == 0.0
    assert c["frictionless_drifts"] == 0
    assert abs(run.xpos[-1, 0, 2] - 0.1) < 1e-9
    # Its page holds every sample (the contact slots empty: a run's samples hold no contacts).
    page = Path(run.view(str(tmp_path / "box.html"))).read_text()
    assert '"contact_slots":64' in page and "2 frames of 500 steps" in page
    # Without contacts, or by the joint-space method: no statistics.
    assert multibody.problem("double-pendulum").run(step=1e-3, t_end=0.01).contacts is None
