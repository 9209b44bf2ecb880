//! MuJoCo MJCF loader.
//!
//! Reads, as published models (MuJoCo Menagerie) write them: `<mujoco model>`,
//! `<compiler angle eulerseq autolimits inertiafromgeom>` (angles are in **degrees** unless
//! `angle="radian"`, as in MuJoCo; this applies to `euler`, `axisangle` and hinge `range`,
//! `ref`, `springref`), `<option gravity timestep>`, nested `<default class>` classes for
//! `joint` and `geom` (a nested class inherits its parent's values; an element uses its
//! own `class`, else the `childclass` of its nearest ancestor body that has one, else
//! `main`), `<worldbody>` with nested `<body name pos quat|axisangle|euler|xyaxes|zaxis
//! childclass>`, `<inertial pos quat… mass diaginertia|fullinertia>`, geoms for mass when
//! a body has no inertial (sphere, capsule, cylinder, box, ellipsoid; `size`, `fromto`,
//! `mass` or `density`, default 1000), `<joint type=hinge|slide|ball|free axis pos range
//! limited ref springref stiffness damping armature frictionloss actuatorfrcrange>`,
//! `<freejoint>`, `<actuator>` (`motor`, `position`, `velocity`, `general` on hinges and
//! slides, see [`mod@actuator`]) and the first `<keyframe><key qpos qvel ctrl>`.
//!
//! Decisions:
//! - A body without a joint is welded to its parent (a `Weld` joint); if it has no mass
//!   at all it is merged into its parent (or the world) instead, see [`Loaded::merged`].
//! - Several joints in one body: MuJoCo composes them through massless intermediate
//!   frames, which maximal coordinates cannot integrate as such. Two or three **hinges
//!   through one point** (their `pos` equal to `1e-9` of the body's size) are exactly a
//!   joint of their own: two with independent axes `a` (first, nearer the parent) and `b`
//!   a [`JointKind::Universal`](super::model::JointKind::Universal) (`exp(θ₁ a) exp(θ₂ b)`),
//!   three with independent axes `a`, `b`, `c` a ball (`exp(θ₁ a) exp(θ₂ b) exp(θ₃ c)`
//!   covers a neighbourhood of every rotation the chain reaches, and the ball has no
//!   gimbal lock where the chain has one). The merged joint is named `a+b(+c)` after the
//!   hinges. Keyframe `qpos`/`qvel` give per-hinge angles and rates (MuJoCo's layout) and
//!   are converted: a universal keeps its two angles, a ball gets the quaternion of the
//!   product and the angular velocity `exp(−θ₃c)exp(−θ₂b) a θ̇₁ + exp(−θ₃c) b θ̇₂ + c θ̇₃`
//!   (child frame). Per-hinge limits, springs, dampers and armature on merged hinges have
//!   no exact form on the merged joint and are refused, naming the body and the joint; so
//!   is any other combination (a hinge and a slide on one axis, a ball or a free joint with
//!   others, four hinges, parallel axes, different anchors), naming the body and its
//!   joints. Actuators on merged hinges are listed as not simulated (the merged joint has no
//!   coordinate per hinge).
//! - Hinge and slide `ref`: MuJoCo's `qpos0 = ref`, i.e. the body pose in the file is the
//!   pose at joint value `ref`. The model's reference is the body pose in the file at joint
//!   coordinate 0, so the model's coordinate is MuJoCo's `qpos − ref`: `range`,
//!   `springref` and keyframe `qpos` values of hinges and slides are shifted by `−ref`.
//!   Without a keyframe the start is MuJoCo's `qpos0`, the reference pose (`qpos = None`).
//!   Ball and free keyframe values are taken as they are (MuJoCo's layout is the model's).
//! - Mesh, height-field and SDF geoms are fine when the body has an `<inertial>` (no file is
//!   read); when their mass would be needed the body is refused, naming the mesh.
//! - `<equality>` `connect` and `weld` become exact loop-closing joints (a ball, a weld;
//!   MuJoCo's are soft), satisfied in the reference pose as in MuJoCo (`equality.rs`);
//!   other equalities are listed as ignored.
//! - `<include file>` is expanded as MuJoCo does (see [`mod@include`]); `<frame>`,
//!   `<composite>`, `<flexcomp>`, `<replicate>` and `<attach>` are refused (they add or move
//!   bodies); tendons, sensors, joint and tendon equalities, contacts,
//!   geom contact and visual properties, sites, cameras, lights, assets and the like are
//!   listed in [`Loaded::ignored`].

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use roxmltree::Node;

