//! `liemid`: run rigid-body scenarios, write trajectories, and reproduce the convergence
//! study of the explicit midpoint Lie paper.

mod baseline;
mod converge;
mod many_cmd;
mod output;
mod plot;
mod scenario;
mod work_precision;

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Args, Parser, Subcommand};
use liemid::{integrate, RotationIntegrator, RotationMethod};
use serde_json::json;

use output::TrajectoryWriter;
use scenario::{Format, Scenario};

const EXAMPLES: &str = "\
Examples:
  liemid run                                   fast top, LIEMID[EA], h = 1e-4, to t = 0.8
  liemid run examples/tennis_racket.toml --out flip.npy --every 10
  liemid run --problem slow-top --method rk4 --step 1e-4 --json
  liemid converge                              the paper's Figure 1: table + convergence.svg/.png
  liemid converge --methods liemid-ea,liemid-i --steps 1e-3,5e-4,2.5e-4 --json -
  liemid work-precision                        CPU time vs error, against DOP853 and RK4
  liemid many --model dipoles --bodies 10000   a dipolar fluid on all cores
  liemid methods";

/// The command line (its help text is the `about` below).
#[derive(Parser, Debug)]
#[command(
    name = "liemid",
    version,
    about = "Structure-preserving integration of rigid-body rotation with the explicit midpoint Lie methods (LIEMID[E1], [E2], [EA]) and their comparison line-up",
    long_about = None,
    after_help = EXAMPLES
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Integrate one scenario, write its trajectory and print a summary.
    #[command(
        after_help = "Examples:\n  liemid run\n  liemid run examples/fast_top.toml --every 10\n  \
        liemid run --problem free-body --out flip.npy --json"
    )]
    Run(RunArgs),
    /// Errors of every method against a reference for a sequence of steps, with plots.
    #[command(
        after_help = "Examples:\n  liemid converge\n  liemid converge --problem slow-top --plot slow\n  \
        liemid converge --scenario examples/fast_top.toml --methods liemid-ea,rk4 --json study.json"
    )]
    Converge(ConvergeArgs),
    /// CPU time against accuracy for every method and the DOP853 and RK4 baselines.
    #[command(
        after_help = "Examples:\n  liemid work-precision\n  liemid work-precision --t-end 100 --plot long\n  \
        liemid work-precision --methods liemid-ea,liemid-ea8,rk4,dop853 --json wp.json"
    )]
    WorkPrecision(WorkPrecisionArgs),
    /// Step N interacting rigid bodies in parallel; throughput and conservation.
    #[command(
        after_help = "Examples:\n  liemid many --model torque-free --bodies 1000000 --t-end 0.01\n  \
        liemid many --model dipoles --bodies 4000 --t-end 1 --threads 2 --json -"
    )]
    Many(many_cmd::ManyArgs),
    /// List the integrators: name, order, torque evaluations, what they conserve.
    Methods,
    /// List the built-in problems.
    Problems,
}

