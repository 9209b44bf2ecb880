//! `liemid._liemid` for many interacting rigid bodies: the `ManyBodies` class (independent
//! tops, torque-free rotors, the dipolar fluid), stepped with the GIL released. The Python
//! layer is `python/liemid/many.py`.

use liemid::many::Bodies;
use liemid::{Mat3, Vec3};
use numpy::IntoPyArray;
use pyo3::exceptions::{PyMemoryError, PyValueError};
use pyo3::prelude::*;

use crate::bounds::check_steps;
use crate::convert::{py_error, v3, Array, Triple};
use crate::signals::Interrupt;
use liemid::error::Num;

/// Body steps in one call of `Bodies::advance` between two looks at the pending signals
/// (a few milliseconds).
const CHUNK_WORK: u64 = 1 << 16;

/// The interaction of a many-body system (one per system, so the size of the dipoles'
/// variant, with its Verlet-list scratch, does not matter).
#[allow(clippy::large_enum_variant)]
enum Model {
    Independent(liemid::interactions::Independent),
    Dipoles(liemid::interactions::Dipoles),
}

/// Many interacting rigid bodies (see `liemid::many`), stepped with the GIL released.
#[pyclass(module = "liemid._liemid")]
struct ManyBodies {
    bodies: Bodies,
    model: Model,
}

macro_rules! with_model {
    ($self:expr, $m:ident => $e:expr) => {
        match &$self.model {
            Model::Independent($m) => $e,
            Model::Dipoles($m) => $e,
        }
    };
}

fn flat3(v: &[Vec3]) -> Vec<f64> {
    v.iter().flat_map(|x| x.to_array()).collect()
}

