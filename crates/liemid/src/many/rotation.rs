//! The torque-free rotation of the many-body step between its impulses
//! ([`FreeRotation`]): the exact flow, or two half steps of the midpoint equation (M) or the
//! variational equation (V) (docs/theory/rigid.md §9-10), body by body or, for (M), four
//! bodies at a time in SIMD lanes.
//!
//! Reference: P. Krysl, Int. J. Numer. Meth. Engng 63 (2005) (M); T. Lee, M. Leok,
//! N. H. McClamroch, Comput. Methods Appl. Mech. Engrg. 196 (2007) (V); E. Celledoni,
//! F. Fassò, N. Säfström, A. Zanna, SIAM J. Sci. Comput. 30 (2008) (the exact flow).

use super::BYTES_PER_BODY;
use crate::inertia::PrincipalInertia;
use crate::linalg::{Mat3, Vec3};
use crate::midpoint;
use crate::rigid::free_flow::FreeFlow;
use crate::variational::Drift;

/// How [`super::Bodies::step`] moves each body between the impulses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FreeRotation {
    /// The torque-free midpoint Lie rotation, two half steps as in LIEMID\[EA\] (one
    /// Newton solve each; SIMD lanes with the `simd` feature).
    #[default]
    Midpoint,
    /// The exact torque-free flow ([`FreeFlow`]), as in LIEMID\[EX\]: no Newton solve,
    /// no error in the free spin.
    Exact,
    /// The variational torque-free rotation, two half steps of (V) as in LIEMID\[EAV\]
    /// (one Newton solve each, on the scalar path: the SIMD lanes hold (M) only). A
    /// Lie–Poisson map, second order and symmetric like the midpoint one
    /// (docs/theory/rigid.md §9).
    Variational,
}

impl FreeRotation {
    /// Every free rotation.
    pub const ALL: [FreeRotation; 3] = [FreeRotation::Midpoint, FreeRotation::Exact, FreeRotation::Variational];

    /// The name on the command line and in files.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            FreeRotation::Midpoint => "midpoint",
            FreeRotation::Exact => "exact",
            FreeRotation::Variational => "variational",
        }
    }

    /// The free rotation of a key ([`FreeRotation::key`]).
    #[must_use]
    pub fn from_key(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|r| r.key() == key)
    }

    /// The drift whose equation the half steps solve; `None` for the exact flow.
    #[must_use]
    pub fn drift(self) -> Option<Drift> {
        match self {
            FreeRotation::Midpoint => Some(Drift::Midpoint),
            FreeRotation::Exact => None,
            FreeRotation::Variational => Some(Drift::Variational),
        }
    }

    /// Bytes of state per body: [`BYTES_PER_BODY`], plus the flow's constants for
    /// [`FreeRotation::Exact`].
    #[must_use]
    pub fn bytes_per_body(self) -> usize {
        match self {
            FreeRotation::Midpoint | FreeRotation::Variational => BYTES_PER_BODY,
            FreeRotation::Exact => BYTES_PER_BODY + std::mem::size_of::<FreeFlow>(),
        }
    }
}

/// Bodies per group of the SIMD lanes.
pub(super) const GROUP: usize = 4;

/// Whether [`rotate_group`] can run: the `simd` feature on an x86-64 processor with AVX.
#[inline]
pub(super) fn lanes_available() -> bool {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    {
        super::lanes::use_avx()
    }
    #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
    {
        false
    }
}

/// The torque-free rotation of a group of [`GROUP`] bodies in SIMD lanes, equal bit for bit
/// to [`free_rotation_by`] with [`Drift::Midpoint`] of each; `false`, with nothing written, when the group needs the
/// scalar path (always without `lanes`, which must be [`lanes_available`]).
#[inline]
#[allow(unused_variables)]
pub(super) fn rotate_group(
    lanes: bool,
    inertia: &[PrincipalInertia],
    r: &mut [Mat3],
    pi: &mut [Vec3],
    hh: f64,
) -> bool {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    {
        use crate::inertia::InertiaOperator;
        let (Ok(group), Ok(r), Ok(pi)) = (
            <&[PrincipalInertia; GROUP]>::try_from(inertia),
            <&mut [Mat3; GROUP]>::try_from(r),
            <&mut [Vec3; GROUP]>::try_from(pi),
        ) else {
            return false;
        };
        super::lanes::free_rotation_x4(
            lanes,
            &group.map(|g| g.moments),
            &group.map(|g| g.inverse),
            group.map(|g| g.inverse_norm_bound()),
            r,
            pi,
            hh,
        )
    }
    #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
    false
}

/// The torque-free rotation of one body over `2 hh` in two half steps of `drift`'s
/// equation, (M) `(1/hh) I Ψ = exp(−Ψ/2) Π` or (V) `(1/hh) I Ψ = Jr(Ψ) Π`:
/// `solve → Ψ; R ← R exp(Ψ); Π ← exp(−Ψ) Π`, twice. Second order and symmetric either way,
/// `|Π|` and `R Π` kept; Lie–Poisson with (V) (docs/theory/rigid.md §9). On an error
/// nothing is written.
///
/// Works on local copies (`Π` read component by component, see [`Vec3::load_split`]) and
/// writes once at the end: writing `Π` back between the half steps and reading it again
/// cost the scalar many-body path 4% (5.08 against 4.87 M body-steps/s).
///
/// Reference: P. Krysl, Int. J. Numer. Meth. Engng 63 (2005) (M); T. Lee, M. Leok,
/// N. H. McClamroch, Comput. Methods Appl. Mech. Engrg. 196 (2007) (V).
#[inline]
pub(crate) fn free_rotation_by(
    drift: Drift,
    inertia: &PrincipalInertia,
    r: &mut Mat3,
    pi: &mut Vec3,
    hh: f64,
) -> std::result::Result<(), midpoint::NotConverged> {
    let (mut rotation, mut momentum) = (*r, Vec3::load_split(pi));
    for _ in 0..2 {
        let (inc, _) = drift.solve_increment(inertia, momentum, hh)?;
        rotation = inc.rotate(&rotation);
        momentum = inc.inverse_apply(momentum);
    }
    (*r, *pi) = (rotation, momentum);
    Ok(())
}
