"""liemid spins against Spirit: CPU time to a given energy error and to a given trajectory
error, on a 64x64 periodic square ferromagnet (J = 1 meV, K = 0.1 meV along z, B = 0,
alpha = 0, mu_s = 1), 10 ps, the same start (spins within 0.3 rad of +z, from a fixed seed)
handed to both codes. One thread each (OMP_NUM_THREADS=1, liemid --threads 1).

Two error measures at t_end = 10 ps, both computed here from the final spins of each run,
in double precision, by the same code for both programs:

- energy error: |E(t_end) - E(0)| / |E(0)| (the conservation a symplectic or reversible method is good at);
- trajectory error: max over sites i of |S_i(t_end) - S_ref,i(t_end)| (Euclidean norm),
  what magnon spectra, correlation functions and switching times depend on. The reference
  is a fine-step run of the most accurate method of either code (liemid's eighth-order
  splitting), checked by step halving: its estimated error is printed and must lie far
  below the smallest level compared.

A fair Spirit: every parameter that matters goes through Spirit's config file, which Spirit
parses in double precision (`llg_dt`, `jij`, `anisotropy_magnitude`,
`external_field_magnitude`). The Python setter `spirit.parameters.llg.set_timestep` passes
a C float (ctypes.c_float): dt = 1e-3 ps becomes 1.00000005e-3 ps, a relative step error of
5e-8 that puts a floor of about 2e-6 under Spirit's RK4 trajectory error at 10 ps (the
phase runs 5e-8 x 10 ps x ~20 rad/ps ahead). Set through the config file, Spirit's RK4
error falls at fourth order to 1e-9 (printed below as the observed orders).

For each level 1e-4, 1e-6, 1e-8 and each measure: each code's best method and its CPU time
(log-log interpolation between steps) and the ratio; the work-precision figure goes to
docs/vs-spirit.png (two panels, one per measure). CPU times are process CPU times
(time.process_time around Spirit's `simulation.start`; getrusage of the child for liemid,
the whole process including its start-up and file I/O).

Installs nothing: needs numpy, the `spirit` package (pip install spirit) and a built liemid
(`cargo build --release -p liemid-cli`, or LIEMID=/path/to/liemid); skips with a message
when one is missing. matplotlib is optional (no figure without it).

    python benchmarks/vs_spirit.py [--quick] [--png PATH]
"""

from __future__ import annotations

import json
import math
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

try:
    import numpy as np
except ImportError:
    print("vs_spirit: numpy is not installed; skipping")
    sys.exit(0)
try:
    from spirit import simulation, state, system
except ImportError:
    print("vs_spirit: the spirit package is not installed (pip install spirit); skipping")
    sys.exit(0)

ROOT = Path(__file__).resolve().parent.parent
LIEMID = os.environ.get("LIEMID") or str(ROOT / "target" / "release" / "liemid")
if not (Path(LIEMID).exists() or shutil.which(LIEMID)):
    print(f"vs_spirit: no liemid binary at {LIEMID} (cargo build --release -p liemid-cli); skipping")
    sys.exit(0)

QUICK = "--quick" in sys.argv
PNG = Path(sys.argv[sys.argv.index("--png") + 1]) if "--png" in sys.argv else ROOT / "docs" / "vs-spirit.png"
T_END = 10.0
LEVELS = (1e-4, 1e-6, 1e-8)


@dataclass
class Hamiltonian:
    """One spin model as both codes read it: a square (or simple-cubic) lattice of
    `cells` sites, nearest-neighbour exchange `exchange` (meV, each pair once), uniaxial
    anisotropy `anisotropy` (meV) along `axis`, field `field` (T) along `field_axis`, moment
    `mu_s` (Bohr magnetons), Gilbert damping `damping`, and optionally a nearest-neighbour
    DMI `dmi` (meV) with Spirit's `dm_chirality` (+-1 Bloch, +-2 Neel)."""

    cells: tuple[int, int, int] = (64, 64, 1)
    periodic: tuple[int, int, int] = (1, 1, 0)
    exchange: float = 1.0
    anisotropy: float = 0.1
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    field: float = 0.0
    field_axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    mu_s: float = 1.0
    damping: float = 0.0
    dmi: float = 0.0
    dm_chirality: int = 2

    @property
    def sites(self) -> int:
        return self.cells[0] * self.cells[1] * self.cells[2]


