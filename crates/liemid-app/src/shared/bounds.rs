//! The step bound every run is held to before its first step, in every domain and front end:
//! a mistyped end time is refused at once instead of running for days (or filling a disk).

/// The most steps a run takes unless the caller allows more (`--max-steps`, Python's
/// `max_steps`): 10⁹. A rigid body's run of that length takes a few minutes, a robot's hours.
pub const DEFAULT_MAX_STEPS: u64 = 1_000_000_000;

/// `Ok` when `steps` is within `max_steps` ([`DEFAULT_MAX_STEPS`] when `None`).
///
/// # Errors
/// One line: the steps the run would take and the bound, naming `flag` (`--max-steps`,
/// `max_steps`) as the way to allow more.
pub fn check_steps(steps: u64, max_steps: Option<u64>, flag: &str) -> Result<(), String> {
    let max = max_steps.unwrap_or(DEFAULT_MAX_STEPS);
    if steps <= max {
        return Ok(());
    }
    let bound = match max_steps {
        Some(m) => format!("{flag} {m}"),
        None => format!("the default bound of {DEFAULT_MAX_STEPS} ({flag} N to allow more)"),
    };
    Err(format!("the run would take {steps} steps, more than {bound}"))
}

/// The steps of an adaptive run at the start's pace: `(t_end − t0) z / ε`, with `z` the
/// start's step density (the run's control) and `ε` its accuracy.
#[must_use]
pub fn adaptive_estimate((t0, t_end): (f64, f64), control: f64, eps: f64) -> f64 {
    (t_end - t0) * control / eps
}

/// The step bound of an adaptive run, after its pre-flight: the steps at the start's pace
/// ([`adaptive_estimate`]), refused when beyond `max_steps` ([`DEFAULT_MAX_STEPS`] when
/// `None`). A run whose pace slows later is to be stopped at the returned bound.
///
/// `flags` name the accuracy and the bound as the caller's user gives them
/// (`("--adaptive", "--max-steps")` for the command, `("adaptive", "max_steps")` for Python).
///
/// # Errors
/// One line: the accuracy, the end time, the estimate, the start's step and the bound.
pub fn check_adaptive_steps(
    span: (f64, f64),
    control: f64,
    eps: f64,
    max_steps: Option<u64>,
    (eps_flag, max_flag): (&str, &str),
) -> Result<u64, String> {
    let estimate = adaptive_estimate(span, control, eps);
    let bound = max_steps.unwrap_or(DEFAULT_MAX_STEPS);
    if !estimate.is_nan() && estimate <= bound as f64 {
        return Ok(bound);
    }
    let limit = match max_steps {
        Some(m) => format!("{max_flag} {m}"),
        None => format!("the default bound of {DEFAULT_MAX_STEPS} ({max_flag} N to allow more)"),
    };
    Err(format!(
        "{eps_flag} {eps:e} to t = {:e}: about {estimate:.1e} steps at the start's step {:.1e}, more than {limit}",
        span.1,
        eps / control
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_names_itself_and_the_way_to_allow_more() {
        assert!(check_steps(DEFAULT_MAX_STEPS, None, "--max-steps").is_ok());
        let e = check_steps(DEFAULT_MAX_STEPS + 1, None, "--max-steps").unwrap_err();
        assert!(e.contains("default bound of 1000000000 (--max-steps N"), "{e}");
        let e = check_steps(11, Some(10), "max_steps").unwrap_err();
        assert_eq!(e, "the run would take 11 steps, more than max_steps 10");
    }

    #[test]
    fn an_adaptive_run_is_bounded_at_the_start_pace() {
        let flags = ("adaptive", "max_steps");
        assert_eq!(
            check_adaptive_steps((0.0, 1.0), 10.0, 0.1, None, flags),
            Ok(DEFAULT_MAX_STEPS)
        );
        assert_eq!(check_adaptive_steps((0.0, 1.0), 10.0, 0.1, Some(100), flags), Ok(100));
        let e = check_adaptive_steps((0.0, 1.0), 10.0, 0.1, Some(99), flags).unwrap_err();
        assert_eq!(
            e,
            "adaptive 1e-1 to t = 1e0: about 1.0e2 steps at the start's step 1.0e-2, more than max_steps 99"
        );
        let e = check_adaptive_steps((0.0, 1e300), 1.0, 1e-300, None, ("--adaptive", "--max-steps")).unwrap_err();
        assert!(e.contains("(--max-steps N to allow more)"), "{e}");
    }
}
