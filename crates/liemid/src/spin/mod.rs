//! Atomistic spin dynamics: classical unit spins on a lattice, the Landau-Lifshitz-Gilbert
//! equation, and integrators that keep its structure.
//!
//! `dS/dt = −γ S × B_eff` (undamped) has the Lie-Poisson structure of the rigid body's
//! `Π' = Π × Ω`: every step is a rotation of each spin, so the project's SO(3) machinery
//! applies. The module has the shape of the other domains:
//!
//! - [`lattice`]: sites, bonds (each pair once), neighbours, and a colouring of the bonds
//!   into matchings;
//! - [`hamiltonian`]: [`SpinSystem`] (exchange `J`, Dzyaloshinskii-Moriya vectors `D_ij`,
//!   uniaxial anisotropy `K` along `n`, field `B`, moment `μ_s`, damping `α`), the energy
//!   and the effective field;
//! - the methods, one file each: `splitting` (explicit, symplectic: exact flows of bond
//!   colours and of the on-site terms, composed to orders 2, 4, 6, 8; with damping the
//!   exact damped flows of `damped`; a DMI bond by the exact flows of `dmi`), `midpoint` (the
//!   implicit midpoint rule in Cayley form: exact energy and `Σ S_z`; damping), and the
//!   baselines of the field in `explicit` (Heun, Depondt-Mertens, RK4);
//! - [`problems`]: named benchmarks (`skyrmion`: a relaxed Néel skyrmion);
//! - [`topological_charge`] (Berg-Lüscher) and [`relax`] (velocity projection).
//!
//! Units: meV, T, ps, Bohr magnetons, with Spirit's constants, so a run with the same
//! inputs as Spirit follows the same equation.

pub mod hamiltonian;
pub mod lattice;
pub mod problems;

#[cfg(all(feature = "simd", target_arch = "x86_64"))]
mod avx;
mod damped;
mod dmi;
mod explicit;
mod lanes;
mod midpoint;
mod pieces;
mod splitting;
mod sweep;
mod topology;

pub use hamiltonian::{DmiKind, SpinSystem};
pub use lattice::{Lattice, LatticeKind};
pub use sweep::CHUNK;
pub use topology::{relax, topological_charge, Relaxation};

use crate::composition::Scheme;
use crate::error::{Error, Result};
use crate::linalg::Vec3;

/// The electron gyromagnetic ratio `γ` in rad/(ps·T) (Spirit's value).
pub const GYROMAGNETIC_RATIO: f64 = 0.176_085_964_4;
/// The Bohr magneton `μ_B` in meV/T (Spirit's value).
pub const MU_B: f64 = 0.057_883_817_555;

/// A spin integrator, chosen by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpinMethod {
    /// The bond-colour splitting, Strang-composed: order 2, explicit, symplectic.
    Splitting,
    /// The splitting composed by Suzuki's 5-stage scheme: order 4.
    Splitting4,
    /// The splitting composed by Kahan and Li's 9-stage scheme: order 6.
    Splitting6,
    /// The splitting composed by Kahan and Li's 17-stage scheme: order 8.
    Splitting8,
    /// The implicit midpoint rule (Cayley form): order 2, energy and `Σ S_z` exact.
    Midpoint,
    /// Heun with renormalisation (Spirit's and UppASD's default family).
    Heun,
    /// Depondt-Mertens: Heun on the rotation.
    DepondtMertens,
    /// Classical RK4 with renormalisation.
    RungeKutta4,
}

impl SpinMethod {
    /// Every spin method.
    pub const ALL: [SpinMethod; 8] = [
        SpinMethod::Splitting,
        SpinMethod::Splitting4,
        SpinMethod::Splitting6,
        SpinMethod::Splitting8,
        SpinMethod::Midpoint,
        SpinMethod::Heun,
        SpinMethod::DepondtMertens,
        SpinMethod::RungeKutta4,
    ];

