//! Named spin-dynamics benchmarks.

use super::hamiltonian::{DmiKind, SpinSystem};
use super::lattice::{Lattice, LatticeKind};
use super::topology::{relax, Relaxation};
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
pub const NAMES: [&str; 3] = ["square-64", "chain-64", "skyrmion"];

/// One line on the built-in problem `name` (without building it: the skyrmion's start is
/// relaxed when it is built).
#[must_use]
pub fn describe(name: &str) -> Option<&'static str> {
    match name {
        "square-64" => Some(SQUARE_64),
        "chain-64" => Some(CHAIN_64),
        "skyrmion" => Some(SKYRMION),
        _ => None,
    }
}

const SQUARE_64: &str =
    "64x64 periodic square ferromagnet, J = 1 meV, K = 0.1 meV along z, B = 0, start within 0.3 rad of +z, 10 ps";
const CHAIN_64: &str =
    "64-spin periodic ferromagnetic chain, J = 1 meV, K = 0.1 meV along z, small deviations (spin waves), 10 ps";
const SKYRMION: &str = "one Neel skyrmion on a 48x48 periodic square lattice, J = 1 meV, interfacial D = 0.3 meV, B = 1.75 T along z, relaxed, then every spin tilted by up to 0.1 rad; undamped, 10 ps";

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
        description: SQUARE_64,
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
        description: CHAIN_64,
        spins: near_z(64, 0.05, 2),
        system,
        step: 1e-2,
        t_end: 10.0,
    }
}

/// The skyrmion problem's system: a 48×48 periodic square lattice, `J = 1` meV,
/// interfacial DMI `D = 0.3` meV (`D_ij = D ẑ × r̂_ij`), `K = 0`, `B = 1.75` T along `z`,
/// `μ_s = 1`, undamped. In units of the continuum, `b = μ_s μ_B B J / D² = 1.13`: above the
/// field (about 0.8) where the skyrmion lattice gives way to the polarised state, so one
/// skyrmion is an isolated metastable texture of radius a few `J/D` (its core about 4 sites
/// across); 48 sites keep it far from its periodic images.
#[must_use]
pub fn skyrmion_system() -> SpinSystem {
    let lattice = Lattice::new(LatticeKind::Square, &[48, 48], true).expect("a valid lattice");
    SpinSystem::new(
        lattice,
        1.0,
        0.0,
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 0.0, 1.75),
        1.0,
        0.0,
    )
    .and_then(|s| s.with_dmi(0.3, DmiKind::Interfacial))
    .expect("valid parameters")
}

/// A Néel skyrmion seed on an `nx × ny` square lattice: core along `−z` at the centre
/// `(nx/2, ny/2)`, polar angle `θ = π (1 − r/radius)` inside `radius` (sites) and `+z`
/// outside, in-plane part along `−r̂` (`inward`, the chirality interfacial DMI with `D > 0`
/// favours in liemid's sign: `E = −D_ij·(S_i × S_j)`) or `+r̂`.
#[must_use]
pub fn skyrmion_seed(nx: usize, ny: usize, radius: f64, inward: bool) -> Vec<Vec3> {
    let (cx, cy) = (0.5 * nx as f64, 0.5 * ny as f64);
    let sign = if inward { -1.0 } else { 1.0 };
    (0..nx * ny)
        .map(|i| {
            let (x, y) = ((i % nx) as f64 + 0.5 - cx, (i / nx) as f64 + 0.5 - cy);
            let r = x.hypot(y);
            if r >= radius {
                return Vec3::new(0.0, 0.0, 1.0);
            }
            let theta = std::f64::consts::PI * (1.0 - r / radius);
            let (st, ct) = theta.sin_cos();
            let (ux, uy) = if r > 0.0 { (x / r, y / r) } else { (1.0, 0.0) };
            Vec3::new(sign * st * ux, sign * st * uy, ct)
        })
        .collect()
}

/// The skyrmion of [`skyrmion_system`] relaxed from [`skyrmion_seed`] (radius 6 sites,
/// centred on a plaquette) by velocity projection to a largest tangent force of 1e-10 meV.
///
/// # Errors
/// If the relaxation does not converge (it does in about 2·10³ iterations).
pub fn skyrmion_relaxed(system: &SpinSystem) -> crate::error::Result<(Vec<Vec3>, Relaxation)> {
    let [nx, ny, _] = system.lattice.size();
    let mut spins = skyrmion_seed(nx, ny, 6.0, true);
    let report = relax(system, &mut spins, 1e-10, 200_000)?;
    Ok((spins, report))
}

/// Every spin of `spins` turned by an angle uniform in `[0, max_tilt]` about a random axis
/// perpendicular to it, from `seed`.
#[must_use]
pub fn tilted(spins: &[Vec3], max_tilt: f64, seed: u64) -> Vec<Vec3> {
    let mut rng = Rng::new(seed);
    spins
        .iter()
        .map(|&s| {
            let angle = max_tilt * rng.uniform();
            let r = rng.unit_vector();
            let axis = s.cross(r);
            let n = axis.norm();
            if n == 0.0 {
                return s;
            }
            crate::so3::exp_apply(axis * (angle / n), s)
        })
        .collect()
}

/// One Néel skyrmion in spin waves ([`skyrmion_system`]): the relaxed skyrmion
/// ([`skyrmion_relaxed`]) with every spin tilted by up to 0.1 rad (seed 3), run undamped
/// to 10 ps. Its topological charge is −1.
///
/// # Panics
/// Never for these fixed parameters (the relaxation converges; tested).
#[must_use]
pub fn skyrmion() -> SpinProblem {
    let system = skyrmion_system();
    let (relaxed, _) = skyrmion_relaxed(&system).expect("the skyrmion relaxes");
    SpinProblem {
        name: "skyrmion",
        description: SKYRMION,
        spins: tilted(&relaxed, 0.1, 3),
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
        "skyrmion" => Some(skyrmion()),
        _ => None,
    }
}
