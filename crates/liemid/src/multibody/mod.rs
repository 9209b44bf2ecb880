//! Jointed rigid bodies (multibody systems) in maximal coordinates: RATTLE with the
//! rotation of LIEMID\[EA\].
//!
//! **Model.** Each body `i` carries its centre of mass `c_i`, linear momentum `p_i`,
//! attitude `R_i` and body angular momentum `Π_i` about the centre of mass
//! ([`MultibodyState`]); joints (ball, universal, hinge, slide, weld, free) are holonomic
//! constraints `g(c, R) = 0` whose gradients act through body-frame rotation increments
//! ([`constraints`]). A [`Model`] (from code, [`problems`], or a file loader) lists bodies,
//! tree joints in body order, loop-closing joints, gravity and MuJoCo-layout joint
//! coordinates; [`Model::initial_state`] does the forward kinematics.
//!
//! **Method.** [`Rattle::step`] is RATTLE (a symmetric constrained Verlet, symplectic when
//! its unconstrained part is) whose free rotation is LIEMID\[EA\]'s torque-free pair of
//! midpoint half steps, which is not symplectic (a Lie–Poisson defect of `O(h³)` per step,
//! docs/theory/rigid.md §9), so neither is the step; it is symmetric:
//!
//! ```text
//! p½ = p + (h/2)(F + G_cᵀλ),  P = Π + (h/2)(T + G_θᵀλ)
//! c⁺ = c + h M⁻¹ p½;  R⁺, Π' from two midpoint solves (M) of step h/2;  g(q⁺) = 0
//! p⁺ = p½ + (h/2)(F⁺ + G_c⁺ᵀμ),  Π⁺ = Π' + (h/2)(T⁺ + G_θ⁺ᵀμ);  G⁺ (v⁺, Ω⁺) = 0
//! ```
//!
//! second order, time reversible, keeping the constraints at round-off each step, the
//! energy error bounded and the total momenta of internal forces exactly
//! ([`rattle`]). [`MultibodyMethod`] adds symmetric compositions of orders 4, 6, 8. The
//! matrices `G M⁻¹ Gᵀ` are factored in O(bodies) by leaves-to-root block elimination of the
//! body-joint tree, with a pseudo-inverted Schur complement for closed loops with redundant
//! rows ([`solver`]); the symmetric ones, one per step, by block Cholesky.
//!
//! **Problems** ([`problems`]): a double pendulum, ball-joint chains (`chain(10)`,
//! `chain(1000)`), a spinning spacecraft with hinged panels, a four-bar linkage of four
//! hinges, and the test chain of docs/theory/multibody.md §5 (two hinges and a ball). [`MultibodyEnsemble`] steps
//! independent copies on threads, bitwise the same for any thread count. Tests:
//! `tests/multibody.rs`.
//!
//! References: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd
//! ed., Springer 2006, VII.1 (RATTLE); B. Leimkuhler, S. Reich, *Simulating Hamiltonian
//! Dynamics*, Cambridge 2004, ch. 7-8; D. Baraff, "Linear-time dynamics using Lagrange
//! multipliers", SIGGRAPH 1996; P. Krysl, Int. J. Numer. Meth. Engng 63 (2005).

mod armature;
mod blocks;
mod cholesky;
pub mod constraints;
pub mod contact;
pub mod control;
mod dampers;
pub mod driver;
pub mod ensemble;
mod forces;
mod friction;
pub mod joint_space;
pub mod mesh;
pub mod method;
pub mod mjcf;
pub mod model;
mod positions;
mod predictor;
pub mod problems;
mod projection;
pub mod rattle;
pub mod shapes;
pub mod solver;
pub mod state;
mod step_check;
pub mod system;
pub mod urdf;
mod velocities;
mod workspace;
mod xml;

pub use constraints::{JointGeometry, JointRows, Row};
pub use contact::Collision;
pub use control::ControlTable;
pub use driver::{joint_space_notes, JointSpaceRun, ModelNote, MultibodyRun, Prepared, Simulation};
pub use ensemble::MultibodyEnsemble;
pub use joint_space::JointSpaceModel;
pub use mesh::Mesh;
pub use method::{Drift, LimitState, MultibodyMethod, StepReport};
pub use model::{Actuator, Body, Joint, JointKind, Link, Model};
pub use rattle::Rattle;
pub use shapes::{Shape, ShapeKind};
pub use state::MultibodyState;
pub use system::{ForceHook, MultibodySystem};
pub use xml::Loaded;
