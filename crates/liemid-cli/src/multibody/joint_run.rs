//! Runs in joint coordinates on the articulated-body algorithm (`JointSpaceModel`):
//! classical RK4 at a fixed step, and Dormand-Prince 8(5,3) with step control (the
//! `ode_solvers` crate's `Dop853`) as the reference for studies without a peer installed.
//! Ball-joint quaternions are integrated as they are and normalised for output only (as a
//! user of a general ODE solver would); no constraint is involved.
//!
//! References: R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §7.3;
//! E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*, 2nd
//! ed., Springer 1993, II.5 and II.10 (DOP853).

use std::cell::RefCell;
use std::time::Instant;

use crate::shared::dop853::dop853;
use liemid::error::Num;
use liemid::multibody::{JointKind, JointSpaceModel};
use liemid::{Mat3, Vec3};
use ode_solvers::{DVector, System};
use serde_json::json;

use super::scenario::MultibodyScenario;
use super::sink::{after_step, Halt, Poses, Sink};
use crate::shared::command::Failure;
use crate::shared::interrupt::{progress, Interrupt};

/// A joint-coordinate state seen through [`Poses`].
struct Joint<'a> {
    kinds: &'a [JointKind],
    model: &'a mut JointSpaceModel,
    t: f64,
    q: &'a [f64],
    v: &'a [f64],
    poses: Vec<(Vec3, Mat3)>,
}

impl Poses for Joint<'_> {
    fn time(&self) -> f64 {
        self.t
    }
    fn energy(&mut self) -> f64 {
        self.model.energy(self.q, self.v).unwrap_or(f64::NAN)
    }
    fn pose(&mut self, i: usize) -> ([f64; 3], [f64; 4]) {
        if self.poses.is_empty() {
            self.poses = self.model.forward_kinematics(self.q).unwrap_or_default();
        }
        let Some(&(x, r)) = self.poses.get(i) else {
            return ([f64::NAN; 3], [f64::NAN; 4]);
        };
        let q = liemid::so3::Quaternion::from_matrix(&r);
        ([x.x, x.y, x.z], [q.w, q.x, q.y, q.z])
    }
    fn hinge_and_slide(&mut self, out: &mut Vec<f64>) {
        hinge_and_slide(self.kinds, self.q, out);
    }
}

/// The hinge angles and slide offsets from joint coordinates in MuJoCo's layout.
fn hinge_and_slide(kinds: &[JointKind], q: &[f64], out: &mut Vec<f64>) {
    let mut at = 0;
    for kind in kinds {
        if kind.axis().is_some() {
            out.push(q.get(at).copied().unwrap_or(f64::NAN));
        }
        at += kind.nq();
    }
}

fn model_of(sc: &MultibodyScenario) -> Result<JointSpaceModel, Failure> {
    JointSpaceModel::new(&sc.model).map_err(|e| Failure::Input(format!("{}: {e}", sc.name)))
}

fn observe(
    sink: &mut Sink,
    sc: &MultibodyScenario,
    model: &mut JointSpaceModel,
    t: f64,
    q: &[f64],
    v: &[f64],
) -> Result<(), Failure> {
    let kinds: Vec<JointKind> = sc.model.joints.iter().map(|j| j.kind).collect();
    sink.observe(&mut Joint {
        kinds: &kinds,
        model,
        t,
        q,
        v,
        poses: Vec::new(),
    })
}

/// The summary's method-independent part of a joint-coordinate run ending at `(q, v)`.
fn summary(
    sc: &MultibodyScenario,
    model: &mut JointSpaceModel,
    q: &[f64],
    max_energy: f64,
    written: Option<(String, u64)>,
) -> Result<serde_json::Value, Failure> {
    let poses = model.forward_kinematics(q).map_err(|e| Failure::Run(e.to_string()))?;
    let finals: Vec<_> = poses
        .iter()
        .enumerate()
        .map(|(i, (x, r))| {
            let qq = liemid::so3::Quaternion::from_matrix(r);
            json!({"name": sc.model.bodies[i].name, "xpos": [x.x, x.y, x.z], "xquat": [qq.w, qq.x, qq.y, qq.z]})
        })
        .collect();
    let kinds: Vec<JointKind> = sc.model.joints.iter().map(|j| j.kind).collect();
    let mut coords = Vec::new();
    hinge_and_slide(&kinds, q, &mut coords);
    let names = sc
        .model
        .joints
        .iter()
        .filter(|j| j.kind.axis().is_some())
        .map(|j| j.name.clone());
    let joints: Vec<_> = names
        .zip(coords)
        .map(|(name, value)| json!({"name": name, "value": value}))
        .collect();
    Ok(json!({
        "model": sc.name,
        "bodies": sc.model.bodies.len(),
        "max_relative_energy_error": max_energy,
        "max_position_constraint_violation": 0.0,
        "max_velocity_constraint_violation": 0.0,
        "max_momentum_change": null,
        "final": finals,
        "joints": joints,
        "ignored": sc.ignored,
        "trajectory": written.map(|(path, rows)| json!({"path": path, "rows": rows})),
    }))
}

