//! `liemid._liemid` for a rigid body about a fixed point: one body's run with a Python or
//! built-in torque, ensembles of independent bodies on all cores, the methods, the built-in
//! problems and the convergence and work-precision studies. The Python layer
//! (`python/liemid/_core.py`, `problems.py`) checks and reshapes.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use liemid::error::Num;
use liemid::rigid::adaptive::{
    AdaptiveRun, AdaptiveStats, AngularSpeed, ReversibleStepper, RigidAdaptive, RigidDensity, TorqueRate,
};
use liemid::{
    so3, ConstantTorque, Error, HeavyTop, Inertia, Mat3, RigidBodySystem, RigidState, RotationIntegrator,
    RotationMethod, Run, Vec3,
};
use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use crate::bounds::{check_estimate, check_samples, check_steps, SAMPLE_HINT};
use crate::convert::{mat, py_error, v3, Array, Triple};
use crate::signals::{watched, Interrupt};
use liemid_app::shared::progress::Progress;

/// A body's torque model: built-in terms summed in order, and optionally a Python callable
/// (through the adapter of the Python layer, which takes `(R row-major 9-tuple, t)` and
/// returns a 3-tuple).
struct PySystem {
    inertia: Inertia,
    gravity: Vec<HeavyTop>,
    constant: Vec<ConstantTorque>,
    torque: Option<Py<PyAny>>,
    potential: Option<Py<PyAny>>,
    /// The first exception a callable raised; the step then fails with a NaN torque and
    /// this error is raised instead of the library's.
    raised: RefCell<Option<PyErr>>,
}

type GravitySpec = Vec<(f64, Triple, Triple)>;
type ConstantSpec = Vec<(Triple, Triple)>;

