"""Type stubs of the compiled core (flat float64 arrays in and out)."""

from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import NDArray

Triple = Tuple[float, float, float]
Adapter = Callable[[List[float], float], Triple]

def integrate(
    inertia: List[float],
    gravity: List[Tuple[float, Triple, Triple]],
    constant: List[Tuple[Triple, Triple]],
    torque: Optional[Adapter],
    potential: Optional[Adapter],
    attitude_kind: str,
    attitude_values: List[float],
    momentum: Tuple[str, Triple],
    t0: float,
    t_end: float,
    step: float,
    method: str,
    every: int,
    adaptive: Optional[float] = None,
    rho: Optional[str] = None,
    max_steps: Optional[int] = None,
) -> dict[str, Any]: ...
def ensemble(
    inertia: List[float],
    gravity: List[Tuple[float, Triple, Triple]],
    constant: List[Tuple[Triple, Triple]],
    attitude_kind: str,
    attitudes: NDArray[np.float64],
    momenta: NDArray[np.float64],
    momentum_kind: str,
    t0: float,
    t_end: float,
    step: float,
    method: str,
    threads: int,
    max_steps: Optional[int] = None,
) -> Tuple[NDArray[np.float64], NDArray[np.float64]]: ...
def methods() -> List[Tuple[str, str, int, str, str]]: ...
def check_body(inertia: List[float], gravity: List[Tuple[float, Triple, Triple]], constant: List[Tuple[Triple, Triple]]) -> None: ...
def problem(name: str) -> Tuple[str, List[float], List[Tuple[float, Triple, Triple]], List[float], Triple, float, float]: ...
def converge(
    problem: str,
    scenario_text: Optional[str],
    methods: Optional[List[str]],
    steps: Optional[List[float]],
    t_end: Optional[float],
    max_steps: Optional[int] = None,
) -> str: ...
def work_precision(
    problem: str,
    scenario_text: Optional[str],
    methods: Optional[List[str]],
    t_end: Optional[float],
    repetitions: int,
    budget: float,
    min_error: float,
    max_points: int,
    max_steps: Optional[int] = None,
) -> str: ...

class ManyBodies:
    def __init__(
        self,
        mass: Sequence[float],
        inertia: Sequence[float],
        free: Sequence[bool],
        position: Sequence[float],
        momentum: Sequence[float],
        rotation: Sequence[float],
        pi: Sequence[float],
        model: Tuple[Any, ...],
    ) -> None: ...
    @staticmethod
    def dipolar_fluid(n: int, density: float, seed: int, cutoff: float) -> "ManyBodies": ...
    def step(self, h: float, steps: int, threads: int, max_steps: Optional[int] = None) -> None: ...
    def set_rotation(self, kind: str) -> None: ...
    @property
    def rotation(self) -> str: ...
    def totals(self) -> Tuple[float, Triple, Triple]: ...
    @property
    def t(self) -> float: ...
    @property
    def len(self) -> int: ...
    def arrays(self) -> Tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...

class Spins:
    def __init__(
        self,
        kind: str,
        size: Sequence[int],
        periodic: bool,
        exchange: float,
        anisotropy: float,
        anisotropy_axis: Triple,
        field: Triple,
        mu_s: float,
        damping: float,
        dmi: float = ...,
        dmi_kind: str = ...,
    ) -> None: ...
    @staticmethod
    def problem(name: str) -> Tuple["Spins", NDArray[np.float64], float, float]: ...
    @property
    def len(self) -> int: ...
    @property
    def size(self) -> Tuple[int, int, int]: ...
    def energy(self, spins: NDArray[np.float64]) -> float: ...
    def integrate(
        self,
        spins: NDArray[np.float64],
        method: str,
        h: float,
        t_end: float,
        every: int,
        threads: int,
        max_steps: Optional[int] = None,
    ) -> Tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]: ...

def spin_methods() -> List[Tuple[str, int, bool, str]]: ...
def spins_near_z(n: int, max_tilt: float, seed: int) -> NDArray[np.float64]: ...
def beam_run(
    problem: Optional[str],
    text: Optional[str],
    elements_per_member: Optional[int],
    method: Optional[str],
    step: Optional[float],
    t_end: Optional[float],
    sample: Optional[float],
    force_step: bool,
    view: bool = False,
    drift: Optional[str] = None,
    max_steps: Optional[int] = None,
) -> Dict[str, Any]: ...
def beam_problems() -> List[Tuple[str, str]]: ...
def beam_methods() -> List[Tuple[str, int]]: ...
class MultibodyModel:
    @property
    def name(self) -> str: ...
    @property
    def bodies(self) -> List[str]: ...
    @property
    def joints(self) -> List[Tuple[str, str]]: ...
    @property
    def ignored(self) -> List[str]: ...
    @property
    def timestep(self) -> Optional[float]: ...
    @property
    def gravity(self) -> Tuple[float, float, float]: ...
    @property
    def default_t_end(self) -> float: ...
    @property
    def default_step(self) -> float: ...

def multibody_load(path: str) -> MultibodyModel: ...
def multibody_problem(name: str) -> MultibodyModel: ...
def multibody_problems() -> List[Tuple[str, str]]: ...
def multibody_run(
    model: MultibodyModel,
    method: str,
    step: float,
    t_end: float,
    every: int,
    drift: str = ...,
    max_steps: Optional[int] = None,
    control: Any = ...,
) -> Dict[str, Any]: ...

class MultibodySimulator:
    def step(self, n: int = ...) -> None: ...
    @property
    def ctrl(self) -> NDArray[np.float64]: ...
    @ctrl.setter
    def ctrl(self, value: List[float]) -> None: ...
    @property
    def actuators(self) -> List[str]: ...
    @property
    def time(self) -> float: ...
    @property
    def timestep(self) -> float: ...
    @property
    def qpos(self) -> NDArray[np.float64]: ...
    @property
    def qvel(self) -> NDArray[np.float64]: ...
    @property
    def xpos(self) -> NDArray[np.float64]: ...
    @property
    def xquat(self) -> NDArray[np.float64]: ...
    @property
    def notes(self) -> List[str]: ...

def multibody_simulator(model: MultibodyModel, method: str, step: float, drift: str = ...) -> MultibodySimulator: ...
def multibody_view(
    model: MultibodyModel,
    times: NDArray[np.float64],
    xpos: NDArray[np.float64],
    xquat: NDArray[np.float64],
    energy_error: NDArray[np.float64],
    total_steps: int,
    path: Optional[str] = None,
) -> str: ...
def read_input(what: str, path: str) -> str: ...
def write_output(what: str, path: str, text: str) -> str: ...
def view_page(
    scene: str,
    title: str,
    times: NDArray[np.float64],
    frames: NDArray[np.float64],
    energy_t: NDArray[np.float64],
    energy_e: NDArray[np.float64],
    total_steps: int,
    path: Optional[str] = None,
) -> str: ...
