//! The adaptive baseline: Dormand-Prince 8(5,3) (the `ode_solvers` crate's `Dop853`) on
//! `(Π, q)` with `Π' = Π × W + T(R(q/|q|), t)`, `q' = ½ q ⊗ (0, W)`; the quaternion is
//! renormalised only at output, as a user of a general ODE solver would do.

use crate::shared::dop853::dop853;
use liemid::so3::Quaternion;
use liemid::{Diagnostics, RigidBodySystem, RigidState, Vec3};
use ode_solvers::{Dop853, SVector, System};

type State = SVector<f64, 7>;

/// What a Dop853 run produced.
pub struct AdaptiveRun {
    /// The state at `t_end` (quaternion renormalised).
    pub state: RigidState,
    /// Right-hand-side evaluations (one torque evaluation each).
    pub evaluations: u64,
}

/// The right-hand side on `(Π, q)`, and whether the caller asks the run to stop.
struct RigidQuaternion<'a, S: ?Sized> {
    system: &'a S,
    stop: &'a dyn Fn() -> bool,
}

fn unpack(y: &State) -> (Vec3, Quaternion) {
    (Vec3::new(y[0], y[1], y[2]), Quaternion::new(y[3], y[4], y[5], y[6]))
}

fn state_of(t: f64, y: &State) -> RigidState {
    let (pi, q) = unpack(y);
    RigidState::new(t, pi, q.normalized().to_matrix())
}

impl<S: RigidBodySystem + ?Sized> System<f64, State> for RigidQuaternion<'_, S> {
    fn system(&self, t: f64, y: &State, dy: &mut State) {
        let (pi, q) = unpack(y);
        let w = self.system.inertia().apply_inverse(pi);
        let dpi = pi.cross(w) + self.system.torque(&q.normalized().to_matrix(), t);
        let dq = q.mul(&Quaternion::new(0.0, 0.5 * w.x, 0.5 * w.y, 0.5 * w.z));
        *dy = State::from([dpi.x, dpi.y, dpi.z, dq.w, dq.x, dq.y, dq.z]);
    }

    /// Read after every accepted step: `true` ends the run there.
    fn solout(&mut self, _t: f64, _y: &State, _dy: &State) -> bool {
        (self.stop)()
    }
}

type Solver<'a, S> = Dop853<f64, State, RigidQuaternion<'a, S>>;

/// Integrate at relative tolerance `rtol` (absolute `rtol/1000`), keeping every accepted
/// step; returns the solver (with its outputs) and the number of evaluations. `stop` is
/// read after every accepted step; once it returns `true` the run ends with an error.
fn integrate<'a, S: RigidBodySystem + ?Sized>(
    system: &'a S,
    initial: RigidState,
    t_end: f64,
    rtol: f64,
    stop: &'a dyn Fn() -> bool,
) -> Result<(Solver<'a, S>, u64), String> {
    let q = Quaternion::from_matrix(&initial.rotation);
    let pi = initial.pi;
    let y0 = State::from([pi.x, pi.y, pi.z, q.w, q.x, q.y, q.z]);
    let span = t_end - initial.t;
    let mut solver = dop853!(RigidQuaternion { system, stop }, initial.t, t_end, span, y0, rtol,);
    let stats = solver
        .integrate()
        .map_err(|e| format!("Dop853 at rtol {rtol:e}: {e}"))?;
    if stop() {
        return Err(format!("Dop853 at rtol {rtol:e}: stopped"));
    }
    Ok((solver, u64::from(stats.num_eval)))
}

/// Integrate with Dop853 at relative tolerance `rtol` to `t_end`.
pub fn dop853<S: RigidBodySystem + ?Sized>(
    system: &S,
    initial: RigidState,
    t_end: f64,
    rtol: f64,
) -> Result<AdaptiveRun, String> {
    dop853_until(system, initial, t_end, rtol, &|| false)
}

/// [`dop853()`], ended (with an error) after the first accepted step at which `stop`
/// returns `true`.
pub fn dop853_until<S: RigidBodySystem + ?Sized>(
    system: &S,
    initial: RigidState,
    t_end: f64,
    rtol: f64,
    stop: &dyn Fn() -> bool,
) -> Result<AdaptiveRun, String> {
    let (solver, evaluations) = integrate(system, initial, t_end, rtol, stop)?;
    let y = solver.y_out().last().ok_or("Dop853 produced no output")?;
    Ok(AdaptiveRun {
        state: state_of(t_end, y),
        evaluations,
    })
}

/// The largest relative energy error of a Dop853 run over all accepted steps, over the
/// first tenth and over the last tenth of the run: `(max, first tenth, last tenth)`.
pub fn dop853_tenths<S: RigidBodySystem + ?Sized>(
    system: &S,
    initial: RigidState,
    t_end: f64,
    rtol: f64,
) -> Result<(f64, f64, f64), String> {
    let e0 = Diagnostics::of(system, &initial).energy;
    let span = t_end - initial.t;
    let (solver, _) = integrate(system, initial, t_end, rtol, &|| false)?;
    let (mut max, mut first, mut last) = (0.0f64, 0.0f64, 0.0f64);
    for (t, y) in solver.x_out().iter().zip(solver.y_out()) {
        let d = Diagnostics::of(system, &state_of(*t, y));
        let e = if e0 != 0.0 {
            ((d.energy - e0) / e0).abs()
        } else {
            (d.energy - e0).abs()
        };
        max = max.max(e);
        if *t <= initial.t + 0.1 * span {
            first = first.max(e);
        }
        if *t >= t_end - 0.1 * span {
            last = last.max(e);
        }
    }
    Ok((max, first, last))
}
