//! Shared parts of the model-file loaders: reading and bounding the XML, located errors,
//! attribute parsing, rotations, mass properties, and the tree builder that turns the
//! loaders' raw bodies into a [`Model`] (lumping welded massless bodies into their parents).

use std::collections::HashSet;
use std::io::Read;
use std::marker::PhantomData;
use std::path::Path;

use roxmltree::{Document, Node, ParsingOptions};

use super::model::{Body, Joint, JointKind, Link, Model};
use crate::error::{Error, Result};
use crate::inertia::Inertia;
use crate::linalg::{Mat3, Vec3};
use crate::so3::Quaternion;

/// Largest model file accepted (bytes).
pub const MAX_FILE_BYTES: u64 = 64 << 20;
/// Deepest element nesting accepted (the document element is level 1).
pub const MAX_DEPTH: usize = 200;
/// Most XML nodes (elements, text, comments) accepted in one file.
pub const MAX_NODES: u32 = 2_000_000;

/// A loaded model with what the file held that the model does not represent.
#[derive(Clone, Debug, PartialEq)]
pub struct Loaded {
    /// The model.
    pub model: Model,
    /// Every file read for the model: the main file and each file it `<include>`s, in the
    /// order read (empty for text parsed from memory). Front ends treat them all as inputs
    /// that no output may replace.
    pub files: Vec<std::path::PathBuf>,
    /// Each kind of content that was read but not used (`"actuator"`, `"tendon"`,
    /// `"geom contacts"`, `"joint armature"`, …), once each, in the order first met.
    pub ignored: Vec<String>,
    /// Bodies (MJCF) or links (URDF) merged into another body because they are welded to it
    /// (URDF fixed joints; massless MJCF bodies without a joint): `(merged, into)`, where
    /// `into` is a body of the model or `"world"`. Readouts of `merged` use `into`.
    pub merged: Vec<(String, String)>,
    /// The shapes the file draws (MJCF geoms, URDF visuals), for viewers.
    pub shapes: Vec<super::shapes::Shape>,
}

/// The kinds of content ignored, each once.
#[derive(Default)]
pub(crate) struct Ignored {
    list: Vec<String>,
    seen: HashSet<String>,
}

impl Ignored {
    /// Records `what` unless already recorded.
    pub(crate) fn note(&mut self, what: &str) {
        if self.seen.insert(what.to_string()) {
            self.list.push(what.to_string());
        }
    }

    /// The list in the order first met.
    pub(crate) fn into_vec(self) -> Vec<String> {
        self.list
    }
}

/// Reads a model file, refusing what is not a regular file (a FIFO would block `open`
/// forever, a device would never end) and files over [`MAX_FILE_BYTES`] before reading
/// them whole.
pub(crate) fn read_bounded(path: &Path) -> Result<String> {
    let name = path.display().to_string();
    let bytes = read_bounded_bytes(path, MAX_FILE_BYTES, "a model file")?;
    String::from_utf8(bytes).map_err(|e| file_error(&name, format!("not UTF-8 text: {e}")))
}

/// The bytes of the regular file `path`, at most `max_bytes` of them: every file a model
/// reads (the model, its includes, its meshes) comes through here; `kind` names the kind of
/// file in the error ("a model file").
pub(crate) fn read_bounded_bytes(path: &Path, max_bytes: u64, kind: &str) -> Result<Vec<u8>> {
    let name = path.display().to_string();
    let io = |e: std::io::Error| file_error(&name, format!("cannot read the file: {e}"));
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(file_error(
            &name,
            "not a regular file (a directory, FIFO or device is not read as a model)".into(),
        ));
    }
    let too_large = || {
        file_error(
            &name,
            format!("larger than the {} MiB accepted for {kind}", max_bytes >> 20),
        )
    };
    if meta.len() > max_bytes {
        return Err(too_large());
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(max_bytes + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large());
    }
    Ok(bytes)
}

