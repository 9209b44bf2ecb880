//! ROS URDF loader.
//!
//! Reads `<robot name>`, its `<link>`s (`<inertial>`: `<origin xyz rpy>`, `<mass value>`,
//! `<inertia ixx ixy ixz iyy iyz izz>` in the inertial origin's frame, rotated here into
//! the link frame) and `<joint>`s (`revolute`, `continuous`, `prismatic`, `fixed`,
//! `floating`; `planar` is refused) with `<origin xyz rpy>` (`rpy` about fixed axes:
//! `R = Rz(y) Ry(p) Rx(r)`), `<parent link>`, `<child link>`, `<axis xyz>` (default
//! `1 0 0`, normalised; the joint frame is the child link's frame), `<limit lower upper>`
//! and `<dynamics damping>`.
//!
//! Decisions:
//! - The root link (the one that is no joint's child) is welded to the world, unless it is
//!   named `world`: then it *is* the world and its joints attach their children to it (a
//!   `floating` joint from `world` gives a free root).
//! - Every `fixed` joint is lumped: the child link's mass joins the parent's (parallel-axis
//!   theorem) and the child's children are re-posed on the parent, as MuJoCo's
//!   `fusestatic` and Pinocchio do. [`Loaded::merged`] records each lumped link. A root
//!   welded to the world without mass is merged into the world.
//! - A link without `<inertial>` (or with `<mass value="0">`) is massless: fine when lumped,
//!   refused (naming the link) when it would move.
//! - A `revolute` or `prismatic` joint without `<limit lower/upper>` is taken as unlimited
//!   (the specification requires the limit; this is noted in [`Loaded::ignored`]).
//! - Visuals are drawn (mesh files found as [`mesh_path`] says). Collisions touch (MuJoCo's
//!   import: friction 1) and are drawn hidden, in group 3; a collision mesh touches as its
//!   file's convex hull, as MuJoCo collides meshes, when [`load`] finds the file (not in a
//!   model parsed from text: noted). Materials, transmissions, Gazebo tags, effort and
//!   velocity limits, mimic, calibration and safety controllers are noted as ignored.

use std::collections::HashMap;
use std::path::Path;

use roxmltree::Node;

use super::model::Model;
use super::shapes::{Shape, ShapeKind};
use super::xml::{
    build, check_inertia, line_starts, parse_document, read_bounded, rpy, Ctx, Ignored, MassProps, Merge, RawBody,
    RawKind, Sources,
};
use crate::error::Result;
use crate::linalg::{Mat3, Vec3};

pub use super::xml::Loaded;

/// Loads a URDF file (at most 64 MiB); its visuals' and collisions' mesh files are found
/// (see [`mesh_path`]) and listed in [`Loaded::files`], not read. A collision mesh whose
/// file is not found does not touch (noted in [`Loaded::ignored`]).
pub fn load(path: &Path) -> Result<Loaded> {
    let text = read_bounded(path)?;
    let mut loaded = parse_unresolved(&text, &path.display().to_string())?;
    loaded.files = vec![path.to_path_buf()];
    let dir = path.parent().unwrap_or(Path::new(""));
    let shapes = loaded.shapes.iter_mut().chain(&mut loaded.model.collision.shapes);
    for shape in shapes {
        if let ShapeKind::Mesh { file, path, .. } = &mut shape.kind {
            *path = mesh_path(dir, file);
            if let Ok(p) = path {
                if !loaded.files.contains(p) {
                    loaded.files.push(p.clone());
                }
            }
        }
    }
    drop_unfound_collision_meshes(&mut loaded);
    Ok(loaded)
}

/// Collision meshes without a file found in a format that is read (STL, OBJ; none in a
/// model parsed from text) do not touch: removed from the contact shapes (the drawn shapes
/// keep them), and noted.
fn drop_unfound_collision_meshes(loaded: &mut Loaded) {
    let unfound = |s: &Shape| match &s.kind {
        ShapeKind::Mesh { path, .. } => !path
            .as_ref()
            .is_ok_and(|p| p.is_file() && super::mesh::format_is_read(p)),
        _ => false,
    };
    let shapes = &mut loaded.model.collision.shapes;
    let before = shapes.len();
    shapes.retain(|s| !unfound(s));
    if shapes.len() < before {
        let note = "collision meshes (not simulated where the mesh file is not found or is not STL or OBJ)";
        if !loaded.ignored.iter().any(|n| n == note) {
            loaded.ignored.push(note.to_string());
        }
    }
    for s in loaded.shapes.iter_mut().filter(|s| s.collision.is_some() && unfound(s)) {
        s.collision = None;
    }
}

