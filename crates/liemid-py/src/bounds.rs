//! The pre-flight of every Python run, as the command's: the steps within `max_steps`
//! (`liemid_app::shared::bounds`, 10⁹ by default) and the samples the run keeps within the
//! memory (`liemid_app::shared::memory`), checked before the first step and before anything
//! is allocated.

use liemid::error::Num;
use pyo3::exceptions::{PyMemoryError, PyValueError};
use pyo3::prelude::*;

/// The name of the bound in messages.
pub(crate) const MAX_STEPS: &str = "max_steps";

/// `ValueError` when a run of `steps` steps passes `max_steps` (10⁹ when `None`); the
/// message starts with `context` (the arguments that make the steps).
pub(crate) fn check_steps(steps: u64, max_steps: Option<u64>, context: &str) -> PyResult<()> {
    liemid_app::shared::bounds::check_steps(steps, max_steps, MAX_STEPS)
        .map_err(|e| PyValueError::new_err(format!("{context}: {e}")))
}

/// `ValueError` when about `estimate` steps (an estimate, perhaps beyond any integer) pass
/// `max_steps` (10⁹ when `None`); the message starts with `context` (which says what would
/// take them).
pub(crate) fn check_estimate(estimate: f64, max_steps: Option<u64>, context: &str) -> PyResult<()> {
    let bound = max_steps.unwrap_or(liemid_app::shared::bounds::DEFAULT_MAX_STEPS);
    if estimate <= bound as f64 {
        return Ok(());
    }
    let limit = match max_steps {
        Some(m) => format!("{MAX_STEPS} {m}"),
        None => format!(
            "the default bound of {} ({MAX_STEPS} N to allow more)",
            liemid_app::shared::bounds::DEFAULT_MAX_STEPS
        ),
    };
    Err(PyValueError::new_err(format!(
        "{context} about {estimate:.1e} steps, more than {limit}"
    )))
}

/// `MemoryError` when `rows` samples of `numbers` float64 each would not fit in the memory
/// available; the message names both sizes and what to change (`hint`).
pub(crate) fn check_samples(rows: f64, numbers: usize, hint: &str) -> PyResult<()> {
    let bytes = rows * (numbers as f64) * 8.0;
    let what = format!("keeping {} samples of {numbers} numbers", Num(rows.round()));
    liemid_app::shared::memory::check_fits(&what, bytes).map_err(|e| PyMemoryError::new_err(format!("{e}: {hint}")))
}

/// The hint of a sampled run with `every` and `t_end`.
pub(crate) const SAMPLE_HINT: &str = "sample less often (a larger every) or shorten t_end";