fn too_large(file: &str) -> Error {
    file_error(
        file,
        format!("larger than the {} MiB accepted for a model file", MAX_FILE_BYTES >> 20),
    )
}

/// An error about the whole file (line 0).
pub(crate) fn file_error(file: &str, message: String) -> Error {
    Error::ModelFile {
        file: file.to_string(),
        line: 0,
        element: String::new(),
        message,
    }
}

/// The 1-based line of byte `pos` of `text`.
/// The byte offsets where the lines of `text` start (the first is 0).
pub(crate) fn line_starts(text: &str) -> Vec<usize> {
    core::iter::once(0)
        .chain(
            text.bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i + 1),
        )
        .collect()
}

/// The 1-based line of byte `pos` given the line starts of its text.
pub(crate) fn line_at(lines: &[usize], pos: usize) -> u32 {
    lines.partition_point(|&start| start <= pos) as u32
}

pub(crate) fn line_of(text: &str, pos: usize) -> u32 {
    let upto = &text.as_bytes()[..pos.min(text.len())];
    1 + upto.iter().filter(|&&b| b == b'\n').count() as u32
}

/// Parses `text` as XML within the bounds: size, no DTD, node count and nesting depth. The
/// parser (roxmltree) nests iteratively, so a deep document cannot overflow the stack; the
/// depth is measured by an iterative traversal.
pub(crate) fn parse_document<'i>(text: &'i str, file: &str, sources: &Sources) -> Result<Document<'i>> {
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(too_large(file));
    }
    if let Some(pos) = text.find("<!DOCTYPE").or_else(|| text.find("<!ENTITY")) {
        return Err(Error::ModelFile {
            file: file.to_string(),
            line: line_of(text, pos),
            element: "!DOCTYPE".into(),
            message: "document type declarations (and their entities) are refused in model files".into(),
        });
    }
    let options = ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_NODES,
        ..ParsingOptions::default()
    };
    let doc = Document::parse_with_options(text, options).map_err(|e| {
        let line = e.pos().row;
        let message = match e {
            roxmltree::Error::NodesLimitReached => format!("more than {MAX_NODES} XML nodes"),
            other => format!("not well-formed XML: {other}"),
        };
        // In a text assembled from several files, the row is the assembled text's.
        let start = text
            .split_inclusive('\n')
            .take(line.saturating_sub(1) as usize)
            .map(str::len)
            .sum();
        let (file, line) = sources.locate(&line_starts(text), start, file);
        Error::ModelFile {
            file,
            line,
            element: "xml".into(),
            message,
        }
    })?;
    // Depth of each node from its parent's, in document order (parents come first).
    let mut depth = vec![0usize; doc.descendants().count()];
    for n in doc.descendants() {
        let d = n.parent().map_or(0, |p| depth[p.id().get_usize()]) + usize::from(n.is_element());
        depth[n.id().get_usize()] = d;
        if d > MAX_DEPTH {
            let lines = line_starts(text);
            return Err(Ctx::new(file, sources, &lines)
                .err(n, format!("elements nested deeper than {MAX_DEPTH} levels are refused")));
        }
    }
    Ok(doc)
}

/// The file name and document, for located errors and attribute parsing.
#[derive(Clone, Copy)]
pub(crate) struct Ctx<'a, 'i> {
    /// The file's name for messages.
    pub file: &'a str,
    /// Where the document's text came from when it was assembled from several files
    /// (MJCF `<include>`); [`Sources::NONE`] for one file.
    pub sources: &'a Sources,
    /// The byte offset of each line's start in the document's text ([`line_starts`]): a
    /// line is a binary search, so locating every element of a file costs `O(n log n)`,
    /// not `O(n²)`.
    lines: &'a [usize],
    _doc: PhantomData<&'a Document<'i>>,
}

/// Where each piece of a text assembled from several files came from (MJCF `<include>`):
/// the byte where the piece starts in the assembled text, its file and its first line there.
#[derive(Debug, Default)]
pub(crate) struct Sources {
    pieces: Vec<(usize, String, u32)>,
}

