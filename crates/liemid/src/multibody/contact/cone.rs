//! The contact problem of one half-kick: `r = r₀ + W σ` over the contacts (three rows each:
//! normal, two tangents), with
//!
//! ```text
//!     r_n ≥ 0,  σ_n ≥ 0,  r_n σ_n = 0,
//!     |σ_t| ≤ µ σ_n,  r_t = 0 where |σ_t| < µ σ_n,  r_t = −κ σ_t (κ ≥ 0) on the edge,
//! ```
//!
//! Coulomb's law with the exact (elliptic) cone and maximal dissipation. Solved by projected
//! Gauss–Seidel over the contacts: each contact's normal force with its friction held, then
//! its friction force as the minimiser of `½ σ_tᵀ W_tt σ_t + ρ_tᵀ σ_t` over the disc
//! `|σ_t| ≤ µ σ_n` (its optimality conditions are exactly the law above: inside, `r_t = 0`;
//! on the edge, `r_t = −κ σ_t`), the others held. That alternation's fixed point is found
//! at once where the contact sticks (one 3x3 solve, `stick`) or, approaching, slides (one
//! scalar root for κ, `slide`); the alternation runs only where neither applies (on a
//! pile of boxes and spheres it took 6.5 passes a contact where it ran, each a disc solve,
//! and the disc was 60 % of the run's time). A sweep ends with the law's worst
//! violation, and the solve stops when it is below the tolerance; it fails after
//! [`MAX_SWEEPS`] sweeps.
//!
//! Over free bodies (`Local`: piles) the sweeps are extrapolated as in Nesterov's method:
//! after sweep `k` (counted from the last restart) the forces move on to
//! `σ_k + k/(k+3) (σ_k − σ_{k−1})`, clamped into the cones (`σ_n ≥ 0`, then `σ_t` scaled
//! radially into its disc: feasible, not the Euclidean projection), and the extrapolation
//! restarts from 0 whenever the worst violation grows (an adaptive restart) or a finish or
//! `align` changes the forces. The tolerance is checked at the extrapolated forces, so what is
//! accepted obeys the law as before; measured on 100 spheres falling into a bin (to
//! t = 1.2 s), 314,002 → 109,229 sweeps and 18.7 → 5.2 s. On jointed bodies (the dense
//! `W`) it is not used: on the falling humanoid it made a position solve stall above the
//! acceptance where plain sweeps do not.
//!
//! Reference: M. Jean, "The non-smooth contact dynamics method", CMAME 177 (1999) (NSCD,
//! Gauss–Seidel over contacts); J. J. Moré, D. C. Sorensen, SIAM J. Sci. Stat. Comput. 4
//! (1983) (the disc-constrained minimiser); B. O'Donoghue, E. Candès, "Adaptive restart for
//! accelerated gradient schemes", Found. Comput. Math. 15 (2015); H. Mazhar et al., ACM
//! Trans. Graph. 34 (2015) (Nesterov's method on the contact cone problem).

use super::block::{norm2, slide, stick, Disc};

/// Most sweeps of one solve.
pub(super) const MAX_SWEEPS: usize = 2000;

/// Sweeps within which a solve must halve its worst violation, else it is stalled and
/// stops (a pile's solves that cycle did not move in 2000 sweeps; the slowest converging
/// ones measured, contacts sliding together at 0.25 % a sweep before `align`, halve in
/// under 280).
const STALL_SWEEPS: usize = 300;

/// Sweeps within which a solve already inside its caller's acceptance (`Tolerance::loose`)
/// must halve its violation, else it stops as stalled: the falling humanoid's velocity
/// solves on its redundant resting contacts (a mode of `W` at 1e-6 of its largest)
/// shrink their violation by a factor of about `1 − 2e-5` a sweep, and would spend all of
/// [`STALL_SWEEPS`] to be taken at the acceptance all the same. Such a solve tries the
/// finishes once or twice (from sweep 20) instead of up to four times.
const LOOSE_STALL_SWEEPS: usize = 40;

/// What a solve aims at.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tolerance {
    /// The law's worst violation at which the solve has converged.
    pub exact: f64,
    /// What the caller takes from a stalled solve (0: nothing): a solve whose violation is
    /// at most this stops as stalled after [`LOOSE_STALL_SWEEPS`] without halving it.
    pub loose: f64,
    /// A solve that stalls outside `loose` while extrapolating goes on with plain sweeps
    /// (the velocity solve, which nothing retries but a split; the position solve's outer
    /// iteration has its own recourse, and 300 more sweeps there cost more than they save).
    pub plain_after_stall: bool,
}

