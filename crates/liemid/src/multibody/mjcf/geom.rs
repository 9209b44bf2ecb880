//! The mass properties of MJCF geoms (sphere, capsule, cylinder, box, ellipsoid; `size`,
//! `fromto`, `mass` or `density`) for bodies without an `<inertial>`, and the shapes geoms
//! draw (with `rgba`, a `material`'s colour and the visual `group`), meshes among them
//! (`<asset><mesh name file scale class>`, the name defaulting to the file's stem; the file
//! found as MuJoCo finds it: as it is when absolute, else under `compiler` `meshdir`, else
//! `assetdir`, each taken as it is when absolute, else relative to the main model file's
//! directory). A mesh's `refpos`/`refquat`, inline `vertex` data and builtin meshes are not
//! drawn (the shape says why).
//!
//! Reference: MuJoCo documentation, XML reference, `geom`, `mesh`, `compiler`.

use std::path::{Path, PathBuf};

use roxmltree::Node;

use super::super::shapes::{Collides, Shape, ShapeKind};
use super::super::xml::{rotation_to_z, MassProps};
use super::{Elem, State};
use crate::error::Result;
use crate::linalg::{Mat3, Vec3};

/// MuJoCo's default geom colour.
const DEFAULT_RGBA: [f32; 4] = [0.5, 0.5, 0.5, 1.0];

/// An `<asset><mesh>`: its file as written, and its scale.
pub(super) struct MeshAsset {
    file: Option<String>,
    scale: [f64; 3],
    /// Why the mesh is not drawn whatever its file (inline data, `refpos`).
    unsupported: Option<String>,
}

impl<'a, 'i> State<'a, 'i> {
    /// The colours of `<asset><material name rgba>` and the meshes of `<asset><mesh>`.
    pub(super) fn read_assets(&mut self, asset: Node<'a, 'i>) -> Result<()> {
        let cx = self.cx;
        for m in asset.children().filter(|c| c.has_tag_name("material")) {
            if let (Some(name), Some(rgba)) = (m.attribute("name"), cx.array::<4>(m, "rgba")?) {
                self.materials.insert(name, rgba.map(|c| c as f32));
            }
        }
        for m in asset.children().filter(|c| c.has_tag_name("mesh")) {
            let class = self.class_of(m, "main")?;
            let defaults = self.classes[class].mesh.clone();
            let get = |a: &str| m.attribute(a).or_else(|| defaults.get(a).copied());
            let file = get("file").map(str::to_string);
            let name = match (m.attribute("name"), &file) {
                (Some(n), _) => n.to_string(),
                (None, Some(f)) => Path::new(f)
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                (None, None) => return Err(cx.err(m, "a <mesh> needs a name or a file")),
            };
            let scale = match get("scale") {
                Some(v) => cx.array_of::<3>(m, "scale", v)?,
                None => [1.0; 3],
            };
            if !scale.iter().all(|c| c.is_finite() && *c != 0.0) {
                return Err(cx.err(m, "scale: three finite, non-zero factors"));
            }
            let unsupported = if file.is_none() {
                Some("a mesh without a file (inline vertex data or a builtin mesh) is not drawn".to_string())
            } else {
                ["refpos", "refquat"]
                    .into_iter()
                    .find(|a| get(a).is_some())
                    .map(|a| format!("a mesh with `{a}` is not drawn"))
            };
            if self
                .meshes
                .insert(
                    name.clone(),
                    MeshAsset {
                        file,
                        scale,
                        unsupported,
                    },
                )
                .is_some()
            {
                return Err(cx.err(m, format!("a second mesh named `{name}`")));
            }
        }
        Ok(())
    }

    /// Where the mesh file `file` is, as MuJoCo looks for it; `Err` (why) for a model
    /// parsed from text.
    fn mesh_path(&self, file: &str) -> std::result::Result<PathBuf, String> {
        let Some(dir) = &self.dir else {
            return Err("the model was parsed from text, with no directory to find its files in".into());
        };
        let f = Path::new(file);
        if f.is_absolute() {
            return Ok(f.to_path_buf());
        }
        Ok(
            match self.compiler.meshdir.as_ref().or(self.compiler.assetdir.as_ref()) {
                Some(d) if Path::new(d).is_absolute() => Path::new(d).join(f),
                Some(d) => dir.join(d).join(f),
                None => dir.join(f),
            },
        )
    }

