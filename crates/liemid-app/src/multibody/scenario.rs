//! What `liemid multibody` runs: a model file (MJCF `.xml`, URDF `.urdf`), a scenario file
//! (`.toml`: `[model] file | problem`, `[integrator] method, step, t_end`, `[output] path,
//! every`, every key checked) or a built-in problem, with the method, step and end time.

use std::path::{Path, PathBuf};

use liemid::multibody::{self, problems, Model, MultibodyMethod};

use crate::shared::toml_table::{parse_table, Section};

/// The built-in problems.
pub const PROBLEMS: [&str; 6] = [
    "double-pendulum",
    "chain-10",
    "spacecraft",
    "closed-loop",
    "chain-1000",
    "test-chain",
];

/// A one-line description of a built-in problem.
#[must_use]
pub fn describe(name: &str) -> &'static str {
    match name {
        "double-pendulum" => "two 1 m rods on hinges under gravity, released at a tilt; t = 10 s",
        "chain-10" => "ten links on ball joints (off-axis centres, full inertia) under gravity; t = 1 s",
        "spacecraft" => {
            "free hub spinning at 20 rad/s off its principal axes, two hinged panels, torque-free; t = 10 s"
        }
        "closed-loop" => "a four-bar linkage of four hinges (3 redundant rows) under gravity; t = 2 s",
        "chain-1000" => "a thousand links on ball joints under gravity (built in code); t = 0.1 s",
        "test-chain" => "the test chain of docs/theory/multibody.md §5: two hinges and a ball, off-axis centres, full inertia; t = 1 s",
        _ => "",
    }
}

/// The integration method of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// RATTLE with EA's rotation, or a symmetric composition of it (maximal coordinates).
    Liemid(MultibodyMethod),
    /// Classical RK4 in joint coordinates (the articulated-body algorithm).
    Rk4,
    /// Dormand-Prince 8(5,3) with step control in joint coordinates (the articulated-body
    /// algorithm): the reference for studies without a peer installed.
    Dop853,
}

impl Method {
    /// The keys on the command line and in files.
    pub const KEYS: [&'static str; 6] = ["liemid", "liemid4", "liemid6", "liemid8", "rk4", "dop853"];

    /// The method named `key`: the library's keys ([`MultibodyMethod::from_key`]) and the
    /// joint-space references `rk4` and `dop853`.
    pub fn from_key(key: &str) -> Result<Method, String> {
        match key {
            "rk4" => Ok(Method::Rk4),
            "dop853" => Ok(Method::Dop853),
            other => MultibodyMethod::from_key(other)
                .map(Method::Liemid)
                .ok_or_else(|| format!("unknown method \"{other}\" (known: {})", Method::KEYS.join(", "))),
        }
    }

    /// The key of the method.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            Method::Liemid(m) => m.key(),
            Method::Rk4 => "rk4",
            Method::Dop853 => "dop853",
        }
    }
}

/// A run's model and settings; `None` where neither file nor command line gives one.
#[derive(Clone, Debug)]
pub struct MultibodyScenario {
    /// The file or problem it came from.
    pub name: String,
    /// The model.
    pub model: Model,
    /// Kinds of content of the model file that are not simulated, each once.
    pub ignored: Vec<String>,
    /// The method.
    pub method: Option<Method>,
    /// The step (s).
    pub step: Option<f64>,
    /// The end time (s).
    pub t_end: Option<f64>,
    /// The trajectory file.
    pub out: Option<PathBuf>,
    /// The trajectory's interval in steps.
    pub every: Option<u64>,
    /// The files the run reads (never written).
    pub inputs: Vec<PathBuf>,
    /// The shapes the model file draws (for the `--view` page).
    pub shapes: Vec<liemid::multibody::Shape>,
}

impl MultibodyScenario {
    fn of(name: String, model: Model, ignored: Vec<String>) -> Self {
        MultibodyScenario {
            name,
            model,
            ignored,
            method: None,
            step: None,
            t_end: None,
            out: None,
            every: None,
            inputs: Vec::new(),
            shapes: Vec::new(),
        }
    }

