//! What every domain's binding shares: flat triples and arrays, and a library error as a
//! Python exception.

use liemid::{Error, Mat3, Vec3};
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

pub(crate) type Triple = (f64, f64, f64);

/// A flat float64 numpy array owned by Python.
pub(crate) type Array<'py> = Bound<'py, PyArray1<f64>>;

pub(crate) fn v3((x, y, z): Triple) -> Vec3 {
    Vec3::new(x, y, z)
}

pub(crate) fn mat(m: &[f64]) -> PyResult<Mat3> {
    let a: [f64; 9] = m
        .try_into()
        .map_err(|_| PyValueError::new_err(format!("expected 9 matrix entries, found {}", m.len())))?;
    Ok(Mat3::from_row_major(a))
}

/// Threads per core at most in a pool (as the command's `--threads`).
const THREADS_PER_CORE: usize = 4;

/// A pool of `threads` threads (0: all cores); more than four per core is refused (a
/// mistyped count used to start that many threads).
pub(crate) fn pool(threads: usize) -> PyResult<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    if threads > THREADS_PER_CORE * cores {
        return Err(PyValueError::new_err(format!(
            "threads: {threads} is more than {THREADS_PER_CORE} per core ({cores} cores here); use 0 for all cores"
        )));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| PyValueError::new_err(format!("threads: {e}")))
}

/// A library error as a Python exception: a failed step is a `ConvergenceError` with its
/// time and step, everything else a `ValueError`.
pub(crate) fn py_error(py: Python<'_>, e: &Error, context: &str) -> PyErr {
    let message = if context.is_empty() {
        e.to_string()
    } else {
        format!("{context}: {e}")
    };
    let step = match e {
        Error::NewtonDidNotConverge { t, h, .. }
        | Error::StepTooLarge { t, h, .. }
        | Error::NonFiniteResult { t, h, .. } => Some((*t, *h)),
        _ => None,
    };
    match step {
        Some((t, h)) => match py
            .import("liemid._errors")
            .and_then(|m| m.getattr("ConvergenceError"))
            .and_then(|c| c.call1((message.clone(), t, h)))
        {
            Ok(exc) => PyErr::from_value(exc),
            Err(e) => e,
        },
        None => PyValueError::new_err(message),
    }
}
