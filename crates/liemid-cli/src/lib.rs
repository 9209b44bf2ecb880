//! The library behind the `liemid` command, shared with the Python package. One folder per
//! domain, each with the same parts: `command` (the subcommand: arguments, the run, its
//! summary), `scenario` (the TOML file format and the built-in problems) and `study`
//! (work-precision and convergence studies); `shared` holds what every domain uses
//! (output files, checkpoints, `.npy`, extended XYZ, plots, interrupts and progress, how a
//! command fails).

pub mod beam;
pub mod many;
pub mod multibody;
pub mod rigid;
pub mod shared;
pub mod spin;
