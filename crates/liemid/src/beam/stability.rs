//! The critical step of the explicit beam integrators.
//!
//! Verlet (and the splitting, which is Verlet on the linearised structure) is stable for
//! `h ω_max < 2`; a composition `Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h}` for `h ω_max < c`, with `c`
//! the first `hω` at which the composed map of the harmonic oscillator leaves
//! `|tr/2| ≤ 1` ([`composition_limit`]: Suzuki's 5 stages 3.14, Yoshida's 3 stages 1.57).
//! `ω_max` is bounded from above element by element
//! ([`super::element::omega_squared_bound`], Irons' theorem), so `c/ω_bound` is a safe
//! step; a power iteration on `M^{-1/2} K M^{-1/2}` (the stiffness by central differences
//! of the internal forces) gives `ω_max` from below, to show how tight the bound is.
//!
//! ## Reference
//! T. Belytschko, W. K. Liu, B. Moran, *Nonlinear Finite Elements for Continua and
//! Structures*, Wiley (2000), section 6.3; E. Hairer, C. Lubich, G. Wanner, *Geometric
//! Numerical Integration*, 2nd ed., Springer (2006), section I.5.

use super::{BeamMethod, BeamSystem};
use crate::composition::Scheme;
use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};
use crate::random::Rng;
use crate::so3;

/// What is known of the structure's largest eigenfrequency.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stability {
    /// Upper bound of `ω_max` (rad per time unit), from the elements.
    pub omega_bound: f64,
    /// Lower estimate of `ω_max` from the power iteration (`None` if not run).
    pub omega_estimate: Option<f64>,
    /// Upper bound of the axial waves' `ω` alone (the impulse method's inner steps).
    pub omega_axial_bound: f64,
    /// Upper bound of the bending and torsion waves' `ω` (the impulse method's outer step).
    pub omega_bending_bound: f64,
    /// The added stretch inertia `β` of [`BeamMethod::MassScaled`] (its axial bound is
    /// `omega_axial_bound/√(1 + 4β)`).
    pub axial_mass: f64,
}

impl Stability {
    /// The largest stable step of `method` by the bound: `c/ω_bound`.
    #[must_use]
    pub fn critical_step(&self, method: BeamMethod) -> f64 {
        match method {
            // The outer step sees only the bending and torsion stiffness (the axial
            // forces are substepped, `super::impulse::substeps`), but resonates with the
            // axial modes beyond half the shortest axial period (`h ω_a < π`, measured on
            // the right-angle cantilever: energy bounded at h ω_a = 3.2, drifting at 4.0,
            // unstable from 5.3).
            BeamMethod::Impulse => (2.0 / self.omega_bending_bound).min(std::f64::consts::PI / self.omega_axial_bound),
            BeamMethod::MassScaled => 2.0 / self.omega_bound_of(method),
            _ => composition_limit(method.scheme()) / self.omega_bound,
        }
    }

    /// The bound of `ω_max` that sets `method`'s step: the element bound, or for
    /// [`BeamMethod::MassScaled`] the larger of the bending bound and the scaled axial one.
    #[must_use]
    pub fn omega_bound_of(&self, method: BeamMethod) -> f64 {
        match method {
            BeamMethod::MassScaled => self
                .omega_bending_bound
                .max(self.omega_axial_bound / (1.0 + 4.0 * self.axial_mass).sqrt()),
            _ => self.omega_bound,
        }
    }

    /// The default step of `method`: 0.9 of the critical one (margin for the stiffening
    /// of large deformations).
    #[must_use]
    pub fn default_step(&self, method: BeamMethod) -> f64 {
        0.9 * self.critical_step(method)
    }

    /// `Ok` when `h` is at most the critical step of `method`.
    ///
    /// # Errors
    /// [`Error::UnstableStep`], with the step, the critical step and `ω_max`.
    pub fn check(&self, method: BeamMethod, h: f64) -> Result<()> {
        let critical = self.critical_step(method);
        if h.abs() > critical {
            return Err(Error::UnstableStep {
                h,
                critical,
                omega: self.omega_bound_of(method),
            });
        }
        Ok(())
    }
}

/// The harmonic oscillator's Verlet map over `τ` (ω = 1): kick, drift, kick.
fn verlet_matrix(tau: f64) -> [[f64; 2]; 2] {
    let a = 1.0 - 0.5 * tau * tau;
    [[a, tau], [-tau + 0.25 * tau * tau * tau, a]]
}

fn stable(scheme: Option<&Scheme>, x: f64) -> bool {
    let mut m = [[1.0, 0.0], [0.0, 1.0]];
    let stages = scheme.map_or(1, Scheme::stages);
    for k in 0..stages {
        let g = scheme.map_or(1.0, |s| s.gamma(k));
        let v = verlet_matrix(g * x);
        m = [
            [
                v[0][0] * m[0][0] + v[0][1] * m[1][0],
                v[0][0] * m[0][1] + v[0][1] * m[1][1],
            ],
            [
                v[1][0] * m[0][0] + v[1][1] * m[1][0],
                v[1][0] * m[0][1] + v[1][1] * m[1][1],
            ],
        ];
    }
    (0.5 * (m[0][0] + m[1][1])).abs() <= 1.0
}

