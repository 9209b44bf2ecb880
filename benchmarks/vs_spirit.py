"""liemid spins against Spirit on issue 17's case: a 64x64 periodic square ferromagnet
(J = 1 meV, K = 0.1 meV along z, B = 0, alpha = 0, mu_s = 1), 10 ps, the same start
(spins within 0.3 rad of +z, from a fixed seed) handed to both codes.

For every Spirit solver (SIB, Depondt, Heun, RK4) and liemid method at a sequence of steps:
the relative energy error at t_end and the CPU time; then the CPU time each needs to reach
energy errors 1e-6 and 1e-8 (log-log interpolation) and the ratio of Spirit's best to
liemid's best. One thread each (OMP_NUM_THREADS=1, liemid --threads 1).

Installs nothing: needs the `spirit` package (pip install spirit) and a built liemid
(`cargo build --release -p liemid-cli`, or LIEMID=/path/to/liemid); skips with a message
when either is missing.

    python benchmarks/vs_spirit.py [--quick]
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

try:
    import numpy as np
except ImportError:
    print("vs_spirit: numpy is not installed; skipping")
    sys.exit(0)
try:
    from spirit import configuration, simulation, state, system  # noqa: F401
except ImportError:
    print("vs_spirit: the spirit package is not installed (pip install spirit); skipping")
    sys.exit(0)

ROOT = Path(__file__).resolve().parent.parent
LIEMID = os.environ.get("LIEMID") or str(ROOT / "target" / "release" / "liemid")
if not (Path(LIEMID).exists() or shutil.which(LIEMID)):
    print(f"vs_spirit: no liemid binary at {LIEMID} (cargo build --release -p liemid-cli); skipping")
    sys.exit(0)

N_SIDE, T_END, J, K = 64, 10.0, 1.0, 0.1
QUICK = "--quick" in sys.argv

SPIRIT_CONFIG = f"""
bravais_lattice sc
n_basis_cells {N_SIDE} {N_SIDE} 1
mu_s 1.0
hamiltonian heisenberg_neighbours
boundary_conditions 1 1 0
external_field_magnitude 0.0
external_field_normal 0.0 0.0 1.0
anisotropy_magnitude {K}
anisotropy_normal 0.0 0.0 1.0
n_shells_exchange 1
jij {J}
n_shells_dmi 0
ddi_method none
llg_damping 0.0
llg_temperature 0.0
llg_force_convergence 0.0
llg_output_any 0
log_output_any 0
log_to_console 0
log_to_file 0
"""


def start_spins() -> np.ndarray:
    """Spins tilted from +z by angles uniform in [0, 0.3] rad, azimuths uniform."""
    rng = np.random.default_rng(17)
    n = N_SIDE * N_SIDE
    theta = 0.3 * rng.random(n)
    phi = 2.0 * math.pi * rng.random(n)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)


def energy(spins: np.ndarray) -> float:
    """E = -J sum_<ij> S_i.S_j - K sum S_z^2 on the periodic square lattice, in double
    precision (Spirit's C API returns its energy as a float32)."""
    s = spins.reshape(N_SIDE, N_SIDE, 3)  # [y, x, component], site index x + N y
    bonds = np.sum(s * np.roll(s, -1, axis=1)) + np.sum(s * np.roll(s, -1, axis=0))
    return float(-J * bonds - K * np.sum(s[..., 2] ** 2))


def spirit_run(cfg: Path, start: np.ndarray, solver: int, dt: float) -> tuple[float, float, float]:
    """(E0, E(t_end), CPU seconds) of one Spirit LLG run."""
    with state.State(str(cfg), quiet=True) as p:
        from spirit.parameters import llg

        llg.set_timestep(p, dt)
        spins = system.get_spin_directions(p)
        spins[:] = start
        e0 = energy(np.array(spins))
        steps = int(round(T_END / dt))
        t = time.process_time()
        simulation.start(p, simulation.METHOD_LLG, solver, n_iterations=steps, n_iterations_log=steps)
        seconds = time.process_time() - t
        return e0, energy(np.array(system.get_spin_directions(p))), seconds


def liemid_run(scenario: Path, method: str, dt: float) -> tuple[float, float, float]:
    """(E0, E(t_end), stepping seconds) of one liemid run."""
    out = subprocess.run(
        [LIEMID, "spins", str(scenario), "--method", method, "--step", repr(dt), "--threads", "1", "--every", "1000000", "--json", "-"],
        check=True,
        capture_output=True,
        text=True,
    )
    s = json.loads(out.stdout)
    return s["energy"][0], s["energy"][1], s["seconds"]


def time_to(points: list[tuple[float, float]], level: float) -> float | None:
    """CPU time to reach `level` along (seconds, error) points, log-log interpolated."""
    pts = sorted(points)
    prev = None
    for sec, err in pts:
        if err <= level:
            if prev is None or prev[1] <= level or err <= 0.0:
                return sec
            a, b = math.log(prev[1]), math.log(err)
            f = (math.log(level) - a) / (b - a)
            return math.exp(math.log(prev[0]) + f * (math.log(sec) - math.log(prev[0])))
        prev = (sec, err)
    return None


def main() -> None:
    start = start_spins()
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        cfg = d / "spirit.cfg"
        cfg.write_text(SPIRIT_CONFIG)
        flat = np.ascontiguousarray(start, dtype="<f8")
        np.save(d / "start.npy", flat)
        scenario = d / "spins.toml"
        scenario.write_text(
            f'[lattice]\nkind = "square"\nsize = [{N_SIDE}, {N_SIDE}]\nperiodic = true\n'
            f"[hamiltonian]\nexchange = {J}\nanisotropy = {K}\nanisotropy_axis = [0.0, 0.0, 1.0]\n"
            f"[dynamics]\nt_end = {T_END}\n[initial]\nfile = \"start.npy\"\n"
        )
        steps = [1e-2, 3e-3, 1e-3] if QUICK else [2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4]
        results: dict[str, list[tuple[float, float]]] = {}
        e0_spirit = None
        for name, solver in [("Spirit SIB", simulation.SOLVER_SIB), ("Spirit Depondt", simulation.SOLVER_DEPONDT),
                             ("Spirit Heun", simulation.SOLVER_HEUN), ("Spirit RK4", simulation.SOLVER_RK4)]:
            for dt in steps:
                e0, e1, sec = spirit_run(cfg, start, solver, dt)
                e0_spirit = e0
                err = abs(e1 - e0) / abs(e0)
                results.setdefault(name, []).append((sec, err))
                print(f"{name:<16} dt {dt:8.1e} ps  energy error {err:9.2e}  {sec:7.3f} s", flush=True)
        e0_liemid = None
        for method in ["split", "split4", "split6", "rk4", "depondt", "heun"]:
            for dt in ([4e-2, 2e-2, 1e-2, 5e-3] if method.startswith("split") else steps):
                e0, e1, sec = liemid_run(scenario, method, dt)
                e0_liemid = e0
                err = abs(e1 - e0) / abs(e0)
                results.setdefault(f"liemid {method}", []).append((sec, err))
                print(f"liemid {method:<9} dt {dt:8.1e} ps  energy error {err:9.2e}  {sec:7.3f} s", flush=True)
        print(f"start energy: this script {e0_spirit:.12f} meV, liemid {e0_liemid:.12f} meV (the same Hamiltonian and start)")
        for level in (1e-6, 1e-8):
            spirit_best = min(((t, n) for n, p in results.items() if n.startswith("Spirit") for t in [time_to(p, level)] if t), default=None)
            liemid_best = min(((t, n) for n, p in results.items() if n.startswith("liemid") for t in [time_to(p, level)] if t), default=None)
            line = f"energy error {level:.0e}: "
            line += f"Spirit best {spirit_best[1]} {spirit_best[0]:.3f} s; " if spirit_best else "Spirit: not reached; "
            line += f"liemid best {liemid_best[1]} {liemid_best[0]:.3f} s" if liemid_best else "liemid: not reached"
            if spirit_best and liemid_best:
                line += f"; ratio {spirit_best[0] / liemid_best[0]:.1f}x"
            print(line)


if __name__ == "__main__":
    main()
