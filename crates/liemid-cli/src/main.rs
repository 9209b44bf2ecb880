//! `liemid`: the command line, wired to the domains (`rigid`, `many`, `spin`, `beam` of
//! the `liemid_cli` library, each with its `command`, `scenario` and `study`); this file
//! only parses the arguments and maps failures to exit codes (2 input, 1 run, 130/143
//! signal).

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use liemid_cli::shared::command::Failure;
use liemid_cli::{beam, many, multibody, rigid, spin};

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
    Run(rigid::command::RunArgs),
    /// Errors of every method against a reference for a sequence of steps, with plots.
    #[command(
        after_help = "Examples:\n  liemid converge\n  liemid converge --problem slow-top --plot slow\n  \
        liemid converge --scenario examples/fast_top.toml --methods liemid-ea,rk4 --json study.json"
    )]
    Converge(rigid::command::ConvergeArgs),
    /// CPU time against accuracy for every method and the DOP853 and RK4 baselines.
    #[command(
        after_help = "Examples:\n  liemid work-precision\n  liemid work-precision --t-end 100 --plot long\n  \
        liemid work-precision --methods liemid-ea,liemid-ea8,rk4,dop853 --json wp.json"
    )]
    WorkPrecision(rigid::command::WorkPrecisionArgs),
    /// Step N interacting rigid bodies in parallel; throughput and conservation.
    #[command(
        after_help = "Examples:\n  liemid many --model torque-free --bodies 1000000 --t-end 0.01\n  \
        liemid many --model dipoles --bodies 4000 --t-end 1 --threads 2 --json -"
    )]
    Many(many::command::ManyArgs),
    /// Jointed rigid bodies from MJCF, URDF or a built-in problem (RATTLE on the explicit
    /// midpoint Lie step).
    Multibody(multibody::command::MultibodyArgs),
    /// Atomistic spin dynamics on a lattice: run a scenario, or `spins work-precision`.
    #[command(after_help = "Examples:\n  liemid spins --problem square-64 --json -\n  \
        liemid spins examples/spins_square.toml --final final.npy --snapshot spins.png\n  \
        liemid spins work-precision --threads 1 --json spin-wp.json")]
    Spins(spin::command::SpinsArgs),
    /// Flexible 3-D beams (corotational elements, nodes as rigid bodies): a benchmark or a
    /// structure file, or `beam work-precision` against implicit Newmark.
    #[command(
        after_help = "Examples:\n  liemid beam --problem right-angle-cantilever --plot elbow.svg\n  \
        liemid beam examples/right_angle_cantilever.toml --elements-per-member 16 --json run.json\n  \
        liemid beam --method newmark --step 0.05 --out newmark.csv\n  liemid beam work-precision"
    )]
    Beam(beam::command::BeamArgs),
    /// List the integrators: name, order, torque evaluations, what they conserve.
    Methods(rigid::command::MethodsArgs),
    /// List the built-in problems of every domain.
    Problems,
}

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
        Command::Run(args) => rigid::command::run(args),
        Command::Converge(args) => rigid::command::converge_cmd(args),
        Command::WorkPrecision(args) => rigid::command::work_precision_cmd(args),
        Command::Many(args) => many::run(&args),
        Command::Multibody(args) => multibody::command::multibody(&args),
        Command::Spins(args) => spin::command::spins(args),
        Command::Beam(args) => beam::command::beam(args),
        Command::Methods(args) => {
            liemid_cli::listing::methods(args.spins, args.json);
            Ok(())
        }
        Command::Problems => {
            liemid_cli::listing::problems();
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

/// clap's message in one line: its first line without the `error: ` prefix, the lines it
/// lists under it (the missing arguments), the possible values if it lists them, and the
/// subcommand's help to read.
fn usage_error(rendered: &str) -> String {
    let lines: Vec<&str> = rendered.lines().map(str::trim).filter(|l| !l.is_empty()).collect();
    let first = lines.first().copied().unwrap_or("invalid arguments");
    let mut first = first
        .strip_prefix("error: ")
        .unwrap_or(first)
        .replace(" is not in 1..18446744073709551615", " must be at least 1");
    if first.ends_with(':') {
        // "the following required arguments were not provided:" and the list below it.
        let listed: Vec<&str> = lines
            .iter()
            .skip(1)
            .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
            .copied()
            .collect();
        first = format!("{first} {}", listed.join(", "));
    }
    let values = lines
        .iter()
        .find(|l| l.starts_with("[possible values:"))
        .map(|l| format!(" {l}"))
        .unwrap_or_default();
    let tip = lines
        .iter()
        .find_map(|l| l.strip_prefix("tip: "))
        .map(|t| format!(" ({t})"))
        .unwrap_or_default();
    // "Usage: liemid run [OPTIONS] <SCENARIO>" names the subcommand whose help to read.
    let command: Vec<&str> = lines
        .iter()
        .find_map(|l| l.strip_prefix("Usage: "))
        .map(|u| {
            u.split_whitespace()
                .take_while(|w| !w.starts_with(['[', '<', '-']))
                .collect()
        })
        .unwrap_or_default();
    let command = if command.is_empty() {
        "liemid".to_string()
    } else {
        command.join(" ")
    };
    format!("{first}{values}{tip} (see `{command} --help`)")
}

fn one_line(m: &str) -> String {
    m.split_whitespace().collect::<Vec<_>>().join(" ")
}
