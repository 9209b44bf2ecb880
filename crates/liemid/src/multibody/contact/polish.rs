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
    if admissible && super::cone::violation(&p.trial_rates, &p.trial, mu) <= tol {
        sigma.copy_from_slice(&p.trial);
        rates.copy_from_slice(&p.trial_rates);
        return true;
    }
    false
}
