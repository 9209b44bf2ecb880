//! `liemid run`: integrate one scenario, stream its trajectory, checkpoint and resume, and
//! print a summary that says what is conserved; the front ends of `liemid converge`,
//! `liemid work-precision` and `liemid methods`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use liemid::error::Num;
use liemid::rigid::adaptive::{AngularSpeed, TorqueRate};
use liemid::{RotationMethod, Run, Vec3};

use super::{converge, satellite, study as work_precision};

mod adaptive_run;
pub mod args;
mod summary;
use crate::rigid::scenario::{self, Conservation, Format, Scenario};
use crate::shared::checkpoint::{Checkpoint, Settings, Source};
use crate::shared::command::{check_positive, check_study_outputs, report, CmdResult, Failure};
use crate::shared::interrupt::{progress, Bar, Interrupt};
use crate::shared::output::{plural, OutputPlan, TrajectoryWriter, COLUMNS};
use crate::shared::view::{self, Scene, ViewPage};
use adaptive_run::run_adaptive;
pub use args::{parse_method, WorkPrecisionArgs};
use summary::print_summary;

/// The largest trajectory `run` writes unless `--allow-large-output` is given (bytes).
pub const MAX_TRAJECTORY_BYTES: f64 = 4.0 * (1u64 << 30) as f64;

/// Bytes per trajectory row: `.npy` exactly, CSV at most (17 numbers in `{:e}`).
fn row_bytes(format: Format) -> f64 {
    match format {
        Format::Npy => 8.0 * COLUMNS.len() as f64,
        Format::Csv => 25.0 * COLUMNS.len() as f64,
    }
}

/// Default interval of `--checkpoint`, in steps.
const CHECKPOINT_EVERY: u64 = 100_000;

/// Arguments of `liemid run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scenario file (TOML). Without it, the built-in problem given by --problem.
    file: Option<PathBuf>,
    /// Built-in problem to run when no file is given.
    #[arg(long, default_value = "fast-top", conflicts_with = "file")]
    problem: String,
    /// Override the scenario's method (see `liemid methods`).
    #[arg(long)]
    method: Option<String>,
    /// Override the step size (s).
    #[arg(long, allow_negative_numbers = true)]
    step: Option<f64>,
    /// Override the end time (s).
    #[arg(long, allow_negative_numbers = true)]
    t_end: Option<f64>,
    /// Trajectory file, `-` for CSV on standard output (the summary then goes to standard
    /// error) [default: the scenario's output path, else trajectory.csv].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write every N-th step (the first and last states are always written) [default: 1].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    every: Option<u64>,
    /// Trajectory format [default: from the file extension, else csv].
    #[arg(long, value_enum)]
    format: Option<Format>,
    /// Write no trajectory, only the summary.
    #[arg(long, conflicts_with = "out")]
    no_output: bool,
    /// Write trajectories larger than 4 GiB (refused by default, with an --every that fits).
    #[arg(long)]
    allow_large_output: bool,
    /// Refuse runs of more than N steps (exit 2) before the first step [default: 10⁹].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    max_steps: Option<u64>,
    /// Write a checkpoint to FILE every --checkpoint-every steps and on SIGINT/SIGTERM.
    #[arg(long)]
    checkpoint: Option<PathBuf>,
    /// Steps between checkpoints [default: 100000].
    #[arg(long, requires = "checkpoint", value_parser = clap::value_parser!(u64).range(1..))]
    checkpoint_every: Option<u64>,
    /// Continue the run saved in a checkpoint FILE, bit for bit as if uninterrupted.
    #[arg(long, conflicts_with_all = ["file", "method", "step", "t_end", "out", "every", "format", "no_output", "checkpoint"])]
    resume: Option<PathBuf>,
    /// Write the summary as one JSON object to FILE, or to standard output with `-` or no
    /// value.
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    json: Option<String>,
    /// Reversible adaptive steps (Hairer-Soderlind) with accuracy EPS: h = EPS / z, z the
    /// step density rho carried by a symmetric recursion; symmetric methods only (the EA,
    /// EX and FS families); replaces --step, the last step lands on t_end.
    #[arg(long, value_name = "EPS", allow_negative_numbers = true, conflicts_with_all = ["step", "resume", "checkpoint"])]
    adaptive: Option<f64>,
    /// The step density of --adaptive: `omega` (|Omega|, the default) or `torque`
    /// ((|Omega|^2 + |T|/I_min)^(1/2)); for eccentric-satellite `orbit` (the default,
    /// (mu/r^3)^(1/2)), `omega` or `orbit+omega`.
    #[arg(long, requires = "adaptive")]
    rho: Option<String>,
    /// Orbits to integrate (eccentric-satellite only) [default: 1].
    #[arg(long, allow_negative_numbers = true, conflicts_with_all = ["t_end", "file", "resume"])]
    orbits: Option<f64>,
    /// Write a self-contained 3-D animation of the run (HTML) to FILE, sampled every
    /// `--every` steps.
    #[arg(long, conflicts_with = "resume")]
    view: Option<PathBuf>,
}