impl PySystem {
    fn new(
        inertia: &[f64],
        gravity: GravitySpec,
        constant: ConstantSpec,
        torque: Option<Py<PyAny>>,
        potential: Option<Py<PyAny>>,
    ) -> PyResult<Self> {
        let m = mat(inertia)?;
        let inertia = Inertia::from_matrix(m.m).map_err(|e| PyValueError::new_err(format!("inertia: {e}")))?;
        let gravity = gravity
            .into_iter()
            .map(|(mass, com, g)| HeavyTop::new(inertia, mass, v3(com), v3(g)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| PyValueError::new_err(format!("Gravity: {e}")))?;
        let constant = constant
            .into_iter()
            .map(|(b, s)| ConstantTorque::new(inertia, v3(b), v3(s)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| PyValueError::new_err(format!("ConstantTorque: {e}")))?;
        Ok(PySystem {
            inertia,
            gravity,
            constant,
            torque,
            potential,
            raised: RefCell::new(None),
        })
    }

    fn has_callable(&self) -> bool {
        self.torque.is_some() || self.potential.is_some()
    }

    fn call(&self, f: &Py<PyAny>, rotation: &Mat3, t: f64) -> Option<Vec3> {
        if self.raised.borrow().is_some() {
            return None;
        }
        let r = rotation.to_row_major();
        let result = Python::attach(|py| f.call1(py, (r.to_vec(), t)).and_then(|v| v.extract::<Triple>(py)));
        match result {
            Ok(v) => Some(v3(v)),
            Err(e) => {
                *self.raised.borrow_mut() = Some(e);
                None
            }
        }
    }

    fn take_raised(&self) -> Option<PyErr> {
        self.raised.borrow_mut().take()
    }
}

impl RigidBodySystem for PySystem {
    fn inertia(&self) -> &Inertia {
        &self.inertia
    }

    /// The sum of the terms; a single term is returned as it is (so that one built-in term
    /// gives the same bits as the Rust model alone).
    fn torque(&self, rotation: &Mat3, t: f64) -> Vec3 {
        let mut sum: Option<Vec3> = None;
        let mut add = |v: Vec3| sum = Some(sum.map_or(v, |s| s + v));
        for g in &self.gravity {
            add(g.torque(rotation, t));
        }
        for c in &self.constant {
            add(c.torque(rotation, t));
        }
        if let Some(f) = &self.torque {
            add(self
                .call(f, rotation, t)
                .unwrap_or(Vec3::new(f64::NAN, f64::NAN, f64::NAN)));
        }
        sum.unwrap_or(Vec3::ZERO)
    }

    fn potential_energy(&self, rotation: &Mat3, t: f64) -> f64 {
        let mut v: f64 = self.gravity.iter().map(|g| g.potential_energy(rotation, t)).sum();
        if let Some(f) = &self.potential {
            v += self.call(f, rotation, t).map_or(f64::NAN, |p| p.x);
        }
        v
    }
}

/// The initial attitude: a rotation matrix (checked to 1e-6 and re-orthonormalised), a
/// rotation vector or a quaternion `[w, x, y, z]` (norm 1 to 1e-6).
fn attitude(kind: &str, values: &[f64]) -> PyResult<Mat3> {
    match kind {
        "matrix" => {
            let m = mat(values)?;
            let d = so3::orthogonality_defect(&m);
            if !(d <= liemid::rigid::ROTATION_TOLERANCE && m.determinant() > 0.0) {
                return Err(PyValueError::new_err(format!(
                    "rotation: not a rotation matrix (orthogonality defect {d:.3e}, at most {:e} accepted; determinant {})",
                    liemid::rigid::ROTATION_TOLERANCE,
                    Num(m.determinant())
                )));
            }
            so3::orthonormalize(&m).ok_or_else(|| PyValueError::new_err("rotation: cannot be orthonormalised"))
        }
        "rotation_vector" => {
            let v = Vec3::new(values[0], values[1], values[2]);
            if !v.is_finite() || v.norm() > 1e4 {
                return Err(PyValueError::new_err(format!(
                    "rotation_vector: its length (the angle) must be finite and at most 1e4 rad, found {:e}",
                    v.norm()
                )));
            }
            Ok(so3::exp(v))
        }
        _ => {
            let q = so3::Quaternion::new(values[0], values[1], values[2], values[3]);
            let n = q.norm();
            if !(n.is_finite() && (n - 1.0).abs() <= 1e-6) {
                return Err(PyValueError::new_err(format!(
                    "quaternion: must be a unit quaternion [w, x, y, z] (norm 1 to 1e-6), norm is {}",
                    Num(n)
                )));
            }
            Ok(q.normalized().to_matrix())
        }
    }
}

fn parse_method(name: &str) -> PyResult<RotationMethod> {
    RotationMethod::from_key(name).ok_or_else(|| {
        let known: Vec<&str> = RotationMethod::ALL.iter().map(|m| m.key()).collect();
        PyValueError::new_err(format!("method: unknown method {name:?} (known: {})", known.join(", ")))
    })
}

/// Integrate one body; returns `(t, pi, rotation, quaternion, energy, spatial_momentum,
/// summary)` with flat arrays. With `adaptive = eps` (and `step` unused) the reversible
/// adaptive steps of `liemid::rigid::adaptive` with the density `rho` (`omega`, the default,
/// or `torque`); the summary then has `adaptive: (eps, rho, min_step, max_step, last_step)`.
/// Before the first step, the steps are held to `max_steps` (10⁹ when `None`; an adaptive
/// run's at the start's pace, and it stops there) and the samples to the memory available.
/// A pending signal (Ctrl-C) stops the run with its exception.
#[pyfunction]
#[pyo3(signature = (inertia, gravity, constant, torque, potential, attitude_kind, attitude_values, momentum, t0, t_end, step, method, every, adaptive=None, rho=None, max_steps=None))]
#[allow(clippy::too_many_arguments)]
fn integrate<'py>(
    py: Python<'py>,
    inertia: Vec<f64>,
    gravity: GravitySpec,
    constant: ConstantSpec,
    torque: Option<Py<PyAny>>,
    potential: Option<Py<PyAny>>,
    attitude_kind: &str,
    attitude_values: Vec<f64>,
    momentum: (&str, Triple),
    t0: f64,
    t_end: f64,
    step: f64,
    method: &str,
    every: u64,
    adaptive: Option<f64>,
    rho: Option<&str>,
    max_steps: Option<u64>,
) -> PyResult<Bound<'py, PyDict>> {
    let system = PySystem::new(&inertia, gravity, constant, torque, potential)?;
    let rotation = attitude(attitude_kind, &attitude_values)?;
    let method = parse_method(method)?;
    if every == 0 {
        return Err(PyValueError::new_err("every: must be at least 1"));
    }
    let w = v3(momentum.1);
    let pi = if momentum.0 == "angular_velocity" {
        system.inertia.apply(w)
    } else {
        w
    };
    let initial = RigidState::new(t0, pi, rotation);
    if let Some(eps) = adaptive {
        initial.check_valid().map_err(|e| py_error(py, &e, ""))?;
        let limits = Limits { every, max_steps };
        return match rho.unwrap_or("omega") {
            "omega" => integrate_adaptive(py, &system, initial, t_end, eps, method, limits, AngularSpeed),
            "torque" => integrate_adaptive(py, &system, initial, t_end, eps, method, limits, TorqueRate),
            other => Err(PyValueError::new_err(format!(
                "rho: unknown step density {other:?} (known: 'omega', 'torque')"
            ))),
        };
    }
    let mut run = Run::new(&system, initial, t_end, step).map_err(|e| py_error(py, &e, ""))?;
    check_steps(run.total_steps, max_steps, "t_end, step")?;
    let rows = run.total_steps / every + 2;
    check_samples(rows as f64, Trajectory::NUMBERS, SAMPLE_HINT)?;
    let mut out = Trajectory::with_capacity(rows as usize);
    let mut integrator = method.integrator();
    let started = Instant::now();
    // With a Python callable the GIL is needed at every step; otherwise it is released.
    let result = if system.has_callable() {
        run_to_end(&mut run, &mut integrator, &system, every, &mut out)
    } else {
        let shared = SharedSystem(&system);
        py.detach(|| run_to_end(&mut run, &mut integrator, shared.get(), every, &mut out))
    };
    let wall = started.elapsed().as_secs_f64();
    if let Some(e) = system.take_raised() {
        return Err(e);
    }
    result?.map_err(|e| py_error(py, &e, ""))?;
    let s = run.summary();
    let d = PyDict::new(py);
    out.into_dict(py, &d)?;
    d.set_item("steps", s.steps)?;
    d.set_item("max_energy_error", s.max_energy_error)?;
    d.set_item(
        "max_spatial_momentum_change",
        s.max_spatial_momentum_change.to_array().to_vec(),
    )?;
    d.set_item("max_body_momentum_norm_change", s.max_body_momentum_norm_change)?;
    d.set_item("max_orthogonality_defect", s.max_orthogonality_defect)?;
    d.set_item("wall_time", wall)?;
    d.set_item("method", method.key())?;
    Ok(d)
}

