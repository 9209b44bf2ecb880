//! Named test problems with their initial states (and exact solutions where they exist),
//! shared by the tests, the benchmarks and the command-line tool.

use crate::inertia::Inertia;
use crate::linalg::{Mat3, Vec3};
use crate::rigid::{FreeBody, HeavyTop, RigidState};
use crate::so3;
use crate::vector::{MassMatrix, MechanicalSystem, PhaseState};

/// A rigid-body problem: a system, an initial state and a default end time.
#[derive(Clone, Debug)]
pub struct RigidProblem<S> {
    /// Short name, e.g. `fast-top`.
    pub name: &'static str,
    /// One line on what it is.
    pub description: &'static str,
    /// The system.
    pub system: S,
    /// The initial state at `t = 0`.
    pub initial: RigidState,
    /// The default end time.
    pub t_end: f64,
}

fn block_top(name: &'static str, description: &'static str, spin: f64) -> RigidProblem<HeavyTop> {
    let system = HeavyTop::lagrangian_block();
    let initial = RigidState::from_angular_velocity(
        0.0,
        &system.inertia,
        Vec3::new(0.0, 0.0, spin),
        so3::exp(Vec3::new(0.05, 0.0, 0.0)),
    );
    RigidProblem {
        name,
        description,
        system,
        initial,
        t_end: 0.8,
    }
}

/// The fast Lagrangian top of the paper (`heavy-top.md`): an aluminium block spinning at
/// `Ω₀ = (0, 0, 313π)` rad/s, tilted by 0.05 rad about `e₁`, to `t = 0.8` s.
#[must_use]
pub fn fast_top() -> RigidProblem<HeavyTop> {
    block_top(
        "fast-top",
        "fast Lagrangian top: aluminium block, spin 313*pi rad/s, tilt 0.05 rad, t = 0.8 s",
        313.0 * std::f64::consts::PI,
    )
}

/// The same top spinning slower, `Ω₀ = (0, 0, 90π)` rad/s.
#[must_use]
pub fn slow_top() -> RigidProblem<HeavyTop> {
    block_top(
        "slow-top",
        "slow Lagrangian top: the same block, spin 90*pi rad/s, t = 0.8 s",
        90.0 * std::f64::consts::PI,
    )
}

/// A torque-dominated top, where the first-order torque error of E1 and E2 is visible:
/// `I = diag(5, 5, 1)`, `m = 1`, centre of mass `(0, 0, 1)`, `g = 9.81`,
/// `R₀ = exp(0.3 e₁)`, `Ω₀ = (0, 0, 20)`, to `t = 1`.
#[must_use]
pub fn torque_dominated_top() -> RigidProblem<HeavyTop> {
    let inertia = Inertia::principal([5.0, 5.0, 1.0]).expect("positive");
    let system = HeavyTop::new(inertia, 1.0, Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -9.81)).expect("finite");
    let initial = RigidState::from_angular_velocity(
        0.0,
        &inertia,
        Vec3::new(0.0, 0.0, 20.0),
        so3::exp(Vec3::new(0.3, 0.0, 0.0)),
    );
    RigidProblem {
        name: "torque-top",
        description: "torque-dominated top: I = diag(5, 5, 1), m = 1, X = (0, 0, 1), spin 20 rad/s, t = 1 s",
        system,
        initial,
        t_end: 1.0,
    }
}

/// A torque-dominated asymmetric top, where the free spin is slow against the torque and
/// the exact flow gains little over the midpoint rule: `I = diag(5, 4, 1.5)`, `m = 1`,
/// centre of mass `(0, 0, 1)`, `g = 9.81`, `R₀ = exp(0.3 e₁)`, `Ω₀ = (0, 0, 30)`, to `t = 1`.
#[must_use]
pub fn asymmetric_top() -> RigidProblem<HeavyTop> {
    let inertia = Inertia::principal([5.0, 4.0, 1.5]).expect("positive");
    let system = HeavyTop::new(inertia, 1.0, Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -9.81)).expect("finite");
    let initial = RigidState::from_angular_velocity(
        0.0,
        &inertia,
        Vec3::new(0.0, 0.0, 30.0),
        so3::exp(Vec3::new(0.3, 0.0, 0.0)),
    );
    RigidProblem {
        name: "asymmetric-top",
        description:
            "torque-dominated asymmetric top: I = diag(5, 4, 1.5), m = 1, X = (0, 0, 1), spin 30 rad/s, t = 1 s",
        system,
        initial,
        t_end: 1.0,
    }
}

/// A free asymmetric body spun about its intermediate axis (the tennis-racket or
/// Dzhanibekov flip): `I = diag(1, 2, 3)`, `Ω₀ = (0.01, 10, 0)`, to `t = 10`.
#[must_use]
pub fn free_body() -> RigidProblem<FreeBody> {
    let inertia = Inertia::principal([1.0, 2.0, 3.0]).expect("positive");
    RigidProblem {
        name: "free-body",
        description: "free asymmetric body about its intermediate axis (tennis-racket flip), t = 10 s",
        system: FreeBody::new(inertia),
        initial: RigidState::from_angular_velocity(0.0, &inertia, Vec3::new(0.01, 10.0, 0.0), Mat3::IDENTITY),
        t_end: 10.0,
    }
}

