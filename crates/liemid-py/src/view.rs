//! The 3-D page of a run (`liemid_app::shared::view`) for every domain's Python result: the
//! Python layer describes the scene as JSON and hands the frames as one flat array.

use liemid_app::shared::view::{Scene, ViewPage};
use numpy::PyReadonlyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The page of `frames` (one row of the scene's numbers per time in `times`) with the
/// energy error `(energy_t, energy_e)`: written to `path` (returns it) or returned as HTML.
#[pyfunction]
#[pyo3(signature = (scene, title, times, frames, energy_t, energy_e, total_steps, path=None))]
#[allow(clippy::too_many_arguments)]
fn view_page(
    scene: &str,
    title: &str,
    times: PyReadonlyArray1<'_, f64>,
    frames: PyReadonlyArray1<'_, f64>,
    energy_t: PyReadonlyArray1<'_, f64>,
    energy_e: PyReadonlyArray1<'_, f64>,
    total_steps: u64,
    path: Option<String>,
) -> PyResult<String> {
    let scene: Scene = serde_json::from_str(scene).map_err(|e| PyValueError::new_err(format!("scene: {e}")))?;
    let (times, frames) = (times.as_slice()?, frames.as_slice()?);
    let per = scene.floats_per_frame();
    if frames.len() != per * times.len() {
        return Err(PyValueError::new_err(format!(
            "frames: expected {} numbers ({} times x {per}), found {}",
            per * times.len(),
            times.len(),
            frames.len()
        )));
    }
    let mut page = ViewPage::new(scene, title);
    let mut row = vec![0f32; per];
    for (k, &t) in times.iter().enumerate() {
        for (r, v) in row.iter_mut().zip(&frames[k * per..(k + 1) * per]) {
            *r = *v as f32;
        }
        page.push_frame(t, &row);
    }
    for (&t, &e) in energy_t.as_slice()?.iter().zip(energy_e.as_slice()?) {
        page.energy_error(t, e);
    }
    finish(&page, total_steps, path)
}

/// Write `page` to `path` (checked like every output; returns the path), or return its HTML.
pub(crate) fn finish(page: &ViewPage, total_steps: u64, path: Option<String>) -> PyResult<String> {
    finish_reading(page, total_steps, path, &[])
}

/// [`finish`] for a run that read `inputs` (a model file and the files it includes), which
/// the page may not replace.
pub(crate) fn finish_reading(
    page: &ViewPage,
    total_steps: u64,
    path: Option<String>,
    inputs: &[std::path::PathBuf],
) -> PyResult<String> {
    match path {
        Some(p) => {
            let inputs: Vec<&std::path::Path> = inputs.iter().map(std::path::PathBuf::as_path).collect();
            let mut plan = liemid_app::shared::output::OutputPlan::new(&inputs);
            plan.add("view", std::path::Path::new(&p))
                .map_err(PyValueError::new_err)?;
            page.write(std::path::Path::new(&p), total_steps)
                .map_err(PyValueError::new_err)?;
            Ok(p)
        }
        None => Ok(page.html(total_steps)),
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(view_page, m)?)
}