#[derive(Args, Debug)]
struct RunArgs {
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
    /// Trajectory file [default: the scenario's [output] path, else trajectory.csv].
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
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
struct ConvergeArgs {
    /// Built-in problem.
    #[arg(long, default_value = "fast-top")]
    problem: String,
    /// Scenario file (TOML) instead of a built-in problem.
    #[arg(long, conflicts_with = "problem")]
    scenario: Option<PathBuf>,
    /// Comma-separated methods [default: all eight].
    #[arg(long, value_delimiter = ',')]
    methods: Option<Vec<String>>,
    /// Comma-separated step sizes [default: 2e-3 halved five times].
    #[arg(long, allow_negative_numbers = true, value_delimiter = ',')]
    steps: Option<Vec<f64>>,
    /// End time [default: the problem's].
    #[arg(long, allow_negative_numbers = true)]
    t_end: Option<f64>,
    /// Plot file: NAME writes NAME.svg and NAME.png; NAME.svg or NAME.png writes one.
    #[arg(long, default_value = "convergence")]
    plot: PathBuf,
    /// Write no plot.
    #[arg(long)]
    no_plot: bool,
    /// Write the study as JSON to FILE, or to standard output with `-` (the table then
    /// goes to standard error).
    #[arg(long)]
    json: Option<String>,
}

#[derive(Args, Debug)]
struct WorkPrecisionArgs {
    /// Built-in problem.
    #[arg(long, default_value = "fast-top")]
    problem: String,
    /// Scenario file (TOML) instead of a built-in problem.
    #[arg(long, conflicts_with = "problem")]
    scenario: Option<PathBuf>,
    /// End time [default: the problem's].
    #[arg(long, allow_negative_numbers = true)]
    t_end: Option<f64>,
    /// Comma-separated methods, `dop853` for the adaptive baseline [default: all].
    #[arg(long, value_delimiter = ',')]
    methods: Option<Vec<String>>,
    /// Timed repetitions per point; the median is reported (at least 5).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(5..))]
    repetitions: u64,
    /// Stop a method's sequence once one run takes longer than this many seconds.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.5)]
    budget: f64,
    /// Stop a method's sequence once its attitude error is below this.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1e-11)]
    min_error: f64,
    /// At most this many points per method.
    #[arg(long, default_value_t = 16)]
    max_points: usize,
    /// Plot file: NAME writes NAME.svg and NAME.png; NAME.svg or NAME.png writes one.
    #[arg(long, default_value = "work-precision")]
    plot: PathBuf,
    /// Write no plot.
    #[arg(long)]
    no_plot: bool,
    /// Write the study as JSON to FILE, or to standard output with `-`.
    #[arg(long)]
    json: Option<String>,
}

/// How a command failed: bad input (exit 2) or a failed run (exit 1).
enum Failure {
    Input(String),
    Run(String),
}

type CmdResult = Result<(), Failure>;

fn input<E: std::fmt::Display>(e: E) -> Failure {
    Failure::Input(e.to_string())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run(args),
        Command::Converge(args) => converge_cmd(args),
        Command::WorkPrecision(args) => work_precision_cmd(args),
        Command::Many(args) => {
            many_cmd::many(&args).map_err(|(code, m)| if code == 2 { Failure::Input(m) } else { Failure::Run(m) })
        }
        Command::Methods => {
            methods();
            Ok(())
        }
        Command::Problems => {
            for name in scenario::PROBLEMS {
                println!("{name:<11} {}", scenario::describe(name));
            }
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(m)) => {
            eprintln!("liemid: error: {}", one_line(&m));
            ExitCode::from(2)
        }
        Err(Failure::Run(m)) => {
            eprintln!("liemid: error: {}", one_line(&m));
            ExitCode::from(1)
        }
    }
}

fn one_line(m: &str) -> String {
    m.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn methods() {
    println!(
        "{:<10} {:<11} {:>5}  {:<22} conserves",
        "name", "method", "order", "torque evals/step"
    );
    for m in RotationMethod::ALL {
        println!(
            "{:<10} {:<11} {:>5}  {:<22} {}",
            m.key(),
            m.name(),
            m.order(),
            m.torque_evaluations_per_step(),
            m.description()
        );
    }
}

fn parse_method(name: &str) -> Result<RotationMethod, Failure> {
    RotationMethod::from_key(name).ok_or_else(|| {
        let known: Vec<&str> = RotationMethod::ALL.iter().map(|m| m.key()).collect();
        Failure::Input(format!("unknown method `{name}` (known: {})", known.join(", ")))
    })
}

fn check_positive(name: &str, v: f64) -> Result<f64, Failure> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(Failure::Input(format!("--{name} must be a positive number, found {v}")))
    }
}

fn load_scenario(file: Option<&Path>, problem: &str) -> Result<Scenario, Failure> {
    match file {
        Some(path) => scenario::load(path).map_err(Failure::Input),
        None => scenario::builtin(problem).map_err(Failure::Input),
    }
}

/// A progress line on stderr for long runs on a terminal.
struct Progress {
    enabled: bool,
    total: u64,
    next: u64,
}

impl Progress {
    fn new(total: u64) -> Self {
        Progress {
            enabled: total >= 200_000 && std::io::stderr().is_terminal(),
            total,
            next: 0,
        }
    }
    fn update(&mut self, k: u64) {
        if self.enabled && k >= self.next {
            let pct = 100 * k / self.total.max(1);
            eprint!("\r[{:<40}] {pct:>3}%", "#".repeat((pct as usize * 40) / 100));
            let _ = std::io::stderr().flush();
            self.next = k + self.total / 100;
        }
    }
    fn finish(&self) {
        if self.enabled {
            eprint!("\r{:<60}\r", "");
        }
    }
}