/// The largest errors of the diagnostics over an adaptive run, as [`Run::step`] keeps them.
#[derive(Default)]
struct Largest {
    energy: f64,
    spatial: Vec3,
    body_norm: f64,
    orthogonality: f64,
}

impl Largest {
    fn see(&mut self, first: &liemid::Diagnostics, d: &liemid::Diagnostics) {
        let de = (d.energy - first.energy).abs();
        self.energy = self.energy.max(if first.energy != 0.0 {
            de / first.energy.abs()
        } else {
            de
        });
        let dm = d.spatial_momentum - first.spatial_momentum;
        let m = self.spatial;
        self.spatial = Vec3::new(m.x.max(dm.x.abs()), m.y.max(dm.y.abs()), m.z.max(dm.z.abs()));
        self.body_norm = self
            .body_norm
            .max((d.body_momentum_norm - first.body_momentum_norm).abs());
        self.orthogonality = self.orthogonality.max(d.orthogonality_defect);
    }
}

/// What holds a run: its sampling and its step bound.
#[derive(Clone, Copy)]
struct Limits {
    every: u64,
    max_steps: Option<u64>,
}

/// [`integrate`] with reversible adaptive steps (`h = eps / z`, Hairer-Söderlind) of a
/// symmetric `method` and the step density `density`; the last step lands on `t_end`.
#[allow(clippy::too_many_arguments)]
fn integrate_adaptive<'py, D: RigidDensity + Send>(
    py: Python<'py>,
    system: &PySystem,
    initial: RigidState,
    t_end: f64,
    eps: f64,
    method: RotationMethod,
    limits: Limits,
    density: D,
) -> PyResult<Bound<'py, PyDict>> {
    let started = Instant::now();
    // With a Python callable the GIL is needed at every step; otherwise it is released.
    let result = if system.has_callable() {
        adaptive_to_end(system, initial, t_end, eps, method, limits, density)
    } else {
        let shared = SharedSystem(system);
        py.detach(|| adaptive_to_end(shared.get(), initial, t_end, eps, method, limits, density))
    };
    let wall = started.elapsed().as_secs_f64();
    if let Some(e) = system.take_raised() {
        return Err(e);
    }
    let (out, largest, stats, density_name) = result?.map_err(|e| py_error(py, &e, "adaptive"))?;
    let d = PyDict::new(py);
    out.into_dict(py, &d)?;
    d.set_item("steps", stats.steps)?;
    d.set_item("max_energy_error", largest.energy)?;
    d.set_item("max_spatial_momentum_change", largest.spatial.to_array().to_vec())?;
    d.set_item("max_body_momentum_norm_change", largest.body_norm)?;
    d.set_item("max_orthogonality_defect", largest.orthogonality)?;
    d.set_item("wall_time", wall)?;
    d.set_item("method", method.key())?;
    d.set_item(
        "adaptive",
        (stats.eps, density_name, stats.min_step, stats.max_step, stats.last_step),
    )?;
    Ok(d)
}

