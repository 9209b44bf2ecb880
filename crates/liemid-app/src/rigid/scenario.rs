//! Scenario files (TOML) and the built-in problems, turned into a system, an initial state
//! and the integrator settings.
//!
//! Every key is checked: unknown sections and keys are errors that name them, and values
//! of the wrong type or out of range name their section and key.

use std::path::Path;

use liemid::{
    rigid::problems, so3, ConstantTorque, FreeBody, HeavyTop, Inertia, Mat3, RigidBodySystem, RigidState,
    RotationMethod, Vec3,
};
use toml::Value;

pub use crate::shared::toml_table::{parse_table, Section};

pub use crate::shared::toml_table::MAX_MAGNITUDE;

/// The range of principal moments (and of the entries of a full tensor): inverse moments,
/// squares and determinants stay far from overflow and underflow. Molecules are about 1e-46
/// kg m², planets 1e38.
pub const INERTIA_RANGE: (f64, f64) = (1e-100, 1e100);

/// The largest rotation angle `|rotation_vector|` accepted (rad): beyond it the angle
/// modulo a turn has lost more than 1e-12 rad to rounding.
pub const MAX_ROTATION_ANGLE: f64 = 1e4;

/// Which quantities a scenario's torque model conserves, for honest summaries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Conservation {
    /// Torque-free: energy and all of `π`.
    Free,
    /// Gravity: energy and `π · ĝ` along the unit vector `ĝ` (the other components change).
    Gravity(Vec3),
    /// A constant torque does work: neither energy nor `π` is conserved.
    Driven,
}

/// The torque models a scenario can use, dispatched statically.
#[derive(Clone, Debug)]
pub enum ScenarioSystem {
    /// `kind = "none"`.
    Free(FreeBody),
    /// `kind = "gravity"`.
    Gravity(HeavyTop),
    /// `kind = "constant"`.
    Constant(ConstantTorque),
}

impl RigidBodySystem for ScenarioSystem {
    fn inertia(&self) -> &Inertia {
        match self {
            ScenarioSystem::Free(s) => s.inertia(),
            ScenarioSystem::Gravity(s) => s.inertia(),
            ScenarioSystem::Constant(s) => s.inertia(),
        }
    }
    #[inline]
    fn torque(&self, rotation: &Mat3, t: f64) -> Vec3 {
        match self {
            ScenarioSystem::Free(s) => s.torque(rotation, t),
            ScenarioSystem::Gravity(s) => s.torque(rotation, t),
            ScenarioSystem::Constant(s) => s.torque(rotation, t),
        }
    }
    fn potential_energy(&self, rotation: &Mat3, t: f64) -> f64 {
        match self {
            ScenarioSystem::Free(s) => s.potential_energy(rotation, t),
            ScenarioSystem::Gravity(s) => s.potential_energy(rotation, t),
            ScenarioSystem::Constant(s) => s.potential_energy(rotation, t),
        }
    }
}

impl ScenarioSystem {
    /// What this torque model conserves.
    pub fn conservation(&self) -> Conservation {
        match self {
            ScenarioSystem::Free(_) => Conservation::Free,
            ScenarioSystem::Gravity(top) => {
                let g = top.gravity;
                if top.mass == 0.0 || g.norm() == 0.0 || top.center_of_mass.norm() == 0.0 {
                    Conservation::Free
                } else {
                    Conservation::Gravity(g * (1.0 / g.norm()))
                }
            }
            ScenarioSystem::Constant(c) => {
                if c.body.norm() == 0.0 && c.spatial.norm() == 0.0 {
                    Conservation::Free
                } else {
                    Conservation::Driven
                }
            }
        }
    }
}

pub use crate::shared::output::Format;

/// The `[output]` section.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OutputSpec {
    /// Trajectory path.
    pub path: Option<String>,
    /// Write every `every`-th step.
    pub every: Option<u64>,
    /// File format.
    pub format: Option<Format>,
}

/// A complete scenario.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Where it came from: a file path or a built-in problem name.
    pub name: String,
    /// The system.
    pub system: ScenarioSystem,
    /// The initial state.
    pub initial: RigidState,
    /// The integrator.
    pub method: RotationMethod,
    /// The step size.
    pub step: f64,
    /// The end time.
    pub t_end: f64,
    /// Output settings from the file.
    pub output: OutputSpec,
}

