//! `--view FILE.html`: one self-contained page that animates a run in 3-D (three.js,
//! vendored in `vendor/three/` and embedded at build time), with play/pause, a time slider,
//! a speed control, orbit and zoom with the mouse, and the energy error along the run in a
//! side panel that follows the slider.
//!
//! A domain describes what it draws once ([`Scene`]) and offers a frame of `f32` numbers at
//! every sample ([`ViewPage::push_frame`]); the page keeps a bounded number of them (a byte
//! budget, [`DEFAULT_BUDGET`]): when they would exceed it, every other frame is dropped and
//! the stride doubles, so memory stays bounded whatever the run's length, and the last frame
//! offered is always shown. The page states how many frames it holds of how many steps.
//! Numbers go into the page as base64 of little-endian `f32`, never as JSON numbers.
//!
//! ```no_run
//! use liemid_app::shared::view::{Scene, ViewPage};
//! let mut page = ViewPage::new(Scene::RigidBody { half_extents: [1.0, 0.6, 0.3] }, "a top");
//! for k in 0..100u32 {
//!     let t = k as f64 * 0.01;
//!     // Row-major rotation, then the spatial angular momentum.
//!     page.push_frame(t, &[1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 1.]);
//!     page.energy_error(t, 1e-12 * k as f64);
//! }
//! page.write(std::path::Path::new("top.html"), 100).unwrap();
//! ```

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::json;

use super::output::partial_path;

/// Bytes of frame data a page holds at most (before base64), unless [`MIN_FRAMES`] frames
/// of the scene take more.
pub const DEFAULT_BUDGET: usize = 3_000_000;

/// Frames a page holds at least, whatever their size (a 10⁵-body fluid takes 2.8 MB a
/// frame).
pub const MIN_FRAMES: usize = 6;

/// Bodies a page draws at most: above it, every k-th body is drawn (stated in the title),
/// so that a software-rendered browser still animates a 10⁵-body fluid.
pub const MAX_DRAWN_BODIES: usize = 20_000;

/// The stride of the bodies drawn out of `count`: every body up to [`MAX_DRAWN_BODIES`].
#[must_use]
pub fn body_stride(count: usize) -> usize {
    count.div_ceil(MAX_DRAWN_BODIES).max(1)
}

/// Energy-error samples a page holds at most (subsampled like the frames).
pub const MAX_ENERGY_POINTS: usize = 20_000;

const THREE_CORE: &str = include_str!("../../vendor/three/three.core.min.js");
const THREE_MODULE: &str = include_str!("../../vendor/three/three.module.min.js");
const ORBIT_CONTROLS: &str = include_str!("../../vendor/three/OrbitControls.js");
const THREE_LICENSE: &str = include_str!("../../vendor/three/LICENSE");
const VIEWER_JS: &str = include_str!("../../assets/viewer.js");
const VIEWER_CSS: &str = include_str!("../../assets/viewer.css");

/// The vendored three.js version.
pub const THREE_VERSION: &str = "0.180.0";

/// A joint of an articulated system, drawn as a line between its two anchor points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    /// The parent body, `None` for the ground (the anchor is then in world coordinates).
    pub parent: Option<usize>,
    /// The child body.
    pub child: usize,
    /// The anchor in the parent's frame (or the world's).
    pub parent_anchor: [f32; 3],
    /// The anchor in the child's frame.
    pub child_anchor: [f32; 3],
}

/// A shape of an articulated system as the model file draws it (MJCF geom, URDF visual),
/// in MuJoCo's conventions (capsules and cylinders along z, a plane's normal z).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewShape {
    /// The body it moves with, `None` for the world.
    pub body: Option<usize>,
    /// `plane`, `sphere`, `capsule`, `cylinder`, `box`, `ellipsoid` or `mesh`.
    pub kind: String,
    /// Plane: half-extents (0: unbounded) and 0; sphere: radius; capsule and cylinder: radius
    /// and half-length; box: half-edges; ellipsoid: semi-axes; mesh: the scale of the
    /// mesh's coordinates.
    pub size: [f32; 3],
    /// A mesh's index in the scene's meshes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<usize>,
    /// Its origin in the body's centre-of-mass frame (or the world).
    pub position: [f32; 3],
    /// Its attitude in the body's frame (or the world), `w, x, y, z`.
    pub quaternion: [f32; 4],
    /// Colour and opacity.
    pub rgba: [f32; 4],
}

