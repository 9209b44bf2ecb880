//! `mpirun -n R liemid many --model dipoles ...` (the `mpi` feature): one periodic dipolar
//! fluid split into R slabs ([`liemid::many::mpi`]), the same bits as one process's run with
//! `--pair-list full` on any R. Every rank checks the input and agrees with the others
//! first (a hash of the arguments and of the files named), so bad use gets one line and exit
//! 2 on every rank; rank 0 writes every file (the totals, the trajectory, the states and the
//! summary) from the bodies gathered in body order.

use std::path::Path;
use std::time::Instant;

use liemid::error::Num;
use liemid::many::mpi::{DomainError, DomainRun, GHOST_RECORD};
use liemid::many::problems;
use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use serde_json::json;

use super::command::{resume_start, settings, ManyArgs};
use super::scenario::Model;
use super::state::{self, State};
use crate::shared::command::{CmdResult, Failure};
use crate::shared::output::{Format, OutputPlan, TrajectoryWriter};

/// Whether the command was started by an MPI launcher (Open MPI's or MPICH's `mpirun`).
#[must_use]
pub fn launched() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
}

/// FNV-1a (64 bits) of `bytes` onto `h`.
fn fnv(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// The hash of the input: the arguments and the files `--scenario` and `--resume` name.
fn input_hash(cli: &ManyArgs) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325;
    for a in std::env::args_os().skip(1) {
        h = fnv(h, a.as_encoded_bytes());
        h = fnv(h, &[0]);
    }
    for p in [&cli.scenario, &cli.resume].into_iter().flatten() {
        h = match liemid_app::shared::input::read_bytes(p, liemid_app::shared::input::MAX_START_BYTES) {
            Ok(b) => fnv(h, &b),
            Err(e) => fnv(h, e.to_string().as_bytes()),
        };
    }
    h
}

/// `Ok` on every rank when `local` is `Ok` on every rank; else the error of this rank, or
/// the line saying which rank failed (one reduction).
fn agree(world: &SimpleCommunicator, local: Result<(), Failure>) -> Result<(), Failure> {
    let (rank, size) = (world.rank(), world.size());
    let code = match &local {
        Ok(()) => 0,
        Err(Failure::Input(_)) => 2,
        Err(_) => 1,
    };
    let mine = [code, if code > 0 { size - rank } else { 0 }];
    let mut all = [0i32; 2];
    world.all_reduce_into(&mine[..], &mut all[..], SystemOperation::max());
    if all[0] == 0 {
        return Ok(());
    }
    match local {
        Err(e) => Err(e),
        Ok(()) => {
            let line = format!("stopped: rank {} failed (its line says why)", size - all[1]);
            Err(if all[0] == 2 {
                Failure::Input(line)
            } else {
                Failure::Run(line)
            })
        }
    }
}

/// Run `liemid many` under MPI.
pub fn many(cli: &ManyArgs) -> CmdResult {
    let Some(universe) = mpi::initialize() else {
        return Err(Failure::Run("MPI was initialized already".into()));
    };
    let world = universe.world();
    let result = run(cli, &world);
    // Every failure from `run` is reached by every rank alike: each prints its line and all
    // meet before any exits (the launcher stops the others once one exits non-zero).
    let (code, m) = match &result {
        Ok(()) => return Ok(()),
        Err(Failure::Input(m)) => (2, m),
        Err(Failure::Run(m) | Failure::Signal(_, m)) => (1, m),
    };
    // One write per line, so that the ranks' lines do not interleave on the launcher's
    // standard error.
    use std::io::Write as _;
    let mut err = std::io::stderr().lock();
    let _ = err.write_all(format!("liemid: error: {m}\n").as_bytes());
    let _ = err.flush();
    drop(err);
    world.barrier();
    drop(universe);
    std::process::exit(code)
}