def spirit_config(h: Hamiltonian, dt: float) -> str:
    """Spirit's input file for `h` and an LLG step `dt` (ps). Every number is written with
    repr(), and Spirit parses its config file in double precision, so the step and the
    couplings are exactly the doubles given (unlike `llg.set_timestep`, a C float)."""
    v = lambda xs: " ".join(repr(float(x)) for x in xs)  # noqa: E731
    dmi = f"n_shells_dmi 1\ndij {h.dmi!r}\ndm_chirality {h.dm_chirality}\n" if h.dmi else "n_shells_dmi 0\n"
    return (
        "bravais_lattice sc\n"
        f"n_basis_cells {h.cells[0]} {h.cells[1]} {h.cells[2]}\n"
        f"mu_s {h.mu_s!r}\n"
        "hamiltonian heisenberg_neighbours\n"
        f"boundary_conditions {h.periodic[0]} {h.periodic[1]} {h.periodic[2]}\n"
        f"external_field_magnitude {h.field!r}\n"
        f"external_field_normal {v(h.field_axis)}\n"
        f"anisotropy_magnitude {h.anisotropy!r}\n"
        f"anisotropy_normal {v(h.axis)}\n"
        f"n_shells_exchange 1\njij {h.exchange!r}\n"
        f"{dmi}"
        "ddi_method none\n"
        f"llg_dt {dt!r}\n"
        f"llg_damping {h.damping!r}\n"
        "llg_temperature 0.0\nllg_force_convergence 0.0\n"
        "llg_output_any 0\nlog_output_any 0\nlog_to_console 0\nlog_to_file 0\n"
    )


def liemid_dmi(h: Hamiltonian) -> tuple[float, str]:
    """liemid's (dmi, dmi_kind) for Spirit's (dij, dm_chirality): chirality 1 is liemid's
    bulk D r_ij, -2 its interfacial D z x r_ij (checked on one-bond energies); -1 and 2 are
    the same with -D."""
    kind = {1: "bulk", -1: "bulk", 2: "interfacial", -2: "interfacial"}[h.dm_chirality]
    sign = 1.0 if h.dm_chirality in (1, -2) else -1.0
    return sign * h.dmi, kind


def liemid_scenario(h: Hamiltonian, start_file: str, t_end: float | None = None, initial: str | None = None) -> str:
    """liemid's scenario file for `h` starting from the spins in `start_file` (.npy, shape
    (N, 3)), or from the `[initial]` table text `initial`."""
    kind = "square" if h.cells[2] == 1 else "cubic"
    size = list(h.cells[:2]) if kind == "square" else list(h.cells)
    periodic = "true" if all(h.periodic[: len(size)]) else "false"
    field = [h.field * c for c in h.field_axis]
    dmi = ""
    if h.dmi:
        d, dkind = liemid_dmi(h)
        dmi = f'dmi = {d!r}\ndmi_kind = "{dkind}"\n'
    init = initial if initial is not None else f'file = "{start_file}"\n'
    return (
        f'[lattice]\nkind = "{kind}"\nsize = {size}\nperiodic = {periodic}\n'
        f"[hamiltonian]\nexchange = {h.exchange!r}\nanisotropy = {h.anisotropy!r}\n"
        f"anisotropy_axis = [{', '.join(repr(float(c)) for c in h.axis)}]\n"
        f"field = [{', '.join(repr(float(c)) for c in field)}]\nmu_s = {h.mu_s!r}\n{dmi}"
        f"[dynamics]\nt_end = {(T_END if t_end is None else t_end)!r}\ndamping = {h.damping!r}\n[initial]\n{init}"
    )


def start_spins(n: int) -> np.ndarray:
    """Spins tilted from +z by angles uniform in [0, 0.3] rad, azimuths uniform."""
    rng = np.random.default_rng(17)
    theta = 0.3 * rng.random(n)
    phi = 2.0 * math.pi * rng.random(n)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)


def energy(h: Hamiltonian, spins: np.ndarray) -> float:
    """E = -J sum_<ij> S_i.S_j - sum_<ij> D_ij.(S_i x S_j) - K sum (S.n)^2 - mu_s mu_B B.sum S
    on the periodic square lattice, in double precision (Spirit's C API returns its energy
    as a float32)."""
    nx, ny = h.cells[0], h.cells[1]
    s = spins.reshape(ny, nx, 3)  # [y, x, component], site index x + nx y
    right, up = np.roll(s, -1, axis=1), np.roll(s, -1, axis=0)
    bonds = np.sum(s * right) + np.sum(s * up)
    n = np.array(h.axis) / np.linalg.norm(h.axis)
    b = h.field * np.array(h.field_axis)
    e = -h.exchange * bonds - h.anisotropy * np.sum((s @ n) ** 2) - h.mu_s * 0.057883817555 * np.sum(s @ b)
    if h.dmi:
        d, kind = liemid_dmi(h)
        for r, nb in (((1.0, 0.0, 0.0), right), ((0.0, 1.0, 0.0), up)):
            dv = d * (np.array(r) if kind == "bulk" else np.cross((0.0, 0.0, 1.0), r))
            e -= float(np.sum(np.cross(s, nb) @ dv))
    return float(e)