/// A triangle mesh a page draws (in the page's `data-meshes` array, not its JSON).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ViewMesh {
    /// The vertices, three numbers each.
    pub vertices: Vec<f32>,
    /// The triangles, three vertex indices each.
    pub indices: Vec<u32>,
}

impl ViewMesh {
    /// Bytes the mesh takes in a page before base64 (four per number).
    #[must_use]
    pub fn bytes(&self) -> usize {
        4 * (self.vertices.len() + self.indices.len())
    }
}

/// What a page draws, and the layout of one frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Scene {
    /// One rigid body about a fixed point: a box with its principal axes and the angular
    /// momentum vector. Frame: the rotation (9, row-major), then the spatial angular
    /// momentum (3).
    RigidBody {
        /// Half the box's edges along the body axes.
        half_extents: [f32; 3],
    },
    /// Many bodies, each an arrow along `axis` (body frame), in a periodic box when
    /// `box_length` is given. Frame per body: position (3), orientation quaternion
    /// `w, x, y, z` (4).
    Bodies {
        /// Number of bodies.
        count: usize,
        /// The edge of the cubic periodic box, if any.
        box_length: Option<f32>,
        /// The arrow's direction in the body frame.
        axis: [f32; 3],
        /// The arrow's length.
        length: f32,
    },
    /// A beam structure: its deformed centre line and the section frames at its nodes.
    /// Frame per node: position (3), quaternion of the section frame `w, x, y, z` (4).
    Beam {
        /// Number of nodes.
        nodes: usize,
        /// The elements' end nodes.
        elements: Vec<[u32; 2]>,
    },
    /// A spin lattice: an arrow per site coloured by S_z. Frame per site: the spin (3).
    Spins {
        /// The sites' positions.
        sites: Vec<[f32; 3]>,
    },
    /// Articulated bodies: a box per body with its pose and a line per joint. Frame per
    /// body: position (3), quaternion `w, x, y, z` (4).
    Articulated {
        /// Half the edges of each body's box.
        half_extents: Vec<[f32; 3]>,
        /// The joints.
        joints: Vec<Joint>,
        /// The shapes the model file draws (MuJoCo's default groups 0-2); the boxes of
        /// inertia are then hidden unless asked for.
        #[serde(default)]
        shapes: Vec<ViewShape>,
        /// The meshes the shapes draw (in the page as numbers, not in its JSON).
        #[serde(default, skip_serializing)]
        meshes: Vec<ViewMesh>,
        /// Contacts a frame holds after the bodies (0 for a model without contacts), each
        /// its point and the force on its first body, `x, y, z, f_x, f_y, f_z`; the
        /// touching ones first, the rest NaN.
        #[serde(default)]
        contact_slots: usize,
    },
}

/// Contacts an articulated page draws at most per frame (the first ones a step gives).
pub const MAX_DRAWN_CONTACTS: usize = 64;

impl Scene {
    /// Numbers in one frame.
    pub fn floats_per_frame(&self) -> usize {
        match self {
            Scene::RigidBody { .. } => 12,
            Scene::Bodies { count, .. } => 7 * count,
            Scene::Beam { nodes, .. } => 7 * nodes,
            Scene::Spins { sites } => 3 * sites.len(),
            Scene::Articulated {
                half_extents,
                contact_slots,
                ..
            } => 7 * half_extents.len() + 6 * contact_slots,
        }
    }

    /// The contact slots of a frame ([`Scene::Articulated`]'s; 0 for the others).
    pub fn contact_slots(&self) -> usize {
        match self {
            Scene::Articulated { contact_slots, .. } => *contact_slots,
            _ => 0,
        }
    }

    /// A one-line description of what the page draws.
    fn caption(&self) -> String {
        let main = match self {
            Scene::RigidBody { .. } => {
                "the body as a box with its principal axes (red, green, blue) and the angular momentum \
                 (yellow)"
                    .into()
            }
            Scene::Bodies { count, box_length, .. } => format!(
                "{count} bodies as arrows{}",
                box_length.map_or(String::new(), |l| format!(" in their periodic box of edge {l}"))
            ),
            Scene::Beam { nodes, elements } => format!(
                "the deformed centre line ({} elements) and the section frames at its {nodes} nodes",
                elements.len()
            ),
            Scene::Spins { sites } => format!("{} spins as arrows coloured by S_z (blue -1, red +1)", sites.len()),
            Scene::Articulated {
                half_extents,
                joints,
                shapes,
                ..
            } if shapes.is_empty() => format!(
                "{} bodies as boxes and {} joints as lines",
                half_extents.len(),
                joints.len()
            ),
            Scene::Articulated {
                half_extents, shapes, ..
            } => format!(
                "{} bodies drawn with the model's {} shapes (the boxes of inertia and the joints on request)",
                half_extents.len(),
                shapes.len()
            ),
        };
        match self.contact_slots() {
            0 => main,
            slots => {
                format!("{main}; the touching contacts (up to {slots}) as red points with their forces as red lines")
            }
        }
    }
}

