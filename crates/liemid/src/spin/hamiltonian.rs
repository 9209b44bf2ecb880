//! The Hamiltonian of classical unit spins and the Landau-Lifshitz-Gilbert equation.
//!
//! ```text
//! E = −J Σ_<ij> S_i·S_j − K Σ_i (S_i·n)² − μ_s μ_B B·Σ_i S_i           (meV)
//! B_i = −(1/(μ_s μ_B)) ∂E/∂S_i = (J Σ_{j~i} S_j + 2K (S_i·n) n)/(μ_s μ_B) + B   (T)
//! dS_i/dt = −γ/(1+α²) [S_i × B_i + α S_i × (S_i × B_i)] = Ω_i × S_i,
//! Ω_i = γ/(1+α²) (B_i + α S_i × B_i)                                      (rad/ps)
//! ```
//!
//! Each pair of neighbours counts once. Undamped (`α = 0`) the energy, every `|S_i|` and,
//! when `n` and `B` are parallel to `z` (or zero), `Σ S_z` are conserved; with `α > 0`
//! the energy decreases.
//!
//! Reference: the units and conventions of Spirit (G. P. Müller et al., Phys. Rev. B 99,
//! 224414 (2019)).

use super::lattice::Lattice;
use super::{GYROMAGNETIC_RATIO, MU_B};
use crate::error::{Error, Result};
use crate::linalg::Vec3;

/// The parameters of a spin system on a lattice.
#[derive(Clone, Debug)]
pub struct SpinSystem {
    /// Sites and bonds.
    pub lattice: Lattice,
    /// Nearest-neighbour exchange `J` (meV; positive is ferromagnetic).
    pub exchange: f64,
    /// Uniaxial anisotropy `K` (meV; positive is an easy axis).
    pub anisotropy: f64,
    /// The anisotropy axis `n` (unit).
    pub anisotropy_axis: Vec3,
    /// External field `B` (T).
    pub field: Vec3,
    /// Moment per spin `μ_s` (Bohr magnetons).
    pub mu_s: f64,
    /// Gilbert damping `α`.
    pub damping: f64,
}

/// The rates the field is made of, in rad/ps.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rates {
    /// `γ J / (μ_s μ_B)`: precession rate per unit neighbour spin.
    pub exchange: f64,
    /// `γ 2K / (μ_s μ_B)`: anisotropy rate per unit `S·n`.
    pub anisotropy: f64,
    /// `n`.
    pub axis: Vec3,
    /// `γ B`.
    pub field: Vec3,
    /// `α`.
    pub damping: f64,
    /// `1/(1 + α²)`.
    pub damping_factor: f64,
}

