//! Collision detection for the contact step: the model's touching shapes as `parry3d`
//! shapes, a uniform grid of bounding spheres as the broad phase, parry's contact manifolds as the
//! narrow phase, and each manifold point as a [`ContactPoint`] whose gap and slide can be
//! evaluated at any configuration (the drift's end) without detecting again.
//!
//! A point's gap is `φ = n·(x_a − x_b) − ρ_a − ρ_b`, with `x_a`, `x_b` material points of
//! the two bodies and `ρ` the rounding radius of a sphere or capsule (its core point is on
//! the centre or the axis, so a rolling ball keeps its exact gap); `n` turns with body `b`
//! (a face or the floor), or, when both shapes are round, is the direction between the two
//! core points (two balls: the exact gap). Flat features (box corners on a face) are exact
//! with material points.
//!
//! Reference: parry3d documentation (contact manifolds); MuJoCo documentation, Computation,
//! "Collision detection" (the filters).

use parry3d_f64::math::{Matrix as PMat, Pose, Rotation as PRot, Vector as PVec};
use parry3d_f64::query::{ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher};
use parry3d_f64::shape::SharedShape;

use crate::linalg::{Mat3, Vec3};

use super::super::shapes::{Shape, ShapeKind};
use super::{boxes, Collision};

/// One shape of the contact geometry, posed relative to its body's centre of mass.
#[derive(Clone)]
struct Collider {
    body: Option<usize>,
    shape: SharedShape,
    /// Offset from the centre of mass and attitude in the body frame (world: absolute).
    offset: Vec3,
    rotation: Mat3,
    /// The rounding radius (sphere, capsule), 0 otherwise.
    round: f64,
    /// Bounding radius about `offset` (infinite for a plane).
    radius: f64,
    plane: bool,
    friction: f64,
    contype: u32,
    conaffinity: u32,
}

/// The model's touching shapes, ready for detection (built once per system).
#[derive(Clone)]
pub(in crate::multibody) struct ContactGeometry {
    colliders: Vec<Collider>,
    /// Body pairs never in contact (excluded, or parent and child), sorted, the world as
    /// `usize::MAX`.
    excluded: Vec<(usize, usize)>,
    /// The largest finite bounding radius: the model's contact length scale.
    pub(in crate::multibody) length: f64,
    /// Per body, the farthest point of its shapes from its centre of mass.
    pub(in crate::multibody) reach: Vec<f64>,
    /// Newton's coefficient of restitution.
    pub(in crate::multibody) restitution: f64,
}

impl core::fmt::Debug for ContactGeometry {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ContactGeometry")
            .field("shapes", &self.colliders.len())
            .finish_non_exhaustive()
    }
}

/// Scratch of the broad phase.
#[derive(Clone, Debug, Default)]
pub(in crate::multibody) struct Broad {
    extents: Vec<f64>,
    cells: Vec<([i64; 3], usize)>,
    large: Vec<usize>,
}

/// One contact point of a step: the bodies, the material points and the normal.
#[derive(Clone, Copy, Debug, Default)]
pub(in crate::multibody) struct ContactPoint {
    pub a: Option<usize>,
    pub b: Option<usize>,
    /// Core points relative to the centres of mass, in the bodies' frames (world: absolute).
    pub pa: Vec3,
    pub pb: Vec3,
    /// Rounding radii.
    pub ra: f64,
    pub rb: f64,
    /// The normal in `b`'s frame (from `b` to `a`), when `b`'s feature is flat.
    pub nb: Vec3,
    /// Both features round: the normal joins the core points.
    pub round: bool,
    pub mu: f64,
    /// The surface material points (for the slide over a step) in the bodies' frames.
    pub ma: Vec3,
    pub mb: Vec3,
    /// Their world positions at the step's start, and the start's tangents.
    pub xa0: Vec3,
    pub xb0: Vec3,
    /// The bodies' centres and attitudes at the step's start (a round side's slide).
    pub ca0: Vec3,
    pub cb0: Vec3,
    pub rota0: Mat3,
    pub rotb0: Mat3,
    pub t1: Vec3,
    pub t2: Vec3,
}