/// A harmonic oscillator `m u'' = −k u` in one dimension.
#[derive(Clone, Debug)]
pub struct HarmonicOscillator {
    mass: MassMatrix,
    /// Spring constant `k`.
    pub stiffness: f64,
}

impl HarmonicOscillator {
    /// An oscillator with mass `m > 0` and stiffness `k`.
    pub fn new(mass: f64, stiffness: f64) -> crate::Result<Self> {
        Ok(HarmonicOscillator {
            mass: MassMatrix::diagonal(vec![mass])?,
            stiffness,
        })
    }

    /// The exact state at time `t` from `(p0, u0)` at `t = 0`.
    #[must_use]
    pub fn exact(&self, p0: f64, u0: f64, t: f64) -> PhaseState {
        let MassMatrix::Diagonal(m) = &self.mass else {
            unreachable!()
        };
        let m = m[0];
        let w = (self.stiffness / m).sqrt();
        let (s, c) = (w * t).sin_cos();
        PhaseState {
            t,
            p: vec![p0 * c - m * w * u0 * s],
            u: vec![u0 * c + p0 / (m * w) * s],
        }
    }
}

impl MechanicalSystem for HarmonicOscillator {
    fn mass(&self) -> &MassMatrix {
        &self.mass
    }
    fn force(&self, u: &[f64], _t: f64, f: &mut [f64]) {
        f[0] = -self.stiffness * u[0];
    }
    fn potential_energy(&self, u: &[f64], _t: f64) -> f64 {
        0.5 * self.stiffness * u[0] * u[0]
    }
}

/// The Kepler problem `u'' = −u/|u|³` in the plane (`μ = 1`, unit mass).
#[derive(Clone, Debug)]
pub struct Kepler {
    mass: MassMatrix,
}

impl Default for Kepler {
    fn default() -> Self {
        Kepler {
            mass: MassMatrix::Diagonal(vec![1.0, 1.0]),
        }
    }
}

impl Kepler {
    /// The orbit of eccentricity `e` and semi-major axis 1 (period `2π`), starting at
    /// pericentre on the x axis.
    #[must_use]
    pub fn initial(e: f64) -> PhaseState {
        PhaseState {
            t: 0.0,
            p: vec![0.0, ((1.0 + e) / (1.0 - e)).sqrt()],
            u: vec![1.0 - e, 0.0],
        }
    }

    /// The exact state at time `t` on that orbit, from Kepler's equation `E − e sin E = t`.
    #[must_use]
    pub fn exact(e: f64, t: f64) -> PhaseState {
        let mut ea = t;
        for _ in 0..100 {
            let d = (ea - e * ea.sin() - t) / (1.0 - e * ea.cos());
            ea -= d;
            if d.abs() < 1e-16 {
                break;
            }
        }
        let (s, c) = ea.sin_cos();
        let b = (1.0 - e * e).sqrt();
        let r = 1.0 - e * c;
        PhaseState {
            t,
            p: vec![-s / r, b * c / r],
            u: vec![c - e, b * s],
        }
    }

    /// The angular momentum `u × p`.
    #[must_use]
    pub fn angular_momentum(state: &PhaseState) -> f64 {
        state.u[0] * state.p[1] - state.u[1] * state.p[0]
    }
}

impl MechanicalSystem for Kepler {
    fn mass(&self) -> &MassMatrix {
        &self.mass
    }
    fn force(&self, u: &[f64], _t: f64, f: &mut [f64]) {
        let r2 = u[0] * u[0] + u[1] * u[1];
        let s = -1.0 / (r2 * r2.sqrt());
        f[0] = s * u[0];
        f[1] = s * u[1];
    }
    fn potential_energy(&self, u: &[f64], _t: f64) -> f64 {
        -1.0 / (u[0] * u[0] + u[1] * u[1]).sqrt()
    }
}

/// The nonlinear pendulum `θ'' = −(g/l) sin θ` (unit mass, `u = θ`).
#[derive(Clone, Debug)]
pub struct Pendulum {
    mass: MassMatrix,
    /// `g/l` (1/s²).
    pub omega_squared: f64,
}

impl Pendulum {
    /// A pendulum with `g/l = omega_squared`.
    #[must_use]
    pub fn new(omega_squared: f64) -> Self {
        Pendulum {
            mass: MassMatrix::Diagonal(vec![1.0]),
            omega_squared,
        }
    }
}

impl MechanicalSystem for Pendulum {
    fn mass(&self) -> &MassMatrix {
        &self.mass
    }
    fn force(&self, u: &[f64], _t: f64, f: &mut [f64]) {
        f[0] = -self.omega_squared * u[0].sin();
    }
    fn potential_energy(&self, u: &[f64], _t: f64) -> f64 {
        self.omega_squared * (1.0 - u[0].cos())
    }
}

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
