//! The contact forces in the step's two half-kicks (module docs of `contact`): the rows,
//! the response matrix `W`, the position problem's outer iteration around the drift and the
//! velocity problem with the μ-kick.

use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};

use super::super::method::StepReport;
use super::super::state::MultibodyState;
use super::super::system::MultibodySystem;
use super::super::workspace::Workspace;
use super::cone;
use super::detect::{tangents, ContactPoint};
use parry3d_f64::query::ContactManifold;

/// Contacts on free bodies from which `W` is applied body by body (`Local`) instead of
/// formed.
const LOCAL_FROM: usize = 64;

/// Most passes of the position problem with points its drift's end found (`missed_contacts`).
const MAX_PASSES: usize = 3;

/// Most outer iterations of the position problem (each re-runs the drift).
const MAX_OUTER: usize = 50;

/// The three rows of one contact at one configuration: directions (normal, two tangents)
/// and the body-frame moments of a unit force along each on `a` and on `b`.
#[derive(Clone, Copy, Debug)]
struct Rows {
    a: Option<usize>,
    b: Option<usize>,
    dir: [Vec3; 3],
    ta: [Vec3; 3],
    tb: [Vec3; 3],
}

impl Rows {
    /// At `(c, R)` through `x`, along `dir`.
    fn at(p: &ContactPoint, c: &[Vec3], r: &[Mat3], x: Vec3, dir: [Vec3; 3]) -> Rows {
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

    fn rate(&self, i: usize, vel: &[Vec3], omega: &[Vec3]) -> f64 {
        let mut r = 0.0;
        if let Some(a) = self.a {
            r += self.dir[i].dot(vel[a]) + self.ta[i].dot(omega[a]);
        }
        if let Some(b) = self.b {
            r -= self.dir[i].dot(vel[b]) + self.tb[i].dot(omega[b]);
        }
        r
    }

    fn apply(&self, i: usize, f: f64, lin: &mut [Vec3], ang: &mut [Vec3]) {
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

/// Scratch of the contact solves, grown as contacts appear (a step with the same number of
/// contacts as a past one allocates nothing).
#[derive(Clone, Default)]
pub(in crate::multibody) struct ContactScratch {
    points: Vec<ContactPoint>,
    active: Vec<usize>,
    rows: Vec<Rows>,
    order: Vec<(f64, usize)>,
    broad: super::detect::Broad,
    manifolds: Vec<ContactManifold<(), ()>>,
    margin: Vec<f64>,
    w: Vec<f64>,
    r0: Vec<f64>,
    rates: Vec<f64>,
    sigma: Vec<f64>,
    sigma_ok: Vec<f64>,
    polish: super::polish::Polish,
    slide: super::polish::Slide,
    newton: super::newton::Newton,
    cluster: super::cluster::Cluster,
    /// The rates the dense response keeps.
    kept: Vec<f64>,
    /// Free bodies only (no joint rows, no armature): `W` applied body by body, never
    /// formed (`Local`): its diagonal blocks and the velocity changes of the forces.
    local: bool,
    blocks: Vec<[[f64; 3]; 3]>,
    dv: Vec<Vec3>,
    dw: Vec<Vec3>,
    /// The last step's points and position forces (the warm start).
    last_points: Vec<ContactPoint>,
    last_sigma: Vec<f64>,
    /// The momenta before the contact forces (a second pass starts from them).
    entry_p: Vec<Vec3>,
    entry_pi: Vec<Vec3>,
    /// Points found at a drift's end, and the zero margins of that detection.
    found: Vec<ContactPoint>,
    zero_margin: Vec<f64>,
    /// Per point, the normal rate at the step's start (restitution only).
    start_normal: Vec<f64>,
    /// The velocity solve's touching points, and the last step's with their forces.
    end_points: Vec<ContactPoint>,
    last_end_points: Vec<ContactPoint>,
    last_end_sigma: Vec<f64>,
    /// Per point, the normal speed at which it would meet (restitution only).
    approach: Vec<f64>,
    lambda_ok: Vec<[f64; 6]>,
    mu: Vec<f64>,
    base_p: Vec<Vec3>,
    base_pi: Vec<Vec3>,
    linear: Vec<Vec3>,
    angular: Vec<Vec3>,
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

impl Workspace {
    /// The contact problem's response `W = (h/2) D P M⁻¹ Dᵀ` over `s.rows` (row-major into
    /// `s.w`): column by column, the rates after a half-kick by a unit force on one row,
    /// projected on the joints (the start rows or the end rows, factored).
    fn contact_response(&mut self, sys: &MultibodySystem, s: &mut ContactScratch, hh: f64, start: bool) {
        let any_rows = if start { &self.rows0 } else { &self.rows1 }.iter().any(|r| r.n > 0);
        let m = 3 * s.rows.len();
        s.w.clear();
        s.w.resize(m * m, 0.0);
        for col in 0..m {
            s.linear.iter_mut().for_each(|v| *v = Vec3::ZERO);
            s.angular.iter_mut().for_each(|v| *v = Vec3::ZERO);
            s.rows[col / 3].apply(col % 3, hh, &mut s.linear, &mut s.angular);
            self.project(sys, &mut s.linear, &mut s.angular, hh, any_rows, start);
            for (row, rows) in s.rows.iter().enumerate() {
                for i in 0..3 {
                    s.w[(3 * row + i) * m + col] = rows.rate(i, &self.vel, &self.omega);
                }
            }
        }
    }

    /// Make `W` ready for the solves: body by body for free bodies (no joint rows, no
    /// armature: the blocks only), else dense (`contact_response`).
    fn prepare_response(&mut self, sys: &MultibodySystem, s: &mut ContactScratch, hh: f64, start: bool) {
        let rows = if start { &self.rows0 } else { &self.rows1 };
        // Few contacts keep the dense W even on free bodies: its finishes (`polish.rs`)
        // need the active set's rows of W.
        s.local = sys.armature.is_none() && !rows.iter().any(|r| r.n > 0) && s.rows.len() > LOCAL_FROM;
        if !s.local {
            self.contact_response(sys, s, hh, start);
            return;
        }
        s.blocks.clear();
        for rows in &s.rows {
            let mut block = [[0.0; 3]; 3];
            for (body, t) in [(rows.a, &rows.ta), (rows.b, &rows.tb)] {
                if let Some(i) = body {
                    let inv_m = 1.0 / sys.mass[i];
                    let it: [Vec3; 3] = core::array::from_fn(|j| sys.inertia[i].apply_inverse(t[j]));
                    for (r, row) in block.iter_mut().enumerate() {
                        for (c, x) in row.iter_mut().enumerate() {
                            *x += hh * (rows.dir[r].dot(rows.dir[c]) * inv_m + t[r].dot(it[c]));
                        }
                    }
                }
            }
            s.blocks.push(block);
        }
    }

    /// The position half of the contact step: contacts detected at the start with the
    /// bodies' reach over the step, then the outer iteration `σ → drift → (gap, slide)/h →
    /// linearised cone problem → σ` until the law holds at the drift's end to the
    /// tolerance (module docs). `positions` runs the drift with its joint solve from
    /// the momenta in `pb`, `pib`.
    pub(in crate::multibody) fn contact_positions(
        &mut self,
        sys: &MultibodySystem,
        state: &MultibodyState,
        h: f64,
        report: &mut StepReport,
        positions: &mut dyn FnMut(&mut Workspace, &mut StepReport, bool) -> Result<()>,
    ) -> Result<()> {
        let Some(geometry) = &sys.contact else {
            return positions(self, report, true);
        };
        if h <= 0.0 {
            return Err(Error::InvalidParameter {
                name: "h",
                value: h,
                reason: "contact needs a positive step (contacts dissipate: they are not time-reversible)",
            });
        }
        let hh = 0.5 * h;
        let mut s = core::mem::take(&mut self.contact);
        // Each body's reach over the step: twice its points' speed bound, and the pull of
        // its forces over the step.
        for i in 0..sys.mass.len() {
            let v = state.p[i].norm() / sys.mass[i];
            let w = sys.inertia[i].apply_inverse(state.pi[i]).norm();
            let a = self.force[i].norm() / sys.mass[i];
            s.margin[i] = 2.0 * h * (v + w * geometry.reach[i]) + h * h * a + 1e-4 * geometry.length;
        }
        let deepest = {
            let ContactScratch {
                points,
                broad,
                manifolds,
                margin,
                ..
            } = &mut s;
            geometry.detect(&state.c, &state.rotation, margin, points, broad, manifolds)
        };
        report.penetration = report.penetration.max(-deepest);
        report.contacts = report.contacts.max(u32::try_from(s.points.len()).unwrap_or(u32::MAX));
        if s.points.is_empty() {
            self.contact = s;
            return positions(self, report, true);
        }
        // The momenta before any contact force, for a second pass.
        s.entry_p.clear();
        s.entry_p.extend_from_slice(&self.pb);
        s.entry_pi.clear();
        s.entry_pi.extend_from_slice(&self.pib);
        let mut result;
        let mut passes = 0;
        loop {
            result = self.contact_outer(sys, state, h, hh, geometry.length, &mut s, report, positions);
            // A point the drift's end penetrates that the start's detection did not give (a
            // box turning another corner down within the step, parry's manifold holding the
            // start's features only) joins the problem, which is solved again from the
            // momenta before the contact forces.
            if result.is_err() || self.missed_contacts(geometry, state, &mut s) == 0 {
                break;
            }
            if passes >= MAX_PASSES {
                // Each pass found another point (an edge sliding along an edge, held at
                // material points): the step is refused, not ended penetrating.
                result = Err(Error::NewtonDidNotConverge {
                    method: self.method_name,
                    equation: "the contacts found again at the drift's end (a new point each pass)",
                    t: state.t,
                    h,
                    residual: s
                        .found
                        .iter()
                        .map(|p| -p.gap(&self.c_new, &self.r_new))
                        .fold(0.0, f64::max)
                        / geometry.length,
                    iterations: u32::try_from(passes).unwrap_or(u32::MAX),
                });
                break;
            }
            passes += 1;
            report.contacts = report.contacts.max(u32::try_from(s.points.len()).unwrap_or(u32::MAX));
            self.pb.copy_from_slice(&s.entry_p);
            self.pib.copy_from_slice(&s.entry_pi);
        }
        self.contact = s;
        result
    }

    /// Detect again at the drift's end (`c_new`, `r_new`) and add to `s.points` every point
    /// deeper than the tolerance (`1e-12` of the length) that none of them covers, rebased
    /// to the step's start; returns how many were added.
    fn missed_contacts(
        &self,
        geometry: &super::detect::ContactGeometry,
        state: &MultibodyState,
        s: &mut ContactScratch,
    ) -> usize {
        let close = 1e-9 * geometry.length;
        s.zero_margin.clear();
        s.zero_margin.resize(state.c.len(), 0.0);
        {
            let ContactScratch {
                found,
                broad,
                manifolds,
                zero_margin,
                ..
            } = s;
            geometry.detect(&self.c_new, &self.r_new, zero_margin, found, broad, manifolds);
        }
        let before = s.points.len();
        for k in 0..s.found.len() {
            let p = s.found[k];
            if p.gap(&self.c_new, &self.r_new) >= -1e-12 * geometry.length {
                continue;
            }
            let covered = s.points[..before]
                .iter()
                .any(|q| q.a == p.a && q.b == p.b && (q.pa - p.pa).norm() <= close && (q.pb - p.pb).norm() <= close);
            if !covered {
                let mut p = p;
                p.rebase(&state.c, &state.rotation);
                s.points.push(p);
            }
        }
        s.points.len() - before
    }

    #[allow(clippy::too_many_arguments)]
    fn contact_outer(
        &mut self,
        sys: &MultibodySystem,
        state: &MultibodyState,
        h: f64,
        hh: f64,
        length: f64,
        s: &mut ContactScratch,
        report: &mut StepReport,
        positions: &mut dyn FnMut(&mut Workspace, &mut StepReport, bool) -> Result<()>,
    ) -> Result<()> {
        let n = s.points.len();
        let (c, r) = (&state.c, &state.rotation);
        s.rows.clear();
        for p in &s.points {
            let (x, nrm) = p.application(c, r);
            s.rows.push(Rows::at(p, c, r, x, [nrm, p.t1, p.t2]));
        }
        // Friction holds a contact over the drift only where it touches at the start: a
        // corner that lands within the step moved along the surface before it touched (a
        // box tipping onto its face about an edge: `g₀²/2L` toward the edge while it
        // closes its gap `g₀`), and holding that still would over-constrain the sticking
        // rows. Below `g₀ = 1e-6 L` that slide is under half the tolerance (`1e-12 L`), so
        // such a contact still sticks; above, its friction acts from the landing on, in
        // the μ-kick.
        s.mu.clear();
        s.mu.extend(
            s.points
                .iter()
                .map(|p| if p.gap(c, r) <= 1e-6 * length { p.mu } else { 0.0 }),
        );
        // W at the start rows, factored (the velocity solve of the last step factored them).
        if self.rows0.iter().any(|r| r.n > 0) && !self.factor_rows0 {
            self.factor(sys, super::super::workspace::Matrix::Start)?;
            report.factorizations += 1;
        }
        s.approach.clear();
        if sys.contact.as_ref().is_some_and(|g| g.restitution > 0.0) {
            // The free normal motion over the step, φ(t) = φ + v t + a t²/2 (exact under a
            // constant force, as kick-drift-kick is), meets φ = 0 at the speed
            // u = √(v² − 2 a φ): the approach speed of an impact within the step.
            self.velocities(sys, &state.p, &state.pi);
            s.approach
                .extend(s.rows.iter().map(|rows| rows.rate(0, &self.vel, &self.omega)));
            s.start_normal.clear();
            s.start_normal.extend_from_slice(&s.approach);
            // The accelerations the forces give through the joints (a pendulum's bob
            // accelerates along its arc, not as if free: free accelerations made an elastic
            // cradle gain 1.5e-6 of its energy at h = 1e-4, O(h)).
            s.linear.copy_from_slice(&self.force);
            s.angular.copy_from_slice(&self.torque);
            let any_rows = self.rows0.iter().any(|r| r.n > 0);
            let (mut lin, mut ang) = (core::mem::take(&mut s.linear), core::mem::take(&mut s.angular));
            self.project(sys, &mut lin, &mut ang, hh, any_rows, true);
            s.linear = lin;
            s.angular = ang;
            for ((p, rows), u) in s.points.iter().zip(&s.rows).zip(s.approach.iter_mut()) {
                let (v, a) = (*u, rows.rate(0, &self.vel, &self.omega));
                let gap = p.gap(c, r).max(0.0);
                *u = if v < 0.0 || a < 0.0 {
                    (v * v - 2.0 * a * gap).max(0.0).sqrt()
                } else {
                    0.0
                };
            }
        }
        self.prepare_response(sys, s, hh, true);
        s.base_p.copy_from_slice(&self.pb);
        s.base_pi.copy_from_slice(&self.pib);
        s.sigma.clear();
        s.sigma.resize(3 * n, 0.0);
        // Warm start: a contact found at the same material points as in the last step
        // (a resting one) starts from its last force.
        warm(
            &s.points,
            &s.last_points,
            &s.last_sigma,
            length,
            &mut s.sigma,
            &mut s.order,
        );
        s.r0.resize(3 * n, 0.0);
        s.rates.resize(3 * n, 0.0);
        // Gap and slide to 1e-12 of the contact length: as rates over the step.
        let tol = 1e-12 * length / h;
        let mut first = true;
        // The last σ whose drift succeeded: a correction whose drift fails (a linearised
        // step too long for a light body's rotation) is halved toward it.
        s.sigma_ok.clear();
        s.sigma_ok.resize(3 * n, 0.0);
        let mut halvings = 0;
        // A cone solve that stopped short, and the violation before it.
        let mut stalled: Option<(cone::Solved, f64)> = None;
        for outer in 0.. {
            self.pb.copy_from_slice(&s.base_p);
            self.pib.copy_from_slice(&s.base_pi);
            for (k, rows) in s.rows.iter().enumerate() {
                for i in 0..3 {
                    rows.apply(i, hh * s.sigma[3 * k + i], &mut self.pb, &mut self.pib);
                }
            }
            let limits = report.limit_changes;
            if let Err(e) = positions(self, report, first) {
                if first || halvings >= 30 {
                    return Err(e);
                }
                halvings += 1;
                for (x, ok) in s.sigma.iter_mut().zip(&s.sigma_ok) {
                    *x = 0.5 * (*x + ok);
                }
                self.lambda.copy_from_slice(&s.lambda_ok);
                continue;
            }
            s.sigma_ok.copy_from_slice(&s.sigma);
            s.lambda_ok.clear();
            s.lambda_ok.extend_from_slice(&self.lambda);
            if first && !s.approach.is_empty() {
                // A contact the first drift ran without force moved freely through the
                // joints: its gap φ₁ at the drift's end gives the normal acceleration
                // a = 2 (φ₁ − φ₀ − v h)/h² with the joints' curvature in it (the bob of a
                // pendulum turns on its arc), and so the approach speed √(v² − 2 a φ₀).
                for (k, p) in s.points.iter().enumerate() {
                    if s.sigma[3 * k..3 * k + 3] == [0.0; 3] {
                        let (v, gap0) = (s.start_normal[k], p.gap(c, r));
                        let a = 2.0 * (p.gap(&self.c_new, &self.r_new) - gap0 - v * h) / (h * h);
                        s.approach[k] = if v < 0.0 || a < 0.0 {
                            (v * v - 2.0 * a * gap0.max(0.0)).max(0.0).sqrt()
                        } else {
                            0.0
                        };
                    }
                }
            }
            first = false;
            if report.limit_changes != limits {
                // A joint limit switched: the rows the contact forces act through changed,
                // and W with them (a stale W contracts slowly, 0.78 per iteration on the
                // humanoid's knee at its limit).
                if self.rows0.iter().any(|r| r.n > 0) {
                    self.factor(sys, super::super::workspace::Matrix::Start)?;
                    report.factorizations += 1;
                }
                self.prepare_response(sys, s, hh, true);
            }
            for (k, p) in s.points.iter().enumerate() {
                let (t1, t2) = p.slide(&self.c_new, &self.r_new);
                s.rates[3 * k] = p.gap(&self.c_new, &self.r_new) / h;
                s.rates[3 * k + 1] = t1 / h;
                s.rates[3 * k + 2] = t2 / h;
            }
            let worst = cone::violation(&s.rates, &s.sigma, &s.mu);
            if worst <= tol {
                report.contact_iterations += u32::try_from(outer).unwrap_or(u32::MAX);
                s.last_points.clear();
                s.last_points.extend_from_slice(&s.points);
                s.last_sigma.clear();
                s.last_sigma.extend_from_slice(&s.sigma);
                return Ok(());
            }
            if let Some((stalled, before)) = stalled.take() {
                // The last cone solve stopped short: its forces are kept only while the law
                // at the drift's end keeps improving.
                if worst > 0.9 * before {
                    let stalled: cone::Solved = stalled;
                    return Err(Error::NewtonDidNotConverge {
                        method: self.method_name,
                        equation: "the contact cone problem of the position solve (projected Gauss-Seidel)",
                        t: state.t,
                        h,
                        residual: stalled.worst * h / length,
                        iterations: u32::try_from(stalled.sweeps).unwrap_or(u32::MAX),
                    });
                }
            }
            if outer >= MAX_OUTER {
                return Err(Error::NewtonDidNotConverge {
                    method: self.method_name,
                    equation: "the contacts at the drift's end (gap and slide)",
                    t: state.t,
                    h,
                    residual: worst * h / length,
                    iterations: u32::try_from(outer).unwrap_or(u32::MAX),
                });
            }
            // The linearised problem about the current σ: r(σ') ≈ r(σ) + W (σ' − σ).
            minus_w_sigma(sys, s, hh);
            // Solved to a thousandth of the current violation (an inexact Newton step:
            // redundant sticking rows are consistent only at the solution, the drift's
            // curvature leaving the linearised ones off W's range; a tenth made the standing
            // quadruped take 5 drifts a step, a thousandth 1.9, the full tolerance stalls
            // piles sooner); the step is accepted above, on the law at the drift's end.
            let done = solve_contacts(sys, s, hh, (0.25 * tol).max(1e-3 * worst));
            report.contact_sweeps += u32::try_from(done.sweeps).unwrap_or(u32::MAX);
            if !done.converged {
                stalled = Some((done, worst));
            }
        }
        unreachable!("the outer loop returns")
    }

    /// The velocity half: the contacts touching at the end (gap within 1e-9 of the contact
    /// length) get rows at the end configuration, and their forces are chosen after the
    /// other end forces so that no contact approaches and each sticks or slides by
    /// Coulomb's law after the μ-kick; the forces are added to `damp_f`, `damp_t`.
    pub(in crate::multibody) fn end_contacts(
        &mut self,
        sys: &MultibodySystem,
        t: f64,
        hh: f64,
        report: &mut StepReport,
    ) -> Result<bool> {
        let Some(geometry) = &sys.contact else {
            return Ok(false);
        };
        let mut s = core::mem::take(&mut self.contact);
        let (c, r) = (&self.c_new, &self.r_new);
        s.active.clear();
        s.rows.clear();
        for (k, p) in s.points.iter().enumerate() {
            if p.gap(c, r) <= 1e-9 * geometry.length {
                let (x, nrm) = p.application(c, r);
                let (t1, t2) = tangents(nrm);
                s.active.push(k);
                s.rows.push(Rows::at(p, c, r, x, [nrm, t1, t2]));
            }
        }
        if s.rows.is_empty() {
            self.contact = s;
            return Ok(false);
        }
        let n = s.rows.len();
        s.mu.clear();
        let points = &s.points;
        s.mu.extend(s.active.iter().map(|&k| points[k].mu));
        let any_rows = self.rows1.iter().any(|r| r.n > 0);
        // r₀: the rates after the μ-kick without contact forces.
        for i in 0..sys.mass.len() {
            s.linear[i] = self.p_half[i] + (self.force1[i] + self.damp_f[i]) * hh;
            s.angular[i] = self.pi_new[i] + (self.torque1[i] + self.damp_t[i]) * hh;
        }
        let (mut lin, mut ang) = (core::mem::take(&mut s.linear), core::mem::take(&mut s.angular));
        self.project(sys, &mut lin, &mut ang, hh, any_rows, false);
        s.linear = lin;
        s.angular = ang;
        s.r0.clear();
        let e = geometry.restitution;
        for (rows, &k) in s.rows.iter().zip(&s.active) {
            for i in 0..3 {
                s.r0.push(rows.rate(i, &self.vel, &self.omega));
            }
            if e > 0.0 {
                // Separate at e times the approach speed: r_n = v_n⁺ − e u ≥ 0.
                let at = s.r0.len() - 3;
                s.r0[at] -= e * s.approach[k];
            }
        }
        self.prepare_response(sys, &mut s, hh, false);
        s.sigma.clear();
        s.sigma.resize(3 * n, 0.0);
        s.rates.resize(3 * n, 0.0);
        // Warm start from the last velocity solve's matching contacts (a resting stack
        // carries the same forces step after step).
        s.end_points.clear();
        let points = &s.points;
        s.end_points.extend(s.active.iter().map(|&k| points[k]));
        warm(
            &s.end_points,
            &s.last_end_points,
            &s.last_end_sigma,
            geometry.length,
            &mut s.sigma,
            &mut s.order,
        );
        let vscale = (0..sys.mass.len()).fold(sys.velocity_floor(), |m, i| {
            m.max(self.vel[i].norm() + geometry.length * self.omega[i].norm())
        });
        let tol = 1e-12 * vscale;
        let done = solve_contacts(sys, &mut s, hh, tol);
        report.contact_sweeps += u32::try_from(done.sweeps).unwrap_or(u32::MAX);
        if !done.converged {
            let worst = done.worst / vscale;
            self.contact = s;
            return Err(Error::NewtonDidNotConverge {
                method: self.method_name,
                equation: "the contact cone problem of the velocity solve (projected Gauss-Seidel)",
                t,
                h: 2.0 * hh,
                residual: worst,
                iterations: u32::try_from(done.sweeps).unwrap_or(u32::MAX),
            });
        }
        for (k, rows) in s.rows.iter().enumerate() {
            for i in 0..3 {
                rows.apply(i, s.sigma[3 * k + i], &mut self.damp_f, &mut self.damp_t);
            }
        }
        core::mem::swap(&mut s.last_end_points, &mut s.end_points);
        s.last_end_sigma.clear();
        s.last_end_sigma.extend_from_slice(&s.sigma);
        self.contact = s;
        Ok(true)
    }
}

/// Start each of `points` from the force of the same contact in `last` (the same bodies and
/// material points within `1e-9` of the contact length, the same normal): `sigma` (zero
/// elsewhere). `order` is scratch: `last` sorted by its bodies, searched by bisection.
fn warm(
    points: &[ContactPoint],
    last: &[ContactPoint],
    last_sigma: &[f64],
    length: f64,
    sigma: &mut [f64],
    order: &mut Vec<(f64, usize)>,
) {
    let key = |p: &ContactPoint| (p.a.unwrap_or(usize::MAX), p.b.unwrap_or(usize::MAX));
    let close = 1e-9 * length;
    order.clear();
    order.extend((0..last.len()).map(|j| (0.0, j)));
    order.sort_unstable_by_key(|&(_, j)| (key(&last[j]), j));
    for (k, p) in points.iter().enumerate() {
        let want = key(p);
        let from = order.partition_point(|&(_, j)| key(&last[j]) < want);
        for &(_, j) in order[from..].iter().take_while(|&&(_, j)| key(&last[j]) == want) {
            let q = &last[j];
            if (q.pa - p.pa).norm() <= close && (q.pb - p.pb).norm() <= close && (q.nb - p.nb).norm() <= 1e-9 {
                sigma[3 * k..3 * k + 3].copy_from_slice(&last_sigma[3 * j..3 * j + 3]);
                break;
            }
        }
    }
}

/// The cone problem of `s` (`W` dense in `s.w`, `r₀`, `µ`) from the forces in `s.sigma`, with
/// the active-set finish (`polish.rs`).
fn solve_dense(s: &mut ContactScratch, tol: f64) -> cone::Solved {
    let ContactScratch {
        w,
        r0,
        mu,
        sigma,
        rates,
        kept,
        polish,
        slide,
        newton,
        ..
    } = s;
    kept.resize(r0.len(), 0.0);
    let mut dense = cone::Dense { w, rates: kept };
    dense.start(r0, sigma);
    cone::solve(&mut dense, mu, sigma, rates, tol, |d, sigma, _| {
        super::polish::polish(w, r0, mu, sigma, d.rates, tol, polish)
            || super::newton::newton(w, r0, mu, sigma, d.rates, tol, newton)
            || super::polish::slide_newton(w, r0, mu, sigma, d.rates, tol, slide)
    })
}

/// `W` applied body by body over free bodies: the forces' velocity changes `dv`, `dw` kept
/// per body, each contact's rates read from its two bodies (linear in the contacts).
struct Local<'a> {
    rows: &'a [Rows],
    r0: &'a [f64],
    blocks: &'a [[[f64; 3]; 3]],
    dv: &'a mut [Vec3],
    dw: &'a mut [Vec3],
    sys: &'a MultibodySystem,
    hh: f64,
}

impl Local<'_> {
    /// Set the velocity changes to those of the forces `sigma`.
    fn start(&mut self, sigma: &[f64]) {
        self.dv.iter_mut().for_each(|v| *v = Vec3::ZERO);
        self.dw.iter_mut().for_each(|v| *v = Vec3::ZERO);
        for k in 0..self.rows.len() {
            self.add_unchecked(k, [sigma[3 * k], sigma[3 * k + 1], sigma[3 * k + 2]]);
        }
    }

    fn add_unchecked(&mut self, k: usize, delta: [f64; 3]) {
        let rows = &self.rows[k];
        let (mut lin, mut ang_a, mut ang_b) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        for (i, d) in delta.iter().enumerate() {
            lin += rows.dir[i] * (self.hh * d);
            ang_a += rows.ta[i] * (self.hh * d);
            ang_b += rows.tb[i] * (self.hh * d);
        }
        if let Some(a) = rows.a {
            self.dv[a] += lin * (1.0 / self.sys.mass[a]);
            self.dw[a] += self.sys.inertia[a].apply_inverse(ang_a);
        }
        if let Some(b) = rows.b {
            self.dv[b] -= lin * (1.0 / self.sys.mass[b]);
            self.dw[b] -= self.sys.inertia[b].apply_inverse(ang_b);
        }
    }
}

impl cone::Response for Local<'_> {
    fn block(&self, k: usize) -> [[f64; 3]; 3] {
        self.blocks[k]
    }

    fn rates(&self, k: usize) -> [f64; 3] {
        core::array::from_fn(|i| self.r0[3 * k + i] + self.rows[k].rate(i, self.dv, self.dw))
    }

    fn add(&mut self, k: usize, delta: [f64; 3]) {
        self.add_unchecked(k, delta);
    }
}

impl super::cluster::Coupled for Local<'_> {
    fn bodies(&self, k: usize) -> [Option<usize>; 2] {
        [self.rows[k].a, self.rows[k].b]
    }