/// How many directories above the URDF's a `package://` path is looked for in.
pub const PACKAGE_SEARCH_DEPTH: usize = 4;

/// The mesh file `filename` of a URDF in directory `dir`: a `file://` path as it is (or
/// relative to `dir`), a relative path relative to `dir`, and `package://PKG/REST` (ROS
/// would ask its package index, which a plain file has not) as `REST` under `dir` or one of
/// the [`PACKAGE_SEARCH_DEPTH`] directories above it, the first that exists. `Err` says why
/// none was found.
pub fn mesh_path(dir: &Path, filename: &str) -> std::result::Result<std::path::PathBuf, String> {
    if let Some(rest) = filename.strip_prefix("package://") {
        let Some((_, rest)) = rest.split_once('/') else {
            return Err("a package:// path names no file in its package".into());
        };
        return dir
            .ancestors()
            .take(PACKAGE_SEARCH_DEPTH + 1)
            .map(|d| d.join(rest))
            .find(|p| p.is_file())
            .ok_or_else(|| {
                format!(
                    "{rest} is not found under the URDF's directory nor the {PACKAGE_SEARCH_DEPTH} above it (ROS \
                     packages are not looked up)"
                )
            });
    }
    let plain = filename.strip_prefix("file://").unwrap_or(filename);
    if plain.contains("://") {
        return Err("only package:// and file:// paths are read".into());
    }
    let p = Path::new(plain);
    Ok(if p.is_absolute() { p.to_path_buf() } else { dir.join(p) })
}

/// Parses URDF text; `name_for_errors` names the file in error messages. Without a
/// directory to find mesh files in, collision meshes do not touch (noted; see [`load`]).
pub fn parse(text: &str, name_for_errors: &str) -> Result<Loaded> {
    let mut loaded = parse_unresolved(text, name_for_errors)?;
    drop_unfound_collision_meshes(&mut loaded);
    Ok(loaded)
}

