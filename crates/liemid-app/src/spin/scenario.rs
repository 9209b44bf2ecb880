//! Spin-dynamics scenario files for `liemid spins` (TOML):
//!
//! ```toml
//! [lattice]
//! kind = "square"            # "chain" | "square" | "cubic"
//! size = [64, 64]            # site index = x + nx (y + ny z)
//! periodic = true
//! [hamiltonian]              # E = -J sum_<ij> S_i.S_j - K sum (S_i.n)^2 - mu_s mu_B B.sum S_i
//! exchange = 1.0             # J, meV, each pair once
//! anisotropy = 0.1           # K, meV
//! anisotropy_axis = [0.0, 0.0, 1.0]
//! field = [0.0, 0.0, 0.0]    # B, T
//! mu_s = 1.0                 # Bohr magnetons
//! dmi = 0.3                  # D, meV: E += -sum_<ij> D_ij.(S_i x S_j) [default 0]
//! dmi_kind = "interfacial"   # D_ij = D z x r_ij ("interfacial", Spirit's dm_chirality -2) or D r_ij ("bulk", 1)
//! [dynamics]
//! damping = 0.0              # Gilbert alpha
//! method = "split"           # `liemid methods --spins`
//! step = 1e-3                # ps
//! t_end = 10.0               # ps
//! [initial]
//! file = "start.npy"         # (N, 3) float64 in site order; or kind = "uniform" | "random" | "near-z"
//!                            # | "skyrmion" (a Neel skyrmion of `radius` sites at the centre of a square
//!                            # lattice, relaxed by velocity projection; then tilted by up to `max_tilt`, default 0)
//! [output]
//! path = "spins.csv"         # t, energy, mx, my, mz (mean spin); .npy or .csv
//! every = 10
//! ```

/// The memory a lattice site takes at most while a run steps (see `parse`).
const BYTES_PER_SITE: f64 = 400.0;

use std::path::{Path, PathBuf};

use liemid::spin::{self, problems, DmiKind, Lattice, LatticeKind, SpinMethod, SpinSystem};
use liemid::Vec3;

use crate::shared::toml_table::{parse_table, Section};

/// A spin scenario: the system, its initial spins, the method and the run's settings.
#[derive(Clone, Debug)]
pub struct SpinScenario {
    /// Name (the problem's or the file's).
    pub name: String,
    /// The system.
    pub system: SpinSystem,
    /// Initial spins (unit).
    pub spins: Vec<liemid::Vec3>,
    /// Method [default: split, or midpoint with damping].
    pub method: SpinMethod,
    /// Step (ps).
    pub step: f64,
    /// End time (ps).
    pub t_end: f64,
    /// `[output] path`.
    pub out: Option<PathBuf>,
    /// `[output] every`.
    pub every: Option<u64>,
    /// Files the scenario reads (the initial `.npy`), so no output may replace them.
    pub inputs: Vec<PathBuf>,
}

/// Why a lattice size is refused.
#[derive(Debug)]
pub enum SizeRefusal {
    /// More than 10⁸ sites.
    Count(String),
    /// More than the memory available.
    Memory(String),
}

/// The sites of a lattice of `size`, refused beyond 10⁸ sites or beyond 80 % of the
/// memory available (400 bytes a site), before anything is built; shared by the scenario
/// files and the Python package.
///
/// # Errors
/// One line: the sites and the limit, or the memory needed and the memory available.
pub fn check_lattice_size(size: &[usize]) -> Result<f64, SizeRefusal> {
    let sites: f64 = size.iter().map(|&n| n as f64).product();
    if sites > 1e8 {
        return Err(SizeRefusal::Count(format!("{sites:e} sites; at most 1e8 are accepted")));
    }
    // The lattice, its bonds, the spins and the integrator's buffers: about 110 bytes a site
    // on a square lattice and 150 on a cubic one (peak resident size of 10⁶-site runs here);
    // the reliability sweep saw 3.7 GB at 10⁷ sites with its outputs, so 400 is asked for.
    crate::shared::memory::check_fits(&format!("a lattice of {sites:e} sites"), sites * BYTES_PER_SITE)
        .map_err(SizeRefusal::Memory)?;
    Ok(sites)
}

/// The method named `key`, or an error listing the spin methods.
pub fn parse_method(key: &str) -> Result<SpinMethod, String> {
    SpinMethod::from_key(key).ok_or_else(|| {
        let known: Vec<&str> = SpinMethod::ALL.iter().map(|m| m.key()).collect();
        format!("unknown spin method `{key}` (known: {})", known.join(", "))
    })
}