use super::model::Model;
use super::xml::{
    axis_angle, build, check_inertia, coordinate_rotation, line_starts, parse_document, quat_matrix, rotation_to_z,
    Ctx, Ignored, MassProps, Merge, RawBody, RawKind, Sources,
};
use crate::error::Result;
use crate::linalg::{Mat3, Vec3};

pub mod actuator;
mod contact;
mod equality;
mod geom;
pub mod include;
mod merge;

use merge::KeyMap;

pub use super::xml::Loaded;

/// Loads an MJCF file (at most 64 MiB with its includes expanded), reading the files it
/// `<include>`s (see [`mod@include`]); mesh files are found (`compiler` `meshdir` or
/// `assetdir`, relative to this file's directory, as MuJoCo does) and listed in
/// [`Loaded::files`] but not read: a viewer reads them ([`ShapeKind::Mesh`](super::ShapeKind::Mesh)).
pub fn load(path: &Path) -> Result<Loaded> {
    let (text, sources, files) = include::expand(path)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut loaded = parse_assembled(&text, &path.display().to_string(), &sources, Some(dir))?;
    // The model's files, then its mesh files (found next to it, see [`ShapeKind::Mesh`]).
    let meshes = std::mem::replace(&mut loaded.files, files);
    loaded.files.extend(meshes);
    Ok(loaded)
}

/// Parses MJCF text; `name_for_errors` names the file in error messages. An `<include>`
/// is refused (no file to resolve it against): use [`load`]; so are mesh files (their
/// shapes say why they cannot be drawn).
pub fn parse(text: &str, name_for_errors: &str) -> Result<Loaded> {
    parse_assembled(text, name_for_errors, Sources::NONE, None)
}