    /// The name in scenario files and on the command line.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            SpinMethod::Splitting => "split",
            SpinMethod::Splitting4 => "split4",
            SpinMethod::Splitting6 => "split6",
            SpinMethod::Splitting8 => "split8",
            SpinMethod::Midpoint => "midpoint",
            SpinMethod::Heun => "heun",
            SpinMethod::DepondtMertens => "depondt",
            SpinMethod::RungeKutta4 => "rk4",
        }
    }

    /// The method named `key`.
    #[must_use]
    pub fn from_key(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.key() == key)
    }

    /// Order of accuracy.
    #[must_use]
    pub fn order(self) -> u32 {
        match self {
            SpinMethod::Splitting | SpinMethod::Midpoint | SpinMethod::Heun | SpinMethod::DepondtMertens => 2,
            SpinMethod::Splitting4 | SpinMethod::RungeKutta4 => 4,
            SpinMethod::Splitting6 => 6,
            SpinMethod::Splitting8 => 8,
        }
    }

    /// Effective-field evaluations per step (for the splitting: sweeps over the bonds).
    #[must_use]
    pub fn field_evaluations(self) -> &'static str {
        match self {
            SpinMethod::Splitting => "1 bond sweep",
            SpinMethod::Splitting4 => "5 bond sweeps",
            SpinMethod::Splitting6 => "9 bond sweeps",
            SpinMethod::Splitting8 => "17 bond sweeps",
            SpinMethod::Midpoint => "1 per fixed-point iteration",
            SpinMethod::Heun | SpinMethod::DepondtMertens => "2",
            SpinMethod::RungeKutta4 => "4",
        }
    }

    /// Whether it integrates the damped equation (`α > 0`): every method does (the
    /// splitting by the exact damped flows of its parts).
    #[must_use]
    pub fn handles_damping(self) -> bool {
        true
    }

    /// One line on what it is and what it keeps.
    #[must_use]
    pub fn description(self) -> &'static str {
        match self {
            SpinMethod::Splitting => {
                "exact flows of the bond colours and the on-site terms, Strang-composed; explicit, symplectic undamped; keeps |S_i| and sum S (exchange) exactly, energy bounded; with damping the exact damped flows of the same parts"
            }
            SpinMethod::Splitting4 => "the splitting composed by Suzuki's 5-stage scheme; keeps what it keeps",
            SpinMethod::Splitting6 => "the splitting composed by Kahan-Li's 9-stage scheme; keeps what it keeps",
            SpinMethod::Splitting8 => "the splitting composed by Kahan-Li's 17-stage scheme; keeps what it keeps",
            SpinMethod::Midpoint => {
                "implicit midpoint rule, Cayley rotation at the midpoint field; keeps |S_i|, energy and sum S_z exactly; energy falls monotonically with damping"
            }
            SpinMethod::Heun => "Heun with renormalisation; keeps |S_i| only",
            SpinMethod::DepondtMertens => "Depondt-Mertens (Heun on the rotation); keeps |S_i| only",
            SpinMethod::RungeKutta4 => "classical RK4 with renormalisation; keeps |S_i| only",
        }
    }

    fn scheme(self) -> Option<Scheme> {
        match self {
            SpinMethod::Splitting4 => Some(Scheme::SUZUKI4),
            SpinMethod::Splitting6 => Some(Scheme::KAHAN_LI6),
            SpinMethod::Splitting8 => Some(Scheme::KAHAN_LI8),
            _ => None,
        }
    }
}

/// The splitting's Strang steps one sweep at a time, without fusing the on-site flows into
/// the colour-0 sweeps: the same result bit for bit (for tests).
#[doc(hidden)]
pub fn splitting_unfused(system: &SpinSystem, spins: &mut [Vec3], h: f64, gammas: &[f64]) {
    splitting::composed_unfused(system, spins, h, gammas);
}

/// One piece of a DMI bond's flow (0 Ising, 1 rotated exchange, 2 the Strang bond flow)
/// over `h`, damped for `alpha > 0` (for tests against a reference integration).
#[doc(hidden)]
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn dmi_piece_flow(
    which: u8,
    d: Vec3,
    exchange: f64,
    k: f64,
    alpha: f64,
    si: Vec3,
    sj: Vec3,
    h: f64,
) -> (Vec3, Vec3) {
    dmi::piece_flow(which, d, exchange, k, alpha, si, sj, h)
}

/// A spin integrator with its scratch buffers (allocated on the first step, reused after:
/// stepping allocates nothing once warm).
#[derive(Clone, Debug)]
pub struct SpinIntegrator {
    method: SpinMethod,
    buffers: [Vec<Vec3>; 3],
    /// Fixed-point iterations of the midpoint rule, summed over all steps.
    pub iterations: u64,
}