/// An adaptive run's trajectory, largest diagnostics errors, steps and density name.
type AdaptiveResult = (Trajectory, Largest, AdaptiveStats, &'static str);

/// The adaptive run of [`integrate_adaptive`]: the trajectory (every `every` steps, the
/// first and the last), the largest diagnostics errors, the steps and the density's name.
/// Its steps at the start's pace are held to `max_steps` and their samples to the memory
/// before the first step (`ValueError`, `MemoryError`); a run whose pace slows stops at
/// `max_steps` (`RuntimeError`), and a pending signal stops it with its exception. The
/// library's errors are the inner ones.
fn adaptive_to_end<D: RigidDensity>(
    system: &PySystem,
    initial: RigidState,
    t_end: f64,
    eps: f64,
    method: RotationMethod,
    Limits { every, max_steps }: Limits,
    density: D,
) -> PyResult<Result<AdaptiveResult, Error>> {
    let stepper = match RigidAdaptive::new(system, method, density) {
        Ok(s) => s,
        Err(e) => return Ok(Err(e)),
    };
    let density_name = stepper.density_name();
    let mut run = match AdaptiveRun::new(stepper, initial, t_end, eps) {
        Ok(r) => r,
        Err(e) => return Ok(Err(e)),
    };
    let bounds = liemid_app::shared::bounds::check_adaptive_steps;
    let bound = bounds(
        run.span(),
        run.control(),
        eps,
        max_steps,
        ("adaptive", crate::bounds::MAX_STEPS),
    )
    .map_err(PyValueError::new_err)?;
    let estimate = liemid_app::shared::bounds::adaptive_estimate(run.span(), run.control(), eps);
    check_samples(estimate / every as f64 + 2.0, Trajectory::NUMBERS, SAMPLE_HINT)?;
    let mut interrupt = Interrupt::new();
    let first = liemid::Diagnostics::of(system, &initial);
    let mut largest = Largest {
        orthogonality: first.orthogonality_defect,
        ..Largest::default()
    };
    let mut out = Trajectory::with_capacity(1024);
    out.push(&initial, &first);
    while !run.is_done() {
        if run.stats().steps >= bound {
            return Err(PyRuntimeError::new_err(format!(
                "adaptive: the run reached {bound} steps (max_steps) at t = {} before t_end = {}",
                Num(run.state().t),
                Num(t_end)
            )));
        }
        if let Err(e) = run.step() {
            return Ok(Err(e));
        }
        interrupt.step()?;
        let s = *run.state();
        let d = liemid::Diagnostics::of(system, &s);
        largest.see(&first, &d);
        if run.stats().steps % every == 0 || run.is_done() {
            out.push(&s, &d);
        }
    }
    Ok(Ok((out, largest, run.stats(), density_name)))
}

/// Step `run` to its end, recording the state every `every` steps (and the first and
/// last); a pending signal stops it with its exception (the outer error), the library's
/// errors are the inner ones.
fn run_to_end(
    run: &mut Run,
    integrator: &mut liemid::AnyRotationIntegrator,
    system: &PySystem,
    every: u64,
    out: &mut Trajectory,
) -> PyResult<Result<(), Error>> {
    let mut interrupt = Interrupt::new();
    out.push(run.state(), &run.progress.initial);
    while !run.is_done() {
        let d = match run.step(integrator, system) {
            Ok(d) => d,
            Err(e) => return Ok(Err(e)),
        };
        interrupt.step()?;
        let k = run.progress.steps;
        if k % every == 0 || run.is_done() {
            out.push(run.state(), &d);
        }
    }
    Ok(Ok(()))
}

/// Trajectory columns, flat.
struct Trajectory {
    t: Vec<f64>,
    pi: Vec<f64>,
    rotation: Vec<f64>,
    quaternion: Vec<f64>,
    energy: Vec<f64>,
    spatial: Vec<f64>,
}

impl Trajectory {
    /// Numbers per sample: t, Π (3), R (9), the quaternion (4), the energy, π (3).
    const NUMBERS: usize = 21;

    fn with_capacity(rows: usize) -> Self {
        Trajectory {
            t: Vec::with_capacity(rows),
            pi: Vec::with_capacity(3 * rows),
            rotation: Vec::with_capacity(9 * rows),
            quaternion: Vec::with_capacity(4 * rows),
            energy: Vec::with_capacity(rows),
            spatial: Vec::with_capacity(3 * rows),
        }
    }

    fn push(&mut self, s: &RigidState, d: &liemid::Diagnostics) {
        self.t.push(s.t);
        self.pi.extend_from_slice(&s.pi.to_array());
        self.rotation.extend_from_slice(&s.rotation.to_row_major());
        let q = so3::Quaternion::from_matrix(&s.rotation);
        self.quaternion.extend_from_slice(&[q.w, q.x, q.y, q.z]);
        self.energy.push(d.energy);
        self.spatial.extend_from_slice(&d.spatial_momentum.to_array());
    }

    fn into_dict<'py>(self, py: Python<'py>, d: &Bound<'py, PyDict>) -> PyResult<()> {
        d.set_item("t", self.t.into_pyarray(py))?;
        d.set_item("pi", self.pi.into_pyarray(py))?;
        d.set_item("rotation", self.rotation.into_pyarray(py))?;
        d.set_item("quaternion", self.quaternion.into_pyarray(py))?;
        d.set_item("energy", self.energy.into_pyarray(py))?;
        d.set_item("spatial_momentum", self.spatial.into_pyarray(py))?;
        Ok(())
    }
}

