//! The method choices and per-step reports of the multibody step.
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd
//! ed., V.3 (compositions), VII.1 (RATTLE).

use crate::composition::Scheme;

/// The torque-free rotation inside the drift of the multibody step: a foundation
/// ([`crate::variational::Drift`]), shared with the beams' node rotations.
pub use crate::variational::Drift;

/// Iteration cap of the position (λ) solve.
pub const MAX_ITERATIONS: u32 = 60;

/// Most re-solves of one step for joint limits switching on or off.
pub const MAX_LIMIT_PASSES: u32 = 8;

/// The integration method: the RATTLE/EA step or a symmetric composition of it.
///
/// Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, V.3.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MultibodyMethod {
    /// The second-order step.
    Liemid,
    /// Suzuki's 5-stage composition, order 4.
    Liemid4,
    /// Kahan-Li 9-stage composition, order 6.
    Liemid6,
    /// Kahan-Li 17-stage composition, order 8.
    Liemid8,
}

impl MultibodyMethod {
    /// All methods, lowest order first.
    pub const ALL: [MultibodyMethod; 4] = [Self::Liemid, Self::Liemid4, Self::Liemid6, Self::Liemid8];

    /// The key on the command line, in scenario files and in Python (`liemid`,
    /// `liemid4`, `liemid6`, `liemid8`).
    #[must_use]
    pub fn key(&self) -> &'static str {
        match self {
            Self::Liemid => "liemid",
            Self::Liemid4 => "liemid4",
            Self::Liemid6 => "liemid6",
            Self::Liemid8 => "liemid8",
        }
    }

    /// The method of a key ([`MultibodyMethod::key`]).
    #[must_use]
    pub fn from_key(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.key() == key)
    }

    /// One line on what the method is.
    #[must_use]
    pub fn description(&self) -> &'static str {
        match self {
            Self::Liemid => "RATTLE with LIEMID[EA]'s rotation in maximal coordinates (joints, limits, dampers)",
            Self::Liemid4 => "the RATTLE step composed by Suzuki's 5-stage scheme",
            Self::Liemid6 => "the RATTLE step composed by Kahan-Li's 9-stage scheme",
            Self::Liemid8 => "the RATTLE step composed by Kahan-Li's 17-stage scheme",
        }
    }

    /// The name (`MB-LIEMID`, `MB-LIEMID4`, ...).
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Self::Liemid => "MB-LIEMID",
            Self::Liemid4 => "MB-LIEMID4",
            Self::Liemid6 => "MB-LIEMID6",
            Self::Liemid8 => "MB-LIEMID8",
        }
    }

    /// The composition scheme, `None` for the base step.
    #[must_use]
    pub fn scheme(&self) -> Option<Scheme> {
        match self {
            Self::Liemid => None,
            Self::Liemid4 => Some(Scheme::SUZUKI4),
            Self::Liemid6 => Some(Scheme::KAHAN_LI6),
            Self::Liemid8 => Some(Scheme::KAHAN_LI8),
        }
    }

    /// The order of accuracy.
    #[must_use]
    pub fn order(&self) -> u32 {
        self.scheme().map_or(2, |s| s.order)
    }
}

/// What a step did.
///
/// Reference: docs/theory/multibody.md §5 (constraints at round-off every step).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Quasi-Newton iterations of the position solve, over all stages.
    pub iterations: u32,
    /// Factorizations of `G M⁻¹ Gᵀ`, over all stages.
    pub factorizations: u32,
    /// Largest `|g|` at the end (length rows divided by the model's length scale).
    pub position_violation: f64,
    /// Largest `|G (v, Ω)|` at the end, divided by `max_i (|v_i| + L |Ω_i|)` (at least
    /// `√(|g| L)`, [`super::MultibodySystem::velocity_floor`]).
    pub velocity_violation: f64,
    /// Joint limits switched on or off.
    pub limit_changes: u32,
    /// Most contact points of a stage (found at its start, touching or within reach).
    pub contacts: u32,
    /// Outer iterations of the contact position problem (each re-runs the drift), over
    /// all stages.
    pub contact_iterations: u32,
    /// Projected Gauss–Seidel sweeps of the contact problems, over all stages (over free
    /// bodies, solved island by island, a solve counts its islands' most).
    pub contact_sweeps: u32,
    /// The deepest penetration found at a stage's start (m; 0 when none).
    pub penetration: f64,
    /// Contact steps whose solve failed and were redone as two half steps (each half
    /// split again where it fails, to `h / 16`), over all levels.
    pub split_steps: u32,
    /// Contact steps of `h / 16` whose solve failed, taken again with a drift that
    /// holds no contact by friction (friction in the closing kick only).
    pub frictionless_drifts: u32,
    /// Contact stages taken with the position problem's law holding to `1e-8` of the
    /// contact length where its iteration stopped short of `1e-12` (`contact/step.rs`),
    /// and the largest such violation (relative to the length).
    pub loose_steps: u32,
    /// See `loose_steps`.
    pub loose_violation: f64,
}

/// State of one joint limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitState {
    /// Not touching.
    Inactive,
    /// Held at the lower bound.
    Lower,
    /// Held at the upper bound.
    Upper,
}
