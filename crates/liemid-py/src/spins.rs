//! `liemid._liemid` spin dynamics: a lattice system, a run that returns its time series and
//! final spins, the built-in problems and the method list. The Python layer
//! (`python/liemid/spins.py`) checks shapes and reshapes the flat arrays.

use liemid::spin::{self, problems, DmiKind, Lattice, LatticeKind, SpinIntegrator, SpinMethod, SpinSystem};
use liemid::Vec3;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyMemoryError, PyValueError};
use pyo3::prelude::*;

use crate::bounds::{check_samples, check_steps, SAMPLE_HINT};
use crate::convert::{py_error, v3, Array, Triple};
use crate::signals::Interrupt;

/// Site steps in one call of `SpinIntegrator::advance` between two looks at the pending
/// signals (a few milliseconds).
const CHUNK_WORK: u64 = 1 << 20;

/// A spin system: lattice and Hamiltonian.
#[pyclass(module = "liemid._liemid")]
pub struct Spins {
    system: SpinSystem,
}

#[pymethods]
impl Spins {
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (kind, size, periodic, exchange, anisotropy, anisotropy_axis, field, mu_s, damping, dmi=0.0, dmi_kind="interfacial"))]
    fn new(
        kind: &str,
        size: Vec<usize>,
        periodic: bool,
        exchange: f64,
        anisotropy: f64,
        anisotropy_axis: Triple,
        field: Triple,
        mu_s: f64,
        damping: f64,
        dmi: f64,
        dmi_kind: &str,
    ) -> PyResult<Self> {
        let dmi_kind = DmiKind::from_key(dmi_kind).ok_or_else(|| {
            PyValueError::new_err(format!(
                "dmi_kind: unknown kind {dmi_kind:?} (\"interfacial\", \"bulk\")"
            ))
        })?;
        let kind = match kind {
            "chain" => LatticeKind::Chain,
            "square" => LatticeKind::Square,
            "cubic" => LatticeKind::Cubic,
            other => {
                return Err(PyValueError::new_err(format!(
                    "kind: unknown lattice {other:?} (\"chain\", \"square\", \"cubic\")"
                )))
            }
        };
        liemid_app::spin::scenario::check_lattice_size(&size).map_err(|e| match e {
            liemid_app::spin::scenario::SizeRefusal::Count(m) => PyValueError::new_err(format!("size: {m}")),
            liemid_app::spin::scenario::SizeRefusal::Memory(m) => PyMemoryError::new_err(format!("size: {m}")),
        })?;
        let lattice = Lattice::new(kind, &size, periodic).map_err(|e| PyValueError::new_err(format!("size: {e}")))?;
        let system = SpinSystem::new(
            lattice,
            exchange,
            anisotropy,
            v3(anisotropy_axis),
            v3(field),
            mu_s,
            damping,
        )
        .and_then(|s| s.with_dmi(dmi, dmi_kind))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(Spins { system })
    }

    /// The built-in problem `name`: the system and its initial spins (flat).
    #[staticmethod]
    fn problem<'py>(py: Python<'py>, name: &str) -> PyResult<(Self, Array<'py>, f64, f64)> {
        let p = problems::get(name).ok_or_else(|| {
            PyValueError::new_err(format!(
                "unknown spin problem {name:?} (known: {})",
                problems::NAMES.join(", ")
            ))
        })?;
        let flat: Vec<f64> = p.spins.iter().flat_map(|s| s.to_array()).collect();
        Ok((Spins { system: p.system }, flat.into_pyarray(py), p.step, p.t_end))
    }

    #[getter]
    fn len(&self) -> usize {
        self.system.len()
    }

    #[getter]
    fn size(&self) -> (usize, usize, usize) {
        let s = self.system.lattice.size();
        (s[0], s[1], s[2])
    }

    /// The energy (meV) of flat spins.
    fn energy(&self, spins: PyReadonlyArray1<'_, f64>) -> PyResult<f64> {
        Ok(self.system.energy(&self.unpack(spins.as_slice()?)?))
    }

    /// Run from flat spins to `t_end` with step `h`, observing every `every` steps:
    /// `(t, energy, magnetisation (flat, 3 per row), final spins (flat), seconds)`. Before
    /// the first step, the steps are held to `max_steps` (10⁹ when `None`) and the
    /// observations to the memory available; the steps are taken in chunks of about
    /// [`CHUNK_WORK`] site steps, between which a pending signal (Ctrl-C) stops the run with
    /// its exception.
    #[pyo3(signature = (spins, method, h, t_end, every, threads, max_steps=None))]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn integrate<'py>(
        &self,
        py: Python<'py>,
        spins: PyReadonlyArray1<'py, f64>,
        method: &str,
        h: f64,
        t_end: f64,
        every: u64,
        threads: usize,
        max_steps: Option<u64>,
    ) -> PyResult<(Array<'py>, Array<'py>, Array<'py>, Array<'py>, f64)> {
        let method = SpinMethod::from_key(method).ok_or_else(|| {
            let known: Vec<&str> = SpinMethod::ALL.iter().map(|m| m.key()).collect();
            PyValueError::new_err(format!(
                "method: unknown spin method {method:?} (known: {})",
                known.join(", ")
            ))
        })?;
        if every == 0 {
            return Err(PyValueError::new_err("every: must be at least 1"));
        }
        let steps = liemid::step_count(0.0, t_end, h).map_err(|e| PyValueError::new_err(format!("h, t_end: {e}")))?;
        check_steps(steps, max_steps, "t_end, step")?;
        check_samples(steps.div_ceil(every) as f64 + 1.0, 5, SAMPLE_HINT)?;
        let mut s = self.unpack(spins.as_slice()?)?;
        let pool = crate::convert::pool(threads)?;
        let system = &self.system;
        let n = system.len() as f64;
        let chunk = (CHUNK_WORK / system.len().max(1) as u64).max(1);
        let mut interrupt = Interrupt::every(1);
        let result: PyResult<_> = py.detach(|| {
            let mut integ = SpinIntegrator::new(method);
            let (mut t, mut energy, mut mag) = (Vec::new(), Vec::new(), Vec::new());
            let mut record = |s: &[Vec3], time: f64| {
                t.push(time);
                energy.push(system.energy(s));
                mag.extend_from_slice(&(system.total_spin(s) * (1.0 / n)).to_array());
            };
            record(&s, 0.0);
            let start = std::time::Instant::now();
            let mut done = 0;
            while done < steps {
                let k = every.min(steps - done);
                let mut left = k;
                while left > 0 {
                    let piece = left.min(chunk);
                    let at = (done + k - left) as f64 * h;
                    if let Err(e) = pool.install(|| integ.advance(system, &mut s, at, h, piece)) {
                        return Ok(Err(e));
                    }
                    left -= piece;
                    interrupt.step()?;
                }
                done += k;
                record(&s, done as f64 * h);
            }
            Ok(Ok((t, energy, mag, start.elapsed().as_secs_f64())))
        });
        let (t, energy, mag, seconds) = result?.map_err(|e| py_error(py, &e, ""))?;
        let flat: Vec<f64> = s.iter().flat_map(|v| v.to_array()).collect();
        Ok((
            t.into_pyarray(py),
            energy.into_pyarray(py),
            mag.into_pyarray(py),
            flat.into_pyarray(py),
            seconds,
        ))
    }
}