def trajectory_error(a: np.ndarray, b: np.ndarray) -> float:
    """max_i |a_i - b_i| (Euclidean norm per site)."""
    return float(np.max(np.linalg.norm(a - b, axis=1)))


def spirit_run(h: Hamiltonian, work: Path, start: np.ndarray, solver: int, dt: float) -> tuple[np.ndarray, float]:
    """(final spins, CPU seconds) of one Spirit LLG run to T_END."""
    cfg = work / "spirit.cfg"
    cfg.write_text(spirit_config(h, dt))
    with state.State(str(cfg), quiet=True) as p:
        spins = system.get_spin_directions(p)  # a view of Spirit's (double) spins
        spins[:] = start
        steps = int(round(T_END / dt))
        t = time.process_time()
        simulation.start(p, simulation.METHOD_LLG, solver, n_iterations=steps, n_iterations_log=steps)
        seconds = time.process_time() - t
        return np.array(system.get_spin_directions(p)), seconds


def child_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def liemid_run(scenario: Path, method: str, dt: float, extra: tuple[str, ...] = ()) -> tuple[np.ndarray, float]:
    """(final spins, CPU seconds of the whole process) of one liemid run to T_END."""
    final = scenario.parent / "final.npy"
    before = child_cpu()
    subprocess.run(
        [LIEMID, "spins", str(scenario), "--method", method, "--step", repr(dt), "--threads", "1",
         "--every", "100000000", "--final", str(final), "--json", str(scenario.parent / "run.json"), *extra],
        check=True,
        capture_output=True,
        text=True,
    )
    seconds = child_cpu() - before
    return np.load(final), seconds


def time_to(points: list[tuple[float, float]], level: float) -> float | None:
    """CPU time to reach `level` along (seconds, error) points, log-log interpolated."""
    prev = None
    for sec, err in sorted(points):
        if err <= level:
            if prev is None or prev[1] <= level or err <= 0.0:
                return sec
            a, b = math.log(prev[1]), math.log(err)
            f = (math.log(level) - a) / (b - a)
            return math.exp(math.log(prev[0]) + f * (math.log(sec) - math.log(prev[0])))
        prev = (sec, err)
    return None


def observed_orders(rows: list[tuple[float, float]]) -> list[float]:
    """log2 of successive error ratios along (dt, error) rows of halving steps."""
    return [math.log(e0 / e1) / math.log(d0 / d1) for (d0, e0), (d1, e1) in zip(rows, rows[1:]) if e1 > 0.0]