/// A built-in problem as a scenario.
pub fn builtin(name: &str) -> Result<SpinScenario, String> {
    let p = problems::get(name)
        .ok_or_else(|| format!("unknown spin problem `{name}` (known: {})", problems::NAMES.join(", ")))?;
    Ok(SpinScenario {
        name: p.name.to_string(),
        system: p.system,
        spins: p.spins,
        method: SpinMethod::Splitting,
        step: p.step,
        t_end: p.t_end,
        out: None,
        every: None,
        inputs: Vec::new(),
    })
}

/// Read and parse a scenario file; errors are one line naming the file, section and key.
pub fn load(path: &Path) -> Result<SpinScenario, String> {
    let file = path.display().to_string();
    let text = crate::shared::input::read_text(path, crate::shared::input::MAX_SCENARIO_BYTES)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_stem()
        .map_or(file.clone(), |s| s.to_string_lossy().into_owned());
    parse(&text, &name, dir).map_err(|e| format!("{file}: {e}"))
}

/// Parse scenario text; relative paths are taken from `dir`.
pub fn parse(text: &str, name: &str, dir: &Path) -> Result<SpinScenario, String> {
    let root = parse_table(text)?;
    for key in root.keys() {
        if !["lattice", "hamiltonian", "dynamics", "initial", "output"].contains(&key.as_str()) {
            let hint = if ["body", "torque", "integrator", "system"].contains(&key.as_str()) {
                "; this looks like a rigid-body scenario: run it with `liemid run` or `liemid many`"
            } else {
                ""
            };
            return Err(format!(
                "unknown section `{key}` (sections: lattice, hamiltonian, dynamics, initial, output){hint}"
            ));
        }
    }
    let lattice_section = Section::new(&root, "lattice", &["kind", "size", "periodic"], true)?.expect("required");
    let kind = match lattice_section.string("kind")?.unwrap_or("square") {
        "chain" => LatticeKind::Chain,
        "square" => LatticeKind::Square,
        "cubic" => LatticeKind::Cubic,
        other => {
            return Err(lattice_section.err("kind", format!("unknown lattice \"{other}\" (chain, square, cubic)")));
        }
    };
    let size: Vec<usize> = lattice_section
        .counts("size")?
        .ok_or_else(|| lattice_section.err("size", "is required"))?
        .into_iter()
        .map(|n| n as usize)
        .collect();
    check_lattice_size(&size).map_err(|e| match e {
        SizeRefusal::Count(m) | SizeRefusal::Memory(m) => lattice_section.err("size", m),
    })?;
    let periodic = lattice_section.boolean("periodic")?.unwrap_or(true);
    let lattice = Lattice::new(kind, &size, periodic).map_err(|e| lattice_section.err("size", e))?;

    let h = Section::new(
        &root,
        "hamiltonian",
        &[
            "exchange",
            "anisotropy",
            "anisotropy_axis",
            "field",
            "mu_s",
            "dmi",
            "dmi_kind",
        ],
        false,
    )?;
    let (mut exchange, mut anisotropy, mut axis, mut field, mut mu_s) =
        (1.0, 0.0, Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 1.0);
    let (mut dmi, mut dmi_kind) = (0.0, DmiKind::Interfacial);
    if let Some(h) = &h {
        exchange = h.number("exchange")?.unwrap_or(exchange);
        anisotropy = h.number("anisotropy")?.unwrap_or(anisotropy);
        axis = h.vec3("anisotropy_axis")?.unwrap_or(axis);
        field = h.vec3("field")?.unwrap_or(field);
        mu_s = h.number("mu_s")?.unwrap_or(mu_s);
        dmi = h.number("dmi")?.unwrap_or(dmi);
        if let Some(k) = h.string("dmi_kind")? {
            dmi_kind = DmiKind::from_key(k)
                .ok_or_else(|| h.err("dmi_kind", format!("unknown kind \"{k}\" (interfacial, bulk)")))?;
        }
    }
    let d = Section::new(&root, "dynamics", &["damping", "method", "step", "t_end"], false)?;
    let mut damping = 0.0;
    let mut method = None;
    let (mut step, mut t_end) = (1e-2, 10.0);
    if let Some(d) = &d {
        damping = d.number("damping")?.unwrap_or(0.0);
        if let Some(m) = d.string("method")? {
            method = Some(parse_method(m).map_err(|e| d.err("method", e))?);
        }
        step = d.number("step")?.unwrap_or(step);
        t_end = d.number("t_end")?.unwrap_or(t_end);
    }
    let system = SpinSystem::new(lattice, exchange, anisotropy, axis, field, mu_s, damping)
        .and_then(|s| s.with_dmi(dmi, dmi_kind))
        .map_err(|e| {
            // The damping is read from [dynamics], every other parameter from [hamiltonian].
            let section = match e {
                liemid::Error::InvalidParameter { name: "damping", .. } => "dynamics",
                _ => "hamiltonian",
            };
            format!("[{section}] {e}")
        })?;
    let n = system.len();
    let mut inputs = Vec::new();
    let init = Section::new(
        &root,
        "initial",
        &["file", "kind", "seed", "direction", "max_tilt", "radius"],
        false,
    )?;
    let spins = match &init {
        None => problems::near_z(n, 0.3, 1),
        Some(init) => {
            if let Some(f) = init.string("file")? {
                if init.string("kind")?.is_some() {
                    return Err("[initial] gives both `file` and `kind`; use only one".into());
                }
                let path = dir.join(f);
                let rows = crate::shared::npy::read_matrix(&path, 3).map_err(|e| init.err("file", e))?;
                if rows.len() != n {
                    return Err(init.err(
                        "file",
                        format!(
                            "{} holds {} spins, the lattice has {n} sites",
                            path.display(),
                            rows.len()
                        ),
                    ));
                }
                inputs.push(path);
                let v: Vec<Vec3> = rows.iter().map(|r| Vec3::new(r[0], r[1], r[2])).collect();
                spin::normalized(&v).map_err(|e| init.err("file", format!("{e}")))?
            } else {
                let seed = init.count("seed")?.unwrap_or(1);
                match init.string("kind")?.unwrap_or("near-z") {
                    "uniform" => {
                        let dir = init.vec3("direction")?.unwrap_or(Vec3::new(0.0, 0.0, 1.0));
                        if dir.norm() == 0.0 {
                            return Err(init.err("direction", "must be a non-zero vector"));
                        }
                        spin::uniform(n, dir)
                    }
                    "random" => {
                        let mut rng = liemid::random::Rng::new(seed);
                        (0..n).map(|_| rng.unit_vector()).collect()
                    }
                    "near-z" => {
                        let tilt = init.number("max_tilt")?.unwrap_or(0.3);
                        if !(0.0..=std::f64::consts::PI).contains(&tilt) {
                            return Err(init.err(
                                "max_tilt",
                                format!("must be in [0, pi] rad, found {}", liemid::error::Num(tilt)),
                            ));
                        }
                        problems::near_z(n, tilt, seed)
                    }
                    "skyrmion" => {
                        let [nx, ny, nz] = system.lattice.size();
                        if system.lattice.kind() != LatticeKind::Square || nz != 1 {
                            return Err(init.err("kind", "a skyrmion start needs a square lattice"));
                        }
                        let radius = init.number("radius")?.unwrap_or(6.0);
                        if !(radius.is_finite() && radius > 0.0) {
                            return Err(init.err(
                                "radius",
                                format!(
                                    "must be a positive number of sites, found {}",
                                    liemid::error::Num(radius)
                                ),
                            ));
                        }
                        let tilt = init.number("max_tilt")?.unwrap_or(0.0);
                        if !(0.0..=std::f64::consts::PI).contains(&tilt) {
                            return Err(init.err(
                                "max_tilt",
                                format!("must be in [0, pi] rad, found {}", liemid::error::Num(tilt)),
                            ));
                        }
                        let mut s = problems::skyrmion_seed(nx, ny, radius, dmi >= 0.0);
                        spin::relax(&system, &mut s, 1e-10, 1_000_000)
                            .map_err(|e| init.err("kind", format!("the skyrmion did not relax: {e}")))?;
                        if tilt > 0.0 {
                            s = problems::tilted(&s, tilt, seed);
                        }
                        s
                    }
                    other => {
                        return Err(init.err(
                            "kind",
                            format!("unknown start \"{other}\" (uniform, random, near-z, skyrmion, or file = ...)"),
                        ))
                    }
                }
            }
        }
    };
    let out = Section::new(&root, "output", &["path", "every"], false)?;
    let (mut path, mut every) = (None, None);
    if let Some(o) = &out {
        path = o.string("path")?.map(|p| dir.join(p));
        every = o.count("every")?;
    }
    let method = method.unwrap_or(if damping > 0.0 {
        SpinMethod::Midpoint
    } else {
        SpinMethod::Splitting
    });
    Ok(SpinScenario {
        name: name.to_string(),
        system,
        spins,
        method,
        step,
        t_end,
        out: path,
        every,
        inputs,
    })
}
