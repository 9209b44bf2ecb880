#!/usr/bin/env python3
"""chain-10's energy over long runs: liemid (time-reversible RATTLE with EA's rotation) against
MuJoCo 4.0's RK4 at equal CPU, and the issue's "tenths" criterion.

Model: benchmarks/models/chain_10.xml (written by vs_mujoco.py from liemid's built-in
`chain-10`: ten slender links on ball joints, released from rest), read by both codes.
Energy: liemid's trajectory column (kinetic + potential, every step of the CLI's loop);
MuJoCo's `mj_energyPos + mj_energyVel` after `mj_forward`.

1. Cost and the equal-CPU step. liemid's CPU per step is the CLI child's
   (`getrusage(RUSAGE_CHILDREN)`) over the long run less the same command for one step,
   and includes the CLI's per-step energy and momentum readouts and the trajectory rows;
   MuJoCo's RK4 is stepped in C (`mj_step(m, d, nstep=k)`, k = 1/2000 of the run) and
   timed by `time.process_time` around those calls only; the energy readout between
   chunks is not counted. RK4's step is then `h_RK4 = h * cpu_RK4 / cpu_liemid` per step.
   One RK4 step from Python (`mj_step` called per step) is printed too.
2. Long run: liemid at H (default 1e-3: the CLI's step when a file gives none, and where
   liemid's energy error is 1e-4, the size a user accepts for a pendulum chain) for
   STEPS (default 10^6) steps, and RK4 at the equal-CPU step over the same time. RK4's
   trend: a least-squares line dE/E = a + b t over the run. RK4's drift rate against h:
   the same line fitted to RK4 runs at several steps over the same time, and a power
   law |b| = C h^p through them.
3. The tenths criterion (largest |dE/E| in the last tenth of a run no larger than 1.2x
   that in the first): the issue's run (10^5 steps at h = 1e-3 from rest), the same run
   at h/2 (a modified energy h^2 H2(y) makes error/h^2 the same function of the state),
   the tenths of the long run, and 10^5 steps from a start already in the chaotic motion
   (the state after 100 s of RK4 at h = 1e-4, written into the model's keyframe).

Run:  python benchmarks/vs_mujoco_energy.py [--quick]     (LIEMID_BIN to point at the binary)
Writes docs/vs-mujoco-energy.txt and docs/multibody-energy.png (--quick: a short run, the figure to
the temporary directory, no text file).
Peers: pip install mujoco==4.0.0 numpy matplotlib (in a venv of your own).
"""

from __future__ import annotations

import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / "benchmarks" / "models" / "chain_10.xml"
DOCS = ROOT / "docs"
QUICK = "--quick" in sys.argv

try:
    import numpy as np
    import mujoco
except ImportError as e:  # pragma: no cover - the skip path
    print(f"vs_mujoco_energy: skipped, a peer is missing ({e}); pip install mujoco==4.0.0 numpy matplotlib")
    sys.exit(0)


sys.path.insert(0, str(Path(__file__).resolve().parent))
from liemid_binary import require_liemid  # noqa: E402

LIEMID = require_liemid("vs_mujoco_energy")

OUT_LINES: list[str] = []


