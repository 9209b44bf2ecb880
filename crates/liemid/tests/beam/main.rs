//! The beam domain (one test binary): frames and the corotational element (`frames`), the
//! impulse method and Newmark's tangent (`impulse`), selective mass scaling (`mass_scaling`).

#[path = "../common/beam_runs.rs"]
mod beam_runs;

mod frames;
mod impulse;
mod mass_scaling;