    /// The end time when nothing sets one: the problem's, else one second.
    #[must_use]
    pub fn default_t_end(&self) -> f64 {
        match self.name.as_str() {
            "double-pendulum" | "spacecraft" => 10.0,
            "closed-loop" => 2.0,
            "chain-1000" => 0.1,
            _ => 1.0,
        }
    }

    /// The step when nothing sets one: the model file's `timestep`, else 1e-3 s.
    #[must_use]
    pub fn default_step(&self) -> f64 {
        self.model.timestep.unwrap_or(1e-3)
    }
}

/// The built-in problem `name`.
pub fn builtin(name: &str) -> Result<MultibodyScenario, String> {
    let model = match name {
        "double-pendulum" => problems::double_pendulum(),
        "chain-10" => problems::chain(10),
        "spacecraft" => problems::spacecraft(),
        "closed-loop" => problems::closed_loop(),
        "chain-1000" => problems::chain(1000),
        "test-chain" => problems::test_chain(),
        other => return Err(format!("unknown problem \"{other}\" (known: {})", PROBLEMS.join(", "))),
    };
    Ok(MultibodyScenario::of(name.to_string(), model, Vec::new()))
}

/// A model file (`.xml` MJCF, `.urdf` URDF) or a scenario file (`.toml`).
pub fn load(path: &Path) -> Result<MultibodyScenario, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let mut sc = match ext.as_str() {
        "xml" | "mjcf" | "urdf" => {
            let loaded = if ext == "urdf" {
                multibody::urdf::load(path)
            } else {
                multibody::mjcf::load(path)
            }
            .map_err(|e| e.to_string())?;
            let mut sc = MultibodyScenario::of(path.display().to_string(), loaded.model, loaded.ignored);
            // Every file read (the included ones too) is an input no output may replace.
            sc.inputs.extend(loaded.files);
            sc.shapes = loaded.shapes;
            sc
        }
        "toml" => return read_toml(path),
        _ => {
            return Err(format!(
                "{}: unknown model file type (.xml for MJCF, .urdf for URDF, .toml for a scenario)",
                path.display()
            ))
        }
    };
    sc.inputs.push(path.to_path_buf());
    Ok(sc)
}

fn read_toml(path: &Path) -> Result<MultibodyScenario, String> {
    let file = path.display().to_string();
    let text = crate::shared::input::read_text(path, crate::shared::input::MAX_SCENARIO_BYTES)?;
    let parse = || -> Result<MultibodyScenario, String> {
        let root = parse_table(&text)?;
        for key in root.keys() {
            if !["model", "integrator", "output"].contains(&key.as_str()) {
                return Err(format!(
                    "unknown section or key `{key}` (sections: model, integrator, output)"
                ));
            }
        }
        let model = Section::new(&root, "model", &["file", "problem"], true)?.expect("required");
        let mut sc = match (model.string("file")?, model.string("problem")?) {
            (Some(f), None) => {
                // A model file named relative to the scenario file.
                let base = path.parent().unwrap_or(Path::new("."));
                let target = base.join(f);
                if target.extension().and_then(|e| e.to_str()) == Some("toml") {
                    return Err(model.err("file", "must be a model file (.xml or .urdf), not another scenario"));
                }
                let mut sc = load(&target)?;
                sc.inputs.push(path.to_path_buf());
                sc
            }
            (None, Some(p)) => {
                let mut sc = builtin(p).map_err(|e| model.err("problem", e))?;
                sc.inputs.push(path.to_path_buf());
                sc
            }
            _ => return Err("[model] needs exactly one of `file` and `problem`".into()),
        };
        if let Some(integ) = Section::new(&root, "integrator", &["method", "step", "t_end"], false)? {
            if let Some(m) = integ.string("method")? {
                sc.method = Some(Method::from_key(m).map_err(|e| integ.err("method", e))?);
            }
            sc.step = integ.number("step")?;
            sc.t_end = integ.number("t_end")?;
        }
        if let Some(out) = Section::new(&root, "output", &["path", "every"], false)? {
            sc.out = out
                .string("path")?
                .map(|p| path.parent().unwrap_or(Path::new(".")).join(p));
            sc.every = out.count("every")?;
        }
        Ok(sc)
    };
    parse().map_err(|e| {
        if e.starts_with(&file) {
            e
        } else {
            format!("{file}: {e}")
        }
    })
}
