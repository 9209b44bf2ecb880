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

/// The contact's sticking force `σ = −W_kk⁻¹ ρ` (its rates all zero) where it lies inside
/// the cone (`σ_n > 0`, `|σ_t| < µ σ_n`), else `None`: the fixed point the alternation of
/// normal and friction force converges to on a sticking contact, in one 3x3 solve.
#[inline]
fn stick(w: [[f64; 3]; 3], rho: [f64; 3], mu: f64) -> Option<[f64; 3]> {
    if mu <= 0.0 {
        return None;
    }
    // Cofactors of the symmetric block.
    let c00 = w[1][1] * w[2][2] - w[1][2] * w[2][1];
    let c01 = w[1][2] * w[2][0] - w[1][0] * w[2][2];
    let c02 = w[1][0] * w[2][1] - w[1][1] * w[2][0];
    let det = w[0][0] * c00 + w[0][1] * c01 + w[0][2] * c02;
    let scale = w[0][0] * w[1][1] * w[2][2];
    // (Written so that a NaN determinant falls back to the alternation.)
    if det.is_nan() || det <= 1e-12 * scale {
        return None;
    }
    let c11 = w[0][0] * w[2][2] - w[0][2] * w[2][0];
    let c12 = w[0][1] * w[2][0] - w[0][0] * w[2][1];
    let c22 = w[0][0] * w[1][1] - w[0][1] * w[1][0];
    let c10 = w[0][2] * w[2][1] - w[0][1] * w[2][2];
    let c20 = w[0][1] * w[1][2] - w[0][2] * w[1][1];
    let c21 = w[0][2] * w[1][0] - w[0][0] * w[1][2];
    let inv = 1.0 / det;
    let x = [
        -(c00 * rho[0] + c10 * rho[1] + c20 * rho[2]) * inv,
        -(c01 * rho[0] + c11 * rho[1] + c21 * rho[2]) * inv,
        -(c02 * rho[0] + c12 * rho[1] + c22 * rho[2]) * inv,
    ];
    (x[0] > 0.0 && norm2(x[1], x[2]) < mu * x[0] * (1.0 - 1e-9)).then_some(x)
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

/// `|(x, y)|` without `hypot`'s care for overflow (forces and rates are far from it; `hypot`
/// was a quarter of a resting stack's step).
#[inline]
fn norm2(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
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

/// The eigenpairs of a 2x2 symmetric positive definite `a` of determinant `det`: λ₁ ≥ λ₂ > 0,
/// q₁ the unit eigenvector of λ₁ (from the better conditioned of its two expressions), q₂ =
/// q₁ turned a quarter.
#[inline]
fn eigen2(a: [[f64; 2]; 2], det: f64) -> ([f64; 2], [f64; 2], [f64; 2]) {
    let (mean, half) = (0.5 * (a[0][0] + a[1][1]), 0.5 * (a[0][0] - a[1][1]));
    let d = norm2(half, a[0][1]);
    // λ₂ = det/λ₁, not `mean − d`: that difference cancels on a nearly singular block
    // (a point free to move along one tangent only) and can come out 0 or negative.
    let lambda = [mean + d, det / (mean + d)];
    let q1 = if half >= 0.0 {
        [lambda[0] - a[1][1], a[0][1]]
    } else {
        [a[0][1], lambda[0] - a[0][0]]
    };
    let l1 = norm2(q1[0], q1[1]);
    let q1 = if l1 > 0.0 { [q1[0] / l1, q1[1] / l1] } else { [1.0, 0.0] };
    (lambda, q1, [-q1[1], q1[0]])
}

/// The contact's sliding force in one solve, where the alternation of normal and friction
/// force would converge to one with `σ_n > 0` on the cone's edge: with the normal rate zero,
/// `σ_n = −(ρ_n + w_ntᵀ σ_t)/w_nn`, and the tangential rates `r_t = −κ σ_t` give
/// `σ_t(κ) = −(S + κ I)⁻¹ c` with the Schur complement `S = W_tt − w_tn w_ntᵀ/w_nn` and
/// `c = ρ_t − w_tn ρ_n/w_nn`; κ ≥ 0 is a root of `g(κ) = |σ_t(κ)| − µ σ_n(κ)` (in `S`'s
/// eigenbasis `σ_t = −Q y`, `yᵢ = cᵢ/(λᵢ + κ)`). An approaching contact (`ρ_n < 0`) that
/// does not stick has `g(0) > 0` and `g(κ) < 0` beyond
/// `κ_hi = |c| (w_nn + µ |w_tn|)/(−µ ρ_n) − λ₂`, so a root lies between: Newton's method on
/// `g`, kept inside the bracket by bisection. `None` (the caller alternates) for a
/// separating contact, a degenerate block, or no root within [`SLIDE_ITERATIONS`]; started
/// at `kappa` (the last root) where that lies in the bracket, and `kappa` receives the root.
/// The force is put exactly on the edge (`|σ_t| = µ σ_n`, the last rounding).
#[inline]
fn slide(w: [[f64; 3]; 3], rho: [f64; 3], mu: f64, kappa: &mut f64) -> Option<[f64; 3]> {
    let (wnn, rn) = (w[0][0], rho[0]);
    if mu <= 0.0 || wnn.is_nan() || wnn <= 0.0 || rn.is_nan() || rn >= 0.0 {
        return None;
    }
    let p = [w[1][0], w[2][0]];
    let sc = [
        [w[1][1] - p[0] * p[0] / wnn, w[1][2] - p[0] * p[1] / wnn],
        [w[2][1] - p[1] * p[0] / wnn, w[2][2] - p[1] * p[1] / wnn],
    ];
    let c = [rho[1] - p[0] * rn / wnn, rho[2] - p[1] * rn / wnn];
    let det = sc[0][0] * sc[1][1] - sc[0][1] * sc[0][1];
    if det.is_nan() || det <= 1e-12 * sc[0][0] * sc[1][1] || sc[0][0] <= 0.0 {
        return None;
    }
    let (lambda, q1, q2) = eigen2(sc, det);
    let ct = [q1[0] * c[0] + q1[1] * c[1], q2[0] * c[0] + q2[1] * c[1]];
    let pt = [q1[0] * p[0] + q1[1] * p[1], q2[0] * p[0] + q2[1] * p[1]];
    let m = mu / wnn;
    // g and g' at κ: |y| − m (p̃·y − ρ_n).
    let g = |k: f64| {
        let d = [1.0 / (lambda[0] + k), 1.0 / (lambda[1] + k)];
        let y = [ct[0] * d[0], ct[1] * d[1]];
        let l = norm2(y[0], y[1]);
        let value = l - m * (pt[0] * y[0] + pt[1] * y[1] - rn);
        let dl = -(y[0] * y[0] * d[0] + y[1] * y[1] * d[1]) / l;
        let ds = -(pt[0] * y[0] * d[0] + pt[1] * y[1] * d[1]);
        (value, dl - m * ds, y)
    };
    let at_zero = g(0.0).0;
    let mut lo = 0.0f64;
    let mut hi = norm2(c[0], c[1]) * (wnn + mu * norm2(p[0], p[1])) / (-mu * rn) - lambda[1];
    if at_zero.is_nan() || at_zero <= 0.0 || !(hi > 0.0 && hi.is_finite()) {
        return None;
    }
    // From below the root when there is no hint (`|y|` is convex and decreasing in κ).
    let hint = core::mem::replace(kappa, f64::NAN);
    let mut k = if hint > lo && hint < hi { hint } else { lo };
    let mut root = None;
    for _ in 0..SLIDE_ITERATIONS {
        let (value, slope, y) = g(k);
        if value == 0.0 {
            root = Some((k, y));
            break;
        }
        if value > 0.0 {
            lo = k;
        } else {
            hi = k;
        }
        let newton = k - value / slope;
        let next = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - k).abs() <= 4.0 * f64::EPSILON * next || hi - lo <= 4.0 * f64::EPSILON * hi {
            root = Some((next, g(next).2));
            break;
        }
        k = next;
    }
    let (k, y) = root?;
    let st = [-(q1[0] * y[0] + q2[0] * y[1]), -(q1[1] * y[0] + q2[1] * y[1])];
    let sn = -(rn + w[0][1] * st[0] + w[0][2] * st[1]) / wnn;
    let l = norm2(st[0], st[1]);
    if !(sn > 0.0 && l > 0.0) {
        return None;
    }
    *kappa = k;
    let f = mu * sn / l;
    Some([sn, st[0] * f, st[1] * f])
}

/// Most iterations of [`slide`]'s root search (Newton converges in a few; bisection halves
/// the bracket).
const SLIDE_ITERATIONS: usize = 100;

/// The minimiser of `½ xᵀ A x + bᵀ x` over `|x| ≤ radius` (`A` 2x2 symmetric positive
/// definite): the free minimiser when inside, else `x(κ) = −(A + κ I)⁻¹ b` with `|x(κ)| =
/// radius`. In `A`'s eigenbasis (`A = Q Λ Qᵀ`, `c = Qᵀ b`) that is the secular equation
/// `|x(κ)|² = Σ cᵢ² / (λᵢ + κ)²`; κ by Newton's method on `1/|x(κ)| − 1/radius`, which
/// is concave and increasing in κ (Moré–Sorensen), started below the root at
/// `|b|/radius − λ_max` (where `|x| ≥ |b|/(λ_max + κ)` is still at least the radius; the
/// root itself when `A` is isotropic), so the iteration rises to it monotonically; or at
/// `kappa` (the last root, of a nearby problem) where that is higher: from above the root
/// the first step lands below it, and the rise goes on from there. `kappa` receives the
/// root (NaN where the minimiser is inside). [`Disc`] keeps `A`'s determinant and
/// eigenpairs over the alternation's passes of one contact, which change only `b` and
/// the radius.
#[cfg(test)]
fn disc(a: [[f64; 2]; 2], b: [f64; 2], radius: f64, kappa: &mut f64) -> [f64; 2] {
    Disc::new(a).solve(b, radius, kappa)
}

/// One contact's tangential block `A` for the disc minimiser (`disc`, above) over several
/// right-hand sides and radii: its determinant, and its eigenpairs once a solve on the
/// edge has needed them (the same operations as a solve from scratch, so the same bits;
/// on the pile of boxes and spheres the alternation made 6.5 passes a contact, each a
/// disc solve, and the disc was 60 % of the run).
struct Disc {
    a: [[f64; 2]; 2],
    det: f64,
    eigen: Option<([f64; 2], [f64; 2], [f64; 2])>,
}

impl Disc {
    fn new(a: [[f64; 2]; 2]) -> Disc {
        Disc {
            a,
            det: a[0][0] * a[1][1] - a[0][1] * a[0][1],
            eigen: None,
        }
    }

    /// The minimiser of `½ xᵀ A x + bᵀ x` over `|x| ≤ radius` with this block (`disc`).
    fn solve(&mut self, b: [f64; 2], radius: f64, kappa: &mut f64) -> [f64; 2] {
        let (a, det) = (self.a, self.det);
        let hint = core::mem::replace(kappa, f64::NAN);
        if radius <= 0.0 || (b[0] == 0.0 && b[1] == 0.0) {
            return [0.0, 0.0];
        }
        if det.is_nan() || det <= 0.0 || a[0][0] <= 0.0 {
            // A degenerate block (a body without inertia along the plane): the force against
            // the rate, at the bound.
            let l = norm2(b[0], b[1]);
            return [-radius * b[0] / l, -radius * b[1] / l];
        }
        let free = [
            -(a[1][1] * b[0] - a[0][1] * b[1]) / det,
            -(a[0][0] * b[1] - a[0][1] * b[0]) / det,
        ];
        if norm2(free[0], free[1]) <= radius {
            return free;
        }
        let (lambda, q1, q2) = *self.eigen.get_or_insert_with(|| eigen2(a, det));
        let c = [q1[0] * b[0] + q1[1] * b[1], q2[0] * b[0] + q2[1] * b[1]];
        let mut k = (norm2(c[0], c[1]) / radius - lambda[0]).max(0.0);
        if hint > k {
            k = hint;
        }
        let mut risen = false;
        for _ in 0..60 {
            let y = [c[0] / (lambda[0] + k), c[1] / (lambda[1] + k)];
            let l = norm2(y[0], y[1]);
            // φ(κ) = 1/|x| − 1/radius, φ' = Σ cᵢ²/(λᵢ + κ)³ / |x|³.
            let phi = 1.0 / l - 1.0 / radius;
            let dphi = (y[0] * y[0] / (lambda[0] + k) + y[1] * y[1] / (lambda[1] + k)) / (l * l * l);
            let next = (k - phi / dphi).max(0.0);
            if (next - k).abs() <= 4.0 * f64::EPSILON * next.max(1e-300) {
                k = next;
                break;
            }
            if risen && next <= k {
                // Once below the root the iterates only rise: one that does not is rounding
                // (neighbouring floats in turn), and the root is reached.
                break;
            }
            risen |= next > k;
            k = next;
        }
        *kappa = k;
        let y = [c[0] / (lambda[0] + k), c[1] / (lambda[1] + k)];
        // x = −Q y, exactly on the edge (the last rounding).
        let x = [-(q1[0] * y[0] + q2[0] * y[1]), -(q1[1] * y[0] + q2[1] * y[1])];
        let l = norm2(x[0], x[1]);
        [x[0] * radius / l, x[1] * radius / l]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The alternation of normal and friction force within one contact, as the sweeps run
    /// it when neither `stick` nor `slide` applies, to `passes` passes from `old`.
    fn alternate(w: [[f64; 3]; 3], rho: [f64; 3], mu: f64, old: [f64; 3], passes: usize) -> [f64; 3] {
        let (mut new, mut kappa) = (old, f64::NAN);
        for _ in 0..passes {
            let sn = (-(rho[0] + w[0][1] * new[1] + w[0][2] * new[2]) / w[0][0]).max(0.0);
            let rho_t = [rho[1] + w[1][0] * sn, rho[2] + w[2][0] * sn];
            let st = disc([[w[1][1], w[1][2]], [w[2][1], w[2][2]]], rho_t, mu * sn, &mut kappa);
            new = [sn, st[0], st[1]];
        }
        new
    }

    #[test]
    fn the_sliding_solve_meets_coulombs_law_where_the_alternation_converges() {
        // Blocks of a unit push at a point r of a body (mass m, principal inertia J) in a
        // random contact frame: W_ij = dᵢ·dⱼ/m + (r × dᵢ)·J⁻¹ (r × dⱼ); approaching rates
        // (ρ_n < 0) and friction coefficients from 0.1 to 1.
        let mut rng = crate::random::Rng::new(45);
        let (mut sliding, mut solved, mut compared) = (0, 0, 0);
        for case in 0..4000 {
            let m = 0.1 + 10.0 * rng.uniform();
            let j: [f64; 3] = core::array::from_fn(|_| m * 1e-3 * (0.2 + rng.uniform()));
            let r: [f64; 3] = core::array::from_fn(|_| 0.1 * rng.normal());
            let frame = rng.rotation();
            let d: [[f64; 3]; 3] = core::array::from_fn(|i| core::array::from_fn(|k| frame.m[k][i]));
            let cross = |a: [f64; 3], b: [f64; 3]| {
                [
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                ]
            };
            let w: [[f64; 3]; 3] = core::array::from_fn(|a| {
                core::array::from_fn(|b| {
                    let (ta, tb) = (cross(r, d[a]), cross(r, d[b]));
                    (0..3).map(|k| d[a][k] * d[b][k] / m + ta[k] * tb[k] / j[k]).sum()
                })
            });
            let rho = [-rng.uniform(), 2.0 * rng.normal(), 2.0 * rng.normal()];
            let mu = 0.1 + 0.9 * rng.uniform();
            if stick(w, rho, mu).is_some() {
                continue;
            }
            sliding += 1;
            let mut kappa = f64::NAN;
            let Some(x) = slide(w, rho, mu, &mut kappa) else {
                continue;
            };
            solved += 1;
            // The law: r_n = 0, |σ_t| = µ σ_n, r_t = −κ σ_t with κ ≥ 0 (the root returned).
            let rate: [f64; 3] = core::array::from_fn(|i| rho[i] + (0..3).map(|k| w[i][k] * x[k]).sum::<f64>());
            let scale = rho.iter().map(|v| v.abs()).sum::<f64>();
            assert!(x[0] > 0.0, "case {case}: σ_n = {}", x[0]);
            assert!(rate[0].abs() <= 1e-12 * scale, "case {case}: r_n = {:e}", rate[0]);
            let l = norm2(x[1], x[2]);
            assert!((l - mu * x[0]).abs() <= 1e-15 * l, "case {case}: off the edge");
            assert!(kappa >= 0.0, "case {case}: κ = {kappa}");
            let off = norm2(rate[1] + kappa * x[1], rate[2] + kappa * x[2]);
            assert!(off <= 1e-12 * scale, "case {case}: r_t + κ σ_t = {off:e} of {scale}");
            // Where the alternation from zero force converges (to round-off in 2000 passes),
            // it reaches the same force.
            let a = alternate(w, rho, mu, [0.0; 3], 2000);
            let b = alternate(w, rho, mu, a, 1);
            let step = (0..3).fold(0.0f64, |s, i| s.max((a[i] - b[i]).abs()));
            if step <= 1e-14 * x[0] {
                compared += 1;
                let gap = (0..3).fold(0.0f64, |s, i| s.max((a[i] - x[i]).abs()));
                assert!(
                    gap <= 1e-10 * x[0],
                    "case {case}: {x:?} against the alternation's {a:?}"
                );
            }
        }
        // Most approaching contacts that do not stick slide, and the solve finds each.
        assert!(sliding > 1000, "{sliding} sliding cases");
        assert_eq!(solved, sliding, "{solved} of {sliding} solved");
        // (3602 of 3667 measured: the rest did not converge in 2000 passes.)
        assert!(compared > 3500, "{compared} compared with the alternation");
    }

    #[test]
    fn the_disc_minimiser_meets_coulombs_law() {
        // Both eigenvector branches (a₀₀ above and below a₁₁), an isotropic block, a nearly
        // singular one (its determinant one rounding unit of 4: `mean − d` cancels to 0
        // there), and the root started from no hint, from between its start and the root,
        // from just below it and from above it.
        let blocks = [
            [[2.0, 0.7], [0.7, 1.0]],
            [[1.0, 0.3], [0.3, 5.0]],
            [[1.5, 0.0], [0.0, 1.5]],
            [[1.0, 2.0], [2.0, 4.0 + 4.0 * f64::EPSILON]],
        ];
        let cases = [
            ([3.0, -1.0], 0.5),
            ([0.1, 0.05], 10.0),
            ([-4.0, 2.0], 1.0),
            ([0.0, 7.0], 0.2),
        ];
        for (a, (b, radius), hint) in blocks
            .iter()
            .flat_map(|a| cases.iter().map(move |c| (*a, *c)))
            .flat_map(|(a, c)| [f64::NAN, 0.5, 0.999, 2.0, 1e6].map(|h| (a, c, h)))
        {
            let mut root = f64::NAN;
            let plain = disc(a, b, radius, &mut root);
            let mut kappa = hint * root;
            let x = disc(a, b, radius, &mut kappa);
            let gap = norm2(x[0] - plain[0], x[1] - plain[1]);
            assert!(gap <= 1e-15 * radius, "hint {hint}: {x:?} against {plain:?}");
            let r = [
                a[0][0] * x[0] + a[0][1] * x[1] + b[0],
                a[1][0] * x[0] + a[1][1] * x[1] + b[1],
            ];
            let l = norm2(x[0], x[1]);
            if l < radius * (1.0 - 1e-12) {
                assert!(r[0].abs() + r[1].abs() < 1e-14, "stuck but r = {r:?}");
            } else {
                // r = −κ x with κ ≥ 0.
                let kappa_r = -(r[0] * x[0] + r[1] * x[1]) / (l * l);
                assert!(kappa_r >= 0.0);
                assert!(
                    (kappa - kappa_r).abs() <= 1e-12 * (1.0 + kappa_r),
                    "κ {kappa} against {kappa_r}: {a:?} {b:?} {radius} hint {hint}"
                );
                let kappa = kappa_r;
                let off = (r[0] + kappa * x[0]).hypot(r[1] + kappa * x[1]);
                assert!(off < 1e-13 * (1.0 + r[0].hypot(r[1])), "off {off:e}");
                assert!((l - radius).abs() < 1e-15 * radius.max(1.0));
            }
        }
    }

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
