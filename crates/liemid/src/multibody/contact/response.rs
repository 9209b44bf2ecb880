//! The response `W = (h/2) D P M⁻¹ Dᵀ` of the contact problems and the solves over it: each
//! contact's three rows, `W` formed densely (projected on the joints column by column) on
//! jointed bodies; over free bodies one problem per island (`islands.rs`), each island's
//! `W` formed from its rows in a scene of at most [`LOCAL_FROM`] contacts, else applied
//! body by body (`Local`); and the cone solve with the finishes each allows (`polish.rs`
//! and `newton.rs` on a dense `W`; none on `Local`).
//!
//! Reference: docs/theory/multibody.md §6.

use crate::linalg::Vec3;

use super::super::constraints::JointRows;
use super::super::system::MultibodySystem;
use super::super::workspace::Workspace;
use super::cone;
use super::scratch::{ContactScratch, Finishes, Islands, Rows};

/// Contacts on free bodies from which each island's `W` is applied body by body (`Local`)
/// instead of formed with the dense finishes (`polish.rs`, `newton.rs`). The count is the
/// scene's, not the island's: a stack of ten boxes (one island of 40 contacts) needs the
/// Newton finish, while in a pile the islands of 17 to 64 resting contacts made it fail
/// at `(3n)³` a try (measured on 100 spheres falling into a bin, 2 s: 15-17 s with the
/// dense finishes on islands of at most 16 contacts and the Newton finish on those of at most 64, against 6.0-7.0 s
/// with this rule).
const LOCAL_FROM: usize = 64;

/// Most contacts of an island whose stalled body-by-body solve goes on over its dense `W`
/// with the finishes (forming `W` is `O(n²)`, a Newton iteration `(3n)³`). Measured on the
/// pile of 100 boxes and spheres drawn with seeds 1, 2 and 3, to 2 s (with the one-root
/// sliding solve, `cone.rs`): without the rescue seeds 1 and 3 stopped with an error (seed
/// 1 at t = 0.68 s, a position solve stalled after the split to `h/16` and the last
/// resort); with it all three complete, at 26.5, 28.1 and 44.9 ms a step. Up to 200
/// contacts instead the three completed to 1 s at 70-100 ms a step, and 100 spheres took
/// 22.3 s instead of 4.1: Newton on the large islands of a settled pile costs more than
/// the sweeps it saves.
const RESCUE_UP_TO: usize = 64;

/// Whether the contact problems' bodies move freely: no joint rows and no armature (then
/// `W` is applied body by body over islands, and the warm start takes only resting
/// contacts, `warm.rs`).
pub(super) fn free_bodies(sys: &MultibodySystem, rows: &[JointRows]) -> bool {
    sys.armature.is_none() && !rows.iter().any(|r| r.n > 0)
}

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

    /// Make `W` ready for the solves: over free bodies (no joint rows, no armature) the
    /// diagonal blocks and the islands, else dense (`contact_response`).
    pub(super) fn prepare_response(&mut self, sys: &MultibodySystem, s: &mut ContactScratch, hh: f64, start: bool) {
        let rows = if start { &self.rows0 } else { &self.rows1 };
        s.local = free_bodies(sys, rows);
        if !s.local {
            // The velocity solve's `W` at the end of a step is the next step's at its start
            // when the contacts, the joint rows and the half step are the same (the joints'
            // factor is the same matrix's): on the standing quadruped 946 of 1000 steps take
            // it, 12 projections fewer each (487 → 431 M instructions to 0.3 s, callgrind),
            // and the run to 2 s gives the same JSON bit for bit as forming `W` again.
            if start && s.end_w.copy_if_for(hh, &s.rows, rows, &mut s.w) {
                return;
            }
            self.contact_response(sys, s, hh, start);
            if !start {
                s.end_w.keep(&s.w, hh, &s.rows, &self.rows1);
            }
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
        s.islands.build(&s.rows, &s.blocks, sys.mass.len());
    }
}

