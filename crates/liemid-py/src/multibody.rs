//! `liemid._liemid` multibody: a model read from an MJCF or URDF file (or a built-in
//! problem, or a scenario file), and a run of it by RATTLE with EA's rotation (maximal
//! coordinates, orders 2 to 8) or by RK4 in joint coordinates, returning flat arrays of
//! the bodies' poses, the energy and the hinge/slide coordinates at every `every`-th step.
//! `python/liemid/multibody.py` shapes them.

use liemid::multibody::{
    joint_space_notes, Drift, JointKind, JointSpaceModel, MultibodyState, MultibodySystem, Prepared, Simulation,
};
use liemid::so3::Quaternion;
use liemid_app::multibody::scenario::{self, Method, MultibodyScenario};
use liemid_app::multibody::view;
use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::bounds::{check_samples, check_steps, SAMPLE_HINT};
use crate::convert::py_error;
use crate::signals::Interrupt;
use liemid::error::Num;

/// A jointed model and what its file held that is not simulated.
#[pyclass(module = "liemid._liemid")]
pub struct MultibodyModel {
    scenario: MultibodyScenario,
}

#[pymethods]
impl MultibodyModel {
    /// The file or problem the model came from.
    #[getter]
    fn name(&self) -> String {
        self.scenario.name.clone()
    }
    /// The bodies' names, in the model's order.
    #[getter]
    fn bodies(&self) -> Vec<String> {
        self.scenario.model.bodies.iter().map(|b| b.name.clone()).collect()
    }
    /// The joints: (name, kind).
    #[getter]
    fn joints(&self) -> Vec<(String, String)> {
        self.scenario
            .model
            .joints
            .iter()
            .map(|j| {
                let kind = j.kind.name();
                (j.name.clone(), kind.to_string())
            })
            .collect()
    }
    /// The kinds of content of the file that are not simulated.
    #[getter]
    fn ignored(&self) -> Vec<String> {
        self.scenario.ignored.clone()
    }
    /// The file's `timestep` (MJCF `option`), if any.
    #[getter]
    fn timestep(&self) -> Option<f64> {
        self.scenario.model.timestep
    }
    /// Gravity (m/s²).
    #[getter]
    fn gravity(&self) -> (f64, f64, f64) {
        let g = self.scenario.model.gravity;
        (g.x, g.y, g.z)
    }
    /// The problem's (or file's) end time when none is given.
    #[getter]
    fn default_t_end(&self) -> f64 {
        self.scenario.t_end.unwrap_or_else(|| self.scenario.default_t_end())
    }
    /// The step when none is given.
    #[getter]
    fn default_step(&self) -> f64 {
        self.scenario.step.unwrap_or_else(|| self.scenario.default_step())
    }
}

/// Read a model file (`.xml` MJCF, `.urdf` URDF, `.toml` scenario).
#[pyfunction]
fn multibody_load(path: &str) -> PyResult<MultibodyModel> {
    let scenario = scenario::load(std::path::Path::new(path)).map_err(PyValueError::new_err)?;
    Ok(MultibodyModel { scenario })
}

/// The built-in problem `name`.
#[pyfunction]
fn multibody_problem(name: &str) -> PyResult<MultibodyModel> {
    let scenario = scenario::builtin(name).map_err(PyValueError::new_err)?;
    Ok(MultibodyModel { scenario })
}

/// The built-in problems: (name, description).
#[pyfunction]
fn multibody_problems() -> Vec<(String, String)> {
    scenario::PROBLEMS
        .iter()
        .map(|p| (p.to_string(), scenario::describe(p).to_string()))
        .collect()
}

/// What a run collects at each sample.
#[derive(Default)]
struct Samples {
    t: Vec<f64>,
    energy: Vec<f64>,
    xpos: Vec<f64>,
    xquat: Vec<f64>,
    joints: Vec<f64>,
}

impl Samples {
    fn push_maximal(&mut self, system: &MultibodySystem, state: &MultibodyState, joints: usize) {
        self.t.push(state.t);
        self.energy.push(system.energy(state));
        for i in 0..state.len() {
            let x = system.frame_origin(state, i);
            self.xpos.extend([x.x, x.y, x.z]);
            self.xquat.extend(system.quaternion(state, i));
        }
        for k in 0..joints {
            if let Some(q) = system.joint_coordinate(state, k) {
                self.joints.push(q);
            }
        }
    }

