//! The many-body scenario file: `[system] model, bodies, seed, density, cutoff,
//! switch_start, cutoff_form`, `[integrator] step, t_end, rotation, temperature,
//! friction` and `[output] path, every`, each key checked; the command line overrides it.

use std::path::{Path, PathBuf};

use liemid::many::FreeRotation;

use crate::shared::toml_table::{parse_table, Section};

/// Which built-in many-body model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Model {
    /// Fast Lagrangian tops in uniform gravity, each about its own pivot.
    Independent,
    /// Torque-free asymmetric rotors.
    TorqueFree,
    /// A dipolar fluid: point dipoles with WCA repulsion in a periodic box.
    Dipoles,
}

/// How each body turns between the impulses (`--rotation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Rotation {
    /// The torque-free midpoint Lie rotation in two half steps, as in `liemid-ea`.
    Midpoint,
    /// The exact torque-free flow, as in `liemid-ex` (no Newton solve).
    Exact,
    /// The variational torque-free rotation in two half steps, as in `liemid-eav` (a
    /// Lie–Poisson drift; no SIMD lanes).
    Variational,
}

impl Rotation {
    /// Every rotation.
    pub const ALL: [Rotation; 3] = [Rotation::Midpoint, Rotation::Exact, Rotation::Variational];

    /// The name on the command line and in files.
    pub fn key(self) -> &'static str {
        self.free_rotation().key()
    }

    /// One line on the many-body step with this rotation.
    pub fn description(self) -> &'static str {
        match self {
            Rotation::Midpoint => {
                "half impulses around the drift and the torque-free midpoint Lie rotation of liemid-ea (order 2, not symplectic)"
            }
            Rotation::Exact => {
                "half impulses around the drift and the exact torque-free flow of liemid-ex (order 2, symplectic, no Newton solve)"
            }
            Rotation::Variational => {
                "half impulses around the drift and the variational torque-free rotation of liemid-eav (order 2, symplectic, no SIMD lanes)"
            }
        }
    }

    /// The library's rotation.
    pub fn free_rotation(self) -> FreeRotation {
        match self {
            Rotation::Midpoint => FreeRotation::Midpoint,
            Rotation::Exact => FreeRotation::Exact,
            Rotation::Variational => FreeRotation::Variational,
        }
    }
}

impl Model {
    /// Every model.
    pub const ALL: [Model; 3] = [Model::Independent, Model::TorqueFree, Model::Dipoles];

    /// One line on what the model is.
    pub fn description(self) -> &'static str {
        match self {
            Model::Independent => "fast Lagrangian tops in uniform gravity, each about its own pivot",
            Model::TorqueFree => "torque-free asymmetric rotors",
            Model::Dipoles => "a dipolar fluid: point dipoles with WCA repulsion in a periodic box",
        }
    }

    /// The name on the command line and in files.
    pub fn key(self) -> &'static str {
        match self {
            Model::Independent => "independent",
            Model::TorqueFree => "torque-free",
            Model::Dipoles => "dipoles",
        }
    }
}

/// The settings of a run, from the scenario file and the command line.
pub struct Settings {
    /// The interaction.
    pub model: Model,
    /// The torque-free rotation between the impulses.
    pub rotation: FreeRotation,
    /// The Langevin thermostat's temperature and friction, if any.
    pub thermostat: Option<(f64, f64)>,
    /// The number of bodies.
    pub bodies: usize,
    /// The seed of the random start.
    pub seed: u64,
    /// The number density of the dipolar fluid.
    pub density: f64,
    /// The dipoles' cutoff (default 3).
    pub cutoff: Option<f64>,
    /// Where the switched cutoff starts.
    pub switch_start: Option<f64>,
    /// How the dipole interaction is cut off.
    pub cutoff_form: liemid::interactions::CutoffForm,
    /// The step.
    pub step: Option<f64>,
    /// The end time.
    pub t_end: Option<f64>,
    /// The totals file.
    pub out: Option<PathBuf>,
    /// The totals file's interval, in steps.
    pub every: u64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            model: Model::Independent,
            rotation: FreeRotation::Midpoint,
            thermostat: None,
            bodies: 1000,
            seed: 1,
            density: 0.3,
            cutoff: None,
            switch_start: None,
            cutoff_form: liemid::interactions::CutoffForm::Switched,
            step: None,
            t_end: None,
            out: None,
            every: 10,
        }
    }
}