/// The outcome of a solve: sweeps made and the law's worst violation at the end.
#[derive(Clone, Copy, Debug)]
pub(super) struct Solved {
    pub sweeps: usize,
    pub worst: f64,
    pub converged: bool,
}

/// Most alternations of normal and friction force within one contact per sweep.
const BLOCK_PASSES: usize = 16;

/// Sweeps between attempts to finish the solve another way (the dense response's
/// active-set finish, `polish.rs`).
pub(super) const FINISH_EVERY: usize = 20;

/// `W` as the solve sees it: each contact's 3x3 block, the current rates of a contact, and
/// the update of every rate when one contact's force changes.
pub(super) trait Response {
    /// Contact `k`'s diagonal block of `W`.
    fn block(&self, k: usize) -> [[f64; 3]; 3];
    /// Contact `k`'s rates `r₀ + W σ` at the current forces.
    fn rates(&self, k: usize) -> [f64; 3];
    /// Contact `k`'s force changed by `delta`.
    fn add(&mut self, k: usize, delta: [f64; 3]);
}

/// `W` dense (row-major, `3n × 3n`), the rates kept up to date column by column.
pub(super) struct Dense<'a> {
    pub w: &'a [f64],
    pub rates: &'a mut [f64],
}

/// `rates = r₀ + W σ` with `W` dense (row-major, `3n × 3n`).
pub(super) fn rates_at(w: &[f64], r0: &[f64], sigma: &[f64], rates: &mut [f64]) {
    let m = r0.len();
    for ((rate, r0), row) in rates.iter_mut().zip(r0).zip(w.chunks_exact(m)) {
        *rate = r0 + row.iter().zip(sigma).map(|(a, b)| a * b).sum::<f64>();
    }
}

impl Dense<'_> {
    /// Start from forces `sigma`: `rates = r₀ + W σ`.
    pub fn start(&mut self, r0: &[f64], sigma: &[f64]) {
        rates_at(self.w, r0, sigma, self.rates);
    }
}

impl Response for Dense<'_> {
    fn block(&self, k: usize) -> [[f64; 3]; 3] {
        let m = self.rates.len();
        let b = 3 * k;
        core::array::from_fn(|i| core::array::from_fn(|j| self.w[(b + i) * m + b + j]))
    }

    fn rates(&self, k: usize) -> [f64; 3] {
        [self.rates[3 * k], self.rates[3 * k + 1], self.rates[3 * k + 2]]
    }

    fn add(&mut self, k: usize, delta: [f64; 3]) {
        let m = self.rates.len();
        for (j, d) in delta.iter().enumerate() {
            if *d != 0.0 {
                let col = 3 * k + j;
                for (i, ri) in self.rates.iter_mut().enumerate() {
                    *ri += self.w[i * m + col] * d;
                }
            }
        }
    }
}

/// What a solve keeps between its sweeps (grown to the contacts' number, so a solve of as
/// many contacts as a past one allocates nothing).
#[derive(Clone, Debug, Default)]
pub(super) struct Memory {
    /// Extrapolate the sweeps (module docs).
    pub extrapolate: bool,
    /// The last sweep's forces (the extrapolation's).
    previous: Vec<f64>,
    /// Per contact, the last root of its disc (NaN: none yet), where the next sweep's
    /// disc starts when that is above its own start.
    kappa: Vec<f64>,
}

#[cfg(test)]
impl Memory {
    /// A memory whose solves extrapolate their sweeps.
    pub fn extrapolating() -> Memory {
        Memory {
            extrapolate: true,
            ..Memory::default()
        }
    }
}