    fn push_joint_space(
        &mut self,
        model: &mut JointSpaceModel,
        kinds: &[JointKind],
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> liemid::Result<()> {
        self.t.push(t);
        self.energy.push(model.energy(q, v)?);
        for (x, r) in model.forward_kinematics(q)? {
            let u = Quaternion::from_matrix(&r);
            self.xpos.extend([x.x, x.y, x.z]);
            self.xquat.extend([u.w, u.x, u.y, u.z]);
        }
        let mut at = 0;
        for kind in kinds {
            if kind.axis().is_some() {
                self.joints.push(q[at]);
            }
            at += kind.nq();
        }
        Ok(())
    }
}

/// Run `model` with `method` at step `step` to `t_end`, sampling every `every` steps (and
/// the last); returns a dict of flat arrays and the run's maxima. Before the first step,
/// the steps are held to `max_steps` (10⁹ when `None`) and the samples to the memory
/// available; a pending signal (Ctrl-C) stops the run with its exception.
///
/// `control`: `None` (the keyframe's ctrl, else 0), a sequence of one float per actuator
/// (constant), or a callable `f(t, qpos, qvel) -> ctrl` called once per step with the time
/// and the hinge and slide coordinates and rates (the joints of `joint_names`; a hinge's
/// coordinate is MuJoCo's qpos minus its `ref`); its control is held over the step.
#[pyfunction]
#[pyo3(signature = (model, method, step, t_end, every, drift = "midpoint", max_steps = None, control = None))]
#[allow(clippy::too_many_arguments)]
fn multibody_run<'py>(
    py: Python<'py>,
    model: &MultibodyModel,
    method: &str,
    step: f64,
    t_end: f64,
    every: u64,
    drift: &str,
    max_steps: Option<u64>,
    control: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let method = Method::from_key(method).map_err(|e| PyValueError::new_err(format!("method: {e}")))?;
    let drift = Drift::from_key(drift).ok_or_else(|| {
        PyValueError::new_err(format!(
            "drift: unknown drift \"{drift}\" (known: midpoint, variational)"
        ))
    })?;
    if drift != Drift::Midpoint && !matches!(method, Method::Liemid(_)) {
        return Err(PyValueError::new_err(
            "drift: chooses the liemid methods' rotation; rk4 runs in joint coordinates",
        ));
    }
    if !(step.is_finite() && step > 0.0) {
        return Err(PyValueError::new_err(format!(
            "step: must be a positive number, found {}",
            Num(step)
        )));
    }
    if !(t_end.is_finite() && t_end > 0.0) {
        return Err(PyValueError::new_err(format!(
            "t_end: must be a positive number, found {}",
            Num(t_end)
        )));
    }
    if every == 0 {
        return Err(PyValueError::new_err("every: at least 1, found 0"));
    }
    let n = liemid::rigid::driver::step_count(0.0, t_end, step)
        .map_err(|e| PyValueError::new_err(format!("step, t_end: {e}")))?;
    check_steps(n, max_steps, "t_end, step")?;
    let mut callback = None;
    let constant;
    let sc = match control {
        Some(c) if c.is_callable() => {
            callback = Some(c);
            &model.scenario
        }
        Some(c) => {
            let u: Vec<f64> = c
                .extract()
                .map_err(|_| PyValueError::new_err("control: a callable f(t, qpos, qvel) or one float per actuator"))?;
            let mut sc = model.scenario.clone();
            sc.model.ctrl = Some(u);
            sc.model
                .validate_actuators()
                .map_err(|e| PyValueError::new_err(format!("control: {e}")))?;
            constant = sc;
            &constant
        }
        None => &model.scenario,
    };
    // A callback's own exception, raised again after the run stops.
    let mut raised: Option<PyErr> = None;
    let kinds: Vec<JointKind> = sc.model.joints.iter().map(|j| j.kind).collect();
    let bodies = sc.model.bodies.len();
    let coordinates = sc.model.joints.iter().filter(|j| j.kind.axis().is_some()).count();
    check_samples((n / every) as f64 + 2.0, 2 + 7 * bodies + coordinates, SAMPLE_HINT)?;
    let mut interrupt = Interrupt::for_work(bodies);
    let mut stopped: Option<PyErr> = None;
    let mut samples = Samples::default();
    let (mut max_pos, mut max_vel) = (0.0f64, 0.0f64);
    // The contact statistics of a maximal-coordinate run of a model with contacts.
    let mut contacts = None;
    let notes;
    let name = match method {
        Method::Liemid(m) => {
            // The library's model policy, as the command's: armature dropped, the start
            // projected onto loop-closing joints; the notes say so.
            let Prepared {
                simulation: mut sim,
                mut state,
                notes: said,
            } = Simulation::prepare(&sc.model, m).map_err(|e| py_error(py, &e, &sc.name))?;
            sim.integrator.set_drift(drift);
            sim.check_step(&state, step).map_err(|e| py_error(py, &e, &sc.name))?;
            notes = said;
            let joints = sc.model.joints.len();
            let system = &sim.system;
            samples.push_maximal(system, &state, joints);
            let run = match &callback {
                None => py.detach(|| {
                    sim.integrator.integrate(system, &mut state, t_end, step, |k, state, _, _| {
                        if k % every == 0 || k == n {
                            samples.push_maximal(system, state, joints);
                        }
                        interrupt.step().map_err(|e| {
                            stopped = Some(e);
                            "stopped".to_string()
                        })
                    })
                }),
                Some(f) => sim.integrate_controlled(
                    &mut state,
                    t_end,
                    step,
                    |system, state, u| {
                        let (q, v) = maximal_coordinates(system, state, joints);
                        call_control(py, f, state.t, q, v, u, &mut raised)
                    },
                    |k, system, state, _, _| {
                        if k % every == 0 || k == n {
                            samples.push_maximal(system, state, joints);
                        }
                        interrupt.step().map_err(|e| {
                            stopped = Some(e);
                            "stopped".to_string()
                        })
                    },
                ),
            };
            if let Some(e) = raised.take().or(stopped.take()) {
                return Err(e);
            }
            let run = run.map_err(|e| py_error(py, &e, &sc.name))?;
            (max_pos, max_vel) = (run.max_position_violation, run.max_velocity_violation);
            if sim.system.has_contacts() {
                contacts = Some(run);
            }
            m.name().to_string()
        }
        Method::Rk4 => {
            notes = joint_space_notes(&sc.model);
            let mut js = JointSpaceModel::new(&sc.model).map_err(|e| py_error(py, &e, &sc.name))?;
            let mut seen = JointSpaceModel::new(&sc.model).map_err(|e| py_error(py, &e, &sc.name))?;
            let (mut q, mut v) = (js.initial_q().to_vec(), js.initial_v().to_vec());
            samples
                .push_joint_space(&mut seen, &kinds, 0.0, &q, &v)
                .map_err(|e| py_error(py, &e, &sc.name))?;
            let mut observer = |k: u64, t: f64, q: &[f64], v: &[f64]| -> Result<(), String> {
                if k % every == 0 || k == n {
                    let mut unit = q.to_vec();
                    seen.normalize_quaternions(&mut unit).map_err(|e| e.to_string())?;
                    samples
                        .push_joint_space(&mut seen, &kinds, t, &unit, v)
                        .map_err(|e| e.to_string())?;
                }
                interrupt.step().map_err(|e| {
                    stopped = Some(e);
                    "stopped".to_string()
                })
            };
            let run = match &callback {
                None => py.detach(|| js.integrate_rk4(&mut q, &mut v, (0.0, t_end, step), &mut observer)),
                Some(f) => js.integrate_rk4_controlled(
                    &mut q,
                    &mut v,
                    (0.0, t_end, step),
                    |t, q, v, u| {
                        let (qq, vv) = joint_space_coordinates(&kinds, q, v);
                        call_control(py, f, t, qq, vv, u, &mut raised)
                    },
                    &mut observer,
                ),
            };
            if let Some(e) = raised.take().or(stopped.take()) {
                return Err(e);
            }
            run.map_err(|e| py_error(py, &e, &sc.name))?;
            "RK4 (joint coordinates)".to_string()
        }
        Method::Dop853 => {
            return Err(PyValueError::new_err(
                "method: dop853 runs from the command line (`liemid multibody --method dop853`); here: liemid, liemid4, liemid6, liemid8, rk4",
            ))
        }
    };
    let d = PyDict::new(py);
    d.set_item("method", name)?;
    d.set_item("steps", n)?;
    d.set_item("t", samples.t.into_pyarray(py))?;
    d.set_item("energy", samples.energy.into_pyarray(py))?;
    d.set_item("xpos", samples.xpos.into_pyarray(py))?;
    d.set_item("xquat", samples.xquat.into_pyarray(py))?;
    d.set_item("joints", samples.joints.into_pyarray(py))?;
    d.set_item(
        "joint_names",
        sc.model
            .joints
            .iter()
            .filter(|j| j.kind.axis().is_some())
            .map(|j| j.name.clone())
            .collect::<Vec<_>>(),
    )?;
    d.set_item("max_position_constraint_violation", max_pos)?;
    d.set_item("max_velocity_constraint_violation", max_vel)?;
    d.set_item("notes", notes.iter().map(ToString::to_string).collect::<Vec<_>>())?;
    match contacts {
        Some(run) => {
            // As the command's JSON summary names them.
            let c = PyDict::new(py);
            c.set_item("most_points", run.max_contacts)?;
            c.set_item("deepest_penetration", run.max_penetration)?;
            c.set_item("position_iterations", run.contact_iterations)?;
            c.set_item("solver_sweeps", run.contact_sweeps)?;
            c.set_item("split_steps", run.split_steps)?;
            c.set_item("frictionless_drifts", run.frictionless_drifts)?;
            c.set_item("loose_steps", run.loose_steps)?;
            c.set_item("max_loose_violation", run.max_loose_violation)?;
            d.set_item("contacts", c)?;
        }
        None => d.set_item("contacts", py.None())?,
    }
    Ok(d)
}

