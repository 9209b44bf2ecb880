//! Beam structure files for `liemid beam` (TOML):
//!
//! ```toml
//! [[section]]
//! name = "square"
//! E = 8.333e7                 # with G, A, I2, I3, J, rho ...
//! G = 4.167e7
//! A = 0.012
//! I2 = 1.2e-5
//! I3 = 1.2e-5
//! J = 2.03e-5
//! rho = 83.33
//! # ... or the coefficients: EA, GJ, EI2, EI3, rhoA, rotary_inertia = [rho J, rho I2, rho I3]
//!
//! [[member]]
//! from = [0.0, 10.0, 0.0]
//! to = [10.0, 10.0, 0.0]
//! elements = 8                # --elements-per-member overrides
//! section = "square"
//! orientation = [0.0, 0.0, 1.0]   # in the plane of the axis and the section's second axis
//!
//! [[node]]                    # supports and names, found by position
//! at = [0.0, 10.0, 0.0]
//! support = "clamped"         # "free" | "pinned" | "clamped"
//! name = "root"               # tracked: its displacement history is written
//!
//! [[load]]
//! at = [10.0, 10.0, 0.0]      # or node = "NAME"
//! force = [0.0, 0.0, 1.0]
//! moment = [0.0, 0.0, 0.0]
//! follower = false            # true: turns with the node
//! history = [[0.0, 0.0], [1.0, 50.0], [2.0, 0.0]]   # (t, multiplier), linear between
//!
//! [run]
//! gravity = [0.0, 0.0, 0.0]
//! method = "liemid"           # "liemid" | "liemid4" | "liemid-mts" | "liemid-sms" | "newmark"
//! drift = "midpoint"          # the node rotations of the liemid methods: "midpoint" | "variational"
//! step = 1e-3                 # default: 0.9 of the critical step (explicit), 0.05 (newmark)
//! t_end = 30.0
//! sample = 0.05               # output interval (time)
//! ```

use std::path::Path;

use liemid::beam::{problems, Drift, Frame, History, NodalLoad, Section, Support};
use liemid::Vec3;
use serde::Deserialize;

/// The integrators of `liemid beam`: the library's ([`liemid::beam::BeamIntegrator`]).
pub use liemid::beam::BeamIntegrator;

/// The integrator of `key`, or an error listing the keys.
pub fn integrator(key: &str) -> Result<BeamIntegrator, String> {
    BeamIntegrator::from_key(key).ok_or_else(|| {
        let known: Vec<&str> = BeamIntegrator::ALL.iter().map(|m| m.key()).collect();
        format!("unknown beam method `{key}` (known: {})", known.join(", "))
    })
}

/// The node rotations' drift of `key` (`midpoint`, `variational`), or an error listing the
/// keys.
pub fn drift(key: &str) -> Result<Drift, String> {
    Drift::from_key(key).ok_or_else(|| format!("unknown drift `{key}` (known: midpoint, variational)"))
}