fn format_key(f: Format) -> &'static str {
    match f {
        Format::Csv => "csv",
        Format::Npy => "npy",
    }
}

/// The settings of a new run from the scenario and the command line.
fn new_settings(args: &RunArgs) -> Result<(Settings, Scenario), Failure> {
    // A file is read once: the checkpoint keeps the very text that was parsed.
    let (sc, source) = match &args.file {
        Some(path) => {
            let (sc, text) = scenario::load_with_text(path).map_err(Failure::Input)?;
            let source = Source::File {
                path: path.display().to_string(),
                text,
            };
            (sc, source)
        }
        None => (
            scenario::builtin(&args.problem).map_err(Failure::Input)?,
            Source::Builtin(args.problem.clone()),
        ),
    };
    let method = match &args.method {
        Some(m) => parse_method(m)?,
        None => sc.method,
    };
    let step = match args.step {
        Some(h) => check_positive("step", h)?,
        None => sc.step,
    };
    let t_end = match args.t_end {
        Some(t) if !t.is_finite() => {
            return Err(Failure::Input(format!("--t-end must be a finite number, found {t}")));
        }
        Some(t) if t < sc.initial.t => {
            return Err(Failure::Input(format!(
                "--t-end {} is before the start time {}",
                Num(t),
                Num(sc.initial.t)
            )));
        }
        Some(t) => t,
        None => sc.t_end,
    };
    let every = args.every.or(sc.output.every).unwrap_or(1);
    let output = if args.no_output {
        None
    } else {
        let path = args
            .out
            .clone()
            .or(sc.output.path.clone().map(PathBuf::from))
            .unwrap_or_else(|| "trajectory.csv".into());
        let format = args.format.or(sc.output.format).unwrap_or_else(|| {
            if path.extension().is_some_and(|x| x == "npy") {
                Format::Npy
            } else {
                Format::Csv
            }
        });
        Some((path.display().to_string(), format_key(format).to_string()))
    };
    let checkpoint = args.checkpoint.as_ref().map(|p| {
        (
            p.display().to_string(),
            args.checkpoint_every.unwrap_or(CHECKPOINT_EVERY),
        )
    });
    Ok((
        Settings {
            source,
            method: method.key().into(),
            step,
            t_end,
            every,
            output,
            checkpoint,
        },
        sc,
    ))
}

/// The scenario of a checkpoint's settings.
fn scenario_of(settings: &Settings) -> Result<Scenario, Failure> {
    match &settings.source {
        Source::Builtin(name) => scenario::builtin(name).map_err(Failure::Input),
        Source::File { path, text } => {
            scenario::parse(text, path).map_err(|e| Failure::Input(format!("{path} (as saved in the checkpoint): {e}")))
        }
    }
}

/// The change of the conserved momentum component (the largest component when all are
/// conserved); `None` under a constant torque, which conserves none.
fn conserved_change(conservation: Conservation, d0: Vec3, d: Vec3) -> Option<f64> {
    let dm = d - d0;
    match conservation {
        Conservation::Free => Some(dm.max_abs()),
        Conservation::Gravity(g) => Some(dm.dot(g).abs()),
        Conservation::Driven => None,
    }
}

fn row(s: &liemid::RigidState, d: &liemid::Diagnostics) -> [f64; 17] {
    let r = s.rotation.to_row_major();
    let p = d.spatial_momentum;
    [
        s.t, s.pi.x, s.pi.y, s.pi.z, r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], d.energy, p.x, p.y, p.z,
    ]
}

