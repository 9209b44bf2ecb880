//! `liemid beam`: run a flexible-beam structure (built-in benchmark or TOML file) with the
//! explicit midpoint Lie splitting or the implicit Newmark baseline; displacement
//! histories of the named nodes as CSV/.npy, JSON and a plot. `liemid beam
//! work-precision`: CPU time against the error of the elbow history, both methods.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use serde_json::json;

use crate::beam::scenario::{self, BeamScenario};
use crate::beam::study::{self, RunFailure};
use crate::shared::command::pool;
use crate::shared::command::{emit_json, CmdResult, Failure};
use crate::shared::interrupt::Interrupt;
use crate::shared::output::Format;
use crate::shared::output::{OutputPlan, TrajectoryWriter};
use crate::shared::plot::{self, Histories};
use crate::shared::view;

/// Arguments of `liemid beam`.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true)]
pub struct BeamArgs {
    #[command(subcommand)]
    pub command: Option<BeamCommand>,
    /// Structure file (TOML); without it, `--problem`.
    pub file: Option<PathBuf>,
    /// Built-in problem: right-angle-cantilever (default), cantilever-vibration, flying-beam.
    #[arg(long)]
    pub problem: Option<String>,
    /// Elements per member [default: the problem's or the file's].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..100_000))]
    pub elements_per_member: Option<u64>,
    /// liemid (order 2), liemid4 (order 4), liemid-mts (order 2, axial forces in
    /// substeps), liemid-sms (order 2, selective mass scaling of the axial waves) or
    /// newmark [default: the file's, else liemid].
    #[arg(long)]
    pub method: Option<String>,
    /// The node rotations of the liemid methods: midpoint (EA's pair of midpoint half
    /// steps) or variational (the pair of liemid-eav, a Lie-Poisson drift: the step is
    /// then symplectic) [default: the file's, else midpoint].
    #[arg(long)]
    pub drift: Option<String>,
    /// Step [default: 0.9 of the critical step; 0.05 for newmark].
    #[arg(long, allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// End time [default: the problem's].
    #[arg(long, allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Output interval in time [default: the file's, else t_end/600].
    #[arg(long, allow_negative_numbers = true)]
    pub sample: Option<f64>,
    /// Run an explicit step above the critical one anyway.
    #[arg(long)]
    pub force_step: bool,
    /// Refuse runs of more than N steps (exit 2) before the first step [default: 10⁹].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_steps: Option<u64>,
    /// Threads [default: all cores]; results are identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub threads: Option<u64>,
    /// Displacement histories: t, energy, then NAME_ux, NAME_uy, NAME_uz per tracked node
    /// (CSV or .npy by extension).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Plot the tracked displacements (.svg or .png).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// The displacement components to plot, any of x, y, z.
    #[arg(long, default_value = "xyz")]
    pub components: String,
    /// Reference points drawn on the plot: a CSV `node,t,value` (lines starting with `#`
    /// are comments), e.g. a published curve of the tracked nodes.
    #[arg(long, requires = "plot")]
    pub compare: Option<PathBuf>,
    /// Write the summary as JSON to FILE, or to standard output with `-` or no value.
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<String>,
    /// Write a self-contained 3-D animation of the run (HTML) to FILE: the deformed centre
    /// line and the section frames at every sample.
    #[arg(long)]
    pub view: Option<PathBuf>,
}

/// Subcommands of `liemid beam`.
#[derive(clap::Subcommand, Debug)]
pub enum BeamCommand {
    /// CPU time to the error of the elbow history on the right-angle cantilever: the
    /// explicit splittings against implicit Newmark.
    WorkPrecision(WorkPrecisionArgs),
}

/// Arguments of `liemid beam work-precision`.
#[derive(clap::Args, Debug)]
pub struct WorkPrecisionArgs {
    /// Elements per leg.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u64).range(1..1000))]
    pub elements_per_member: u64,
    /// Timed repetitions per point (the fastest is kept).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..100))]
    pub repetitions: u64,
    /// Threads [default: 1, the fair setting against serial Newmark].
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub threads: u64,
    /// Write the study as JSON to FILE, or to standard output with `-` or no value.
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<String>,
}