/// Parses the assembled text of a model whose file lies in `dir` (`None`: text).
fn parse_assembled(text: &str, name_for_errors: &str, sources: &Sources, dir: Option<PathBuf>) -> Result<Loaded> {
    let doc = parse_document(text, name_for_errors, sources)?;
    let lines = line_starts(text);
    let cx = Ctx::new(name_for_errors, sources, &lines);
    let root = doc.root_element();
    if root.tag_name().name() != "mujoco" {
        return Err(cx.err(root, "an MJCF file's root element must be <mujoco>"));
    }
    let mut st = State {
        cx,
        compiler: Compiler::default(),
        classes: HashMap::new(),
        ignored: Ignored::default(),
        raw: Vec::new(),
        refs: Vec::new(),
        body_names: HashMap::new(),
        joint_names: HashMap::new(),
        materials: HashMap::new(),
        meshes: HashMap::new(),
        dir,
        world_shapes: Vec::new(),
        joint_refs: HashMap::new(),
    };
    st.classes.insert("main", Class::default());
    let elements: Vec<Node> = root.children().filter(Node::is_element).collect();
    // The compiler and the defaults apply wherever they stand in the file.
    for &node in &elements {
        match node.tag_name().name() {
            "compiler" => st.read_compiler(node)?,
            "default" => st.read_default(node, None)?,
            "asset" => st.read_assets(node)?,
            _ => {}
        }
    }
    let mesh_files = st.mesh_files();
    let mut gravity = Vec3::new(0.0, 0.0, -9.81);
    let mut timestep = None;
    let mut keys = Vec::new();
    let mut equalities = Vec::new();
    let mut actuators = Vec::new();
    let mut contacts = Vec::new();
    let (mut contact_disabled, mut parent_contacts) = (false, false);
    let mut restitution = 0.0;
    for &node in &elements {
        match node.tag_name().name() {
            "compiler" | "default" => {}
            "option" => {
                if let Some(g) = cx.array::<3>(node, "gravity")? {
                    gravity = Vec3::from_array(g);
                }
                if let Some([h]) = cx.array::<1>(node, "timestep")? {
                    if h <= 0.0 {
                        return Err(cx.err(node, format!("timestep {h} must be positive")));
                    }
                    timestep = Some(h);
                }
                st.note_other_attributes(node, &["gravity", "timestep"]);
                for c in node.children().filter(Node::is_element) {
                    if c.has_tag_name("flag") {
                        for a in c.attributes() {
                            let on = match a.value() {
                                "enable" => true,
                                "disable" => false,
                                v => {
                                    return Err(
                                        cx.err(c, format!("flag {}=\"{v}\": expected enable or disable", a.name()))
                                    )
                                }
                            };
                            match a.name() {
                                "contact" => contact_disabled = !on,
                                "filterparent" => parent_contacts = !on,
                                other => st.ignored.note(&format!("option flag {other}")),
                            }
                        }
                    } else {
                        st.ignored.note(&format!("option {}", c.tag_name().name()));
                    }
                }
            }
            "worldbody" => st.read_children(node, None, "main")?,
            "keyframe" => keys.extend(node.children().filter(|c| c.has_tag_name("key"))),
            "equality" => equalities.push(node),
            "actuator" => actuators.push(node),
            "contact" => contacts.push(node),
            "custom" => {
                for c in node.children().filter(Node::is_element) {
                    match (c.tag_name().name(), c.attribute("name")) {
                        ("numeric", Some("restitution")) => {
                            let [e] = cx
                                .array::<1>(c, "data")?
                                .ok_or_else(|| cx.err(c, "restitution needs data=\"e\""))?;
                            if !(0.0..=1.0).contains(&e) {
                                return Err(cx.err(c, format!("restitution {e}: expected a coefficient from 0 to 1")));
                            }
                            restitution = e;
                        }
                        (kind, _) => st.ignored.note(&format!("custom {kind}")),
                    }
                }
            }
            "include" => return Err(cx.err(node, NO_INCLUDE)),
            other => st.ignored.note(other),
        }
    }
    if keys.len() > 1 {
        st.ignored.note("keyframes after the first");
    }
    let (qpos, qvel) = match keys.first() {
        Some(&key) => st.read_key(key)?,
        None => (None, None),
    };
    let mut built = build(std::mem::take(&mut st.raw))?;
    built.shapes.extend(std::mem::take(&mut st.world_shapes));
    let exclude = st.read_excludes(&contacts, &built)?;
    for s in &built.shapes {
        if s.collision.is_some() && matches!(s.kind, crate::multibody::ShapeKind::Ellipsoid { .. }) {
            st.ignored
                .note("ellipsoid geom contacts (no ellipsoid in the collision library: drawn only)");
        }
    }
    let mut model = Model {
        name: root.attribute("model").unwrap_or_default().to_string(),
        bodies: built.bodies,
        joints: built.joints,
        gravity,
        timestep,
        qpos,
        qvel,
        actuators: Vec::new(),
        ctrl: None,
        collision: crate::multibody::Collision {
            shapes: built.shapes.iter().filter(|s| s.collision.is_some()).cloned().collect(),
            exclude,
            disabled: contact_disabled,
            parent_contacts,
            restitution,
        },
    };
    let loops = equality::loop_joints(&cx, &equalities, &model, &built.merged, &mut st.ignored)?;
    model.joints.extend(loops);
    let kept = st.read_actuators(&actuators, &mut model)?;
    if let Some(&key) = keys.first() {
        st.read_key_ctrl(key, &kept, &mut model)?;
    }
    model.validate_actuators().map_err(|e| cx.err(root, e.to_string()))?;
    Ok(Loaded {
        files: mesh_files,
        model,
        ignored: st.ignored.into_vec(),
        merged: built.merged,
        shapes: built.shapes,
    })
}

/// Why an `<include>` left in the text is refused: only [`load`] reads other files.
const NO_INCLUDE: &str = "<include> needs the model loaded from a file (the included file is found next to it)";

/// A keyframe's `qpos` and `qvel`, each when given.
type KeyState = (Option<Vec<f64>>, Option<Vec<f64>>);

#[derive(Clone, Copy, PartialEq, Eq)]
enum FromGeom {
    False,
    True,
    Auto,
}

struct Compiler {
    degree: bool,
    eulerseq: [u8; 3],
    autolimits: bool,
    from_geom: FromGeom,
    /// `meshdir`, else `assetdir`: where mesh files are found.
    meshdir: Option<String>,
    assetdir: Option<String>,
}

impl Default for Compiler {
    fn default() -> Self {
        Compiler {
            degree: true,
            eulerseq: *b"xyz",
            autolimits: true,
            from_geom: FromGeom::Auto,
            meshdir: None,
            assetdir: None,
        }
    }
}