impl Sources {
    /// A text read from one file.
    pub(crate) const NONE: &'static Sources = &Sources { pieces: Vec::new() };

    /// Records that the assembled text from byte `start` on is `file` from line `line` on.
    pub(crate) fn push(&mut self, start: usize, file: &str, line: u32) {
        self.pieces.push((start, file.to_string(), line));
    }

    /// The file and 1-based line of byte `pos` of the assembled `text` (`file`'s own line
    /// when the text is one file's).
    pub(crate) fn locate(&self, lines: &[usize], pos: usize, file: &str) -> (String, u32) {
        let line = line_at(lines, pos);
        match self.pieces.partition_point(|p| p.0 <= pos).checked_sub(1) {
            Some(i) => {
                let (start, source, first) = &self.pieces[i];
                (source.clone(), first + line - line_at(lines, *start))
            }
            None => (file.to_string(), line),
        }
    }
}

pub(crate) use crate::error::abbreviate;

/// `tag name="…"` (or just `tag`) for messages.
pub(crate) fn describe(node: Node) -> String {
    let tag = node.tag_name().name();
    match node.attribute("name") {
        Some(name) => format!("{tag} name=\"{name}\""),
        None => tag.to_string(),
    }
}

impl<'a, 'i> Ctx<'a, 'i> {
    /// The context of a document read from `file` (assembled from `sources`), whose text
    /// has the line starts `lines`.
    pub(crate) fn new(file: &'a str, sources: &'a Sources, lines: &'a [usize]) -> Self {
        Ctx {
            file,
            sources,
            lines,
            _doc: PhantomData,
        }
    }

    /// The file and 1-based line where `node` starts.
    pub(crate) fn locate(&self, node: Node) -> (String, u32) {
        self.sources.locate(self.lines, node.range().start, self.file)
    }

    /// The 1-based line where `node` starts, in its own file.
    pub(crate) fn line(&self, node: Node) -> u32 {
        self.locate(node).1
    }

    /// An error located at `node`.
    pub(crate) fn err(&self, node: Node, message: impl Into<String>) -> Error {
        let (file, line) = self.locate(node);
        Error::ModelFile {
            file,
            line,
            element: describe(node),
            message: message.into(),
        }
    }

    /// Parses the whitespace-separated finite numbers of attribute `attr` (text `value`) of
    /// `node`, between `min` and `max` of them.
    pub(crate) fn floats(&self, node: Node, attr: &str, value: &str, min: usize, max: usize) -> Result<Vec<f64>> {
        let mut out = Vec::new();
        let shown = abbreviate(value);
        for word in value.split_ascii_whitespace() {
            let v: f64 = word.parse().map_err(|_| {
                self.err(
                    node,
                    format!("attribute {attr}=\"{shown}\": `{}` is not a number", abbreviate(word)),
                )
            })?;
            if !v.is_finite() {
                return Err(self.err(node, format!("attribute {attr}=\"{shown}\": `{word}` is not finite")));
            }
            out.push(v);
            if out.len() > max {
                break;
            }
        }
        if out.len() < min || out.len() > max {
            let want = if min == max {
                format!("{min}")
            } else {
                format!("{min} to {max}")
            };
            let got = value.split_ascii_whitespace().count();
            return Err(self.err(
                node,
                format!("attribute {attr}=\"{shown}\" has {got} values, {want} expected"),
            ));
        }
        Ok(out)
    }

    /// Exactly `N` numbers from attribute `attr` of `node` itself, if present.
    pub(crate) fn array<const N: usize>(&self, node: Node, attr: &str) -> Result<Option<[f64; N]>> {
        match node.attribute(attr) {
            None => Ok(None),
            Some(v) => self.array_of::<N>(node, attr, v).map(Some),
        }
    }

    /// Exactly `N` numbers from the text `value` of attribute `attr`.
    pub(crate) fn array_of<const N: usize>(&self, node: Node, attr: &str, value: &str) -> Result<[f64; N]> {
        let v = self.floats(node, attr, value, N, N)?;
        let mut a = [0.0; N];
        a.copy_from_slice(&v);
        Ok(a)
    }