/// Refuse (exit 2) a trajectory of about `steps` steps written every `every` beyond
/// [`MAX_TRAJECTORY_BYTES`], unless `--allow-large-output`.
pub(super) fn check_trajectory_size(
    path: &str,
    steps: f64,
    every: u64,
    format: Format,
    allow_large_output: bool,
) -> Result<(), Failure> {
    let rows = (steps / every as f64).floor() + 2.0;
    let bytes = rows * row_bytes(format);
    if bytes > MAX_TRAJECTORY_BYTES && !allow_large_output {
        let fits = ((steps * row_bytes(format)) / 1e8).ceil().max(1.0);
        return Err(Failure::Input(format!(
            "{path}: the trajectory would take about {:.1} GB ({rows:.3e} rows, every {every} {}), more than \
             the 4 GiB limit; write fewer rows (--every {fits:.0} makes about 100 MB) or give \
             --allow-large-output",
            bytes / 1e9,
            plural(every, "step", "steps"),
        )));
    }
    Ok(())
}

/// Run `liemid run`.
pub fn run(args: RunArgs) -> CmdResult {
    if args.file.is_none() && args.resume.is_none() && args.problem == satellite::PROBLEM {
        let unsupported = [
            ("--view", args.view.is_some()),
            ("--out", args.out.is_some()),
            ("--every", args.every.is_some()),
            ("--format", args.format.is_some()),
            ("--checkpoint", args.checkpoint.is_some()),
            ("--t-end", args.t_end.is_some()),
        ];
        if let Some((flag, _)) = unsupported.iter().find(|(_, given)| *given) {
            let instead = if *flag == "--t-end" { "; give --orbits" } else { "" };
            return Err(Failure::Input(format!(
                "{flag} is not available for --problem {}: its run reports the final attitude and \
                 orbit only{instead} (a rigid-body scenario takes {flag}, with or without --adaptive)",
                satellite::PROBLEM
            )));
        }
        return satellite::run(&satellite::RunRequest {
            method: args.method.as_deref(),
            adaptive: args.adaptive,
            rho: args.rho.as_deref(),
            step: args.step,
            orbits: args.orbits.unwrap_or(1.0),
            json: args.json.as_deref(),
            max_steps: args.max_steps,
        });
    }
    if args.orbits.is_some() {
        return Err(Failure::Input(format!(
            "--orbits is for --problem {} only; give --t-end",
            satellite::PROBLEM
        )));
    }
    let resumed = args
        .resume
        .as_ref()
        .map(|p| Checkpoint::read(p))
        .transpose()
        .map_err(Failure::Input)?;
    let (settings, sc) = match &resumed {
        Some(c) => (c.settings.clone(), scenario_of(&c.settings)?),
        None => new_settings(&args)?,
    };
    let method = RotationMethod::from_key(&settings.method)
        .ok_or_else(|| Failure::Input(format!("unknown method `{}` in the checkpoint", settings.method)))?;
    if let Some(eps) = args.adaptive {
        check_positive("adaptive", eps)?;
        method
            .check_reversible()
            .map_err(|e| Failure::Input(format!("--adaptive: {e}")))?;
        return match args.rho.as_deref().unwrap_or("omega") {
            "omega" => run_adaptive(&args, &settings, &sc, method, eps, AngularSpeed),
            "torque" => run_adaptive(&args, &settings, &sc, method, eps, TorqueRate),
            other => Err(Failure::Input(format!(
                "--rho {other}: unknown step density for a rigid body (known: omega, torque)"
            ))),
        };
    }
    let steps = liemid::step_count(sc.initial.t, settings.t_end, settings.step).map_err(|e| {
        Failure::Input(format!(
            "--step {} and --t-end {}: {e}",
            Num(settings.step),
            Num(settings.t_end)
        ))
    })?;
    crate::shared::command::check_steps(steps, args.max_steps)?;
    let format = match settings.output.as_ref().map(|(_, f)| f.as_str()) {
        Some("npy") => Format::Npy,
        _ => Format::Csv,
    };
    let every = settings.every;
    if let Some((path, _)) = &settings.output {
        check_trajectory_size(path, steps as f64, every, format, args.allow_large_output)?;
    }

    // Every output is checked before the first step.
    let input_paths: Vec<PathBuf> = match (&args.file, &settings.source) {
        (Some(p), _) => vec![p.clone()],
        (None, Source::File { path, .. }) if resumed.is_none() => vec![PathBuf::from(path)],
        _ => vec![],
    };
    let inputs: Vec<&Path> = input_paths.iter().map(PathBuf::as_path).collect();
    let mut plan = OutputPlan::new(&inputs);
    if let Some((path, _)) = &settings.output {
        if path != "-" {
            plan.add("--out", Path::new(path)).map_err(Failure::Input)?;
        }
    }
    if let Some((path, _)) = &settings.checkpoint {
        plan.add("--checkpoint", Path::new(path)).map_err(Failure::Input)?;
    }
    if let Some(path) = &args.view {
        plan.add("--view", path).map_err(Failure::Input)?;
    }
    if let Some(path) = args.json.as_deref().filter(|p| *p != "-") {
        plan.add("--json", Path::new(path)).map_err(Failure::Input)?;
    }

    let system = &sc.system;
    let conservation = system.conservation();
    let mut integrator = method.integrator();
    let (mut run, mut max_conserved) = match &resumed {
        Some(c) => {
            integrator
                .restore_cache(system, c.cache())
                .map_err(|e| Failure::Input(e.to_string()))?;
            (c.run(), c.max_conserved_momentum_change)
        }
        None => {
            let run = Run::new(system, sc.initial, settings.t_end, settings.step)
                .map_err(|e| Failure::Input(format!("{}: {e}", sc.name)))?;
            (run, 0.0)
        }
    };
    let mut writer = match &settings.output {
        None => None,
        Some((path, _)) => Some(
            match resumed.as_ref().and_then(|c| c.written).filter(|_| path != "-") {
                Some(written) => TrajectoryWriter::resume(Path::new(path), format, COLUMNS.len(), written),
                None => TrajectoryWriter::create(Path::new(path), format, &COLUMNS),
            }
            .map_err(Failure::Input)?,
        ),
    };
    let to_stdout = settings.output.as_ref().is_some_and(|(p, _)| p == "-");
    let mut page = args.view.as_ref().map(|_| view_page(&sc));
    let e0 = run.progress.initial.energy;
    let sample = |page: &mut Option<ViewPage>, s: &liemid::RigidState, d: &liemid::Diagnostics| {
        if let Some(p) = page.as_mut() {
            view_frame(p, s, d, e0);
        }
    };
    sample(&mut page, run.state(), &run.progress.initial);
    let checkpoint = |run: &Run, cache, max_conserved, writer: &mut Option<TrajectoryWriter>| -> Result<(), String> {
        let Some((path, _)) = &settings.checkpoint else {
            return Ok(());
        };
        let written = writer.as_mut().map(TrajectoryWriter::sync).transpose()?;
        Checkpoint::new(&settings, run, cache, max_conserved, written).write(Path::new(path))
    };

    let interrupt = Interrupt::install();
    let started = Instant::now();
    let bar = progress(run.total_steps, "steps", run.total_steps >= 200_000);
    bar.set_position(run.progress.steps);
    let initial_momentum = run.progress.initial.spatial_momentum;
    if resumed.is_none() {
        if let Some(w) = writer.as_mut() {
            w.write_row(&row(run.state(), &run.progress.initial))
                .map_err(Failure::Run)?;
        }
    }
    let checkpoint_every = settings.checkpoint.as_ref().map_or(u64::MAX, |(_, n)| *n);
    let failure = loop {
        if run.is_done() {
            break None;
        }
        if let Some((signal, code)) = interrupt.requested() {
            bar.finish_and_clear();
            let saved = match checkpoint(&run, integrator.cache(), max_conserved, &mut writer) {
                Ok(()) => settings
                    .checkpoint
                    .as_ref()
                    .map(|(p, _)| format!("; resume with `liemid run --resume {p}`"))
                    .unwrap_or_default(),
                Err(e) => format!("; {e}"),
            };
            let kept = writer.map(|w| format!("; {}", w.keep_partial())).unwrap_or_default();
            let p = &run.progress;
            return Err(Failure::Signal(
                code,
                format!(
                    "{signal}: stopped at t = {} after {} of {} steps{kept}{saved}",
                    Num(p.state.t),
                    p.steps,
                    run.total_steps
                ),
            ));
        }
        let d = match run.step(&mut integrator, system) {
            Ok(d) => d,
            Err(e) => break Some(format!("{}: {e}", sc.name)),
        };
        if let Some(change) = conserved_change(conservation, initial_momentum, d.spatial_momentum) {
            max_conserved = max_conserved.max(change);
        }
        let k = run.progress.steps;
        if k % every == 0 || run.is_done() {
            sample(&mut page, run.state(), &d);
            if let Some(w) = writer.as_mut() {
                if let Err(e) = w.write_row(&row(run.state(), &d)) {
                    break Some(e);
                }
            }
        }
        if k % checkpoint_every == 0 && !run.is_done() {
            if let Err(e) = checkpoint(&run, integrator.cache(), max_conserved, &mut writer) {
                break Some(e);
            }
        }
        if k % 4096 == 0 {
            bar.set_position(k);
        }
    };
    bar.finish_and_clear();
    let wall = started.elapsed().as_secs_f64();
    if let Some(message) = failure {
        let kept = writer.map(|w| format!("; {}", w.keep_partial())).unwrap_or_default();
        return Err(Failure::Run(format!("{message}{kept}")));
    }
    let trajectory = writer.map(TrajectoryWriter::finish).transpose().map_err(Failure::Run)?;
    let viewed = write_view(page.as_ref(), args.view.as_deref(), run.total_steps)?;
    print_summary(
        &args,
        &settings,
        &sc,
        &run,
        method,
        max_conserved,
        wall,
        trajectory,
        to_stdout,
        None,
    )?;
    print_view_line(viewed, args.json.as_deref() == Some("-") || to_stdout);
    Ok(())
}

