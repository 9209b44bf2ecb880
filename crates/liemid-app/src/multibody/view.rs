//! The `--view` page of a multibody run: each body drawn with the shapes its model file
//! gives it (MJCF geoms of MuJoCo's default groups 0-2, URDF visuals; the collision geoms of
//! a body none of whose shapes of those groups can be drawn), the world's shapes (a floor),
//! and on request each body a box of its inertia's proportions about its centre of mass
//! (always, for a body without shapes) and each joint a line between its anchors on the two
//! bodies.
//!
//! Meshes are read from their files here, when a page is made (never for a run without
//! one), through the library's bounded reading ([`Mesh::read`]); the files are the model's
//! inputs, which no output may replace. A mesh whose file gives none is drawn as the box of
//! its geom's `size` when the geom gives one, else not at all, and a [`ModelNote`] names the
//! geom, the file and why. The meshes of a page hold at most [`MESH_BUDGET`] bytes: above
//! it, each mesh is simplified ([`Mesh::simplified`]) to its share of the budget, said in a
//! note per file.

use std::collections::HashMap;
use std::path::PathBuf;

use liemid::multibody::{Link, Mesh, ModelNote, Shape};
use liemid::so3::Quaternion;
use liemid::Vec3;

use super::scenario::MultibodyScenario;
use crate::shared::view::{Joint, Scene, ViewMesh, ViewPage, ViewShape};
use liemid::multibody::ShapeKind;

/// Bytes of mesh data (vertices and indices, four bytes a number, before base64) a page
/// holds at most: about 110,000 triangles of closed meshes, 2.7 MB of the page.
pub const MESH_BUDGET: usize = 2_000_000;

/// Triangles a simplified mesh is allowed at least, however many meshes share the budget.
pub const MIN_MESH_TRIANGLES: usize = 200;

/// Half the edges of the uniform box with body `i`'s mass and the diagonal of its inertia
/// (`I_xx = m (b² + c²) / 3` for half-edges `a, b, c`), at least `floor`.
fn half_extents(mass: f64, diagonal: [f64; 3], floor: f64) -> [f32; 3] {
    let [a, b, c] = diagonal;
    [b + c - a, a + c - b, a + b - c].map(|v| ((1.5 * v.max(0.0) / mass).sqrt().max(floor)) as f32)
}

/// The meshes of a page: each file read once.
#[derive(Default)]
struct Meshes {
    /// By file: the mesh's index in `list`, or why the file gives none.
    by_path: HashMap<PathBuf, Result<usize, String>>,
    /// The meshes read, with the file as the model names it.
    list: Vec<(Mesh, String)>,
}

impl Meshes {
    /// The mesh of `kind` (a mesh shape): its index, or why there is none.
    fn get(&mut self, kind: &ShapeKind) -> Result<usize, String> {
        let ShapeKind::Mesh { file, path, .. } = kind else {
            return Err("not a mesh".into());
        };
        let path = path.as_ref().map_err(Clone::clone)?;
        if let Some(r) = self.by_path.get(path) {
            return r.clone();
        }
        let r = Mesh::read(path).map(|m| {
            self.list.push((m, file.clone()));
            self.list.len() - 1
        });
        self.by_path.insert(path.clone(), r.clone());
        r
    }

    /// Whether `s` draws anything: a primitive, a mesh read, or a mesh's stand-in box.
    fn draws(&mut self, s: &Shape) -> bool {
        match &s.kind {
            ShapeKind::Mesh { half, .. } => half.is_some() || self.get(&s.kind).is_ok(),
            _ => true,
        }
    }
}

/// The meshes as the page holds them: each within its share of [`MESH_BUDGET`], with a
/// note for each one simplified.
fn budgeted(list: &[(Mesh, String)], notes: &mut Vec<ModelNote>) -> Vec<ViewMesh> {
    let bytes: usize = list
        .iter()
        .map(|(m, _)| 12 * (m.vertices.len() + m.triangles.len()))
        .sum();
    let share = (MESH_BUDGET as f64 / bytes.max(1) as f64).min(1.0);
    list.iter()
        .map(|(m, file)| {
            let cap = ((m.triangles.len() as f64 * share) as usize).max(MIN_MESH_TRIANGLES);
            let kept = m.simplified(cap);
            if kept.triangles.len() < m.triangles.len() {
                notes.push(ModelNote::MeshSimplified {
                    file: file.clone(),
                    triangles: m.triangles.len(),
                    kept: kept.triangles.len(),
                });
            }
            ViewMesh {
                vertices: kept.vertices.iter().flatten().copied().collect(),
                indices: kept.triangles.iter().flatten().copied().collect(),
            }
        })
        .collect()
}

