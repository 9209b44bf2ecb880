//! The arguments and method keys that `liemid work-precision` shares with the satellite's
//! study (`satellite.rs`).

use std::path::PathBuf;

use clap::Args;
use liemid::RotationMethod;

use crate::shared::command::Failure;

#[derive(Args, Debug)]
pub struct WorkPrecisionArgs {
    /// Built-in problem.
    #[arg(long, default_value = "fast-top")]
    pub problem: String,
    /// Scenario file (TOML) instead of a built-in problem.
    #[arg(long, conflicts_with = "problem")]
    pub scenario: Option<PathBuf>,
    /// End time [default: the problem's].
    #[arg(long, allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Comma-separated methods, `dop853` for the adaptive baseline [default: all].
    #[arg(long, value_delimiter = ',')]
    pub methods: Option<Vec<String>>,
    /// Timed repetitions per point; the median is reported (at least 5).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(5..))]
    pub repetitions: u64,
    /// Stop a method's sequence once one run takes longer than this many seconds.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.5)]
    pub budget: f64,
    /// Stop a method's sequence once its attitude error is below this.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1e-11)]
    pub min_error: f64,
    /// At most this many points per method.
    #[arg(long, default_value_t = 16)]
    pub max_points: usize,
    /// Plot file: NAME writes NAME.svg and NAME.png; NAME.svg or NAME.png writes one.
    #[arg(long, default_value = "work-precision")]
    pub plot: PathBuf,
    /// Write no plot.
    #[arg(long)]
    pub no_plot: bool,
    /// Write the study as JSON to FILE, or to standard output with `-` or no value.
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<String>,
    /// Add the reversible adaptive family (EA, EX and their compositions, density |Omega|);
    /// with --problem eccentric-satellite, the satellite's own study (fixed and adaptive
    /// EA/EX, the adaptive compositions, DOP853 on the full orbit + attitude ODE).
    #[arg(long)]
    pub adaptive: bool,
    /// With --problem eccentric-satellite --adaptive: instead of the study, N orbits with
    /// the adaptive --drift-method at --drift-eps against DOP853 at the same CPU time; the
    /// energy and angular momentum errors per orbit go to --plot.
    #[arg(long, requires = "adaptive")]
    pub drift_orbits: Option<u32>,
    /// The method of the drift run.
    #[arg(long, default_value = "liemid-ea4", requires = "drift_orbits")]
    pub drift_method: String,
    /// The eps of the drift run.
    #[arg(long, default_value_t = 0.05, requires = "drift_orbits")]
    pub drift_eps: f64,
}

/// The rotation method named `name`, or an input error listing them.
pub fn parse_method(name: &str) -> Result<RotationMethod, Failure> {
    RotationMethod::from_key(name).ok_or_else(|| {
        let known: Vec<&str> = RotationMethod::ALL.iter().map(|m| m.key()).collect();
        Failure::Input(format!("unknown method `{name}` (known: {})", known.join(", ")))
    })
}
