"""A fuzz of the Python arguments: seeded random calls of the public entry points (rigid
bodies, ensembles, the studies, multibody files and runs, beams, spins, many bodies, the
3-D pages) with arguments mutated into NaN, infinities, ±1e300, zero, negative numbers,
huge integers, wrong types, wrong shapes and lengths of numpy arrays, empty strings,
unknown names, and paths to a directory, a missing file or a FIFO.

Every call must return or raise one of the exceptions the package documents (ValueError,
TypeError, OSError, MemoryError, RuntimeError and liemid.ConvergenceError): never a Rust
panic (``pyo3_runtime.PanicException``, a BaseException), never another exception
(OverflowError, KeyError, ...), never a hang (an alarm per case, and faulthandler ends the
process if even that does not come back). Error messages are one line, without Rust debug
text (``Some(``, ``None /``) and without numbers of 20 digits or more. The test prints the
case count and the outcomes."""

from __future__ import annotations

import faulthandler
import math
import os
import re
import signal
import time
import warnings
from collections import Counter
from pathlib import Path
from types import FrameType
from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np
import pytest

import liemid
from liemid import beam, many, multibody, spins

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"

SEED = int(os.environ.get("LIEMID_FUZZ_SEED", "20480"))
CASES = int(os.environ.get("LIEMID_FUZZ_CASES", "3000"))
ALARM_SECONDS = 10.0
VERBOSE = bool(os.environ.get("LIEMID_FUZZ_VERBOSE"))
CLEAN = (ValueError, TypeError, OSError, MemoryError, RuntimeError)


class Hang(BaseException):
    """A call that had not returned when its alarm rang."""


def _alarm(_signum: int, _frame: Optional[FrameType]) -> None:
    raise Hang()


class Paths:
    """The paths given as arguments: a directory, a missing file, FIFOs named like each
    kind of file, the example files, a directory that does not exist."""

    def __init__(self, tmp: Path) -> None:
        self.directory = tmp / "a_directory.xml"
        self.directory.mkdir()
        self.missing = tmp / "missing.xml"
        self.fifos = []
        for suffix in ("xml", "urdf", "toml", "html"):
            fifo = tmp / f"fifo.{suffix}"
            os.mkfifo(fifo)
            self.fifos.append(fifo)
        self.out = tmp / "page.html"
        self.nowhere = tmp / "no" / "such" / "dir" / "page.html"
        self.models = sorted((EXAMPLES / "multibody").iterdir())

    def bad(self) -> List[Any]:
        return [str(self.directory), str(self.missing), *map(str, self.fifos), str(self.nowhere), "", "\0", self.directory]


def bad_values(paths: Paths) -> List[Any]:
    """The mutations: numbers out of range, wrong types and shapes, names and paths."""
    return [
        math.nan,
        math.inf,
        -math.inf,
        1e300,
        -1e300,
        1e-300,
        1e-3,
        0.5,
        2,
        3.0,
        0,
        0.0,
        -1,
        -1.5,
        2**70,
        -(2**70),
        2**64,
        True,
        None,
        "",
        "nonsense",
        "liemid-zz",
        "rk4",
        "exact",
        "chain",
        "1e-3",
        [],
        [1.0, 2.0],
        [math.nan] * 3,
        [[1.0, 2.0, 3.0]] * 2,
        np.zeros(7),
        np.full(3, math.inf),
        np.full((3, 3), math.nan),
        np.zeros((2, 2, 2)),
        np.array(["a", "b", "c"]),
        np.array([1e300, -1e300, 1e300]),
        np.array([1e150, 0.0, 0.0, 0.0]),
        np.full((3, 3), 1e300),
        np.zeros(0),
        complex(1.0, 2.0),
        b"bytes",
        {"a": 1},
        object(),
        *paths.bad(),
    ]


Call = Callable[..., Any]


