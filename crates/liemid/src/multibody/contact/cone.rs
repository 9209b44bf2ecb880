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
//! on the edge, `r_t = −κ σ_t`), the others held. A sweep ends with the law's worst
//! violation, and the solve stops when it is below the tolerance; it fails after
//! [`MAX_SWEEPS`] sweeps.
//!
//! Reference: M. Jean, "The non-smooth contact dynamics method", CMAME 177 (1999) (NSCD,
//! Gauss–Seidel over contacts); J. J. Moré, D. C. Sorensen, SIAM J. Sci. Stat. Comput. 4
//! (1983) (the disc-constrained minimiser).

/// Most sweeps of one solve.
pub(super) const MAX_SWEEPS: usize = 2000;

/// Sweeps between attempts to finish the solve on the active set ([`polish`]).
const POLISH_EVERY: usize = 20;

/// Scratch of [`polish`].
#[derive(Clone, Debug, Default)]
pub(super) struct Polish {
    rows: Vec<usize>,
    a: Vec<f64>,
    x: Vec<f64>,
    b: Vec<f64>,
    trial: Vec<f64>,
    trial_rates: Vec<f64>,
}

/// Finish a slow Gauss–Seidel solve where it has found the active set and every active
/// contact sticks (a stack at rest: Gauss–Seidel contracts slowly over redundant contacts,
/// four corners on a face, and wanders into internal friction forces that cancel, some on
/// their cones' edges): from its normal forces and no friction, solve `W_AA σ_A = −r₀_A` over the rows of the touching contacts
/// (normal and tangents), regularised by `ε = 1e-13 max W_ii` and refined to the system's
/// own residual (consistent over redundant rows, so the refinement converges), and accept
/// it when it obeys the law to the tolerance (normal forces not negative, inside the cones,
/// the other contacts not approaching). Returns whether it was accepted.
fn polish(w: &[f64], r0: &[f64], mu: &[f64], sigma: &mut [f64], rates: &mut [f64], tol: f64, p: &mut Polish) -> bool {
    let m = r0.len();
    p.rows.clear();
    for (k, &mu_k) in mu.iter().enumerate() {
        let b = 3 * k;
        if sigma[b] > 0.0 {
            p.rows.push(b);
            if mu_k > 0.0 {
                p.rows.extend([b + 1, b + 2]);
            }
        }
    }
    let n = p.rows.len();
    if n == 0 {
        return false;
    }
    p.a.clear();
    p.a.resize(n * n, 0.0);
    let mut diag: f64 = 0.0;
    for (i, &ri) in p.rows.iter().enumerate() {
        for (j, &rj) in p.rows.iter().enumerate() {
            p.a[i * n + j] = 0.5 * (w[ri * m + rj] + w[rj * m + ri]);
        }
        diag = diag.max(p.a[i * n + i]);
    }
    if diag <= 0.0 {
        return false;
    }
    let eps = 1e-13 * diag;
    for i in 0..n {
        p.a[i * n + i] += eps;
    }
    // Cholesky in place (lower).
    for j in 0..n {
        let mut d = p.a[j * n + j];
        for k in 0..j {
            d -= p.a[j * n + k] * p.a[j * n + k];
        }
        if d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        p.a[j * n + j] = d;
        for i in j + 1..n {
            let mut v = p.a[i * n + j];
            for k in 0..j {
                v -= p.a[i * n + k] * p.a[j * n + k];
            }
            p.a[i * n + j] = v / d;
        }
    }
    let chol_solve = |a: &[f64], x: &mut [f64]| {
        for i in 0..n {
            let mut v = x[i];
            for k in 0..i {
                v -= a[i * n + k] * x[k];
            }
            x[i] = v / a[i * n + i];
        }
        for i in (0..n).rev() {
            let mut v = x[i];
            for k in i + 1..n {
                v -= a[k * n + i] * x[k];
            }
            x[i] = v / a[i * n + i];
        }
    };
    // From the Gauss–Seidel normal forces: the refinement corrects it within the range of W_AA
    // and keeps its share of the redundant rows (positive normal forces), where a
    // minimum-norm solution could trade normal for internal tangential forces.
    p.x.clear();
    p.x.extend(p.rows.iter().map(|&r| if r % 3 == 0 { sigma[r] } else { 0.0 }));
    p.b.resize(n, 0.0);
    for _ in 0..6 {
        // b = −r₀_A − W_AA x, the residual of the unregularised system.
        for (i, &ri) in p.rows.iter().enumerate() {
            let mut v = -r0[ri];
            for (j, &rj) in p.rows.iter().enumerate() {
                v -= w[ri * m + rj] * p.x[j];
            }
            p.b[i] = v;
        }
        let (a, b) = (&p.a, &mut p.b);
        chol_solve(a, b);
        for (x, d) in p.x.iter_mut().zip(&p.b) {
            *x += d;
        }
    }
    p.trial.clear();
    p.trial.resize(m, 0.0);
    for (i, &ri) in p.rows.iter().enumerate() {
        p.trial[ri] = p.x[i];
    }
    p.trial_rates.resize(m, 0.0);
    for i in 0..m {
        let row = &w[i * m..(i + 1) * m];
        p.trial_rates[i] = r0[i] + row.iter().zip(&p.trial).map(|(a, b)| a * b).sum::<f64>();
    }
    let admissible = p
        .trial
        .chunks(3)
        .zip(mu)
        .all(|(c, &mu)| c[0] >= 0.0 && c[1].hypot(c[2]) <= mu * c[0]);
    if admissible && violation(&p.trial_rates, &p.trial, mu) <= tol {
        sigma.copy_from_slice(&p.trial);
        rates.copy_from_slice(&p.trial_rates);
        return true;
    }
    false
}

