//! The contact forces in the step's two half-kicks (module docs of `contact`): the position
//! problem's outer iteration around the drift, the second detection at its end, and the
//! velocity problem with the μ-kick (the rows and `W` in `response.rs`, their data in
//! `scratch.rs`).

use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};

use super::super::method::StepReport;
use super::super::state::MultibodyState;
use super::super::system::MultibodySystem;
use super::super::workspace::Workspace;
use super::cone;
use super::detect::tangents;
use super::response::{minus_w_sigma, solve_contacts};
use super::scratch::{ContactScratch, Rows};
use super::warm::{warm, WarmReach};

/// Most passes of the position problem with points its drift's end found (`missed_contacts`).
const MAX_PASSES: usize = 3;

/// Most outer iterations of the position problem (each re-runs the drift).
const MAX_OUTER: usize = 50;

/// A point found at the drift's end within this distance (relative to the contact length)
/// of one of the problem's, with the same normal, is that contact slid (`missed_contacts`).
const SAME_CONTACT: f64 = 1e-3;

/// The law's violation (gap and slide over the step, relative to the contact length) a
/// step is taken at where the position problem's iteration stops short of its tolerance
/// (`1e-12`): a few contacts sliding together near their friction limit, whose cone
/// problem Gauss–Seidel and the finishes do not bring lower (piles). `1e-8` of the length
/// is far below the step's own error (`O(h³)`: `g h³ ≈ 1e-8` m at `h = 1e-3`) and does not
/// accumulate in the gaps (each step closes the gap it starts with); such steps are
/// counted (`StepReport::loose_steps`).
const ACCEPT: f64 = 1e-8;

impl Workspace {
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
            // The same contact slid within the step (a ball's point on a floor, a capsule
            // along another): the same pair, its point and normal at the drift's end where
            // one of the problem's is. Its depth differs from that point's by the slide's
            // second-order term, and the next step detects it afresh; adding it would
            // give the problem two nearly equal rows with different gaps, on which
            // Gauss–Seidel stalls (a falling humanoid's capsules, piles).
            let (x, nrm) = p.application(&self.c_new, &self.r_new);
            let covered = s.points[..before].iter().any(|q| {
                if q.a != p.a || q.b != p.b {
                    return false;
                }
                if (q.pa - p.pa).norm() <= close && (q.pb - p.pb).norm() <= close {
                    return true;
                }
                let (xq, nq) = q.application(&self.c_new, &self.r_new);
                (xq - x).norm() <= SAME_CONTACT * geometry.length && nq.dot(nrm) >= 1.0 - 1e-6
            });
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
        s.mu.extend(s.points.iter().map(|p| {
            if p.gap(c, r) <= 1e-6 * length && !s.frictionless_drift {
                p.mu
            } else {
                0.0
            }
        }));
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
        // Warm start: a contact found at (nearly) the same material points as in the last
        // step starts from its last force.
        let reach = WarmReach::of(sys, &self.rows0);
        warm(
            &s.points,
            &s.last_points,
            &s.last_sigma,
            length,
            reach,
            &mut s.sigma,
            &mut s.order,
        );
        // No friction where the drift holds none (the cone's radius is zero there, and its
        // law would not see a warm friction force).
        for (sigma, &mu) in s.sigma.chunks_exact_mut(3).zip(&s.mu) {
            if mu == 0.0 {
                sigma[1] = 0.0;
                sigma[2] = 0.0;
            }
        }
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
        // The forces with the least violation at their drift's end so far: where the
        // iteration stops short of `tol`, a step whose law holds to `ACCEPT` of the length
        // is taken with them (one more drift) and counted.
        let accept = ACCEPT * length / h;
        let mut best = f64::INFINITY;
        s.sigma_best.clear();
        s.sigma_best.resize(3 * n, 0.0);
        let mut final_drift = false;
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
            if final_drift && worst <= accept {
                report.loose_steps += 1;
                report.loose_violation = report.loose_violation.max(worst * h / length);
            }
            if worst < best {
                best = worst;
                s.sigma_best.copy_from_slice(&s.sigma);
            }
            if worst <= tol || (final_drift && worst <= accept) {
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
                    if !final_drift && best <= accept {
                        final_drift = true;
                        s.sigma.copy_from_slice(&s.sigma_best);
                        continue;
                    }
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
            if outer >= MAX_OUTER || final_drift {
                if !final_drift && best <= accept {
                    final_drift = true;
                    s.sigma.copy_from_slice(&s.sigma_best);
                    continue;
                }
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
            // piles sooner); the step is accepted above, on the law at the drift's end. A
            // solve that stalls within half the acceptance stops after 40 sweeps without
            // halving its violation instead of 300 (`cone::Tolerance::loose`): measured on
            // 100 boxes and spheres falling into a bin, to t = 0.9 s, 46.8 → 28.9 s (with the
            // cluster finish of that time, since removed).
            let inner = cone::Tolerance {
                exact: (0.25 * tol).max(1e-3 * worst),
                loose: 0.5 * accept,
                plain_after_stall: false,
            };
            let done = solve_contacts(sys, s, hh, inner);
            report.contact_sweeps += u32::try_from(done.sweeps).unwrap_or(u32::MAX);
            if !done.converged {
                stalled = Some((done, worst));
            }
            if self.rows0.iter().any(|r| r.n > 0) {
                self.follow_contact_forces(sys, s, hh);
            }
        }
        unreachable!("the outer loop returns")
    }

