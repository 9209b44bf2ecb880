//! The contact step's data: each contact's three rows at one configuration, and the scratch
//! of the contact solves (grown as contacts appear, so a step allocates nothing once the
//! contacts' number has been met).
//!
//! Reference: docs/theory/multibody.md §6.

use crate::linalg::{Mat3, Vec3};

use super::super::constraints::JointRows;
use super::detect::ContactPoint;
use parry3d_f64::query::ContactManifold;

/// The three rows of one contact at one configuration: directions (normal, two tangents)
/// and the body-frame moments of a unit force along each on `a` and on `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Rows {
    pub(super) a: Option<usize>,
    pub(super) b: Option<usize>,
    pub(super) dir: [Vec3; 3],
    pub(super) ta: [Vec3; 3],
    pub(super) tb: [Vec3; 3],
}

impl Rows {
    /// At `(c, R)` through `x`, along `dir`.
    pub(super) fn at(p: &ContactPoint, c: &[Vec3], r: &[Mat3], x: Vec3, dir: [Vec3; 3]) -> Rows {
        let moment = |body: Option<usize>, d: Vec3| match body {
            Some(i) => r[i].tr_mul_vec((x - c[i]).cross(d)),
            None => Vec3::ZERO,
        };
        Rows {
            a: p.a,
            b: p.b,
            dir,
            ta: dir.map(|d| moment(p.a, d)),
            tb: dir.map(|d| moment(p.b, d)),
        }
    }

    pub(super) fn rate(&self, i: usize, vel: &[Vec3], omega: &[Vec3]) -> f64 {
        let mut r = 0.0;
        if let Some(a) = self.a {
            r += self.dir[i].dot(vel[a]) + self.ta[i].dot(omega[a]);
        }
        if let Some(b) = self.b {
            r -= self.dir[i].dot(vel[b]) + self.tb[i].dot(omega[b]);
        }
        r
    }

    /// The three rates at once, each as [`Rows::rate`] computes it (the same operations in
    /// the same order: the same bits), each body read once.
    #[inline]
    pub(super) fn rates(&self, vel: &[Vec3], omega: &[Vec3]) -> [f64; 3] {
        let mut r = [0.0; 3];
        if let Some(a) = self.a {
            let (v, w) = (vel[a], omega[a]);
            for (i, r) in r.iter_mut().enumerate() {
                *r += self.dir[i].dot(v) + self.ta[i].dot(w);
            }
        }
        if let Some(b) = self.b {
            let (v, w) = (vel[b], omega[b]);
            for (i, r) in r.iter_mut().enumerate() {
                *r -= self.dir[i].dot(v) + self.tb[i].dot(w);
            }
        }
        r
    }

    pub(super) fn apply(&self, i: usize, f: f64, lin: &mut [Vec3], ang: &mut [Vec3]) {
        if let Some(a) = self.a {
            lin[a] += self.dir[i] * f;
            ang[a] += self.ta[i] * f;
        }
        if let Some(b) = self.b {
            lin[b] -= self.dir[i] * f;
            ang[b] -= self.tb[i] * f;
        }
    }
}

/// A dense `W` and what it was formed for (`ContactScratch::end_w`): the half step, the
/// contact rows and the joint rows, which with the constant masses determine it.
#[derive(Clone, Debug, Default)]
pub(super) struct EndResponse {
    w: Vec<f64>,
    hh: f64,
    rows: Vec<Rows>,
    joints: Vec<JointRows>,
}

impl EndResponse {
    /// Keep `w`, formed for `hh`, `rows` and `joints`.
    pub(super) fn keep(&mut self, w: &[f64], hh: f64, rows: &[Rows], joints: &[JointRows]) {
        self.w.clear();
        self.w.extend_from_slice(w);
        self.hh = hh;
        self.rows.clear();
        self.rows.extend_from_slice(rows);
        self.joints.clear();
        self.joints.extend_from_slice(joints);
    }

    /// Copy the kept `W` into `w` if it was formed for `hh`, `rows` and `joints`; whether it
    /// was.
    pub(super) fn copy_if_for(&self, hh: f64, rows: &[Rows], joints: &[JointRows], w: &mut Vec<f64>) -> bool {
        let same = self.hh == hh && self.rows == rows && self.joints == joints;
        if same {
            w.clear();
            w.extend_from_slice(&self.w);
        }
        same
    }
}

/// The islands of one set of contact rows, and the rows, blocks and friction coefficients
/// gathered island by island (the forces and the rates are gathered per solve).
#[derive(Clone, Debug, Default)]
pub(super) struct Islands {
    /// Union–find over the bodies: each body's parent.
    pub(super) parent: Vec<usize>,
    /// Per body, its island's index (`usize::MAX`: none yet); per contact, its island.
    pub(super) label: Vec<usize>,
    pub(super) island_of: Vec<usize>,
    /// The contacts island by island; island `i` is `order[starts[i]..starts[i + 1]]`.
    pub(super) order: Vec<usize>,
    pub(super) starts: Vec<usize>,
    /// The contacts' rows, diagonal blocks and friction coefficients in `order`.
    pub(super) rows: Vec<Rows>,
    pub(super) blocks: Vec<[[f64; 3]; 3]>,
    pub(super) mu: Vec<f64>,
    /// The forces, the rates' constant `r₀` and the rates in `order` (three per contact).
    pub(super) sigma: Vec<f64>,
    pub(super) r0: Vec<f64>,
    pub(super) rates: Vec<f64>,
    /// One island's dense `W` and the rates its solve keeps.
    pub(super) w: Vec<f64>,
    pub(super) kept: Vec<f64>,
}

