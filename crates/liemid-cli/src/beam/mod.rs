//! Flexible beams: `liemid beam` and `liemid beam work-precision` (`command`), the
//! structure file and built-in frames (`scenario`), the sampled runs and the study against
//! Newmark (`study`).

pub mod command;
pub mod scenario;
pub mod study;
