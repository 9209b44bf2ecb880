//! Face contact between two boxes: the incident face of one clipped by the side planes of
//! the other's reference face (Sutherland–Hodgman), with a slack so that corners lying on
//! an edge (equal boxes stacked square) are kept.
//!
//! parry's polygon clipping loses such corners to round-off: two equal boxes stacked square
//! gave a manifold of four points with one corner twice and the opposite corner missing,
//! and three corners cannot hold a box whose centre of mass is over their diagonal.
//!
//! Reference: D. Eberly, "Game Physics" (2010), §6.6 (face contact by clipping);
//! I. E. Sutherland, G. W. Hodgman, CACM 17 (1974) (the clipping).

use crate::linalg::{Mat3, Vec3};

/// A box: half extents, world attitude and centre.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cuboid {
    pub half: Vec3,
    pub rotation: Mat3,
    pub centre: Vec3,
}

/// The points of a face contact: normals in each box's frame (outward, `n1` on `a` toward
/// `b`, `n2` on `b` toward `a`) and per point its place on `a` and on `b` in their frames
/// and the distance along the normal.
#[derive(Clone, Copy, Debug)]
pub(super) struct FacePoints {
    pub n1: Vec3,
    pub n2: Vec3,
    pub points: [(Vec3, Vec3, f64); 8],
    pub len: usize,
}

/// Most vertices of a quadrilateral clipped by four half-planes.
const MOST: usize = 8;

