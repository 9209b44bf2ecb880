//! Spin lattices: `liemid spins` and `liemid spins work-precision` (`command`). The spin
//! scenario file (`scenario`) and the work-precision study (`study`) are the application
//! crate's, named here as the command uses them.

pub mod command;

pub use liemid_app::spin::{scenario, study};