/// Bodies per work item of an ensemble (fixed, so that nothing depends on the threads).
const ENSEMBLE_CHUNK: usize = 64;

/// N independent bodies from flat `rotations (9N)` and `momenta (3N)` to `t_end`, on
/// `threads` threads (0: all cores); returns the final `(pi (3N), rotation (9N))`. Each
/// body's steps are held to `max_steps` (10⁹ when `None`); a pending signal (Ctrl-C) stops
/// the bodies within a few steps and raises its exception.
#[pyfunction]
#[pyo3(signature = (inertia, gravity, constant, attitude_kind, attitudes, momenta, momentum_kind, t0, t_end, step, method, threads, max_steps=None))]
#[allow(clippy::too_many_arguments)]
fn ensemble<'py>(
    py: Python<'py>,
    inertia: Vec<f64>,
    gravity: GravitySpec,
    constant: ConstantSpec,
    attitude_kind: &str,
    attitudes: PyReadonlyArray1<'py, f64>,
    momenta: PyReadonlyArray1<'py, f64>,
    momentum_kind: &str,
    t0: f64,
    t_end: f64,
    step: f64,
    method: &str,
    threads: usize,
    max_steps: Option<u64>,
) -> PyResult<(Array<'py>, Array<'py>)> {
    let system = PySystem::new(&inertia, gravity, constant, None, None)?;
    let method = parse_method(method)?;
    let attitudes = attitudes.as_slice()?;
    let pool = crate::convert::pool(threads)?;
    let momenta = momenta.as_slice()?;
    let n = momenta.len() / 3;
    let per = match attitude_kind {
        "matrix" => 9,
        "rotation_vector" => 3,
        _ => 4,
    };
    if attitudes.len() != per * n || momenta.len() != 3 * n {
        return Err(PyValueError::new_err(format!(
            "attitudes and momenta: {} and {} values do not describe the same number of bodies",
            attitudes.len(),
            momenta.len()
        )));
    }
    // Every attitude is checked before any work, so errors name the first bad body.
    let mut rotations = Vec::with_capacity(n);
    for i in 0..n {
        let r = attitude(attitude_kind, &attitudes[per * i..per * (i + 1)])
            .map_err(|e| PyValueError::new_err(format!("body {i}: {}", e.value(py))))?;
        rotations.push(r);
    }
    let steps = liemid::step_count(t0, t_end, step).map_err(|e| py_error(py, &e, ""))?;
    check_steps(steps, max_steps, "t_end, step")?;
    let by_velocity = momentum_kind == "angular_velocity";
    let mut pi_out = vec![0.0; 3 * n];
    let mut r_out = vec![0.0; 9 * n];
    let shared = SharedSystem(&system);
    let errors: Vec<Option<(usize, Error)>> = watched(py, |stop| {
        pool.install(|| {
            pi_out
                .par_chunks_mut(3 * ENSEMBLE_CHUNK)
                .zip(r_out.par_chunks_mut(9 * ENSEMBLE_CHUNK))
                .enumerate()
                .map(|(c, (pis, rs))| {
                    let system = shared.get();
                    for (j, (pi, r)) in pis.chunks_mut(3).zip(rs.chunks_mut(9)).enumerate() {
                        let i = c * ENSEMBLE_CHUNK + j;
                        let rotation = rotations[i];
                        let w = Vec3::new(momenta[3 * i], momenta[3 * i + 1], momenta[3 * i + 2]);
                        let p = if by_velocity { system.inertia.apply(w) } else { w };
                        let mut state = RigidState::new(t0, p, rotation);
                        let mut integrator = method.integrator();
                        if let Err(e) = advance(&mut integrator, system, &mut state, (t_end, step), stop) {
                            return Some((i, e));
                        }
                        pi.copy_from_slice(&state.pi.to_array());
                        r.copy_from_slice(&state.rotation.to_row_major());
                    }
                    None
                })
                .collect()
        })
    })?;
    if let Some((i, e)) = errors.into_iter().flatten().next() {
        return Err(py_error(py, &e, &format!("body {i}")));
    }
    Ok((pi_out.into_pyarray(py), r_out.into_pyarray(py)))
}

