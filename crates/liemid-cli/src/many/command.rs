//! `liemid many`: step an ensemble of rigid bodies in parallel and report throughput and
//! conservation.

use std::path::{Path, PathBuf};
use std::time::Instant;

use liemid::error::Num;
use liemid::many::problems;
use liemid::many::{Bodies, Interaction, Totals};
use serde_json::json;

use super::scenario::{self, parse_cutoff_form, Model, Rotation, Settings};
use crate::shared::command::{CmdResult, Failure};
use crate::shared::interrupt::{progress, Interrupt};
use crate::shared::output::Format;
use crate::shared::output::{plural, OutputPlan, TrajectoryWriter};
use crate::shared::view::{self, Scene, ViewPage};

/// The densest dipolar fluid accepted: the WCA spheres have diameter 1 and the bodies start
/// on a simple cubic lattice, so above 1.2 (lattice spacing 0.94) neighbours start deep in
/// each other's repulsion; close packing is sqrt(2) = 1.414.
pub const MAX_DENSITY: f64 = 1.2;

/// Threads beyond this multiple of the cores are capped (they only add switching).
const THREADS_PER_CORE: usize = 4;

/// Memory a run needs per body, beyond the state: forces, cell lists and the model's
/// parameters, with a margin (bytes).
const WORKING_BYTES_PER_BODY: usize = 2 * liemid::many::BYTES_PER_BODY;

/// Columns of the totals file.
pub(crate) const TOTALS_COLUMNS: [&str; 8] = ["t", "energy", "px", "py", "pz", "lx", "ly", "lz"];

/// Arguments of `liemid many`.
#[derive(clap::Args, Debug)]
pub struct ManyArgs {
    /// Scenario file (TOML) with `[system] model, bodies, seed, density, cutoff,
    /// switch_start`,
    /// `[integrator] step, t_end` and `[output] path, every`; command-line options win.
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// The interaction model [default: independent].
    #[arg(long, value_enum)]
    pub model: Option<Model>,
    /// Number of bodies [default: 1000].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub bodies: Option<u64>,
    /// End time [default: 0.01 for tops, 0.1 torque-free, 1 for dipoles].
    #[arg(long, allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Step [default: 1e-4 for tops, 1e-3 otherwise].
    #[arg(long, allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// The free rotation between the impulses [default: midpoint]: the midpoint Lie rule
    /// (as in `liemid-ea`), the exact torque-free flow (as in `liemid-ex`) or the
    /// variational rotation (as in `liemid-eav`; no SIMD lanes).
    #[arg(long, value_enum)]
    pub rotation: Option<Rotation>,
    /// Langevin thermostat at this k_B T (model units; BAOAB around the splitting, noise
    /// keyed on seed, body and step); NVE without it.
    #[arg(long, allow_negative_numbers = true)]
    pub temperature: Option<f64>,
    /// The thermostat's friction, translational and rotational (1/time) [default: 1].
    #[arg(long, allow_negative_numbers = true)]
    pub friction: Option<f64>,
    /// Threads [default: all cores]; results are identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub threads: Option<u64>,
    /// Seed of the initial conditions [default: 1].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Number density of the dipolar fluid [default: 0.3].
    #[arg(long, allow_negative_numbers = true)]
    pub density: Option<f64>,
    /// Cutoff of the dipolar fluid's pair sum [default: 3]; without a box of at least twice
    /// the cutoff, all pairs in open space.
    #[arg(long, allow_negative_numbers = true)]
    pub cutoff: Option<f64>,
    /// Where the dipole energy starts to be switched off [default: 0.8 × cutoff]; equal to
    /// the cutoff, a plain truncation.
    #[arg(long, allow_negative_numbers = true)]
    pub switch_start: Option<f64>,
    /// How the dipole energy goes to zero at the cutoff: `switched` (the plain dipole up to
    /// the switch start) or `shifted-force` (Allen and Germano's, LAMMPS's lj/sf/dipole/sf)
    /// [default: switched].
    #[arg(long)]
    pub cutoff_form: Option<String>,
    /// Write the summary as JSON to FILE, or to standard output with `-` or no value.
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<String>,
    /// Write the totals (t, energy, P, L) every `--every` steps to this CSV file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Interval of the totals file, in steps [default: 10].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub every: Option<u64>,
    /// Refuse runs of more than N body-steps (bodies × steps; exit 2) before the first step.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_body_steps: Option<u64>,
    /// Write every body (position, orientation quaternion, velocity, angular momenta) to
    /// this extended XYZ file (OVITO, ASE, MDAnalysis) every `--trajectory-every` steps.
    #[arg(long)]
    pub trajectory: Option<PathBuf>,
    /// Interval of the trajectory, in steps [default: `--every`].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub trajectory_every: Option<u64>,
    /// Radial distribution function g(r), averaged over the configurations sampled every
    /// `--every` steps: NAME writes NAME.csv and NAME.png (at most 20,000 bodies).
    #[arg(long)]
    pub rdf: Option<PathBuf>,
    /// Write a self-contained 3-D animation of the run (HTML) to FILE, sampled every
    /// `--every` steps (frames subsampled to the page's byte budget).
    #[arg(long)]
    pub view: Option<PathBuf>,
    /// The dipolar fluid's pair list: `half` (each pair once, Newton's third law; the
    /// default in one process) or `full` (each body sums its own neighbours, in the order
    /// MPI runs sum them: the same bits on any number of ranks).
    #[arg(long, value_parser = ["half", "full"])]
    pub pair_list: Option<String>,
    /// Write the final state (every body in body order, and the positions of the last
    /// neighbour-list build) to this binary file; `--resume` reads it.
    #[arg(long)]
    pub state: Option<PathBuf>,
    /// Write the state after `--checkpoint-at` steps to this file (and go on).
    #[arg(long, requires = "checkpoint_at")]
    pub checkpoint: Option<PathBuf>,
    /// The step after which `--checkpoint` is written.
    #[arg(long, requires = "checkpoint", value_parser = clap::value_parser!(u64).range(1..))]
    pub checkpoint_at: Option<u64>,
    /// Start from a state file (`--state` or `--checkpoint`, written in one process or on
    /// any number of MPI ranks) and run on to `--t-end` with the same step: the bits of an
    /// uninterrupted run.
    #[arg(long)]
    pub resume: Option<PathBuf>,
}