impl Spins {
    fn unpack(&self, flat: &[f64]) -> PyResult<Vec<Vec3>> {
        let n = self.system.len();
        if flat.len() != 3 * n {
            return Err(PyValueError::new_err(format!(
                "spins: expected shape ({n}, 3) for this lattice, found {} values",
                flat.len()
            )));
        }
        let rows: Vec<Vec3> = flat.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
        spin::normalized(&rows).map_err(|e| PyValueError::new_err(format!("spins: {e}")))
    }
}

/// `[(name, order, damping, description)]` of the spin methods.
#[pyfunction]
pub fn spin_methods() -> Vec<(&'static str, u32, bool, &'static str)> {
    SpinMethod::ALL
        .iter()
        .map(|m| (m.key(), m.order(), m.handles_damping(), m.description()))
        .collect()
}

/// Spins within `max_tilt` rad of +z, seeded (as the built-in problems' starts), flat.
#[pyfunction]
pub fn spins_near_z<'py>(py: Python<'py>, n: usize, max_tilt: f64, seed: u64) -> PyResult<Bound<'py, PyArray1<f64>>> {
    // The spins and their flat copy, 48 bytes each.
    liemid_app::shared::memory::check_fits(&format!("n: {} spins", liemid::error::Num(n as f64)), n as f64 * 48.0)
        .map_err(PyMemoryError::new_err)?;
    let flat: Vec<f64> = problems::near_z(n, max_tilt, seed)
        .iter()
        .flat_map(|s| s.to_array())
        .collect();
    Ok(flat.into_pyarray(py))
}

/// Add the spin classes and functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Spins>()?;
    m.add_function(wrap_pyfunction!(spin_methods, m)?)?;
    m.add_function(wrap_pyfunction!(spins_near_z, m)?)?;
    Ok(())
}
