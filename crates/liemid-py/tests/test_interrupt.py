"""Ctrl-C stops every long Python run: the run raises KeyboardInterrupt within a few seconds
and returns nothing. The runs loop in Rust, most with the GIL released, where Python
cannot deliver the signal; they used to run on to their end (minutes here, forever for a
mistyped t_end)."""

from __future__ import annotations

import select
import signal
import subprocess
import sys
import time

import pytest

# Each run would take a minute or more on this machine (10⁸ steps or so, within the default
# step bound and with few samples), so that one still running after the signal is seen.
RUNS = {
    "rigid": (
        "top = liemid.problems.fast_top()",
        "liemid.integrate(top.body, rotation=top.rotation, angular_momentum=top.angular_momentum,"
        " t_end=5e4, step=1e-4, every=10**7)",
    ),
    "rigid-adaptive": (
        "top = liemid.problems.fast_top()",
        "liemid.integrate(top.body, rotation=top.rotation, angular_momentum=top.angular_momentum,"
        " t_end=1e3, adaptive=1e-2, every=10**7)",
    ),
    "ensemble": (
        "top = liemid.problems.fast_top()",
        "liemid.ensemble(top.body, rotations=top.rotation, angular_momenta=[top.angular_momentum] * 2,"
        " t_end=1e4, step=1e-4, threads=1)",
    ),
    "converge": (
        "",
        "liemid.converge('fast-top', methods=['liemid-ea'], steps=[1e-5] * 2000, t_end=1.0)",
    ),
    "work-precision": (
        "",
        "liemid.work_precision('free-body', methods=['liemid-ea'], t_end=1e5)",
    ),
    "multibody": (
        "model = multibody.problem('double-pendulum')",
        "model.run(step=1e-4, t_end=1e4, every=10**7)",
    ),
    "multibody-rk4": (
        "model = multibody.problem('double-pendulum')",
        "model.run('rk4', step=1e-4, t_end=1e4, every=10**7)",
    ),
    "spins": (
        "system, start = spins.problem('square-64')",
        "spins.integrate(system, start, t_end=1e6, step=1e-2, every=10**6)",
    ),
    "many": (
        "system = many.System.dipolar_fluid(216, density=0.3)",
        "system.step(1e-3, 10**8)",
    ),
    "beam": (
        "",
        "beam.run('right-angle-cantilever', elements_per_member=4, t_end=1e5)",
    ),
}

SCRIPT = """
import liemid
from liemid import beam, many, multibody, spins
{setup}
print("ready", flush=True)
{run}
print("finished", flush=True)
"""


@pytest.mark.parametrize("name", sorted(RUNS))
def test_ctrl_c_stops_the_run_with_keyboard_interrupt(name: str) -> None:
    setup, run = RUNS[name]
    proc = subprocess.Popen(
        [sys.executable, "-c", SCRIPT.format(setup=setup, run=run)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        ready, _, _ = select.select([proc.stdout], [], [], 60.0)
        assert ready and proc.stdout is not None, "the run did not start within 60 s"
        line = proc.stdout.readline()
        assert line.strip() == "ready", (line, proc.stderr.read() if proc.stderr else "")
        time.sleep(1.0)
        assert proc.poll() is None, f"{name}: the run ended within 1 s; it should take minutes"
        proc.send_signal(signal.SIGINT)
        sent = time.monotonic()
        try:
            out, err = proc.communicate(timeout=10.0)
        except subprocess.TimeoutExpired:
            pytest.fail(f"{name}: still running 10 s after SIGINT")
        waited = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert "finished" not in out, f"{name}: the run returned a result after the signal"
    assert proc.returncode != 0 and "KeyboardInterrupt" in err, (proc.returncode, err[-2000:])
    assert err.strip().splitlines()[-1] == "KeyboardInterrupt", err[-2000:]
    print(f"{name}: stopped {waited:.2f} s after SIGINT")