/// Bodies above which `--rdf` is refused (its pair count grows as N²).
const MAX_RDF_BODIES: usize = 20_000;

/// What a run observes besides the totals.
pub(crate) struct Observers {
    trajectory: Option<(PathBuf, u64)>,
    rdf: Option<liemid::many::observables::PairHistogram>,
    box_length: Option<f64>,
    view: Option<ViewPage>,
}

/// Where a run starts and which states it writes.
pub(crate) struct Checkpoints<'a> {
    /// Steps already done (from `--resume`).
    pub start: u64,
    /// `--checkpoint-at` and `--checkpoint`.
    pub at: Option<(u64, &'a Path)>,
    /// `--state`.
    pub last: Option<&'a Path>,
    /// The positions of the last neighbour-list build (the positions without a list).
    pub reference: &'a (dyn Fn(&Bodies) -> Vec<liemid::Vec3> + Sync),
}

impl Checkpoints<'_> {
    fn write(&self, path: &Path, b: &Bodies, steps: u64, h: f64, box_length: Option<f64>) -> Result<(), String> {
        let s = super::state::State {
            bodies: b.clone(),
            reference: (self.reference)(b),
            steps,
            h,
            box_length,
        };
        super::state::write(path, &s)
    }
}

pub(crate) fn settings(args: &ManyArgs) -> Result<Settings, String> {
    let mut s = match &args.scenario {
        Some(path) => scenario::read(path)?,
        None => Settings::default(),
    };
    if let Some(m) = args.model {
        s.model = m;
    }
    if let Some(kt) = args.temperature {
        s.thermostat = Some((kt, args.friction.or(s.thermostat.map(|t| t.1)).unwrap_or(1.0)));
    } else if let (Some(f), Some((kt, _))) = (args.friction, s.thermostat) {
        s.thermostat = Some((kt, f));
    } else if args.friction.is_some() {
        return Err("--friction needs --temperature (or [integrator] temperature)".into());
    }
    if let Some(r) = args.rotation {
        s.rotation = r.free_rotation();
    }
    if let Some(n) = args.bodies {
        s.bodies = n as usize;
    }
    if let Some(v) = args.seed {
        s.seed = v;
    }
    if let Some(v) = args.density {
        s.density = v;
    }
    if args.cutoff.is_some() {
        s.cutoff = args.cutoff;
    }
    if args.switch_start.is_some() {
        s.switch_start = args.switch_start;
    }
    if let Some(f) = &args.cutoff_form {
        s.cutoff_form = parse_cutoff_form(f).map_err(|e| format!("--cutoff-form: {e}"))?;
    }
    if s.cutoff_form == liemid::interactions::CutoffForm::ShiftedForce && s.switch_start.is_some() {
        return Err("switch_start applies to the switched cutoff form, not to shifted-force".into());
    }
    if s.model != Model::Dipoles && (s.cutoff.is_some() || s.switch_start.is_some()) {
        return Err("cutoff and switch_start apply to the dipoles model only".into());
    }
    if args.step.is_some() {
        s.step = args.step;
    }
    if args.t_end.is_some() {
        s.t_end = args.t_end;
    }
    if args.out.is_some() {
        s.out = args.out.clone();
    }
    if let Some(e) = args.every {
        s.every = e;
    }
    Ok(s)
}

