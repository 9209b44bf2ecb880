//! The files the Python layer reads and writes by path, through the application's layers
//! as the command does: an input only if it is a regular file of a bounded size (a FIFO
//! used to block `open` forever), an output only where a regular file may be written (never
//! through a FIFO, a device or a directory), through `PATH.partial` and a rename.

use std::path::Path;

use liemid_app::shared::input::{read_text, MAX_SCENARIO_BYTES};
use liemid_app::shared::output::{write_atomically, OutputPlan};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The text of a scenario or structure file (`what` names the argument in errors).
#[pyfunction]
fn read_input(what: &str, path: &str) -> PyResult<String> {
    read_text(Path::new(path), MAX_SCENARIO_BYTES).map_err(|e| PyValueError::new_err(format!("{what}: {e}")))
}

/// Write `text` to `path` (checked as every output is; `what` names the argument); returns
/// the path.
#[pyfunction]
fn write_output(what: &str, path: &str, text: &str) -> PyResult<String> {
    let p = Path::new(path);
    OutputPlan::new(&[]).add(what, p).map_err(PyValueError::new_err)?;
    write_atomically(p, text.as_bytes())
        .map_err(|e| PyValueError::new_err(format!("{what} {path}: cannot write: {e}")))?;
    Ok(path.to_string())
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_input, m)?)?;
    m.add_function(wrap_pyfunction!(write_output, m)?)?;
    Ok(())
}
