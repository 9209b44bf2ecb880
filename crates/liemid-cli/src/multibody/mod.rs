//! Jointed rigid bodies: `liemid multibody` (`command`), its runs in joint coordinates
//! (`joint_run`: RK4 and the DOP853 reference) and where a run's observations go (`sink`).
//! The model and scenario files (`scenario`) and the `--view` page (`view`) are the
//! application crate's, named here as the command uses them.

pub mod command;
mod joint_run;
mod sink;

pub use liemid_app::multibody::{scenario, view};