/// What a finished run reports.
struct Outcome {
    bodies: Bodies,
    first: Totals,
    last: Totals,
    stepping_seconds: f64,
    max_energy_error: f64,
    rdf: Option<liemid::many::observables::PairHistogram>,
    frames: Option<u64>,
    view: Option<ViewPage>,
}

/// Step `bodies` to `t_end` (the last step lands on it), writing the totals every
/// `args.every` steps; errors are failed runs (exit 1) or a stop by a signal.
fn run_model<I: Interaction>(
    args: &Settings,
    mut bodies: Bodies,
    model: &I,
    (h, t_end, steps): (f64, f64, u64),
    interrupt: &Interrupt,
    mut observers: Observers,
    states: &Checkpoints<'_>,
) -> Result<Outcome, Failure> {
    let thermostat = match args.thermostat {
        Some((kt, friction)) => Some(
            liemid::many::thermostat::Langevin::new(kt, friction, args.seed)
                .map_err(|e| Failure::Input(e.to_string()))?,
        ),
        None => None,
    };
    let mut frames = match &observers.trajectory {
        Some((p, _)) => Some(crate::shared::xyz::FrameWriter::create(p).map_err(Failure::Run)?),
        None => None,
    };
    if states.start > 0 && bodies.free_rotation() != args.rotation {
        return Err(Failure::Input(format!(
            "the state file --resume was written with the {} rotation, this run asks for {}",
            bodies.free_rotation().key(),
            args.rotation.key()
        )));
    }
    bodies
        .set_free_rotation(args.rotation)
        .map_err(|e| Failure::Run(e.to_string()))?;
    bodies.evaluate(model);
    let first = bodies.totals(model);
    let mut out = match &args.out {
        Some(p) => Some(TrajectoryWriter::create(p, Format::Csv, &TOTALS_COLUMNS).map_err(Failure::Run)?),
        None => None,
    };
    let mut max_de = 0.0f64;
    let mut page = observers.view.take();
    let mut write =
        |b: &Bodies, out: &mut Option<TrajectoryWriter>, page: &mut Option<ViewPage>| -> Result<(), String> {
            let tot = b.totals(model);
            let de = ((tot.energy - first.energy) / first.energy).abs();
            max_de = max_de.max(de);
            if let Some(p) = page.as_mut() {
                p.energy_error(b.t, (tot.energy - first.energy) / first.energy.abs());
                let frame: Vec<f32> = (0..b.len())
                    .step_by(view::body_stride(b.len()))
                    .flat_map(|i| {
                        let (x, q) = (b.position[i], view::quaternion(&b.rotation[i].m));
                        [x.x as f32, x.y as f32, x.z as f32, q[0], q[1], q[2], q[3]]
                    })
                    .collect();
                p.push_frame(b.t, &frame);
            }
            if let Some(w) = out.as_mut() {
                let (p, l) = (tot.linear_momentum, tot.angular_momentum);
                w.write_row(&[b.t, tot.energy, p.x, p.y, p.z, l.x, l.y, l.z])?;
            }
            Ok(())
        };
    let keep = |out: Option<TrajectoryWriter>, frames: Option<crate::shared::xyz::FrameWriter>| {
        out.map(|w| format!("; {}", w.keep_partial())).unwrap_or_default()
            + &frames.map(|w| format!("; {}", w.keep_partial())).unwrap_or_default()
    };
    let traj_every = observers.trajectory.as_ref().map_or(u64::MAX, |(_, k)| *k);
    let box_length = observers.box_length;
    let mut observe =
        |b: &Bodies, frames: &mut Option<crate::shared::xyz::FrameWriter>, k: u64| -> Result<(), String> {
            if let Some(h) = observers.rdf.as_mut() {
                if k % args.every == 0 || k == steps {
                    h.add(&b.position, box_length);
                }
            }
            if let Some(w) = frames.as_mut() {
                if k % traj_every == 0 || k == steps {
                    w.write_frame(b, box_length)?;
                }
            }
            Ok(())
        };
    if let Err(e) = write(&bodies, &mut out, &mut page).and_then(|()| observe(&bodies, &mut frames, 0)) {
        return Err(Failure::Run(format!("{e}{}", keep(out, frames))));
    }
    let bar = progress(steps, "steps", steps as f64 * bodies.len() as f64 >= 2e7);
    let mut stepping = 0.0;
    // Times are t0 + k h from the run's start at t = 0, resumed or not.
    let t0 = 0.0;
    // Steps are taken in blocks that end where something is observed (the totals, the
    // trajectory, the last step) and hold at most about 5·10⁵ body-steps, so that a stop
    // request is seen within a fraction of a second. A block of NVE steps is one
    // `Bodies::advance` (a team of threads for all its steps; the same bits as single
    // steps); the last step lands on t_end.
    let block_cap = (500_000 / bodies.len().max(1) as u64).max(1);
    let next_multiple = |k: u64, m: u64| if m == u64::MAX { u64::MAX } else { (k / m + 1) * m };
    let mut k = states.start;
    let at = states.at.map_or(u64::MAX, |(k, _)| k);
    while k < steps {
        if let Some((signal, code)) = interrupt.requested() {
            bar.finish_and_clear();
            return Err(Failure::Signal(
                code,
                format!(
                    "{signal}: stopped at t = {} after {k} of {steps} steps{}",
                    Num(bodies.t),
                    keep(out, frames)
                ),
            ));
        }
        let end = next_multiple(k, args.every)
            .min(next_multiple(k, traj_every))
            .min(steps)
            .min(k + block_cap)
            .min(if k < at { at } else { u64::MAX });
        let start = Instant::now();
        let result = match &thermostat {
            Some(th) => (k..end).try_for_each(|j| {
                // The nominal step, except for the last one, which lands on t_end.
                let target = if j + 1 == steps { t_end } else { t0 + (j + 1) as f64 * h };
                let dt = target - bodies.t;
                bodies.step_langevin(model, dt, th).map(|()| bodies.t = target)
            }),
            None => {
                let nominal = if end == steps { end - 1 - k } else { end - k };
                bodies.advance(model, h, nominal).and_then(|()| {
                    if end == steps {
                        bodies.t = t0 + (steps - 1) as f64 * h;
                        bodies.step(model, t_end - bodies.t)?;
                    }
                    Ok(())
                })
            }
        };
        stepping += start.elapsed().as_secs_f64();
        if let Err(e) = result {
            bar.finish_and_clear();
            return Err(Failure::Run(format!("steps {}-{end}: {e}{}", k + 1, keep(out, frames))));
        }
        bodies.t = if end == steps { t_end } else { t0 + end as f64 * h };
        k = end;
        if k % args.every == 0 || k == steps {
            if let Err(e) = write(&bodies, &mut out, &mut page) {
                return Err(Failure::Run(format!("{e}{}", keep(out, frames))));
            }
        }
        if let Err(e) = observe(&bodies, &mut frames, k) {
            return Err(Failure::Run(format!("{e}{}", keep(out, frames))));
        }
        if k == at {
            if let Some((_, path)) = states.at {
                states
                    .write(path, &bodies, k, h, box_length)
                    .map_err(|e| Failure::Run(format!("{e}{}", keep(out.take(), frames.take()))))?;
            }
        }
        bar.set_position(k);
    }
    if let Some(path) = states.last {
        states.write(path, &bodies, k, h, box_length).map_err(Failure::Run)?;
    }
    bar.finish_and_clear();
    if let Some(w) = out {
        w.finish().map_err(Failure::Run)?;
    }
    let frames = match frames {
        Some(w) => Some(w.finish().map_err(Failure::Run)?),
        None => None,
    };
    let last = bodies.totals(model);
    Ok(Outcome {
        bodies,
        first,
        last,
        stepping_seconds: stepping,
        max_energy_error: max_de,
        rdf: observers.rdf,
        frames,
        view: page,
    })
}