/// [`parse`] with its collision meshes kept, for [`load`] to find their files.
fn parse_unresolved(text: &str, name_for_errors: &str) -> Result<Loaded> {
    let doc = parse_document(text, name_for_errors, Sources::NONE)?;
    let lines = line_starts(text);
    let cx = Ctx::new(name_for_errors, Sources::NONE, &lines);
    let robot = doc.root_element();
    if robot.tag_name().name() != "robot" {
        return Err(cx.err(robot, "a URDF file's root element must be <robot>"));
    }
    let mut ignored = Ignored::default();
    let mut links: Vec<LinkData> = Vec::new();
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    let mut joints: Vec<JointData> = Vec::new();
    let mut joint_names: HashMap<&str, Node> = HashMap::new();
    for node in robot.children().filter(Node::is_element) {
        match node.tag_name().name() {
            "link" => {
                let link = read_link(&cx, node, &mut ignored)?;
                if link_index.insert(link.name, links.len()).is_some() {
                    return Err(cx.err(node, format!("a second link named `{}`", link.name)));
                }
                links.push(link);
            }
            "joint" => {
                let joint = read_joint(&cx, node, &mut ignored)?;
                if joint_names.insert(joint.name, node).is_some() {
                    return Err(cx.err(node, format!("a second joint named `{}`", joint.name)));
                }
                joints.push(joint);
            }
            other => ignored.note(other),
        }
    }
    if links.is_empty() {
        return Err(cx.err(robot, "the robot has no <link>"));
    }
    // The tree: each link is the child of at most one joint.
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    let mut child_joints: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
    for (j, joint) in joints.iter().enumerate() {
        let find = |name: &str, role: &str| {
            link_index
                .get(name)
                .copied()
                .ok_or_else(|| cx.err(joint.node, format!("the {role} link `{name}` is not defined")))
        };
        let (p, c) = (find(joint.parent, "parent")?, find(joint.child, "child")?);
        if let Some(first) = parent_joint[c] {
            return Err(cx.err(
                joint.node,
                format!(
                    "link `{}` has two parents: it is already the child of joint `{}` (line {})",
                    joint.child,
                    joints[first].name,
                    cx.line(joints[first].node)
                ),
            ));
        }
        parent_joint[c] = Some(j);
        child_joints[p].push(j);
    }
    let roots: Vec<usize> = (0..links.len()).filter(|&l| parent_joint[l].is_none()).collect();
    let root = match roots.as_slice() {
        [r] => *r,
        [] => {
            return Err(cx.err(
                joints[0].node,
                "the joints form a cycle: every link is some joint's child",
            ));
        }
        [a, b, ..] => {
            return Err(cx.err(
                links[*b].node,
                format!(
                    "the links do not form one tree: `{}` and `{}` are both roots (no joint's child)",
                    links[*a].name, links[*b].name
                ),
            ));
        }
    };
    let world_root = links[root].name == "world";
    if world_root && links[root].mass.mass > 0.0 {
        ignored.note("inertial of the world link");
    }
    // Breadth-first from the root: parents before children.
    let mut raw: Vec<RawBody> = Vec::new();
    let mut raw_of_link: Vec<Option<usize>> = vec![None; links.len()];
    let mut queue = std::collections::VecDeque::new();
    if !world_root {
        let l = &links[root];
        raw_of_link[root] = Some(0);
        raw.push(raw_body(
            &cx,
            l,
            None,
            Vec3::ZERO,
            Mat3::IDENTITY,
            RawKind::Weld,
            Merge::IfMassless,
        ));
    }
    let mut reached = vec![false; links.len()];
    reached[root] = true;
    queue.push_back(root);
    while let Some(l) = queue.pop_front() {
        for &j in &child_joints[l] {
            let joint = &joints[j];
            let c = link_index[joint.child];
            reached[c] = true;
            let parent = raw_of_link[l];
            let merge = match (joint.kind, parent) {
                (RawKind::Weld, Some(_)) => Merge::Always,
                (RawKind::Weld, None) => Merge::IfMassless,
                _ => Merge::Never,
            };
            let mut body = raw_body(&cx, &links[c], parent, joint.xyz, joint.rot, joint.kind, merge);
            body.joint_name = Some(joint.name.to_string());
            body.range = joint.range;
            body.damping = joint.damping;
            body.line = cx.line(joint.node);
            body.element = format!("joint name=\"{}\"", joint.name);
            raw_of_link[c] = Some(raw.len());
            raw.push(body);
            queue.push_back(c);
        }
    }
    if let Some(c) = (0..links.len()).find(|&l| !reached[l]) {
        let j = parent_joint[c].expect("an unreached link has a parent joint");
        return Err(cx.err(
            joints[j].node,
            "the joints form a cycle (this joint's child link is not reached from the root)",
        ));
    }
    let built = build(raw)?;
    Ok(Loaded {
        files: Vec::new(),
        model: Model {
            name: robot.attribute("name").unwrap_or_default().to_string(),
            bodies: built.bodies,
            joints: built.joints,
            gravity: Vec3::new(0.0, 0.0, -9.81),
            timestep: None,
            qpos: None,
            qvel: None,
            actuators: Vec::new(),
            ctrl: None,
            collision: super::contact::Collision {
                shapes: built.shapes.iter().filter(|s| s.collision.is_some()).cloned().collect(),
                ..Default::default()
            },
        },
        ignored: ignored.into_vec(),
        merged: built.merged,
        shapes: built.shapes,
    })
}

struct LinkData<'a, 'i> {
    name: &'a str,
    node: Node<'a, 'i>,
    mass: MassProps,
    /// The link's visuals, in its frame.
    shapes: Vec<Shape>,
}

struct JointData<'a, 'i> {
    name: &'a str,
    node: Node<'a, 'i>,
    kind: RawKind,
    parent: &'a str,
    child: &'a str,
    xyz: Vec3,
    rot: Mat3,
    range: Option<(f64, f64)>,
    damping: f64,
}

fn raw_body(
    cx: &Ctx,
    link: &LinkData,
    parent: Option<usize>,
    pos: Vec3,
    rot: Mat3,
    kind: RawKind,
    merge: Merge,
) -> RawBody {
    RawBody {
        name: link.name.to_string(),
        parent,
        pos,
        rot,
        mass: link.mass,
        kind,
        joint_name: None,
        anchor: Vec3::ZERO,
        range: None,
        stiffness: 0.0,
        spring_ref: 0.0,
        damping: 0.0,
        armature: 0.0,
        frictionloss: 0.0,
        actuator_force_range: None,
        merge,
        shapes: link.shapes.clone(),
        file: cx.file.to_string(),
        line: cx.line(link.node),
        element: super::xml::describe(link.node),
    }
}

fn required<'a>(cx: &Ctx, node: Node<'a, '_>, attr: &str) -> Result<&'a str> {
    node.attribute(attr)
        .ok_or_else(|| cx.err(node, format!("the attribute `{attr}` is required")))
}