fn to_p(v: Vec3) -> PVec {
    PVec::new(v.x, v.y, v.z)
}

fn from_p(v: PVec) -> Vec3 {
    Vec3::new(v.x, v.y, v.z)
}

fn rot_p(r: &Mat3) -> PRot {
    let m = &r.m;
    let mat = PMat::from_cols(
        PVec::new(m[0][0], m[1][0], m[2][0]),
        PVec::new(m[0][1], m[1][1], m[2][1]),
        PVec::new(m[0][2], m[1][2], m[2][2]),
    );
    PRot::from_mat3(&mat).normalize()
}

/// The world position of a point `p` of body `i` (relative to its centre of mass).
#[inline]
pub(in crate::multibody) fn world(body: Option<usize>, p: Vec3, c: &[Vec3], r: &[Mat3]) -> Vec3 {
    body.map_or(p, |i| c[i] + r[i] * p)
}

/// A body's attitude (the world's: identity).
#[inline]
pub(in crate::multibody) fn attitude(body: Option<usize>, r: &[Mat3]) -> &Mat3 {
    body.map_or(&Mat3::IDENTITY, |i| &r[i])
}

/// Two unit vectors completing the unit `n` to a right-handed basis.
pub(in crate::multibody) fn tangents(n: Vec3) -> (Vec3, Vec3) {
    let helper = if n.x.abs() < 0.6 {
        Vec3::new(1.0, 0.0, 0.0)
    } else {
        Vec3::new(0.0, 1.0, 0.0)
    };
    let t1 = helper - n * n.dot(helper);
    let t1 = t1 * (1.0 / t1.norm());
    (t1, n.cross(t1))
}

impl ContactPoint {
    /// The normal and the core points' world positions at `(c, R)`.
    #[inline]
    pub(in crate::multibody) fn frame(&self, c: &[Vec3], r: &[Mat3]) -> (Vec3, Vec3, Vec3) {
        let xa = world(self.a, self.pa, c, r);
        let xb = world(self.b, self.pb, c, r);
        let n = if self.round {
            let d = xa - xb;
            let l = d.norm();
            if l > 0.0 {
                d * (1.0 / l)
            } else {
                *attitude(self.b, r) * self.nb
            }
        } else {
            *attitude(self.b, r) * self.nb
        };
        (n, xa, xb)
    }

    /// The gap at `(c, R)` (negative: penetration).
    #[inline]
    pub(in crate::multibody) fn gap(&self, c: &[Vec3], r: &[Mat3]) -> f64 {
        let (n, xa, xb) = self.frame(c, r);
        n.dot(xa - xb) - self.ra - self.rb
    }

    /// The slide of the contact since the step's start, on the start's tangents. A flat
    /// side's contact is a material point (a box corner: pivoting about it keeps it exactly);
    /// a round side's is where it rolls to: the centre's displacement plus the start's
    /// lever `x₀ − c₀` turned by the rotation vector `log(R R₀ᵀ)`, which vanishes exactly for
    /// rolling without slip at any angle (a material point of a rolling ball moves by
    /// `ρ (θ − sin θ)`, and holding it still makes the ball roll fast by O(h)).
    #[inline]
    pub(in crate::multibody) fn slide(&self, c: &[Vec3], r: &[Mat3]) -> (f64, f64) {
        let moved = |body: Option<usize>, round: f64, m: Vec3, x0: Vec3, c0: Vec3, r0: &Mat3| match body {
            None => Vec3::ZERO,
            Some(i) if round > 0.0 => {
                let phi = crate::so3::log(&(r[i] * r0.transpose()));
                (c[i] - c0) + phi.cross(x0 - c0)
            }
            Some(i) => c[i] + r[i] * m - x0,
        };
        let d = moved(self.a, self.ra, self.ma, self.xa0, self.ca0, &self.rota0)
            - moved(self.b, self.rb, self.mb, self.xb0, self.cb0, &self.rotb0);
        (d.dot(self.t1), d.dot(self.t2))
    }