/// `[translational, rotational]` kinetic temperatures, `⟨p²/m⟩/3` over the free bodies and
/// `⟨Π·I⁻¹Π⟩/3` over all.
fn kinetic_temperatures(b: &Bodies) -> [f64; 2] {
    let (mut tr, mut free, mut rot) = (0.0, 0usize, 0.0);
    for i in 0..b.len() {
        if b.free[i] {
            tr += b.momentum[i].norm_squared() / b.mass[i];
            free += 1;
        }
        rot += b.pi[i].dot(b.inertia[i].inverse.component_mul(b.pi[i]));
    }
    [tr / (3 * free.max(1)) as f64, rot / (3 * b.len().max(1)) as f64]
}

/// The steps a resumed run has done (0 without `--resume`), checked against this run: the
/// same step (bit for bit), the state's time `k h`, no more steps than the run's.
pub(crate) fn resume_start(resumed: Option<&super::state::State>, h: f64, steps: u64) -> Result<u64, String> {
    let Some(r) = resumed else {
        return Ok(0);
    };
    if r.h.to_bits() != h.to_bits() {
        return Err(format!(
            "the state file --resume was written with the step {}, this run's is {} (a resumed run keeps its step)",
            Num(r.h),
            Num(h)
        ));
    }
    if r.steps > steps {
        return Err(format!(
            "the state file --resume is at step {}, past this run's last step {steps} (--t-end)",
            r.steps
        ));
    }
    Ok(r.steps)
}

