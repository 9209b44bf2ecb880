//! Checkpoints of `liemid run`: everything a run needs to continue bit for bit, as JSON.
//!
//! A checkpoint holds the scenario (the built-in name, or the file's path and full text, so
//! that editing the file afterwards cannot change a resumed run), the settings, the run's
//! progress ([`liemid::Run`]: state, step count, extremes of the diagnostics), the method's
//! cache ([`liemid::MethodCache`]) and how much of the trajectory file belongs to it.
//! Numbers are written as shortest round-trip decimals and parsed exactly
//! (`serde_json`'s `float_roundtrip`), so nothing is lost.
//!
//! A checkpoint carries a checksum: the CRC-32 of its own text written without the checksum
//! (the pretty JSON of [`Checkpoint`] with `checksum` null). Reading parses the file,
//! writes it again without the checksum and compares, so any edited or damaged value is
//! refused, while the layout (spaces, line ends) may change. Then its content is validated
//! like any input (grid, interval, time, attitude): a checkpoint edited on purpose and
//! sealed again with [`reseal`] is still checked.

use std::path::Path;

use liemid::error::Num;
use liemid::{Diagnostics, Mat3, MethodCache, Run, RunSummary, Vec3};
use serde::{Deserialize, Serialize};

use crate::shared::output::Written;

/// The format tag of the checkpoint files this version reads and writes.
pub const FORMAT: &str = "liemid-checkpoint-2";

/// Where the scenario came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// A built-in problem.
    Builtin(String),
    /// A scenario file: its path when the run started, and its text.
    File {
        /// The path it was read from.
        path: String,
        /// Its full text.
        text: String,
    },
}

/// The settings of a run, as resolved from the scenario and the command line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// The scenario.
    pub source: Source,
    /// Method key.
    pub method: String,
    /// Nominal step.
    pub step: f64,
    /// End time.
    pub t_end: f64,
    /// Write every N-th step.
    pub every: u64,
    /// The trajectory: path (or `-`) and format (`csv`, `npy`); absolute in a checkpoint.
    pub output: Option<(String, String)>,
    /// The checkpoint file and its interval in steps; absolute in a checkpoint.
    pub checkpoint: Option<(String, u64)>,
}