/// Solve for `sigma` (started from its content, with `response` at those forces) with
/// friction `mu`; `rates` receives the final rates. Stops when the worst violation is at
/// most `tolerance.exact`; every [`FINISH_EVERY`] sweeps `finish` may complete the solve (it returns
/// whether it changed `sigma` and the response). With `memory.extrapolate` the sweeps
/// are extrapolated (module docs).
pub(super) fn solve<R: Response>(
    response: &mut R,
    mu: &[f64],
    sigma: &mut [f64],
    rates: &mut [f64],
    tolerance: Tolerance,
    memory: &mut Memory,
    mut finish: impl FnMut(&mut R, &mut [f64], &[f64]) -> bool,
) -> Solved {
    let (n, tol) = (mu.len(), tolerance.exact);
    let mut sweeps = 0;
    memory.kappa.clear();
    memory.kappa.resize(n, f64::NAN);
    let kappas = &mut memory.kappa;
    let mut previous = memory.extrapolate.then_some(&mut memory.previous);
    if let Some(previous) = previous.as_deref_mut() {
        previous.clear();
        previous.extend_from_slice(sigma);
    }
    let (mut momentum, mut last_worst) = (0usize, f64::INFINITY);
    let (mut interval, mut next_finish) = (FINISH_EVERY, FINISH_EVERY);
    // The violation last halved and when: a solve that has not halved it in
    // `STALL_SWEEPS` sweeps is stalled (cycling near a cone's edge) and stops.
    let (mut anchor, mut anchor_sweep) = (f64::INFINITY, 0);
    loop {
        for k in 0..n {
            rates[3 * k..3 * k + 3].copy_from_slice(&response.rates(k));
        }
        let worst = violation(rates, sigma, mu);
        if worst <= tol {
            return Solved {
                sweeps,
                worst,
                converged: true,
            };
        }
        if worst <= 0.5 * anchor {
            (anchor, anchor_sweep) = (worst, sweeps);
        }
        if worst > last_worst {
            momentum = 0;
        }
        last_worst = worst;
        let patience = if worst <= tolerance.loose {
            LOOSE_STALL_SWEEPS
        } else {
            STALL_SWEEPS
        };
        if tolerance.plain_after_stall
            && sweeps - anchor_sweep >= patience
            && worst > tolerance.loose
            && previous.is_some()
        {
            // Stalled outside the acceptance while extrapolating: plain sweeps from here,
            // with their own patience (a pile's velocity solve that stalled at 6.5e-3 of
            // its speed scale with the extrapolation converged without it).
            previous = None;
            momentum = 0;
            (anchor, anchor_sweep) = (worst, sweeps);
        }
        if sweeps >= MAX_SWEEPS || sweeps - anchor_sweep >= patience {
            return Solved {
                sweeps,
                worst,
                converged: false,
            };
        }
        if sweeps == next_finish {
            // Once per such sweep count (each may change the forces, then the rates are
            // measured again; `next_finish` moves on either way); after a finish that
            // changed nothing the next waits twice as long (a pile's stalled solves spent
            // most of their time in finishes that failed every 20 sweeps).
            if finish(response, sigma, rates) || align(response, mu, sigma, rates) {
                interval = FINISH_EVERY;
                next_finish = sweeps + interval;
                momentum = 0;
                if let Some(previous) = previous.as_deref_mut() {
                    previous.copy_from_slice(sigma);
                }
                last_worst = f64::INFINITY;
                continue;
            }
            interval *= 2;
            next_finish = sweeps + interval;
        }
        sweeps += 1;
        for (k, &mu_k) in mu.iter().enumerate() {
            let b = 3 * k;
            let w = response.block(k);
            let r = response.rates(k);
            let old = [sigma[b], sigma[b + 1], sigma[b + 2]];
            // The rates without contact k's own force.
            let rho: [f64; 3] =
                core::array::from_fn(|i| r[i] - (w[i][0] * old[0] + w[i][1] * old[1] + w[i][2] * old[2]));
            // The contact's own 3x3 problem, normal and friction in turn until they agree
            // (a box corner's normal force turns the box and so moves the corner along the
            // plane: one pass each would leave that coupling to the outer sweeps).
            let mut new = old;
            // The disc's multiplier from the last pass or sweep (the next root is near it).
            let kappa = &mut kappas[k];
            let passes = match stick(w, rho, mu_k).or_else(|| slide(w, rho, mu_k, kappa)) {
                Some(x) => {
                    new = x;
                    0
                }
                None => BLOCK_PASSES,
            };
            let mut tangential = Disc::new([[w[1][1], w[1][2]], [w[2][1], w[2][2]]]);
            for _ in 0..passes {
                let sn = if w[0][0] > 0.0 {
                    (-(rho[0] + w[0][1] * new[1] + w[0][2] * new[2]) / w[0][0]).max(0.0)
                } else {
                    0.0
                };
                let rho_t = [rho[1] + w[1][0] * sn, rho[2] + w[2][0] * sn];
                let st = tangential.solve(rho_t, mu_k * sn, kappa);
                let next = [sn, st[0], st[1]];
                let change = (0..3).fold(0.0f64, |m, i| m.max((next[i] - new[i]).abs()));
                new = next;
                if change <= 4.0 * f64::EPSILON * (new[0].abs() + new[1].abs() + new[2].abs()) {
                    break;
                }
            }
            let delta = [new[0] - old[0], new[1] - old[1], new[2] - old[2]];
            if delta != [0.0; 3] {
                sigma[b..b + 3].copy_from_slice(&new);
                response.add(k, delta);
            }
        }
        // Nesterov's extrapolation of the sweeps, restarted when the violation grows.
        let Some(previous) = previous.as_deref_mut() else {
            continue;
        };
        let beta = momentum as f64 / (momentum as f64 + 3.0);
        momentum += 1;
        for (k, &mu_k) in mu.iter().enumerate() {
            let b = 3 * k;
            let now = [sigma[b], sigma[b + 1], sigma[b + 2]];
            let mut y: [f64; 3] = core::array::from_fn(|i| now[i] + beta * (now[i] - previous[b + i]));
            previous[b..b + 3].copy_from_slice(&now);
            y[0] = y[0].max(0.0);
            let (tl, bound) = (norm2(y[1], y[2]), mu_k * y[0]);
            if tl > bound {
                let f = if tl > 0.0 { bound / tl } else { 0.0 };
                y[1] *= f;
                y[2] *= f;
            }
            let delta = [y[0] - now[0], y[1] - now[1], y[2] - now[2]];
            if delta != [0.0; 3] {
                sigma[b..b + 3].copy_from_slice(&y);
                response.add(k, delta);
            }
        }
    }
}