/// A default class: attribute values for joints and geoms.
#[derive(Clone, Default)]
struct Class<'a> {
    joint: HashMap<&'a str, &'a str>,
    geom: HashMap<&'a str, &'a str>,
    /// Every actuator shortcut's defaults in one map (MuJoCo's shortcuts all set the one
    /// actuator default of a class).
    actuator: HashMap<&'a str, &'a str>,
    /// `<mesh>` asset defaults (`scale`).
    mesh: HashMap<&'a str, &'a str>,
}

struct State<'a, 'i> {
    cx: Ctx<'a, 'i>,
    compiler: Compiler,
    classes: HashMap<&'a str, Class<'a>>,
    ignored: Ignored,
    raw: Vec<RawBody>,
    /// Per raw body: how its joints map a keyframe.
    refs: Vec<KeyMap>,
    body_names: HashMap<String, Node<'a, 'i>>,
    joint_names: HashMap<&'a str, Node<'a, 'i>>,
    /// `<asset><material name rgba>`: the colours geoms name.
    materials: HashMap<&'a str, [f32; 4]>,
    /// `<asset><mesh>`: the meshes geoms name.
    meshes: HashMap<String, geom::MeshAsset>,
    /// The model file's directory (`None`: parsed from text).
    dir: Option<PathBuf>,
    /// The shapes of `<worldbody>`'s own geoms.
    world_shapes: Vec<crate::multibody::shapes::Shape>,
    /// The `ref` of each named hinge and slide (MuJoCo's `qpos` minus the model's).
    joint_refs: HashMap<String, f64>,
}

/// An element with its default class: attribute lookup falls back on the class.
struct Elem<'a, 'i> {
    node: Node<'a, 'i>,
    defaults: HashMap<&'a str, &'a str>,
}

impl<'a> Elem<'a, '_> {
    fn get(&self, attr: &str) -> Option<&'a str> {
        self.node.attribute(attr).or_else(|| self.defaults.get(attr).copied())
    }
}

fn parse_bool(cx: &Ctx, node: Node, attr: &str, value: &str) -> Result<bool> {
    match value {
        "true" => Ok(true),
        "false" => Ok(false),
        _ => Err(cx.err(node, format!("attribute {attr}=\"{value}\": expected true or false"))),
    }
}

impl<'a, 'i> State<'a, 'i> {
    fn angle(&self, v: f64) -> f64 {
        if self.compiler.degree {
            v.to_radians()
        } else {
            v
        }
    }

    fn note_other_attributes(&mut self, node: Node, known: &[&str]) {
        for a in node.attributes() {
            if !known.contains(&a.name()) {
                self.ignored.note(&format!("{} {}", node.tag_name().name(), a.name()));
            }
        }
    }

    /// Whether a range is limited: `limited` (`true`, `false` or `auto`, the default),
    /// `auto` meaning "when a range is given" under `compiler autolimits` (an error without).
    fn limited(&self, node: Node, limited: Option<&str>, has_range: bool, range: &str) -> Result<bool> {
        match limited.unwrap_or("auto") {
            "auto" => {
                if has_range && !self.compiler.autolimits {
                    return Err(self.cx.err(
                        node,
                        format!("{range} given without its limited attribute while compiler autolimits is false"),
                    ));
                }
                Ok(has_range)
            }
            v => parse_bool(&self.cx, node, range, v),
        }
    }

    fn read_compiler(&mut self, node: Node<'a, 'i>) -> Result<()> {
        let cx = self.cx;
        if let Some(a) = node.attribute("angle") {
            self.compiler.degree = match a {
                "degree" => true,
                "radian" => false,
                _ => return Err(cx.err(node, format!("angle=\"{a}\": expected degree or radian"))),
            };
        }
        if let Some(s) = node.attribute("eulerseq") {
            let b = s.as_bytes();
            if b.len() != 3 || !b.iter().all(|c| b"xyzXYZ".contains(c)) {
                return Err(cx.err(node, format!("eulerseq=\"{s}\": expected three of x y z X Y Z")));
            }
            self.compiler.eulerseq = [b[0], b[1], b[2]];
        }
        if let Some(v) = node.attribute("autolimits") {
            self.compiler.autolimits = parse_bool(&cx, node, "autolimits", v)?;
        }
        if let Some(v) = node.attribute("inertiafromgeom") {
            self.compiler.from_geom = match v {
                "false" => FromGeom::False,
                "true" => FromGeom::True,
                "auto" => FromGeom::Auto,
                _ => return Err(cx.err(node, format!("inertiafromgeom=\"{v}\": expected false, true or auto"))),
            };
        }
        for (attr, into) in [
            ("meshdir", &mut self.compiler.meshdir),
            ("assetdir", &mut self.compiler.assetdir),
        ] {
            if let Some(v) = node.attribute(attr) {
                *into = Some(v.to_string());
            }
        }
        self.note_other_attributes(
            node,
            &[
                "angle",
                "eulerseq",
                "autolimits",
                "inertiafromgeom",
                "meshdir",
                "assetdir",
            ],
        );
        Ok(())
    }

