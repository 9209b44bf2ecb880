//! The adaptive baseline: Dormand-Prince 8(5,3) (the `ode_solvers` crate's `Dop853`) on
//! `(Π, q)` with `Π' = Π × W + T(R(q/|q|), t)`, `q' = ½ q ⊗ (0, W)`; the quaternion is
//! renormalised only at output, as a user of a general ODE solver would do.

use std::cell::Cell;

use liemid::so3::Quaternion;
use liemid::{Diagnostics, RigidBodySystem, RigidState, Vec3};
use ode_solvers::{Dop853, OutputType, SVector, System};

type State = SVector<f64, 7>;

/// What a Dop853 run produced.
pub struct AdaptiveRun {
    /// The state at `t_end` (quaternion renormalised).
    pub state: RigidState,
    /// Right-hand-side evaluations (one torque evaluation each).
    pub evaluations: u64,
}

/// The right-hand side; the solver owns it, so its counters live outside.
struct RigidQuaternion<'a, S: ?Sized> {
    system: &'a S,
    track: Option<f64>,
    max_energy_error: &'a Cell<f64>,
}

fn unpack(y: &State) -> (Vec3, Quaternion) {
    (Vec3::new(y[0], y[1], y[2]), Quaternion::new(y[3], y[4], y[5], y[6]))
}

impl<S: RigidBodySystem + ?Sized> System<f64, State> for RigidQuaternion<'_, S> {
    fn system(&self, t: f64, y: &State, dy: &mut State) {
        let (pi, q) = unpack(y);
        let w = self.system.inertia().apply_inverse(pi);
        let dpi = pi.cross(w) + self.system.torque(&q.normalized().to_matrix(), t);
        let dq = q.mul(&Quaternion::new(0.0, 0.5 * w.x, 0.5 * w.y, 0.5 * w.z));
        *dy = State::from([dpi.x, dpi.y, dpi.z, dq.w, dq.x, dq.y, dq.z]);
    }

    fn solout(&mut self, t: f64, y: &State, _dy: &State) -> bool {
        if let Some(e0) = self.track {
            let (pi, q) = unpack(y);
            let d = Diagnostics::of(self.system, &RigidState::new(t, pi, q.normalized().to_matrix()));
            let err = if e0 != 0.0 {
                ((d.energy - e0) / e0).abs()
            } else {
                (d.energy - e0).abs()
            };
            self.max_energy_error.set(self.max_energy_error.get().max(err));
        }
        false
    }
}

/// Integrate with Dop853 at relative tolerance `rtol` (absolute tolerance `rtol` times the
/// initial momentum's size for `Π`, which makes both parts of the state O(1)-scaled).
pub fn dop853<S: RigidBodySystem + ?Sized>(
    system: &S,
    initial: RigidState,
    t_end: f64,
    rtol: f64,
) -> Result<AdaptiveRun, String> {
    let q = Quaternion::from_matrix(&initial.rotation);
    let pi = initial.pi;
    let y0 = State::from([pi.x, pi.y, pi.z, q.w, q.x, q.y, q.z]);
    let unused = Cell::new(0.0);
    let rhs = RigidQuaternion {
        system,
        track: None,
        max_energy_error: &unused,
    };
    let span = t_end - initial.t;
    let mut solver = Dop853::from_param(
        rhs,
        initial.t,
        t_end,
        span,
        y0,
        rtol,
        rtol * 1e-3,
        0.9,
        0.0,
        0.333,
        6.0,
        span,
        0.0,
        u32::MAX,
        1000,
        OutputType::Sparse,
    );
    let stats = solver
        .integrate()
        .map_err(|e| format!("Dop853 at rtol {rtol:e}: {e}"))?;
    let y = solver.y_out().last().ok_or("Dop853 produced no output")?;
    let (pi, q) = unpack(y);
    let state = RigidState::new(t_end, pi, q.normalized().to_matrix());
    Ok(AdaptiveRun {
        state,
        evaluations: u64::from(stats.num_eval),
    })
}

/// A Dop853 run that also tracks the largest relative energy error over the whole run, the
/// first tenth and the last tenth: `(max, first tenth, last tenth)`.
pub fn dop853_tenths<S: RigidBodySystem + ?Sized>(
    system: &S,
    initial: RigidState,
    t_end: f64,
    rtol: f64,
) -> Result<(f64, f64, f64), String> {
    let e0 = Diagnostics::of(system, &initial).energy;
    let span = t_end - initial.t;
    let q = Quaternion::from_matrix(&initial.rotation);
    let pi = initial.pi;
    let y0 = State::from([pi.x, pi.y, pi.z, q.w, q.x, q.y, q.z]);
    let max = Cell::new(0.0);
    let rhs = RigidQuaternion {
        system,
        track: Some(e0),
        max_energy_error: &max,
    };
    let mut solver = Dop853::from_param(
        rhs,
        initial.t,
        t_end,
        span,
        y0,
        rtol,
        rtol * 1e-3,
        0.9,
        0.0,
        0.333,
        6.0,
        span,
        0.0,
        u32::MAX,
        1000,
        OutputType::Sparse,
    );
    solver
        .integrate()
        .map_err(|e| format!("Dop853 at rtol {rtol:e}: {e}"))?;
    let (mut first, mut last) = (0.0f64, 0.0f64);
    for (t, y) in solver.x_out().iter().zip(solver.y_out()) {
        let (pi, q) = unpack(y);
        let d = Diagnostics::of(system, &RigidState::new(*t, pi, q.normalized().to_matrix()));
        let e = if e0 != 0.0 {
            ((d.energy - e0) / e0).abs()
        } else {
            (d.energy - e0).abs()
        };
        if *t <= initial.t + 0.1 * span {
            first = first.max(e);
        }
        if *t >= t_end - 0.1 * span {
            last = last.max(e);
        }
    }
    drop(solver);
    Ok((max.get(), first, last))
}
