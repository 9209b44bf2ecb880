//! CPU time of the calling thread or of the whole process, for studies that compare codes
//! on a shared machine: the load of other processes stretches wall-clock time but not the
//! CPU time a run itself uses.

/// Seconds of CPU time the calling thread has used (`clock_gettime` with
/// `CLOCK_THREAD_CPUTIME_ID`, nanosecond resolution); on other platforms, or if the clock
/// fails, wall-clock seconds since the first call.
#[must_use]
pub fn thread_seconds() -> f64 {
    #[cfg(unix)]
    {
        let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: `ts` is a valid, writable `timespec` and the clock id is a constant.
        if unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) } == 0 {
            return ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9;
        }
    }
    wall_seconds()
}

/// Seconds of CPU time all threads of this process have used (`clock_gettime` with
/// `CLOCK_PROCESS_CPUTIME_ID`), for runs that use a team of threads; on other platforms,
/// or if the clock fails, wall-clock seconds since the first call.
#[must_use]
pub fn process_seconds() -> f64 {
    #[cfg(unix)]
    {
        let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: `ts` is a valid, writable `timespec` and the clock id is a constant.
        if unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) } == 0 {
            return ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9;
        }
    }
    wall_seconds()
}

fn wall_seconds() -> f64 {
    use std::sync::OnceLock;
    use std::time::Instant;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_time_advances_with_work() {
        let t0 = thread_seconds();
        let mut x = 0.0f64;
        for k in 0..2_000_000 {
            x += (f64::from(k) * 1e-6).sin();
        }
        std::hint::black_box(x);
        assert!(thread_seconds() > t0);
    }

    #[test]
    fn process_time_counts_other_threads() {
        let t0 = process_seconds();
        let worker = std::thread::spawn(|| {
            let t = thread_seconds();
            let mut x = 0.0f64;
            for k in 0..2_000_000 {
                x += (f64::from(k) * 1e-6).sin();
            }
            std::hint::black_box(x);
            thread_seconds() - t
        });
        let worked = worker.join().unwrap();
        assert!(process_seconds() - t0 >= 0.9 * worked, "{worked}");
    }
}
