//! Spin lattices: `liemid spins` and `liemid spins work-precision` (`command`), the spin
//! scenario file and built-in lattices (`scenario`), the work-precision study (`study`).

pub mod command;
pub mod scenario;
pub mod study;