/// A page being filled while a run goes on.
pub struct ViewPage {
    scene: Scene,
    title: String,
    per_frame: usize,
    max_frames: usize,
    budget: usize,
    frames: Vec<f32>,
    times: Vec<f32>,
    stride: u64,
    offered: u64,
    last: Option<(f32, Vec<f32>)>,
    energy: Vec<[f32; 2]>,
    energy_stride: u64,
    energy_offered: u64,
    energy_label: String,
}

impl ViewPage {
    /// A page drawing `scene`, titled `title`, with the default byte budget.
    pub fn new(scene: Scene, title: &str) -> Self {
        Self::with_budget(scene, title, DEFAULT_BUDGET)
    }

    /// A page that keeps at most `budget` bytes of frames (at least [`MIN_FRAMES`] frames).
    pub fn with_budget(scene: Scene, title: &str, budget: usize) -> Self {
        let per_frame = scene.floats_per_frame();
        let max_frames = (budget / (4 * per_frame.max(1))).max(MIN_FRAMES);
        ViewPage {
            scene,
            title: title.to_string(),
            per_frame,
            max_frames,
            budget,
            frames: Vec::new(),
            times: Vec::new(),
            stride: 1,
            offered: 0,
            last: None,
            energy: Vec::new(),
            energy_stride: 1,
            energy_offered: 0,
            energy_label: "relative energy error".into(),
        }
    }