/// The built-in problem names.
pub const PROBLEMS: [&str; 5] = ["fast-top", "slow-top", "free-body", "torque-top", "asymmetric-top"];

/// A built-in problem as a scenario (LIEMID\[EA\], h = 1e-4 for the tops).
pub fn builtin(name: &str) -> Result<Scenario, String> {
    let (system, initial, t_end, step) = match name {
        "fast-top" => {
            let p = problems::fast_top();
            (ScenarioSystem::Gravity(p.system), p.initial, p.t_end, 1e-4)
        }
        "slow-top" => {
            let p = problems::slow_top();
            (ScenarioSystem::Gravity(p.system), p.initial, p.t_end, 1e-4)
        }
        "torque-top" => {
            let p = problems::torque_dominated_top();
            (ScenarioSystem::Gravity(p.system), p.initial, p.t_end, 1e-3)
        }
        "asymmetric-top" => {
            let p = problems::asymmetric_top();
            (ScenarioSystem::Gravity(p.system), p.initial, p.t_end, 1e-3)
        }
        "free-body" => {
            let p = problems::free_body();
            (ScenarioSystem::Free(p.system), p.initial, p.t_end, 1e-3)
        }
        other => {
            return Err(format!("unknown problem `{other}` (known: {})", PROBLEMS.join(", ")));
        }
    };
    Ok(Scenario {
        name: name.to_string(),
        system,
        initial,
        method: RotationMethod::LieMidpointAlternating,
        step,
        t_end,
        output: OutputSpec::default(),
    })
}

/// One line describing a built-in problem.
pub fn describe(name: &str) -> &'static str {
    match name {
        "fast-top" => problems::fast_top().description,
        "slow-top" => problems::slow_top().description,
        "torque-top" => problems::torque_dominated_top().description,
        "free-body" => problems::free_body().description,
        "asymmetric-top" => problems::asymmetric_top().description,
        _ => "",
    }
}

/// Parse a scenario file; errors are one line naming the file, the key and the problem.
pub fn load(path: &Path) -> Result<Scenario, String> {
    load_with_text(path).map(|(scenario, _)| scenario)
}

/// [`load`], also returning the text that was parsed.
pub fn load_with_text(path: &Path) -> Result<(Scenario, String), String> {
    let file = path.display().to_string();
    let text = crate::shared::input::read_text(path, crate::shared::input::MAX_SCENARIO_BYTES)?;
    let scenario = parse(&text, &file).map_err(|e| format!("{file}: {e}"))?;
    Ok((scenario, text))
}

