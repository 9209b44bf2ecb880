//! The library behind the `liemid` command, shared with the Python package. One folder per
//! domain, each with the same parts: `command` (the subcommand: arguments, the run, its
//! summary), `scenario` (the TOML file format and the built-in problems) and `study`
//! (work-precision and convergence studies); `shared` holds what every domain uses
//! (output files, checkpoints, `.npy`, extended XYZ, plots, interrupts and progress, how a
//! command fails).

/// `println!` to standard output that ignores a failed write (a reader such as `head` that
/// has exited closes the pipe): the run goes on, writes its files and exits as it would;
/// `println!` would panic.
#[macro_export]
macro_rules! outln {
    () => {
        $crate::outln!("")
    };
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// `print!` to standard output that ignores a failed write (see [`outln!`]).
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), $($arg)*);
    }};
}

pub mod beam;
pub mod listing;
pub mod many;
pub mod multibody;
pub mod rigid;
pub mod shared;
pub mod spin;