/// `liemid::advance` (the same steps, the same bits) that returns early, leaving `state`
/// mid-run, once `stop` is set (read every [`crate::signals::STEPS`] steps).
fn advance(
    method: &mut liemid::AnyRotationIntegrator,
    system: &PySystem,
    state: &mut RigidState,
    (t_end, h): (f64, f64),
    stop: &AtomicBool,
) -> Result<(), Error> {
    state.check_valid()?;
    let t0 = state.t;
    let steps = liemid::step_count(t0, t_end, h)?;
    for k in 1..=steps {
        if k % crate::signals::STEPS == 0 && stop.load(Ordering::Relaxed) {
            return Ok(());
        }
        let target = if k == steps { t_end } else { t0 + k as f64 * h };
        let dt = if k == steps { target - state.t } else { h };
        method.step(system, state, dt)?;
        state.t = target;
    }
    Ok(())
}

/// A system without Python callables, shared by the ensemble's threads (it only reads).
struct SharedSystem<'a>(&'a PySystem);

// SAFETY: a shared system has no Python callables (`SharedSystem::get` checks), so its
// `RefCell` is never touched; the rest is plain data, only read.
unsafe impl Sync for SharedSystem<'_> {}

impl SharedSystem<'_> {
    fn get(&self) -> &PySystem {
        assert!(!self.0.has_callable(), "a system with Python callables is not shared");
        self.0
    }
}

