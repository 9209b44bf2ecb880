//! # liemid
//!
//! Structure-preserving time integration of mechanical systems, built around the explicit
//! midpoint Lie integrators for rigid-body rotation (LIEMID\[E1\], LIEMID\[E2\] and their
//! alternating, second-order, symplectic, momentum-conserving composition LIEMID\[EA\]).
//!
//! - [`so3`]: hat/vee, `exp`, `log`, Jacobians, Cayley, quaternions.
//! - [`rigid`]: the rigid-body state, the [`RigidBodySystem`] trait, models
//!   ([`HeavyTop`], [`FreeBody`], [`ConstantTorque`], [`TorqueFn`]) and [`Diagnostics`].
//! - [`rotation`]: one type per method ([`LieMidpointAlternating`], …) behind
//!   [`RotationIntegrator`], and [`RotationMethod`] for selection by name.
//! - [`free_flow`]: the exact torque-free flow ([`FreeFlow`]: closed form for symmetric
//!   bodies, Jacobi elliptic functions for asymmetric ones).
//! - [`midpoint`]: the midpoint equation `(1/h) I Ψ = exp(−Ψ/2) P` and its Newton solver.
//! - [`composition`]: symmetric compositions (Suzuki, Yoshida, Kahan-Li) of EA or Verlet
//!   up to eighth order.
//! - [`vector`]: symplectic Euler, its adjoint, Verlet and explicit Newmark on `ℝⁿ`.
//! - [`many`] (with [`many::interactions`], also at [`interactions`]): N interacting rigid bodies (independent heavy tops,
//!   dipoles), stepped in parallel by the splitting integrator, identical for any thread
//!   count.
//! - [`driver`]: [`integrate`] from `t0` to `t_end` with an observer and diagnostics.
//! - [`problems`]: the fast and slow Lagrangian tops, a torque-dominated top, a free body,
//!   and vector-space test problems with exact solutions.
//!
//! ```
//! use liemid::{problems, LieMidpointAlternating, RotationIntegrator};
//! let top = problems::fast_top();
//! let mut ea = LieMidpointAlternating::new();
//! let mut state = top.initial;
//! for _ in 0..100 {
//!     ea.step(&top.system, &mut state, 1e-4).unwrap();
//! }
//! // The vertical spatial angular momentum is kept to round-off.
//! let drift = (state.spatial_momentum().z - top.initial.spatial_momentum().z).abs();
//! assert!(drift < 1e-14);
//! ```
#![warn(missing_docs)]
#![allow(non_snake_case)]

pub mod beam;
pub mod composition;
pub mod driver;
pub mod error;
pub mod free_flow;
pub mod inertia;
pub mod linalg;
pub mod many;
pub use many::interactions;
pub mod midpoint;
pub mod multibody;
pub mod problems;
pub mod random;
pub mod rigid;
pub mod rotation;
pub mod so3;
pub mod spin;
mod team;
pub mod vector;

pub use composition::{Composition, Scheme};
pub use driver::{advance, integrate, integrate_to, observed_order, step_count, Run, RunSummary, MAX_STEPS};
pub use error::{Error, Result};
pub use free_flow::FreeFlow;
pub use inertia::{Inertia, InertiaOperator, PrincipalInertia};
pub use linalg::{Mat3, Vec3};
pub use rigid::{
    ConstantTorque, CountingTorque, Diagnostics, FreeBody, HeavyTop, RigidBodySystem, RigidState, TorqueFn,
};
pub use rotation::{
    AnyRotationIntegrator, AustinKrishnaprasadWang, KryslEndresNewmark, LieMidpointAlternating, LieMidpointE1,
    LieMidpointE2, LieMidpointExact, LieMidpointImplicit, MethodCache, RotationIntegrator, RotationMethod,
    RungeKutta4Quaternion, RungeKuttaMuntheKaas4, SimoWong,
};
