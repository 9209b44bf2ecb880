//! Flexible beams: the structure file and built-in frames (`scenario`), the sampled runs
//! and the study against Newmark (`study`).

pub mod scenario;
pub mod study;
