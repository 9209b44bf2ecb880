//! Many interacting rigid bodies: `liemid many` (`command`) and its scenario file
//! (`scenario`).

pub mod command;
pub mod scenario;