    /// A unit vector from three numbers; zero is refused.
    pub(crate) fn unit(&self, node: Node, attr: &str, v: [f64; 3]) -> Result<Vec3> {
        let v = Vec3::from_array(v);
        let n = v.norm();
        if n <= 1e-300 || !n.is_finite() {
            return Err(self.err(node, format!("attribute {attr}: a zero vector has no direction")));
        }
        Ok(v * (1.0 / n))
    }
}

/// The rotation of a quaternion `w x y z`, normalised; `None` for a zero quaternion.
pub(crate) fn quat_matrix(q: [f64; 4]) -> Option<Mat3> {
    let q = Quaternion::new(q[0], q[1], q[2], q[3]);
    let n = q.norm();
    (n > 1e-300 && n.is_finite()).then(|| q.normalized().to_matrix())
}

/// Rotation by `angle` about the unit `axis`.
pub(crate) fn axis_angle(axis: Vec3, angle: f64) -> Mat3 {
    crate::so3::exp(axis * angle)
}

/// Rotation by `angle` about coordinate axis `k` (0, 1, 2).
pub(crate) fn coordinate_rotation(k: usize, angle: f64) -> Mat3 {
    let mut e = [0.0; 3];
    e[k] = 1.0;
    axis_angle(Vec3::from_array(e), angle)
}

/// URDF roll-pitch-yaw (fixed axes): `Rz(yaw) Ry(pitch) Rx(roll)`.
pub(crate) fn rpy(r: [f64; 3]) -> Mat3 {
    coordinate_rotation(2, r[2]) * coordinate_rotation(1, r[1]) * coordinate_rotation(0, r[0])
}

/// The smallest rotation taking `e_z` to the unit vector `z` (MJCF `zaxis`, `fromto`).
pub(crate) fn rotation_to_z(z: Vec3) -> Mat3 {
    let ez = Vec3::new(0.0, 0.0, 1.0);
    let c = ez.dot(z);
    if c < -1.0 + 1e-14 {
        return coordinate_rotation(0, std::f64::consts::PI);
    }
    let v = ez.cross(z);
    quat_matrix([1.0 + c, v.x, v.y, v.z]).unwrap_or(Mat3::IDENTITY)
}

/// Checks an inertia tensor about the centre of mass as every body's tensor is checked
/// ([`Inertia::from_matrix`]: finite, symmetric, positive definite, principal moments
/// obeying the triangle inequality), with the reason as a message for the file's error.
pub(crate) fn check_inertia(i: &Mat3) -> std::result::Result<(), String> {
    if !i.is_finite() {
        return Err("the inertia is not finite".into());
    }
    match Inertia::from_matrix(i.m) {
        Ok(_) => Ok(()),
        Err(Error::InvalidInertia { reason }) => Err(format!("the inertia tensor: {reason}")),
        Err(e) => Err(e.to_string()),
    }
}

/// Mass, centre of mass and inertia about it, in some frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MassProps {
    /// Mass.
    pub mass: f64,
    /// Centre of mass.
    pub com: Vec3,
    /// Inertia about the centre of mass, in the frame's axes.
    pub inertia: Mat3,
}

impl MassProps {
    /// No mass.
    pub(crate) const ZERO: MassProps = MassProps {
        mass: 0.0,
        com: Vec3::ZERO,
        inertia: Mat3::ZERO,
    };

    /// The same mass seen from a frame in which this frame sits at `pos` with attitude `rot`.
    pub(crate) fn transformed(&self, pos: Vec3, rot: &Mat3) -> MassProps {
        MassProps {
            mass: self.mass,
            com: pos + rot * self.com,
            inertia: *rot * self.inertia * rot.transpose(),
        }
    }