/// The outcome of a solve: sweeps made and the law's worst violation at the end.
#[derive(Clone, Copy, Debug)]
pub(super) struct Solved {
    pub sweeps: usize,
    pub worst: f64,
    pub converged: bool,
}

/// Solve for `sigma` (started from its content) with `w` (row-major, `3n × 3n`), `r0`,
/// friction `mu`; `rates` receives `r₀ + W σ`. Stops when the worst violation is at most `tol`.
pub(super) fn solve(
    w: &[f64],
    r0: &[f64],
    mu: &[f64],
    sigma: &mut [f64],
    rates: &mut [f64],
    tol: f64,
    scratch: &mut Polish,
) -> Solved {
    let m = r0.len();
    let n = m / 3;
    for i in 0..m {
        let row = &w[i * m..(i + 1) * m];
        rates[i] = r0[i] + row.iter().zip(sigma.iter()).map(|(a, b)| a * b).sum::<f64>();
    }
    let mut sweeps = 0;
    loop {
        let worst = violation(rates, sigma, mu);
        if worst <= tol {
            return Solved {
                sweeps,
                worst,
                converged: true,
            };
        }
        if sweeps >= MAX_SWEEPS {
            return Solved {
                sweeps,
                worst,
                converged: false,
            };
        }
        if sweeps > 0 && sweeps % POLISH_EVERY == 0 && polish(w, r0, mu, sigma, rates, tol, scratch) {
            continue;
        }
        sweeps += 1;
        for (k, &mu_k) in mu.iter().enumerate().take(n) {
            let b = 3 * k;
            let at = |i: usize, j: usize| w[(b + i) * m + b + j];
            let old = [sigma[b], sigma[b + 1], sigma[b + 2]];
            // The rates without contact k's own force.
            let rho: [f64; 3] =
                core::array::from_fn(|i| rates[b + i] - (at(i, 0) * old[0] + at(i, 1) * old[1] + at(i, 2) * old[2]));
            let wnn = at(0, 0);
            let sn = if wnn > 0.0 {
                (-(rho[0] + at(0, 1) * old[1] + at(0, 2) * old[2]) / wnn).max(0.0)
            } else {
                0.0
            };
            let rho_t = [rho[1] + at(1, 0) * sn, rho[2] + at(2, 0) * sn];
            let st = disc([[at(1, 1), at(1, 2)], [at(2, 1), at(2, 2)]], rho_t, mu_k * sn);
            let new = [sn, st[0], st[1]];
            for (j, (nv, ov)) in new.iter().zip(old).enumerate() {
                let d = nv - ov;
                if d != 0.0 {
                    sigma[b + j] = *nv;
                    for (i, ri) in rates.iter_mut().enumerate() {
                        *ri += w[i * m + b + j] * d;
                    }
                }
            }
        }
    }
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
        let (sl, rl) = (st[0].hypot(st[1]), rt[0].hypot(rt[1]));
        let bound = mu * sn;
        let tangential = if bound <= 0.0 {
            0.0
        } else if sl < bound * (1.0 - 1e-9) {
            rl
        } else {
            // On the edge the slip opposes the force: r_t + |r_t| σ̂_t = 0.
            let u = [st[0] / sl, st[1] / sl];
            (rt[0] + rl * u[0]).hypot(rt[1] + rl * u[1])
        };
        worst = worst.max(normal).max(tangential);
    }
    worst
}

