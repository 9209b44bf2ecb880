//! Test problems on vector spaces with exact or reference solutions: the harmonic
//! oscillator, the Kepler problem and the pendulum.

use super::{MassMatrix, MechanicalSystem, PhaseState};

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
