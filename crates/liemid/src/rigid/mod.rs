//! A rigid body about a fixed point: the paper's core domain.
//!
//! **Model** ([`body`], re-exported here): the state `(t, Π, R)` ([`RigidState`]), the
//! [`RigidBodySystem`] trait (inertia and torque model: [`HeavyTop`], [`FreeBody`],
//! [`ConstantTorque`], [`TorqueFn`]) and the [`Diagnostics`] of a state; the validated
//! body tensor is the crate's [`crate::inertia`], shared with every rotating domain. Equations of motion in the body frame:
//! `Π' = Π × Ω + T(R, t)`, `Ω = I⁻¹ Π`, `R' = R hat(Ω)`.
//!
//! **Methods**: [`crate::midpoint`] (at the crate's root, shared) solves the midpoint equation `(1/h) I Ψ = exp(−Ψ/2) P` that
//! every LIEMID step is built on; [`rotation`] holds one type per method (LIEMID\[E1\],
//! \[E2\], \[EA\], \[I\], AKW, Simo-Wong, NMB, RK4, RKMK4, and LIEMID\[EX\]/\[FS\] on
//! [`free_flow`], the exact torque-free flow), selected by name through
//! [`rotation::RotationMethod`]; [`driver`] runs any of them from `t0` to `t_end` with an
//! observer and the extremes of the diagnostics.
//!
//! **Adaptive steps** ([`adaptive`]): Hairer and Söderlind's explicit, time-reversible
//! step-size control for the symmetric methods; [`satellite`]: a rigid satellite on an
//! eccentric orbit, translation and attitude by one coupled splitting.
//!
//! **Problems** ([`problems`]): the fast and slow Lagrangian tops, the torque-dominated
//! symmetric and asymmetric tops and the free asymmetric body, each with its initial state
//! and end time.
//!
//! ## Reference
//! P. Krysl, *Explicit momentum-conserving integrator for dynamics of rigid bodies
//! approximating the midpoint Lie algorithm*, Int. J. Numer. Meth. Engng 63 (2005).

pub mod adaptive;
pub mod body;
pub mod driver;
pub mod free_flow;
pub mod problems;
pub mod rotation;
pub mod satellite;

/// The inertia tensor and the midpoint solve, foundations every rotating domain uses, as
/// this module named them before they moved to the crate's root.
pub use crate::{inertia, midpoint};
pub use body::*;
