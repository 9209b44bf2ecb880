//! `liemid._liemid` beams: run a built-in benchmark or a structure file's text with the
//! explicit splitting or Newmark, as `liemid beam` does (the same `liemid_app` runner), and
//! return the sampled histories as flat arrays. `python/liemid/beam.py` shapes them.

use std::collections::HashMap;

use liemid::beam::{problems, StepPlan};
use liemid_app::beam::scenario::{self, BeamIntegrator};
use liemid_app::beam::study::{self, RunFailure};
use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::bounds::{check_estimate, check_samples, check_steps};
use crate::signals::Interrupt;

/// What to change when a run's samples do not fit.
const BEAM_HINT: &str = "sample less often (a larger sample) or shorten t_end";

/// Run a beam scenario; returns a dict of the run (arrays flat, `tracked` per node (n·3)).
/// Once the step is known and before the first, the steps are held to `max_steps` (10⁹
/// when `None`) and the samples to the memory available; a pending signal (Ctrl-C) stops
/// the run with its exception.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (problem, text, elements_per_member, method, step, t_end, sample, force_step, view=false, drift=None, max_steps=None))]
fn beam_run<'py>(
    py: Python<'py>,
    problem: Option<&str>,
    text: Option<&str>,
    elements_per_member: Option<usize>,
    method: Option<&str>,
    step: Option<f64>,
    t_end: Option<f64>,
    sample: Option<f64>,
    force_step: bool,
    view: bool,
    drift: Option<&str>,
    max_steps: Option<u64>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut sc = match (problem, text) {
        (Some(p), None) => scenario::builtin(p, elements_per_member),
        (None, Some(t)) => scenario::parse(t, "text", elements_per_member),
        _ => Err("give a problem name or a structure file's text, not both".into()),
    }
    .map_err(PyValueError::new_err)?;
    if let Some(m) = method {
        sc.method = scenario::integrator(m).map_err(|e| PyValueError::new_err(format!("method: {e}")))?;
    }
    if let Some(d) = drift {
        sc.drift = scenario::drift(d).map_err(|e| PyValueError::new_err(format!("drift: {e}")))?;
    }
    if step.is_some() {
        sc.step = step;
    }
    let t_end = t_end.unwrap_or(sc.problem.t_end);
    let sample = sample.or(sc.sample).unwrap_or(t_end / 600.0);
    let title = sc.name.clone();
    // Per sample: t, the energy and three displacements per tracked node; with the page,
    // a frame of seven float32 per node and the energy error.
    let per_sample = 2
        + 3 * sc.problem.frame.names.len()
        + if view {
            2 + 7 * sc.problem.frame.nodes.len() / 2
        } else {
            0
        };
    let mut preflight: Option<PyErr> = None;
    let mut check = |plan: &StepPlan| -> Result<(), String> {
        // The plan's count saturates for a huge t_end: beyond 2⁵³ it is shown as an estimate.
        let steps = if plan.steps < 1 << 53 {
            check_steps(plan.steps, max_steps, "t_end, step")
        } else {
            check_estimate(t_end / plan.step, max_steps, "t_end, step: the run would take")
        };
        let checked =
            steps.and_then(|()| check_samples(plan.steps.div_ceil(plan.every) as f64 + 1.0, per_sample, BEAM_HINT));
        checked.map_err(|e| {
            preflight = Some(e);
            "refused".to_string()
        })
    };
    let mut interrupt = Interrupt::every(1);
    let mut stopped: Option<PyErr> = None;
    let mut stop = |_: f64| {
        interrupt.step().err().map(|e| {
            stopped = Some(e);
            "stopped".to_string()
        })
    };
    let result = py.detach(|| {
        study::run_checked(
            &sc,
            t_end,
            study::Stepping {
                step: sc.step,
                sample,
                force_step,
                max_steps,
            },
            &mut check,
            &mut stop,
            view.then_some(title.as_str()),
        )
    });
    if let Some(e) = preflight.or(stopped) {
        return Err(e);
    }
    let (run, page) = result.map_err(|e| match e {
        RunFailure::Input(m) => PyValueError::new_err(m),
        RunFailure::Numerical(m) => {
            match py
                .import("liemid._errors")
                .and_then(|m| m.getattr("ConvergenceError"))
                .and_then(|c| c.call1((m.clone(), f64::NAN, sc.step.unwrap_or(f64::NAN))))
            {
                Ok(exc) => PyErr::from_value(exc),
                Err(e) => e,
            }
        }
    })?;
    let d = PyDict::new(py);
    d.set_item("method", run.method.key())?;
    d.set_item("drift", run.drift.map(|d| d.key()))?;
    d.set_item("page", page.map(|p| p.html(run.steps)))?;
    d.set_item("t", run.t.clone().into_pyarray(py))?;
    let tracked: HashMap<String, Bound<'py, PyArray1<f64>>> = run
        .tracked
        .iter()
        .map(|(n, u)| {
            (
                n.clone(),
                u.iter().flatten().copied().collect::<Vec<f64>>().into_pyarray(py),
            )
        })
        .collect();
    d.set_item("tracked", tracked)?;
    d.set_item("names", run.tracked.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>())?;
    d.set_item("energy", run.energy.clone().into_pyarray(py))?;
    d.set_item("steps", run.steps)?;
    d.set_item("step", run.step)?;
    d.set_item("critical_step", run.critical_step)?;
    d.set_item("wall_seconds", run.wall_seconds)?;
    d.set_item("element_steps_per_second", run.element_steps_per_second())?;
    d.set_item("elements", run.elements)?;
    d.set_item("newton_iterations", run.newton_iterations)?;
    Ok(d)
}

/// The built-in beam problems: (name, description).
#[pyfunction]
fn beam_problems() -> PyResult<Vec<(String, String)>> {
    problems::NAMES
        .iter()
        .map(|n| {
            problems::by_name(n, None)
                .map(|p| (p.name.to_string(), p.description.to_string()))
                .map_err(|e| PyValueError::new_err(e.to_string()))
        })
        .collect()
}

/// The beam methods: (name, order).
#[pyfunction]
fn beam_methods() -> Vec<(String, u32)> {
    BeamIntegrator::ALL
        .iter()
        .map(|m| {
            let order = match m {
                BeamIntegrator::Explicit(b) => b.order(),
                BeamIntegrator::Newmark => 2,
            };
            (m.key().to_string(), order)
        })
        .collect()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(beam_run, m)?)?;
    m.add_function(wrap_pyfunction!(beam_problems, m)?)?;
    m.add_function(wrap_pyfunction!(beam_methods, m)?)?;
    Ok(())
}