fn load(args: &BeamArgs) -> Result<BeamScenario, Failure> {
    let elements = args.elements_per_member.map(|n| n as usize);
    let mut sc = match (&args.file, &args.problem) {
        (Some(_), Some(_)) => return Err(Failure::Input("give a structure file or --problem, not both".into())),
        (Some(f), None) => scenario::load(f, elements),
        (None, p) => scenario::builtin(p.as_deref().unwrap_or("right-angle-cantilever"), elements),
    }
    .map_err(Failure::Input)?;
    if let Some(m) = &args.method {
        sc.method = scenario::integrator(m).map_err(Failure::Input)?;
    }
    if let Some(d) = &args.drift {
        sc.drift = scenario::drift(d).map_err(|e| Failure::Input(format!("--drift: {e}")))?;
    }
    if let Some(h) = args.step {
        sc.step = Some(h);
    }
    if let Some(t) = args.t_end {
        sc.problem.t_end = t;
    }
    if let Some(s) = args.sample {
        sc.sample = Some(s);
    }
    Ok(sc)
}

/// Run `liemid beam`.
pub fn beam(args: BeamArgs) -> CmdResult {
    if let Some(BeamCommand::WorkPrecision(wp)) = &args.command {
        return work_precision(wp);
    }
    let input = Failure::Input;
    let sc = load(&args)?;
    let inputs: Vec<&Path> = args.file.iter().map(PathBuf::as_path).collect();
    let mut plan = OutputPlan::new(&inputs);
    if let Some(p) = &args.out {
        plan.add("--out", p).map_err(input)?;
    }
    if let Some(p) = &args.plot {
        if !matches!(p.extension().and_then(|x| x.to_str()), Some("svg" | "png")) {
            return Err(input(format!("--plot {}: use a .svg or .png file name", p.display())));
        }
        plan.add("--plot", p).map_err(input)?;
    }
    if let Some(j) = args.json.as_deref().filter(|j| *j != "-") {
        plan.add("--json", Path::new(j)).map_err(input)?;
    }
    if let Some(p) = &args.view {
        plan.add("--view", p).map_err(input)?;
    }
    if args.components.is_empty() || !args.components.chars().all(|c| "xyz".contains(c)) {
        return Err(input(format!("--components {}: use some of x, y, z", args.components)));
    }
    let reference = match &args.compare {
        Some(p) => reference_points(p).map_err(input)?,
        None => Vec::new(),
    };
    let t_end = sc.problem.t_end;
    let sample = sc.sample.unwrap_or(t_end / 600.0);
    let pool = pool(args.threads)?;
    let threads = pool.current_num_threads();
    let interrupt = Interrupt::install();
    let signal: Mutex<Option<u8>> = Mutex::new(None);
    let result = pool.install(|| {
        let title = args.view.as_ref().map(|_| sc.name.as_str());
        study::run_viewed(
            &sc,
            t_end,
            study::Stepping {
                step: sc.step,
                sample,
                force_step: args.force_step,
                max_steps: args.max_steps,
            },
            &mut |t| {
                interrupt.requested().map(|(name, code)| {
                    *signal.lock().expect("not poisoned") = Some(code);
                    format!("{name}: stopped at t = {t}; nothing was written")
                })
            },
            title,
        )
    });
    let (run, page) = match result {
        Ok(r) => r,
        Err(RunFailure::Input(m)) => return Err(Failure::Input(m)),
        Err(RunFailure::Numerical(m)) => {
            return Err(match *signal.lock().expect("not poisoned") {
                Some(code) => Failure::Signal(code, m),
                None => Failure::Run(m),
            })
        }
    };
    if let Some(p) = &args.out {
        let mut columns: Vec<String> = vec!["t".into(), "energy".into()];
        for (n, _) in &run.tracked {
            for c in ["ux", "uy", "uz"] {
                columns.push(format!("{n}_{c}"));
            }
        }
        let names: Vec<&str> = columns.iter().map(String::as_str).collect();
        let format = if p.extension().and_then(|x| x.to_str()) == Some("npy") {
            Format::Npy
        } else {
            Format::Csv
        };
        let mut w = TrajectoryWriter::create(p, format, &names).map_err(Failure::Run)?;
        for (k, t) in run.t.iter().enumerate() {
            let mut row = vec![*t, run.energy.get(k).copied().unwrap_or(f64::NAN)];
            for (_, u) in &run.tracked {
                row.extend(u[k]);
            }
            w.write_row(&row).map_err(Failure::Run)?;
        }
        w.finish().map_err(Failure::Run)?;
    }
    if let Some(p) = &args.plot {
        let mut lines = Vec::new();
        for (n, u) in &run.tracked {
            for (c, axis) in ["x", "y", "z"].iter().enumerate() {
                if !args.components.contains(axis) {
                    continue;
                }
                let v: Vec<(f64, f64)> = run.t.iter().zip(u).map(|(t, u)| (*t, u[c])).collect();
                if v.iter().any(|p| p.1.abs() > 1e-9 * (1.0 + t_end)) {
                    lines.push((format!("{n} u_{axis}"), v));
                }
            }
        }
        let title = format!(
            "{}: {} elements, {}{} h = {:.3e}",
            sc.name,
            run.elements,
            run.method.key(),
            drift_note(&run),
            run.step
        );
        plot::histories(
            p,
            &Histories {
                title: &title,
                x_desc: "t",
                y_desc: "displacement",
                lines: &lines,
                points: &reference,
            },
        )
        .map_err(Failure::Run)?;
    }
    if let (Some(p), Some(path)) = (&page, &args.view) {
        let line = view::report(path, p.write(path, run.steps).map_err(Failure::Run)?, run.steps);
        if args.json.as_deref() == Some("-") {
            eprintln!("{line}");
        } else {
            crate::outln!("{line}");
        }
    }
    let mut summary = run.json(&sc.name);
    summary["threads"] = json!(threads);
    emit_json(args.json.as_deref(), &summary)?;
    if args.json.as_deref() != Some("-") {
        crate::outln!(
            "{} ({}{}): {} elements, {} steps of {:.4e} to t = {} on {threads} thread(s): {:.3} s, {:.3e} element-steps/s",
            sc.name,
            run.method.key(),
            drift_note(&run),
            run.elements,
            run.steps,
            run.step,
            format!("{:.6}", run.t.last().copied().unwrap_or(0.0)).trim_end_matches('0').trim_end_matches('.'),
            run.wall_seconds,
            run.element_steps_per_second()
        );
        crate::outln!(
            "critical step of the explicit splitting {:.4e} (omega_max <= {:.4e})",
            run.critical_step,
            run.omega_bound
        );
        if let Some(beta) = run.axial_mass {
            crate::outln!("axial mass scaling: stretch inertia {beta:.4} times the element mass");
        }
        if let Some(it) = run.newton_iterations {
            crate::outln!(
                "Newton iterations {it} ({:.2} per step)",
                it as f64 / run.steps.max(1) as f64
            );
        }
        let loads_end = sc
            .problem
            .frame
            .loads
            .iter()
            .map(|l| l.history.end())
            .fold(0.0, f64::max);
        let after: Vec<f64> = run
            .t
            .iter()
            .zip(&run.energy)
            .filter(|(t, _)| **t >= loads_end)
            .map(|(_, e)| *e)
            .collect();
        if let Some(&e0) = after.first() {
            let scale = e0.abs().max(1e-300);
            let de = after.iter().map(|e| (e - e0).abs() / scale).fold(0.0, f64::max);
            crate::outln!("max relative energy change after the loads (t >= {loads_end}) {de:.3e}");
        }
        for (n, u) in &run.tracked {
            let (mut hi, mut lo) = ((f64::MIN, 0.0), (f64::MAX, 0.0));
            for (t, u) in run.t.iter().zip(u) {
                if u[2] > hi.0 {
                    hi = (u[2], *t);
                }
                if u[2] < lo.0 {
                    lo = (u[2], *t);
                }
            }
            crate::outln!(
                "{n:>8}: u_z max {:.4} at t = {:.2}, min {:.4} at t = {:.2}",
                hi.0,
                hi.1,
                lo.0,
                lo.1
            );
        }
    }
    Ok(())
}

