//! `liemid._liemid`: the compiled core of the Python package.
//!
//! The Python layer (`python/liemid/`) checks and converts arguments (any dtype and memory
//! order in, shapes named in errors) and hands this module flat, C-contiguous float64
//! arrays; results come back as owned numpy arrays that it reshapes. Errors of the library
//! become `ValueError` (bad input) or `liemid.ConvergenceError` (a step too large, carrying
//! `t` and `h`); a Python torque that raises re-raises its own exception. Pure-Rust work
//! runs with the GIL released. Every run is held to a step bound (`max_steps`) and its
//! samples to the memory before the first step (`bounds`), and looks for Ctrl-C between
//! steps (`signals`).

mod beam;
mod bounds;
mod convert;
mod files;
mod many;
mod multibody;
mod rigid;
mod signals;
mod spins;
mod view;

use pyo3::prelude::*;

/// The compiled module: one registration per domain.
#[pymodule]
fn _liemid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    rigid::register(m)?;
    many::register(m)?;
    spins::register(m)?;
    beam::register(m)?;
    multibody::register(m)?;
    view::register(m)?;
    files::register(m)?;
    Ok(())
}
