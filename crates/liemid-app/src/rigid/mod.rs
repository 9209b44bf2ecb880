//! A rigid body about a fixed point: the scenario file and the built-in tops (`scenario`),
//! the work-precision study (`study`), the convergence study of the paper's Figure 1
//! (`converge`) and the DOP853 baseline (`baseline`).

pub mod baseline;
pub mod converge;
pub mod scenario;
pub mod study;
