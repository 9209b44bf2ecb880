//! Named rigid-body problems (a body about a fixed point) with their initial states and
//! default end times, shared by the tests, the benchmarks and the command-line tool.

use crate::inertia::Inertia;
use crate::linalg::{Mat3, Vec3};
use crate::rigid::{FreeBody, HeavyTop, RigidState};
use crate::so3;

/// A rigid-body problem: a system, an initial state and a default end time.
#[derive(Clone, Debug)]
pub struct RigidProblem<S> {
    /// Short name, e.g. `fast-top`.
    pub name: &'static str,
    /// One line on what it is.
    pub description: &'static str,
    /// The system.
    pub system: S,
    /// The initial state at `t = 0`.
    pub initial: RigidState,
    /// The default end time.
    pub t_end: f64,
}

fn block_top(name: &'static str, description: &'static str, spin: f64) -> RigidProblem<HeavyTop> {
    let system = HeavyTop::lagrangian_block();
    let initial = RigidState::from_angular_velocity(
        0.0,
        &system.inertia,
        Vec3::new(0.0, 0.0, spin),
        so3::exp(Vec3::new(0.05, 0.0, 0.0)),
    );
    RigidProblem {
        name,
        description,
        system,
        initial,
        t_end: 0.8,
    }
}

/// The fast Lagrangian top of the paper (docs/theory/rigid.md §8): an aluminium block spinning at
/// `Ω₀ = (0, 0, 313π)` rad/s, tilted by 0.05 rad about `e₁`, to `t = 0.8` s.
#[must_use]
pub fn fast_top() -> RigidProblem<HeavyTop> {
    block_top(
        "fast-top",
        "fast Lagrangian top: aluminium block, spin 313*pi rad/s, tilt 0.05 rad, t = 0.8 s",
        313.0 * std::f64::consts::PI,
    )
}

/// The same top spinning slower, `Ω₀ = (0, 0, 90π)` rad/s.
#[must_use]
pub fn slow_top() -> RigidProblem<HeavyTop> {
    block_top(
        "slow-top",
        "slow Lagrangian top: the same block, spin 90*pi rad/s, t = 0.8 s",
        90.0 * std::f64::consts::PI,
    )
}

/// A torque-dominated top, where the first-order torque error of E1 and E2 is visible:
/// `I = diag(5, 5, 1)`, `m = 1`, centre of mass `(0, 0, 1)`, `g = 9.81`,
/// `R₀ = exp(0.3 e₁)`, `Ω₀ = (0, 0, 20)`, to `t = 1`.
#[must_use]
pub fn torque_dominated_top() -> RigidProblem<HeavyTop> {
    let inertia = Inertia::principal([5.0, 5.0, 1.0]).expect("positive");
    let system = HeavyTop::new(inertia, 1.0, Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -9.81)).expect("finite");
    let initial = RigidState::from_angular_velocity(
        0.0,
        &inertia,
        Vec3::new(0.0, 0.0, 20.0),
        so3::exp(Vec3::new(0.3, 0.0, 0.0)),
    );
    RigidProblem {
        name: "torque-top",
        description: "torque-dominated top: I = diag(5, 5, 1), m = 1, X = (0, 0, 1), spin 20 rad/s, t = 1 s",
        system,
        initial,
        t_end: 1.0,
    }
}

/// A torque-dominated asymmetric top, where the free spin is slow against the torque and
/// the exact flow gains little over the midpoint rule: `I = diag(5, 4, 1.5)`, `m = 1`,
/// centre of mass `(0, 0, 1)`, `g = 9.81`, `R₀ = exp(0.3 e₁)`, `Ω₀ = (0, 0, 30)`, to `t = 1`.
#[must_use]
pub fn asymmetric_top() -> RigidProblem<HeavyTop> {
    let inertia = Inertia::principal([5.0, 4.0, 1.5]).expect("positive");
    let system = HeavyTop::new(inertia, 1.0, Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -9.81)).expect("finite");
    let initial = RigidState::from_angular_velocity(
        0.0,
        &inertia,
        Vec3::new(0.0, 0.0, 30.0),
        so3::exp(Vec3::new(0.3, 0.0, 0.0)),
    );
    RigidProblem {
        name: "asymmetric-top",
        description:
            "torque-dominated asymmetric top: I = diag(5, 4, 1.5), m = 1, X = (0, 0, 1), spin 30 rad/s, t = 1 s",
        system,
        initial,
        t_end: 1.0,
    }
}

/// A free asymmetric body spun about its intermediate axis (the tennis-racket or
/// Dzhanibekov flip): `I = diag(1, 2, 3)`, `Ω₀ = (0.01, 10, 0)`, to `t = 10`.
#[must_use]
pub fn free_body() -> RigidProblem<FreeBody> {
    let inertia = Inertia::principal([1.0, 2.0, 3.0]).expect("positive");
    RigidProblem {
        name: "free-body",
        description: "free asymmetric body about its intermediate axis (tennis-racket flip), t = 10 s",
        system: FreeBody::new(inertia),
        initial: RigidState::from_angular_velocity(0.0, &inertia, Vec3::new(0.01, 10.0, 0.0), Mat3::IDENTITY),
        t_end: 10.0,
    }
}
