//! The active-set finish of a slow Gauss–Seidel solve over a dense `W` (`cone.rs`).
//!
//! Reference: docs/theory/multibody.md §6.

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
pub(super) fn polish(
    w: &[f64],
    r0: &[f64],
    mu: &[f64],
    sigma: &mut [f64],
    rates: &mut [f64],
    tol: f64,
    p: &mut Polish,
) -> bool {
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
    if crate::linalg::cholesky_in_place(&mut p.a, n).is_err() {
        return false;
    }
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
        crate::linalg::cholesky_solve(&p.a, n, &mut p.b);
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
    super::cone::rates_at(w, r0, &p.trial, &mut p.trial_rates);
    let admissible = p
        .trial
        .chunks(3)
        .zip(mu)
        .all(|(c, &mu)| c[0] >= 0.0 && c[1].hypot(c[2]) <= mu * c[0]);
    if admissible && super::cone::violation(&p.trial_rates, &p.trial, mu) <= tol {
        sigma.copy_from_slice(&p.trial);
        rates.copy_from_slice(&p.trial_rates);
        return true;
    }
    false
}

/// Scratch of [`slide_newton`].
#[derive(Clone, Debug, Default)]
pub(super) struct Slide {
    /// Per unknown: the contact's first row, and which force (0 normal; 1, 2 tangents).
    unknowns: Vec<(usize, usize)>,
    /// Per contact sliding: its friction direction (`σ_t = µ σ_n d`).
    direction: Vec<[f64; 2]>,
    sliding: Vec<bool>,
    a: Vec<f64>,
    lu: Vec<f64>,
    pivots: Vec<usize>,
    x: Vec<f64>,
    b: Vec<f64>,
    step: Vec<f64>,
    trial: Vec<f64>,
    trial_rates: Vec<f64>,
}