/// Turn every sliding contact's friction force against its slip rate, `σ_t = −µ σ_n r̂_t`
/// at the current rates; returns whether a force changed. Gauss–Seidel leaves opposite
/// friction forces on contacts that slide together along one edge (a mode that moves
/// nothing, so the sweeps correct it only through the cone's curvature: 0.25 % per sweep on
/// a tilted cube landing on an edge); aligning them removes it at once, and the sweeps go
/// on from there.
fn align<R: Response>(response: &mut R, mu: &[f64], sigma: &mut [f64], rates: &[f64]) -> bool {
    let mut changed = false;
    for (k, &mu_k) in mu.iter().enumerate() {
        let b = 3 * k;
        let bound = mu_k * sigma[b];
        let (st, rt) = ([sigma[b + 1], sigma[b + 2]], [rates[b + 1], rates[b + 2]]);
        let rl = norm2(rt[0], rt[1]);
        if bound > 0.0 && norm2(st[0], st[1]) >= bound * (1.0 - 1e-9) && rl > 0.0 {
            let aligned = [-bound * rt[0] / rl, -bound * rt[1] / rl];
            let delta = [0.0, aligned[0] - st[0], aligned[1] - st[1]];
            if delta != [0.0; 3] {
                sigma[b + 1] = aligned[0];
                sigma[b + 2] = aligned[1];
                response.add(k, delta);
                changed = true;
            }
        }
    }
    changed
}