fn run(args: RunArgs) -> CmdResult {
    let mut sc = load_scenario(args.file.as_deref(), &args.problem)?;
    if let Some(m) = &args.method {
        sc.method = parse_method(m)?;
    }
    if let Some(h) = args.step {
        sc.step = check_positive("step", h)?;
    }
    if let Some(t) = args.t_end {
        if !(t.is_finite() && t >= sc.initial.t) {
            return Err(Failure::Input(format!(
                "--t-end {t} is before the start time {}",
                sc.initial.t
            )));
        }
        sc.t_end = t;
    }
    let steps = liemid::step_count(sc.initial.t, sc.t_end, sc.step).map_err(input)?;
    let every = args.every.or(sc.output.every).unwrap_or(1);
    let path = if args.no_output {
        None
    } else {
        Some(
            args.out
                .clone()
                .or(sc.output.path.clone().map(PathBuf::from))
                .unwrap_or_else(|| "trajectory.csv".into()),
        )
    };
    let format = args.format.or(sc.output.format).unwrap_or_else(|| match &path {
        Some(p) if p.extension().is_some_and(|x| x == "npy") => Format::Npy,
        _ => Format::Csv,
    });
    let mut writer = match &path {
        Some(p) => Some(
            TrajectoryWriter::create(p, format)
                .map_err(|e| Failure::Input(format!("{}: cannot create: {e}", output::partial_path(p).display())))?,
        ),
        None => None,
    };

    let mut integrator = sc.method.integrator();
    let mut progress = Progress::new(steps);
    let started = Instant::now();
    let result = integrate(
        &mut integrator,
        &sc.system,
        sc.initial,
        sc.t_end,
        sc.step,
        every,
        |k, s, d| {
            progress.update(k);
            if let Some(w) = writer.as_mut() {
                let r = s.rotation.to_row_major();
                let p = d.spatial_momentum;
                let row = [
                    s.t, s.pi.x, s.pi.y, s.pi.z, r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], d.energy, p.x,
                    p.y, p.z,
                ];
                w.write_row(&row)
                    .map_err(|e| format!("writing {}: {e}", w.partial().display()))?;
            }
            Ok(())
        },
    );
    let wall = started.elapsed().as_secs_f64();
    progress.finish();
    let summary = match result {
        Ok(s) => s,
        Err(e) => {
            let kept = writer
                .as_ref()
                .map(|w| format!("; the {} rows written are kept in {}", w.rows(), w.partial().display()))
                .unwrap_or_default();
            return Err(Failure::Run(format!("{}: {e}{kept}", sc.name)));
        }
    };
    let trajectory = match writer {
        Some(w) => {
            let partial = w.partial().to_path_buf();
            Some(
                w.finish()
                    .map_err(|e| Failure::Run(format!("finishing {}: {e}", partial.display())))?,
            )
        }
        None => None,
    };

    let s = &summary.state;
    if args.json {
        let out = json!({
            "problem": sc.name,
            "method": sc.method.key(),
            "step": sc.step,
            "t": s.t,
            "pi": s.pi.to_array(),
            "rotation": s.rotation.to_row_major(),
            "steps": summary.steps,
            "max_energy_error": summary.max_energy_error,
            "max_spatial_momentum_change": summary.max_spatial_momentum_change.to_array(),
            "max_orthogonality_defect": summary.max_orthogonality_defect,
            "wall_time_seconds": wall,
            "trajectory": trajectory.as_ref().map(|(p, rows)| json!({
                "path": p.display().to_string(),
                "rows": rows,
                "format": if format == Format::Npy { "npy" } else { "csv" },
            })),
        });
        println!("{out}");
    } else {
        let r = s.rotation.m;
        let dm = summary.max_spatial_momentum_change;
        println!("{}: {} with h = {} to t = {}", sc.name, integrator.name(), sc.step, s.t);
        println!("steps                          {}", summary.steps);
        println!(
            "final Pi                       [{:.12e}, {:.12e}, {:.12e}]",
            s.pi.x, s.pi.y, s.pi.z
        );
        for (i, row) in r.iter().enumerate() {
            let label = if i == 0 { "final R" } else { "" };
            println!(
                "{label:<30} [{:>19.12e}, {:>19.12e}, {:>19.12e}]",
                row[0], row[1], row[2]
            );
        }
        println!("max relative energy error      {:.3e}", summary.max_energy_error);
        println!(
            "max spatial momentum change    [{:.3e}, {:.3e}, {:.3e}]",
            dm.x, dm.y, dm.z
        );
        println!(
            "max orthogonality defect       {:.3e}",
            summary.max_orthogonality_defect
        );
        println!("wall time                      {wall:.3} s");
        if let Some((p, rows)) = &trajectory {
            println!("trajectory                     {} ({rows} rows)", p.display());
        }
    }
    Ok(())
}

