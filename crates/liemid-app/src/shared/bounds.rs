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
}
