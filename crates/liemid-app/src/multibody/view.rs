//! The `--view` page of a multibody run: each body drawn with the shapes its model file
//! gives it (MJCF geoms of MuJoCo's default groups 0-2, URDF visuals; the collision geoms of
//! a body whose meshes are not read), the world's shapes (a floor), and on request each body
//! a box of its inertia's proportions about its centre of mass (always, for a body without
//! shapes) and each joint a line between its anchors on the two bodies.

use liemid::multibody::Link;
use liemid::so3::Quaternion;
use liemid::Vec3;

use super::scenario::MultibodyScenario;
use crate::shared::view::{Joint, Scene, ViewPage, ViewShape};
use liemid::multibody::ShapeKind;

/// Half the edges of the uniform box with body `i`'s mass and the diagonal of its inertia
/// (`I_xx = m (b² + c²) / 3` for half-edges `a, b, c`), at least `floor`.
fn half_extents(mass: f64, diagonal: [f64; 3], floor: f64) -> [f32; 3] {
    let [a, b, c] = diagonal;
    [b + c - a, a + c - b, a + b - c].map(|v| ((1.5 * v.max(0.0) / mass).sqrt().max(floor)) as f32)
}

/// The empty page of `sc`'s run.
pub fn page(sc: &MultibodyScenario) -> ViewPage {
    let model = &sc.model;
    let extent = model
        .joints
        .iter()
        .map(|j| j.anchor_parent.norm().max(j.anchor_child.norm()))
        .chain(model.bodies.iter().map(|b| b.com.norm()))
        .fold(0.0f64, f64::max)
        .max(1e-3);
    let boxes = model
        .bodies
        .iter()
        .map(|b| {
            let m = b.inertia.m;
            half_extents(b.mass, [m[0][0], m[1][1], m[2][2]], 0.02 * extent)
        })
        .collect();
    let f32s = |v: Vec3| [v.x as f32, v.y as f32, v.z as f32];
    let joints = model
        .joints
        .iter()
        .map(|j| {
            let (parent, parent_anchor) = match j.parent {
                Link::World => (None, f32s(j.anchor_parent)),
                Link::Body(p) => (Some(p), f32s(j.anchor_parent - model.bodies[p].com)),
            };
            Joint {
                parent,
                child: j.child,
                parent_anchor,
                child_anchor: f32s(j.anchor_child - model.bodies[j.child].com),
            }
        })
        .collect();
    // MuJoCo's default groups (0-2); a body with none of those drawn (its visual meshes are
    // not read) shows its other shapes (collision geoms, group 3), else its box of inertia.
    let mut shown_body = vec![false; model.bodies.len()];
    for s in sc.shapes.iter().filter(|s| s.shown_by_default()) {
        if let Some(b) = s.body {
            shown_body[b] = true;
        }
    }
    let shapes = sc
        .shapes
        .iter()
        .filter(|s| s.shown_by_default() || s.body.is_some_and(|b| !shown_body[b]))
        .map(|s| {
            let (kind, size) = match s.kind {
                ShapeKind::Plane { half } => ("plane", [half[0], half[1], 0.0]),
                ShapeKind::Sphere { radius } => ("sphere", [radius, 0.0, 0.0]),
                ShapeKind::Capsule { radius, half_length } => ("capsule", [radius, half_length, 0.0]),
                ShapeKind::Cylinder { radius, half_length } => ("cylinder", [radius, half_length, 0.0]),
                ShapeKind::Box { half } => ("box", half),
                ShapeKind::Ellipsoid { radii } => ("ellipsoid", radii),
            };
            // Body shapes are posed from the body's frame origin; the page moves the centre
            // of mass.
            let position = match s.body {
                Some(b) => s.position - model.bodies[b].com,
                None => s.position,
            };
            let q = Quaternion::from_matrix(&s.rotation);
            ViewShape {
                body: s.body,
                kind: kind.to_string(),
                size: size.map(|v| v as f32),
                position: f32s(position),
                quaternion: [q.w, q.x, q.y, q.z].map(|v| v as f32),
                rgba: s.rgba,
            }
        })
        .collect();
    ViewPage::new(
        Scene::Articulated {
            half_extents: boxes,
            joints,
            shapes,
        },
        &sc.name,
    )
}

/// The centre of mass of a body whose frame origin is `x` and attitude `q` (`w, x, y, z`),
/// with its centre `s` in body coordinates: `x + R(q) s`.
#[must_use]
pub fn centre(x: [f64; 3], q: [f64; 4], s: Vec3) -> [f64; 3] {
    let c = Vec3::new(x[0], x[1], x[2]) + Quaternion::new(q[0], q[1], q[2], q[3]).to_matrix() * s;
    [c.x, c.y, c.z]
}