fn run(cli: &ManyArgs, world: &SimpleCommunicator) -> CmdResult {
    let (rank, ranks) = (world.rank() as usize, world.size() as usize);
    // The same input on every rank, before anything else.
    let mine = input_hash(cli);
    let mut hashes = vec![0u64; ranks];
    world.all_gather_into(&mine, &mut hashes[..]);
    if let Some(k) = hashes.iter().position(|&h| h != hashes[0]) {
        return Err(Failure::Input(format!(
            "the ranks disagree on the input (a hash of the arguments and the files --scenario and --resume): rank 0 \
             has {:016x}, rank {k} has {:016x}",
            hashes[0], hashes[k]
        )));
    }
    // From here every rank decides alike on the same input.
    let prepared = prepare(cli, ranks);
    let (args, resumed, h, t_end, steps, start) = prepared?;
    let seeded = problems::dipolar_fluid_with_cutoff(
        args.bodies,
        args.density,
        args.seed,
        args.cutoff.unwrap_or(problems::DIPOLAR_FLUID_CUTOFF),
    );
    let (mut all, mut model) = seeded.map_err(|e| Failure::Input(e.to_string()))?;
    if let Some(r_s) = args.switch_start {
        if model.cutoff.is_some() {
            model = model
                .with_switch_start(r_s)
                .map_err(|e| Failure::Input(e.to_string()))?;
        }
    }
    model.cutoff_form = args.cutoff_form;
    model.half_list_max_bodies = 0;
    let mut reference = None;
    if let Some(r) = resumed {
        if r.box_length.map(f64::to_bits) != model.box_length.map(f64::to_bits) {
            return Err(Failure::Input(format!(
                "the state file --resume has the box {:?}, this run {:?} (--density and --bodies must be those of the \
                 run that wrote it)",
                r.box_length, model.box_length
            )));
        }
        if r.bodies.free_rotation() != args.rotation {
            return Err(Failure::Input(format!(
                "the state file --resume was written with the {} rotation, this run asks for {}",
                r.bodies.free_rotation().key(),
                args.rotation.key()
            )));
        }
        all = r.bodies;
        reference = Some(r.reference);
    } else {
        all.set_free_rotation(args.rotation)
            .map_err(|e| Failure::Input(e.to_string()))?;
    }
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(k) = cli.threads {
        pool = pool.num_threads(usize::try_from(k).unwrap_or(1));
    }
    // The process's global pool (the communicator cannot move into another pool's threads).
    pool.build_global()
        .map_err(|e| Failure::Run(format!("thread pool: {e}")))?;
    let threads = rayon::current_num_threads();
    let domain_error = |e: DomainError| match e {
        DomainError::Input(m) => Failure::Input(m),
        DomainError::Run(m) => Failure::Run(m),
    };
    let mut domain = DomainRun::new(world, &model, &all, reference.as_deref()).map_err(domain_error)?;
    drop(all);
    let box_length = model.box_length;
    let thermostat = match args.thermostat {
        Some((kt, friction)) => Some(
            liemid::many::thermostat::Langevin::new(kt, friction, args.seed)
                .map_err(|e| Failure::Input(e.to_string()))?,
        ),
        None => None,
    };
    // Rank 0's files.
    let mut out = None;
    let opened = if rank == 0 {
        args.out
            .as_ref()
            .map(|p| TrajectoryWriter::create(p, Format::Csv, &super::command::TOTALS_COLUMNS))
            .transpose()
            .map(|w| out = w)
            .map_err(Failure::Run)
    } else {
        Ok(())
    };
    agree(world, opened)?;
    let traj_every = cli.trajectory_every.unwrap_or(args.every);
    let mut frames = None;
    let opened = match (&cli.trajectory, rank) {
        (Some(p), 0) => crate::shared::xyz::FrameWriter::create(p)
            .map(|w| frames = Some(w))
            .map_err(Failure::Run),
        _ => Ok(()),
    };
    agree(world, opened)?;
    let mut first = None;
    let mut observe = |d: &DomainRun<'_>, out: &mut Option<TrajectoryWriter>, k: u64, last: bool| -> CmdResult {
        // Gathered only where something is written (the totals file every `every` steps,
        // the checkpoint, the first and last totals): the gather and rank 0's totals hold
        // the other ranks at their next reduction.
        let frame = cli.trajectory.is_some() && (k % traj_every == 0 || last);
        let wanted =
            (args.out.is_some() && k % args.every == 0) || frame || last || k == start || cli.checkpoint_at == Some(k);
        if !wanted {
            return Ok(());
        }
        let gathered = d.gather();
        let written = match gathered {
            None => Ok(()),
            Some((b, reference)) => (|| {
                let tot = b.totals(&model);
                if first.is_none() {
                    first = Some(tot);
                }
                if let Some(w) = out.as_mut().filter(|_| k % args.every == 0 || last) {
                    let (p, l) = (tot.linear_momentum, tot.angular_momentum);
                    w.write_row(&[b.t, tot.energy, p.x, p.y, p.z, l.x, l.y, l.z])
                        .map_err(Failure::Run)?;
                }
                if let Some(w) = frames.as_mut().filter(|_| frame) {
                    w.write_frame(&b, box_length).map_err(Failure::Run)?;
                }
                let write_state = |path: &Path| {
                    let s = State {
                        bodies: b.clone(),
                        reference: reference.clone(),
                        steps: k,
                        h,
                        box_length,
                    };
                    state::write(path, &s).map_err(Failure::Run)
                };
                if let (Some(at), Some(path)) = (cli.checkpoint_at, &cli.checkpoint) {
                    if at == k {
                        write_state(path)?;
                    }
                }
                if last {
                    if let Some(path) = &cli.state {
                        write_state(path)?;
                    }
                    if cli.json.as_deref() != Some("-") {
                        crate::outln!(
                            "energy {:e} -> {:e} (relative change {:.3e})",
                            first.map_or(f64::NAN, |f| f.energy),
                            tot.energy,
                            first.map_or(f64::NAN, |f| ((tot.energy - f.energy) / f.energy).abs())
                        );
                    }
                }
                Ok(())
            })(),
        };
        agree(world, written)
    };
    observe(&domain, &mut out, start, start == steps)?;
    world.barrier();
    let started = Instant::now();
    let mut stepping = 0.0;
    for j in start..steps {
        let last = j + 1 == steps;
        let t0 = Instant::now();
        match &thermostat {
            // As one process: the step from the last time to the next, t0 + (j + 1) h or t_end.
            Some(th) => {
                let target = if last { t_end } else { (j + 1) as f64 * h };
                domain.step_langevin(target - domain.bodies.t, th)
            }
            None => domain.step(if last { t_end - (steps - 1) as f64 * h } else { h }),
        }
        .map_err(domain_error)?;
        stepping += t0.elapsed().as_secs_f64();
        domain.bodies.t = if last { t_end } else { (j + 1) as f64 * h };
        observe(&domain, &mut out, j + 1, last)?;
    }
    let wall = started.elapsed().as_secs_f64();
    let finished = if rank == 0 {
        out.map_or(Ok(()), |w| w.finish().map(|_| ()).map_err(Failure::Run))
            .and_then(|()| frames.map_or(Ok(()), |w| w.finish().map(|_| ()).map_err(Failure::Run)))
    } else {
        Ok(())
    };
    agree(world, finished)?;
    // The communication counted on every rank, summed.
    let s = domain.stats;
    let evaluations = s.evaluations.max(1);
    let totals = [
        domain.sum(s.ghost_bytes),
        domain.sum(s.ghost_messages),
        domain.sum(s.build_bytes),
        domain.sum(s.ghosts as u64),
        domain.sum(s.builds),
    ];
    let mut slowest = 0.0f64;
    world.all_reduce_into(&stepping, &mut slowest, SystemOperation::max());
    if rank == 0 {
        let n = args.bodies;
        let done = (steps - start) as f64 * n as f64;
        let throughput = if slowest > 0.0 { done / slowest } else { f64::NAN };
        let summary = json!({
            "model": "dipoles",
            "ranks": ranks,
            "threads_per_rank": threads,
            "bodies": n,
            "steps": steps - start,
            "start_step": start,
            "step": h,
            "t": domain.bodies.t,
            "stepping_seconds": slowest,
            "wall_seconds": wall,
            "body_steps_per_second": throughput,
            "cutoff": model.cutoff,
            "skin": model.skin,
            "box_length": box_length,
            "list_builds": s.builds,
            "ghost_record_bytes": 8 * GHOST_RECORD,
            "ghosts_per_rank_last_build": totals[3] as f64 / ranks as f64,
            "ghost_bytes_per_rank_per_step": totals[0] as f64 / ranks as f64 / evaluations as f64,
            "ghost_messages_per_rank_per_step": totals[1] as f64 / ranks as f64 / evaluations as f64,
            "build_bytes_per_rank_per_build": totals[2] as f64 / ranks as f64 / (totals[4].max(1) as f64 / ranks as f64),
        });
        match cli.json.as_deref() {
            Some("-") => crate::outln!("{summary}"),
            Some(path) => {
                crate::shared::output::write_atomically(Path::new(path), (summary.to_string() + "\n").as_bytes())
                    .map_err(|e| Failure::Run(format!("{path}: cannot write: {e}")))?
            }
            None => {}
        }
        if cli.json.as_deref() != Some("-") {
            crate::outln!(
                "dipoles over MPI: {n} bodies in {ranks} slabs ({threads} threads each), {} steps of {} to t = {}: \
                 {slowest:.3} s stepping, {throughput:.3e} body-steps/s; {:.0} ghosts and {:.0} bytes sent per rank \
                 per step",
                steps - start,
                Num(h),
                Num(domain.bodies.t),
                totals[3] as f64 / ranks as f64,
                totals[0] as f64 / ranks as f64 / evaluations as f64
            );
        }
    }
    Ok(())
}

