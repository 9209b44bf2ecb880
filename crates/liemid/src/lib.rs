//! # liemid
//!
//! Structure-preserving time integration of mechanical systems, built around the explicit
//! midpoint Lie integrators for rigid-body rotation (LIEMID\[E1\], LIEMID\[E2\] and their
//! alternating, second-order, time-reversible, momentum-conserving composition LIEMID\[EA\];
//! the source paper calls EA symplectic, measurement says its Lie–Poisson defect is `O(h³)`
//! per step, and LIEMID\[EAV\] is the Lie–Poisson variant, docs/theory/rigid.md §9).
//!
//! One folder per domain, each with its model, interaction, methods and problems:
//! - [`rigid`]: a rigid body about a fixed point (the paper's core): state, models,
//!   [`Diagnostics`], the midpoint solver, one type per method in [`rigid::rotation`]
//!   behind [`RotationIntegrator`], the exact free flow [`FreeFlow`], the driver
//!   ([`integrate`]) and [`rigid::problems`].
//! - [`many`]: N interacting rigid bodies (independent heavy tops, dipoles), stepped in
//!   parallel by the splitting integrator, identical for any thread count.
//! - [`spin`]: atomistic spin lattices (the LLG equation) by an exact-flow splitting.
//! - [`beam`]: flexible 3-D beam frames, nodes as rigid bodies.
//! - [`multibody`]: rigid bodies joined by joints (RATTLE on EA's rotation), read from
//!   MJCF and URDF files.
//! - [`vector`]: symplectic Euler, its adjoint, Verlet and explicit Newmark on `ℝⁿ`, with
//!   test problems in [`vector::problems`].
//!
//! Shared foundations at the root: [`variational`] (the variational torque-free equation),
//! [`linalg`] (vectors, matrices, the symmetric 3x3 eigen
//! solver), [`so3`] (hat/vee, `exp`, `log`, Jacobians, Cayley, quaternions, the series
//! coefficients), [`inertia`] (the validated body tensor), [`midpoint`] (the midpoint solve
//! every rotating domain's step is built on, and the map of a failed solve to an error),
//! [`composition`] (symmetric compositions up to eighth order of any symmetric method),
//! [`random`] and [`error`] (with the step check).
//!
//! ```
//! use liemid::{rigid::problems, LieMidpointAlternating, RotationIntegrator};
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
pub mod error;
pub mod inertia;
pub mod linalg;
pub mod many;
pub mod midpoint;
pub use many::interactions;
pub mod multibody;
pub mod random;
pub mod rigid;
pub mod so3;
pub mod spin;
mod team;
pub mod variational;
pub mod vector;

pub use composition::{Composition, Scheme};
pub use error::{Error, Result};
pub use inertia::{Inertia, InertiaOperator, PrincipalInertia};
pub use linalg::{Mat3, Vec3};
pub use rigid::adaptive::{AdaptiveRun, AdaptiveStats, ReversibleStepper, RigidAdaptive};
pub use rigid::driver::{advance, integrate, integrate_to, observed_order, step_count, Run, RunSummary, MAX_STEPS};
pub use rigid::free_flow::FreeFlow;
pub use rigid::rotation::{
    AnyRotationIntegrator, AustinKrishnaprasadWang, KryslEndresNewmark, LieMidpointAlternating, LieMidpointE1,
    LieMidpointE2, LieMidpointExact, LieMidpointImplicit, LieVariationalAlternating, MethodCache, RotationIntegrator,
    RotationMethod, RungeKutta4Quaternion, RungeKuttaMuntheKaas4, SimoWong,
};
pub use rigid::{
    ConstantTorque, CountingTorque, Diagnostics, FreeBody, HeavyTop, RigidBodySystem, RigidState, TorqueFn,
};