/// Run `liemid many` in one process.
pub fn many(cli: &ManyArgs) -> CmdResult {
    let input = Failure::Input;
    let mut args = settings(cli).map_err(input)?;
    let resumed = match &cli.resume {
        Some(path) => Some(super::state::read(path).map_err(input)?),
        None => None,
    };
    if let Some(r) = &resumed {
        if cli.bodies.is_some_and(|n| n != r.bodies.len() as u64) {
            return Err(input(format!(
                "--bodies {} but the state file --resume holds {} bodies",
                cli.bodies.unwrap_or(0),
                r.bodies.len()
            )));
        }
        args.bodies = r.bodies.len();
    }
    if cli.pair_list.is_some() && args.model != Model::Dipoles {
        return Err(input("--pair-list applies to the dipoles model only".into()));
    }
    let args = &args;
    let n = args.bodies;
    let (h_default, t_default) = match args.model {
        Model::Independent => (1e-4, 0.01),
        Model::TorqueFree => (1e-3, 0.1),
        Model::Dipoles => (1e-3, 1.0),
    };
    let h = args.step.unwrap_or(h_default);
    let t_end = args.t_end.unwrap_or(t_default);
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
    if let Some(max) = cli.max_body_steps {
        let work = steps as f64 * n as f64;
        if work > max as f64 {
            return Err(input(format!(
                "the run would take {work:e} body-steps ({n} {} × {steps} {}), more than --max-body-steps {max}",
                plural(n as u64, "body", "bodies"),
                plural(steps, "step", "steps")
            )));
        }
    }
    let per_body = args.rotation.bytes_per_body() + WORKING_BYTES_PER_BODY;
    let needed = n as f64 * per_body as f64;
    if let Some(available) = liemid_app::shared::memory::available_memory() {
        if needed > 0.8 * available as f64 {
            return Err(input(format!(
                "--bodies {n}: the bodies need about {:.1} GB ({} bytes each with working storage), more \
                 than 80% of the {:.1} GB of memory available",
                needed / 1e9,
                per_body,
                available as f64 / 1e9
            )));
        }
    }
    if args.model == Model::Dipoles && !(args.density > 0.0 && args.density <= MAX_DENSITY) {
        return Err(input(format!(
            "density {}: the dipolar fluid accepts 0 < density <= {MAX_DENSITY} (WCA diameter 1; above it \
             the bodies start inside each other's repulsion; close packing is 1.414)",
            Num(args.density)
        )));
    }
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(k) = cli.threads {
        let cap = THREADS_PER_CORE * cores;
        let k = usize::try_from(k).unwrap_or(usize::MAX);
        if k > cap {
            eprintln!(
                "liemid: note: --threads {k} capped at {cap} ({THREADS_PER_CORE} per core on {cores} {}); \
                 the results do not depend on it",
                plural(cores as u64, "core", "cores")
            );
        }
        builder = builder.num_threads(k.min(cap));
    }
    // Every output is checked before the bodies are built.
    let inputs: Vec<&Path> = cli.scenario.as_deref().into_iter().collect();
    let mut plan = OutputPlan::new(&inputs);
    if let Some(p) = &args.out {
        plan.add("--out", p).map_err(input)?;
    }
    if let Some(j) = cli.json.as_deref().filter(|j| *j != "-") {
        plan.add("--json", Path::new(j)).map_err(input)?;
    }
    if let Some(p) = &cli.trajectory {
        plan.add("--trajectory", p).map_err(input)?;
    }
    if let Some(p) = &cli.view {
        plan.add("--view", p).map_err(input)?;
    }
    if let Some(p) = &cli.state {
        plan.add("--state", p).map_err(input)?;
    }
    if let Some(p) = &cli.checkpoint {
        plan.add("--checkpoint", p).map_err(input)?;
    }
    let rdf_paths = cli.rdf.as_ref().map(|base| {
        let with = |ext: &str| {
            let mut s = base.as_os_str().to_owned();
            s.push(".");
            s.push(ext);
            PathBuf::from(s)
        };
        (with("csv"), with("png"))
    });
    if let Some((csv, png)) = &rdf_paths {
        if n > MAX_RDF_BODIES {
            return Err(input(format!(
                "--rdf counts every pair (N² = {:e} for {n} bodies); it accepts at most {MAX_RDF_BODIES} bodies",
                (n as f64).powi(2)
            )));
        }
        plan.add("--rdf", csv).map_err(input)?;
        plan.add("--rdf", png).map_err(input)?;
    }
    let observers = |box_length: Option<f64>, axis: liemid::Vec3, length: f64| {
        let r_max = box_length.map_or(5.0, |l| (0.5 * l).min(5.0));
        Observers {
            trajectory: cli
                .trajectory
                .clone()
                .map(|p| (p, cli.trajectory_every.unwrap_or(args.every))),
            rdf: rdf_paths
                .as_ref()
                .map(|_| liemid::many::observables::PairHistogram::new(r_max, 100)),
            box_length,
            view: cli.view.as_ref().map(|_| {
                let stride = view::body_stride(n);
                let scene = Scene::Bodies {
                    count: n.div_ceil(stride),
                    box_length: box_length.map(|l| l as f32),
                    axis: axis.to_array().map(|v| v as f32),
                    length: length as f32,
                };
                let drawn = if stride > 1 {
                    format!("; every {stride}th body drawn")
                } else {
                    String::new()
                };
                ViewPage::new(scene, &format!("{} ({n} bodies{drawn})", args.model.key()))
            }),
        }
    };
    // The body-frame direction whose order is reported: the dipole, or the top's axis.
    let mut axis = liemid::Vec3::new(0.0, 0.0, 1.0);
    let pool = builder.build().map_err(|e| Failure::Run(format!("thread pool: {e}")))?;
    let threads = pool.current_num_threads();
    let interrupt = Interrupt::install();
    let run = (h, t_end, steps);
    let plain = Checkpoints {
        start,
        at: cli.checkpoint_at.zip(cli.checkpoint.as_deref()),
        last: cli.state.as_deref(),
        reference: &|b: &Bodies| b.position.clone(),
    };
    let from_state = |b: Bodies| -> Result<Bodies, Failure> {
        match &resumed {
            Some(r) => {
                if r.box_length.is_some() {
                    return Err(input(
                        "the state file --resume is of a periodic system, not of this model".into(),
                    ));
                }
                Ok(r.bodies.clone())
            }
            None => Ok(b),
        }
    };
    let outcome = pool.install(|| match args.model {
        Model::Independent => {
            let (b, m) = problems::top_ensemble(n, args.seed);
            run_model(
                args,
                from_state(b)?,
                &m,
                run,
                &interrupt,
                observers(None, axis, 1.0),
                &plain,
            )
        }
        Model::TorqueFree => {
            let (b, m) = problems::torque_free_ensemble(n, args.seed);
            run_model(
                args,
                from_state(b)?,
                &m,
                run,
                &interrupt,
                observers(None, axis, 1.0),
                &plain,
            )
        }
        Model::Dipoles => {
            // A bad density, cutoff or switch is bad input (exit 2), not a failed run.
            let cutoff = args.cutoff.unwrap_or(problems::DIPOLAR_FLUID_CUTOFF);
            let (b, mut m) = problems::dipolar_fluid_with_cutoff(n, args.density, args.seed, cutoff)
                .map_err(|e| input(e.to_string()))?;
            if let Some(r_s) = args.switch_start {
                if m.cutoff.is_none() {
                    return Err(input(format!(
                        "switch_start = {r_s} needs a cutoff, but the box ({:.3}) is shorter than twice the cutoff \
                         {cutoff}, so all pairs interact",
                        (n as f64 / args.density).cbrt()
                    )));
                }
                m = m.with_switch_start(r_s).map_err(|e| input(e.to_string()))?;
            }
            m.cutoff_form = args.cutoff_form;
            if cli.pair_list.as_deref() == Some("full") {
                m.half_list_max_bodies = 0;
            }
            axis = m.moment;
            let b = match &resumed {
                Some(r) => {
                    if r.box_length.map(f64::to_bits) != m.box_length.map(f64::to_bits) {
                        return Err(input(format!(
                            "the state file --resume has the box {:?}, this run {:?} (--density and --bodies must \
                             be those of the run that wrote it)",
                            r.box_length, m.box_length
                        )));
                    }
                    // The neighbour list of the interrupted run: built at its reference positions.
                    let mut at_build = r.bodies.clone();
                    at_build.position.clone_from(&r.reference);
                    at_build.evaluate(&m);
                    r.bodies.clone()
                }
                None => b,
            };
            let listed = |bodies: &Bodies| {
                let r = m.list_reference();
                if r.len() == bodies.len() {
                    r
                } else {
                    bodies.position.clone()
                }
            };
            let dipole_states = Checkpoints {
                start,
                at: cli.checkpoint_at.zip(cli.checkpoint.as_deref()),
                last: cli.state.as_deref(),
                reference: &listed,
            };
            run_model(
                args,
                b,
                &m,
                run,
                &interrupt,
                observers(m.box_length, axis, 0.9),
                &dipole_states,
            )
            .map_err(|f| match f {
                Failure::Run(m) => Failure::Run(format!("{m} (density {}, step {})", Num(args.density), Num(h))),
                other => other,
            })
        }
    })?;
    let Outcome {
        bodies,
        first,
        last,
        stepping_seconds: seconds,
        max_energy_error: max_de,
        rdf,
        frames,
        view: page,
    } = outcome;
    let viewed = match (&page, &cli.view) {
        (Some(p), Some(path)) => Some(view::report(path, p.write(path, steps).map_err(Failure::Run)?, steps)),
        _ => None,
    };
    let (polar, nematic) = liemid::many::observables::orientational_order(&bodies.rotation, axis);
    if let (Some(h), Some((csv, png))) = (&rdf, &rdf_paths) {
        let g = h.g();
        let mut text = String::from("r,g\n");
        for (r, v) in &g {
            text += &format!("{r:?},{v:?}\n");
        }
        crate::shared::output::write_atomically(csv, text.as_bytes())
            .map_err(|e| Failure::Run(format!("{}: cannot write: {e}", csv.display())))?;
        let title = format!(
            "{}: g(r) over {} configurations ({} bodies)",
            args.model.key(),
            h.samples,
            bodies.len()
        );
        crate::shared::plot::curve(png, &title, "r", "g(r)", &g).map_err(Failure::Run)?;
    }
    let body_steps = steps as f64 * bodies.len() as f64;
    let throughput = if seconds > 0.0 { body_steps / seconds } else { f64::NAN };
    let dp = last.linear_momentum - first.linear_momentum;
    let dl = last.angular_momentum - first.angular_momentum;
    // Every model conserves energy (gravity about fixed pivots, the dipole and WCA
    // potentials), so a large error is the step's.
    if max_de > 1e-2 && args.thermostat.is_none() {
        eprintln!(
            "liemid: warning: the relative energy error reached {max_de:.3e}; the step {} is probably too large \
             for this system",
            Num(h)
        );
    }
    let summary = json!({
        "model": args.model.key(),
        "cutoff_form": if args.model == Model::Dipoles { json!(args.cutoff_form.key()) } else { json!(null) },
        "rotation": args.rotation.key(),
        "bodies": bodies.len(),
        "steps": steps,
        "step": h,
        "t_end": t_end,
        "t": bodies.t,
        "threads": threads,
        "stepping_seconds": seconds,
        "body_steps_per_second": throughput,
        "bytes_per_body": bodies.bytes_per_body(),
        "energy": [first.energy, last.energy],
        "max_relative_energy_error": max_de,
        "energy_error_sampled_every": args.every,
        "linear_momentum_change": dp.to_array(),
        "angular_momentum_change": dl.to_array(),
        "thermostat": args.thermostat.map(|(kt, f)| json!({"temperature": kt, "friction": f})),
        "kinetic_temperature": kinetic_temperatures(&bodies),
        "polar_order": polar,
        "nematic_order": nematic,
        "trajectory_frames": frames,
    });
    match cli.json.as_deref() {
        Some("-") => crate::outln!("{summary}"),
        Some(path) => {
            crate::shared::output::write_atomically(Path::new(path), (summary.to_string() + "\n").as_bytes())
                .map_err(|e| Failure::Run(format!("{path}: cannot write: {e}")))?;
            crate::outln!("wrote {path}");
        }
        None => {}
    }
    if cli.json.as_deref() != Some("-") {
        let nb = bodies.len() as u64;
        crate::outln!(
            "{} ({} rotation): {nb} {}, {steps} {} of {} to t = {} on {threads} {}: {:.3} s stepping, \
             {:.3e} body-steps/s",
            args.model.key(),
            args.rotation.key(),
            plural(nb, "body", "bodies"),
            plural(steps, "step", "steps"),
            Num(h),
            Num(bodies.t),
            plural(threads as u64, "thread", "threads"),
            seconds,
            throughput
        );
        if let Some((kt, f)) = args.thermostat {
            let [tt, tr] = kinetic_temperatures(&bodies);
            crate::outln!("Langevin thermostat k_B T = {kt}, friction {f}: final kinetic temperature {tt:.4} (translation), {tr:.4} (rotation)");
        }
        crate::outln!(
            "max relative energy error (sampled every {} {})  {max_de:.3e}",
            args.every,
            plural(args.every, "step", "steps")
        );
        crate::outln!(
            "change of total linear momentum   [{:.3e}, {:.3e}, {:.3e}]",
            dp.x,
            dp.y,
            dp.z
        );
        crate::outln!(
            "change of total angular momentum  [{:.3e}, {:.3e}, {:.3e}]",
            dl.x,
            dl.y,
            dl.z
        );
        crate::outln!(
            "state memory                      {} bytes per body",
            bodies.bytes_per_body()
        );
    }
    if let Some(line) = viewed {
        if cli.json.as_deref() == Some("-") {
            eprintln!("{line}");
        } else {
            crate::outln!("{line}");
        }
    }
    Ok(())
}