/// The hinge and slide coordinates and rates of a maximal-coordinate state, in joint order.
fn maximal_coordinates(system: &MultibodySystem, state: &MultibodyState, joints: usize) -> (Vec<f64>, Vec<f64>) {
    let q = (0..joints).filter_map(|k| system.joint_coordinate(state, k)).collect();
    let v = (0..joints).filter_map(|k| system.joint_rate(state, k)).collect();
    (q, v)
}

/// The hinge and slide coordinates and rates of a joint-space state (MuJoCo's layout).
fn joint_space_coordinates(kinds: &[JointKind], q: &[f64], v: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let (mut qq, mut vv) = (Vec::new(), Vec::new());
    let (mut iq, mut iv) = (0, 0);
    for kind in kinds {
        if kind.axis().is_some() {
            qq.push(q[iq]);
            vv.push(v[iv]);
        }
        iq += kind.nq();
        iv += kind.nv();
    }
    (qq, vv)
}

/// Call the control callback `f(t, qpos, qvel)` and copy its control into `u`; a Python
/// exception is kept in `raised` (raised again by the caller) and stops the run.
fn call_control(
    py: Python<'_>,
    f: &Bound<'_, PyAny>,
    t: f64,
    q: Vec<f64>,
    v: Vec<f64>,
    u: &mut [f64],
    raised: &mut Option<PyErr>,
) -> Result<(), String> {
    let out = f
        .call1((t, q.into_pyarray(py), v.into_pyarray(py)))
        .and_then(|r| r.extract::<Vec<f64>>());
    match out {
        Ok(c) if c.len() == u.len() => {
            u.copy_from_slice(&c);
            Ok(())
        }
        Ok(c) => {
            let msg = format!(
                "control: the callback returned {} values at t = {t}, the model has {} actuators",
                c.len(),
                u.len()
            );
            *raised = Some(PyValueError::new_err(msg.clone()));
            Err(msg)
        }
        Err(e) => {
            let msg = e.to_string();
            *raised = Some(e);
            Err(msg)
        }
    }
}

