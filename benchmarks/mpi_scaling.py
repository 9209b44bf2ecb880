#!/usr/bin/env python3
"""Strong scaling of the dipolar fluid over MPI (issue 44) and its communication model.

Runs `mpirun -n R liemid many --model dipoles --threads 1` for R = 1 and 2 (or --ranks),
reads each run's JSON summary and prints body-steps per second, the speed-up, and the
ghosts and bytes each rank sends per step against the model of slabs:

    L = (N / rho)^(1/3),  reach = r_c + skin,
    ghosts per rank  G = 2 rho L^2 reach          (R >= 2: a layer of the reach on each face)
    bytes per rank per step  B = 48 G             (position and dipole, 6 doubles)
    messages per rank per step  1 (R = 2) or 2 (R >= 3), plus one 16-byte reduction
    per list build: migration (27 doubles per body that changed slab) + 32 G (identity
    and position of each ghost)

and the same model on paper at 64 and 1024 ranks. Needs the release binary built with
the feature (`cargo build --release -p liemid-cli --features mpi`; LIEMID_BIN or
target/release/liemid) and `mpirun` (Open MPI); skips with a message otherwise.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from liemid_binary import find_liemid  # noqa: E402


def model(n, rho, cutoff, skin, ranks):
    box = (n / rho) ** (1.0 / 3.0)
    reach = cutoff + skin
    ghosts = 0.0 if ranks == 1 else 2.0 * rho * box * box * reach
    messages = 0 if ranks == 1 else (1 if ranks == 2 else 2)
    return box, ghosts, 48.0 * ghosts, messages


def run(binary, ranks, n, steps, rho, out):
    path = os.path.join(out, f"r{ranks}.json")
    cmd = ["mpirun", "--oversubscribe"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    cmd += ["-n", str(ranks), binary,
            "many", "--model", "dipoles", "--bodies", str(n), "--density", str(rho), "--step", "1e-3",
            "--t-end", str(steps * 1e-3), "--threads", "1", "--json", path]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(path) as f:
        return json.load(f)


def side_by_side(binary, n, steps, rho, out):
    """The summed body-steps/s of two independent 1-rank runs at once: what the machine's two
    cores give this work with nothing shared (the ceiling of a 2-rank speed-up here, now)."""
    procs, paths = [], []
    for k in range(2):
        path = os.path.join(out, f"side{k}.json")
        cmd = ["mpirun", "--oversubscribe"] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
        cmd += ["-n", "1", "--bind-to", "none", binary, "many", "--model", "dipoles", "--bodies", str(n),
                "--density", str(rho), "--step", "1e-3", "--t-end", str(steps * 1e-3), "--threads", "1",
                "--json", path]
        procs.append(subprocess.Popen(cmd, stdout=subprocess.DEVNULL))
        paths.append(path)
    for p in procs:
        p.wait()
    total = 0.0
    for path in paths:
        with open(path) as f:
            total += json.load(f)["body_steps_per_second"]
    return total


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bodies", type=int, default=100_000)
    p.add_argument("--steps", type=int, default=100)
    p.add_argument("--density", type=float, default=0.3)
    p.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    p.add_argument("--rounds", type=int, default=3, help="alternating rounds; the best of each is kept")
    a = p.parse_args()
    binary = find_liemid()
    if binary is None or shutil.which("mpirun") is None:
        print("skipped: needs the release liemid built with --features mpi and mpirun")
        return
    with tempfile.TemporaryDirectory() as out:
        best = {}
        ceiling = 0.0
        for _ in range(a.rounds):
            for r in a.ranks:
                d = run(binary, r, a.bodies, a.steps, a.density, out)
                if r not in best or d["body_steps_per_second"] > best[r]["body_steps_per_second"]:
                    best[r] = d
            ceiling = max(ceiling, side_by_side(binary, a.bodies, a.steps, a.density, out))
    base = best[a.ranks[0]]["body_steps_per_second"]
    print(f"dipolar fluid, N = {a.bodies}, density {a.density}, {a.steps} steps, 1 thread per rank, "
          f"best of {a.rounds} alternating rounds")
    print("ranks  body-steps/s  speed-up  ghosts/rank (model)  bytes/rank/step (model)  msgs/rank/step (model)  builds")
    for r in a.ranks:
        d = best[r]
        box, g, b, m = model(a.bodies, a.density, d["cutoff"], d["skin"], r)
        print(f"{r:5d}  {d['body_steps_per_second']:12.4e}  {d['body_steps_per_second'] / base:8.2f}  "
              f"{d['ghosts_per_rank_last_build']:9.0f} ({g:8.0f})  {d['ghost_bytes_per_rank_per_step']:11.0f} "
              f"({b:9.0f})  {d['ghost_messages_per_rank_per_step']:7.2f} ({m})  {d['list_builds']}")
    print(f"two independent 1-rank runs side by side: {ceiling:.4e} body-steps/s in all, "
          f"{ceiling / base:.2f}x one run (this machine's ceiling for 2 ranks in this run)")
    d = best[a.ranks[-1]]
    print("\non paper (slabs need L/R >= reach; beyond, a 3-D grid of R = P^3 domains of side L/P has ghosts "
          "((L/P + 2 reach)^3 - (L/P)^3) rho):")
    for n in (10**6, 10**8):
        for r in (64, 1024):
            box = (n / a.density) ** (1 / 3)
            reach = d["cutoff"] + d["skin"]
            p3 = round(r ** (1 / 3))
            side = box / p3
            owned = n / r
            if p3 ** 3 == r and side >= reach:
                g = ((side + 2 * reach) ** 3 - side ** 3) * a.density
                print(f"  N = {n:.0e}, R = {r:5d} ({p3}^3 grid, side {side:.1f}): {owned:.0f} owned, {g:.0f} ghosts "
                      f"per rank ({g / owned:.2f} per owned), {48 * g:.3e} bytes and 6 messages (26 with edges and "
                      f"corners sent directly) per rank per step")
            else:
                slabs = box / r
                print(f"  N = {n:.0e}, R = {r:5d}: slabs {slabs:.2f} thin (reach {reach}); a {p3}^3 grid has side "
                      f"{side:.2f}: {'too thin' if side < reach else 'possible'}")


if __name__ == "__main__":
    main()