/// The minimiser of `½ xᵀ A x + bᵀ x` over `|x| ≤ radius` (`A` 2x2 symmetric positive
/// definite): the free minimiser when inside, else `x(κ) = −(A + κ I)⁻¹ b` with `|x(κ)| =
/// radius`, κ by Newton's method on `1/|x(κ)| − 1/radius` (Moré–Sorensen), which is convex
/// and increasing in κ, so the iteration converges monotonically.
fn disc(a: [[f64; 2]; 2], b: [f64; 2], radius: f64) -> [f64; 2] {
    if radius <= 0.0 || (b[0] == 0.0 && b[1] == 0.0) {
        return [0.0, 0.0];
    }
    let solve = |k: f64| {
        let (p, q, s) = (a[0][0] + k, a[0][1], a[1][1] + k);
        let det = p * s - q * q;
        [-(s * b[0] - q * b[1]) / det, -(p * b[1] - q * b[0]) / det]
    };
    let det = a[0][0] * a[1][1] - a[0][1] * a[0][1];
    if det > 0.0 && a[0][0] > 0.0 {
        let x = solve(0.0);
        if x[0].hypot(x[1]) <= radius {
            return x;
        }
    } else {
        // A degenerate block (a body without inertia along the plane): the force against
        // the rate, at the bound.
        let l = b[0].hypot(b[1]);
        return [-radius * b[0] / l, -radius * b[1] / l];
    }
    let mut k = 0.0f64;
    for _ in 0..60 {
        let x = solve(k);
        let l = x[0].hypot(x[1]);
        // d|x|/dκ = −xᵀ (A + κI)⁻¹ x / |x|.
        let y = {
            let (p, q, s) = (a[0][0] + k, a[0][1], a[1][1] + k);
            let det = p * s - q * q;
            [(s * x[0] - q * x[1]) / det, (p * x[1] - q * x[0]) / det]
        };
        let dl = -(x[0] * y[0] + x[1] * y[1]) / l;
        // φ(κ) = 1/|x| − 1/radius, φ' = −dl/|x|².
        let phi = 1.0 / l - 1.0 / radius;
        let dphi = -dl / (l * l);
        let step = phi / dphi;
        let next = (k - step).max(0.0);
        if (next - k).abs() <= 4.0 * f64::EPSILON * next.max(1e-300) {
            k = next;
            break;
        }
        k = next;
    }
    let x = solve(k);
    // Exactly on the edge (the last rounding).
    let l = x[0].hypot(x[1]);
    [x[0] * radius / l, x[1] * radius / l]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_disc_minimiser_meets_coulombs_law() {
        let a = [[2.0, 0.7], [0.7, 1.0]];
        for (b, radius) in [([3.0, -1.0], 0.5), ([0.1, 0.05], 10.0), ([-4.0, 2.0], 1.0)] {
            let x = disc(a, b, radius);
            let r = [
                a[0][0] * x[0] + a[0][1] * x[1] + b[0],
                a[1][0] * x[0] + a[1][1] * x[1] + b[1],
            ];
            let l = x[0].hypot(x[1]);
            if l < radius * (1.0 - 1e-12) {
                assert!(r[0].abs() + r[1].abs() < 1e-14, "stuck but r = {r:?}");
            } else {
                // r = −κ x with κ ≥ 0.
                let kappa = -(r[0] * x[0] + r[1] * x[1]) / (l * l);
                assert!(kappa >= 0.0);
                let off = (r[0] + kappa * x[0]).hypot(r[1] + kappa * x[1]);
                assert!(off < 1e-13 * (1.0 + r[0].hypot(r[1])), "off {off:e}");
                assert!((l - radius).abs() < 1e-15 * radius.max(1.0));
            }
        }
    }

    #[test]
    fn one_contact_sticks_below_the_cone_and_slides_on_it() {
        // A point of unit mass on a plane: W = I (per unit force over the half-kick).
        let w = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        // Pushed into the plane at 1 and along it at 0.3 with µ = 0.5: sticks.
        let (mut s, mut r) = ([0.0; 3], [0.0; 3]);
        let done = solve(
            &w,
            &[-1.0, 0.3, 0.0],
            &[0.5],
            &mut s,
            &mut r,
            1e-15,
            &mut Polish::default(),
        );
        assert!(done.converged);
        assert_eq!(s, [1.0, -0.3, 0.0]);
        // Along it at 0.8: slides, the force at µ σ_n against the motion.
        let (mut s, mut r) = ([0.0; 3], [0.0; 3]);
        let done = solve(
            &w,
            &[-1.0, 0.8, 0.0],
            &[0.5],
            &mut s,
            &mut r,
            1e-15,
            &mut Polish::default(),
        );
        assert!(done.converged);
        assert_eq!(s, [1.0, -0.5, 0.0]);
        assert!((r[1] - 0.3).abs() < 1e-15 && r[0].abs() < 1e-15);
        // Moving away: no force.
        let (mut s, mut r) = ([0.0; 3], [0.0; 3]);
        assert!(
            solve(
                &w,
                &[0.5, 0.8, 0.0],
                &[0.5],
                &mut s,
                &mut r,
                1e-15,
                &mut Polish::default()
            )
            .converged
        );
        assert_eq!(s, [0.0; 3]);
    }
}