/// Check a body's inertia and built-in torques (the errors `integrate` would raise).
#[pyfunction]
fn check_body(inertia: Vec<f64>, gravity: GravitySpec, constant: ConstantSpec) -> PyResult<()> {
    PySystem::new(&inertia, gravity, constant, None, None).map(|_| ())
}

/// Every method: `(key, name, order, torque evaluations per step, description)`.
#[pyfunction]
fn methods() -> Vec<(&'static str, &'static str, u32, &'static str, &'static str)> {
    RotationMethod::ALL
        .iter()
        .map(|m| {
            (
                m.key(),
                m.name(),
                m.order(),
                m.torque_evaluations_per_step(),
                m.description(),
            )
        })
        .collect()
}

/// A built-in problem: `(description, inertia (9), gravity terms, rotation (9), pi (3),
/// t_end, default step)`.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn problem(name: &str) -> PyResult<(String, Vec<f64>, GravitySpec, Vec<f64>, Triple, f64, f64)> {
    let sc = liemid_app::rigid::scenario::builtin(name).map_err(PyValueError::new_err)?;
    let description = liemid_app::rigid::scenario::describe(name).to_string();
    let (inertia, gravity) = match &sc.system {
        liemid_app::rigid::scenario::ScenarioSystem::Gravity(top) => (
            top.inertia,
            vec![(
                top.mass,
                (top.center_of_mass.x, top.center_of_mass.y, top.center_of_mass.z),
                (top.gravity.x, top.gravity.y, top.gravity.z),
            )],
        ),
        other => (*other.inertia(), vec![]),
    };
    let pi = sc.initial.pi;
    Ok((
        description,
        inertia.matrix().to_row_major().to_vec(),
        gravity,
        sc.initial.rotation.to_row_major().to_vec(),
        (pi.x, pi.y, pi.z),
        sc.t_end,
        sc.step,
    ))
}

fn scenario_of(problem: &str, scenario_text: Option<&str>) -> PyResult<liemid_app::rigid::scenario::Scenario> {
    match scenario_text {
        Some(text) => liemid_app::rigid::scenario::parse(text, "scenario").map_err(PyValueError::new_err),
        None => liemid_app::rigid::scenario::builtin(problem).map_err(PyValueError::new_err),
    }
}

/// A study's progress that nobody watches, asked to stop when a signal is pending
/// (`signals::watched` sets the flag; the study reads it between runs).
struct Watch<'a>(&'a AtomicBool);