def entries(paths: Paths) -> Dict[str, Tuple[Call, Dict[str, Any]]]:
    """Each public entry point with valid arguments (short runs)."""
    top = liemid.problems.fast_top()
    free = liemid.problems.free_body()
    pendulum = multibody.problem("double-pendulum")
    chain, chain_start = spins.problem("chain-64")
    sol = liemid.integrate(free.body, rotation=free.rotation, angular_momentum=free.angular_momentum, t_end=0.01, step=1e-3)
    mrun = pendulum.run(step=1e-3, t_end=0.01)
    srun = spins.integrate(chain, chain_start, t_end=0.05, step=1e-2)
    brun = beam.run("right-angle-cantilever", elements_per_member=1, t_end=0.05, view=True)
    bodies = many.System([1.0, 2.0], [1.0, 2.0, 3.0], [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]], np.eye(3), [[1.0, 0.0, 0.0]] * 2)

    def integrate_body(inertia: Any, torque: Any, potential: Any, **run: Any) -> Any:
        return liemid.integrate(liemid.RigidBody(inertia, torque, potential), **run)

    def gravity(mass: Any, center_of_mass: Any, gravity: Any) -> Any:
        g = liemid.Gravity(mass, center_of_mass, gravity)
        return liemid.integrate(liemid.RigidBody([1.0, 2.0, 2.5], g), angular_velocity=[1.0, 2.0, 3.0], t_end=0.01, step=1e-3)

    def constant(body: Any, spatial: Any) -> Any:
        c = liemid.ConstantTorque(body, spatial)
        return liemid.integrate(liemid.RigidBody([1.0, 2.0, 2.5], c), angular_velocity=[1.0, 2.0, 3.0], t_end=0.01, step=1e-3)

    def model_run(model: Any, **run: Any) -> Any:
        return (multibody.load(model) if isinstance(model, (str, Path)) else pendulum).run(**run)

    def spins_system(**kw: Any) -> Any:
        return len(spins.System(**kw))

    def spins_run(system: Any, start: Any, **kw: Any) -> Any:
        return spins.integrate(chain if system == "chain" else system, start, **kw)

    def many_system(**kw: Any) -> Any:
        s = many.System(**kw)
        s.step(1e-3, 3, threads=1)
        return s.totals()

    def dipoles(**kw: Any) -> Any:
        s = many.System(
            [1.0, 1.0], [1.0, 1.0, 1.0], [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0]], np.eye(3), [[0.0, 0.0, 1.0]] * 2, model=many.Dipoles(**kw)
        )
        s.step(1e-3, 3, threads=1)
        return s.totals()

    def many_step(h: Any, steps: Any, threads: Any, max_steps: Any) -> Any:
        return bodies.step(h, steps, threads=threads, max_steps=max_steps)

    def rotation(kind: Any) -> Any:
        bodies.rotation = kind
        return bodies.rotation

    fluid = many.System.dipolar_fluid

    return {
        "integrate": (
            liemid.integrate,
            dict(
                body=top.body,
                t_end=0.01,
                step=1e-3,
                method="liemid-ea",
                rotation=top.rotation,
                angular_momentum=top.angular_momentum,
                t0=0.0,
                every=1,
                max_steps=None,
            ),
        ),
        "integrate-adaptive": (
            liemid.integrate,
            dict(body=top.body, t_end=0.01, adaptive=0.1, rho="omega", method="liemid-ea", rotation_vector=[0.1, 0.2, 0.3], angular_velocity=[1.0, 2.0, 3.0], every=1),
        ),
        "integrate-quaternion": (
            liemid.integrate,
            dict(body=free.body, t_end=0.01, step=1e-3, quaternion=[1.0, 0.0, 0.0, 0.0], angular_velocity=[1.0, 2.0, 3.0], method="liemid-ex"),
        ),
        "body": (
            integrate_body,
            dict(inertia=[1.0, 2.0, 2.5], torque=None, potential=None, angular_velocity=[1.0, 2.0, 3.0], t_end=0.01, step=1e-3),
        ),
        "gravity": (gravity, dict(mass=1.0, center_of_mass=[0.0, 0.0, 0.1], gravity=[0.0, 0.0, -9.81])),
        "constant-torque": (constant, dict(body=[0.0, 0.0, 1.0], spatial=[0.1, 0.0, 0.0])),
        "problem": (liemid.problems.get, dict(name="fast-top")),
        "problem-integrate": (
            lambda name, **kw: liemid.problems.get(name).integrate(**kw),
            dict(name="free-body", method="liemid-ea", step=1e-3, t_end=0.01, every=1, max_steps=None),
        ),
        "ensemble": (
            liemid.ensemble,
            dict(
                body=top.body,
                rotations=top.rotation,
                angular_momenta=[top.angular_momentum] * 3,
                t_end=0.01,
                step=1e-3,
                method="liemid-ea",
                t0=0.0,
                threads=1,
                max_steps=None,
            ),
        ),
        "converge": (
            liemid.converge,
            dict(problem="free-body", scenario=None, methods=["liemid-ea"], steps=[2e-3, 1e-3], t_end=0.02, max_steps=None),
        ),
        "work-precision": (
            liemid.work_precision,
            dict(problem="free-body", methods=["liemid-ea"], t_end=0.01, repetitions=5, budget=1e-3, min_error=1e-2, max_points=1),
        ),
        "scenario-file": (liemid.converge, dict(scenario=str(EXAMPLES / "fast_top.toml"), methods=["liemid-ea"], steps=[1e-3], t_end=0.01)),
        "multibody-load": (multibody.load, dict(path=str(paths.models[0]))),
        "multibody-problem": (multibody.problem, dict(name="double-pendulum")),
        "multibody-run": (
            model_run,
            dict(model=pendulum, method="liemid", step=1e-3, t_end=0.01, every=1, drift="midpoint", max_steps=None),
        ),
        "multibody-file-run": (model_run, dict(model=str(paths.models[1]), method="rk4", step=1e-3, t_end=0.01, every=2)),
        "multibody-view": (mrun.view, dict(path=str(paths.out))),
        "beam": (
            beam.run,
            dict(
                problem="right-angle-cantilever",
                elements_per_member=1,
                method=None,
                step=None,
                t_end=0.05,
                sample=None,
                force_step=False,
                view=False,
                max_steps=None,
            ),
        ),
        "beam-file": (beam.run, dict(file=str(EXAMPLES / "right_angle_cantilever.toml"), elements_per_member=1, t_end=0.02)),
        "beam-text": (beam.run, dict(text=(EXAMPLES / "right_angle_cantilever.toml").read_text(), elements_per_member=1, t_end=0.02)),
        "beam-view": (brun.view, dict(path=str(paths.out))),
        "spins-system": (
            spins_system,
            dict(
                kind="square",
                size=(4, 4),
                periodic=True,
                exchange=1.0,
                anisotropy=0.1,
                anisotropy_axis=(0.0, 0.0, 1.0),
                field=(0.0, 0.0, 1.0),
                mu_s=1.0,
                damping=0.0,
                dmi=0.1,
                dmi_kind="interfacial",
            ),
        ),
        "spins-integrate": (
            spins_run,
            dict(system="chain", start=chain_start, t_end=0.05, step=1e-2, method="split", every=1, threads=1, max_steps=None),
        ),
        "spins-problem": (spins.problem, dict(name="chain-64")),
        "spins-near-z": (spins.near_z, dict(n=10, max_tilt=0.3, seed=1)),
        "spins-energy": (chain.energy, dict(spins=chain_start)),
        "spins-view": (srun.view, dict(system=chain, path=str(paths.out))),
        "many-system": (
            many_system,
            dict(
                masses=[1.0, 2.0],
                inertia=[1.0, 2.0, 3.0],
                positions=[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
                rotations=np.eye(3),
                angular_momenta=[[1.0, 0.0, 0.0]] * 2,
                momenta=None,
                free=True,
                model=many.Independent(),
                rotation="midpoint",
            ),
        ),
        "many-independent": (
            lambda **kw: many_system(
                masses=[1.0], inertia=[1.0, 2.0, 3.0], positions=[[0.0] * 3], rotations=np.eye(3), angular_momenta=[[1.0, 0.0, 0.0]], model=many.Independent(**kw)
            ),
            dict(gravity=(0.0, 0.0, -9.81), center_of_mass=(0.0, 0.0, 0.1)),
        ),
        "many-dipoles": (
            dipoles,
            dict(moment=(0.0, 0.0, 1.0), sigma=1.0, epsilon=1.0, cutoff=None, box_length=None, switch_start=None, cutoff_form="switched"),
        ),
        "many-fluid": (fluid, dict(n=64, density=0.1, seed=1, cutoff=2.0, rotation="exact")),
        "many-step": (many_step, dict(h=1e-3, steps=3, threads=1, max_steps=None)),
        "many-rotation": (rotation, dict(kind="exact")),
        "many-view": (bodies.view, dict(path=str(paths.out), box_length=None)),
        "solution-view": (sol.view, dict(path=str(paths.out))),
    }


def check_message(name: str, kwargs: Dict[str, Any], e: BaseException) -> Optional[str]:
    """What is wrong with an error's message, if anything."""
    text = str(e)
    if "\n" in text.strip():
        return "a message of several lines"
    if "Some(" in text or "None /" in text:
        return "Rust debug text"
    if re.search(r"\d{20,}", text):
        return "a number of 20 digits or more"
    return None


def mutate(rng: np.random.Generator, base: Dict[str, Any], values: List[Any]) -> Dict[str, Any]:
    kwargs = dict(base)
    keys = list(kwargs)
    for _ in range(int(rng.integers(1, 3))):
        key = keys[int(rng.integers(len(keys)))]
        kwargs[key] = values[int(rng.integers(len(values)))]
    return kwargs


def describe(kwargs: Dict[str, Any]) -> str:
    def short(v: Any) -> str:
        r = repr(v)
        return r if len(r) < 60 else r[:57] + "..."

    return ", ".join(f"{k}={short(v)}" for k, v in kwargs.items())


def test_mutated_arguments_give_clean_outcomes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A mutated path ("nonsense") is a page written in the working directory: the scratch one.
    monkeypatch.chdir(tmp_path)
    paths = Paths(tmp_path)
    values = bad_values(paths)
    calls = entries(paths)
    names = sorted(calls)
    rng = np.random.default_rng(SEED)
    outcomes: Counter[str] = Counter()
    failures: List[str] = []
    previous = signal.signal(signal.SIGALRM, _alarm)
    started = time.monotonic()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for case in range(CASES):
                name = names[case % len(names)] if case < len(names) else names[int(rng.integers(len(names)))]
                call, base = calls[name]
                kwargs = base if case < len(names) else mutate(rng, base, values)
                if VERBOSE:
                    print(f"case {case} {name}({describe(kwargs)})", flush=True)
                faulthandler.dump_traceback_later(3 * ALARM_SECONDS, exit=True)
                signal.setitimer(signal.ITIMER_REAL, ALARM_SECONDS)
                try:
                    call(**kwargs)
                    outcome = "returned"
                except Hang:
                    outcome = "hang"
                    failures.append(f"case {case} {name}({describe(kwargs)}): no answer within {ALARM_SECONDS} s")
                except CLEAN as e:
                    outcome = type(e).__name__
                    problem = check_message(name, kwargs, e)
                    if problem:
                        failures.append(f"case {case} {name}({describe(kwargs)}): {problem}: {type(e).__name__}: {e}"[:600])
                except BaseException as e:  # noqa: BLE001 - a panic is a BaseException
                    if isinstance(e, KeyboardInterrupt):
                        raise
                    outcome = type(e).__name__
                    failures.append(f"case {case} {name}({describe(kwargs)}): {type(e).__name__}: {e}"[:600])
                finally:
                    signal.setitimer(signal.ITIMER_REAL, 0)
                    faulthandler.cancel_dump_traceback_later()
                outcomes[outcome] += 1
                if case < len(names):
                    assert outcome == "returned", f"the valid call of {name} failed: {failures[-1:]}"
    finally:
        signal.signal(signal.SIGALRM, previous)
    elapsed = time.monotonic() - started
    summary = ", ".join(f"{k} {v}" for k, v in outcomes.most_common())
    print(f"\n{CASES} cases over {len(names)} entry points in {elapsed:.1f} s: {summary}")
    if VERBOSE:
        print("\n".join(failures))
    assert not failures, f"{len(failures)} not clean:\n" + "\n".join(failures[:40])
    assert elapsed < 30.0, f"the fuzz took {elapsed:.1f} s"