/// Parse scenario text (`name` labels the scenario).
pub fn parse(text: &str, name: &str) -> Result<Scenario, String> {
    let root = parse_table(text)?;
    for key in root.keys() {
        if !["body", "initial", "torque", "integrator", "output"].contains(&key.as_str()) {
            let hint = if key == "system" {
                "; this is a many-body scenario: run it with `liemid many --scenario FILE`"
            } else {
                ""
            };
            return Err(format!(
                "unknown section or key `{key}` (sections: body, initial, torque, integrator, output){hint}"
            ));
        }
    }

    let body = Section::new(&root, "body", &["inertia"], true)?.expect("required");
    let inertia_value = body
        .table
        .get("inertia")
        .ok_or_else(|| body.err("inertia", "is required"))?;
    let inertia = match inertia_value {
        Value::Array(a) if a.first().is_some_and(|v| v.is_array()) => {
            Inertia::from_matrix(body.mat3_of("inertia", inertia_value)?)
        }
        _ => Inertia::principal(body.vec3_of("inertia", inertia_value)?.to_array()),
    }
    .map_err(|e| body.err("inertia", e))?;
    let (lo, hi) = INERTIA_RANGE;
    let entries = inertia.matrix().m;
    if let Some(x) = entries
        .iter()
        .flatten()
        .find(|x| **x != 0.0 && !(lo..=hi).contains(&x.abs()))
    {
        return Err(body.err(
            "inertia",
            format!("{x:e} is out of range: moments from {lo:e} to {hi:e} kg m^2 are accepted (rescale the units)"),
        ));
    }

    let initial = Section::new(
        &root,
        "initial",
        &[
            "rotation_vector",
            "quaternion",
            "matrix",
            "angular_velocity",
            "angular_momentum",
            "time",
        ],
        true,
    )?
    .expect("required");
    let rotation = match initial.one_of(&["rotation_vector", "quaternion", "matrix"], true)? {
        None => Mat3::IDENTITY,
        Some("rotation_vector") => {
            let v = initial.vec3("rotation_vector")?.expect("present");
            if v.norm() > MAX_ROTATION_ANGLE {
                return Err(initial.err(
                    "rotation_vector",
                    format!(
                        "its length, the rotation angle, is {:e} rad; at most {MAX_ROTATION_ANGLE:e} is accepted \
                         (take it modulo 2 pi)",
                        v.norm()
                    ),
                ));
            }
            so3::exp(v)
        }
        Some("quaternion") => {
            let a = initial.array_of("quaternion", &initial.table["quaternion"], 4)?;
            let c: Vec<f64> = a
                .iter()
                .map(|v| initial.number_of("quaternion", v))
                .collect::<Result<_, _>>()?;
            let q = so3::Quaternion::new(c[0], c[1], c[2], c[3]);
            let n = q.norm();
            if n.is_nan() || (n - 1.0).abs() > 1e-6 {
                return Err(initial.err(
                    "quaternion",
                    format!("must be a unit quaternion [w, x, y, z], norm is {n}"),
                ));
            }
            q.normalized().to_matrix()
        }
        Some(_) => {
            let m = Mat3::from_rows(initial.mat3_of("matrix", &initial.table["matrix"])?);
            let defect = so3::orthogonality_defect(&m);
            if defect > 1e-6 || m.determinant() <= 0.0 {
                return Err(initial.err(
                    "matrix",
                    format!(
                        "must be a rotation (orthogonality defect {defect:.1e}, determinant {:.3})",
                        m.determinant()
                    ),
                ));
            }
            so3::orthonormalize(&m).expect("checked")
        }
    };
    let t0 = initial.number("time")?.unwrap_or(0.0);
    let pi = match initial.one_of(&["angular_velocity", "angular_momentum"], false)? {
        Some("angular_velocity") => inertia.apply(initial.vec3("angular_velocity")?.expect("present")),
        _ => initial.vec3("angular_momentum")?.expect("present"),
    };

    let torque = Section::new(
        &root,
        "torque",
        &["kind", "mass", "gravity", "center_of_mass", "body", "spatial"],
        false,
    )?;
    let system = match &torque {
        None => ScenarioSystem::Free(FreeBody::new(inertia)),
        Some(t) => {
            let kind = t
                .string("kind")?
                .ok_or_else(|| t.err("kind", "is required (\"none\", \"gravity\" or \"constant\")"))?;
            let allowed: &[&str] = match kind {
                "none" => &["kind"],
                "gravity" => &["kind", "mass", "gravity", "center_of_mass"],
                "constant" => &["kind", "body", "spatial"],
                other => {
                    return Err(t.err(
                        "kind",
                        format!("unknown kind \"{other}\" (use \"none\", \"gravity\" or \"constant\")"),
                    ))
                }
            };
            if let Some(k) = t.table.keys().find(|k| !allowed.contains(&k.as_str())) {
                return Err(t.err(k, format!("is not used by kind = \"{kind}\"")));
            }
            match kind {
                "none" => ScenarioSystem::Free(FreeBody::new(inertia)),
                "gravity" => {
                    let mass = t.required_number("mass")?;
                    if mass <= 0.0 {
                        return Err(t.err("mass", format!("must be positive, found {}", liemid::error::Num(mass))));
                    }
                    let gravity = t.vec3("gravity")?.unwrap_or(Vec3::new(0.0, 0.0, -9.81));
                    let com = t
                        .vec3("center_of_mass")?
                        .ok_or_else(|| t.err("center_of_mass", "is required"))?;
                    ScenarioSystem::Gravity(
                        HeavyTop::new(inertia, mass, com, gravity).map_err(|e| t.err("gravity", e))?,
                    )
                }
                _ => {
                    if !t.has("body") && !t.has("spatial") {
                        return Err("[torque] kind = \"constant\" needs `body` and/or `spatial`".to_string());
                    }
                    let b = t.vec3("body")?.unwrap_or(Vec3::ZERO);
                    let s = t.vec3("spatial")?.unwrap_or(Vec3::ZERO);
                    ScenarioSystem::Constant(ConstantTorque::new(inertia, b, s).map_err(|e| t.err("body", e))?)
                }
            }
        }
    };

    // Inputs each in range can still overflow together (a huge mass at a huge distance).
    let state = RigidState::new(t0, pi, rotation);
    let d = liemid::Diagnostics::of(&system, &state);
    let torque0 = system.torque(&rotation, t0);
    let omega = inertia.apply_inverse(pi);
    for (what, ok, keys) in [
        (
            "angular velocity",
            omega.is_finite() && omega.norm() <= MAX_MAGNITUDE,
            "[body] inertia, [initial] angular_velocity or angular_momentum",
        ),
        (
            "torque",
            torque0.is_finite() && torque0.norm() <= MAX_MAGNITUDE,
            "[torque]",
        ),
        (
            "energy",
            d.energy.is_finite() && d.energy.abs() <= MAX_MAGNITUDE,
            "[body], [initial] and [torque]",
        ),
    ] {
        if !ok {
            return Err(format!(
                "the initial {what} overflows (beyond {MAX_MAGNITUDE:e}); check the magnitudes in {keys}"
            ));
        }
    }

    let integ = Section::new(&root, "integrator", &["method", "step", "t_end"], true)?.expect("required");
    let method_name = integ.string("method")?.unwrap_or("liemid-ea");
    let method = RotationMethod::from_key(method_name).ok_or_else(|| {
        let known: Vec<&str> = RotationMethod::ALL.iter().map(|m| m.key()).collect();
        integ.err(
            "method",
            format!("unknown method \"{method_name}\" (known: {})", known.join(", ")),
        )
    })?;
    let step = integ.required_number("step")?;
    if step <= 0.0 {
        return Err(integ.err("step", format!("must be positive, found {}", liemid::error::Num(step))));
    }
    let t_end = integ.required_number("t_end")?;
    if t_end < t0 {
        return Err(integ.err("t_end", format!("{t_end} is before the start time {t0}")));
    }
    liemid::step_count(t0, t_end, step).map_err(|e| integ.err("step and t_end", e.to_string()))?;

    let mut output = OutputSpec::default();
    if let Some(out) = Section::new(&root, "output", &["path", "every", "format"], false)? {
        output.path = out.string("path")?.map(str::to_string);
        output.every = out.count("every")?;
        output.format = match out.string("format")? {
            None => None,
            Some("csv") => Some(Format::Csv),
            Some("npy") => Some(Format::Npy),
            Some(other) => {
                return Err(out.err("format", format!("unknown format \"{other}\" (use \"csv\" or \"npy\")")))
            }
        };
    }

    Ok(Scenario {
        name: name.to_string(),
        system,
        initial: RigidState::new(t0, pi, rotation),
        method,
        step,
        t_end,
        output,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const FAST_TOP: &str = r#"
[body]
inertia = [0.0454896, 0.0454896, 0.00139968]
[initial]
rotation_vector = [0.05, 0.0, 0.0]
angular_velocity = [0.0, 0.0, 983.3185]
[torque]
kind = "gravity"
mass = 2.3328
gravity = [0.0, 0.0, -9.81]
center_of_mass = [0.0, 0.0, 0.12]
[integrator]
method = "liemid-ea"
step = 1e-4
t_end = 0.8
[output]
path = "trajectory.csv"
every = 10
"#;

    #[test]
    fn parses_every_key() {
        let s = parse(FAST_TOP, "t").unwrap();
        assert_eq!(s.method, RotationMethod::LieMidpointAlternating);
        assert_eq!((s.step, s.t_end), (1e-4, 0.8));
        assert_eq!(s.output.path.as_deref(), Some("trajectory.csv"));
        assert_eq!(s.output.every, Some(10));
        assert!((s.initial.pi.z - 0.00139968 * 983.3185).abs() < 1e-15);
        assert!((s.initial.rotation - so3::exp(Vec3::new(0.05, 0.0, 0.0))).max_abs() == 0.0);
        let ScenarioSystem::Gravity(top) = &s.system else {
            panic!("gravity")
        };
        assert_eq!(top.mass, 2.3328);
        assert_eq!(top.center_of_mass, Vec3::new(0.0, 0.0, 0.12));
        // Same body as the built-in problem.
        let builtin = builtin("fast-top").unwrap();
        let torque_a = s.system.torque(&s.initial.rotation, 0.0);
        let torque_b = builtin.system.torque(&s.initial.rotation, 0.0);
        assert!((torque_a - torque_b).max_abs() < 1e-12);
    }

    #[test]
    fn alternative_forms() {
        let text = r#"
[body]
inertia = [[2.0, 0.1, 0.0], [0.1, 3.0, 0.0], [0.0, 0.0, 4.0]]
[initial]
quaternion = [0.0, 1.0, 0.0, 0.0]
angular_momentum = [1.0, 2.0, 3.0]
time = 1.5
[torque]
kind = "constant"
spatial = [0.0, 0.0, 1.0]
[integrator]
method = "rk4"
step = 0.01
t_end = 2.0
[output]
format = "npy"
"#;
        let s = parse(text, "t").unwrap();
        assert_eq!(s.initial.pi, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(s.initial.t, 1.5);
        assert!((s.initial.rotation - Mat3::from_diagonal(Vec3::new(1.0, -1.0, -1.0))).max_abs() < 1e-15);
        assert_eq!(s.method, RotationMethod::RungeKutta4);
        assert_eq!(s.output.format, Some(Format::Npy));
        let torque = s.system.torque(&s.initial.rotation, 0.0);
        assert!((torque - Vec3::new(0.0, 0.0, -1.0)).max_abs() < 1e-15);
        let m = text.replace(
            "quaternion = [0.0, 1.0, 0.0, 0.0]",
            "matrix = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]",
        );
        let s2 = parse(&m, "t").unwrap();
        assert!((s2.initial.rotation - s.initial.rotation).max_abs() < 1e-15);
        let none = text.replace("kind = \"constant\"\nspatial = [0.0, 0.0, 1.0]", "kind = \"none\"");
        assert!(matches!(parse(&none, "t").unwrap().system, ScenarioSystem::Free(_)));
    }

    #[test]
    fn errors_name_the_key() {
        let cases = [
            (
                "inertia = [0.0454896",
                "inertiaa = [0.0454896",
                "[body] unknown key `inertiaa`",
            ),
            ("[output]", "[outputs]", "unknown section or key `outputs`"),
            ("mass = 2.3328", "mass = -1.0", "[torque] mass: must be positive"),
            (
                "mass = 2.3328",
                "mass = \"heavy\"",
                "[torque] mass: expected a number, found string",
            ),
            ("step = 1e-4", "step = 0.0", "[integrator] step: must be positive"),
            (
                "step = 1e-4",
                "step = 1e-40",
                "[integrator] step and t_end: step size h = 1e-40 is too small for t from 0 to 0.8: t + h rounds",
            ),
            (
                "t_end = 0.8",
                "t_end = -1.0",
                "[integrator] t_end: -1 is before the start time 0",
            ),
            (
                "\"liemid-ea\"",
                "\"euler\"",
                "[integrator] method: unknown method \"euler\"",
            ),
            (
                "kind = \"gravity\"",
                "kind = \"magnetic\"",
                "[torque] kind: unknown kind \"magnetic\"",
            ),
            (
                "every = 10",
                "every = 0",
                "[output] every: expected a whole number of at least 1",
            ),
            (
                "[0.0454896, 0.0454896, 0.00139968]",
                "[0.0454896, -0.1, 0.00139968]",
                "[body] inertia: invalid inertia tensor: principal moment I2 = -0.1",
            ),
            (
                "rotation_vector = [0.05, 0.0, 0.0]",
                "rotation_vector = [0.05, 0.0]",
                "[initial] rotation_vector: expected 3 entries, found 2",
            ),
            (
                "angular_velocity = [0.0, 0.0, 983.3185]",
                "",
                "[initial] needs one of: angular_velocity, angular_momentum",
            ),
            (
                "rotation_vector = [0.05, 0.0, 0.0]",
                "rotation_vector = [0.05, 0.0, 0.0]\nquaternion = [1.0, 0.0, 0.0, 0.0]",
                "gives both `rotation_vector` and `quaternion`",
            ),
            (
                "center_of_mass = [0.0, 0.0, 0.12]",
                "center_of_mass = [0.0, 0.0, 0.12]\nbody = [1.0, 0.0, 0.0]",
                "[torque] body: is not used by kind = \"gravity\"",
            ),
            ("[integrator]", "[integrator\n", "line "),
        ];
        for (from, to, expected) in cases {
            assert!(FAST_TOP.contains(from), "{from}");
            let text = FAST_TOP.replacen(from, to, 1);
            let e = parse(&text, "t").unwrap_err();
            assert!(e.contains(expected), "{to}: got `{e}`, expected `{expected}`");
            assert!(!e.contains('\n'), "multi-line error: {e}");
        }
    }
}