    fn coupling(&self, i: usize, j: usize) -> [[f64; 3]; 3] {
        let (ri, rj) = (&self.rows[i], &self.rows[j]);
        let mut block = [[0.0; 3]; 3];
        // Each body the two contacts share, with the sign of each contact's force on it.
        for (body_i, sign_i, ti) in [(ri.a, 1.0, &ri.ta), (ri.b, -1.0, &ri.tb)] {
            for (body_j, sign_j, tj) in [(rj.a, 1.0, &rj.ta), (rj.b, -1.0, &rj.tb)] {
                let (Some(bi), Some(bj)) = (body_i, body_j) else {
                    continue;
                };
                if bi != bj {
                    continue;
                }
                let inv_m = 1.0 / self.sys.mass[bi];
                let it: [Vec3; 3] = core::array::from_fn(|c| self.sys.inertia[bi].apply_inverse(tj[c]));
                let scale = self.hh * sign_i * sign_j;
                for (r, row) in block.iter_mut().enumerate() {
                    for (c, x) in row.iter_mut().enumerate() {
                        *x += scale * (ri.dir[r].dot(rj.dir[c]) * inv_m + ti[r].dot(it[c]));
                    }
                }
            }
        }
        block
    }
}

impl ContactScratch {
    /// The body-by-body response over `self`'s rows at the forces in `sigma`, with the
    /// forces, the rates and the friction coefficients beside it.
    fn local<'s>(
        &'s mut self,
        sys: &'s MultibodySystem,
        hh: f64,
    ) -> (Local<'s>, &'s mut [f64], &'s mut [f64], &'s [f64]) {
        let ContactScratch {
            rows,
            blocks,
            dv,
            dw,
            sigma,
            r0,
            rates,
            mu,
            ..
        } = self;
        let mut local = Local {
            rows,
            r0,
            blocks,
            dv,
            dw,
            sys,
            hh,
        };
        local.start(sigma);
        (local, sigma, rates, mu)
    }
}