/// The page of `--view` for a rigid-body scenario: a box with the body's principal moments.
fn view_page(sc: &Scenario) -> ViewPage {
    let i = liemid::RigidBodySystem::inertia(&sc.system).matrix().m;
    let scene = Scene::RigidBody {
        half_extents: view::box_of_inertia([i[0][0], i[1][1], i[2][2]]),
    };
    ViewPage::new(scene, &sc.name)
}

/// Offer the state `s` (its rotation and spatial momentum) and its relative energy error
/// against `e0` to the page; the page keeps each frame's time, so unequal (adaptive) steps
/// play back at the right pace.
fn view_frame(page: &mut ViewPage, s: &liemid::RigidState, d: &liemid::Diagnostics, e0: f64) {
    let r = row(s, d);
    page.push_frame(
        s.t,
        &r[4..13].iter().chain(&r[14..17]).map(|&v| v as f32).collect::<Vec<_>>(),
    );
    page.energy_error(s.t, (d.energy - e0) / e0.abs().max(f64::MIN_POSITIVE));
}

/// Write the page of `--view` (if any) after a run of `steps` steps; the line to print.
fn write_view(page: Option<&ViewPage>, path: Option<&Path>, steps: u64) -> Result<Option<String>, Failure> {
    match (page, path) {
        (Some(p), Some(path)) => Ok(Some(view::report(
            path,
            p.write(path, steps).map_err(Failure::Run)?,
            steps,
        ))),
        _ => Ok(None),
    }
}