/// The first `hω` at which the composition of Verlet by `scheme` (Verlet itself for
/// `None`) becomes unstable on the harmonic oscillator, to 1e-9 (Verlet: 2).
#[must_use]
pub fn composition_limit(scheme: Option<&Scheme>) -> f64 {
    let mut x = 0.0;
    let step = 1e-3;
    while stable(scheme, x + step) {
        x += step;
        if x > 100.0 {
            return x;
        }
    }
    let (mut lo, mut hi) = (x, x + step);
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        if stable(scheme, mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

impl BeamSystem {
    /// The bound of `ω_max` over the elements, and with `power_iterations > 0` a power
    /// iteration's estimate from below.
    #[must_use]
    pub fn stability(&self, power_iterations: usize) -> Stability {
        let (mut axial, mut bending): (f64, f64) = (0.0, 0.0);
        for (k, e) in self.structure.elements.iter().enumerate() {
            let s = &self.frame.elements[k].section;
            let half = 0.5 * e.stiffness.length;
            let (a, b) =
                super::element::omega_squared_bounds(&e.stiffness, s.mass_per_length * half, s.rotary_inertia * half);
            axial = axial.max(a);
            bending = bending.max(b);
        }
        Stability {
            omega_bound: axial.max(bending).sqrt(),
            omega_axial_bound: axial.sqrt(),
            omega_bending_bound: bending.sqrt(),
            axial_mass: self.mass_scaling.beta,
            omega_estimate: (power_iterations > 0).then(|| self.power_iteration(power_iterations).sqrt()),
        }
    }

    /// `λ_max` of `M^{-1/2} K M^{-1/2}` at the current configuration by `iterations` power
    /// steps (the Rayleigh quotient of the last).
    fn power_iteration(&self, iterations: usize) -> f64 {
        let b = &self.bodies;
        let n = b.len();
        let min_length = self
            .structure
            .elements
            .iter()
            .map(|e| e.stiffness.length)
            .fold(f64::INFINITY, f64::min);
        // y: mass-scaled coordinates, 6 per body (translations of pinned bodies stay 0).
        let mut rng = Rng::new(0x5EED_BEA4);
        let mut y: Vec<f64> = (0..6 * n).map(|_| rng.uniform() - 0.5).collect();
        let mask = |i: usize, k: usize| k >= 3 || b.free[i];
        let scale = |i: usize, k: usize| -> f64 {
            if k < 3 {
                1.0 / b.mass[i].sqrt()
            } else {
                1.0 / b.inertia[i].moments.to_array()[k - 3].sqrt()
            }
        };
        let mut force = vec![Vec3::ZERO; n];
        let mut torque = vec![Vec3::ZERO; n];
        let mut lambda = 0.0;
        for _ in 0..iterations {
            for (j, v) in y.iter_mut().enumerate() {
                if !mask(j / 6, j % 6) {
                    *v = 0.0;
                }
            }
            let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm == 0.0 {
                return 0.0;
            }
            y.iter_mut().for_each(|v| *v /= norm);
            // z = M^{-1/2} y, then a central difference of the internal forces along z.
            let z: Vec<f64> = y.iter().enumerate().map(|(j, v)| v * scale(j / 6, j % 6)).collect();
            let zt = (0..n)
                .map(|i| Vec3::new(z[6 * i], z[6 * i + 1], z[6 * i + 2]).max_abs() / min_length)
                .fold(0.0, f64::max);
            let zr = (0..n)
                .map(|i| Vec3::new(z[6 * i + 3], z[6 * i + 4], z[6 * i + 5]).max_abs())
                .fold(0.0, f64::max);
            let eps = 1e-7 / zt.max(zr);
            let mut ky = vec![0.0; 6 * n];
            for sign in [1.0, -1.0] {
                let position: Vec<Vec3> = (0..n)
                    .map(|i| b.position[i] + Vec3::new(z[6 * i], z[6 * i + 1], z[6 * i + 2]) * (sign * eps))
                    .collect();
                let rotation: Vec<Mat3> = (0..n)
                    .map(|i| {
                        b.rotation[i] * so3::exp(Vec3::new(z[6 * i + 3], z[6 * i + 4], z[6 * i + 5]) * (sign * eps))
                    })
                    .collect();
                self.structure
                    .internal_forces(&position, &rotation, &mut force, &mut torque);
                for i in 0..n {
                    for k in 0..3 {
                        // K z = −dF/dε.
                        ky[6 * i + k] -= sign * force[i].to_array()[k] / (2.0 * eps);
                        ky[6 * i + 3 + k] -= sign * torque[i].to_array()[k] / (2.0 * eps);
                    }
                }
            }
            for (j, v) in ky.iter_mut().enumerate() {
                *v *= scale(j / 6, j % 6);
            }
            lambda = y.iter().zip(&ky).map(|(a, b)| a * b).sum();
            y = ky;
        }
        lambda
    }
}