/// Merge `extra`'s keys into the object `base`.
fn with(mut base: serde_json::Value, extra: serde_json::Value) -> serde_json::Value {
    if let (Some(b), serde_json::Value::Object(e)) = (base.as_object_mut(), extra) {
        b.extend(e);
    }
    base
}

/// Classical RK4 in joint coordinates: `n` steps of `h` (the last one landing on `t_end`).
pub(super) fn rk4(
    sc: &MultibodyScenario,
    (h, t_end, every, n): (f64, f64, u64, u64),
    table: Option<&liemid::multibody::ControlTable>,
    mut sink: Sink,
) -> Result<(serde_json::Value, Sink), Failure> {
    let mut model = model_of(sc)?;
    let (mut q, mut v) = (model.initial_q().to_vec(), model.initial_v().to_vec());
    let bodies = sc.model.bodies.len();
    observe(&mut sink, sc, &mut model, 0.0, &q, &v)?;
    let interrupt = Interrupt::install();
    let bar = progress(n, "steps", n >= 200_000);
    let started = Instant::now();
    // The stepping model and a second one for the observations (the driver borrows the first).
    let mut seen = model_of(sc)?;
    let mut stop: Option<Halt> = None;
    let observer = |k: u64, t: f64, q: &[f64], v: &[f64]| -> Result<(), String> {
        if k % every == 0 || k == n {
            if let Err(failure) = observe(&mut sink, sc, &mut seen, t, q, v) {
                stop = Some(Halt::Output(failure));
                return Err("the output failed".into());
            }
        }
        after_step(k, n, &bar, &interrupt, &mut stop)
    };
    // A table's control, held over each step from its start (docs/theory/multibody.md §8).
    let outcome = match table {
        None => model.integrate_rk4(&mut q, &mut v, (0.0, t_end, h), observer),
        Some(table) => model.integrate_rk4_controlled(
            &mut q,
            &mut v,
            (0.0, t_end, h),
            |t, _, _, u| {
                u.copy_from_slice(table.at(t));
                Ok(())
            },
            observer,
        ),
    };
    bar.finish_and_clear();
    let max_energy = match (outcome, stop) {
        (Ok(run), _) => run.max_energy_error,
        (Err(_), Some(Halt::Output(failure))) => return Err(failure),
        (Err(liemid::Error::ObserverFailed { t, .. }), Some(Halt::Signal(signal, done))) => {
            return Err(sink.stopped(signal, t, done, n))
        }
        (Err(e), _) => return Err(sink.failed(format!("{}: {e}", sc.name))),
    };
    let seconds = started.elapsed().as_secs_f64();
    let written = sink.finish()?;
    let base = summary(sc, &mut model, &q, max_energy, written)?;
    let summary = with(
        base,
        json!({
            "method": "RK4 (joint coordinates)",
            "step": h,
            "t_end": t_end,
            "steps": n,
            "stepping_seconds": seconds,
            "body_steps_per_second": (bodies as f64 * n as f64) / seconds.max(1e-12),
        }),
    );
    Ok((summary, sink))
}

/// The first-order system `y = [q; v]`, `y' = [Q(q) v; ABA(q, v, 0)]` for `Dop853`.
struct Rhs<'a> {
    model: &'a RefCell<JointSpaceModel>,
    error: &'a RefCell<Option<String>>,
    interrupt: Interrupt,
}

impl System<f64, DVector<f64>> for Rhs<'_> {
    fn system(&self, t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) {
        if let Err(e) = self.model.borrow_mut().derivative(t, y.as_slice(), dy.as_mut_slice()) {
            self.error.borrow_mut().get_or_insert_with(|| e.to_string());
            dy.fill(f64::NAN);
        }
    }

    /// Stop at the first failed evaluation or a signal.
    fn solout(&mut self, _t: f64, y: &DVector<f64>, _dy: &DVector<f64>) -> bool {
        self.error.borrow().is_some() || !y.iter().all(|x| x.is_finite()) || self.interrupt.requested().is_some()
    }
}