impl Settings {
    /// The same settings with absolute paths, so that a run resumes from any directory.
    fn with_absolute_paths(&self) -> Settings {
        let absolute = |p: &str| {
            if p == "-" {
                p.to_string()
            } else {
                std::path::absolute(p).map_or_else(|_| p.to_string(), |a| a.display().to_string())
            }
        };
        let mut s = self.clone();
        s.output = s.output.map(|(p, f)| (absolute(&p), f));
        s.checkpoint = s.checkpoint.map(|(p, n)| (absolute(&p), n));
        if let Source::File { path, .. } = &mut s.source {
            *path = absolute(path);
        }
        s
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct StateRecord {
    t: f64,
    pi: [f64; 3],
    rotation: [f64; 9],
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct DiagnosticsRecord {
    energy: f64,
    kinetic_energy: f64,
    spatial_momentum: [f64; 3],
    body_momentum: [f64; 3],
    body_momentum_norm: f64,
    orthogonality_defect: f64,
}

impl From<&Diagnostics> for DiagnosticsRecord {
    fn from(d: &Diagnostics) -> Self {
        DiagnosticsRecord {
            energy: d.energy,
            kinetic_energy: d.kinetic_energy,
            spatial_momentum: d.spatial_momentum.to_array(),
            body_momentum: d.body_momentum.to_array(),
            body_momentum_norm: d.body_momentum_norm,
            orthogonality_defect: d.orthogonality_defect,
        }
    }
}

impl From<&DiagnosticsRecord> for Diagnostics {
    fn from(d: &DiagnosticsRecord) -> Self {
        Diagnostics {
            energy: d.energy,
            kinetic_energy: d.kinetic_energy,
            spatial_momentum: Vec3::from_array(d.spatial_momentum),
            body_momentum: Vec3::from_array(d.body_momentum),
            body_momentum_norm: d.body_momentum_norm,
            orthogonality_defect: d.orthogonality_defect,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct RunRecord {
    t0: f64,
    t_end: f64,
    h: f64,
    total_steps: u64,
    steps: u64,
    state: StateRecord,
    initial: DiagnosticsRecord,
    last: DiagnosticsRecord,
    max_energy_error: f64,
    max_spatial_momentum_change: [f64; 3],
    max_body_momentum_norm_change: f64,
    max_orthogonality_defect: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum CacheRecord {
    Empty,
    Torque {
        t: f64,
        rotation: [f64; 9],
        torque: [f64; 3],
    },
    Quaternion {
        rotation: [f64; 9],
        quaternion: [f64; 4],
    },
}

/// A checkpoint file's content.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    format: String,
    /// The settings.
    pub settings: Settings,
    run: RunRecord,
    cache: CacheRecord,
    /// Largest change of the conserved momentum component so far.
    pub max_conserved_momentum_change: f64,
    /// How much of the trajectory file belongs to the run at this point.
    pub written: Option<Written>,
    /// `crc32:` and eight hex digits: the CRC-32 of the checkpoint's text with this field
    /// null (see the module's documentation).
    #[serde(default)]
    checksum: Option<String>,
}

/// The checksum of a checkpoint: CRC-32 of its pretty JSON with `checksum` null.
fn checksum(c: &Checkpoint) -> Result<String, String> {
    let mut unsealed = c.clone();
    unsealed.checksum = None;
    let text = serde_json::to_string_pretty(&unsealed).map_err(|e| format!("checkpoint: {e}"))?;
    Ok(format!("crc32:{:08x}", crc32fast::hash(text.as_bytes())))
}

/// The text of a checkpoint with its checksum made right: for tools and tests that edit a
/// checkpoint on purpose (what they write is still validated when read).
///
/// # Errors
/// When `text` is not a checkpoint of this format.
pub fn reseal(text: &str) -> Result<String, String> {
    let mut c: Checkpoint = serde_json::from_str(text).map_err(|e| format!("not a liemid checkpoint ({e})"))?;
    c.checksum = Some(checksum(&c)?);
    serde_json::to_string_pretty(&c)
        .map(|t| t + "\n")
        .map_err(|e| format!("checkpoint: {e}"))
}

impl Checkpoint {
    /// A checkpoint of `run` with the method's `cache`.
    pub fn new(
        settings: &Settings,
        run: &Run,
        cache: MethodCache,
        max_conserved_momentum_change: f64,
        written: Option<Written>,
    ) -> Self {
        let p = &run.progress;
        let s = &p.state;
        Checkpoint {
            format: FORMAT.into(),
            settings: settings.with_absolute_paths(),
            run: RunRecord {
                t0: run.t0,
                t_end: run.t_end,
                h: run.h,
                total_steps: run.total_steps,
                steps: p.steps,
                state: StateRecord {
                    t: s.t,
                    pi: s.pi.to_array(),
                    rotation: s.rotation.to_row_major(),
                },
                initial: (&p.initial).into(),
                last: (&p.last).into(),
                max_energy_error: p.max_energy_error,
                max_spatial_momentum_change: p.max_spatial_momentum_change.to_array(),
                max_body_momentum_norm_change: p.max_body_momentum_norm_change,
                max_orthogonality_defect: p.max_orthogonality_defect,
            },
            cache: match cache {
                MethodCache::Empty => CacheRecord::Empty,
                MethodCache::Torque { t, rotation, torque } => CacheRecord::Torque {
                    t,
                    rotation: rotation.to_row_major(),
                    torque: torque.to_array(),
                },
                MethodCache::Quaternion {
                    rotation,
                    quaternion: q,
                } => CacheRecord::Quaternion {
                    rotation: rotation.to_row_major(),
                    quaternion: [q.w, q.x, q.y, q.z],
                },
            },
            max_conserved_momentum_change,
            written,
            checksum: None,
        }
    }

    /// The run as it was.
    pub fn run(&self) -> Run {
        let r = &self.run;
        Run {
            t0: r.t0,
            t_end: r.t_end,
            h: r.h,
            total_steps: r.total_steps,
            progress: RunSummary {
                state: liemid::RigidState::new(
                    r.state.t,
                    Vec3::from_array(r.state.pi),
                    Mat3::from_row_major(r.state.rotation),
                ),
                steps: r.steps,
                initial: (&r.initial).into(),
                last: (&r.last).into(),
                max_energy_error: r.max_energy_error,
                max_spatial_momentum_change: Vec3::from_array(r.max_spatial_momentum_change),
                max_body_momentum_norm_change: r.max_body_momentum_norm_change,
                max_orthogonality_defect: r.max_orthogonality_defect,
            },
        }
    }

    /// The method's cache as it was.
    pub fn cache(&self) -> MethodCache {
        match self.cache {
            CacheRecord::Empty => MethodCache::Empty,
            CacheRecord::Torque { t, rotation, torque } => MethodCache::Torque {
                t,
                rotation: Mat3::from_row_major(rotation),
                torque: Vec3::from_array(torque),
            },
            CacheRecord::Quaternion {
                rotation,
                quaternion: [w, x, y, z],
            } => MethodCache::Quaternion {
                rotation: Mat3::from_row_major(rotation),
                quaternion: liemid::so3::Quaternion::new(w, x, y, z),
            },
        }
    }

    /// Write to `path` atomically (a `.partial` file renamed over it).
    pub fn write(&self, path: &Path) -> Result<(), String> {
        let mut sealed = self.clone();
        sealed.checksum = Some(checksum(self)?);
        let text = serde_json::to_string_pretty(&sealed).map_err(|e| format!("checkpoint: {e}"))? + "\n";
        crate::shared::output::write_atomically(path, text.as_bytes())
            .map_err(|e| format!("writing the checkpoint {}: {e}", path.display()))
    }

    /// Read and check a checkpoint file.
    pub fn read(path: &Path) -> Result<Self, String> {
        let shown = path.display();
        let text = crate::shared::input::read_text(path, crate::shared::input::MAX_CHECKPOINT_BYTES)?;
        let c: Checkpoint =
            serde_json::from_str(&text).map_err(|e| format!("{shown}: not a liemid checkpoint ({e})"))?;
        if c.format != FORMAT {
            return Err(format!(
                "{shown}: checkpoint format `{}`, this liemid reads `{FORMAT}`",
                c.format
            ));
        }
        match &c.checksum {
            Some(sum) if *sum == checksum(&c)? => {}
            Some(_) => {
                return Err(format!(
                    "{shown}: the checkpoint's checksum does not match its content (edited or damaged; \
                     a run cannot resume from it)"
                ))
            }
            None => return Err(format!("{shown}: the checkpoint has no checksum (edited or damaged)")),
        }
        let r = &c.run;
        if r.steps > r.total_steps || c.settings.every == 0 {
            return Err(format!(
                "{shown}: inconsistent checkpoint (step {} of {})",
                r.steps, r.total_steps
            ));
        }
        // A hand-edited checkpoint is checked like any input: its grid, its interval, its time
        // and its attitude (the run resumes from them).
        if c.settings.checkpoint.as_ref().is_some_and(|(_, every)| *every == 0) {
            return Err(format!(
                "{shown}: inconsistent checkpoint (a checkpoint interval of 0 steps)"
            ));
        }
        let grid = liemid::step_count(r.t0, r.t_end, r.h).ok();
        let t = r.state.t;
        if grid != Some(r.total_steps) || !(t.is_finite() && t >= r.t0 && t <= r.t_end) {
            return Err(format!(
                "{shown}: inconsistent checkpoint (t = {} on the grid from {} to {} by {}: {} steps recorded)",
                Num(t),
                Num(r.t0),
                Num(r.t_end),
                Num(r.h),
                r.total_steps
            ));
        }
        let rotation = liemid::Mat3::from_row_major(r.state.rotation);
        let valid = rotation.is_finite()
            && liemid::so3::orthogonality_defect(&rotation) < 1e-6
            && rotation.determinant() > 0.0
            && r.state.pi.iter().all(|x| x.is_finite());
        if !valid {
            return Err(format!(
                "{shown}: inconsistent checkpoint (its attitude is not a rotation or its state not finite)"
            ));
        }
        Ok(c)
    }
}
