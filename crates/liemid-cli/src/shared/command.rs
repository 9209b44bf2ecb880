//! What every command shares: how it fails (exit codes), number checks, the thread pool,
//! and a study's report (table, plots, JSON), its output paths checked before it runs.

use std::path::Path;

use crate::shared::output::{self, OutputPlan};
use crate::shared::plot::{self, plot_paths};

/// How a command failed: bad input (exit 2), a failed run (exit 1), or a stop asked for by
/// a signal (exit 130 for SIGINT, 143 for SIGTERM).
pub enum Failure {
    Input(String),
    Run(String),
    Signal(u8, String),
}

pub type CmdResult = Result<(), Failure>;

pub fn check_positive(name: &str, v: f64) -> Result<f64, Failure> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(Failure::Input(format!("--{name} must be a positive number, found {v}")))
    }
}

pub use liemid_app::shared::bounds::DEFAULT_MAX_STEPS;

/// Refuse (exit 2), before the first step, a run of `steps` steps beyond `--max-steps`
/// (`max_steps`, [`DEFAULT_MAX_STEPS`] when not given).
pub fn check_steps(steps: u64, max_steps: Option<u64>) -> Result<(), Failure> {
    liemid_app::shared::bounds::check_steps(steps, max_steps, "--max-steps").map_err(Failure::Input)
}

/// The step bound of an adaptive run, after its pre-flight
/// ([`liemid_app::shared::bounds::check_adaptive_steps`]): the steps at the start's pace,
/// refused (exit 2) when beyond `--max-steps` (`max_steps`, [`DEFAULT_MAX_STEPS`] when not
/// given). A run whose pace slows later is stopped at the returned bound.
pub fn check_adaptive_steps(span: (f64, f64), control: f64, eps: f64, max_steps: Option<u64>) -> Result<u64, Failure> {
    liemid_app::shared::bounds::check_adaptive_steps(span, control, eps, max_steps, ("--adaptive", "--max-steps"))
        .map_err(Failure::Input)
}

/// A thread pool of `threads` (at most four per core), or of all cores.
pub fn pool(threads: Option<u64>) -> Result<rayon::ThreadPool, Failure> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(k) = threads {
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        b = b.num_threads(usize::try_from(k).unwrap_or(usize::MAX).min(4 * cores));
    }
    b.build().map_err(|e| Failure::Run(format!("thread pool: {e}")))
}

/// Check a study's plot and JSON paths before it runs (a study takes seconds to minutes).
pub fn check_study_outputs(scenario: Option<&Path>, plot: &Path, no_plot: bool, json: Option<&str>) -> CmdResult {
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
pub fn report<T: serde::Serialize>(
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
            crate::out!("{m}");
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
pub fn write_json<T: serde::Serialize>(target: &str, value: &T) -> CmdResult {
    let text = serde_json::to_string_pretty(value).map_err(|e| Failure::Run(e.to_string()))?;
    if target == "-" {
        crate::outln!("{text}");
    } else {
        output::write_atomically(Path::new(target), (text + "\n").as_bytes())
            .map_err(|e| Failure::Run(format!("{target}: cannot write: {e}")))?;
        crate::outln!("wrote {target}");
    }
    Ok(())
}

/// Write a summary as one line of JSON to `target` (`-` for standard output), atomically
/// for files; nothing without a target.
pub fn emit_json(target: Option<&str>, value: &serde_json::Value) -> CmdResult {
    match target {
        Some("-") => crate::outln!("{value}"),
        Some(path) => output::write_atomically(Path::new(path), (value.to_string() + "\n").as_bytes())
            .map_err(|e| Failure::Run(format!("{path}: cannot write: {e}")))?,
        None => {}
    }
    Ok(())
}