/// Dormand-Prince 8(5,3) at relative tolerance `rtol` (absolute `rtol / 1000`) to `t_end`;
/// the trajectory holds every `every`-th accepted step and the last one (at `t_end`), the
/// energy error is the largest over the accepted steps.
pub(super) fn dop853(
    sc: &MultibodyScenario,
    rtol: f64,
    t_end: f64,
    (every, max_steps): (u64, Option<u64>),
    mut sink: Sink,
) -> Result<(serde_json::Value, Sink), Failure> {
    // The step bound, honoured as the solver's own limit (its steps are not known ahead).
    let bound = max_steps.unwrap_or(crate::shared::command::DEFAULT_MAX_STEPS);
    let model = RefCell::new(model_of(sc)?);
    let y0 = {
        let m = model.borrow();
        DVector::from_iterator(m.nq() + m.nv(), m.initial_q().iter().chain(m.initial_v()).copied())
    };
    let nq = model.borrow().nq();
    let error = RefCell::new(None);
    let interrupt = Interrupt::install();
    let started = Instant::now();
    let mut solver = dop853!(
        Rhs {
            model: &model,
            error: &error,
            interrupt: interrupt.clone(),
        },
        0.0,
        t_end,
        t_end,
        y0,
        rtol,
        u32::try_from(bound).unwrap_or(u32::MAX),
    );
    let stats = solver.integrate();
    let seconds = started.elapsed().as_secs_f64();
    if let Some(stop) = interrupt.requested() {
        let done = solver.x_out().len().saturating_sub(1) as u64;
        return Err(sink.stopped(stop, solver.x_out().last().copied().unwrap_or(0.0), done, done));
    }
    if let Some(e) = error.borrow().as_ref() {
        return Err(sink.failed(format!("{}: dop853: {e}", sc.name)));
    }
    let stats = stats.map_err(|e| {
        let limit = match max_steps {
            Some(m) => format!("--max-steps {m}"),
            None => format!("the default bound of {bound} steps (--max-steps N to allow more)"),
        };
        let why = match e {
            ode_solvers::dop_shared::IntegrationError::MaxNumStepReached { x, n_step } => {
                format!("reached {limit} at t = {} ({n_step} steps) before t_end", Num(x))
            }
            e => e.to_string(),
        };
        Failure::Run(format!("{}: dop853 at rtol {}: {why}", sc.name, Num(rtol)))
    })?;
    // The solver borrows the stepping model; a second one evaluates the outputs.
    let mut model = model_of(sc)?;
    let (times, states) = (solver.x_out(), solver.y_out());
    let Some(last) = states.last() else {
        return Err(sink.failed(format!("{}: dop853 produced no output", sc.name)));
    };
    if (times.last().copied().unwrap_or(0.0) - t_end).abs() > 1e-9 * t_end || !last.iter().all(|x| x.is_finite()) {
        return Err(sink.failed(format!(
            "{}: dop853 stopped at t = {} before t_end (non-finite state)",
            sc.name,
            Num(times.last().copied().unwrap_or(0.0))
        )));
    }
    let unit = |model: &JointSpaceModel, y: &DVector<f64>| -> Result<Vec<f64>, Failure> {
        let mut q = y.as_slice()[..nq].to_vec();
        model
            .normalize_quaternions(&mut q)
            .map_err(|e| Failure::Run(e.to_string()))?;
        Ok(q)
    };
    let e0 = {
        let y = &states[0];
        model
            .energy(&y.as_slice()[..nq], &y.as_slice()[nq..])
            .unwrap_or(f64::NAN)
    };
    let mut max_energy: f64 = 0.0;
    let count = states.len();
    for (k, (t, y)) in times.iter().zip(states).enumerate() {
        let q = unit(&model, y)?;
        let v = &y.as_slice()[nq..];
        let e = model.energy(&q, v).unwrap_or(f64::NAN);
        max_energy = max_energy.max(((e - e0) / e0.abs().max(f64::MIN_POSITIVE)).abs());
        if k as u64 % every == 0 || k + 1 == count {
            observe(&mut sink, sc, &mut model, *t, &q, v)?;
        }
    }
    let q_end = unit(&model, last)?;
    let written = sink.finish()?;
    let base = summary(sc, &mut model, &q_end, max_energy, written)?;
    let steps = u64::from(stats.accepted_steps);
    let summary = with(
        base,
        json!({
            "method": "DOP853 (joint coordinates)",
            "rtol": rtol,
            "t_end": t_end,
            "steps": steps,
            "rejected_steps": stats.rejected_steps,
            "evaluations": stats.num_eval,
            "stepping_seconds": seconds,
            "body_steps_per_second": (sc.model.bodies.len() as f64 * steps as f64) / seconds.max(1e-12),
        }),
    );
    Ok((summary, sink))
}