fn plot_paths(base: &Path) -> Vec<PathBuf> {
    match base.extension().and_then(|x| x.to_str()) {
        Some("svg") | Some("png") => vec![base.to_path_buf()],
        _ => {
            let with = |ext: &str| {
                let mut s = base.as_os_str().to_owned();
                s.push(".");
                s.push(ext);
                PathBuf::from(s)
            };
            vec![with("svg"), with("png")]
        }
    }
}

fn converge_cmd(args: ConvergeArgs) -> CmdResult {
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
    let study = converge::study(&sc, &methods, &steps, t_end).map_err(|e| Failure::Run(format!("reference: {e}")))?;
    report(
        &converge::table(&study),
        &study,
        plot::Figure::Convergence(&study),
        &args.plot,
        args.no_plot,
        args.json.as_deref(),
    )
}

/// The end time of a study: `--t-end` if given (after the start), else the scenario's.
fn study_end(sc: &Scenario, t_end: Option<f64>) -> Result<f64, Failure> {
    match t_end {
        Some(t) if t.is_finite() && t > sc.initial.t => Ok(t),
        Some(t) => Err(Failure::Input(format!(
            "--t-end {t} must be after the start time {}",
            sc.initial.t
        ))),
        None => Ok(sc.t_end),
    }
}

/// Print a study's table, write its plots and its JSON. With JSON on standard output
/// (`-`), the table and the messages go to standard error.
fn report<T: serde::Serialize>(
    table: &str,
    study: &T,
    figure: plot::Figure,
    plot_base: &Path,
    no_plot: bool,
    json: Option<&str>,
) -> CmdResult {
    let to_stdout = json == Some("-");
    let say = |m: &str| {
        if to_stdout {
            eprint!("{m}");
        } else {
            print!("{m}");
        }
    };
    say(table);
    if !no_plot {
        for p in plot_paths(plot_base) {
            plot::write(&p, &figure).map_err(Failure::Run)?;
            say(&format!("wrote {}\n", p.display()));
        }
    }
    if let Some(target) = json {
        write_json(target, study)?;
    }
    Ok(())
}

/// Write `value` as JSON to `target` (`-` for standard output), atomically for files.
fn write_json<T: serde::Serialize>(target: &str, value: &T) -> CmdResult {
    let text = serde_json::to_string_pretty(value).map_err(|e| Failure::Run(e.to_string()))?;
    if target == "-" {
        println!("{text}");
    } else {
        let partial = output::partial_path(Path::new(target));
        std::fs::write(&partial, text + "\n")
            .and_then(|()| std::fs::rename(&partial, target))
            .map_err(|e| Failure::Run(format!("{target}: cannot write: {e}")))?;
        println!("wrote {target}");
    }
    Ok(())
}

fn work_precision_cmd(args: WorkPrecisionArgs) -> CmdResult {
    let sc = load_scenario(args.scenario.as_deref(), &args.problem)?;
    let entries: Vec<work_precision::Entry> = match &args.methods {
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
    let t_end = study_end(&sc, args.t_end)?;
    let options = work_precision::Options {
        entries,
        repetitions: args.repetitions as usize,
        budget: check_positive("budget", args.budget)?,
        min_error: check_positive("min-error", args.min_error)?,
        max_points: args.max_points.max(1),
    };
    let study = work_precision::study(&sc, t_end, &options).map_err(Failure::Run)?;
    report(
        &work_precision::table(&study),
        &study,
        plot::Figure::WorkPrecision(&study),
        &args.plot,
        args.no_plot,
        args.json.as_deref(),
    )
}