    /// A `<default>` element under `parent` (None: top level, the `main` class). Nesting
    /// is bounded by the document's depth check.
    fn read_default(&mut self, node: Node<'a, 'i>, parent: Option<&'a str>) -> Result<()> {
        let cx = self.cx;
        let name = match (node.attribute("class"), parent) {
            (Some(c), _) => c,
            (None, None) => "main",
            (None, Some(_)) => return Err(cx.err(node, "a nested <default> needs a class attribute")),
        };
        let mut class = match parent {
            Some(p) => self.classes[p].clone(),
            None => self.classes.get(name).cloned().unwrap_or_default(),
        };
        if parent.is_some() && self.classes.contains_key(name) {
            return Err(cx.err(node, format!("a second default class `{name}`")));
        }
        for c in node.children().filter(Node::is_element) {
            let map = match c.tag_name().name() {
                "joint" => &mut class.joint,
                "geom" => &mut class.geom,
                "mesh" => &mut class.mesh,
                "general" | "motor" | "position" | "velocity" | "intvelocity" | "damper" | "cylinder" | "muscle"
                | "adhesion" => &mut class.actuator,
                _ => continue,
            };
            for a in c.attributes() {
                map.insert(a.name(), a.value());
            }
        }
        self.classes.insert(name, class);
        for c in node.children().filter(|c| c.has_tag_name("default")) {
            self.read_default(c, Some(name))?;
        }
        Ok(())
    }

