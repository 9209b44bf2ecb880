//! The Hamiltonian of classical unit spins and the Landau-Lifshitz-Gilbert equation.
//!
//! ```text
//! E = −J Σ_<ij> S_i·S_j − Σ_<ij> D_ij·(S_i × S_j) − K Σ_i (S_i·n)² − μ_s μ_B B·Σ_i S_i   (meV)
//! B_i = −(1/(μ_s μ_B)) ∂E/∂S_i
//!     = (J Σ_{j~i} S_j + Σ_{j~i} S_j × D_ij + 2K (S_i·n) n)/(μ_s μ_B) + B             (T)
//! dS_i/dt = −γ/(1+α²) [S_i × B_i + α S_i × (S_i × B_i)] = Ω_i × S_i,
//! Ω_i = γ/(1+α²) (B_i + α S_i × B_i)                                      (rad/ps)
//! ```
//!
//! Each pair of neighbours counts once; `D_ji = −D_ij`. The Dzyaloshinskii-Moriya vectors
//! are optional ([`SpinSystem::with_dmi`]): bulk `D_ij = D r̂_ij`, interfacial
//! `D_ij = D (ẑ × r̂_ij)`, `r̂_ij` the unit vector from site `i` to site `j`, or any vector
//! per bond ([`SpinSystem::with_dmi_vectors`]). Undamped (`α = 0`) the energy, every `|S_i|` and,
//! when `n` and `B` are parallel to `z` (or zero) and there is no DMI, `Σ S_z` are
//! conserved; with `α > 0`
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
    /// The Dzyaloshinskii-Moriya vectors, if any is non-zero.
    dmi: Option<Dmi>,
}

/// Which Dzyaloshinskii-Moriya vectors a chain, square or cubic lattice gets from one
/// strength `D` (meV).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DmiKind {
    /// `D_ij = D r̂_ij` (B20 magnets; Bloch skyrmions). Spirit's `dm_chirality 1`.
    Bulk,
    /// `D_ij = D (ẑ × r̂_ij)` (a film on a heavy-metal substrate; Néel skyrmions).
    /// Spirit's `dm_chirality -2` (its `2` is `D r̂_ij × ẑ`, the opposite sign).
    Interfacial,
}

impl DmiKind {
    /// The name in scenario files.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            DmiKind::Bulk => "bulk",
            DmiKind::Interfacial => "interfacial",
        }
    }

    /// The kind named `key`.
    #[must_use]
    pub fn from_key(key: &str) -> Option<Self> {
        [DmiKind::Bulk, DmiKind::Interfacial]
            .into_iter()
            .find(|k| k.key() == key)
    }
}

/// The DMI vectors of a system, per bond and per (site, neighbour).
#[derive(Clone, Debug)]
struct Dmi {
    /// `D_ij` (meV) of each bond `[i, j]` of [`Lattice::bonds`], in its order.
    bond: Vec<Vec3>,
    /// `D_ij` seen from site `i` for each entry of the neighbour lists (`−D_b` at the
    /// bond's second site), so that `B_i` adds `Σ_j S_j × D_ij`.
    neighbour: Vec<Vec3>,
    /// `D/|D|` of each bond (zero where `D = 0`) and `|D|`.
    unit: Vec<Vec3>,
    norm: Vec<f64>,
    /// The common `|D|` when every bond has the same non-zero `|D|`.
    uniform: Option<f64>,
}

/// The DMI of every bond as the splitting uses it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DmiBonds<'a> {
    /// `D/|D|` per bond (zero where `D = 0`).
    pub unit: &'a [Vec3],
    /// `|D|` per bond.
    pub norm: &'a [f64],
    /// The common `|D|` when every bond has the same non-zero one.
    pub uniform: Option<f64>,
}