/// The empty page of `sc`'s run, and what it could not draw as the file says.
pub fn page(sc: &MultibodyScenario) -> (ViewPage, Vec<ModelNote>) {
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
    // MuJoCo's default groups (0-2); a body with none of those drawn (its visual meshes
    // missing) shows its other shapes (collision geoms, group 3), else its box of inertia.
    let mut meshes = Meshes::default();
    let mut shown_body = vec![false; model.bodies.len()];
    for s in sc.shapes.iter().filter(|s| s.shown_by_default()) {
        if let Some(b) = s.body {
            if meshes.draws(s) {
                shown_body[b] = true;
            }
        }
    }
    let mut notes = Vec::new();
    let mut drawn = Vec::new();
    for s in sc
        .shapes
        .iter()
        .filter(|s| s.shown_by_default() || s.body.is_some_and(|b| !shown_body[b]))
    {
        let (kind, size, mesh) = match &s.kind {
            ShapeKind::Plane { half } => ("plane", [half[0], half[1], 0.0], None),
            ShapeKind::Sphere { radius } => ("sphere", [*radius, 0.0, 0.0], None),
            ShapeKind::Capsule { radius, half_length } => ("capsule", [*radius, *half_length, 0.0], None),
            ShapeKind::Cylinder { radius, half_length } => ("cylinder", [*radius, *half_length, 0.0], None),
            ShapeKind::Box { half } => ("box", *half, None),
            ShapeKind::Ellipsoid { radii } => ("ellipsoid", *radii, None),
            ShapeKind::Mesh {
                name,
                file,
                scale,
                half,
                ..
            } => match meshes.get(&s.kind) {
                Ok(k) => ("mesh", *scale, Some(k)),
                Err(reason) => {
                    let body = match s.body {
                        Some(b) => format!("body `{}`", model.bodies[b].name),
                        None => "the world".into(),
                    };
                    notes.push(ModelNote::MeshNotDrawn {
                        geom: format!("`{name}` on {body}"),
                        file: file.clone(),
                        reason,
                        boxed: half.is_some(),
                    });
                    match half {
                        Some(h) => ("box", *h, None),
                        None => continue,
                    }
                }
            },
        };
        drawn.push((s, kind, size, mesh));
    }
    let shapes = drawn
        .into_iter()
        .map(|(s, kind, size, mesh)| {
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
                mesh,
                position: f32s(position),
                quaternion: [q.w, q.x, q.y, q.z].map(|v| v as f32),
                rgba: s.rgba,
            }
        })
        .collect();
    let meshes = budgeted(&meshes.list, &mut notes);
    let page = ViewPage::new(
        Scene::Articulated {
            half_extents: boxes,
            joints,
            shapes,
            meshes,
            // A model with contacts: its touching contacts and their forces in each frame.
            contact_slots: if model.collision.any() {
                crate::shared::view::MAX_DRAWN_CONTACTS
            } else {
                0
            },
        },
        &sc.name,
    );
    (page, notes)
}

/// The centre of mass of a body whose frame origin is `x` and attitude `q` (`w, x, y, z`),
/// with its centre `s` in body coordinates: `x + R(q) s`.
#[must_use]
pub fn centre(x: [f64; 3], q: [f64; 4], s: Vec3) -> [f64; 3] {
    let c = Vec3::new(x[0], x[1], x[2]) + Quaternion::new(q[0], q[1], q[2], q[3]).to_matrix() * s;
    [c.x, c.y, c.z]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of `n × n` squares (two triangles each) in the plane z = 0.
    fn sheet(n: u32) -> Mesh {
        let vertices = (0..=n)
            .flat_map(|i| (0..=n).map(move |j| [i as f32 / n as f32, j as f32 / n as f32, 0.0]))
            .collect();
        let at = |i: u32, j: u32| i * (n + 1) + j;
        let triangles = (0..n)
            .flat_map(|i| {
                (0..n).flat_map(move |j| {
                    [
                        [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                        [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
                    ]
                })
            })
            .collect();
        Mesh { vertices, triangles }
    }

    /// Meshes over the budget are simplified to their shares, each said in a note; meshes
    /// within it are kept whole.
    #[test]
    fn meshes_over_the_budget_are_simplified_with_a_note() {
        let mut notes = Vec::new();
        let small = budgeted(&[(sheet(10), "small.stl".into())], &mut notes);
        assert!(notes.is_empty());
        assert_eq!(small[0].indices.len(), 3 * 200);
        let list = [(sheet(300), "big.stl".into()), (sheet(200), "bigger.obj".into())];
        let kept = budgeted(&list, &mut notes);
        let bytes: usize = kept.iter().map(ViewMesh::bytes).sum();
        assert!(bytes <= MESH_BUDGET, "{bytes} bytes");
        assert_eq!(notes.len(), 2);
        assert!(
            notes[0].to_string().contains("`big.stl` is drawn simplified"),
            "{}",
            notes[0]
        );
    }
}