/// The cone problem over a dense `w` (row-major) with `r₀`, `µ`, from the forces in
/// `sigma`, with the active-set and Newton finishes; `kept` holds the rates the response
/// keeps.
#[allow(clippy::too_many_arguments)]
fn solve_dense(
    w: &[f64],
    r0: &[f64],
    mu: &[f64],
    sigma: &mut [f64],
    rates: &mut [f64],
    kept: &mut Vec<f64>,
    finishes: &mut Finishes,
    memory: &mut cone::Memory,
    tolerance: cone::Tolerance,
) -> cone::Solved {
    let tol = tolerance.exact;
    let Finishes { polish, slide, newton } = finishes;
    kept.clear();
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
        let r = self.rows[k].rates(self.dv, self.dw);
        [
            self.r0[3 * k] + r[0],
            self.r0[3 * k + 1] + r[1],
            self.r0[3 * k + 2] + r[2],
        ]
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
/// for: over free bodies island by island (each to `tolerance`; the result has the most
/// sweeps any island made and the worst violation of all), else over the dense `W`.
pub(super) fn solve_contacts(
    sys: &MultibodySystem,
    s: &mut ContactScratch,
    hh: f64,
    tolerance: cone::Tolerance,
) -> cone::Solved {
    let ContactScratch {
        w,
        r0,
        mu,
        sigma,
        rates,
        kept,
        finishes,
        memory,
        islands,
        dv,
        dw,
        local,
        ..
    } = s;
    if !*local {
        return solve_dense(w, r0, mu, sigma, rates, kept, finishes, memory, tolerance);
    }
    let Islands {
        order,
        starts,
        rows,
        blocks,
        mu: island_mu,
        sigma: island_sigma,
        r0: island_r0,
        rates: island_rates,
        w: island_w,
        kept: island_kept,
        ..
    } = islands;
    gather(order, mu, 1, island_mu);
    gather(order, sigma, 3, island_sigma);
    gather(order, r0, 3, island_r0);
    island_rates.clear();
    island_rates.resize(island_r0.len(), 0.0);
    dv.iter_mut().for_each(|v| *v = Vec3::ZERO);
    dw.iter_mut().for_each(|v| *v = Vec3::ZERO);
    let mut all = cone::Solved {
        sweeps: 0,
        worst: 0.0,
        converged: true,
    };
    let dense = order.len() <= LOCAL_FROM;
    for bounds in starts.windows(2) {
        let range = bounds[0]..bounds[1];
        let (c, f) = (range.clone(), 3 * range.start..3 * range.end);
        let done = if dense {
            super::islands::dense_w(&sys.mass, &sys.inertia, &rows[c.clone()], hh, island_w);
            solve_dense(
                island_w,
                &island_r0[f.clone()],
                &island_mu[c],
                &mut island_sigma[f.clone()],
                &mut island_rates[f],
                island_kept,
                finishes,
                memory,
                tolerance,
            )
        } else {
            // The island's bodies start without velocity changes (the islands share none).
            let mut local = Local {
                rows: &rows[c.clone()],
                r0: &island_r0[f.clone()],
                blocks: &blocks[c.clone()],
                dv,
                dw,
                sys,
                hh,
            };
            let sigma = &mut island_sigma[f.clone()];
            for k in 0..local.rows.len() {
                local.add_unchecked(k, [sigma[3 * k], sigma[3 * k + 1], sigma[3 * k + 2]]);
            }
            memory.extrapolate = true;
            let swept = cone::solve(
                &mut local,
                &island_mu[c.clone()],
                sigma,
                &mut island_rates[f.clone()],
                tolerance,
                memory,
                |_, _, _| false,
            );
            if swept.converged || c.len() > RESCUE_UP_TO {
                swept
            } else {
                // A stalled island (redundant resting contacts) goes on from where the
                // sweeps stopped over its dense `W`, with the finishes: also one stalled
                // inside the caller's acceptance (rescuing only those outside it, up to 200
                // contacts, failed seed 3 and took seed 1 past 200 s of CPU to t = 1 s).
                super::islands::dense_w(&sys.mass, &sys.inertia, &rows[c.clone()], hh, island_w);
                let rescued = solve_dense(
                    island_w,
                    &island_r0[f.clone()],
                    &island_mu[c],
                    sigma,
                    &mut island_rates[f],
                    island_kept,
                    finishes,
                    memory,
                    tolerance,
                );
                cone::Solved {
                    sweeps: swept.sweeps + rescued.sweeps,
                    ..rescued
                }
            }
        };
        all = cone::Solved {
            sweeps: all.sweeps.max(done.sweeps),
            worst: all.worst.max(done.worst),
            converged: all.converged && done.converged,
        };
    }
    scatter(order, island_sigma, 3, sigma);
    scatter(order, island_rates, 3, rates);
    all
}

/// `to[j] = from[order[j]]`, `width` values each.
fn gather(order: &[usize], from: &[f64], width: usize, to: &mut Vec<f64>) {
    to.clear();
    for &k in order {
        to.extend_from_slice(&from[width * k..width * (k + 1)]);
    }
}

/// `to[order[j]] = from[j]`, `width` values each.
fn scatter(order: &[usize], from: &[f64], width: usize, to: &mut [f64]) {
    for (j, &k) in order.iter().enumerate() {
        to[width * k..width * (k + 1)].copy_from_slice(&from[width * j..width * (j + 1)]);
    }
}