    /// The union of two masses in the same frame (parallel-axis theorem).
    pub(crate) fn combine(&self, other: &MassProps) -> MassProps {
        let mass = self.mass + other.mass;
        if mass <= 0.0 {
            return MassProps::ZERO;
        }
        let com = (self.com * self.mass + other.com * other.mass) * (1.0 / mass);
        let shift = |p: &MassProps| {
            let d = p.com - com;
            (Mat3::IDENTITY * d.norm_squared() - Mat3::outer(d, d)) * p.mass
        };
        MassProps {
            mass,
            com,
            inertia: self.inertia + other.inertia + shift(self) + shift(other),
        }
    }
}

/// A joint kind before the tree is built (`Weld` for a body without a joint).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum RawKind {
    Weld,
    Free,
    Ball,
    Hinge(Vec3),
    Slide(Vec3),
    /// First and second axis (MJCF: two hinges of one body merged).
    Universal(Vec3, Vec3),
}

/// When a body is merged into its parent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Merge {
    /// Kept as a body.
    Never,
    /// Merged when it (with what was merged into it) has no mass (a weld).
    IfMassless,
    /// Always merged (a weld to a parent body: URDF fixed joints).
    Always,
}

/// A body as a loader reads it, posed relative to its parent.
#[derive(Clone, Debug)]
pub(crate) struct RawBody {
    pub name: String,
    /// Index of the parent in the raw list (before this body), `None` for the world.
    pub parent: Option<usize>,
    /// Frame origin in the parent frame.
    pub pos: Vec3,
    /// Attitude relative to the parent frame.
    pub rot: Mat3,
    /// Mass properties in the body frame.
    pub mass: MassProps,
    pub kind: RawKind,
    pub joint_name: Option<String>,
    /// The joint's point in the body frame.
    pub anchor: Vec3,
    pub range: Option<(f64, f64)>,
    pub stiffness: f64,
    pub spring_ref: f64,
    pub damping: f64,
    pub armature: f64,
    /// Dry friction and the summed actuator force clamp of the joint.
    pub frictionloss: f64,
    pub actuator_force_range: Option<(f64, f64)>,
    pub merge: Merge,
    /// The shapes drawn with the body, posed in its frame (`body` not yet set).
    pub shapes: Vec<super::shapes::Shape>,
    /// File, line and element description for errors.
    pub file: String,
    pub line: u32,
    pub element: String,
}

/// The result of [`build`]: bodies, joints, the merge record and the shapes.
pub(crate) struct Built {
    pub bodies: Vec<Body>,
    pub joints: Vec<Joint>,
    pub merged: Vec<(String, String)>,
    /// The bodies' shapes (those of merged bodies on the body they were merged into, or on
    /// the world).
    pub shapes: Vec<super::shapes::Shape>,
}

