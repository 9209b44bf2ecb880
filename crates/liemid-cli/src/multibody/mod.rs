//! Jointed rigid bodies: `liemid multibody` (`command`) and the model files, scenario files
//! and built-in problems it runs (`scenario`).

pub mod command;
pub mod scenario;
