//! Whether a run's storage fits the machine, asked before anything is allocated: a lattice
//! or a body count that does not fit is refused with the memory it would need and the memory
//! available, instead of aborting on an allocation midway.

/// The memory available to a new allocation (`MemAvailable` of `/proc/meminfo`), if the
/// system says.
#[must_use]
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// `Ok` when `bytes` fit in 80 % of the available memory (or the system does not say).
///
/// # Errors
/// One line: `what` would need so many GB, more than 80 % of the GB available.
pub fn check_fits(what: &str, bytes: f64) -> Result<(), String> {
    check_fits_in(what, bytes, available_memory())
}

fn check_fits_in(what: &str, bytes: f64, available: Option<u64>) -> Result<(), String> {
    match available {
        Some(free) if bytes > 0.8 * free as f64 => Err(format!(
            "{what} would need about {:.1} GB, more than 80 % of the {:.1} GB of memory available",
            bytes / 1e9,
            free as f64 / 1e9
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_need_beyond_the_memory_is_named_with_both_sizes() {
        let e = check_fits_in("1e8 sites", 40e9, Some(24_000_000_000)).unwrap_err();
        assert!(e.contains("about 40.0 GB") && e.contains("24.0 GB"), "{e}");
        assert!(check_fits_in("1e6 sites", 0.4e9, Some(24_000_000_000)).is_ok());
        assert!(check_fits_in("unknown", 1e15, None).is_ok());
    }
}