/// Builds bodies and tree joints from raw bodies listed parents before children: merges
/// what [`Merge`] asks (children first, by the parallel-axis theorem, re-posing the merged
/// body's children on its parent), refuses a remaining body without mass or with an
/// impossible inertia, and poses everything in the world.
pub(crate) fn build(mut raw: Vec<RawBody>) -> Result<Built> {
    let n = raw.len();
    let located = |b: &RawBody, message: String| Error::ModelFile {
        file: b.file.clone(),
        line: b.line,
        element: b.element.clone(),
        message,
    };
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, b) in raw.iter().enumerate() {
        if let Some(p) = b.parent {
            debug_assert!(p < i);
            children[p].push(i);
        }
    }
    let mut removed = vec![false; n];
    let mut into: Vec<Option<usize>> = vec![None; n];
    let mut world_shapes = Vec::new();
    for i in (0..n).rev() {
        let b = &raw[i];
        let merge = match b.merge {
            Merge::Never => false,
            Merge::IfMassless => b.mass.mass == 0.0,
            Merge::Always => b.parent.is_some() || b.mass.mass == 0.0,
        };
        if !merge {
            continue;
        }
        debug_assert_eq!(b.kind, RawKind::Weld);
        removed[i] = true;
        let (parent, pos, rot, mass) = (b.parent, b.pos, b.rot, b.mass);
        into[i] = parent;
        let shapes: Vec<_> = std::mem::take(&mut raw[i].shapes)
            .iter()
            .map(|s| s.moved(pos, &rot))
            .collect();
        if let Some(p) = parent {
            let moved = mass.transformed(pos, &rot);
            raw[p].mass = raw[p].mass.combine(&moved);
            raw[p].shapes.extend(shapes);
        } else {
            world_shapes.extend(shapes);
        }
        for c in std::mem::take(&mut children[i]) {
            let child = &mut raw[c];
            child.parent = parent;
            child.pos = pos + rot * child.pos;
            child.rot = rot * child.rot;
            if let Some(p) = parent {
                children[p].push(c);
            }
        }
    }
    let mut merged = Vec::new();
    let mut shapes = world_shapes;
    let mut index = vec![usize::MAX; n];
    let mut bodies = Vec::new();
    let mut joints = Vec::new();
    let mut names: HashSet<String> = raw.iter().filter_map(|b| b.joint_name.clone()).collect();
    for i in 0..n {
        if removed[i] {
            let mut target = into[i];
            while let Some(t) = target.filter(|&t| removed[t]) {
                target = into[t];
            }
            let name = target.map_or_else(|| "world".to_string(), |t| raw[t].name.clone());
            merged.push((raw[i].name.clone(), name));
            continue;
        }
        let b = &raw[i];
        if b.mass.mass <= 0.0 {
            let how = if b.kind == RawKind::Weld {
                "is welded to a moving parent"
            } else {
                "has a joint"
            };
            return Err(located(
                b,
                format!(
                    "body `{}` has no mass (no inertial and no geometry with mass) and {how}: a massless body \
                     cannot be integrated in maximal coordinates",
                    b.name
                ),
            ));
        }
        check_inertia(&b.mass.inertia).map_err(|m| located(b, format!("body `{}`: {m}", b.name)))?;
        let (parent, position, rotation) = match b.parent {
            None => (Link::World, b.pos, b.rot),
            Some(p) => {
                let pb: &Body = &bodies[index[p]];
                (
                    Link::Body(index[p]),
                    pb.position + pb.rotation * b.pos,
                    pb.rotation * b.rot,
                )
            }
        };
        index[i] = bodies.len();
        shapes.extend(b.shapes.iter().map(|s| super::shapes::Shape {
            body: Some(index[i]),
            ..s.clone()
        }));
        bodies.push(Body {
            name: b.name.clone(),
            mass: b.mass.mass,
            com: b.mass.com,
            inertia: b.mass.inertia,
            position,
            rotation,
        });
        let kind = match b.kind {
            RawKind::Weld => JointKind::Weld,
            RawKind::Free => JointKind::Free,
            RawKind::Ball => JointKind::Ball,
            RawKind::Hinge(axis) => JointKind::Hinge { axis },
            RawKind::Slide(axis) => JointKind::Slide { axis },
            RawKind::Universal(first, second) => JointKind::Universal { first, second },
        };
        let name = b.joint_name.clone().unwrap_or_else(|| {
            let stem = format!("{}_{}", b.name, if b.kind == RawKind::Weld { "weld" } else { "joint" });
            let mut name = stem.clone();
            let mut k = 1;
            while names.contains(&name) {
                k += 1;
                name = format!("{stem}{k}");
            }
            names.insert(name.clone());
            name
        });
        joints.push(Joint {
            name,
            kind,
            parent,
            child: index[i],
            anchor_parent: b.pos + b.rot * b.anchor,
            anchor_child: b.anchor,
            reference_rotation: b.rot,
            range: b.range,
            stiffness: b.stiffness,
            spring_ref: b.spring_ref,
            damping: b.damping,
            armature: b.armature,
            frictionloss: b.frictionloss,
            actuator_force_range: b.actuator_force_range,
        });
    }
    Ok(Built {
        bodies,
        joints,
        merged,
        shapes,
    })
}