    /// The same material points with the step's start at `(c, R)`, the tangents from the
    /// normal there (a point found at a drift's end, taken into the step's problem).
    pub(in crate::multibody) fn rebase(&mut self, c: &[Vec3], r: &[Mat3]) {
        self.xa0 = world(self.a, self.ma, c, r);
        self.xb0 = world(self.b, self.mb, c, r);
        self.ca0 = self.a.map_or(Vec3::ZERO, |i| c[i]);
        self.cb0 = self.b.map_or(Vec3::ZERO, |i| c[i]);
        self.rota0 = *attitude(self.a, r);
        self.rotb0 = *attitude(self.b, r);
        let (_, n) = self.application(c, r);
        (self.t1, self.t2) = tangents(n);
    }

    /// The point where the contact's forces act at `(c, R)` and the normal there: on the
    /// normal through `a`'s contact point, halfway across the gap (both forces of the pair
    /// act at it, so they have no moment). Not halfway to `b`'s point: `b`'s point is where
    /// the contact was at the step's start, and a rolling ball has moved on from it.
    #[inline]
    pub(in crate::multibody) fn application(&self, c: &[Vec3], r: &[Mat3]) -> (Vec3, Vec3) {
        let (n, xa, xb) = self.frame(c, r);
        let gap = n.dot(xa - xb) - self.ra - self.rb;
        (xa - n * (self.ra + 0.5 * gap), n)
    }
}

impl ContactGeometry {
    /// The contact geometry of `collision` for bodies whose centres of mass are `com` (body
    /// frame), `parents` the tree's parent of each body; `None` when nothing can touch.
    ///
    /// # Errors
    /// A plane on a moving body (MuJoCo's planes are static), named.
    pub(in crate::multibody) fn new(
        collision: &Collision,
        com: &[Vec3],
        parents: &[Option<usize>],
        body_names: &[String],
    ) -> core::result::Result<Option<Self>, String> {
        if !collision.any() {
            return Ok(None);
        }
        for s in &collision.shapes {
            if let (ShapeKind::Plane { .. }, Some(b)) = (&s.kind, s.body) {
                let name = s
                    .collision
                    .as_ref()
                    .and_then(|c| c.name.as_deref())
                    .unwrap_or("(unnamed)");
                return Err(format!(
                    "plane geom {name} on body {}: a plane touches things only as static ground (put it in the worldbody, or give it contype=\"0\" conaffinity=\"0\")",
                    body_names[b]
                ));
            }
        }
        let colliders: Vec<Collider> = collision.shapes.iter().filter_map(|s| collider(s, com)).collect();
        let mut reach = vec![0.0f64; com.len()];
        for k in &colliders {
            if let Some(b) = k.body {
                reach[b] = reach[b].max(k.offset.norm() + k.radius);
            }
        }
        let key = |b: Option<usize>| b.unwrap_or(usize::MAX);
        let mut excluded: Vec<(usize, usize)> = collision
            .exclude
            .iter()
            .map(|&(x, y)| (key(x).min(key(y)), key(x).max(key(y))))
            .collect();
        if !collision.parent_contacts {
            for (i, p) in parents.iter().enumerate() {
                if let Some(p) = p {
                    excluded.push(((*p).min(i), (*p).max(i)));
                }
            }
        }
        excluded.sort_unstable();
        excluded.dedup();
        let length = colliders
            .iter()
            .filter(|c| c.radius.is_finite())
            .fold(0.0f64, |m, c| m.max(c.radius));
        Ok(Some(ContactGeometry {
            colliders,
            excluded,
            length: if length > 0.0 { length } else { 1.0 },
            reach,
            restitution: collision.restitution,
        }))
    }

    fn excluded(&self, x: Option<usize>, y: Option<usize>) -> bool {
        let (x, y) = (x.unwrap_or(usize::MAX), y.unwrap_or(usize::MAX));
        self.excluded.binary_search(&(x.min(y), x.max(y))).is_ok()
    }