/// A model stepped by the caller (MuJoCo's `mj_step` loop): set `ctrl`, `step(n)`, read the
/// state. The liemid methods only.
#[pyclass(module = "liemid._liemid")]
pub struct MultibodySimulator {
    sim: Simulation,
    state: MultibodyState,
    step: f64,
    /// The start's time and the steps taken since.
    t0: f64,
    steps: u64,
    joints: usize,
    name: String,
    notes: Vec<String>,
}

#[pymethods]
impl MultibodySimulator {
    /// Take `n` steps, the control held.
    #[pyo3(signature = (n = 1))]
    fn step(&mut self, py: Python<'_>, n: u64) -> PyResult<()> {
        let (sim, state, h) = (&mut self.sim, &mut self.state, self.step);
        let (t0, done) = (self.t0, &mut self.steps);
        // The times as the library's driver takes them (t₀ + k h), so that n steps here
        // are the bits of run().
        let r = py.detach(|| -> liemid::Result<()> {
            for _ in 0..n {
                let t_next = t0 + (*done + 1) as f64 * h;
                sim.step(state, t_next - state.t)?;
                sim.integrator.set_time(state, t_next);
                *done += 1;
            }
            Ok(())
        });
        r.map_err(|e| py_error(py, &e, &self.name))
    }
    /// The control, one value per actuator.
    #[getter]
    fn get_ctrl<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        self.sim.system.ctrl().to_vec().into_pyarray(py)
    }
    #[setter]
    fn set_ctrl(&mut self, ctrl: Vec<f64>) -> PyResult<()> {
        self.sim
            .set_ctrl(&ctrl)
            .map_err(|e| PyValueError::new_err(format!("ctrl: {e}")))
    }
    /// The actuators' names (the order of `ctrl`).
    #[getter]
    fn actuators(&self) -> Vec<String> {
        self.sim.system.actuator_names().to_vec()
    }
    /// The time (s).
    #[getter]
    fn time(&self) -> f64 {
        self.state.t
    }
    /// The step (s).
    #[getter]
    fn timestep(&self) -> f64 {
        self.step
    }
    /// The hinge and slide coordinates, in joint order.
    #[getter]
    fn qpos<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        maximal_coordinates(&self.sim.system, &self.state, self.joints)
            .0
            .into_pyarray(py)
    }
    /// The hinge and slide rates, in joint order.
    #[getter]
    fn qvel<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        maximal_coordinates(&self.sim.system, &self.state, self.joints)
            .1
            .into_pyarray(py)
    }
    /// Each body frame's origin, flat (bodies · 3).
    #[getter]
    fn xpos<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        let mut out = Vec::with_capacity(3 * self.state.len());
        for i in 0..self.state.len() {
            let x = self.sim.system.frame_origin(&self.state, i);
            out.extend([x.x, x.y, x.z]);
        }
        out.into_pyarray(py)
    }
    /// Each body's attitude quaternion (w, x, y, z), flat (bodies · 4).
    #[getter]
    fn xquat<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        let mut out = Vec::with_capacity(4 * self.state.len());
        for i in 0..self.state.len() {
            out.extend(self.sim.system.quaternion(&self.state, i));
        }
        out.into_pyarray(py)
    }
    /// What the model policy left out or changed.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }
}

