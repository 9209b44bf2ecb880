//! The library behind the `liemid` command, shared with the Python package: scenario files
//! and built-in problems, output files and checkpoints, the convergence and
//! work-precision studies (with the DOP853 baseline) and their plots.
//!
//! The commands themselves (`run`, `many`, and the front ends of the studies) are in the
//! binary.

pub mod baseline;
pub mod beam_scenario;
pub mod beam_study;
pub mod checkpoint;
pub mod converge;
pub mod interrupt;
pub mod npy;
pub mod output;
pub mod plot;
pub mod scenario;
pub mod spin_scenario;
pub mod spin_study;
pub mod work_precision;
pub mod xyz;