/// The finishes of a solve over a dense `W` (`polish.rs`, `newton.rs`) and their scratch.
#[derive(Clone, Debug, Default)]
pub(super) struct Finishes {
    pub(super) polish: super::polish::Polish,
    pub(super) slide: super::polish::Slide,
    pub(super) newton: super::newton::Newton,
}

/// Scratch of the contact solves, grown as contacts appear (a step with the same number of
/// contacts as a past one allocates nothing).
#[derive(Clone, Default)]
pub(in crate::multibody) struct ContactScratch {
    pub(super) points: Vec<ContactPoint>,
    pub(super) active: Vec<usize>,
    pub(super) rows: Vec<Rows>,
    pub(super) order: Vec<(f64, usize)>,
    pub(super) broad: super::detect::Broad,
    pub(super) manifolds: Vec<ContactManifold<(), ()>>,
    pub(super) margin: Vec<f64>,
    pub(super) w: Vec<f64>,
    /// The velocity solve's dense `W` over jointed bodies, with the half step, contact rows
    /// and joint rows it was formed for: the next step's position solve starts at that
    /// configuration and takes it where all of these are the same (`response.rs`).
    pub(super) end_w: EndResponse,
    pub(super) r0: Vec<f64>,
    pub(super) rates: Vec<f64>,
    pub(super) sigma: Vec<f64>,
    pub(super) sigma_ok: Vec<f64>,
    /// The forces with the least violation of the position problem's iteration so far.
    pub(super) sigma_best: Vec<f64>,
    /// The finishes of the dense solves.
    pub(super) finishes: Finishes,
    /// The rates the dense response keeps.
    pub(super) kept: Vec<f64>,
    /// What the cone solve keeps between its sweeps.
    pub(super) memory: super::cone::Memory,
    /// Free bodies only (no joint rows, no armature): `W` never formed whole, the contacts
    /// solved island by island (`islands.rs`), every island of a scene of more than 64
    /// contacts body by body (`Local`):
    /// the diagonal blocks and the velocity changes of the forces.
    pub(super) local: bool,
    pub(super) blocks: Vec<[[f64; 3]; 3]>,
    /// Over free bodies, the contacts grouped into independent problems.
    pub(super) islands: Islands,
    pub(super) dv: Vec<Vec3>,
    pub(super) dw: Vec<Vec3>,
    /// The last step's points and position forces (the warm start).
    pub(super) last_points: Vec<ContactPoint>,
    pub(super) last_sigma: Vec<f64>,
    /// The momenta before the contact forces (a second pass starts from them).
    pub(super) entry_p: Vec<Vec3>,
    pub(super) entry_pi: Vec<Vec3>,
    /// Points found at a drift's end, and the zero margins of that detection.
    pub(super) found: Vec<ContactPoint>,
    pub(super) zero_margin: Vec<f64>,
    /// Per point, the normal rate at the step's start (restitution only).
    pub(super) start_normal: Vec<f64>,
    /// The velocity solve's touching points, and the last step's with their forces.
    pub(super) end_points: Vec<ContactPoint>,
    pub(super) last_end_points: Vec<ContactPoint>,
    pub(super) last_end_sigma: Vec<f64>,
    /// How many of `last_end_points` touched at the end of the last step (0 when none did:
    /// the warm start keeps older ones).
    pub(super) end_count: usize,
    /// Per point, the normal speed at which it would meet (restitution only).
    pub(super) approach: Vec<f64>,
    pub(super) lambda_ok: Vec<[f64; 6]>,
    pub(super) mu: Vec<f64>,
    /// The drift holds no contact by friction (friction in the closing μ-kick only): the
    /// fallback of a step whose solve fails at every split.
    pub(in crate::multibody) frictionless_drift: bool,
    pub(super) base_p: Vec<Vec3>,
    pub(super) base_pi: Vec<Vec3>,
    pub(super) linear: Vec<Vec3>,
    pub(super) angular: Vec<Vec3>,
}

impl core::fmt::Debug for ContactScratch {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ContactScratch")
            .field("points", &self.points.len())
            .finish_non_exhaustive()
    }
}

impl ContactScratch {
    pub(in crate::multibody) fn new(bodies: usize) -> Self {
        ContactScratch {
            margin: vec![0.0; bodies],
            base_p: vec![Vec3::ZERO; bodies],
            base_pi: vec![Vec3::ZERO; bodies],
            linear: vec![Vec3::ZERO; bodies],
            angular: vec![Vec3::ZERO; bodies],
            dv: vec![Vec3::ZERO; bodies],
            dw: vec![Vec3::ZERO; bodies],
            ..ContactScratch::default()
        }
    }
}