/// A simulator of `model` by a liemid `method` at `step`, from the model's start.
#[pyfunction]
#[pyo3(signature = (model, method, step, drift = "midpoint"))]
fn multibody_simulator(
    py: Python<'_>,
    model: &MultibodyModel,
    method: &str,
    step: f64,
    drift: &str,
) -> PyResult<MultibodySimulator> {
    let Method::Liemid(m) = Method::from_key(method).map_err(|e| PyValueError::new_err(format!("method: {e}")))? else {
        return Err(PyValueError::new_err(
            "method: the simulator steps the liemid methods (liemid, liemid4, liemid6, liemid8); rk4 runs through run()",
        ));
    };
    let drift = Drift::from_key(drift).ok_or_else(|| {
        PyValueError::new_err(format!(
            "drift: unknown drift \"{drift}\" (known: midpoint, variational)"
        ))
    })?;
    if !(step.is_finite() && step > 0.0) {
        return Err(PyValueError::new_err(format!(
            "step: must be a positive number, found {step}"
        )));
    }
    let sc = &model.scenario;
    let Prepared {
        simulation: mut sim,
        state,
        notes,
    } = Simulation::prepare(&sc.model, m).map_err(|e| py_error(py, &e, &sc.name))?;
    sim.integrator.set_drift(drift);
    sim.check_step(&state, step).map_err(|e| py_error(py, &e, &sc.name))?;
    Ok(MultibodySimulator {
        sim,
        t0: state.t,
        steps: 0,
        state,
        step,
        joints: sc.model.joints.len(),
        name: sc.name.clone(),
        notes: notes.iter().map(ToString::to_string).collect(),
    })
}