impl SpinSystem {
    /// A system with the given parameters; `anisotropy_axis` is normalised.
    ///
    /// # Errors
    /// Non-finite parameters, `μ_s ≤ 0`, `α < 0`, or a zero anisotropy axis with `K ≠ 0`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        lattice: Lattice,
        exchange: f64,
        anisotropy: f64,
        anisotropy_axis: Vec3,
        field: Vec3,
        mu_s: f64,
        damping: f64,
    ) -> Result<Self> {
        for (name, v) in [("exchange", exchange), ("anisotropy", anisotropy)] {
            if !v.is_finite() {
                return Err(Error::InvalidParameter {
                    name,
                    value: v,
                    reason: "must be finite",
                });
            }
        }
        if !field.is_finite() {
            return Err(Error::InvalidParameter {
                name: "field",
                value: field.max_abs(),
                reason: "must be finite",
            });
        }
        if !(mu_s.is_finite() && mu_s > 0.0) {
            return Err(Error::InvalidParameter {
                name: "mu_s",
                value: mu_s,
                reason: "must be finite and positive",
            });
        }
        if !(damping.is_finite() && damping >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "damping",
                value: damping,
                reason: "must be finite and non-negative",
            });
        }
        let norm = anisotropy_axis.norm();
        let axis = if norm > 0.0 && norm.is_finite() {
            anisotropy_axis * (1.0 / norm)
        } else if anisotropy == 0.0 {
            Vec3::new(0.0, 0.0, 1.0)
        } else {
            return Err(Error::InvalidParameter {
                name: "anisotropy_axis",
                value: norm,
                reason: "must be a non-zero finite vector",
            });
        };
        Ok(SpinSystem {
            lattice,
            exchange,
            anisotropy,
            anisotropy_axis: axis,
            field,
            mu_s,
            damping,
        })
    }

    /// Number of spins.
    #[must_use]
    pub fn len(&self) -> usize {
        self.lattice.sites()
    }

    /// Whether there are no spins.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.lattice.sites() == 0
    }

    pub(crate) fn rates(&self) -> Rates {
        let per_moment = GYROMAGNETIC_RATIO / (self.mu_s * MU_B);
        Rates {
            exchange: per_moment * self.exchange,
            anisotropy: per_moment * 2.0 * self.anisotropy,
            axis: self.anisotropy_axis,
            field: self.field * GYROMAGNETIC_RATIO,
            damping: self.damping,
            damping_factor: 1.0 / (1.0 + self.damping * self.damping),
        }
    }

    /// Whether the on-site terms (anisotropy and field) commute, so that their joint flow is
    /// one rotation: `K = 0`, `B = 0`, or `B` parallel to `n`.
    pub(crate) fn onsite_commutes(&self) -> bool {
        self.anisotropy == 0.0 || self.field.cross(self.anisotropy_axis).max_abs() <= 1e-15 * self.field.max_abs()
    }

    /// Whether `Σ S_z` is conserved (undamped, `n` and `B` along `z` or zero).
    #[must_use]
    pub fn conserves_sz(&self) -> bool {
        let along_z = |v: Vec3| v.x == 0.0 && v.y == 0.0;
        (self.anisotropy == 0.0 || along_z(self.anisotropy_axis)) && along_z(self.field)
    }

    /// The energy `E` (meV), summed in index order.
    #[must_use]
    pub fn energy(&self, spins: &[Vec3]) -> f64 {
        let mut exchange = 0.0;
        for b in self.lattice.bonds() {
            exchange += spins[b[0] as usize].dot(spins[b[1] as usize]);
        }
        let mut anisotropy = 0.0;
        let mut total = Vec3::ZERO;
        for s in spins {
            let d = s.dot(self.anisotropy_axis);
            anisotropy += d * d;
            total += *s;
        }
        -self.exchange * exchange - self.anisotropy * anisotropy - self.mu_s * MU_B * self.field.dot(total)
    }

    /// `Σ S_i`, summed in index order.
    #[must_use]
    pub fn total_spin(&self, spins: &[Vec3]) -> Vec3 {
        spins.iter().fold(Vec3::ZERO, |a, s| a + *s)
    }

    /// The effective field `B_i` (T) at site `i`.
    #[must_use]
    pub fn effective_field(&self, spins: &[Vec3], i: usize) -> Vec3 {
        self.rates().precession(&self.lattice, spins, i) * (1.0 / GYROMAGNETIC_RATIO)
    }
}

impl Rates {
    /// `γ B_i`: the undamped angular velocity of spin `i`.
    #[inline]
    pub fn precession(&self, lattice: &Lattice, spins: &[Vec3], i: usize) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for &j in lattice.neighbours(i) {
            sum += spins[j as usize];
        }
        let s = spins[i];
        sum * self.exchange + self.axis * (self.anisotropy * s.dot(self.axis)) + self.field
    }

    /// `Ω_i = γ/(1+α²) (B_i + α S_i × B_i)`, evaluated at `spins` (any lengths).
    #[inline]
    pub fn omega(&self, lattice: &Lattice, spins: &[Vec3], i: usize) -> Vec3 {
        let b = self.precession(lattice, spins, i);
        if self.damping == 0.0 {
            b
        } else {
            (b + spins[i].cross(b) * self.damping) * self.damping_factor
        }
    }
}