    /// The mesh files of the assets that exist: the model's inputs besides its XML files.
    pub(super) fn mesh_files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = self
            .meshes
            .values()
            .filter_map(|m| m.file.as_deref())
            .filter_map(|f| self.mesh_path(f).ok())
            .filter(|p| p.is_file())
            .collect();
        files.sort();
        files.dedup();
        files
    }

    /// The colour (`rgba`, else the material's, else MuJoCo's grey) and the visual group of
    /// a geom.
    fn appearance(&self, g: &Elem<'a, 'i>) -> Result<([f32; 4], u8)> {
        let cx = self.cx;
        let node = g.node;
        let explicit = match g.get("rgba") {
            Some(v) => Some(cx.array_of::<4>(node, "rgba", v)?.map(|c| c as f32)),
            None => None,
        };
        let material = g.get("material").and_then(|m| self.materials.get(m).copied());
        let rgba = explicit.or(material).unwrap_or(DEFAULT_RGBA);
        if rgba.iter().any(|c| !(0.0..=1.0).contains(c)) {
            return Err(cx.err(node, "rgba: each component must lie in [0, 1]"));
        }
        let group = match g.get("group") {
            Some(v) => {
                let [k] = cx.array_of::<1>(node, "group", v)?;
                if !(0.0..=5.0).contains(&k) || k.fract() != 0.0 {
                    return Err(cx.err(node, format!("group {k}: expected a whole number from 0 to 5")));
                }
                k as u8
            }
            None => 0,
        };
        Ok((rgba, group))
    }

    /// The shape of a mesh geom: its asset's file (found, or why not) and scale, posed by
    /// the geom's own frame (see [`ShapeKind::Mesh`] and the module `shapes` on why that
    /// is where MuJoCo draws it), with the box of the geom's `size` to stand in for a file
    /// that gives no mesh.
    fn mesh_shape(&mut self, g: &Elem<'a, 'i>) -> Result<Shape> {
        let cx = self.cx;
        let node = g.node;
        let mesh = g.get("mesh").unwrap_or_default();
        let name = node.attribute("name").unwrap_or(mesh).to_string();
        let (file, path, scale) = match self.meshes.get(mesh) {
            None if mesh.is_empty() => (String::new(), Err("the geom names no mesh".to_string()), [1.0; 3]),
            None => (
                mesh.to_string(),
                Err(format!("no <mesh name=\"{mesh}\"> in <asset>")),
                [1.0; 3],
            ),
            Some(a) => {
                let file = a.file.clone().unwrap_or_default();
                let path = match &a.unsupported {
                    Some(why) => Err(why.clone()),
                    None => self.mesh_path(&file),
                };
                (file, path, a.scale)
            }
        };
        let size = match g.get("size") {
            Some(v) => cx.floats(node, "size", v, 1, 3)?,
            None => Vec::new(),
        };
        let half =
            (size.len() == 3 && size.iter().all(|s| s.is_finite() && *s > 0.0)).then(|| [size[0], size[1], size[2]]);
        let (position, rotation) = self.frame(node, &|a| g.get(a))?;
        let (rgba, group) = self.appearance(g)?;
        // A mesh that touches is its file's convex hull (as MuJoCo collides meshes); without
        // its file it does not touch, noted.
        let mut collision = self.geom_collision(g)?;
        if collision.is_some() && path.is_err() {
            self.ignored
                .note("mesh geom contacts (not simulated where the mesh file is not read)");
            collision = None;
        }
        Ok(Shape {
            body: None,
            kind: ShapeKind::Mesh {
                name,
                file,
                path,
                scale,
                half,
            },
            position,
            rotation,
            rgba,
            group,
            collision,
        })
    }

    /// The shape a geom draws, in its body's frame; `None` for a height field or an SDF
    /// (their files are not read: noted once).
    pub(super) fn geom_shape(&mut self, g: &Elem<'a, 'i>) -> Result<Option<Shape>> {
        let cx = self.cx;
        let node = g.node;
        let ty = g.get("type").unwrap_or("sphere");
        if ty == "mesh" {
            return self.mesh_shape(g).map(Some);
        }
        if matches!(ty, "hfield" | "sdf") {
            self.ignored
                .note(&format!("{ty} geoms (not drawn: the files are not read)"));
            return Ok(None);
        }
        let (size, position, rotation, half_length) = self.geom_frame(g, ty)?;
        let at = |k: usize| size.get(k).copied().unwrap_or(0.0);
        let kind = match ty {
            "plane" => ShapeKind::Plane { half: [at(0), at(1)] },
            "sphere" => ShapeKind::Sphere { radius: at(0) },
            "capsule" => ShapeKind::Capsule {
                radius: at(0),
                half_length: half_length.unwrap_or(at(1)),
            },
            "cylinder" => ShapeKind::Cylinder {
                radius: at(0),
                half_length: half_length.unwrap_or(at(1)),
            },
            "box" => ShapeKind::Box {
                half: [at(0), at(1), half_length.unwrap_or(at(2))],
            },
            "ellipsoid" => ShapeKind::Ellipsoid {
                radii: [at(0), at(1), half_length.unwrap_or(at(2))],
            },
            other => return Err(cx.err(node, format!("unknown geom type `{other}`"))),
        };
        let finite = match &kind {
            ShapeKind::Plane { half } => half.iter().all(|s| s.is_finite() && *s >= 0.0),
            ShapeKind::Sphere { radius } => radius.is_finite() && *radius > 0.0,
            ShapeKind::Capsule { radius, half_length } | ShapeKind::Cylinder { radius, half_length } => {
                radius.is_finite() && *radius > 0.0 && half_length.is_finite() && *half_length >= 0.0
            }
            ShapeKind::Box { half } => half.iter().all(|s| s.is_finite() && *s > 0.0),
            ShapeKind::Ellipsoid { radii } => radii.iter().all(|s| s.is_finite() && *s > 0.0),
            ShapeKind::Mesh { .. } => true,
        };
        if !finite {
            return Err(cx.err(node, format!("a {ty} geom needs positive, finite size values")));
        }
        let (rgba, group) = self.appearance(g)?;
        Ok(Some(Shape {
            body: None,
            kind,
            position,
            rotation,
            rgba,
            group,
            collision: self.geom_collision(g)?,
        }))
    }

    /// A geom's `size` values, its pose in the body's frame and, with `fromto`, the half
    /// length it sets. MuJoCo reads `fromto` for capsules, cylinders, boxes and ellipsoids
    /// only (a class default's `fromto` does not move a plane or a sphere of that class).
    fn geom_frame(&self, g: &Elem<'a, 'i>, ty: &str) -> Result<(Vec<f64>, Vec3, Mat3, Option<f64>)> {
        let cx = self.cx;
        let node = g.node;
        let size = match g.get("size") {
            Some(v) => cx.floats(node, "size", v, 1, 3)?,
            None => Vec::new(),
        };
        let (position, rotation) = self.frame(node, &|a| g.get(a))?;
        let fromto = g
            .get("fromto")
            .filter(|_| matches!(ty, "capsule" | "cylinder" | "box" | "ellipsoid"));
        let Some(v) = fromto else {
            return Ok((size, position, rotation, None));
        };
        let f = cx.array_of::<6>(node, "fromto", v)?;
        let (a, b) = (Vec3::new(f[0], f[1], f[2]), Vec3::new(f[3], f[4], f[5]));
        let rotation = rotation_to_z(cx.unit(node, "fromto", (b - a).to_array())?);
        Ok((size, (a + b) * 0.5, rotation, Some(0.5 * (b - a).norm())))
    }

    /// A geom's contact properties (`contype`, `conaffinity`, `friction`, `condim`); `None`
    /// when it touches nothing (both masks 0). The soft-contact parameters (`solref`,
    /// `solimp`, `margin`, `gap`, `priority`, `solmix`) are noted: liemid's contacts are
    /// hard. `condim` 1 is frictionless; 4 and 6 (torsional, rolling friction) keep the
    /// sliding friction only, with a note.
    fn geom_collision(&mut self, g: &Elem<'a, 'i>) -> Result<Option<Collides>> {
        let cx = self.cx;
        let node = g.node;
        let mask = |attr: &str| -> Result<u32> {
            match g.get(attr) {
                None => Ok(1),
                Some(v) => {
                    let [k] = cx.array_of::<1>(node, attr, v)?;
                    if !(0.0..=f64::from(u32::MAX)).contains(&k) || k.fract() != 0.0 {
                        return Err(cx.err(
                            node,
                            format!("{attr} {k}: expected a whole number from 0 to 4294967295"),
                        ));
                    }
                    Ok(k as u32)
                }
            }
        };
        let (contype, conaffinity) = (mask("contype")?, mask("conaffinity")?);
        if contype == 0 && conaffinity == 0 {
            return Ok(None);
        }
        let condim = match g.get("condim") {
            None => 3,
            Some(v) => {
                let [k] = cx.array_of::<1>(node, "condim", v)?;
                match k {
                    1.0 => 1,
                    3.0 => 3,
                    4.0 | 6.0 => {
                        self.ignored
                            .note("geom condim 4 and 6 (torsional and rolling friction; sliding friction kept)");
                        3
                    }
                    _ => return Err(cx.err(node, format!("condim {k}: expected 1, 3, 4 or 6"))),
                }
            }
        };
        let friction = match g.get("friction") {
            None => 1.0,
            Some(v) => {
                let f = cx.floats(node, "friction", v, 1, 3)?;
                if f.iter().any(|x| !x.is_finite() || *x < 0.0) {
                    return Err(cx.err(node, "friction: each value must be finite and not negative"));
                }
                f[0]
            }
        };
        for attr in ["solref", "solimp", "margin", "gap", "priority", "solmix"] {
            if g.get(attr).is_some() {
                self.ignored
                    .note(&format!("geom {attr} (soft-contact parameter: contacts are hard here)"));
            }
        }
        Ok(Some(Collides {
            name: node.attribute("name").map(str::to_string),
            contype,
            conaffinity,
            friction: if condim == 1 { 0.0 } else { friction },
        }))
    }

    /// The mass properties of a geom in its body's frame (zero for a massless geom).
    pub(super) fn geom_mass(&mut self, g: Elem<'a, 'i>) -> Result<MassProps> {
        let cx = self.cx;
        let node = g.node;
        let ty = g.get("type").unwrap_or("sphere");
        let mass_attr = g.get("mass").map(|v| cx.array_of::<1>(node, "mass", v)).transpose()?;
        let density = g
            .get("density")
            .map(|v| cx.array_of::<1>(node, "density", v))
            .transpose()?;
        if let Some([m]) = mass_attr {
            if m < 0.0 {
                return Err(cx.err(node, format!("mass {m} is negative")));
            }
        }
        if let Some([d]) = density {
            if d < 0.0 {
                return Err(cx.err(node, format!("density {d} is negative")));
            }
        }
        if mass_attr == Some([0.0]) || (mass_attr.is_none() && density == Some([0.0])) {
            return Ok(MassProps::ZERO);
        }
        match ty {
            "sphere" | "capsule" | "cylinder" | "box" | "ellipsoid" => {}
            "mesh" | "hfield" | "sdf" => {
                let what = g.get("mesh").or(g.get("hfield")).unwrap_or("(unnamed)");
                return Err(cx.err(
                    node,
                    format!(
                        "the body has no <inertial>, so its mass would come from this {ty} geom `{what}`, whose \
                         file is not read: give the body an <inertial>"
                    ),
                ));
            }
            "plane" => return Err(cx.err(node, "a plane has no finite mass: planes belong in <worldbody>")),
            other => return Err(cx.err(node, format!("unknown geom type `{other}`"))),
        }
        let (size, pos, rot, half_length) = self.geom_frame(&g, ty)?;
        let needed = match (ty, half_length) {
            ("sphere", _) => 1,
            ("capsule" | "cylinder", None) => 2,
            ("capsule" | "cylinder", Some(_)) => 1,
            (_, None) => 3,
            (_, Some(_)) => 2,
        };
        if size.len() < needed || size[..needed].iter().any(|&s| s <= 0.0) {
            return Err(cx.err(node, format!("a {ty} geom needs {needed} positive size values")));
        }
        let s = |k: usize| {
            if k == needed && half_length.is_some() {
                half_length.unwrap_or(0.0)
            } else {
                size[k]
            }
        };
        use std::f64::consts::PI;
        let (volume, unit_inertia): (f64, Box<dyn Fn(f64) -> Vec3>) = match ty {
            "sphere" => {
                let r = s(0);
                (
                    4.0 / 3.0 * PI * r.powi(3),
                    Box::new(move |m| Vec3::new(1.0, 1.0, 1.0) * (0.4 * m * r * r)),
                )
            }
            "box" | "ellipsoid" => {
                let (a, b, c) = (s(0), s(1), s(2));
                let (v, k) = if ty == "box" {
                    (8.0 * a * b * c, 1.0 / 3.0)
                } else {
                    (4.0 / 3.0 * PI * a * b * c, 0.2)
                };
                (
                    v,
                    Box::new(move |m| Vec3::new(b * b + c * c, a * a + c * c, a * a + b * b) * (k * m)),
                )
            }
            "cylinder" => {
                let (r, h) = (s(0), 2.0 * s(1));
                (
                    PI * r * r * h,
                    Box::new(move |m| {
                        let t = m * (3.0 * r * r + h * h) / 12.0;
                        Vec3::new(t, t, 0.5 * m * r * r)
                    }),
                )
            }
            _ => {
                let (r, h) = (s(0), 2.0 * s(1));
                let (v_cyl, v_sph) = (PI * r * r * h, 4.0 / 3.0 * PI * r.powi(3));
                (
                    v_cyl + v_sph,
                    Box::new(move |m| {
                        let (mc, ms) = (m * v_cyl / (v_cyl + v_sph), m * v_sph / (v_cyl + v_sph));
                        let t = mc * (3.0 * r * r + h * h) / 12.0 + ms * (0.4 * r * r + 0.25 * h * h + 0.375 * h * r);
                        Vec3::new(t, t, 0.5 * mc * r * r + 0.4 * ms * r * r)
                    }),
                )
            }
        };
        let m = match mass_attr {
            Some([m]) => m,
            None => density.map_or(1000.0, |d| d[0]) * volume,
        };
        let local = MassProps {
            mass: m,
            com: Vec3::ZERO,
            inertia: Mat3::from_diagonal(unit_inertia(m)),
        };
        Ok(local.transformed(pos, &rot))
    }
}