/// The rates the field is made of, in rad/ps.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rates<'a> {
    /// `γ/(μ_s μ_B)`: the rate per meV of a coupling.
    pub per_moment: f64,
    /// The DMI vectors per (site, neighbour) (meV), empty without DMI.
    pub dmi: &'a [Vec3],
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
            dmi: None,
        })
    }

    /// The system with nearest-neighbour Dzyaloshinskii-Moriya interaction of strength
    /// `strength` (meV) of `kind` on a chain, square or cubic lattice:
    /// `E_DMI = −Σ_<ij> D_ij·(S_i × S_j)`; `strength = 0` removes it.
    ///
    /// # Errors
    /// A non-finite strength, or a lattice built from a list of bonds (no bond
    /// directions: use [`SpinSystem::with_dmi_vectors`]).
    pub fn with_dmi(self, strength: f64, kind: DmiKind) -> Result<Self> {
        if !strength.is_finite() {
            return Err(Error::InvalidParameter {
                name: "dmi",
                value: strength,
                reason: "must be finite",
            });
        }
        let mut vectors = Vec::with_capacity(self.lattice.bonds().len());
        for &b in self.lattice.bonds() {
            let r = Vec3::from_array(self.lattice.bond_direction(b).ok_or(Error::InvalidParameter {
                name: "dmi",
                value: strength,
                reason: "a lattice given as a list of bonds has no bond directions; give one DMI vector per bond",
            })?);
            vectors.push(match kind {
                DmiKind::Bulk => r * strength,
                DmiKind::Interfacial => Vec3::new(0.0, 0.0, 1.0).cross(r) * strength,
            });
        }
        self.with_dmi_vectors(&vectors)
    }

    /// The system with one Dzyaloshinskii-Moriya vector `D_ij` (meV) per bond `[i, j]` of
    /// [`Lattice::bonds`], in that order; all zero removes the DMI.
    ///
    /// # Errors
    /// A count other than the number of bonds, or a non-finite vector.
    pub fn with_dmi_vectors(mut self, vectors: &[Vec3]) -> Result<Self> {
        let bonds = self.lattice.bonds();
        if vectors.len() != bonds.len() {
            return Err(Error::InvalidParameter {
                name: "dmi",
                value: vectors.len() as f64,
                reason: "needs one vector per bond of the lattice",
            });
        }
        if let Some(k) = vectors.iter().position(|v| !v.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "dmi",
                value: k as f64,
                reason: "a DMI vector (of the bond at this index) is not finite",
            });
        }
        if vectors.iter().all(|v| *v == Vec3::ZERO) {
            self.dmi = None;
            return Ok(self);
        }
        let lattice = &self.lattice;
        let mut neighbour = vec![Vec3::ZERO; 2 * bonds.len()];
        for (b, d) in bonds.iter().zip(vectors) {
            let (i, j) = (b[0] as usize, b[1] as usize);
            // Neighbour lists are sorted and hold each pair once.
            let at = |site: usize, other: u32| {
                lattice.neighbour_offset(site)
                    + lattice
                        .neighbours(site)
                        .binary_search(&other)
                        .expect("a bond's sites are neighbours")
            };
            neighbour[at(i, b[1])] = *d;
            neighbour[at(j, b[0])] = -*d;
        }
        let norm: Vec<f64> = vectors.iter().map(|v| v.norm()).collect();
        let unit = vectors
            .iter()
            .zip(&norm)
            .map(|(v, &n)| if n > 0.0 { *v * (1.0 / n) } else { Vec3::ZERO })
            .collect();
        let uniform = Some(norm[0]).filter(|&n| n > 0.0 && norm.iter().all(|&m| m == n));
        self.dmi = Some(Dmi {
            bond: vectors.to_vec(),
            neighbour,
            unit,
            norm,
            uniform,
        });
        Ok(self)
    }

    /// The DMI vector `D_ij` (meV) of each bond `[i, j]` of [`Lattice::bonds`], or `None`
    /// without DMI.
    #[must_use]
    pub fn dmi_vectors(&self) -> Option<&[Vec3]> {
        self.dmi.as_ref().map(|d| d.bond.as_slice())
    }

    /// The DMI per bond for the splitting.
    pub(crate) fn dmi_bonds(&self) -> Option<DmiBonds<'_>> {
        self.dmi.as_ref().map(|d| DmiBonds {
            unit: &d.unit,
            norm: &d.norm,
            uniform: d.uniform,
        })
    }

    /// Whether the DMI table still matches the lattice (the lattice is a public field).
    pub(crate) fn dmi_matches_lattice(&self) -> bool {
        self.dmi.as_ref().is_none_or(|d| {
            d.bond.len() == self.lattice.bonds().len() && d.neighbour.len() == 2 * self.lattice.bonds().len()
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

    pub(crate) fn rates(&self) -> Rates<'_> {
        let per_moment = GYROMAGNETIC_RATIO / (self.mu_s * MU_B);
        Rates {
            per_moment,
            dmi: self.dmi.as_ref().map_or(&[], |d| d.neighbour.as_slice()),
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

    /// Whether `Σ S_z` is conserved (undamped, `n` and `B` along `z` or zero, no DMI).
    #[must_use]
    pub fn conserves_sz(&self) -> bool {
        let along_z = |v: Vec3| v.x == 0.0 && v.y == 0.0;
        self.dmi.is_none() && (self.anisotropy == 0.0 || along_z(self.anisotropy_axis)) && along_z(self.field)
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
        let e = -self.exchange * exchange - self.anisotropy * anisotropy - self.mu_s * MU_B * self.field.dot(total);
        match &self.dmi {
            None => e,
            Some(d) => {
                let mut dmi = 0.0;
                for (b, v) in self.lattice.bonds().iter().zip(&d.bond) {
                    dmi += v.dot(spins[b[0] as usize].cross(spins[b[1] as usize]));
                }
                e - dmi
            }
        }
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

impl Rates<'_> {
    /// `γ B_i`: the undamped angular velocity of spin `i`.
    #[inline]
    pub fn precession(&self, lattice: &Lattice, spins: &[Vec3], i: usize) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for &j in lattice.neighbours(i) {
            sum += spins[j as usize];
        }
        let s = spins[i];
        let b = sum * self.exchange + self.axis * (self.anisotropy * s.dot(self.axis)) + self.field;
        if self.dmi.is_empty() {
            return b;
        }
        let start = lattice.neighbour_offset(i);
        let mut dmi = Vec3::ZERO;
        for (&j, d) in lattice.neighbours(i).iter().zip(&self.dmi[start..]) {
            dmi += spins[j as usize].cross(*d);
        }
        b + dmi * self.per_moment
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
