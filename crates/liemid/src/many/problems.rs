//! Named many-body problems: ensembles of independent heavy tops or torque-free rotors,
//! and the dipolar fluid, each built from a seed.

use crate::linalg::Vec3;
use crate::rigid::HeavyTop;
use crate::so3;

/// An ensemble of `n` fast Lagrangian tops (rotors about their own pivots) with spread
/// initial conditions: tilt uniform in [0, 0.1] rad about a random horizontal axis, spin
/// `313π (1 ± 10%)`. Returns the bodies (on a grid, 1 m apart) and the gravity model.
#[must_use]
pub fn top_ensemble(n: usize, seed: u64) -> (crate::many::Bodies, crate::interactions::Independent) {
    let top = HeavyTop::lagrangian_block();
    let moments = top.inertia.principal_moments().expect("principal");
    let mut rng = crate::random::Rng::new(seed);
    let mut bodies = crate::many::Bodies::new();
    let side = (n as f64).cbrt().ceil() as usize;
    for i in 0..n {
        let axis = std::f64::consts::TAU * rng.uniform();
        let tilt = 0.1 * rng.uniform();
        let rotation = so3::exp(Vec3::new(axis.cos(), axis.sin(), 0.0) * tilt);
        let spin = 313.0 * std::f64::consts::PI * (0.9 + 0.2 * rng.uniform());
        let pi = moments.component_mul(Vec3::new(0.0, 0.0, spin));
        let pos = Vec3::new(
            (i % side) as f64,
            ((i / side) % side) as f64,
            (i / (side * side)) as f64,
        );
        bodies
            .push(top.mass, moments, false, pos, Vec3::ZERO, rotation, pi)
            .expect("valid body");
    }
    let gravity = crate::interactions::Independent {
        gravity: top.gravity,
        center_of_mass: top.center_of_mass,
    };
    (bodies, gravity)
}

/// `n` torque-free asymmetric rotors, `I = (1, 2, 3) (1 + 10% random)`, random attitudes
/// and body angular momenta of size 10.
#[must_use]
pub fn torque_free_ensemble(n: usize, seed: u64) -> (crate::many::Bodies, crate::interactions::Independent) {
    let mut rng = crate::random::Rng::new(seed);
    let mut bodies = crate::many::Bodies::new();
    for _ in 0..n {
        let moments = Vec3::new(1.0, 2.0, 3.0) * (1.0 + 0.1 * rng.uniform());
        let pi = rng.unit_vector() * 10.0;
        bodies
            .push(1.0, moments, false, Vec3::ZERO, Vec3::ZERO, rng.rotation(), pi)
            .expect("valid body");
    }
    (bodies, crate::interactions::Independent::torque_free())
}

/// The cutoff of [`dipolar_fluid`].
pub const DIPOLAR_FLUID_CUTOFF: f64 = 3.0;

/// A dipolar fluid of `n` free spheres (mass 1, inertia 0.1, dipole `(0, 0, 1)` in the body
/// frame, WCA σ = ε = 1) on a cubic lattice at number density `density` in a periodic box
/// with cutoff 3 (the dipole energy switched off smoothly from 2.4; open space with all pairs
/// when the box is smaller than twice the cutoff),
/// random attitudes, Maxwell velocities at unit temperature with zero total momentum.
///
/// # Errors
/// A density that is not finite and positive.
pub fn dipolar_fluid(
    n: usize,
    density: f64,
    seed: u64,
) -> crate::Result<(crate::many::Bodies, crate::interactions::Dipoles)> {
    dipolar_fluid_with_cutoff(n, density, seed, DIPOLAR_FLUID_CUTOFF)
}

/// [`dipolar_fluid`] with another cutoff (the switch starts at 0.8 of it).
///
/// # Errors
/// A density or cutoff that is not finite and positive.
pub fn dipolar_fluid_with_cutoff(
    n: usize,
    density: f64,
    seed: u64,
    cutoff: f64,
) -> crate::Result<(crate::many::Bodies, crate::interactions::Dipoles)> {
    if !(density.is_finite() && density > 0.0) {
        return Err(crate::Error::InvalidParameter {
            name: "density",
            value: density,
            reason: "must be finite and positive",
        });
    }
    if !(cutoff.is_finite() && cutoff > 0.0) {
        return Err(crate::Error::InvalidParameter {
            name: "cutoff",
            value: cutoff,
            reason: "must be finite and positive",
        });
    }
    let mut rng = crate::random::Rng::new(seed);
    let box_length = (n as f64 / density).cbrt();
    let side = (n as f64).cbrt().ceil() as usize;
    let a = box_length / side as f64;
    let mut momenta: Vec<Vec3> = (0..n)
        .map(|_| Vec3::new(rng.normal(), rng.normal(), rng.normal()))
        .collect();
    let mean = momenta.iter().fold(Vec3::ZERO, |s, p| s + *p) * (1.0 / n.max(1) as f64);
    momenta.iter_mut().for_each(|p| *p -= mean);
    let mut bodies = crate::many::Bodies::new();
    for (i, p) in momenta.into_iter().enumerate() {
        let pos = Vec3::new(
            (i % side) as f64 + 0.5,
            ((i / side) % side) as f64 + 0.5,
            (i / (side * side)) as f64 + 0.5,
        ) * a;
        let pi = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 0.1f64.sqrt();
        bodies.push(1.0, Vec3::new(0.1, 0.1, 0.1), true, pos, p, rng.rotation(), pi)?;
    }
    let (cutoff, box_length) = if box_length >= 2.0 * cutoff {
        (Some(cutoff), Some(box_length))
    } else {
        (None, None)
    };
    let model = crate::interactions::Dipoles::new(Vec3::new(0.0, 0.0, 1.0), 1.0, 1.0, cutoff, box_length)?;
    Ok((bodies, model))
}
