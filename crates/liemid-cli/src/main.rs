//! `liemid`: run rigid-body scenarios, write trajectories, and reproduce the convergence
//! study of the explicit midpoint Lie paper.

mod beam_cmd;
mod many_cmd;
mod run_cmd;
mod spins_cmd;

use liemid_cli::{converge, output, plot, scenario, work_precision};

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use liemid::error::Num;
use liemid::RotationMethod;

use output::OutputPlan;
use scenario::Scenario;

const EXAMPLES: &str = "\
Examples:
  liemid run                                   fast top, LIEMID[EA], h = 1e-4, to t = 0.8
  liemid run examples/tennis_racket.toml --out flip.npy --every 10
  liemid run --problem slow-top --method rk4 --step 1e-4 --json
  liemid converge                              the paper's Figure 1: table + convergence.svg/.png
  liemid converge --methods liemid-ea,liemid-i --steps 1e-3,5e-4,2.5e-4 --json -
  liemid work-precision                        CPU time vs error, against DOP853 and RK4
  liemid many --model dipoles --bodies 10000   a dipolar fluid on all cores
  liemid spins --problem square-64             spin dynamics on a 64x64 lattice
  liemid methods [--spins]";

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
    Run(run_cmd::RunArgs),
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
    /// Atomistic spin dynamics on a lattice: run a scenario, or `spins work-precision`.
    #[command(after_help = "Examples:\n  liemid spins --problem square-64 --json -\n  \
        liemid spins examples/spins_square.toml --final final.npy --snapshot spins.png\n  \
        liemid spins work-precision --threads 1 --json spin-wp.json")]
    Spins(spins_cmd::SpinsArgs),
    /// Flexible 3-D beams (corotational elements, nodes as rigid bodies): a benchmark or a
    /// structure file, or `beam work-precision` against implicit Newmark.
    #[command(
        after_help = "Examples:\n  liemid beam --problem right-angle-cantilever --plot elbow.svg\n  \
        liemid beam examples/right_angle_cantilever.toml --elements-per-member 16 --json run.json\n  \
        liemid beam --method newmark --step 0.05 --out newmark.csv\n  liemid beam work-precision"
    )]
    Beam(beam_cmd::BeamArgs),
    /// List the integrators: name, order, torque evaluations, what they conserve.
    Methods(MethodsArgs),
    /// List the built-in problems.
    Problems,
}

#[derive(Args, Debug)]
struct MethodsArgs {
    /// The spin-dynamics methods of `liemid spins` instead of the rigid-body ones.
    #[arg(long)]
    spins: bool,
    /// As JSON (with `--spins`).
    #[arg(long, requires = "spins")]
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

/// How a command failed: bad input (exit 2), a failed run (exit 1), or a stop asked for by
/// a signal (exit 130 for SIGINT, 143 for SIGTERM).
pub(crate) enum Failure {
    Input(String),
    Run(String),
    Signal(u8, String),
}

pub(crate) type CmdResult = Result<(), Failure>;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help, --version: their text, exit 0.
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = e.print();
            return ExitCode::from(2);
        }
        Err(e) => {
            eprintln!("liemid: error: {}", usage_error(&e.render().to_string()));
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Run(args) => run_cmd::run(args),
        Command::Converge(args) => converge_cmd(args),
        Command::WorkPrecision(args) => work_precision_cmd(args),
        Command::Many(args) => many_cmd::many(&args),
        Command::Spins(args) => spins_cmd::spins(args),
        Command::Beam(args) => beam_cmd::beam(args),
        Command::Methods(args) => {
            if args.spins {
                spins_cmd::methods(args.json);
            } else {
                methods();
            }
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
        Err(Failure::Signal(code, m)) => {
            eprintln!("liemid: {}", one_line(&m));
            ExitCode::from(code)
        }
    }
}

/// clap's message in one line: its first line without the `error: ` prefix, the possible
/// values if it lists them, and where to find help.
fn usage_error(rendered: &str) -> String {
    let mut lines = rendered.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("invalid arguments");
    let first = first
        .strip_prefix("error: ")
        .unwrap_or(first)
        .replace(" is not in 1..18446744073709551615", " must be at least 1");
    let values = rendered
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("[possible values:"))
        .map(|l| format!(" {l}"))
        .unwrap_or_default();
    format!("{first}{values} (see `liemid --help`)")
}

fn one_line(m: &str) -> String {
    m.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn methods() {
    println!(
        "{:<11} {:<12} {:>5}  {:<22} conserves",
        "name", "method", "order", "torque evals/step"
    );
    for m in RotationMethod::ALL {
        println!(
            "{:<11} {:<12} {:>5}  {:<22} {}",
            m.key(),
            m.name(),
            m.order(),
            m.torque_evaluations_per_step(),
            m.description()
        );
    }
}

pub(crate) fn parse_method(name: &str) -> Result<RotationMethod, Failure> {
    RotationMethod::from_key(name).ok_or_else(|| {
        let known: Vec<&str> = RotationMethod::ALL.iter().map(|m| m.key()).collect();
        Failure::Input(format!("unknown method `{name}` (known: {})", known.join(", ")))
    })
}

pub(crate) fn check_positive(name: &str, v: f64) -> Result<f64, Failure> {
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

use plot::plot_paths;

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
    check_study_outputs(args.scenario.as_deref(), &args.plot, args.no_plot, args.json.as_deref())?;
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

/// Check a study's plot and JSON paths before it runs (a study takes seconds to minutes).
fn check_study_outputs(scenario: Option<&Path>, plot: &Path, no_plot: bool, json: Option<&str>) -> CmdResult {
    let inputs: Vec<&Path> = scenario.into_iter().collect();
    let mut plan = OutputPlan::new(&inputs);
    if !no_plot {
        for p in plot_paths(plot) {
            plan.add("--plot", &p).map_err(Failure::Input)?;
        }
    }
    if let Some(j) = json.filter(|j| *j != "-") {
        plan.add("--json", Path::new(j)).map_err(Failure::Input)?;
    }
    Ok(())
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
        output::write_atomically(Path::new(target), (text + "\n").as_bytes())
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
    check_study_outputs(args.scenario.as_deref(), &args.plot, args.no_plot, args.json.as_deref())?;
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