type Prepared = (super::scenario::Settings, Option<State>, f64, f64, u64, u64);

/// The checks of the input, the same on every rank (no communication).
fn prepare(cli: &ManyArgs, ranks: usize) -> Result<Prepared, Failure> {
    let input = Failure::Input;
    let mut args = settings(cli).map_err(input)?;
    if args.model != Model::Dipoles {
        return Err(input(format!(
            "MPI runs the periodic dipolar fluid (--model dipoles), not the {} model (its bodies do not interact: run \
             it without mpirun)",
            args.model.key()
        )));
    }
    for (given, what) in [
        (cli.rdf.is_some(), "--rdf"),
        (cli.view.is_some(), "--view"),
        (cli.pair_list.as_deref() == Some("half"), "--pair-list half"),
    ] {
        if given {
            return Err(input(format!(
                "{what} is not available with MPI ({ranks} ranks): run it in one process"
            )));
        }
    }
    let resumed = match &cli.resume {
        Some(p) => Some(state::read(p).map_err(input)?),
        None => None,
    };
    if let Some(r) = &resumed {
        args.bodies = r.bodies.len();
    }
    if !(args.density > 0.0 && args.density <= super::command::MAX_DENSITY) {
        return Err(input(format!(
            "density {}: the dipolar fluid accepts 0 < density <= {}",
            Num(args.density),
            super::command::MAX_DENSITY
        )));
    }
    let h = args.step.unwrap_or(1e-3);
    let t_end = args.t_end.unwrap_or(1.0);
    if !(h.is_finite() && h > 0.0) {
        return Err(input(format!("--step must be a positive number, found {h}")));
    }
    if !(t_end.is_finite() && t_end >= 0.0) {
        return Err(input(format!("--t-end must be a non-negative number, found {t_end}")));
    }
    let steps = liemid::step_count(0.0, t_end, h)
        .map_err(|e| input(format!("--step {} and --t-end {}: {e}", Num(h), Num(t_end))))?;
    let start = resume_start(resumed.as_ref(), h, steps).map_err(input)?;
    if let Some(k) = cli.checkpoint_at.filter(|&k| k <= start || k >= steps) {
        return Err(input(format!(
            "--checkpoint-at {k} must lie after the start (step {start}) and before the last step ({steps})"
        )));
    }
    let inputs: Vec<&Path> = cli.scenario.as_deref().into_iter().collect();
    let mut plan = OutputPlan::new(&inputs);
    for (flag, path) in [
        ("--out", args.out.as_deref()),
        ("--state", cli.state.as_deref()),
        ("--checkpoint", cli.checkpoint.as_deref()),
        ("--trajectory", cli.trajectory.as_deref()),
        ("--json", cli.json.as_deref().filter(|j| *j != "-").map(Path::new)),
    ] {
        if let Some(p) = path {
            plan.add(flag, p).map_err(input)?;
        }
    }
    if let Some(max) = cli.max_body_steps {
        let work = steps as f64 * args.bodies as f64;
        if work > max as f64 {
            return Err(input(format!(
                "the run would take {work:e} body-steps, more than --max-body-steps {max}"
            )));
        }
    }
    Ok((args, resumed, h, t_end, steps, start))
}