/// The 3-D page of a run of `model`: `times` (n), `xpos` (n·bodies·3), `xquat`
/// (n·bodies·4), the relative energy error at the same times; written to `path` (returns
/// it) or returned as HTML.
#[pyfunction]
#[pyo3(signature = (model, times, xpos, xquat, energy_error, total_steps, path=None))]
#[allow(clippy::too_many_arguments)] // the Python signature, keyword by keyword
fn multibody_view(
    py: Python<'_>,
    model: &MultibodyModel,
    times: PyReadonlyArray1<'_, f64>,
    xpos: PyReadonlyArray1<'_, f64>,
    xquat: PyReadonlyArray1<'_, f64>,
    energy_error: PyReadonlyArray1<'_, f64>,
    total_steps: u64,
    path: Option<String>,
) -> PyResult<String> {
    let sc = &model.scenario;
    let (times, xpos, xquat, energy) = (
        times.as_slice()?,
        xpos.as_slice()?,
        xquat.as_slice()?,
        energy_error.as_slice()?,
    );
    let bodies = sc.model.bodies.len();
    let n = times.len();
    if xpos.len() != 3 * bodies * n || xquat.len() != 4 * bodies * n || energy.len() != n {
        return Err(PyValueError::new_err(format!(
            "a run of {bodies} bodies at {n} times needs {} positions, {} quaternion numbers and {n} energies; found {}, {}, {}",
            3 * bodies * n,
            4 * bodies * n,
            xpos.len(),
            xquat.len(),
            energy.len()
        )));
    }
    let (mut page, notes) = view::page(sc);
    // What the page cannot draw as the file says (missing or simplified meshes), as the
    // command says it.
    for note in notes {
        let text = std::ffi::CString::new(format!("{}: {note}", sc.name)).unwrap_or_default();
        PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyUserWarning>(), &text, 1)?;
    }
    let mut frame = Vec::with_capacity(7 * bodies);
    for k in 0..n {
        frame.clear();
        for (i, body) in sc.model.bodies.iter().enumerate() {
            let at = k * bodies + i;
            let x = [xpos[3 * at], xpos[3 * at + 1], xpos[3 * at + 2]];
            let q = [xquat[4 * at], xquat[4 * at + 1], xquat[4 * at + 2], xquat[4 * at + 3]];
            let c = view::centre(x, q, body.com);
            frame.extend(c.iter().chain(&q).map(|&v| v as f32));
        }
        // A run's samples hold no contacts: the page's contact slots stay empty.
        frame.extend(std::iter::repeat_n(f32::NAN, 6 * page.scene().contact_slots()));
        page.push_frame(times[k], &frame);
        page.energy_error(times[k], energy[k]);
    }
    crate::view::finish_reading(&page, total_steps, path, &sc.inputs)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<MultibodyModel>()?;
    m.add_class::<MultibodySimulator>()?;
    m.add_function(wrap_pyfunction!(multibody_simulator, m)?)?;
    m.add_function(wrap_pyfunction!(multibody_load, m)?)?;
    m.add_function(wrap_pyfunction!(multibody_problem, m)?)?;
    m.add_function(wrap_pyfunction!(multibody_problems, m)?)?;
    m.add_function(wrap_pyfunction!(multibody_run, m)?)?;
    m.add_function(wrap_pyfunction!(multibody_view, m)?)?;
    Ok(())
}