/// The cutoff form named `key`.
pub fn parse_cutoff_form(key: &str) -> Result<liemid::interactions::CutoffForm, String> {
    use liemid::interactions::CutoffForm;
    [CutoffForm::Switched, CutoffForm::ShiftedForce]
        .into_iter()
        .find(|f| f.key() == key)
        .ok_or_else(|| format!("unknown cutoff form \"{key}\" (switched, shifted-force)"))
}

/// The settings of a scenario file, on top of the defaults.
pub fn read(path: &Path) -> Result<Settings, String> {
    let mut s = Settings::default();
    let file = path.display().to_string();
    let text = crate::shared::input::read_text(path, crate::shared::input::MAX_SCENARIO_BYTES)?;
    let mut parse = || -> Result<(), String> {
        let root = parse_table(&text)?;
        for key in root.keys() {
            if !["system", "integrator", "output"].contains(&key.as_str()) {
                let hint = if ["body", "initial", "torque"].contains(&key.as_str()) {
                    "; this is a single-body scenario: run it with `liemid run FILE`"
                } else {
                    ""
                };
                return Err(format!(
                    "unknown section or key `{key}` (sections: system, integrator, output){hint}"
                ));
            }
        }
        if let Some(sys) = Section::new(
            &root,
            "system",
            &[
                "model",
                "bodies",
                "seed",
                "density",
                "cutoff",
                "switch_start",
                "cutoff_form",
            ],
            true,
        )? {
            if let Some(m) = sys.string("model")? {
                s.model = match m {
                    "independent" => Model::Independent,
                    "torque-free" => Model::TorqueFree,
                    "dipoles" => Model::Dipoles,
                    other => {
                        return Err(sys.err(
                            "model",
                            format!("unknown model \"{other}\" (independent, torque-free, dipoles)"),
                        ))
                    }
                };
            }
            if let Some(n) = sys.count("bodies")? {
                s.bodies = n as usize;
            }
            if let Some(n) = sys.count("seed")? {
                s.seed = n;
            }
            if let Some(d) = sys.number("density")? {
                s.density = d;
            }
            s.cutoff = sys.number("cutoff")?;
            s.switch_start = sys.number("switch_start")?;
            if let Some(f) = sys.string("cutoff_form")? {
                s.cutoff_form = parse_cutoff_form(f).map_err(|e| sys.err("cutoff_form", e))?;
            }
        }
        if let Some(integ) = Section::new(
            &root,
            "integrator",
            &["step", "t_end", "rotation", "temperature", "friction"],
            false,
        )? {
            if let Some(kt) = integ.number("temperature")? {
                s.thermostat = Some((kt, integ.number("friction")?.unwrap_or(1.0)));
            } else if integ.number("friction")?.is_some() {
                return Err(integ.err("friction", "needs a temperature"));
            }
            s.step = integ.number("step")?;
            s.t_end = integ.number("t_end")?;
            if let Some(r) = integ.string("rotation")? {
                s.rotation = FreeRotation::from_key(r).ok_or_else(|| {
                    integ.err(
                        "rotation",
                        format!("unknown rotation \"{r}\" (midpoint, exact, variational)"),
                    )
                })?;
            }
        }
        if let Some(out) = Section::new(&root, "output", &["path", "every"], false)? {
            s.out = out.string("path")?.map(PathBuf::from);
            if let Some(e) = out.count("every")? {
                s.every = e;
            }
        }
        Ok(())
    };
    parse().map_err(|e| format!("{file}: {e}"))?;
    Ok(s)
}