def main() -> None:
    h = Hamiltonian()
    start = start_spins(h.sites)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        np.save(work / "start.npy", np.ascontiguousarray(start, dtype="<f8"))
        scenario = work / "spins.toml"
        scenario.write_text(liemid_scenario(h, "start.npy"))
        e0 = energy(h, start)

        # The reference: liemid's split8 at a small step, and at twice that step.
        ref_dt = 2.5e-3
        reference, _ = liemid_run(scenario, "split8", ref_dt)
        coarse, _ = liemid_run(scenario, "split8", 2 * ref_dt)
        ref_err = trajectory_error(reference, coarse)
        print(f"reference: liemid split8 at dt {ref_dt} ps; against dt {2 * ref_dt} ps it differs by {ref_err:.1e} "
              f"(its own error is smaller still: order 8)")
        if ref_err > 1e-10:
            print("vs_spirit: the reference is not accurate enough for the 1e-8 level; stopping")
            sys.exit(1)

        _, overhead = liemid_run(scenario, "split", 0.04, ("--t-end", "0.04"))
        print(f"liemid process overhead (start, read, one step, write): {overhead:.3f} s CPU, included in its times")

        results: dict[str, list[tuple[float, float, float, float]]] = {}  # name -> (dt, s, energy, trajectory)

        def record(name: str, dt: float, final: np.ndarray, sec: float) -> None:
            de = abs(energy(h, final) - e0) / abs(e0)
            dx = trajectory_error(final, reference)
            results.setdefault(name, []).append((dt, sec, de, dx))
            print(f"{name:<16} dt {dt:9.3e} ps  energy error {de:9.2e}  trajectory error {dx:9.2e}  {sec:7.3f} s",
                  flush=True)

        second = [2e-2, 1e-2, 5e-3, 2.5e-3, 1.25e-3] if QUICK else [2e-2, 1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4]
        fourth = [2e-2, 1e-2, 5e-3, 2.5e-3] if QUICK else [2e-2, 1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4, 3.125e-4]
        for name, solver, steps in [("Spirit SIB", simulation.SOLVER_SIB, second),
                                    ("Spirit Depondt", simulation.SOLVER_DEPONDT, second),
                                    ("Spirit Heun", simulation.SOLVER_HEUN, second),
                                    ("Spirit RK4", simulation.SOLVER_RK4, fourth)]:
            for dt in steps:
                final, sec = spirit_run(h, work, start, solver, dt)
                record(name, dt, final, sec)
        # Each method along its own work-precision curve: the compositions are cheapest at
        # large steps (every step divides 10 ps).
        liemid_steps = {
            "split": [1e-1, 8e-2, 6.25e-2, 5e-2, 4e-2, 2e-2, 1e-2, 5e-3, 2.5e-3],
            "split4": [1.25e-1, 1e-1, 8e-2, 6.25e-2, 5e-2, 4e-2, 2.5e-2, 2e-2],
            "split6": [2e-1, 1.25e-1, 1e-1, 8e-2, 6.25e-2, 5e-2, 4e-2],
            "split8": [3.125e-1, 2.5e-1, 2e-1, 1.25e-1, 1e-1, 8e-2],
            "rk4": [2e-2, 1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4],
            "depondt": [2e-2, 1e-2, 5e-3, 2.5e-3, 1.25e-3],
            "heun": [2e-2, 1e-2, 5e-3, 2.5e-3, 1.25e-3],
        }
        for method, steps in liemid_steps.items():
            for dt in steps[:3] if QUICK else steps:
                final, sec = liemid_run(scenario, method, dt)
                record(f"liemid {method}", dt, final, sec)

        rk4 = [(dt, dx) for dt, _, _, dx in results["Spirit RK4"]]
        print("Spirit RK4 trajectory error, observed orders between halved steps: "
              + ", ".join(f"{p:.2f}" for p in observed_orders(rk4)) + f"; smallest error {min(e for _, e in rk4):.1e}")

        summary = []
        for measure, col in [("energy", 2), ("trajectory", 3)]:
            for level in LEVELS:
                best = {}
                for code in ("Spirit", "liemid"):
                    cands = [(t, n) for n, rows in results.items() if n.startswith(code)
                             for t in [time_to([(r[1], r[col]) for r in rows], level)] if t is not None]
                    best[code] = min(cands) if cands else None
                line = f"{measure} error {level:.0e}: "
                for code in ("Spirit", "liemid"):
                    b = best[code]
                    line += f"{code} best {b[1].split(' ', 1)[1]} {b[0]:.3f} s; " if b else f"{code}: not reached; "
                ratio = best["Spirit"][0] / best["liemid"][0] if best["Spirit"] and best["liemid"] else None
                line += f"ratio {ratio:.1f}x" if ratio else "ratio -"
                summary.append(line)
                print(line)
        plot(results, "vs_spirit", PNG, 6,
             f"64x64 ferromagnet, J = 1 meV, K = 0.1 meV, 10 ps: liemid (solid) vs Spirit (dashed); "
             f"reference split8, error {ref_err:.0e}")


def plot(results: dict[str, list[tuple[float, float, float, float]]], script: str, png: Path, ncol: int,
         suptitle: str) -> None:
    """The two-panel work-precision figure (energy error, trajectory error against CPU time) of
    a Spirit comparison, written to `png`."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print(f"{script}: matplotlib is not installed; no figure")
        return
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.6), layout="constrained")
    for ax, col, title in [(axes[0], 2, "relative energy error at 10 ps"),
                           (axes[1], 3, "trajectory error max_i |S_i - S_ref,i| at 10 ps")]:
        for name, rows in results.items():
            rows = sorted(rows, key=lambda r: r[1])
            spirit = name.startswith("Spirit")
            ax.loglog([r[1] for r in rows], [max(r[col], 1e-16) for r in rows], "--o" if spirit else "-s",
                      label=name, markersize=4, alpha=0.85 if spirit else 1.0)
        for level in LEVELS:
            ax.axhline(level, color="0.8", lw=0.8, zorder=0)
        ax.set_xlabel("CPU seconds (one thread)")
        ax.set_ylabel(title)
        ax.set_title(title)
        ax.grid(True, which="major", alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=ncol, fontsize=8)
    fig.suptitle(suptitle)
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=110)
    print(f"figure: {png}")


if __name__ == "__main__":
    main()
