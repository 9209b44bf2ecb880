//! The response `W = (h/2) D P M⁻¹ Dᵀ` of the contact problems and the solves over it: each
//! contact's three rows, `W` formed densely (projected on the joints column by column) or
//! applied body by body over free bodies (`Local`), and the cone solve with the finishes
//! each allows (`polish.rs` and `newton.rs` on a dense `W`; none on `Local`).
//!
//! Reference: docs/theory/multibody.md §6.

use crate::linalg::Vec3;

use super::super::system::MultibodySystem;
use super::super::workspace::Workspace;
use super::cone;
use super::scratch::{ContactScratch, Rows};

/// Contacts on free bodies from which `W` is applied body by body (`Local`) instead of
/// formed.
const LOCAL_FROM: usize = 64;

impl Workspace {
    /// The contact problem's response `W = (h/2) D P M⁻¹ Dᵀ` over `s.rows` (row-major into
    /// `s.w`): column by column, the rates after a half-kick by a unit force on one row,
    /// projected on the joints (the start rows or the end rows, factored).
    pub(super) fn contact_response(&mut self, sys: &MultibodySystem, s: &mut ContactScratch, hh: f64, start: bool) {
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
    pub(super) fn prepare_response(&mut self, sys: &MultibodySystem, s: &mut ContactScratch, hh: f64, start: bool) {
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
}

/// The cone problem of `s` (`W` dense in `s.w`, `r₀`, `µ`) from the forces in `s.sigma`, with
/// the active-set finish (`polish.rs`).
fn solve_dense(s: &mut ContactScratch, tolerance: cone::Tolerance) -> cone::Solved {
    let tol = tolerance.exact;
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
        memory,
        ..
    } = s;
    kept.resize(r0.len(), 0.0);
    let mut dense = cone::Dense { w, rates: kept };
    dense.start(r0, sigma);
    memory.extrapolate = false;
    cone::solve(&mut dense, mu, sigma, rates, tolerance, memory, |d, sigma, _| {
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
pub(super) fn minus_w_sigma(sys: &MultibodySystem, s: &mut ContactScratch, hh: f64) {
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
pub(super) fn solve_contacts(
    sys: &MultibodySystem,
    s: &mut ContactScratch,
    hh: f64,
    tolerance: cone::Tolerance,
) -> cone::Solved {
    if !s.local {
        return solve_dense(s, tolerance);
    }
    let mut memory = core::mem::take(&mut s.memory);
    memory.extrapolate = true;
    let (mut local, sigma, rates, mu) = s.local(sys, hh);
    let done = cone::solve(&mut local, mu, sigma, rates, tolerance, &mut memory, |_, _, _| false);
    s.memory = memory;
    done
}
