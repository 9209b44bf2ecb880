//! Spin lattices: the spin scenario file and built-in lattices (`scenario`), the
//! work-precision study (`study`).

pub mod scenario;
pub mod study;