/// `", variational drift"` when the run's node rotations are not the default midpoint ones.
fn drift_note(run: &study::BeamRun) -> String {
    match run.drift {
        Some(d) if d != liemid::beam::Drift::Midpoint => format!(", {} drift", d.key()),
        _ => String::new(),
    }
}

/// A labelled set of points `(t, value)`.
type PointSet = (String, Vec<(f64, f64)>);

/// Labelled point sets from a `node,t,value` CSV.
fn reference_points(path: &Path) -> Result<Vec<PointSet>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("--compare {}: {e}", path.display()))?;
    let mut sets: Vec<PointSet> = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with("node,") {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        let parsed = (f.len() == 3).then(|| (f[1].trim().parse::<f64>(), f[2].trim().parse::<f64>()));
        let Some((Ok(t), Ok(v))) = parsed else {
            return Err(format!(
                "--compare {}: line {}: expected `node,t,value`",
                path.display(),
                k + 1
            ));
        };
        let label = format!("{} (reference)", f[0].trim());
        match sets.iter_mut().find(|(l, _)| *l == label) {
            Some((_, pts)) => pts.push((t, v)),
            None => sets.push((label, vec![(t, v)])),
        }
    }
    Ok(sets)
}

fn work_precision(args: &WorkPrecisionArgs) -> CmdResult {
    if let Some(j) = args.json.as_deref().filter(|j| *j != "-") {
        OutputPlan::new(&[])
            .add("--json", Path::new(j))
            .map_err(Failure::Input)?;
    }
    let pool = pool(Some(args.threads))?;
    let (points, reference_error) = pool
        .install(|| study::work_precision(args.elements_per_member as usize, args.repetitions as usize))
        .map_err(|e| match e {
            RunFailure::Input(m) => Failure::Input(m),
            RunFailure::Numerical(m) => Failure::Run(m),
        })?;
    let to_stdout = args.json.as_deref() != Some("-");
    let say = |s: String| {
        if to_stdout {
            crate::outln!("{s}");
        } else {
            eprintln!("{s}");
        }
    };
    say(format!(
        "right-angle cantilever, {} elements per leg, t = 30; error = max_t |u_elbow - u_ref| / max_t |u_ref| \
         (reference liemid4 at 0.2 of its critical step, its own error {reference_error:.1e})",
        args.elements_per_member
    ));
    say(format!(
        "{:<9} {:>11} {:>11} {:>11}",
        "method", "step", "CPU s", "error"
    ));
    for p in &points {
        say(format!(
            "{:<9} {:>11.4e} {:>11.4} {:>11.3e}",
            p.method, p.step, p.seconds, p.error
        ));
    }
    let mut targets = serde_json::Map::new();
    for target in [1e-2, 1e-3] {
        let mut row = serde_json::Map::new();
        for m in ["liemid", "liemid4", "liemid-mts", "liemid-sms", "newmark"] {
            let v = study::time_to_error(&points, m, target);
            say(format!(
                "CPU time to {target:e}: {m:<8} {}",
                match v {
                    Some((s, true)) => format!("{s:.4} s"),
                    Some((s, false)) => format!("{s:.4} s (already below the target at the largest step run)"),
                    None => "not reached".into(),
                }
            ));
            row.insert(m.into(), json!(v.map(|x| x.0)));
        }
        targets.insert(format!("{target:e}"), serde_json::Value::Object(row));
    }
    let value = json!({
        "problem": "right-angle-cantilever",
        "elements_per_leg": args.elements_per_member,
        "reference_error": reference_error,
        "points": points.iter().map(|p| json!({"method": p.method, "step": p.step, "seconds": p.seconds, "error": p.error})).collect::<Vec<_>>(),
        "time_to_error": targets,
    });
    emit_json(args.json.as_deref(), &value)
}