/// The face contact of `a` on `b` when the contact normal `n2` (in `b`'s frame, from
/// parry's manifold) is a face normal of `b` to within `1e-9` (else `None`: an edge or a
/// corner of `b` leads, and parry's points stand). Points within `margin`, corners kept
/// within `slack` of `b`'s face.
pub(super) fn face_contact(a: &Cuboid, b: &Cuboid, n2: Vec3, margin: f64, slack: f64) -> Option<FacePoints> {
    let length = n2.norm();
    if length.is_nan() || length <= 0.0 {
        return None;
    }
    let n2 = n2 * (1.0 / length);
    let axis = |v: Vec3| {
        let a = v.to_array().map(f64::abs);
        if a[0] >= a[1] && a[0] >= a[2] {
            0
        } else if a[1] >= a[2] {
            1
        } else {
            2
        }
    };
    let i = axis(n2);
    if n2[i].abs() < 1.0 - 1e-9 {
        return None;
    }
    let s = n2[i].signum();
    let mut e = Vec3::ZERO;
    e[i] = s;
    // a in b's frame: x_b = R x_a + t.
    let r = b.rotation.transpose() * a.rotation;
    let t = b.rotation.tr_mul_vec(a.centre - b.centre);
    let d = r.tr_mul_vec(-e);
    let j = axis(d);
    let sj = d[j].signum();
    let (u, v) = ((j + 1) % 3, (j + 2) % 3);
    let mut poly = [Vec3::ZERO; MOST];
    for (k, (su, sv)) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
        .into_iter()
        .enumerate()
    {
        let mut va = Vec3::ZERO;
        va[j] = sj * a.half[j];
        va[u] = su * a.half[u];
        va[v] = sv * a.half[v];
        poly[k] = r * va + t;
    }
    let mut len = 4;
    let mut next = [Vec3::ZERO; MOST];
    for k in [(i + 1) % 3, (i + 2) % 3] {
        for side in [1.0, -1.0] {
            let bound = b.half[k] + slack;
            let inside = |p: &Vec3| side * p[k] <= bound;
            let mut out = 0;
            for m in 0..len {
                let (p, q) = (poly[m], poly[(m + 1) % len]);
                let (pin, qin) = (inside(&p), inside(&q));
                if pin && out < MOST {
                    next[out] = p;
                    out += 1;
                }
                if pin != qin && out < MOST {
                    let f = (bound - side * p[k]) / (side * (q[k] - p[k]));
                    next[out] = p + (q - p) * f;
                    out += 1;
                }
            }
            poly[..out].copy_from_slice(&next[..out]);
            len = out;
            if len == 0 {
                return Some(FacePoints {
                    n1: d,
                    n2: e,
                    points: [(Vec3::ZERO, Vec3::ZERO, 0.0); 8],
                    len: 0,
                });
            }
        }
    }
    let mut points = [(Vec3::ZERO, Vec3::ZERO, 0.0); 8];
    let mut count = 0;
    for p in &poly[..len] {
        let dist = s * p[i] - b.half[i];
        if dist <= margin {
            let mut on_b = *p;
            on_b[i] = s * b.half[i];
            points[count] = (r.tr_mul_vec(*p - t), on_b, dist);
            count += 1;
        }
    }
    Some(FacePoints {
        n1: d,
        n2: e,
        points,
        len: count,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_boxes_stacked_square_touch_at_four_corners() {
        let half = Vec3::new(0.1, 0.1, 0.05);
        let b = Cuboid {
            half,
            rotation: Mat3::IDENTITY,
            centre: Vec3::ZERO,
        };
        // A turn of 1e-16 rad about z (round-off) and a gap of 1e-17.
        let (s, c) = (1e-16f64.sin(), 1e-16f64.cos());
        let a = Cuboid {
            half,
            rotation: Mat3::from_rows([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]),
            centre: Vec3::new(1e-17, 0.0, 0.1 + 1e-17),
        };
        let f = face_contact(&a, &b, Vec3::new(1e-16, 0.0, 1.0), 1e-3, 1e-10).unwrap();
        assert_eq!(f.len, 4);
        for (p1, p2, dist) in &f.points[..4] {
            assert!(
                (p1.x.abs() - 0.1).abs() < 1e-15 && (p1.y.abs() - 0.1).abs() < 1e-15 && (p1.z + 0.05).abs() < 1e-15
            );
            assert!((p2.z - 0.05).abs() == 0.0 && dist.abs() < 1e-15);
        }
        assert_eq!(f.n2, Vec3::new(0.0, 0.0, 1.0));
    }

    #[test]
    fn a_smaller_box_turned_on_a_larger_one_touches_at_its_own_corners_and_a_tilted_one_at_its_edge() {
        let b = Cuboid {
            half: Vec3::new(1.0, 1.0, 0.1),
            rotation: Mat3::IDENTITY,
            centre: Vec3::ZERO,
        };
        let turn = 0.3f64;
        let a = Cuboid {
            half: Vec3::new(0.2, 0.1, 0.1),
            rotation: Mat3::from_rows([
                [turn.cos(), -turn.sin(), 0.0],
                [turn.sin(), turn.cos(), 0.0],
                [0.0, 0.0, 1.0],
            ]),
            centre: Vec3::new(0.3, -0.2, 0.2),
        };
        let f = face_contact(&a, &b, Vec3::new(0.0, 0.0, 1.0), 1e-6, 1e-12).unwrap();
        assert_eq!(f.len, 4);
        // Tilted about x by 0.2 rad and lowered onto an edge: two points.
        let tilt = 0.2f64;
        let rot = Mat3::from_rows([
            [1.0, 0.0, 0.0],
            [0.0, tilt.cos(), -tilt.sin()],
            [0.0, tilt.sin(), tilt.cos()],
        ]);
        let low = 0.1 * tilt.cos() + 0.1 * tilt.sin();
        let a = Cuboid {
            half: Vec3::new(0.2, 0.1, 0.1),
            rotation: rot,
            centre: Vec3::new(0.0, 0.0, 0.1 + low),
        };
        let f = face_contact(&a, &b, Vec3::new(0.0, 0.0, 1.0), 1e-6, 1e-12).unwrap();
        assert_eq!(f.len, 2);
        for (_, p2, dist) in &f.points[..2] {
            assert!(dist.abs() < 1e-15 && (p2.x.abs() - 0.2).abs() < 1e-15);
        }
        // An edge-on normal is left to parry.
        assert!(face_contact(&a, &b, Vec3::new(0.0, 0.6, 0.8), 1e-6, 1e-12).is_none());
    }
}