/// Finish a Gauss–Seidel solve stalled on sliding contacts: with friction µ ≳ 0.5 the
/// friction of a sliding contact feeds back into the normal rates (`W_nn − µ W_nt d` is
/// nearly singular for a box slapping down on an edge), and Gauss–Seidel contracts by
/// 0.25 % per sweep. Newton's method on the active set: the touching contacts' normal rates
/// (and the sticking ones' tangential rates) set to 0, each sliding contact's friction fixed
/// on its cone's edge along its current direction, `σ_t = µ σ_n d`: one nonsymmetric linear
/// system (LU with partial pivoting, regularised by `1e-13 max |A_ii|`, refined), up to
/// four times with the directions updated from the new slip rates. Accepted when the law
/// holds to the tolerance.
pub(super) fn slide_newton(
    w: &[f64],
    r0: &[f64],
    mu: &[f64],
    sigma: &mut [f64],
    rates: &mut [f64],
    tol: f64,
    p: &mut Slide,
) -> bool {
    let m = r0.len();
    p.trial.clear();
    p.trial.extend_from_slice(sigma);
    p.trial_rates.clear();
    p.trial_rates.extend_from_slice(rates);
    for _ in 0..4 {
        p.unknowns.clear();
        p.direction.clear();
        p.sliding.clear();
        for (k, &mu_k) in mu.iter().enumerate() {
            let b = 3 * k;
            let (sn, st) = (p.trial[b], [p.trial[b + 1], p.trial[b + 2]]);
            let sl = st[0].hypot(st[1]);
            let rt = [p.trial_rates[b + 1], p.trial_rates[b + 2]];
            let rl = rt[0].hypot(rt[1]);
            let slides = mu_k > 0.0 && sn > 0.0 && sl >= mu_k * sn * (1.0 - 1e-9);
            // Against the slip where it slips, else along the current force.
            let d = if slides && rl > 0.0 {
                [-rt[0] / rl, -rt[1] / rl]
            } else if sl > 0.0 {
                [st[0] / sl, st[1] / sl]
            } else {
                [0.0, 0.0]
            };
            p.direction.push(d);
            p.sliding.push(slides);
            if sn > 0.0 {
                p.unknowns.push((b, 0));
                if mu_k > 0.0 && !slides {
                    p.unknowns.extend([(b, 1), (b, 2)]);
                }
            }
        }
        let n = p.unknowns.len();
        if n == 0 || !p.sliding.iter().any(|s| *s) {
            return false;
        }
        // A[e][u]: the rate of equation e per unit of unknown u.
        p.a.clear();
        p.a.resize(n * n, 0.0);
        for (e, &(be, fe)) in p.unknowns.iter().enumerate() {
            let row = be + fe;
            for (u, &(bu, fu)) in p.unknowns.iter().enumerate() {
                let k = bu / 3;
                p.a[e * n + u] = if fu == 0 && p.sliding[k] {
                    let d = p.direction[k];
                    w[row * m + bu] + mu[k] * (w[row * m + bu + 1] * d[0] + w[row * m + bu + 2] * d[1])
                } else {
                    w[row * m + bu + fu]
                };
            }
        }
        let diag = (0..n).fold(0.0f64, |x, i| x.max(p.a[i * n + i].abs()));
        if diag <= 0.0 {
            return false;
        }
        p.lu.clear();
        p.lu.extend_from_slice(&p.a);
        for i in 0..n {
            p.lu[i * n + i] += 1e-13 * diag;
        }
        p.pivots.clear();
        p.pivots.extend(0..n);
        // LU with partial pivoting, in place.
        for col in 0..n {
            let best = (col..n)
                .max_by(|&x, &y| p.lu[x * n + col].abs().total_cmp(&p.lu[y * n + col].abs()))
                .unwrap_or(col);
            if p.lu[best * n + col] == 0.0 {
                return false;
            }
            if best != col {
                for j in 0..n {
                    p.lu.swap(best * n + j, col * n + j);
                }
                p.pivots.swap(best, col);
            }
            let pivot = p.lu[col * n + col];
            for i in col + 1..n {
                let f = p.lu[i * n + col] / pivot;
                p.lu[i * n + col] = f;
                for j in col + 1..n {
                    p.lu[i * n + j] -= f * p.lu[col * n + j];
                }
            }
        }
        let lu_solve = |lu: &[f64], pivots: &[usize], b: &[f64], x: &mut [f64]| {
            for i in 0..n {
                let mut v = b[pivots[i]];
                for k in 0..i {
                    v -= lu[i * n + k] * x[k];
                }
                x[i] = v;
            }
            for i in (0..n).rev() {
                let mut v = x[i];
                for k in i + 1..n {
                    v -= lu[i * n + k] * x[k];
                }
                x[i] = v / lu[i * n + i];
            }
        };
        // From the current forces, refined to the unregularised system's residual.
        p.x.clear();
        p.x.extend(p.unknowns.iter().map(|&(b, f)| p.trial[b + f]));
        p.step.clear();
        p.step.resize(n, 0.0);
        p.b.resize(n, 0.0);
        for _ in 0..6 {
            for (e, &(be, fe)) in p.unknowns.iter().enumerate() {
                let mut v = -r0[be + fe];
                for (u, x) in p.x.iter().enumerate() {
                    v -= p.a[e * n + u] * x;
                }
                p.b[e] = v;
            }
            lu_solve(&p.lu, &p.pivots, &p.b, &mut p.step);
            for (x, d) in p.x.iter_mut().zip(&p.step) {
                *x += d;
            }
        }
        p.trial.iter_mut().for_each(|x| *x = 0.0);
        for (&(b, f), x) in p.unknowns.iter().zip(&p.x) {
            p.trial[b + f] = *x;
        }
        for (k, (&mu_k, (&slides, d))) in mu.iter().zip(p.sliding.iter().zip(&p.direction)).enumerate() {
            let b = 3 * k;
            if slides {
                p.trial[b + 1] = mu_k * p.trial[b] * d[0];
                p.trial[b + 2] = mu_k * p.trial[b] * d[1];
            }
        }
        super::cone::rates_at(w, r0, &p.trial, &mut p.trial_rates);
        let admissible = p
            .trial
            .chunks(3)
            .zip(mu)
            .all(|(c, &mu)| c[0] >= 0.0 && c[1].hypot(c[2]) <= mu * c[0] * (1.0 + 1e-12));
        if admissible && super::cone::violation(&p.trial_rates, &p.trial, mu) <= tol {
            sigma.copy_from_slice(&p.trial);
            rates.copy_from_slice(&p.trial_rates);
            return true;
        }
        if !admissible {
            return false;
        }
    }
    false
}
