"""Control from Python: a PD callback holds a pendulum at a target angle, a constant
control and the stepping simulator agree with run(), bad controls are refused."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from liemid import multibody

ARM = """<mujoco><compiler angle="radian"/><worldbody><body name="rod">
<joint name="shoulder" axis="0 1 0" damping="0.5"/>
<inertial pos="0.5 0 0" mass="1" diaginertia="0.01 0.01 0.01"/></body></worldbody>
<actuator><motor name="torque" joint="shoulder" ctrlrange="-50 50"/></actuator></mujoco>"""


def arm(tmp_path: Path) -> multibody.Model:
    path = tmp_path / "arm.xml"
    path.write_text(ARM)
    return multibody.load(path)


@pytest.mark.parametrize("method", ["liemid", "rk4"])
def test_a_pd_callback_holds_the_arm_at_its_target(tmp_path: Path, method: str) -> None:
    model = arm(tmp_path)
    target, kp, kd = 0.4, 200.0, 20.0
    calls = []

    def pd(t: float, qpos: np.ndarray, qvel: np.ndarray) -> list[float]:
        calls.append(t)
        # Gravity compensation m g l cos q plus PD about the target.
        return [kp * (target - qpos[0]) - kd * qvel[0] - 9.81 * 0.5 * np.cos(qpos[0])]

    run = model.run(method, step=1e-3, t_end=3.0, every=100, control=pd)
    assert len(calls) == 3000 and calls[0] == 0.0
    assert abs(run.joints[-1, 0] - target) < 1e-6


def test_a_constant_control_and_the_simulator_agree_with_run(tmp_path: Path) -> None:
    model = arm(tmp_path)
    run = model.run("liemid", step=1e-3, t_end=0.2, every=200, control=[2.0])
    sim = model.simulator("liemid", step=1e-3)
    assert sim.actuators == ["torque"]
    sim.ctrl = [2.0]
    sim.step(200)
    assert abs(sim.time - 0.2) < 1e-12
    assert np.array_equal(sim.xpos, run.xpos[-1])
    assert np.array_equal(sim.xquat, run.xquat[-1])
    assert sim.qpos[0] == run.joints[-1, 0]
    assert sim.qvel.shape == (1,)


def test_bad_controls_are_refused(tmp_path: Path) -> None:
    model = arm(tmp_path)
    with pytest.raises(ValueError, match="ctrl has 2"):
        model.run("liemid", step=1e-3, t_end=0.01, control=[1.0, 2.0])
    with pytest.raises(ValueError, match="torque"):
        model.run("liemid", step=1e-3, t_end=0.01, control=[float("nan")])
    with pytest.raises(ValueError, match="returned 2 values"):
        model.run("liemid", step=1e-3, t_end=0.01, control=lambda t, q, v: [1.0, 2.0])

    def boom(t: float, q: np.ndarray, v: np.ndarray) -> list[float]:
        raise KeyError("from the controller")

    with pytest.raises(KeyError, match="from the controller"):
        model.run("rk4", step=1e-3, t_end=0.01, control=boom)
    sim = model.simulator()
    with pytest.raises(ValueError, match="torque"):
        sim.ctrl = [float("nan")]