/// Print the line of `--view` after the summary, to standard error when standard output
/// carries JSON or the trajectory.
fn print_view_line(line: Option<String>, to_stderr: bool) {
    if let Some(line) = line {
        if to_stderr {
            eprintln!("{line}");
        } else {
            crate::outln!("{line}");
        }
    }
}

#[derive(Args, Debug)]
pub struct MethodsArgs {
    /// Only the spin-dynamics methods of `liemid spins` (without it: every domain's).
    #[arg(long)]
    pub spins: bool,
    /// As JSON (with `--spins`).
    #[arg(long, requires = "spins")]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct ConvergeArgs {
    /// Built-in problem.
    #[arg(long, default_value = "fast-top")]
    pub problem: String,
    /// Scenario file (TOML) instead of a built-in problem.
    #[arg(long, conflicts_with = "problem")]
    pub scenario: Option<PathBuf>,
    /// Comma-separated methods [default: all eight].
    #[arg(long, value_delimiter = ',')]
    pub methods: Option<Vec<String>>,
    /// Comma-separated step sizes [default: 2e-3 halved five times].
    #[arg(long, allow_negative_numbers = true, value_delimiter = ',')]
    pub steps: Option<Vec<f64>>,
    /// End time [default: the problem's].
    #[arg(long, allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Plot file: NAME writes NAME.svg and NAME.png; NAME.svg or NAME.png writes one.
    #[arg(long, default_value = "convergence")]
    pub plot: PathBuf,
    /// Write no plot.
    #[arg(long)]
    pub no_plot: bool,
    /// Write the study as JSON to FILE, or to standard output with `-` or no value (the table then
    /// goes to standard error).
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<String>,
}