/// A beam scenario: the model, the initial deflection of a built-in problem, and the run.
#[derive(Clone, Debug)]
pub struct BeamScenario {
    /// Name (the problem's or the file's).
    pub name: String,
    /// The built problem (frame, end time, initial mode).
    pub problem: problems::BeamProblem,
    /// Method.
    pub method: BeamIntegrator,
    /// The node rotations' drift of the explicit methods (midpoint by default; Newmark
    /// takes only the default).
    pub drift: Drift,
    /// Step (`None`: the default of the method).
    pub step: Option<f64>,
    /// Output interval in time.
    pub sample: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSection {
    name: String,
    #[serde(rename = "E")]
    e: Option<f64>,
    #[serde(rename = "G")]
    g: Option<f64>,
    #[serde(rename = "A")]
    a: Option<f64>,
    #[serde(rename = "I2")]
    i2: Option<f64>,
    #[serde(rename = "I3")]
    i3: Option<f64>,
    #[serde(rename = "J")]
    j: Option<f64>,
    rho: Option<f64>,
    #[serde(rename = "EA")]
    ea: Option<f64>,
    #[serde(rename = "GJ")]
    gj: Option<f64>,
    #[serde(rename = "EI2")]
    ei2: Option<f64>,
    #[serde(rename = "EI3")]
    ei3: Option<f64>,
    #[serde(rename = "rhoA")]
    rho_a: Option<f64>,
    rotary_inertia: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileMember {
    from: [f64; 3],
    to: [f64; 3],
    elements: Option<usize>,
    section: String,
    orientation: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileNode {
    at: [f64; 3],
    support: Option<String>,
    name: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileLoad {
    at: Option<[f64; 3]>,
    node: Option<String>,
    force: Option<[f64; 3]>,
    moment: Option<[f64; 3]>,
    follower: Option<bool>,
    history: Option<Vec<[f64; 2]>>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct FileRun {
    gravity: Option<[f64; 3]>,
    method: Option<String>,
    drift: Option<String>,
    step: Option<f64>,
    t_end: Option<f64>,
    sample: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    section: Vec<FileSection>,
    #[serde(default)]
    member: Vec<FileMember>,
    #[serde(default)]
    node: Vec<FileNode>,
    #[serde(default)]
    load: Vec<FileLoad>,
    #[serde(default)]
    run: FileRun,
}

fn section(s: &FileSection) -> Result<Section, String> {
    let what = |e: liemid::Error| format!("section `{}`: {e}", s.name);
    let material = [s.e, s.g, s.a, s.i2, s.i3, s.j, s.rho];
    let coefficients = [s.ea, s.gj, s.ei2, s.ei3, s.rho_a];
    match (
        material.iter().all(Option::is_some),
        coefficients.iter().all(Option::is_some),
    ) {
        (true, false) if coefficients.iter().all(Option::is_none) && s.rotary_inertia.is_none() => {
            let [e, g, a, i2, i3, j, rho] = material.map(|v| v.unwrap_or(0.0));
            Section::from_material(e, g, a, i2, i3, j, rho).map_err(what)
        }
        (false, true) if material.iter().all(Option::is_none) => {
            let [ea, gj, ei2, ei3, rho_a] = coefficients.map(|v| v.unwrap_or(0.0));
            let rotary = s.rotary_inertia.ok_or_else(|| {
                format!(
                    "section `{}`: with EA, GJ, EI2, EI3, rhoA give rotary_inertia = [rho J, rho I2, rho I3]",
                    s.name
                )
            })?;
            let sec = Section {
                axial_stiffness: ea,
                torsional_stiffness: gj,
                bending_stiffness_2: ei2,
                bending_stiffness_3: ei3,
                mass_per_length: rho_a,
                rotary_inertia: Vec3::from_array(rotary),
            };
            sec.validate().map_err(what)?;
            Ok(sec)
        }
        _ => Err(format!(
            "section `{}`: give either all of E, G, A, I2, I3, J, rho or all of EA, GJ, EI2, EI3, rhoA, rotary_inertia",
            s.name
        )),
    }
}

fn support(key: &str) -> Result<Support, String> {
    match key {
        "free" => Ok(Support::Free),
        "pinned" => Ok(Support::Pinned),
        "clamped" => Ok(Support::Clamped),
        _ => Err(format!("support `{key}`: use free, pinned or clamped")),
    }
}

/// Parse a structure file's text; `elements` overrides every member's element count.
pub fn parse(text: &str, name: &str, elements: Option<usize>) -> Result<BeamScenario, String> {
    let file: File = toml::from_str(text).map_err(|e| e.to_string().replace('\n', " ").trim().to_string())?;
    if file.member.is_empty() {
        return Err("the file has no [[member]]".into());
    }
    let mut frame = Frame::new();
    let mut sections = Vec::new();
    for s in &file.section {
        if sections.iter().any(|(n, _): &(String, Section)| n == &s.name) {
            return Err(format!("section `{}` is defined twice", s.name));
        }
        sections.push((s.name.clone(), section(s)?));
    }
    let mut scale: f64 = 0.0;
    for (k, m) in file.member.iter().enumerate() {
        let sec = sections
            .iter()
            .find(|(n, _)| n == &m.section)
            .ok_or_else(|| format!("member {k}: no section named `{}`", m.section))?
            .1;
        let n = elements.or(m.elements).unwrap_or(8);
        let (from, to) = (Vec3::from_array(m.from), Vec3::from_array(m.to));
        scale = scale.max((to - from).norm());
        frame
            .add_member(from, to, n, sec, Vec3::from_array(m.orientation))
            .map_err(|e| format!("member {k}: {e}"))?;
    }
    let tolerance = 1e-6 * scale;
    let find = |frame: &Frame, at: [f64; 3], what: &str| {
        frame
            .node_at(Vec3::from_array(at), tolerance)
            .ok_or_else(|| format!("{what}: no node at {at:?} (nodes are the members' ends and element divisions)"))
    };
    for (k, nd) in file.node.iter().enumerate() {
        let id = find(&frame, nd.at, &format!("node {k}"))?;
        if let Some(s) = &nd.support {
            frame
                .support(id, support(s).map_err(|e| format!("node {k}: {e}"))?)
                .map_err(|e| e.to_string())?;
        }
        if let Some(n) = &nd.name {
            frame.name(n, id).map_err(|e| format!("node {k}: {e}"))?;
        }
    }
    for (k, l) in file.load.iter().enumerate() {
        let id = match (&l.at, &l.node) {
            (Some(at), None) => find(&frame, *at, &format!("load {k}"))?,
            (None, Some(n)) => frame.named(n).ok_or_else(|| format!("load {k}: no node named `{n}`"))?,
            _ => return Err(format!("load {k}: give `at = [x, y, z]` or `node = \"NAME\"`")),
        };
        let history = match &l.history {
            Some(points) => {
                History::new(points.iter().map(|p| (p[0], p[1])).collect()).map_err(|e| format!("load {k}: {e}"))?
            }
            None => History::constant(),
        };
        frame
            .load(NodalLoad {
                node: id,
                force: Vec3::from_array(l.force.unwrap_or([0.0; 3])),
                moment: Vec3::from_array(l.moment.unwrap_or([0.0; 3])),
                follower: l.follower.unwrap_or(false),
                history,
            })
            .map_err(|e| format!("load {k}: {e}"))?;
    }
    if let Some(g) = file.run.gravity {
        frame.gravity = Vec3::from_array(g);
        if !frame.gravity.is_finite() {
            return Err("[run] gravity is not finite".into());
        }
    }
    let method =
        integrator(file.run.method.as_deref().unwrap_or("liemid")).map_err(|e| format!("[run] method: {e}"))?;
    let drift = drift(file.run.drift.as_deref().unwrap_or("midpoint")).map_err(|e| format!("[run] drift: {e}"))?;
    let t_end = file.run.t_end.ok_or("[run] t_end is missing")?;
    Ok(BeamScenario {
        name: name.to_string(),
        problem: problems::BeamProblem {
            name: "file",
            description: "a structure file",
            frame,
            t_end,
            initial_mode: None,
        },
        method,
        drift,
        step: file.run.step,
        sample: file.run.sample,
    })
}

/// Load a structure file.
pub fn load(path: &Path, elements: Option<usize>) -> Result<BeamScenario, String> {
    let text = crate::shared::input::read_text(path, crate::shared::input::MAX_SCENARIO_BYTES)?;
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("file");
    parse(&text, name, elements).map_err(|e| format!("{}: {e}", path.display()))
}

/// A built-in problem as a scenario.
pub fn builtin(name: &str, elements: Option<usize>) -> Result<BeamScenario, String> {
    let problem = problems::by_name(name, elements).map_err(|e| e.to_string())?;
    Ok(BeamScenario {
        name: problem.name.to_string(),
        problem,
        method: BeamIntegrator::Explicit(liemid::beam::BeamMethod::Splitting),
        drift: Drift::Midpoint,
        step: None,
        sample: None,
    })
}