    /// The contact points at `(c, R)` whose gap is below `margin(a) + margin(b)` (each
    /// body's reach over the step; the world's 0), into `out`; `broad` and `manifolds` are
    /// scratch. Returns the deepest penetration found (0 when none).
    ///
    /// Broad phase: a uniform grid of cells twice the 90th percentile of the shapes' reach
    /// (bounding radius plus the body's margin), each shape tested against the shapes in
    /// its own and the 26 neighbouring cells; the larger shapes (a bin's walls) and the
    /// planes against every shape. Linear in the shapes for shapes of similar sizes.
    pub(in crate::multibody) fn detect(
        &self,
        c: &[Vec3],
        r: &[Mat3],
        margin: &[f64],
        out: &mut Vec<ContactPoint>,
        broad: &mut Broad,
        manifolds: &mut Vec<ContactManifold<(), ()>>,
    ) -> f64 {
        out.clear();
        let reach = |b: Option<usize>| b.map_or(0.0, |i| margin[i]);
        let centre = |k: &Collider| world(k.body, k.offset, c, r);
        let extent = |k: &Collider| k.radius + reach(k.body);
        broad.extents.clear();
        broad
            .extents
            .extend(self.colliders.iter().filter(|k| !k.plane).map(&extent));
        let mut deepest = 0.0f64;
        if !broad.extents.is_empty() {
            let at = ((broad.extents.len() * 9) / 10).min(broad.extents.len() - 1);
            let (_, p90, _) = broad.extents.select_nth_unstable_by(at, f64::total_cmp);
            let cell = 2.0 * *p90;
            broad.cells.clear();
            broad.large.clear();
            for (i, k) in self.colliders.iter().enumerate().filter(|(_, k)| !k.plane) {
                if extent(k) > 0.5 * cell || cell.is_nan() || cell <= 0.0 {
                    broad.large.push(i);
                } else {
                    let x = centre(k);
                    let key = [x.x, x.y, x.z].map(|v| (v / cell).floor() as i64);
                    broad.cells.push((key, i));
                }
            }
            broad.cells.sort_unstable();
            let near = |i: usize, j: usize| {
                let (ki, kj) = (&self.colliders[i], &self.colliders[j]);
                (centre(ki) - centre(kj)).norm() <= extent(ki) + extent(kj)
            };
            for s in 0..broad.cells.len() {
                let (key, i) = broad.cells[s];
                for d in 0..27i64 {
                    let want = [key[0] + d % 3 - 1, key[1] + (d / 3) % 3 - 1, key[2] + d / 9 - 1];
                    let from = broad.cells.partition_point(|&(k, _)| k < want);
                    for &(k, j) in &broad.cells[from..] {
                        if k != want {
                            break;
                        }
                        if j > i && near(i, j) {
                            let m = reach(self.colliders[i].body) + reach(self.colliders[j].body);
                            deepest = deepest.min(self.pair(i, j, c, r, m, out, manifolds));
                        }
                    }
                }
            }
            for (a, &i) in broad.large.iter().enumerate() {
                let others = broad
                    .cells
                    .iter()
                    .map(|&(_, j)| j)
                    .chain(broad.large[a + 1..].iter().copied());
                for j in others {
                    if near(i, j) {
                        let m = reach(self.colliders[i].body) + reach(self.colliders[j].body);
                        deepest = deepest.min(self.pair(i, j, c, r, m, out, manifolds));
                    }
                }
            }
        }
        for (i, ki) in self.colliders.iter().enumerate().filter(|(_, k)| k.plane) {
            let n = *attitude(ki.body, r) * (ki.rotation * Vec3::new(0.0, 0.0, 1.0));
            let o = centre(ki);
            for (j, kj) in self.colliders.iter().enumerate().filter(|(_, k)| !k.plane) {
                let m = reach(ki.body) + reach(kj.body);
                if n.dot(centre(kj) - o) <= kj.radius + m {
                    deepest = deepest.min(self.pair(j, i, c, r, m, out, manifolds));
                }
            }
        }
        deepest
    }

