//! LIEMID\[EAV\]: EA's impulses around the variational torque-free step.
//!
//! The same half impulses as LIEMID\[EA\] at the start and the end of the step, and between
//! them two torque-free half steps of the variational equation (V) of
//! [`crate::variational`] in place of the midpoint equation (M):
//!
//! ```text
//! P = Π_n + (h/2) T_n;            solve (V) with (P, h/2) → Ψ₁;
//! R½ = R_n exp(Ψ₁);               Π½ = exp(−Ψ₁) P;
//! solve (V) with (Π½, h/2) → Ψ₂;  R_{n+1} = R½ exp(Ψ₂);
//! Π_{n+1} = exp(−Ψ₂) Π½ + (h/2) T(R_{n+1}, t_{n+1})
//! ```
//!
//! Second order and symmetric; each part is a Lie–Poisson map (the impulses are exact flows
//! of the potential, the drift is the discrete Euler–Poincaré flow), so the step is, as
//! measured by `tests/rigid/structure.rs`. It keeps `|Π|` and `π` exactly torque-free and
//! `π · ĝ` for a heavy top, as EA does; one torque evaluation per step in a run.
//!
//! Reference: docs/theory/rigid.md §9; T. Lee, M. Leok, N. H. McClamroch, *Lie group
//! variational integrators for the full body problem*, Comput. Methods Appl. Mech. Engrg.
//! 196 (2007).

use super::liemid::alternating_step;
use super::{check_step, commit, newton_error, RotationIntegrator, TorqueCache};
use crate::error::Result;
use crate::linalg::Vec3;
use crate::rigid::{RigidBodySystem, RigidState};
use crate::so3;

/// LIEMID\[EAV\]: EA's half impulses around two variational torque-free half steps (see
/// the module documentation). Second order, symmetric, Lie–Poisson.
#[derive(Clone, Debug, Default)]
pub struct LieVariationalAlternating {
    pub(super) cache: TorqueCache,
}

impl LieVariationalAlternating {
    /// A new integrator.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }
}

impl RotationIntegrator for LieVariationalAlternating {
    fn name(&self) -> &'static str {
        "LIEMID[EAV]"
    }
    fn order(&self) -> u32 {
        2
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        alternating_step!(
            self,
            system,
            state,
            h,
            crate::variational::solve_increment,
            "variational equation (V)"
        )
    }
    fn reset(&mut self) {
        self.cache.clear();
    }
}