fn child<'a, 'i>(node: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    node.children().find(|c| c.has_tag_name(tag))
}

/// `<origin xyz rpy>` of `node`: position and rotation (identity when absent).
fn origin(cx: &Ctx, node: Node) -> Result<(Vec3, Mat3)> {
    let Some(o) = child(node, "origin") else {
        return Ok((Vec3::ZERO, Mat3::IDENTITY));
    };
    let xyz = cx.array::<3>(o, "xyz")?.unwrap_or([0.0; 3]);
    let r = cx.array::<3>(o, "rpy")?.unwrap_or([0.0; 3]);
    Ok((Vec3::from_array(xyz), rpy(r)))
}

fn read_link<'a, 'i>(cx: &Ctx, node: Node<'a, 'i>, ignored: &mut Ignored) -> Result<LinkData<'a, 'i>> {
    let name = required(cx, node, "name")?;
    let mut mass = MassProps::ZERO;
    let mut shapes = Vec::new();
    for c in node.children().filter(Node::is_element) {
        match c.tag_name().name() {
            "inertial" => mass = read_inertial(cx, c)?,
            "visual" => shapes.extend(read_visual(cx, c, name)?),
            "collision" => {
                // The contact shape (MuJoCo's URDF import: contype and conaffinity 1, friction
                // 1), in the hidden group 3 as collision geoms are drawn; a mesh touches as
                // its file's convex hull once `load` has found the file.
                if let Some(mut s) = read_visual(cx, c, name)? {
                    s.group = 3;
                    s.collision = Some(super::shapes::Collides {
                        name: c.attribute("name").map(str::to_string),
                        contype: 1,
                        conaffinity: 1,
                        friction: 1.0,
                    });
                    shapes.push(s);
                }
            }
            other => ignored.note(other),
        }
    }
    Ok(LinkData {
        name,
        node,
        mass,
        shapes,
    })
}

/// The shape of a `<visual>` of link `link`: `<origin>`, `<geometry>` (box, cylinder, sphere,
/// mesh with `filename` and `scale`, the file found by [`load`]) and `<material><color
/// rgba>`.
fn read_visual(cx: &Ctx, node: Node, link: &str) -> Result<Option<Shape>> {
    let (position, rotation) = origin(cx, node)?;
    let Some(g) = child(node, "geometry").and_then(|g| g.children().find(Node::is_element)) else {
        return Err(cx.err(node, "a <visual> or <collision> needs a <geometry> with a shape"));
    };
    let positive = |attr: &str| -> Result<f64> {
        let [v] = cx.array_of::<1>(g, attr, required(cx, g, attr)?)?;
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(cx.err(
                g,
                format!("{attr} = {}: must be positive and finite", crate::error::Num(v)),
            ))
        }
    };
    let kind = match g.tag_name().name() {
        "box" => {
            let s = cx.array_of::<3>(g, "size", required(cx, g, "size")?)?;
            if !s.iter().all(|v| v.is_finite() && *v > 0.0) {
                return Err(cx.err(g, "size: three positive, finite edges"));
            }
            ShapeKind::Box {
                half: s.map(|v| 0.5 * v),
            }
        }
        "cylinder" => ShapeKind::Cylinder {
            radius: positive("radius")?,
            half_length: 0.5 * positive("length")?,
        },
        "sphere" => ShapeKind::Sphere {
            radius: positive("radius")?,
        },
        "mesh" => {
            let scale = cx.array::<3>(g, "scale")?.unwrap_or([1.0; 3]);
            if !scale.iter().all(|c| c.is_finite() && *c != 0.0) {
                return Err(cx.err(g, "scale: three finite, non-zero factors"));
            }
            ShapeKind::Mesh {
                name: link.to_string(),
                file: required(cx, g, "filename")?.to_string(),
                path: Err("the model was parsed from text, with no directory to find its files in".into()),
                scale,
                half: None,
            }
        }
        other => return Err(cx.err(g, format!("unknown geometry <{other}>"))),
    };
    let rgba = match child(node, "material").and_then(|m| child(m, "color")) {
        Some(c) => {
            let v = cx.array_of::<4>(c, "rgba", required(cx, c, "rgba")?)?;
            if v.iter().any(|x| !(0.0..=1.0).contains(x)) {
                return Err(cx.err(c, "rgba: each component must lie in [0, 1]"));
            }
            v.map(|x| x as f32)
        }
        None => [0.5, 0.5, 0.5, 1.0],
    };
    Ok(Some(Shape {
        body: None,
        kind,
        position,
        rotation,
        rgba,
        group: 0,
        collision: None,
    }))
}