impl Progress for Watch<'_> {
    fn start(&self, _total: u64, _unit: &str) {}
    fn advance(&self) {}
    fn finish(&self) {}
    fn stopped(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// The convergence study of `liemid converge`, as its JSON text. The steps of its runs
/// (every method at every step) are held to `max_steps` (10⁹ when `None`) before the
/// first; a pending signal (Ctrl-C) stops it between runs.
#[pyfunction]
#[pyo3(signature = (problem, scenario_text, methods, steps, t_end, max_steps=None))]
fn converge(
    py: Python<'_>,
    problem: &str,
    scenario_text: Option<&str>,
    methods: Option<Vec<String>>,
    steps: Option<Vec<f64>>,
    t_end: Option<f64>,
    max_steps: Option<u64>,
) -> PyResult<String> {
    let sc = scenario_of(problem, scenario_text)?;
    let methods: Vec<RotationMethod> = match methods {
        None => RotationMethod::PAPER.to_vec(),
        Some(list) => list.iter().map(|m| parse_method(m)).collect::<PyResult<_>>()?,
    };
    let steps = steps.unwrap_or_else(|| (0..6).map(|k| 2e-3 / f64::from(1u32 << k)).collect());
    if steps.is_empty() || methods.is_empty() || steps.iter().any(|h| !(h.is_finite() && *h > 0.0)) {
        return Err(PyValueError::new_err(
            "steps and methods must be non-empty, steps positive",
        ));
    }
    let t_end = t_end.unwrap_or(sc.t_end);
    let mut total: u64 = 0;
    for &h in &steps {
        let n = liemid::step_count(sc.initial.t, t_end, h).map_err(|e| py_error(py, &e, "steps, t_end"))?;
        total = total.saturating_add(n.saturating_mul(methods.len() as u64));
    }
    check_steps(total, max_steps, "converge: steps, t_end")?;
    let study = watched(py, |stop| {
        liemid_app::rigid::converge::study(&sc, &methods, &steps, t_end, &Watch(stop))
    })?
    .map_err(|e| py_error(py, &e, "reference"))?;
    serde_json::to_string(&study).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The work-precision study of `liemid work-precision`, as its JSON text. Its coarsest run
/// is held to `max_steps` (10⁹ when `None`) before the reference is computed; a pending
/// signal (Ctrl-C) stops it between runs and within its DOP853 and RK4 references.
#[pyfunction]
#[pyo3(signature = (problem, scenario_text, methods, t_end, repetitions, budget, min_error, max_points, max_steps=None))]
#[allow(clippy::too_many_arguments)]
fn work_precision(
    py: Python<'_>,
    problem: &str,
    scenario_text: Option<&str>,
    methods: Option<Vec<String>>,
    t_end: Option<f64>,
    repetitions: usize,
    budget: f64,
    min_error: f64,
    max_points: usize,
    max_steps: Option<u64>,
) -> PyResult<String> {
    use liemid_app::rigid::study::{study, Entry, Options};
    let sc = scenario_of(problem, scenario_text)?;
    let entries = match methods {
        None => Entry::all(),
        Some(list) => list
            .iter()
            .map(|m| Entry::from_key(m).ok_or_else(|| PyValueError::new_err(format!("methods: unknown method {m:?}"))))
            .collect::<PyResult<_>>()?,
    };
    if repetitions < 5 || budget.is_nan() || budget <= 0.0 || min_error.is_nan() || min_error <= 0.0 || max_points == 0
    {
        return Err(PyValueError::new_err(
            "repetitions must be at least 5, budget and min_error positive, max_points at least 1",
        ));
    }
    let options = Options {
        entries,
        repetitions,
        budget,
        min_error,
        max_points,
    };
    let t_end = t_end.unwrap_or(sc.t_end);
    if !(t_end.is_finite() && t_end > sc.initial.t) {
        return Err(PyValueError::new_err(format!(
            "t_end: must be a finite time after the start {}, found {}",
            Num(sc.initial.t),
            Num(t_end)
        )));
    }
    let coarsest = liemid_app::rigid::study::coarsest_steps(&sc, t_end);
    check_estimate(
        coarsest,
        max_steps,
        "work_precision: t_end: the study's coarsest run would take",
    )?;
    let result = watched(py, |stop| study(&sc, t_end, &options, &Watch(stop)))?.map_err(PyValueError::new_err)?;
    serde_json::to_string(&result).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Register the rigid-body functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(integrate, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    m.add_function(wrap_pyfunction!(methods, m)?)?;
    m.add_function(wrap_pyfunction!(check_body, m)?)?;
    m.add_function(wrap_pyfunction!(problem, m)?)?;
    m.add_function(wrap_pyfunction!(converge, m)?)?;
    m.add_function(wrap_pyfunction!(work_precision, m)?)?;
    Ok(())
}