/// The worst violation of the law by `(rates, sigma)`.
pub(super) fn violation(rates: &[f64], sigma: &[f64], mu: &[f64]) -> f64 {
    let mut worst = 0.0f64;
    for (k, &mu) in mu.iter().enumerate() {
        let b = 3 * k;
        let (sn, rn) = (sigma[b], rates[b]);
        let normal = if sn > 0.0 { rn.abs() } else { (-rn).max(0.0) };
        let st = [sigma[b + 1], sigma[b + 2]];
        let rt = [rates[b + 1], rates[b + 2]];
        let (sl, rl) = (norm2(st[0], st[1]), norm2(rt[0], rt[1]));
        let bound = mu * sn;
        let tangential = if bound <= 0.0 {
            0.0
        } else if sl < bound * (1.0 - 1e-9) {
            rl
        } else {
            // On the edge the slip opposes the force: r_t + |r_t| σ̂_t = 0.
            let u = [st[0] / sl, st[1] / sl];
            norm2(rt[0] + rl * u[0], rt[1] + rl * u[1])
        };
        worst = worst.max(normal).max(tangential);
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two frictionless contacts whose normals differ by a hair: `W` couples their normal
    /// rows by `c` (eigenvalues `1 ± c`), `r₀ = −W (1, 1)` (both pressed, `σ_n = 1` each at
    /// the solution); solved from zero forces with `tolerance` and `memory`.
    fn nearly_parallel_pair(c: f64, tolerance: Tolerance, memory: &mut Memory) -> Solved {
        let mut w = [0.0; 36];
        for (i, j, v) in [
            (0, 0, 1.0),
            (3, 3, 1.0),
            (0, 3, c),
            (3, 0, c),
            (1, 1, 1.0),
            (2, 2, 1.0),
            (4, 4, 1.0),
            (5, 5, 1.0),
        ] {
            w[i * 6 + j] = v;
        }
        let r0 = [-(1.0 + c), 0.0, 0.0, -(1.0 + c), 0.0, 0.0];
        let (mut sigma, mut rates, mut kept) = ([0.0; 6], [0.0; 6], [0.0; 6]);
        let mut dense = Dense {
            w: &w,
            rates: &mut kept,
        };
        dense.start(&r0, &sigma);
        solve(
            &mut dense,
            &[0.0; 2],
            &mut sigma,
            &mut rates,
            tolerance,
            memory,
            |_, _, _| false,
        )
    }

    /// The pair above with `W`'s eigenvalues 2 and 1e-5: Gauss–Seidel contracts by
    /// `1 − 2e-5` a sweep along their difference. Aiming at the law exactly, the solve stops
    /// as stalled after [`STALL_SWEEPS`]; told that its caller accepts the violation it has,
    /// after [`LOOSE_STALL_SWEEPS`].
    #[test]
    fn a_stalled_solve_inside_its_acceptance_stops_sooner() {
        let run = |loose: f64| {
            let tolerance = Tolerance {
                exact: 1e-14,
                loose,
                plain_after_stall: false,
            };
            nearly_parallel_pair(1.0 - 1e-5, tolerance, &mut Memory::default())
        };
        let exact = run(0.0);
        let loose = run(1.0);
        assert!(!exact.converged && !loose.converged);
        assert!(exact.worst < 1.0 && loose.worst < 1.0, "{exact:?} {loose:?}");
        assert!(
            exact.sweeps >= STALL_SWEEPS && exact.sweeps < STALL_SWEEPS + 10,
            "{exact:?}"
        );
        assert!(
            loose.sweeps >= LOOSE_STALL_SWEEPS && loose.sweeps < LOOSE_STALL_SWEEPS + 10,
            "{loose:?}"
        );
    }

    /// The velocity solve's recourse: an extrapolated solve that stalls outside its
    /// acceptance goes on with its own patience again, without the extrapolation (the pair
    /// above with `W`'s eigenvalues 2 and 1e-7): it stops after twice the sweeps, no worse.
    /// (That the later sweeps are plain is the code's `previous = None`; the test sees the
    /// sweeps only.)
    #[test]
    fn an_extrapolated_solve_that_stalls_goes_on_with_plain_sweeps() {
        let run = |plain_after_stall: bool| {
            let tolerance = Tolerance {
                exact: 1e-14,
                loose: 0.0,
                plain_after_stall,
            };
            nearly_parallel_pair(1.0 - 1e-7, tolerance, &mut Memory::extrapolating())
        };
        let alone = run(false);
        let then_plain = run(true);
        assert!(!alone.converged && !then_plain.converged);
        assert!((STALL_SWEEPS..STALL_SWEEPS + 10).contains(&alone.sweeps), "{alone:?}");
        assert!(
            (2 * STALL_SWEEPS..2 * STALL_SWEEPS + 10).contains(&then_plain.sweeps),
            "{then_plain:?}"
        );
        assert!(then_plain.worst <= alone.worst, "{alone:?} {then_plain:?}");
    }

    #[test]
    fn one_contact_sticks_below_the_cone_and_slides_on_it() {
        // A point of unit mass on a plane: W = I (per unit force over the half-kick).
        let w = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let solve = |w: &[f64], r0: &[f64], mu: &[f64], s: &mut [f64], r: &mut [f64], tol: f64| {
            let mut kept = r0.to_vec();
            let mut dense = Dense { w, rates: &mut kept };
            dense.start(r0, s);
            super::solve(
                &mut dense,
                mu,
                s,
                r,
                Tolerance {
                    exact: tol,
                    loose: 0.0,
                    plain_after_stall: false,
                },
                &mut Memory::default(),
                |_, _, _| false,
            )
        };
        // Pushed into the plane at 1 and along it at 0.3 with µ = 0.5: sticks.
        let (mut s, mut r) = ([0.0; 3], [0.0; 3]);
        let done = solve(&w, &[-1.0, 0.3, 0.0], &[0.5], &mut s, &mut r, 1e-15);
        assert!(done.converged);
        assert_eq!(s, [1.0, -0.3, 0.0]);
        // Along it at 0.8: slides, the force at µ σ_n against the motion.
        let (mut s, mut r) = ([0.0; 3], [0.0; 3]);
        let done = solve(&w, &[-1.0, 0.8, 0.0], &[0.5], &mut s, &mut r, 1e-15);
        assert!(done.converged);
        assert_eq!(s, [1.0, -0.5, 0.0]);
        assert!((r[1] - 0.3).abs() < 1e-15 && r[0].abs() < 1e-15);
        // Moving away: no force.
        let (mut s, mut r) = ([0.0; 3], [0.0; 3]);
        assert!(solve(&w, &[0.5, 0.8, 0.0], &[0.5], &mut s, &mut r, 1e-15,).converged);
        assert_eq!(s, [0.0; 3]);
    }
}
