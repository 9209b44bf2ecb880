"""What the fuzz of the arguments (test_fuzz_arguments.py) found, one regular test each: every
argument is checked by one shared layer (``liemid._core``: ``_number``, ``_count``,
``_text``, ``_path``, ``_show``) before the compiled core sees it, files go through the
application's input and output layers, and pools and storage are bounded before they are
made."""

from __future__ import annotations

import os
import re
import signal
from pathlib import Path
from types import FrameType
from typing import Any, Callable, Iterator, Optional

import numpy as np
import pytest

import liemid
from liemid import beam, many, multibody, spins

ROOT = Path(__file__).resolve().parents[3]


def one_clean_line(e: BaseException) -> str:
    text = str(e)
    assert "\n" not in text and not re.search(r"\d{20,}", text), text
    return text


def free_run(**kwargs: Any) -> liemid.Solution:
    free = liemid.problems.free_body()
    run: dict[str, Any] = dict(rotation=free.rotation, angular_momentum=free.angular_momentum, t_end=0.01, step=1e-3)
    run.update(kwargs)
    return liemid.integrate(free.body, **run)


def fluid() -> many.System:
    return many.System.dipolar_fluid(64, density=0.1, cutoff=2.0)


def test_integers_beyond_64_bits_are_a_value_error_naming_the_argument() -> None:
    # They used to escape the core's conversion as OverflowError ("int too big to convert").
    chain, start = spins.problem("chain-64")
    calls: list[tuple[str, Callable[[], Any]]] = [
        ("every", lambda: free_run(every=2**70)),
        ("every", lambda: spins.integrate(chain, start, t_end=0.05, step=1e-2, every=2**64)),
        ("every", lambda: multibody.problem("double-pendulum").run(t_end=0.01, every=2**64)),
        ("elements_per_member", lambda: beam.run(elements_per_member=2**64, t_end=0.01)),
        ("seed", lambda: spins.near_z(3, seed=2**70)),
        ("seed", lambda: many.System.dipolar_fluid(64, seed=-1)),
        ("max_points", lambda: liemid.work_precision(max_points=-(2**70))),
        ("steps", lambda: fluid().step(1e-3, 2**64)),
        ("threads", lambda: spins.integrate(chain, start, t_end=0.05, step=1e-2, threads=2**70)),
        ("max_steps", lambda: free_run(max_steps=2**70)),
    ]
    for name, call in calls:
        with pytest.raises(ValueError, match=f"^{name}: expected a whole number") as e:
            call()
        one_clean_line(e.value)
    with pytest.raises(ValueError, match="seed: expected a whole number, found inf"):
        many.System.dipolar_fluid(64, seed=float("inf"))  # type: ignore[arg-type]


def test_arrays_given_for_numbers_are_named_by_their_shape_on_one_line() -> None:
    # The message used to be the array's repr, over several lines.
    bad = np.full((3, 3), np.nan)
    for name, call in [
        ("adaptive", lambda: free_run(step=None, adaptive=bad)),
        ("t0", lambda: free_run(t0=bad)),
        ("min_error", lambda: liemid.work_precision(min_error=bad)),
        ("switch_start", lambda: many.Dipoles(switch_start=bad)._spec()),  # type: ignore[arg-type]
        ("dmi", lambda: spins.System(dmi=bad)),  # type: ignore[arg-type]
    ]:
        with pytest.raises(ValueError, match=rf"^{name}: expected a number, found an array of shape \(3, 3\) \(float64\)$"):
            call()
    with pytest.raises(ValueError, match=r"every: a whole number of steps, at least 1, found an array of shape \(3, 3\)"):
        multibody.problem("double-pendulum").run(every=bad)  # type: ignore[arg-type]


