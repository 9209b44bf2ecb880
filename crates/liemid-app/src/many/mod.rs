//! Many interacting rigid bodies: the scenario file (`scenario`).

pub mod scenario;