#[pymethods]
impl ManyBodies {
    /// Bodies from flat arrays and a model: `("independent", gravity, center_of_mass)` or
    /// `("dipoles", moment, sigma, epsilon, cutoff, box_length, switch_start, cutoff_form)`.
    #[new]
    #[pyo3(signature = (mass, inertia, free, position, momentum, rotation, pi, model))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        mass: Vec<f64>,
        inertia: Vec<f64>,
        free: Vec<bool>,
        position: Vec<f64>,
        momentum: Vec<f64>,
        rotation: Vec<f64>,
        pi: Vec<f64>,
        model: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let n = mass.len();
        for (name, len, per) in [
            ("inertia", inertia.len(), 3),
            ("free", free.len(), 1),
            ("positions", position.len(), 3),
            ("momenta", momentum.len(), 3),
            ("rotations", rotation.len(), 9),
            ("angular_momenta", pi.len(), 3),
        ] {
            if len != per * n {
                return Err(PyValueError::new_err(format!(
                    "{name}: {} values for {n} bodies, expected {}",
                    len,
                    per * n
                )));
            }
        }
        let mut bodies = Bodies::new();
        let at = |v: &[f64], i: usize| Vec3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
        for i in 0..n {
            let r = Mat3::from_row_major(rotation[9 * i..9 * i + 9].try_into().expect("9"));
            bodies
                .push(
                    mass[i],
                    at(&inertia, i),
                    free[i],
                    at(&position, i),
                    at(&momentum, i),
                    r,
                    at(&pi, i),
                )
                .map_err(|e| PyValueError::new_err(format!("body {i}: {e}")))?;
        }
        let kind: String = model.get_item(0)?.extract()?;
        let model = match kind.as_str() {
            "independent" => {
                let (_, g, c): (String, Triple, Triple) = model.extract()?;
                Model::Independent(liemid::interactions::Independent {
                    gravity: v3(g),
                    center_of_mass: v3(c),
                })
            }
            "dipoles" => {
                #[allow(clippy::type_complexity)]
                let (_, m, sigma, epsilon, cutoff, box_length, switch, form): (
                    String,
                    Triple,
                    f64,
                    f64,
                    Option<f64>,
                    Option<f64>,
                    Option<f64>,
                    String,
                ) = model.extract()?;
                let mut d = liemid::interactions::Dipoles::new(v3(m), sigma, epsilon, cutoff, box_length)
                    .map_err(|e| PyValueError::new_err(format!("Dipoles: {e}")))?;
                d.cutoff_form = match form.as_str() {
                    "switched" => liemid::interactions::CutoffForm::Switched,
                    "shifted-force" => liemid::interactions::CutoffForm::ShiftedForce,
                    other => {
                        return Err(PyValueError::new_err(format!(
                            "Dipoles: cutoff_form: unknown form {other:?} (\"switched\", \"shifted-force\")"
                        )))
                    }
                };
                if let Some(r_s) = switch {
                    d = d
                        .with_switch_start(r_s)
                        .map_err(|e| PyValueError::new_err(format!("Dipoles: {e}")))?;
                }
                Model::Dipoles(d)
            }
            other => return Err(PyValueError::new_err(format!("model: unknown model {other:?}"))),
        };
        let mut me = ManyBodies { bodies, model };
        with_model!(me, m => me.bodies.evaluate(m));
        Ok(me)
    }

    /// The built-in dipolar fluid: `n` bodies at `density` in a periodic box.
    #[staticmethod]
    #[pyo3(signature = (n, density, seed, cutoff))]
    fn dipolar_fluid(n: usize, density: f64, seed: u64, cutoff: f64) -> PyResult<Self> {
        // The bodies with the exact rotation's storage (it may be chosen later) and the
        // interaction's working storage, as the command counts them.
        let per_body = liemid::many::FreeRotation::Exact.bytes_per_body() + 2 * liemid::many::BYTES_PER_BODY;
        liemid_app::shared::memory::check_fits(&format!("n: {} bodies", Num(n as f64)), n as f64 * per_body as f64)
            .map_err(PyMemoryError::new_err)?;
        let (mut bodies, d) = liemid::many::problems::dipolar_fluid_with_cutoff(n, density, seed, cutoff)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        bodies.evaluate(&d);
        Ok(ManyBodies {
            bodies,
            model: Model::Dipoles(d),
        })
    }

    /// `steps` steps of `h` on `threads` threads (0: all cores); bit-identical for any count.
    /// The steps are taken by `Bodies::advance` (a team of threads for the dipolar fluid's
    /// neighbour list; the same bits as single steps), in chunks of about [`CHUNK_WORK`]
    /// body steps, between which a pending signal (Ctrl-C) stops the run with its exception.
    /// `steps` is held to `max_steps` (10⁹ when `None`) before the first.
    #[pyo3(signature = (h, steps, threads, max_steps=None))]
    fn step(&mut self, py: Python<'_>, h: f64, steps: u64, threads: usize, max_steps: Option<u64>) -> PyResult<()> {
        if !(h.is_finite() && h != 0.0) {
            return Err(PyValueError::new_err(format!(
                "h: must be finite and non-zero, found {}",
                Num(h)
            )));
        }
        check_steps(steps, max_steps, "steps")?;
        let pool = crate::convert::pool(threads)?;
        let ManyBodies { bodies, model } = self;
        let chunk = (CHUNK_WORK / bodies.len().max(1) as u64).max(1);
        let mut interrupt = Interrupt::every(1);
        let result: PyResult<_> = py.detach(|| {
            let mut done = 0;
            while done < steps {
                let k = chunk.min(steps - done);
                let advanced = pool.install(|| match model {
                    Model::Independent(m) => bodies.advance(m, h, k),
                    Model::Dipoles(m) => bodies.advance(m, h, k),
                });
                if let Err(e) = advanced {
                    return Ok(Err(e));
                }
                done += k;
                interrupt.step()?;
            }
            Ok(Ok(()))
        });
        result?.map_err(|e| py_error(py, &e, ""))
    }

    /// Choose the free rotation between the impulses: "midpoint" (as in LIEMID\[EA\]),
    /// "exact" (the exact torque-free flow, as in LIEMID\[EX\]) or "variational" (the
    /// variational half steps, as in LIEMID\[EAV\]).
    fn set_rotation(&mut self, kind: &str) -> PyResult<()> {
        let kind = liemid::many::FreeRotation::from_key(kind).ok_or_else(|| {
            PyValueError::new_err(format!(
                "rotation: unknown rotation {kind:?} (\"midpoint\", \"exact\", \"variational\")"
            ))
        })?;
        self.bodies
            .set_free_rotation(kind)
            .map_err(|e| PyValueError::new_err(format!("rotation: {e}")))
    }

    /// The free rotation between the impulses ("midpoint", "exact" or "variational").
    #[getter]
    fn rotation(&self) -> &'static str {
        self.bodies.free_rotation().key()
    }

    /// `(energy, linear momentum, angular momentum)` of the whole system.
    fn totals(&self) -> (f64, Triple, Triple) {
        let t = with_model!(self, m => self.bodies.totals(m));
        let (p, l) = (t.linear_momentum, t.angular_momentum);
        (t.energy, (p.x, p.y, p.z), (l.x, l.y, l.z))
    }

    #[getter]
    fn t(&self) -> f64 {
        self.bodies.t
    }

    #[getter]
    fn len(&self) -> usize {
        self.bodies.len()
    }

    /// Flat `(positions, momenta, rotations, angular_momenta)`.
    fn arrays<'py>(&self, py: Python<'py>) -> (Array<'py>, Array<'py>, Array<'py>, Array<'py>) {
        let b = &self.bodies;
        let r: Vec<f64> = b.rotation.iter().flat_map(|m| m.to_row_major()).collect();
        (
            flat3(&b.position).into_pyarray(py),
            flat3(&b.momentum).into_pyarray(py),
            r.into_pyarray(py),
            flat3(&b.pi).into_pyarray(py),
        )
    }
}

/// Register the many-body class.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ManyBodies>()?;
    Ok(())
}
