//! The pieces of a fused sweep of the splitting, as the scheduler (`splitting.rs`) writes
//! them and the executors (the scalar path there, the AVX lanes of `avx.rs`) read them.
//!
//! Reference: docs/theory/spins.md §2.

use super::damped;
use crate::linalg::Vec3;

/// A piece of a fused sweep over the bonds of colour 0.
#[derive(Clone, Copy)]
pub(crate) enum Piece {
    /// The on-site flow of both spins over this time.
    Site(f64),
    /// The bond's flow over this time.
    Bond(f64),
    /// Renormalize both spins (the end of a step).
    Unit,
}

/// A [`Piece`] with its damped flow's constants.
#[derive(Clone, Copy)]
pub(crate) enum DampedPiece {
    Site(damped::SiteStep),
    Skip,
    Bond(damped::BondStep),
    Unit,
}

/// What the lanes need of the system (rates in rad/ps); read only by the SIMD lanes.
#[cfg_attr(not(all(feature = "simd", target_arch = "x86_64")), allow(dead_code))]
pub(crate) struct Kernel {
    /// `γJ/(μ_s μ_B)`.
    pub rate: f64,
    /// `n`.
    pub axis: Vec3,
    /// `γB`.
    pub field: Vec3,
    /// `γ 2K/(μ_s μ_B)`.
    pub anisotropy: f64,
    /// Whether there is an on-site term at all.
    pub onsite_terms: bool,
}