    /// The manifold points of colliders `i` and `j` within `margin`; returns the deepest
    /// penetration (or 0).
    #[allow(clippy::too_many_arguments)]
    fn pair(
        &self,
        i: usize,
        j: usize,
        c: &[Vec3],
        r: &[Mat3],
        margin: f64,
        out: &mut Vec<ContactPoint>,
        manifolds: &mut Vec<ContactManifold<(), ()>>,
    ) -> f64 {
        let (ki, kj) = (&self.colliders[i], &self.colliders[j]);
        if ki.body == kj.body
            || ki.contype & kj.conaffinity == 0 && kj.contype & ki.conaffinity == 0
            || self.excluded(ki.body, kj.body)
        {
            return 0.0;
        }
        // The flat side is `b`: the world or a plane, else a shape that is not round.
        let (mut ka, mut kb) = if kj.plane || (kj.body.is_none() && !ki.plane) || (ki.round > 0.0 && kj.round == 0.0) {
            (ki, kj)
        } else {
            (kj, ki)
        };
        let pose = |k: &Collider| {
            let rot = *attitude(k.body, r) * k.rotation;
            Pose::from_parts(to_p(world(k.body, k.offset, c, r)), rot_p(&rot))
        };
        let query = |ka: &Collider, kb: &Collider, manifolds: &mut Vec<ContactManifold<(), ()>>| {
            let pab = pose(ka).inv_mul(&pose(kb));
            manifolds.clear();
            let mut workspace = None;
            DefaultQueryDispatcher
                .contact_manifolds(&pab, &*ka.shape, &*kb.shape, margin, manifolds, &mut workspace)
                .is_ok()
        };
        if !query(ka, kb, manifolds) {
            return 0.0;
        }
        // Two boxes: `b` must own the face the normal is normal to (the gap's normal turns
        // with `b`); a corner of `b` on a face of `a` is queried the other way round.
        if ka.shape.as_cuboid().is_some() && kb.shape.as_cuboid().is_some() {
            let alignment = |n: PVec| {
                let l = n.length();
                if l > 0.0 {
                    n.x.abs().max(n.y.abs()).max(n.z.abs()) / l
                } else {
                    0.0
                }
            };
            if let Some(mf) = manifolds.first() {
                if alignment(mf.local_n1) > alignment(mf.local_n2) + 1e-9 {
                    (ka, kb) = (kb, ka);
                    if !query(ka, kb, manifolds) {
                        return 0.0;
                    }
                }
            }
        }
        let mu = ka.friction.max(kb.friction);
        let round = ka.round > 0.0 && kb.round > 0.0;
        let ra_body = *attitude(ka.body, r);
        let rb_body = *attitude(kb.body, r);
        let mut deepest = 0.0f64;
        let first = out.len();
        // Two boxes face on face: the corners by our own clipping (`boxes.rs`).
        let cuboids = match (ka.shape.as_cuboid(), kb.shape.as_cuboid()) {
            (Some(x), Some(y)) => {
                let cuboid = |k: &Collider, half: PVec| boxes::Cuboid {
                    half: from_p(half),
                    rotation: *attitude(k.body, r) * k.rotation,
                    centre: world(k.body, k.offset, c, r),
                };
                Some((cuboid(ka, x.half_extents), cuboid(kb, y.half_extents)))
            }
            _ => None,
        };
        for mf in manifolds.iter() {
            let faces = cuboids
                .as_ref()
                .and_then(|(a, b)| boxes::face_contact(a, b, from_p(mf.local_n2), margin, 1e-9 * self.length));
            // Normals in the shapes' frames, outward: n1 on `a` toward `b`, n2 on `b` toward `a`.
            let (n1, n2) = match &faces {
                Some(f) => (f.n1, f.n2),
                None => (from_p(mf.local_n1), from_p(mf.local_n2)),
            };
            if n2.norm() == 0.0 {
                continue;
            }
            let nb_body = kb.rotation * n2;
            let na_body = ka.rotation * n1;
            let count = faces.as_ref().map_or(mf.points.len(), |f| f.len);
            for index in 0..count {
                let (local_p1, local_p2, dist) = match &faces {
                    Some(f) => f.points[index],
                    None => {
                        let p = &mf.points[index];
                        (from_p(p.local_p1), from_p(p.local_p2), p.dist)
                    }
                };
                if dist > margin {
                    continue;
                }
                deepest = deepest.min(dist);
                // Core points: the surface point moved inward by the rounding radius.
                let core_a = ka.offset + ka.rotation * local_p1 - na_body * ka.round;
                let core_b = kb.offset + kb.rotation * local_p2 - nb_body * kb.round;
                // The same point twice (face on face: each face's clip gives the corners
                // the other gives) would be a redundant row.
                let close = 1e-9 * self.length;
                if out[first..]
                    .iter()
                    .any(|q| (q.pa - core_a).norm() <= close && (q.pb - core_b).norm() <= close)
                {
                    continue;
                }
                let n = rb_body * nb_body;
                let (t1, t2) = tangents(n);
                let ma = core_a - ra_body.transpose() * n * ka.round;
                let mb = core_b + rb_body.transpose() * n * kb.round;
                out.push(ContactPoint {
                    a: ka.body,
                    b: kb.body,
                    pa: core_a,
                    pb: core_b,
                    ra: ka.round,
                    rb: kb.round,
                    nb: nb_body,
                    round,
                    mu,
                    ma,
                    mb,
                    xa0: world(ka.body, ma, c, r),
                    xb0: world(kb.body, mb, c, r),
                    ca0: ka.body.map_or(Vec3::ZERO, |i| c[i]),
                    cb0: kb.body.map_or(Vec3::ZERO, |i| c[i]),
                    rota0: ra_body,
                    rotb0: rb_body,
                    t1,
                    t2,
                });
            }
        }
        deepest
    }
}