fn read_inertial(cx: &Ctx, node: Node) -> Result<MassProps> {
    let (pos, rot) = origin(cx, node)?;
    let m_node = child(node, "mass").ok_or_else(|| cx.err(node, "<inertial> without <mass>"))?;
    let m = cx.array_of::<1>(m_node, "value", required(cx, m_node, "value")?)?[0];
    if m < 0.0 {
        return Err(cx.err(m_node, format!("mass {m} is negative")));
    }
    if m == 0.0 {
        return Ok(MassProps::ZERO);
    }
    let i_node = child(node, "inertia").ok_or_else(|| cx.err(node, "<inertial> without <inertia>"))?;
    let mut v = [0.0; 6];
    for (k, attr) in ["ixx", "iyy", "izz", "ixy", "ixz", "iyz"].into_iter().enumerate() {
        v[k] = cx.array_of::<1>(i_node, attr, required(cx, i_node, attr)?)?[0];
    }
    let i = Mat3::from_rows([[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]]);
    check_inertia(&i).map_err(|msg| cx.err(i_node, msg))?;
    Ok(MassProps {
        mass: m,
        com: pos,
        inertia: rot * i * rot.transpose(),
    })
}

fn read_joint<'a, 'i>(cx: &Ctx, node: Node<'a, 'i>, ignored: &mut Ignored) -> Result<JointData<'a, 'i>> {
    let name = required(cx, node, "name")?;
    let ty = required(cx, node, "type")?;
    let link_of = |tag: &str| -> Result<&'a str> {
        let c = child(node, tag).ok_or_else(|| cx.err(node, format!("the joint has no <{tag}>")))?;
        required(cx, c, "link")
    };
    let (parent, child_link) = (link_of("parent")?, link_of("child")?);
    let (xyz, rot) = origin(cx, node)?;
    let axis = match child(node, "axis") {
        Some(a) => cx.unit(a, "xyz", cx.array_of::<3>(a, "xyz", required(cx, a, "xyz")?)?)?,
        None => Vec3::new(1.0, 0.0, 0.0),
    };
    let kind = match ty {
        "revolute" | "continuous" => RawKind::Hinge(axis),
        "prismatic" => RawKind::Slide(axis),
        "fixed" => RawKind::Weld,
        "floating" => RawKind::Free,
        "planar" => {
            return Err(cx.err(
                node,
                "planar joints are not supported (no such joint in the multibody model)",
            ));
        }
        other => return Err(cx.err(node, format!("unknown joint type `{other}`"))),
    };
    let mut range = None;
    let limit = child(node, "limit");
    if let Some(l) = limit {
        if l.has_attribute("effort") || l.has_attribute("velocity") {
            ignored.note("joint effort and velocity limits");
        }
    }
    if matches!(ty, "revolute" | "prismatic") {
        let bound = |attr: &str| -> Result<Option<f64>> {
            match limit {
                Some(l) => Ok(cx.array::<1>(l, attr)?.map(|v| v[0])),
                None => Ok(None),
            }
        };
        let (lo, hi) = (bound("lower")?, bound("upper")?);
        if lo.is_none() && hi.is_none() {
            ignored.note("missing revolute/prismatic limit (taken as unlimited)");
        } else {
            let (lo, hi) = (lo.unwrap_or(0.0), hi.unwrap_or(0.0));
            if lo > hi {
                return Err(cx.err(
                    limit.unwrap_or(node),
                    format!("lower limit {lo} above upper limit {hi}"),
                ));
            }
            range = Some((lo, hi));
        }
    }
    let mut damping = 0.0;
    if let Some(d) = child(node, "dynamics") {
        damping = cx.array::<1>(d, "damping")?.map_or(0.0, |v| v[0]);
        if damping < 0.0 {
            return Err(cx.err(d, format!("negative damping {}", crate::error::Num(damping))));
        }
        if cx.array::<1>(d, "friction")?.is_some_and(|f| f[0] != 0.0) {
            ignored.note("joint friction");
        }
    }
    for c in node.children().filter(Node::is_element) {
        let tag = c.tag_name().name();
        if !matches!(tag, "origin" | "parent" | "child" | "axis" | "limit" | "dynamics") {
            ignored.note(&format!("joint {tag}"));
        }
    }
    Ok(JointData {
        name,
        node,
        kind,
        parent,
        child: child_link,
        xyz,
        rot,
        range,
        damping,
    })
}
