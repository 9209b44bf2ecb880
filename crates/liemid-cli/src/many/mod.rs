//! Many interacting rigid bodies: `liemid many` (`command`); its scenario file
//! (`scenario`) is the application crate's.

pub mod command;

pub use liemid_app::many::scenario;
