"""The pre-flight of every Python run, as the command's: a run of more than ``max_steps``
steps (10⁹ by default) is refused before the first step (ValueError naming max_steps), and
samples that would not fit in the memory available before anything is allocated
(MemoryError naming both sizes and what to change). ``Model.run(t_end=1e9)`` used to abort
the process on a huge allocation or run for days."""

from __future__ import annotations

import time
from typing import Any, Callable, Dict

import numpy as np
import pytest

import liemid
from liemid import beam, many, multibody, spins


def available_memory() -> int:
    """MemAvailable of /proc/meminfo, in bytes (what liemid_app::shared::memory reads)."""
    with open("/proc/meminfo", encoding="ascii") as f:
        for line in f:
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    pytest.skip("the system does not say how much memory is available")


def fast_top(**kwargs: Any) -> liemid.Solution:
    top = liemid.problems.fast_top()
    return liemid.integrate(top.body, rotation=top.rotation, angular_momentum=top.angular_momentum, **kwargs)


def test_a_run_beyond_the_default_bound_is_refused_at_once_naming_max_steps() -> None:
    started = time.monotonic()
    with pytest.raises(ValueError, match=r"10000000000000 steps, more than the default bound of 1000000000 \(max_steps N"):
        fast_top(t_end=1e9, step=1e-4)
    with pytest.raises(ValueError, match="max_steps"):
        multibody.problem("double-pendulum").run(t_end=1e9)
    with pytest.raises(ValueError, match="max_steps"):
        fast_top(t_end=1e9, adaptive=1e-2)
    assert time.monotonic() - started < 5.0


# Runs of 100 steps each, refused by max_steps=10 and done with max_steps=100.
HUNDRED: Dict[str, Callable[[int], Any]] = {
    "rigid": lambda m: fast_top(t_end=0.01, step=1e-4, max_steps=m),
    "problem": lambda m: liemid.problems.fast_top().integrate(t_end=0.01, step=1e-4, max_steps=m),
    "ensemble": lambda m: liemid.ensemble(
        liemid.problems.free_body().body, angular_velocities=[[1.0, 2.0, 3.0]] * 3, t_end=0.01, step=1e-4, max_steps=m
    ),
    "converge": lambda m: liemid.converge(methods=["liemid-ea"], steps=[2e-3, 1e-3], t_end=0.06, max_steps=m),
    "multibody": lambda m: multibody.problem("double-pendulum").run(step=1e-3, t_end=0.1, max_steps=m),
    "multibody-rk4": lambda m: multibody.problem("double-pendulum").run("rk4", step=1e-3, t_end=0.1, max_steps=m),
    "spins": lambda m: spins.integrate(*spins.problem("chain-64"), step=1e-2, t_end=1.0, max_steps=m),
    "many": lambda m: many.System([1.0], [1.0, 2.0, 3.0], [[0.0, 0.0, 0.0]], np.eye(3), [[1.0, 0.0, 0.0]]).step(
        1e-3, 100, max_steps=m
    ),
    "beam": lambda m: beam.run("right-angle-cantilever", elements_per_member=1, method="newmark", t_end=5.0, sample=0.05, max_steps=m),
}


@pytest.mark.parametrize("name", sorted(HUNDRED))
def test_max_steps_refuses_a_longer_run_and_allows_its_own(name: str) -> None:
    with pytest.raises(ValueError, match="steps, more than max_steps 10"):
        HUNDRED[name](10)
    HUNDRED[name](100)


def test_max_steps_must_be_a_whole_number() -> None:
    for bad, kind in [(0, ValueError), (-5, ValueError), (2**64, ValueError), ("10", TypeError), (True, TypeError), (1.5, TypeError)]:
        with pytest.raises(kind, match="max_steps"):
            fast_top(t_end=0.01, step=1e-4, max_steps=bad)


def test_an_adaptive_run_is_bounded_at_the_start_pace_and_stopped_at_the_bound() -> None:
    # A body spun up by a constant torque: |Ω| from 1 to 101 rad/s, about 5,100 steps of
    # eps 0.1, where the start's pace makes about 150.
    body = liemid.RigidBody([1.0, 1.0, 1.0], liemid.ConstantTorque(body=(0.0, 0.0, 10.0)))
    run = dict(angular_velocity=[0.0, 0.0, 1.0], t_end=10.0, adaptive=0.1)
    with pytest.raises(ValueError, match=r"adaptive 1e-1 to t = 1e1: about 1.5e2 steps at the start's step 6.7e-2, more than max_steps 99"):
        liemid.integrate(body, **run, max_steps=99)  # type: ignore[arg-type]
    with pytest.raises(RuntimeError, match=r"the run reached 200 steps \(max_steps\) at t = .* before t_end = 10"):
        liemid.integrate(body, **run, max_steps=200)  # type: ignore[arg-type]
    assert liemid.integrate(body, **run).steps > 5000  # type: ignore[arg-type]


def test_samples_beyond_the_memory_are_refused_before_allocating_naming_both_sizes() -> None:
    # Twice the available memory in rows of 21 numbers, within the step bound given.
    steps = 2 * available_memory() // (21 * 8)
    started = time.monotonic()
    with pytest.raises(MemoryError, match=r"samples of 21 numbers would need about .* GB, more than 80 % of the .* GB of memory available: .*every"):
        fast_top(t_end=steps * 1e-4, step=1e-4, every=1, max_steps=steps)
    # The same run sampled less often is not refused for its memory (the bound stops it).
    with pytest.raises(ValueError, match="max_steps 10"):
        fast_top(t_end=steps * 1e-4, step=1e-4, every=10**6, max_steps=10)
    # Spins keep 5 numbers per observation.
    system, start = spins.problem("chain-64")
    steps = 2 * available_memory() // (5 * 8)
    with pytest.raises(MemoryError, match=r"samples of 5 numbers would need about"):
        spins.integrate(system, start, step=1e-2, t_end=steps * 1e-2, every=1, max_steps=steps)
    assert time.monotonic() - started < 5.0