    /// The joints' multipliers moved with the contact forces' change since the last drift
    /// (`s.sigma − s.sigma_ok`), to first order: the multipliers that keep the start rows'
    /// rates of that impulse at zero, one solve with the factored `G M⁻¹ Gᵀ` (the position
    /// solve's quasi-Newton matrix). Without it each contact iteration's drift started the
    /// joints from the last iteration's multipliers, a residual of the order of the force
    /// change: on the standing quadruped 5.5e-6 and five position iterations, with it
    /// 4.9e-10 and three (545 → 488 M instructions to 0.3 s, callgrind).
    fn follow_contact_forces(&mut self, sys: &MultibodySystem, s: &mut ContactScratch, hh: f64) {
        let (mut lin, mut ang) = (core::mem::take(&mut s.linear), core::mem::take(&mut s.angular));
        lin.iter_mut().for_each(|v| *v = Vec3::ZERO);
        ang.iter_mut().for_each(|v| *v = Vec3::ZERO);
        for (k, rows) in s.rows.iter().enumerate() {
            for i in 0..3 {
                let change = s.sigma[3 * k + i] - s.sigma_ok[3 * k + i];
                if change != 0.0 {
                    rows.apply(i, hh * change, &mut lin, &mut ang);
                }
            }
        }
        self.project(sys, &mut lin, &mut ang, hh, true, true);
        s.linear = lin;
        s.angular = ang;
        for ((jr, delta), lambda) in self.rows0.iter().zip(&self.delta).zip(&mut self.lambda) {
            for (l, d) in lambda[..jr.n].iter_mut().zip(&delta[..jr.n]) {
                *l += d;
            }
        }
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
            s.end_count = 0;
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
        // The speed scale of the velocity solve's tolerance: the bodies' speeds after the
        // μ-kick without contact forces (read before the response is formed, whose
        // projections per column overwrite `vel`, `omega`).
        let vscale = (0..sys.mass.len()).fold(sys.velocity_floor(), |m, i| {
            m.max(self.vel[i].norm() + geometry.length * self.omega[i].norm())
        });
        self.prepare_response(sys, &mut s, hh, false);
        s.sigma.clear();
        s.sigma.resize(3 * n, 0.0);
        s.rates.resize(3 * n, 0.0);
        // Warm start from the last velocity solve's matching contacts (a resting stack
        // carries the same forces step after step).
        s.end_points.clear();
        let points = &s.points;
        s.end_points.extend(s.active.iter().map(|&k| points[k]));
        let reach = WarmReach::of(sys, &self.rows1);
        warm(
            &s.end_points,
            &s.last_end_points,
            &s.last_end_sigma,
            geometry.length,
            reach,
            &mut s.sigma,
            &mut s.order,
        );
        // A solve that stalls is taken where what it leaves would move a contact by at most
        // `ACCEPT` of the length over a step (the position problem's acceptance), counted.
        let accept = ACCEPT * geometry.length / (2.0 * hh);
        let tolerance = cone::Tolerance {
            exact: 1e-12 * vscale,
            loose: accept,
            plain_after_stall: true,
        };
        let done = solve_contacts(sys, &mut s, hh, tolerance);
        report.contact_sweeps += u32::try_from(done.sweeps).unwrap_or(u32::MAX);
        if !done.converged && done.worst <= accept {
            report.loose_steps += 1;
            report.loose_violation = report.loose_violation.max(done.worst * 2.0 * hh / geometry.length);
        } else if !done.converged {
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
        s.end_count = n;
        self.contact = s;
        Ok(true)
    }

    /// The contacts touching at the end of the last step at `(c, R)` (its end), each as
    /// its point and the force of the step's closing half-kick on body `a` (from `b`; N),
    /// `[x, y, z, f_x, f_y, f_z]`, appended to `out`.
    pub(in crate::multibody) fn contact_forces(&self, c: &[Vec3], r: &[Mat3], out: &mut Vec<[f64; 6]>) {
        let s = &self.contact;
        let n = s.end_count.min(s.last_end_points.len());
        for (p, sigma) in s.last_end_points[..n].iter().zip(s.last_end_sigma.chunks_exact(3)) {
            let (x, nrm) = p.application(c, r);
            let (t1, t2) = tangents(nrm);
            let f = nrm * sigma[0] + t1 * sigma[1] + t2 * sigma[2];
            out.push([x.x, x.y, x.z, f.x, f.y, f.z]);
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::multibody::{mjcf, MultibodyMethod, Simulation};

    /// The last resort of a failed step (friction in the closing kick only) on a box at rest
    /// on a 20° slope with µ = 0.5 (it sticks: tan 20° = 0.36): within that step it slides
    /// `h² g sin θ / 2`, and the closing kick's friction, bounded by that kick's normal
    /// impulse `µ (h/2) g cos θ`, leaves it moving downhill at `h g sin θ − µ (h/2) g cos θ`.
    /// The next steps, holding it in both kicks, stop it, and it stays put.
    #[test]
    fn a_step_with_friction_in_the_closing_kick_only_slides_half_a_step_of_gravity() {
        let (slope, h, g, mu) = (20f64.to_radians(), 1e-3, 9.81, 0.5);
        let (sn, cs) = slope.sin_cos();
        let (qw, qy) = ((slope / 2.0).cos(), (slope / 2.0).sin());
        let text = format!(
            "<mujoco><worldbody><geom type=\"plane\" size=\"0 0 1\" euler=\"0 {deg} 0\" friction=\"{mu}\"/>\
             <body name=\"box\"><freejoint/><geom type=\"box\" size=\"0.1 0.1 0.1\" mass=\"1\" friction=\"{mu}\"/></body>\
             </worldbody><keyframe><key qpos=\"{px} 0 {pz} {qw} 0 {qy} 0\"/></keyframe></mujoco>",
            deg = slope.to_degrees(),
            px = 0.1 * sn,
            pz = 0.1 * cs,
        );
        let model = mjcf::parse(&text, "slope.xml").unwrap().model;
        let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
        let (mut sim, mut state) = (prepared.simulation, prepared.state);
        let downhill = |c: crate::linalg::Vec3| c.x * cs - c.z * sn;
        // One ordinary step: it sticks.
        let start = downhill(state.c[0]);
        sim.step(&mut state, h).unwrap();
        assert!((downhill(state.c[0]) - start).abs() <= 1e-13);
        let start = downhill(state.c[0]);
        sim.integrator.work.contact.frictionless_drift = true;
        let report = sim.step(&mut state, h).unwrap();
        sim.integrator.work.contact.frictionless_drift = false;
        assert!(report.contacts >= 4, "{report:?}");
        let slid = downhill(state.c[0]) - start;
        let expected = 0.5 * h * h * g * sn;
        assert!(
            (slid - expected).abs() <= 1e-9 * expected,
            "slid {slid:e}, expected {expected:e}"
        );
        // The closing kick's normal impulse is the first kick's complement to within the
        // position problem's tolerance as a rate (`1e-12 L / h`), and its friction µ times it.
        let speed = downhill(state.p[0]);
        let expected = h * g * sn - mu * 0.5 * h * g * cs;
        let length = sim.system.contact.as_ref().unwrap().length;
        let bound = mu * 1e-12 * length / h;
        assert!(
            (speed - expected).abs() <= bound,
            "speed {speed:e}, expected {expected:e}, bound {bound:e}"
        );
        for _ in 0..3 {
            sim.step(&mut state, h).unwrap();
        }
        assert!(state.p[0].norm() <= 1e-12, "still moving: {:?}", state.p[0]);
        let before = downhill(state.c[0]);
        for _ in 0..100 {
            sim.step(&mut state, h).unwrap();
        }
        let moved = (downhill(state.c[0]) - before).abs();
        assert!(moved <= 1e-12, "moved {moved:e} in 100 steps after");
    }
}