/// `s.r0 = s.rates − W σ`: the constant of the problem linearised about the current forces.
fn minus_w_sigma(sys: &MultibodySystem, s: &mut ContactScratch, hh: f64) {
    let m = s.rates.len();
    if s.local {
        // With r₀ = 0 the response's rates are W σ.
        s.r0.iter_mut().for_each(|x| *x = 0.0);
        let (local, _, rates, _) = s.local(sys, hh);
        for k in 0..local.rows.len() {
            let ws = cone::Response::rates(&local, k);
            for i in 0..3 {
                rates[3 * k + i] -= ws[i];
            }
        }
        s.r0.copy_from_slice(&s.rates);
        return;
    }
    for i in 0..m {
        let row = &s.w[i * m..(i + 1) * m];
        s.r0[i] = s.rates[i] - row.iter().zip(&s.sigma).map(|(a, b)| a * b).sum::<f64>();
    }
}

/// The cone problem of `s` from the forces in `s.sigma`, by the response `s` is prepared
/// for.
fn solve_contacts(sys: &MultibodySystem, s: &mut ContactScratch, hh: f64, tol: f64) -> cone::Solved {
    if !s.local {
        return solve_dense(s, tol);
    }
    let mut cluster = core::mem::take(&mut s.cluster);
    let (mut local, sigma, rates, mu) = s.local(sys, hh);
    let bodies = sys.mass.len();
    let done = cone::solve(&mut local, mu, sigma, rates, tol, |response, sigma, rates| {
        super::cluster::finish(response, bodies, mu, sigma, rates, tol, &mut cluster)
    });
    s.cluster = cluster;
    done
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multibody::{mjcf, MultibodyMethod, Simulation};
    use cone::Response;

    /// The cluster finish's coupling blocks are the body-by-body response itself: `W_ij`
    /// column by column from a unit force on contact `j` (two columns of spheres on a floor,
    /// and a box leaning across them).
    #[test]
    fn the_coupling_blocks_are_the_responses_columns() {
        let mut bodies = String::new();
        for (k, (x, z)) in [(0.0, 0.1), (0.0, 0.3), (0.0, 0.5), (0.25, 0.1), (0.25, 0.3)]
            .iter()
            .enumerate()
        {
            bodies += &format!(
                "<body name=\"s{k}\" pos=\"{x} 0 {z}\"><freejoint/><geom type=\"sphere\" size=\"0.1\" mass=\"{m}\"/></body>",
                m = 1.0 + k as f64
            );
        }
        bodies += "<body name=\"lid\" pos=\"0.125 0 0.65\" quat=\"0.99 0 0.1 0\"><freejoint/>\
                   <geom type=\"box\" size=\"0.3 0.1 0.05\" mass=\"2\"/></body>";
        let text = format!("<mujoco><worldbody><geom type=\"plane\" size=\"0 0 1\"/>{bodies}</worldbody></mujoco>");
        let model = mjcf::parse(&text, "columns.xml").unwrap().model;
        let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
        let (sys, state) = (&prepared.simulation.system, &prepared.state);
        let geometry = sys.contact.as_ref().unwrap();
        let (mut points, mut broad, mut manifolds) = (Vec::new(), super::super::detect::Broad::default(), Vec::new());
        let margin = vec![0.05; sys.mass.len()];
        geometry.detect(
            &state.c,
            &state.rotation,
            &margin,
            &mut points,
            &mut broad,
            &mut manifolds,
        );
        assert!(points.len() >= 6, "{} points", points.len());
        let (c, r) = (&state.c, &state.rotation);
        let rows: Vec<Rows> = points
            .iter()
            .map(|p| {
                let (x, n) = p.application(c, r);
                Rows::at(p, c, r, x, [n, p.t1, p.t2])
            })
            .collect();
        let n = rows.len();
        let r0 = vec![0.0; 3 * n];
        let (mut dv, mut dw) = (vec![Vec3::ZERO; sys.mass.len()], vec![Vec3::ZERO; sys.mass.len()]);
        let hh = 5e-4;
        let mut local = Local {
            rows: &rows,
            r0: &r0,
            blocks: &[],
            dv: &mut dv,
            dw: &mut dw,
            sys,
            hh,
        };
        let mut worst: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for j in 0..n {
            for col in 0..3 {
                local.start(&vec![0.0; 3 * n]);
                let mut unit = [0.0; 3];
                unit[col] = 1.0;
                local.add(j, unit);
                for i in 0..n {
                    let rates = local.rates(i);
                    let block = super::super::cluster::Coupled::coupling(&local, i, j);
                    for row in 0..3 {
                        worst = worst.max((rates[row] - block[row][col]).abs());
                        scale = scale.max(rates[row].abs());
                    }
                }
            }
        }
        assert!(scale > 0.0 && worst <= 1e-15 * scale, "worst {worst:e} of {scale:e}");
    }
}
