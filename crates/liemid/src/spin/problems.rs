//! Named spin-dynamics benchmarks.

use super::hamiltonian::SpinSystem;
use super::lattice::{Lattice, LatticeKind};
use crate::linalg::Vec3;
use crate::random::Rng;

/// A spin system, its initial spins and the default step and end time (ps).
#[derive(Clone, Debug)]
pub struct SpinProblem {
    /// Name on the command line.
    pub name: &'static str,
    /// One line.
    pub description: &'static str,
    /// The system.
    pub system: SpinSystem,
    /// Initial spins (unit).
    pub spins: Vec<Vec3>,
    /// Default step (ps).
    pub step: f64,
    /// End time (ps).
    pub t_end: f64,
}

/// The names of the built-in problems.
pub const NAMES: [&str; 2] = ["square-64", "chain-64"];

/// Spins tilted from `+z` by angles uniform in `[0, max_tilt]`, azimuths uniform, from
/// `seed`.
#[must_use]
pub fn near_z(n: usize, max_tilt: f64, seed: u64) -> Vec<Vec3> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let theta = max_tilt * rng.uniform();
            let phi = 2.0 * std::f64::consts::PI * rng.uniform();
            let (st, ct) = theta.sin_cos();
            let (sp, cp) = phi.sin_cos();
            Vec3::new(st * cp, st * sp, ct)
        })
        .collect()
}

/// Issue 17's benchmark, the case run with Spirit: a 64×64 periodic square lattice,
/// `J = 1` meV, `K = 0.1` meV along `z`, `B = 0`, `α = 0`, `μ_s = 1`, to 10 ps, from spins
/// tilted by up to 0.3 rad from `+z` (seed 1).
#[must_use]
pub fn square_64() -> SpinProblem {
    let lattice = Lattice::new(LatticeKind::Square, &[64, 64], true).expect("a valid lattice");
    let system =
        SpinSystem::new(lattice, 1.0, 0.1, Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 1.0, 0.0).expect("valid parameters");
    SpinProblem {
        name: "square-64",
        description: "64x64 periodic square ferromagnet, J = 1 meV, K = 0.1 meV along z, B = 0, start within 0.3 rad of +z, 10 ps",
        spins: near_z(64 * 64, 0.3, 1),
        system,
        step: 1e-2,
        t_end: 10.0,
    }
}

/// A periodic ferromagnetic chain of 64 spins (`J = 1` meV, `K = 0.1` meV along `z`)
/// slightly off `+z` (within 0.05 rad, seed 2): its small deviations are spin waves of
/// `ħω(k) = 2J(1 − cos k) + 2K`.
#[must_use]
pub fn chain_64() -> SpinProblem {
    let lattice = Lattice::new(LatticeKind::Chain, &[64], true).expect("a valid lattice");
    let system =
        SpinSystem::new(lattice, 1.0, 0.1, Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 1.0, 0.0).expect("valid parameters");
    SpinProblem {
        name: "chain-64",
        description:
            "64-spin periodic ferromagnetic chain, J = 1 meV, K = 0.1 meV along z, small deviations (spin waves), 10 ps",
        spins: near_z(64, 0.05, 2),
        system,
        step: 1e-2,
        t_end: 10.0,
    }
}

/// The built-in problem `name`.
#[must_use]
pub fn get(name: &str) -> Option<SpinProblem> {
    match name {
        "square-64" => Some(square_64()),
        "chain-64" => Some(chain_64()),
        _ => None,
    }
}
