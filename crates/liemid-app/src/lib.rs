//! What the `liemid` command and the Python package share, above the library and below
//! their front ends: scenario files and built-in problems, the studies, output files
//! (trajectories, checkpoints, `.npy`, extended XYZ) and the 3-D page of a run. One folder
//! per domain, with `scenario` (the file format) and, where the domain has one, `study`;
//! `shared` holds what every domain uses. Nothing here parses arguments, draws a progress
//! bar, catches signals or renders a plot: those belong to the command line.

pub mod beam;
pub mod many;
pub mod multibody;
pub mod rigid;
pub mod shared;
pub mod spin;