    /// Name the quantity of [`ViewPage::energy_error`] (e.g. "relative energy change").
    pub fn set_energy_label(&mut self, label: &str) {
        self.energy_label = label.to_string();
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Frames kept so far (the last one offered is added when the page is written).
    pub fn frames(&self) -> usize {
        self.times.len()
    }

    /// Whether the next frame offered will be kept (a caller may skip building it
    /// otherwise, but must still call [`ViewPage::push_frame`] for the last one).
    pub fn wants_frame(&self) -> bool {
        self.offered % self.stride == 0
    }

    /// Offer the frame at time `t` (as many numbers as [`Scene::floats_per_frame`]; a frame
    /// of another length is ignored).
    pub fn push_frame(&mut self, t: f64, frame: &[f32]) {
        if frame.len() != self.per_frame {
            return;
        }
        let keep = self.offered % self.stride == 0;
        self.offered += 1;
        if !keep {
            match &mut self.last {
                Some((lt, buf)) => {
                    *lt = t as f32;
                    buf.clear();
                    buf.extend_from_slice(frame);
                }
                None => self.last = Some((t as f32, frame.to_vec())),
            }
            return;
        }
        self.last = None;
        self.frames.extend_from_slice(frame);
        self.times.push(t as f32);
        if self.times.len() > self.max_frames {
            // Keep the frames at even positions: those at offers that are multiples of the
            // doubled stride.
            let n = self.per_frame;
            let kept = self.times.len().div_ceil(2);
            for j in 0..kept {
                self.times[j] = self.times[2 * j];
                self.frames.copy_within(2 * j * n..(2 * j + 1) * n, j * n);
            }
            self.times.truncate(kept);
            self.frames.truncate(kept * n);
            self.stride *= 2;
        }
    }

    /// Record the energy error `e` at time `t`.
    pub fn energy_error(&mut self, t: f64, e: f64) {
        let keep = self.energy_offered % self.energy_stride == 0;
        self.energy_offered += 1;
        if !keep {
            return;
        }
        self.energy.push([t as f32, e as f32]);
        if self.energy.len() > MAX_ENERGY_POINTS {
            let kept = self.energy.len().div_ceil(2);
            for j in 0..kept {
                self.energy[j] = self.energy[2 * j];
            }
            self.energy.truncate(kept);
            self.energy_stride *= 2;
        }
    }

    /// The numbers the scene needs once (sites, elements), as `f32`.
    fn static_data(&self) -> Vec<f32> {
        match &self.scene {
            Scene::Spins { sites } => sites.iter().flatten().copied().collect(),
            Scene::Beam { elements, .. } => elements.iter().flatten().map(|&i| i as f32).collect(),
            Scene::Articulated { half_extents, .. } => half_extents.iter().flatten().copied().collect(),
            _ => Vec::new(),
        }
    }

    /// Write the page to `path` (through `PATH.partial` and a rename; a path checked by
    /// `OutputPlan::add`) for a run of `total_steps` steps; returns the frames written.
    pub fn write(&self, path: &Path, total_steps: u64) -> Result<usize, String> {
        let partial = partial_path(path);
        let result = File::create(&partial).and_then(|f| {
            let mut w = BufWriter::with_capacity(1 << 16, f);
            let frames = self.write_to(&mut w, total_steps)?;
            let f = w.into_inner().map_err(|e| e.into_error())?;
            f.sync_all()?;
            Ok(frames)
        });
        match result.and_then(|frames| std::fs::rename(&partial, path).map(|()| frames)) {
            Ok(frames) => Ok(frames),
            Err(e) => {
                let _ = std::fs::remove_file(&partial);
                Err(format!("--view {}: cannot write: {e}", path.display()))
            }
        }
    }

    /// The page as a string (for a notebook).
    pub fn html(&self, total_steps: u64) -> String {
        let mut bytes = Vec::new();
        self.write_to(&mut bytes, total_steps).expect("writing to a Vec");
        String::from_utf8(bytes).expect("the page is UTF-8")
    }

    /// Stream the page into `w`; returns the frames written.
    pub fn write_to(&self, w: &mut impl Write, total_steps: u64) -> io::Result<usize> {
        let last = self.last.as_ref().filter(|_| self.per_frame > 0);
        let frames = self.times.len() + usize::from(last.is_some());
        let mut meta = serde_json::to_value(&self.scene).unwrap_or_else(|_| json!({}));
        if let Some(m) = meta.as_object_mut() {
            // Large lists go in the static array, not in JSON.
            m.remove("sites");
            m.remove("elements");
            if let Scene::Articulated {
                half_extents, meshes, ..
            } = &self.scene
            {
                m.insert("half_extents".into(), json!(half_extents.len()));
                // Each mesh's vertex and triangle counts; the numbers are in `data-meshes`.
                let counts: Vec<[usize; 2]> = meshes
                    .iter()
                    .map(|k| [k.vertices.len() / 3, k.indices.len() / 3])
                    .collect();
                m.insert("meshes".into(), json!(counts));
            }
        }
        let budget_mb = self.budget as f64 / 1e6;
        let note = format!(
            "{frames} frames of {total_steps} steps (frames subsampled to a budget of {budget_mb:.1} MB, at least \
             {MIN_FRAMES} frames; one frame every {} samples)",
            self.stride
        );
        let meta = json!({
            "scene": meta,
            "title": self.title,
            "caption": self.scene.caption(),
            "frames": frames,
            "steps": total_steps,
            "per_frame": self.per_frame,
            "energy_points": self.energy.len(),
            "energy_label": self.energy_label,
            "note": note,
            "three": THREE_VERSION,
        });
        let title = escape_html(&self.title);
        write!(
            w,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>{title} - liemid view</title>\n\
             <!-- Made by liemid {}. Self-contained: three.js {THREE_VERSION} (MIT licence below) and the data are \
             inlined; the page loads nothing. -->\n<style>{VIEWER_CSS}</style></head>\n<body>\n",
            env!("CARGO_PKG_VERSION")
        )?;
        write!(
            w,
            "<div id=\"app\"><div id=\"stage\"></div><aside id=\"panel\"><h1>{title}</h1>\
             <p id=\"caption\"></p><p id=\"note\">{}</p><canvas id=\"energy\" width=\"320\" height=\"220\"></canvas>\
             <p id=\"readout\"></p><p id=\"fps\"></p></aside></div>\n<div id=\"controls\">\
             <button id=\"play\" type=\"button\">pause</button><input id=\"slider\" type=\"range\" min=\"0\" \
             max=\"{}\" value=\"0\" step=\"1\"><span id=\"time\"></span><label>speed <select id=\"speed\">\
             <option>0.25</option><option>0.5</option><option selected>1</option><option>2</option>\
             <option>4</option></select></label></div>\n",
            escape_html(&note),
            frames.saturating_sub(1)
        )?;
        let meta_text = meta.to_string().replace("</", "<\\/");
        writeln!(w, "<script type=\"application/json\" id=\"meta\">{meta_text}</script>")?;
        write_floats(w, "data-times", self.times.iter().copied().chain(last.map(|l| l.0)))?;
        write_floats(
            w,
            "data-frames",
            self.frames
                .iter()
                .copied()
                .chain(last.into_iter().flat_map(|l| l.1.iter().copied())),
        )?;
        write_floats(w, "data-energy", self.energy.iter().flatten().copied())?;
        write_floats(w, "data-static", self.static_data().into_iter())?;
        // Each mesh's vertices, then its indices (as f32: exact below 2^24, far above the
        // vertices of a mesh the page keeps).
        let meshes: &[ViewMesh] = match &self.scene {
            Scene::Articulated { meshes, .. } => meshes,
            _ => &[],
        };
        write_floats(
            w,
            "data-meshes",
            meshes
                .iter()
                .flat_map(|k| k.vertices.iter().copied().chain(k.indices.iter().map(|&i| i as f32))),
        )?;
        for (id, text) in [
            ("three-core", THREE_CORE),
            ("three-module", THREE_MODULE),
            ("three-orbit", ORBIT_CONTROLS),
        ] {
            write!(w, "<script type=\"text/plain\" id=\"{id}\">")?;
            w.write_all(script_safe(text).as_bytes())?;
            w.write_all(b"</script>\n")?;
        }
        write!(w, "<script>\n{}\n</script>\n", script_safe(VIEWER_JS))?;
        write!(
            w,
            "<!-- three.js licence:\n{}\n-->\n</body></html>\n",
            THREE_LICENSE.replace("--", "- -")
        )?;
        Ok(frames)
    }
}

/// `text` with every `</script` broken so that it cannot close the element it sits in.
fn script_safe(text: &str) -> std::borrow::Cow<'_, str> {
    if text.to_ascii_lowercase().contains("</script") {
        std::borrow::Cow::Owned(text.replace("</script", "<\\/script").replace("</SCRIPT", "<\\/SCRIPT"))
    } else {
        std::borrow::Cow::Borrowed(text)
    }
}

fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const BASE64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Base64 of `bytes` (a multiple of 3 except at the end) appended to `out`.
fn base64_into(bytes: &[u8], out: &mut Vec<u8>) {
    for c in bytes.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        out.push(BASE64[(n >> 18) as usize & 63]);
        out.push(BASE64[(n >> 12) as usize & 63]);
        out.push(if c.len() > 1 {
            BASE64[(n >> 6) as usize & 63]
        } else {
            b'='
        });
        out.push(if c.len() > 2 { BASE64[n as usize & 63] } else { b'=' });
    }
}

/// A `<script>` element holding `values` as base64 of little-endian `f32`, streamed in
/// chunks (never the whole array as text in memory).
fn write_floats(w: &mut impl Write, id: &str, values: impl Iterator<Item = f32>) -> io::Result<()> {
    write!(w, "<script type=\"application/octet-stream\" id=\"{id}\">")?;
    // 3 floats = 12 bytes = 16 base64 characters: chunks of 3·4096 floats end on a boundary.
    let mut raw: Vec<u8> = Vec::with_capacity(12 * 4096);
    let mut text: Vec<u8> = Vec::with_capacity(16 * 4096);
    for v in values {
        raw.extend_from_slice(&v.to_le_bytes());
        if raw.len() == 12 * 4096 {
            base64_into(&raw, &mut text);
            w.write_all(&text)?;
            raw.clear();
            text.clear();
        }
    }
    base64_into(&raw, &mut text);
    w.write_all(&text)?;
    w.write_all(b"</script>\n")
}

