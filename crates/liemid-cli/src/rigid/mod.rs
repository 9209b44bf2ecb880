//! A rigid body about a fixed point: `liemid run` (`command`, also `converge`,
//! `work-precision`, `methods`) and the eccentric satellite (`satellite`). The scenario file
//! and built-in tops (`scenario`), the studies (`study`, `converge`) and the DOP853 baseline
//! (`baseline`) are the application crate's, named here as the command uses them.

pub mod command;
pub mod satellite;

pub use liemid_app::rigid::{baseline, converge, scenario, study};
