//! Many interacting rigid bodies: `liemid many` (`command`); its scenario file
//! (`scenario`) is the application crate's.

pub mod command;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod state;

pub use liemid_app::many::scenario;