/// The quaternion `w, x, y, z` of a rotation matrix given by rows (Shepperd's method).
pub fn quaternion(r: &[[f64; 3]; 3]) -> [f32; 4] {
    let t = r[0][0] + r[1][1] + r[2][2];
    let q = if t > 0.0 {
        let s = 2.0 * (1.0 + t).sqrt();
        [
            0.25 * s,
            (r[2][1] - r[1][2]) / s,
            (r[0][2] - r[2][0]) / s,
            (r[1][0] - r[0][1]) / s,
        ]
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = 2.0 * (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt();
        [
            (r[2][1] - r[1][2]) / s,
            0.25 * s,
            (r[0][1] + r[1][0]) / s,
            (r[0][2] + r[2][0]) / s,
        ]
    } else if r[1][1] > r[2][2] {
        let s = 2.0 * (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt();
        [
            (r[0][2] - r[2][0]) / s,
            (r[0][1] + r[1][0]) / s,
            0.25 * s,
            (r[1][2] + r[2][1]) / s,
        ]
    } else {
        let s = 2.0 * (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt();
        [
            (r[1][0] - r[0][1]) / s,
            (r[0][2] + r[2][0]) / s,
            (r[1][2] + r[2][1]) / s,
            0.25 * s,
        ]
    };
    q.map(|v| v as f32)
}

/// The positions of a lattice's sites: `x + nx (y + ny z)` on a grid of unit spacing for
/// a chain, square or cubic lattice, a circle for a graph.
pub fn lattice_sites(lattice: &liemid::spin::Lattice) -> Vec<[f32; 3]> {
    let n = lattice.sites();
    let [nx, ny, _] = lattice.size().map(|s| s.max(1));
    if lattice.kind() == liemid::spin::LatticeKind::Graph {
        let r = (n as f32 / std::f32::consts::TAU).max(1.0);
        return (0..n)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / n as f32;
                [r * a.cos(), r * a.sin(), 0.0]
            })
            .collect();
    }
    (0..n)
        .map(|i| [(i % nx) as f32, ((i / nx) % ny) as f32, (i / (nx * ny)) as f32])
        .collect()
}

/// The line a command prints for a page written to `path`.
pub fn report(path: &Path, frames: usize, steps: u64) -> String {
    format!("view: {} ({frames} frames of {steps} steps)", path.display())
}

/// Half the edges of a uniform box with the principal moments `moments` (any mass), the
/// largest scaled to 1.
pub fn box_of_inertia(moments: [f64; 3]) -> [f32; 3] {
    let [a, b, c] = moments;
    let h = [b + c - a, a + c - b, a + b - c].map(|v| v.max(0.01 * (a + b + c)).sqrt());
    let m = h.iter().copied().fold(0.0, f64::max).max(1e-300);
    h.map(|v| (v / m) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_ensembles_draw_every_kth_body() {
        assert_eq!(body_stride(1), 1);
        assert_eq!(body_stride(MAX_DRAWN_BODIES), 1);
        assert_eq!(body_stride(MAX_DRAWN_BODIES + 1), 2);
        assert_eq!(body_stride(100_000), 5);
        assert!(100_000usize.div_ceil(body_stride(100_000)) <= MAX_DRAWN_BODIES);
    }

    #[test]
    fn base64_matches_the_standard() {
        let mut out = Vec::new();
        base64_into(b"Man", &mut out);
        base64_into(b"Ma", &mut out);
        base64_into(b"M", &mut out);
        assert_eq!(out, b"TWFuTWE=TQ==");
    }

    #[test]
    fn frames_stay_within_the_budget_and_the_last_is_kept() {
        let scene = Scene::Spins {
            sites: vec![[0.0; 3]; 100],
        };
        let mut page = ViewPage::with_budget(scene, "x", 4 * 300 * 50);
        for k in 0..1000 {
            page.push_frame(k as f64, &[k as f32; 300]);
        }
        assert!(page.frames() <= 50 && page.frames() > 25, "{}", page.frames());
        let html = page.html(1000);
        assert!(html.contains(&format!("{} frames of 1000 steps", page.frames() + 1)));
        assert!(!html.contains("src=\"http") && !html.contains("href=\"http"));
    }

    #[test]
    fn quaternion_of_a_quarter_turn() {
        let q = quaternion(&[[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
        let h = std::f32::consts::FRAC_1_SQRT_2;
        assert!((q[0] - h).abs() < 1e-6 && (q[3] - h).abs() < 1e-6 && q[1] == 0.0 && q[2] == 0.0);
    }

    #[test]
    fn the_assets_cannot_close_their_script_elements() {
        for text in [THREE_CORE, THREE_MODULE, ORBIT_CONTROLS, VIEWER_JS] {
            assert!(!script_safe(text).to_ascii_lowercase().contains("</script"));
        }
        assert!(THREE_MODULE.contains("\"./three.core.min.js\""));
    }
}
