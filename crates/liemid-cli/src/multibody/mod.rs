//! Jointed rigid bodies: `liemid multibody` (`command`), the model files, scenario files
//! and built-in problems it runs (`scenario`), its runs in joint coordinates (`joint_run`:
//! RK4 and the DOP853 reference), where a run's observations go (`sink`) and its `--view`
//! page (`view`).

pub mod command;
mod joint_run;
pub mod scenario;
mod sink;
pub mod view;