/// Print the rigid-body methods: order, torque evaluations a step, what they conserve.
pub fn methods() {
    crate::outln!(
        "{:<11} {:<12} {:>5}  {:<22} conserves",
        "name",
        "method",
        "order",
        "torque evals/step"
    );
    for m in RotationMethod::ALL {
        crate::outln!(
            "{:<11} {:<12} {:>5}  {:<22} {}",
            m.key(),
            m.name(),
            m.order(),
            m.torque_evaluations_per_step(),
            m.description()
        );
    }
}

fn load_scenario(file: Option<&Path>, problem: &str) -> Result<Scenario, Failure> {
    match file {
        Some(path) => scenario::load(path).map_err(Failure::Input),
        None => scenario::builtin(problem).map_err(Failure::Input),
    }
}

/// Run `liemid converge`.
pub fn converge_cmd(args: ConvergeArgs) -> CmdResult {
    let sc = load_scenario(args.scenario.as_deref(), &args.problem)?;
    let methods: Vec<RotationMethod> = match &args.methods {
        None => RotationMethod::PAPER.to_vec(),
        Some(list) => list.iter().map(|m| parse_method(m.trim())).collect::<Result<_, _>>()?,
    };
    let steps: Vec<f64> = match &args.steps {
        None => (0..6).map(|k| 2e-3 / f64::from(1u32 << k)).collect(),
        Some(list) => list
            .iter()
            .map(|&h| check_positive("steps", h))
            .collect::<Result<_, _>>()?,
    };
    if steps.is_empty() || methods.is_empty() {
        return Err(Failure::Input("--steps and --methods must not be empty".into()));
    }
    let t_end = study_end(&sc, args.t_end)?;
    check_study_outputs(args.scenario.as_deref(), &args.plot, args.no_plot, args.json.as_deref())?;
    let study = converge::study(&sc, &methods, &steps, t_end, &Bar::new())
        .map_err(|e| Failure::Run(format!("reference: {e}")))?;
    report(
        &converge::table(&study),
        &study,
        study.figure(),
        &args.plot,
        args.no_plot,
        args.json.as_deref(),
    )
}

/// The end time of a study: `--t-end` if given (after the start), else the scenario's.
fn study_end(sc: &Scenario, t_end: Option<f64>) -> Result<f64, Failure> {
    match t_end {
        Some(t) if !t.is_finite() => Err(Failure::Input(format!("--t-end must be a finite number, found {t}"))),
        Some(t) if t > sc.initial.t => Ok(t),
        Some(t) => Err(Failure::Input(format!(
            "--t-end {} must be after the start time {}",
            Num(t),
            Num(sc.initial.t)
        ))),
        None => Ok(sc.t_end),
    }
}

/// Run `liemid work-precision`.
pub fn work_precision_cmd(args: WorkPrecisionArgs) -> CmdResult {
    if args.scenario.is_none() && args.problem == satellite::PROBLEM {
        return satellite::work_precision(&args);
    }
    let sc = load_scenario(args.scenario.as_deref(), &args.problem)?;
    let entries: Vec<work_precision::Entry> = match &args.methods {
        None if args.adaptive => {
            let mut v = work_precision::Entry::all();
            v.extend(work_precision::Entry::adaptive());
            v
        }
        None => work_precision::Entry::all(),
        Some(list) => list
            .iter()
            .map(|m| {
                work_precision::Entry::from_key(m.trim()).ok_or_else(|| {
                    Failure::Input(format!(
                        "unknown method `{}` (see `liemid methods`, or dop853)",
                        m.trim()
                    ))
                })
            })
            .collect::<Result<_, _>>()?,
    };
    let entries = if args.adaptive && args.methods.is_some() {
        let mut v = entries.clone();
        for e in &entries {
            if let work_precision::Entry::Fixed(m) = e {
                if m.check_reversible().is_ok() {
                    v.push(work_precision::Entry::Adaptive(*m));
                }
            }
        }
        v
    } else {
        entries
    };
    let t_end = study_end(&sc, args.t_end)?;
    let options = work_precision::Options {
        entries,
        repetitions: args.repetitions as usize,
        budget: check_positive("budget", args.budget)?,
        min_error: check_positive("min-error", args.min_error)?,
        max_points: args.max_points.max(1),
    };
    check_study_outputs(args.scenario.as_deref(), &args.plot, args.no_plot, args.json.as_deref())?;
    let study = work_precision::study(&sc, t_end, &options, &Bar::new()).map_err(Failure::Run)?;
    report(
        &work_precision::table(&study),
        &study,
        study.figure(),
        &args.plot,
        args.no_plot,
        args.json.as_deref(),
    )
}