/// A shape as a collider: posed from its body's centre of mass; `None` when it does not
/// touch or its kind has no contact here (ellipsoids: the loader notes them).
fn collider(s: &Shape, com: &[Vec3]) -> Option<Collider> {
    let props = s.collision.as_ref()?;
    let offset = s.body.map_or(s.position, |b| s.position - com[b]);
    // parry's cylinder is along y, MuJoCo's along z: a quarter turn about x.
    let y_to_z = Mat3::from_rows([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]);
    let (shape, rotation, round, radius, plane) = match &s.kind {
        ShapeKind::Plane { .. } => (
            SharedShape::halfspace(PVec::new(0.0, 0.0, 1.0)),
            s.rotation,
            0.0,
            f64::INFINITY,
            true,
        ),
        ShapeKind::Sphere { radius } => (SharedShape::ball(*radius), s.rotation, *radius, *radius, false),
        ShapeKind::Capsule { radius, half_length } => (
            SharedShape::capsule_z(*half_length, *radius),
            s.rotation,
            *radius,
            radius + half_length,
            false,
        ),
        ShapeKind::Cylinder { radius, half_length } => (
            SharedShape::cylinder(*half_length, *radius),
            s.rotation * y_to_z,
            0.0,
            radius.hypot(*half_length),
            false,
        ),
        ShapeKind::Box { half } => (
            SharedShape::cuboid(half[0], half[1], half[2]),
            s.rotation,
            0.0,
            Vec3::from_array(*half).norm(),
            false,
        ),
        ShapeKind::Mesh {
            path: Ok(path), scale, ..
        } => {
            // The convex hull of the file's scaled vertices, in the geom's frame (MuJoCo
            // re-centres a mesh on its principal axes and folds the same offset into the
            // geom's frame: the two cancel, docs/multibody.md).
            let mesh = super::super::mesh::Mesh::read(path).ok()?;
            let points: Vec<PVec> = mesh
                .vertices
                .iter()
                .map(|v| {
                    PVec::new(
                        f64::from(v[0]) * scale[0],
                        f64::from(v[1]) * scale[1],
                        f64::from(v[2]) * scale[2],
                    )
                })
                .collect();
            let radius = points.iter().map(|p| p.length()).fold(0.0, f64::max);
            (SharedShape::convex_hull(&points)?, s.rotation, 0.0, radius, false)
        }
        ShapeKind::Ellipsoid { .. } | ShapeKind::Mesh { .. } => return None,
    };
    Some(Collider {
        body: s.body,
        shape,
        offset,
        rotation,
        round,
        radius,
        plane,
        friction: props.friction,
        contype: props.contype,
        conaffinity: props.conaffinity,
    })
}