def test_no_message_holds_a_number_of_twenty_digits() -> None:
    with pytest.raises(ValueError, match=r"max_steps: expected a whole number from 1 to 2\*\*64 - 1, found 1.181e\+21$"):
        free_run(max_steps=2**70)
    with pytest.raises(ValueError, match=r"principal moment I2 = -1e300 must be finite and positive"):
        liemid.RigidBody([1e300, -1e300, 1e300])
    with pytest.raises(ValueError, match=r"body 0: .*principal moment I2 = -1e300"):
        many.System([1.0], [1e300, -1e300, 1e300], [[0.0] * 3], np.eye(3), [[1.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match=r"not symmetric: I\[0\]\[1\] = 1e300 but I\[1\]\[0\] = -1e300"):
        liemid.RigidBody([[1.0, 1e300, 0.0], [-1e300, 1.0, 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match=r"t_end, step: the run would take about \d\.\de\d+ steps, more than the default bound") as e:
        beam.run(t_end=float(2**64))
    one_clean_line(e.value)
    with pytest.raises(ValueError, match=r"quaternion: .* norm is 1e150$"):
        free_run(rotation=None, quaternion=[1e150, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"determinant 1e300"):
        free_run(rotation=np.diag([1e100, 1e100, 1e100]))


def test_names_and_paths_must_be_strings() -> None:
    # str() turned any value into a name (a 22-digit "unknown problem") and a string of
    # methods into its letters.
    for call in [
        lambda: spins.problem(2**70),  # type: ignore[arg-type]
        lambda: multibody.problem(2**70),  # type: ignore[arg-type]
        lambda: multibody.load(np.zeros(3)),  # type: ignore[arg-type]
        lambda: liemid.converge(methods="liemid-ea"),
        lambda: liemid.converge(methods=[1, 2]),  # type: ignore[list-item]
        lambda: free_run(method=2**70),
        lambda: spins.System(size=3),  # type: ignore[arg-type]
    ]:
        with pytest.raises(TypeError, match=r"^(name|path|methods|method|size): expected"):
            call()


def test_wrong_objects_are_a_type_error_naming_the_argument() -> None:
    # They used to raise AttributeError ('float' object has no attribute 'size' / '_spec').
    chain, start = spins.problem("chain-64")
    run = spins.integrate(chain, start, t_end=0.05, step=1e-2)
    with pytest.raises(TypeError, match="system: expected liemid.spins.System, found float"):
        run.view(1.5)  # type: ignore[arg-type]
    square, _ = spins.problem("square-64")
    with pytest.raises(ValueError, match="system: 4096 sites, but the run has 64 spins"):
        run.view(square)
    with pytest.raises(TypeError, match="model: expected liemid.many.Independent or Dipoles, found float"):
        many.System([1.0], [1.0, 2.0, 3.0], [[0.0] * 3], np.eye(3), [[1.0, 0.0, 0.0]], model=1.5)  # type: ignore[arg-type]


class Blocked(BaseException):
    pass


def _ring(_signum: int, _frame: Optional[FrameType]) -> None:
    raise Blocked()


@pytest.fixture
def fifo(tmp_path: Path) -> Iterator[Path]:
    """A FIFO named like a scenario file; an alarm turns a call that waits on it into a
    failure instead of a hang."""
    path = tmp_path / "fifo.toml"
    os.mkfifo(path)
    previous = signal.signal(signal.SIGALRM, _ring)
    signal.setitimer(signal.ITIMER_REAL, 5.0)
    try:
        yield path
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def test_a_fifo_is_refused_as_a_structure_file_without_blocking(fifo: Path) -> None:
    with pytest.raises(ValueError, match="file: .*fifo.toml: not a regular file"):
        beam.run(file=fifo, t_end=0.01)


def test_a_fifo_is_refused_as_a_scenario_file_without_blocking(fifo: Path) -> None:
    with pytest.raises(ValueError, match="scenario: .*fifo.toml: not a regular file"):
        liemid.converge(scenario=str(fifo))


def test_a_beam_page_is_not_written_through_a_fifo(fifo: Path, tmp_path: Path) -> None:
    run = beam.run(elements_per_member=1, t_end=0.02, view=True)
    page = fifo.with_suffix(".html")
    os.mkfifo(page)
    with pytest.raises(ValueError, match="view .*fifo.html is a FIFO"):
        run.view(str(page))
    with pytest.raises(ValueError, match="view .*a_dir.html is a directory"):
        (tmp_path / "a_dir.html").mkdir()
        run.view(str(tmp_path / "a_dir.html"))
    written = tmp_path / "beam.html"
    assert run.view(written) == str(written) and written.read_text(encoding="utf-8") == run.page


def test_thread_counts_beyond_four_per_core_are_refused() -> None:
    # A mistyped count used to start that many threads.
    chain, start = spins.problem("chain-64")
    with pytest.raises(ValueError, match="threads: 100000 is more than 4 per core"):
        spins.integrate(chain, start, t_end=0.05, step=1e-2, threads=100_000)
    with pytest.raises(ValueError, match="threads: 100000 is more than 4 per core"):
        fluid().step(1e-3, 1, threads=100_000)


def test_storage_beyond_the_memory_is_refused_before_it_is_made() -> None:
    with pytest.raises(ValueError, match=r"size: 1e10 sites; at most 1e8 are accepted"):
        spins.System("square", (10**5, 10**5))
    with pytest.raises(MemoryError, match=r"n: 1\.15\d*e18 spins would need about .* GB, more than 80 % of the .* GB"):
        spins.near_z(2**60)
    with pytest.raises(MemoryError, match=r"n: 1\.15\d*e18 bodies would need about"):
        many.System.dipolar_fluid(2**60)


def test_a_study_beyond_the_step_bound_is_refused_at_once() -> None:
    # work_precision(t_end=1e6) used to compute its DOP853 reference for many minutes.
    with pytest.raises(ValueError, match=r"work_precision: t_end: the study's coarsest run would take about .* steps, more than max_steps 10"):
        liemid.work_precision("free-body", t_end=100.0, max_steps=10)
    with pytest.raises(ValueError, match=r"default bound of 1000000000"):
        liemid.work_precision("free-body", t_end=1e300)
    with pytest.raises(ValueError, match=r"converge: steps, t_end: the run would take 90 steps, more than max_steps 10"):
        liemid.converge(methods=["liemid-ea"], steps=[2e-3, 1e-3], t_end=0.06, max_steps=10)