    /// The defaults for `kind` of the class an element uses.
    fn class_of(&self, node: Node, childclass: &str) -> Result<&'a str> {
        let name = node.attribute("class").unwrap_or(childclass);
        match self.classes.get_key_value(name) {
            Some((k, _)) => Ok(k),
            None => Err(self.cx.err(node, format!("unknown default class `{name}`"))),
        }
    }

    /// Position and attitude from `pos` and one of `quat`, `axisangle`, `euler`, `xyaxes`,
    /// `zaxis` (through `get`, so defaults apply).
    fn frame(&self, node: Node, get: &dyn Fn(&str) -> Option<&'a str>) -> Result<(Vec3, Mat3)> {
        let cx = self.cx;
        let pos = match get("pos") {
            Some(v) => Vec3::from_array(cx.array_of::<3>(node, "pos", v)?),
            None => Vec3::ZERO,
        };
        let given: Vec<&str> = ["quat", "axisangle", "euler", "xyaxes", "zaxis"]
            .into_iter()
            .filter(|a| get(a).is_some())
            .collect();
        if given.len() > 1 {
            return Err(cx.err(node, format!("more than one orientation given: {}", given.join(", "))));
        }
        let rot = match given.first().copied() {
            None => Mat3::IDENTITY,
            Some(attr) => {
                let v = get(attr).unwrap_or_default();
                self.orientation(node, attr, v)?
            }
        };
        Ok((pos, rot))
    }

    fn orientation(&self, node: Node, attr: &str, v: &str) -> Result<Mat3> {
        let cx = self.cx;
        Ok(match attr {
            "quat" => quat_matrix(cx.array_of::<4>(node, attr, v)?)
                .ok_or_else(|| cx.err(node, "quat: a zero quaternion is no rotation"))?,
            "axisangle" => {
                let a = cx.array_of::<4>(node, attr, v)?;
                axis_angle(cx.unit(node, attr, [a[0], a[1], a[2]])?, self.angle(a[3]))
            }
            "euler" => {
                let e = cx.array_of::<3>(node, attr, v)?;
                let mut r = Mat3::IDENTITY;
                for (k, &c) in self.compiler.eulerseq.iter().enumerate() {
                    let step = coordinate_rotation((c.to_ascii_lowercase() - b'x') as usize, self.angle(e[k]));
                    // Lower case: about the rotated (moving) axes; upper case: fixed axes.
                    r = if c.is_ascii_lowercase() { r * step } else { step * r };
                }
                r
            }
            "xyaxes" => {
                let a = cx.array_of::<6>(node, attr, v)?;
                let x = cx.unit(node, attr, [a[0], a[1], a[2]])?;
                let y = Vec3::new(a[3], a[4], a[5]);
                let y = cx.unit(node, attr, (y - x * x.dot(y)).to_array())?;
                let z = x.cross(y);
                Mat3::from_rows([[x.x, y.x, z.x], [x.y, y.y, z.y], [x.z, y.z, z.z]])
            }
            _ => rotation_to_z(cx.unit(node, attr, cx.array_of::<3>(node, attr, v)?)?),
        })
    }

    /// The bodies (and ignored elements) under `node` (a body or the worldbody).
    fn read_children(&mut self, node: Node<'a, 'i>, parent: Option<usize>, childclass: &'a str) -> Result<()> {
        let cx = self.cx;
        for c in node.children().filter(Node::is_element) {
            match c.tag_name().name() {
                "body" => self.read_body(c, parent, childclass)?,
                "joint" | "freejoint" | "inertial" if parent.is_some() => {}
                "geom" => {
                    if parent.is_none() {
                        let class = self.class_of(c, childclass)?;
                        let elem = Elem {
                            node: c,
                            defaults: self.classes[class].geom.clone(),
                        };
                        if let Some(shape) = self.geom_shape(&elem)? {
                            self.world_shapes.push(shape);
                        }
                    }
                }
                "include" => return Err(cx.err(c, NO_INCLUDE)),
                tag @ ("frame" | "composite" | "flexcomp" | "replicate" | "attach") => {
                    return Err(cx.err(c, format!("<{tag}> is not supported by this loader")));
                }
                tag @ ("joint" | "freejoint" | "inertial") => {
                    return Err(cx.err(c, format!("<{tag}> directly in <worldbody>: the world cannot move")));
                }
                other => self.ignored.note(other),
            }
        }
        Ok(())
    }

    fn read_body(&mut self, node: Node<'a, 'i>, parent: Option<usize>, inherited: &'a str) -> Result<()> {
        let cx = self.cx;
        let index = self.raw.len();
        let name = node
            .attribute("name")
            .map_or_else(|| format!("body{index}"), str::to_string);
        if let Some(first) = self.body_names.insert(name.clone(), node) {
            return Err(cx.err(
                node,
                format!("a second body named `{name}` (first on line {})", cx.line(first)),
            ));
        }
        let childclass = match node.attribute("childclass") {
            Some(c) => match self.classes.get_key_value(c) {
                Some((k, _)) => *k,
                None => return Err(cx.err(node, format!("unknown default class `{c}` in childclass"))),
            },
            None => inherited,
        };
        let (pos, rot) = self.frame(node, &|a| node.attribute(a))?;
        self.note_other_attributes(
            node,
            &[
                "name",
                "childclass",
                "pos",
                "quat",
                "axisangle",
                "euler",
                "xyaxes",
                "zaxis",
            ],
        );
        let joints: Vec<Node> = node
            .children()
            .filter(|c| c.has_tag_name("joint") || c.has_tag_name("freejoint"))
            .collect();
        let inertials: Vec<Node> = node.children().filter(|c| c.has_tag_name("inertial")).collect();
        if inertials.len() > 1 {
            return Err(cx.err(inertials[1], "a second <inertial> in one body"));
        }
        let mass = match (inertials.first(), self.compiler.from_geom) {
            (Some(&i), FromGeom::Auto | FromGeom::False) => self.read_inertial(i)?,
            (_, FromGeom::False) => MassProps::ZERO,
            _ => {
                let mut total = MassProps::ZERO;
                for g in node.children().filter(|c| c.has_tag_name("geom")) {
                    let class = self.class_of(g, childclass)?;
                    let elem = Elem {
                        node: g,
                        defaults: self.classes[class].geom.clone(),
                    };
                    total = total.combine(&self.geom_mass(elem)?);
                }
                total
            }
        };
        let mut shapes = Vec::new();
        for g in node.children().filter(|c| c.has_tag_name("geom")) {
            let class = self.class_of(g, childclass)?;
            let elem = Elem {
                node: g,
                defaults: self.classes[class].geom.clone(),
            };
            shapes.extend(self.geom_shape(&elem)?);
        }
        let (file, line) = cx.locate(node);
        let mut body = RawBody {
            name,
            parent,
            pos,
            rot,
            mass,
            kind: RawKind::Weld,
            joint_name: None,
            anchor: Vec3::ZERO,
            range: None,
            stiffness: 0.0,
            spring_ref: 0.0,
            damping: 0.0,
            armature: 0.0,
            frictionloss: 0.0,
            actuator_force_range: None,
            merge: Merge::IfMassless,
            shapes,
            file,
            line,
            element: super::xml::describe(node),
        };
        let mut reference = 0.0;
        let mut merged_hinges = None;
        if joints.len() > 1 {
            body.merge = Merge::Never;
            merged_hinges = Some(self.read_merged(node, &joints, childclass, &mut body)?);
        } else if let Some(&j) = joints.first() {
            body.merge = Merge::Never;
            if let Some(n) = j.attribute("name") {
                if let Some(first) = self.joint_names.insert(n, j) {
                    return Err(cx.err(
                        j,
                        format!("a second joint named `{n}` (first on line {})", cx.line(first)),
                    ));
                }
                body.joint_name = Some(n.to_string());
            }
            if j.has_tag_name("freejoint") {
                body.kind = RawKind::Free;
                self.note_other_attributes(j, &["name"]);
            } else {
                let class = self.class_of(j, childclass)?;
                let defaults = self.classes[class].joint.clone();
                reference = self.read_joint(Elem { node: j, defaults }, &mut body)?;
            }
        }
        let map = match merged_hinges {
            Some(h) => KeyMap::Merged(h),
            None => KeyMap::One(body.kind, reference),
        };
        self.raw.push(body);
        self.refs.push(map);
        self.read_children(node, Some(index), childclass)
    }

    fn read_inertial(&mut self, node: Node<'a, 'i>) -> Result<MassProps> {
        let cx = self.cx;
        let (pos, rot) = self.frame(node, &|a| node.attribute(a))?;
        let [mass] = cx
            .array::<1>(node, "mass")?
            .ok_or_else(|| cx.err(node, "<inertial> needs a mass"))?;
        if mass <= 0.0 {
            return Err(cx.err(node, format!("mass {mass} must be positive")));
        }
        let full = cx.array::<6>(node, "fullinertia")?;
        let diag = cx.array::<3>(node, "diaginertia")?;
        let inertia = match (diag, full) {
            (Some(d), None) => rot * Mat3::from_diagonal(Vec3::from_array(d)) * rot.transpose(),
            (None, Some(f)) => {
                if ["quat", "axisangle", "euler", "xyaxes", "zaxis"]
                    .iter()
                    .any(|a| node.has_attribute(*a))
                {
                    return Err(cx.err(node, "fullinertia and an orientation of the inertial frame both given"));
                }
                Mat3::from_rows([[f[0], f[3], f[4]], [f[3], f[1], f[5]], [f[4], f[5], f[2]]])
            }
            (Some(_), Some(_)) => return Err(cx.err(node, "both diaginertia and fullinertia given")),
            (None, None) => return Err(cx.err(node, "<inertial> needs diaginertia or fullinertia")),
        };
        check_inertia(&inertia).map_err(|m| cx.err(node, m))?;
        self.note_other_attributes(
            node,
            &[
                "pos",
                "quat",
                "axisangle",
                "euler",
                "xyaxes",
                "zaxis",
                "mass",
                "diaginertia",
                "fullinertia",
            ],
        );
        Ok(MassProps {
            mass,
            com: pos,
            inertia,
        })
    }

    /// Reads a `<joint>` into `body`; returns its `ref` (model coordinate = MuJoCo's − ref).
    fn read_joint(&mut self, j: Elem<'a, 'i>, body: &mut RawBody) -> Result<f64> {
        let cx = self.cx;
        let node = j.node;
        let num = |attr: &str| -> Result<Option<f64>> {
            j.get(attr)
                .map(|v| cx.array_of::<1>(node, attr, v).map(|a| a[0]))
                .transpose()
        };
        let ty = j.get("type").unwrap_or("hinge");
        let axis = match j.get("axis") {
            Some(v) => cx.unit(node, "axis", cx.array_of::<3>(node, "axis", v)?)?,
            None => Vec3::new(0.0, 0.0, 1.0),
        };
        let (kind, angular) = match ty {
            "hinge" => (RawKind::Hinge(axis), true),
            "slide" => (RawKind::Slide(axis), false),
            "ball" => (RawKind::Ball, true),
            "free" => (RawKind::Free, false),
            other => return Err(cx.err(node, format!("unknown joint type `{other}`"))),
        };
        let degree = self.compiler.degree && angular;
        let unit = |v: f64| if degree { v.to_radians() } else { v };
        body.kind = kind;
        if kind != RawKind::Free {
            if let Some(v) = j.get("pos") {
                body.anchor = Vec3::from_array(cx.array_of::<3>(node, "pos", v)?);
            }
        }
        let reference = num("ref")?.map_or(0.0, unit);
        let range = j.get("range").map(|v| cx.array_of::<2>(node, "range", v)).transpose()?;
        let limited = match j.get("limited").unwrap_or("auto") {
            "auto" => {
                if range.is_some() && !self.compiler.autolimits {
                    return Err(cx.err(node, "range given without limited while compiler autolimits is false"));
                }
                range.is_some()
            }
            v => parse_bool(&cx, node, "limited", v)?,
        };
        if limited {
            let [lo, hi] = range.ok_or_else(|| cx.err(node, "limited joint without range"))?;
            if lo > hi {
                return Err(cx.err(node, format!("range lower bound {lo} above upper bound {hi}")));
            }
            match kind {
                RawKind::Hinge(_) | RawKind::Slide(_) => {
                    body.range = Some((unit(lo) - reference, unit(hi) - reference));
                }
                _ => self.ignored.note(&format!("{ty} joint range")),
            }
        }
        body.stiffness = num("stiffness")?.unwrap_or(0.0);
        body.damping = num("damping")?.unwrap_or(0.0);
        body.armature = num("armature")?.unwrap_or(0.0);
        for (what, v) in [
            ("stiffness", body.stiffness),
            ("damping", body.damping),
            ("armature", body.armature),
        ] {
            if v < 0.0 {
                return Err(cx.err(node, format!("negative {what} {}", crate::error::Num(v))));
            }
        }
        body.spring_ref = num("springref")?.map_or(0.0, unit) - reference;
        if kind == RawKind::Free && (body.stiffness != 0.0 || body.damping != 0.0) {
            self.ignored.note("free joint stiffness and damping");
        }
        body.frictionloss = num("frictionloss")?.unwrap_or(0.0);
        if body.frictionloss < 0.0 {
            return Err(cx.err(node, format!("negative frictionloss {}", body.frictionloss)));
        }
        if body.frictionloss != 0.0 && !matches!(kind, RawKind::Hinge(_) | RawKind::Slide(_)) {
            self.ignored.note(&format!("{ty} joint frictionloss"));
            body.frictionloss = 0.0;
        }
        let frc_range = j
            .get("actuatorfrcrange")
            .map(|v| cx.array_of::<2>(node, "actuatorfrcrange", v))
            .transpose()?;
        if self.limited(
            node,
            j.get("actuatorfrclimited"),
            frc_range.is_some(),
            "actuatorfrcrange",
        )? {
            let [lo, hi] = frc_range.ok_or_else(|| cx.err(node, "actuatorfrclimited without actuatorfrcrange"))?;
            if lo.is_nan() || hi.is_nan() || lo > hi {
                return Err(cx.err(
                    node,
                    format!("actuatorfrcrange lower bound {lo} above upper bound {hi}"),
                ));
            }
            body.actuator_force_range = Some((lo, hi));
        }
        if let (Some(n), RawKind::Hinge(_) | RawKind::Slide(_)) = (node.attribute("name"), kind) {
            self.joint_refs.insert(n.to_string(), reference);
        }
        let known = [
            "name",
            "class",
            "type",
            "pos",
            "axis",
            "range",
            "limited",
            "ref",
            "springref",
            "stiffness",
            "damping",
            "armature",
            "frictionloss",
            "actuatorfrcrange",
            "actuatorfrclimited",
        ];
        let extra = node.attributes().map(|a| a.name()).chain(j.defaults.keys().copied());
        for a in extra.filter(|a| !known.contains(a)).collect::<Vec<_>>() {
            self.ignored.note(&format!("joint {a}"));
        }
        Ok(if matches!(kind, RawKind::Hinge(_) | RawKind::Slide(_)) {
            reference
        } else {
            0.0
        })
    }
}