impl SpinIntegrator {
    /// A new integrator of `method`.
    #[must_use]
    pub fn new(method: SpinMethod) -> Self {
        SpinIntegrator {
            method,
            buffers: Default::default(),
            iterations: 0,
        }
    }

    /// The method.
    #[must_use]
    pub fn method(&self) -> SpinMethod {
        self.method
    }

    /// One step of `h` (ps) from time `t` (for error messages).
    ///
    /// # Errors
    /// A spin array of the wrong length, a non-finite or zero step, a midpoint solve that does not converge (the spins are
    /// then left as they were), or a non-finite result.
    pub fn step(&mut self, system: &SpinSystem, spins: &mut [Vec3], t: f64, h: f64) -> Result<()> {
        self.advance(system, spins, t, h, 1)
    }

    /// `steps` steps of `h` from time `t`: bit for bit the same as `steps` calls of
    /// [`SpinIntegrator::step`]. For the splitting the threads stay together for all the
    /// steps (one team, the last colour-0 sweep of a step fused with the first of the
    /// next), which is what a long run should call between observations.
    ///
    /// # Errors
    /// As for [`SpinIntegrator::step`]; a failure in step `k` leaves the spins after step
    /// `k − 1` (the splitting cannot fail once its input is checked).
    pub fn advance(&mut self, system: &SpinSystem, spins: &mut [Vec3], t: f64, h: f64, steps: u64) -> Result<()> {
        if spins.len() != system.len() {
            return Err(Error::InvalidParameter {
                name: "spins",
                value: spins.len() as f64,
                reason: "must have one spin per site",
            });
        }
        if !(h.is_finite() && h != 0.0) {
            return Err(Error::InvalidStep { h });
        }
        if !system.dmi_matches_lattice() {
            return Err(Error::InvalidParameter {
                name: "dmi",
                value: system.lattice.bonds().len() as f64,
                reason: "the DMI vectors were set for another lattice (bond count given); set them again",
            });
        }
        let [a, b, c] = &mut self.buffers;
        match self.method {
            SpinMethod::Splitting | SpinMethod::Splitting4 | SpinMethod::Splitting6 | SpinMethod::Splitting8 => {
                let scheme = self.method.scheme();
                let stages = scheme.map_or(1, |s| s.stages());
                let gammas = (0..steps)
                    .flat_map(move |_| (0..stages).map(move |k| (scheme.map_or(1.0, |s| s.gamma(k)), k + 1 == stages)));
                splitting::composed(system, spins, h, gammas);
            }
            _ => {
                for k in 0..steps {
                    let tk = t + k as f64 * h;
                    match self.method {
                        SpinMethod::Midpoint => {
                            self.iterations += midpoint::step(system, spins, h, tk, a, b, c)? as u64;
                        }
                        SpinMethod::Heun => explicit::heun(system, spins, h, a, b),
                        SpinMethod::DepondtMertens => explicit::depondt(system, spins, h, a, b),
                        _ => explicit::rk4(system, spins, h, a, b, c),
                    }
                }
            }
        }
        if spins.iter().any(|s| !s.is_finite()) {
            return Err(Error::NonFiniteResult {
                method: self.method.key(),
                t,
                h,
            });
        }
        Ok(())
    }
}

/// Spins all along `direction` (normalised).
#[must_use]
pub fn uniform(n: usize, direction: Vec3) -> Vec<Vec3> {
    vec![direction * (1.0 / direction.norm()); n]
}

/// Unit spins from `(N, 3)` rows, each normalised; a row already of unit length to
/// rounding (`| |s|² − 1 | ≤ 4ε`) is kept bit for bit, so that spins written by one run
/// and read by another continue exactly.
///
/// # Errors
/// A zero or non-finite row (named by its index).
pub fn normalized(rows: &[Vec3]) -> Result<Vec<Vec3>> {
    rows.iter()
        .enumerate()
        .map(|(i, s)| {
            let n2 = s.norm_squared();
            if (n2 - 1.0).abs() <= 4.0 * f64::EPSILON {
                Ok(*s)
            } else if n2 > 0.0 && n2.is_finite() {
                Ok(*s * (1.0 / n2.sqrt()))
            } else {
                Err(Error::InvalidParameter {
                    name: "spins",
                    value: i as f64,
                    reason: "a spin (at the index given) is zero or not finite",
                })
            }
        })
        .collect()
}
