//! The beam domain (one test binary): frames and the corotational element (`frames`), the
//! impulse method and Newmark's tangent (`impulse`), selective mass scaling (`mass_scaling`),
//! and the symplecticity of the explicit methods (`symplectic`).

#[path = "../common/beam_runs.rs"]
mod beam_runs;
#[path = "../common/cotangent.rs"]
mod cotangent;

mod frames;
mod impulse;
mod mass_scaling;
mod symplectic;
