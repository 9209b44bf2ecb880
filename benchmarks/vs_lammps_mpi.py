#!/usr/bin/env python3
"""liemid over MPI against LAMMPS over MPI on the dipolar fluid of vs_lammps.py (issue 44).

The same system as vs_lammps.py: N = side^3 spheres (mass 1, diameter 1) at density 0.3 on
a simple cubic lattice, unit point dipoles with WCA (sigma = epsilon = 1), dipole cutoff 3,
skin 0.3, h = 1e-3, Allen and Germano's shifted force on both sides (LAMMPS `pair_style
lj/sf/dipole/sf`, `fix nve/sphere update dipole/dlm`; liemid `--cutoff-form
shifted-force`). Each code runs under `mpirun -n R` with one thread per rank (R = 1, 2):
LAMMPS's own domain decomposition (Debian's `lammps` package, the `lmp` binary built with
Open MPI), liemid's slabs (`--features mpi`). Prints body-steps per second, per core, and
each code's speed-up from 1 to 2 ranks, alternating the codes, best of --rounds.

Installs nothing; skips when `lmp`, `mpirun` or the release liemid built with the feature
(LIEMID_BIN or target/release/liemid) is missing.
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from liemid_binary import find_liemid  # noqa: E402

LAMMPS_INPUT = """
units lj
atom_style hybrid sphere dipole
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
timestep 0.001
thermo {steps}
run 0
run {steps} pre no post no
"""


def mpirun(ranks):
    cmd = ["mpirun", "--oversubscribe"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    return cmd + ["-n", str(ranks)]


def lammps(lmp, ranks, side, steps, tmp):
    path = os.path.join(tmp, "in.dipoles")
    with open(path, "w") as f:
        f.write(LAMMPS_INPUT.format(side=side, steps=steps))
    env = dict(os.environ, OMP_NUM_THREADS="1")
    out = subprocess.run(mpirun(ranks) + [lmp, "-in", path, "-log", "none"], check=True,
                         capture_output=True, text=True, env=env).stdout
    # "Loop time of T on R procs for S steps with N atoms" (the last: the timed run).
    t, procs, s, n = re.findall(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms",
                                out)[-1]
    return int(n) * int(s) / float(t)


def liemid(binary, ranks, side, steps, tmp):
    path = os.path.join(tmp, f"liemid{ranks}.json")
    subprocess.run(mpirun(ranks) + [binary, "many", "--model", "dipoles", "--bodies", str(side ** 3),
                                    "--cutoff-form", "shifted-force", "--step", "1e-3",
                                    "--t-end", str(steps * 1e-3), "--threads", "1", "--json", path],
                   check=True, stdout=subprocess.DEVNULL)
    with open(path) as f:
        return json.load(f)["body_steps_per_second"]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--side", type=int, default=46, help="lattice side (N = side^3; 46: 97,336)")
    p.add_argument("--steps", type=int, default=100)
    p.add_argument("--rounds", type=int, default=2)
    a = p.parse_args()
    binary, lmp = find_liemid(), shutil.which("lmp") or shutil.which("lmp_openmpi")
    if binary is None or lmp is None or shutil.which("mpirun") is None:
        print("skipped: needs lmp (Debian's lammps), mpirun and the release liemid built with --features mpi")
        return
    best = {}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(a.rounds):
            for ranks in (1, 2):
                for code, f in (("liemid", liemid), ("lammps", lammps)):
                    v = f(binary if code == "liemid" else lmp, ranks, a.side, a.steps, tmp)
                    best[(code, ranks)] = max(best.get((code, ranks), 0.0), v)
    print(f"dipolar fluid, N = {a.side ** 3}, {a.steps} steps, shifted force, 1 thread per rank, "
          f"best of {a.rounds} alternating rounds; LAMMPS: {lmp}")
    print("code     ranks  body-steps/s  per core     speed-up")
    for code in ("liemid", "lammps"):
        for ranks in (1, 2):
            v = best[(code, ranks)]
            print(f"{code:8s} {ranks:5d}  {v:12.4e}  {v / ranks:10.4e}  {v / best[(code, 1)]:8.2f}")
    for ranks in (1, 2):
        print(f"liemid / LAMMPS at {ranks} rank(s): {best[('liemid', ranks)] / best[('lammps', ranks)]:.2f}x")


if __name__ == "__main__":
    main()