def say(line=""):
    print(line, flush=True)
    OUT_LINES.append(line)


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def liemid_energy(model, h, t_end, every):
    """One CLI run (`model` a file, or ":name" for a built-in problem), the energy every
    `every` steps; returns (t, relative energy error, child CPU s, summary)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run.npy"
        model = str(model)
        cmd = [LIEMID, "multibody", *(["--problem", model[1:]] if model.startswith(":") else [model]),
               "--step", repr(h), "--t-end", repr(t_end), "--every", str(every), "--out", str(out), "--json", "-"]
        c0 = child_cpu()
        r = subprocess.run(cmd, capture_output=True, text=True)
        cpu = child_cpu() - c0
        if r.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)}: {r.stderr.strip()}")
        rows = np.array(np.load(out, mmap_mode="r")[:, :2])
    e = rows[:, 1]
    js = json.loads(r.stdout)
    js["initial_energy"] = float(e[0])
    return rows[:, 0], (e - e[0]) / abs(e[0]), cpu, js


def liemid_startup(model):
    """CPU of the same command for one step (start-up and model reading), least of three."""
    return min(liemid_energy(model, 1e-3, 1e-3, 1)[2] for _ in range(3))


def mj_energy(m, d):
    mujoco.mj_energyPos(m, d)
    mujoco.mj_energyVel(m, d)
    return float(d.energy[0] + d.energy[1])


def mj_model(path, h):
    m = mujoco.MjModel.from_xml_path(str(path))
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    m.opt.timestep = h
    return m


def mj_start(m):
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    return d


def rk4_energy(path, h, t_end, points=20000):
    """MuJoCo RK4 at step h to t_end; returns (t, dE/E, CPU s of the stepping alone)."""
    m = mj_model(path, h)
    d = mj_start(m)
    e0 = mj_energy(m, d)
    n = int(round(t_end / h))
    chunk = max(n // points, 1)
    ts, es, cpu, done = [0.0], [0.0], 0.0, 0
    while done < n:
        k = min(chunk, n - done)
        c0 = time.process_time()
        mujoco.mj_step(m, d, nstep=k)
        cpu += time.process_time() - c0
        done += k
        mujoco.mj_forward(m, d)
        ts.append(d.time)
        es.append((mj_energy(m, d) - e0) / abs(e0))
    return np.array(ts), np.array(es), cpu


def rk4_cost(path, h, n_probe):
    """CPU per RK4 step: stepped in C (nstep), and one mj_step call per step from Python."""
    m = mj_model(path, h)
    d = mj_start(m)
    c0 = time.process_time()
    mujoco.mj_step(m, d, nstep=n_probe)
    in_c = (time.process_time() - c0) / n_probe
    d = mj_start(m)
    c0 = time.process_time()
    for _ in range(n_probe // 4):
        mujoco.mj_step(m, d)
    from_py = (time.process_time() - c0) / (n_probe // 4)
    return in_c, from_py


def trend(t, r):
    """Least-squares line r = a + b t; returns (a, b, the fraction of r's variance it explains)."""
    A = np.vstack([np.ones_like(t), t]).T
    (a, b), *_ = np.linalg.lstsq(A, r, rcond=None)
    resid = r - (a + b * t)
    return a, b, 1.0 - np.var(resid) / np.var(r)


def tenths(r):
    n = len(r)
    return [float(np.max(np.abs(r[k * n // 10:(k + 1) * n // 10]))) for k in range(10)]


def say_means(label, r):
    n = len(r)
    say(f"  {label}: mean dE/E per tenth " + " ".join(f"{np.mean(r[k * n // 10:(k + 1) * n // 10]):.2e}" for k in range(10)))


def say_tenths(label, r):
    tt = tenths(r)
    say(f"  {label}: max |dE/E| per tenth " + " ".join(f"{x:.2e}" for x in tt)
        + f"; last / first = {tt[-1] / tt[0]:.2f}")
    return tt


def chaotic_start(tmp, t_transient, h=1e-4):
    """chain-10's MJCF with its keyframe replaced by the state after t_transient of RK4 at h."""
    m = mj_model(MODEL, h)
    d = mj_start(m)
    mujoco.mj_step(m, d, nstep=int(round(t_transient / h)))
    mujoco.mj_forward(m, d)
    text = MODEL.read_text()
    key = f'<key qpos="{" ".join(repr(float(x)) for x in d.qpos)}" qvel="{" ".join(repr(float(x)) for x in d.qvel)}"/>'
    text, k = re.subn(r"<key [^>]*/>", key, text)
    assert k == 1
    p = Path(tmp) / "chain_10_chaotic.xml"
    p.write_text(text)
    return p, mj_energy(m, d)


def long_run(H, steps, base):
    """liemid at H for `steps` steps and MuJoCo RK4 at the step of equal CPU, same time."""
    T = steps * H
    say(f"\n1. Long run: liemid at h = {H:g}, {steps} steps (t = {T:g} s); MuJoCo RK4 at equal CPU")
    tl, rl, cpu_l, _ = liemid_energy(MODEL, H, T, max(steps // 20000, 1))
    per_l = (cpu_l - base) / steps
    per_c, per_py = rk4_cost(MODEL, H, 2000 if QUICK else 100000)
    h_eq = H * per_c / per_l
    say(f"  CPU per step: liemid {per_l * 1e6:.2f} us at h = {H:g} (CLI, with its per-step energy and momenta;"
        f" start-up {base:.3f} s removed); MuJoCo RK4 {per_c * 1e6:.2f} us stepped in C (nstep),"
        f" {per_py * 1e6:.2f} us called per step from Python")
    say(f"  equal CPU: RK4 at h = {h_eq:.3e} ({h_eq / H:.2f} x liemid's step)")
    t4, r4, cpu_4 = rk4_energy(MODEL, h_eq, T)
    a4, b4, fit4 = trend(t4, r4)
    al, bl, fitl = trend(tl, rl)
    say(f"  liemid h = {H:g}: CPU {cpu_l:.1f} s, max |dE/E| {np.max(np.abs(rl)):.3e}, final dE/E {rl[-1]:.3e};"
        f" line fit dE/E = {al:.2e} + {bl:.2e} t (explains {fitl:.2f} of the variance)")
    say(f"  MuJoCo RK4 h = {h_eq:.3e}: CPU {cpu_4:.1f} s, max |dE/E| {np.max(np.abs(r4)):.3e},"
        f" final dE/E {r4[-1]:.3e}; line fit dE/E = {a4:.2e} + {b4:.2e} t (explains {fit4:.2f} of the variance)")
    say_tenths(f"liemid h = {H:g}", rl)
    say_tenths(f"RK4 h = {h_eq:.2e}", r4)
    say_means(f"liemid h = {H:g}", rl)
    say_means(f"RK4 h = {h_eq:.2e}", r4)
    return dict(H=H, T=T, steps=steps, tl=tl, rl=rl, cpu_l=cpu_l, h_eq=h_eq, t4=t4, r4=r4,
                cpu_4=cpu_4, fit=(a4, b4, fit4))


def rk4_rates(H, T, known):
    """RK4's drift rate (slope of the line fit) at several steps over T, and a power law
    through the steps where the line explains at least half of the variance (a trend)."""
    rates = dict(known)
    for hh in (0.5 * H, 0.7 * H, H, 1.4 * H, 2 * H, 2.8 * H, 4 * H):
        if hh not in rates:
            t, r, _ = rk4_energy(MODEL, hh, T, points=2000)
            a, b, fit = trend(t, r)
            rates[hh] = (b, fit)
            say(f"  MuJoCo RK4 h = {hh:.3e}: max |dE/E| {np.max(np.abs(r)):.3e}, final {r[-1]:.3e}; "
                f"line {a:.2e} + {b:.2e} t (explains {fit:.2f})")
    hh = np.array(sorted(rates))
    bb = np.array([abs(rates[x][0]) for x in hh])
    trending = np.array([rates[x][1] >= 0.5 for x in hh])
    p, lc = np.polyfit(np.log(hh[trending]), np.log(bb[trending]), 1)
    C = float(np.exp(lc))
    say(f"  RK4 drift rate |b| against h (t = {T:g} s), fitted where the line explains >= 0.5:"
        f" |b| = {C:.3g} h^{p:.2f} per s; points (h: |b|, explained): "
        + ", ".join(f"{x:.2e}: {y:.2e}, {rates[x][1]:.2f}" for x, y in zip(hh, bb)))
    h_old, t_old = 3.172e-4, 100.0
    say(f"  the earlier study's setting (liemid h = 1e-4 at 12.4 us per step, RK4 at equal CPU h = {h_old:.3e},"
        f" t = {t_old:g}): the law extrapolated gives {C * h_old ** p * t_old:.1e} over that run; measured there:"
        f" RK4's |dE/E| at most 2.6e-7, final -1.6e-8 (docs/vs-mujoco.txt before this script)")
    return hh, bb, trending, C, p, h_old


def main():
    if not MODEL.is_file():
        print(f"vs_mujoco_energy: skipped, {MODEL} missing (python benchmarks/vs_mujoco.py writes it)")
        return
    DOCS.mkdir(exist_ok=True)
    steps = int(os.environ.get("VS_MUJOCO_ENERGY_STEPS", 10**4 if QUICK else 10**6))
    say(f"vs_mujoco_energy.py: liemid ({LIEMID}) against MuJoCo {mujoco.__version__} RK4, numpy {np.__version__}")
    say("CPU times are process times on a shared 2-core machine under load (other builds beside).")
    say(f"Model {MODEL.relative_to(ROOT)} (chain-10: ten ball joints, released from rest).")

    # 1. long runs at equal CPU ------------------------------------------------------------
    base = liemid_startup(MODEL)
    runs = [long_run(H, steps, base) for H in (1e-3, 2e-3)]
    r1 = runs[0]
    # the larger step twice as long again: does liemid's mean error keep its trend?
    H2 = runs[1]["H"]
    t2, r2, _, _ = liemid_energy(MODEL, H2, 2 * steps * H2, max(steps // 10000, 1))
    a2, b2, fit2 = trend(t2, r2)
    say(f"\n  liemid h = {H2:g}, {2 * steps} steps (t = {2 * steps * H2:g} s): max |dE/E| {np.max(np.abs(r2)):.3e};"
        f" line fit dE/E = {a2:.2e} + {b2:.2e} t (explains {fit2:.2f} of the variance)")
    say_tenths(f"liemid h = {H2:g}, t = {2 * steps * H2:g} s", r2)
    say_means(f"liemid h = {H2:g}, t = {2 * steps * H2:g} s", r2)
    # RK4 at liemid's own step and RK4's drift rate against its step, over the first run's time
    H, T = r1["H"], r1["T"]
    t41, r41, cpu_41 = rk4_energy(MODEL, H, T)
    a41, b41, fit41 = trend(t41, r41)
    say(f"\n  MuJoCo RK4 at liemid's step h = {H:g} to t = {T:g}: CPU {cpu_41:.1f} s, max |dE/E|"
        f" {np.max(np.abs(r41)):.3e}, final {r41[-1]:.3e}; line {a41:.2e} + {b41:.2e} t (explains {fit41:.2f})")
    hh, bb, trending, C, p, h_old = rk4_rates(H, T, {H: (b41, fit41), r1["h_eq"]: r1["fit"][1:]})

    # 2. tenths -------------------------------------------------------------------------------
    h1, n1 = 1e-3, (10**4 if QUICK else 10**5)
    say(f"\n2. The tenths criterion on chain-10: {n1} steps at h = {h1:g} (t = {n1 * h1:g} s)")
    say("  (energy every step; from rest: the built-in --problem chain-10, as the issue's run;"
        " the MJCF file's inertia, printed to 17 digits, starts a different chaotic trajectory)")
    _ta, ra, _, _ = liemid_energy(":chain-10", h1, n1 * h1, 1)
    _tb, rb, _, _ = liemid_energy(":chain-10", h1 / 2, n1 * h1, 1)
    A = say_tenths(f"from rest, h = {h1:g}", ra)
    B = say_tenths(f"from rest, h = {h1 / 2:g} (same t)", rb)
    _tf, rf, _, _ = liemid_energy(MODEL, h1, n1 * h1, 1)
    say_tenths(f"from rest, the MJCF file, h = {h1:g}", rf)
    say("  per tenth, (max at h) / (max at h/2): " + " ".join(f"{x / y:.2f}" for x, y in zip(A, B))
        + " (4 for an O(h^2) modified energy)")
    say_tenths(f"the long run above, h = {H:g}, t = {T:g} s", r1["rl"])
    say_tenths(f"the long run after its first tenth (t = {T / 10:g} .. {T:g} s)", r1["rl"][len(r1["rl"]) // 10:])
    with tempfile.TemporaryDirectory() as tmp:
        t_tr = 20.0 if QUICK else 100.0
        pc, ec = chaotic_start(tmp, t_tr)
        say(f"  chaotic start: the state after {t_tr:g} s of RK4 at h = 1e-4 (energy {ec:.12g} J"
            f" in MuJoCo) as the keyframe")
        tc, rc, _, jc = liemid_energy(pc, h1, n1 * h1, 1)
        td, rd, _, _ = liemid_energy(pc, h1 / 2, n1 * h1, 1)
        say(f"  liemid's energy of that start {jc['initial_energy']!r} J (the same state in both codes)")
        C1 = say_tenths(f"chaotic start, h = {h1:g}", rc)
        C2 = say_tenths(f"chaotic start, h = {h1 / 2:g}", rd)
        say("  per tenth, (max at h) / (max at h/2): " + " ".join(f"{x / y:.2f}" for x, y in zip(C1, C2)))
        _t, rc10, _, _ = liemid_energy(pc, h1, 10 * n1 * h1, 10)
        say_tenths(f"chaotic start, h = {h1:g}, {10 * n1} steps (every 10th step)", rc10)
        say(f"  the same start to t = {10 * n1 * h1:g} s at three steps: mean dE/E / h^2 per tenth, and the"
            " line fit's slope / h^2 (a drift from round-off or the solves' tolerances would not scale as h^2)")
        for hs, ev in ((h1 / 2, 20), (h1, 10), (2 * h1, 5)):
            if hs == h1:
                t, r = _t, rc10
            else:
                t, r, _, _ = liemid_energy(pc, hs, 10 * n1 * h1, ev)
            n = len(r)
            _a, b, fit = trend(t, r)
            say(f"    h = {hs:g}: " + " ".join(f"{np.mean(r[k * n // 10:(k + 1) * n // 10]) / hs**2:6.1f}" for k in range(10))
                + f"; slope / h^2 {b / hs**2:.3f} per s (explains {fit:.2f}); max |dE/E| / h^2 {np.max(np.abs(r)) / hs**2:.0f}")

    # figure ----------------------------------------------------------------------------------
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        say("  (matplotlib missing: no figure)")
        plt = None
    def envelope(t, r, windows=400):
        """The largest |dE/E| in each of `windows` equal windows of the run, at the window's end."""
        k = max(len(r) // windows, 1)
        n = len(r) // k * k
        return t[k - 1:n:k], np.max(np.abs(r[:n]).reshape(-1, k), axis=1)

    def line(ax, t, a, b, **kw):
        """|a + b t| where the line has the sign of its slope (its growing part)."""
        y = a + b * t
        keep = np.sign(y) == np.sign(b)
        ax.plot(t[keep], np.abs(y[keep]), **kw)

    if plt is not None:
        fig, axs = plt.subplots(2, 2, figsize=(13, 9))
        ax = axs.ravel()
        for k, run in enumerate(runs):
            a4, b4, _ = run["fit"]
            al, bl, _ = trend(run["tl"], run["rl"])
            ax[k].plot(*envelope(run["tl"], run["rl"]), lw=0.8, color="C0",
                       label=f"liemid h = {run['H']:g} ({run['steps']} steps, CPU {run['cpu_l']:.0f} s)")
            ax[k].plot(*envelope(run["t4"], run["r4"]), lw=0.8, color="C3",
                       label=f"MuJoCo RK4 h = {run['h_eq']:.2e} (equal CPU, {run['cpu_4']:.0f} s)")
            line(ax[k], run["t4"], a4, b4, color="k", ls="--", lw=1, label=f"RK4 line fit: slope {b4:.2e} per s")
            line(ax[k], run["tl"], al, bl, color="navy", ls=":", lw=1.2,
                 label=f"liemid line fit: slope {bl:.2e} per s")
            if k == 0:
                ax[k].plot(*envelope(t41, r41), lw=0.6, color="C1", alpha=0.7,
                           label=f"MuJoCo RK4 h = {H:g} (liemid's step, CPU {cpu_41:.0f} s)")
            ax[k].set_yscale("log")
            ax[k].set_ylim(1e-6 * (run["H"] / 1e-3) ** 2, None)
            ax[k].set_xlabel("t (s)")
            ax[k].set_ylabel("largest |relative energy error| per 1/400 of the run")
            ax[k].set_title(f"chain-10, {run['steps']} liemid steps of {run['H']:g} s")
            ax[k].legend(fontsize=7, loc="upper left")
        ax[2].loglog(hh[trending], bb[trending], "o", color="C3", label="RK4: |slope of the line fit of dE/E|")
        ax[2].loglog(hh[~trending], bb[~trending], "o", mfc="none", color="C3",
                     label="the same, no trend (line explains < 0.5)")
        xs = np.geomspace(h_old, hh[-1], 50)
        ax[2].loglog(xs, C * xs ** p, "k--", lw=1, label=f"{C:.2g} h^{p:.2f} per s")
        ax[2].axvline(h_old, color="grey", lw=0.5, ls=":")
        ax[2].text(h_old, C * h_old ** p, " earlier equal-CPU step (liemid at 1e-4)", fontsize=7, va="top")
        ax[2].set_xlabel("RK4 step h (s)")
        ax[2].set_ylabel("energy drift rate (1/s)")
        ax[2].set_title(f"RK4's drift rate against its step (t = {T:g} s)")
        ax[2].legend(fontsize=7)
        tt, ee = envelope(tc, rc, 200)
        ax[3].plot(tt, ee / h1**2, lw=0.8, label=f"h = {h1:g}")
        tt, ee = envelope(td, rd, 200)
        ax[3].plot(tt, ee / (h1 / 2) ** 2, lw=0.8, label=f"h = {h1 / 2:g}")
        ax[3].set_xlabel(f"t (s) after a {t_tr:g} s transient")
        ax[3].set_ylabel("largest |relative energy error| / h² per 0.5 s")
        ax[3].set_title("liemid from a start in the chaotic motion: error / h² at two steps")
        ax[3].legend(fontsize=7)
        fig.tight_layout()
        out = Path(tempfile.gettempdir()) / "multibody-energy-quick.png" if QUICK else DOCS / "multibody-energy.png"
        fig.savefig(out, dpi=100)
        say(f"  figure: {out.relative_to(ROOT) if not QUICK else out}")
    if not QUICK:
        (DOCS / "vs-mujoco-energy.txt").write_text("\n".join(OUT_LINES) + "\n")
        print("wrote docs/vs-mujoco-energy.txt")


if __name__ == "__main__":
    main()
