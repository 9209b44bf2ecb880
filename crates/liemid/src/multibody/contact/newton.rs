//! A semismooth Newton finish of the cone problem over a dense `W` (`cone.rs`), for the
//! cases where Gauss–Seidel stalls and the active-set finishes (`polish.rs`) do not apply:
//! a stack whose contacts mix sticking corners and corners about to lift, contacts sliding
//! near their friction limit.
//!
//! Coulomb's law with the elliptic cone is the root of Alart and Curnier's function, per
//! contact with `r = r₀ + W σ` and the scales `ρ_n = 1/W_nn`, `ρ_t = 1/max(W_t1t1, W_t2t2)`:
//!
//! ```text
//!     F_n = σ_n − max(0, σ_n − ρ_n r_n)
//!     F_t = σ_t − proj_{|x| ≤ µ max(σ_n, 0)} (σ_t − ρ_t r_t)
//! ```
//!
//! (`F = 0` exactly when `σ_n ≥ 0`, `r_n ≥ 0`, `σ_n r_n = 0`, and the friction force is inside
//! the disc with `r_t = 0` or on its edge against `r_t`.) `F` is piecewise smooth; Newton's
//! method takes an element of its generalized Jacobian `J` (each max and projection
//! differentiated on its current piece). Redundant contacts (four corners on a face) make
//! `J` singular, so the step is Levenberg–Marquardt's `(JᵀJ + λ I) Δ = −Jᵀ F` with
//! `λ = 1e-12 max (JᵀJ)_ii`, from the Gauss–Seidel iterate, with a backtracking line search
//! on `½ |F|²`. The result is projected on the cones and accepted only where the law
//! holds to the solve's tolerance (`cone::violation`).
//!
//! Reference: P. Alart, A. Curnier, CMAME 92 (1991) (the augmented Lagrangian function);
//! V. Acary, B. Brogliato, "Numerical Methods for Nonsmooth Dynamical Systems" (2008),
//! §13.5 (its semismooth Newton method); docs/theory/multibody.md §6.

/// Most Newton iterations of one finish.
const MAX_ITERATIONS: usize = 15;

/// Iterations in a row that do not halve `½ |F|²` after which a finish gives up (a
/// cycling or stuck iteration: measured on a pile's islands, the successful finishes
/// shrink it by orders of magnitude each iteration until the law holds).
const STAGNANT: usize = 2;

/// The largest problem (rows) the dense finish takes on (`(3n)³` work per iteration).
pub(super) const MAX_ROWS: usize = 360;

/// Scratch of [`newton`].
#[derive(Clone, Debug, Default)]
pub(super) struct Newton {
    /// `F` and its generalized Jacobian (row-major) at the iterate.
    f: Vec<f64>,
    jac: Vec<f64>,
    /// `JᵀJ + λ I`, then its Cholesky factor.
    normal: Vec<f64>,
    step: Vec<f64>,
    /// The iterate and its rates.
    sigma: Vec<f64>,
    rates: Vec<f64>,
    /// A trial point of the line search (or the projected iterate), its rates and `F`.
    trial: Vec<f64>,
    trial_rates: Vec<f64>,
    trial_f: Vec<f64>,
    /// Per contact `[ρ_n, ρ_t]`.
    scale: Vec<[f64; 2]>,
    /// The columns of one row of `J` that are not zero.
    nonzero: Vec<usize>,
}

/// Alart–Curnier's `F` at `sigma` with `rates = r₀ + W σ` (written into `f`); with
/// `jac` (row-major `m × m`) an element of its generalized Jacobian too, taking the stick
/// (pressed) piece at a contact within `band` (relative) of its kink. Returns `½ |F|²`.
#[allow(clippy::too_many_arguments)]
fn residual(
    w: &[f64],
    mu: &[f64],
    scale: &[[f64; 2]],
    sigma: &[f64],
    rates: &[f64],
    f: &mut [f64],
    mut jac: Option<&mut [f64]>,
    band: f64,
) -> f64 {
    let m = sigma.len();
    for (k, (&mu_k, &[rho_n, rho_t])) in mu.iter().zip(scale).enumerate() {
        let b = 3 * k;
        let (sn, rn) = (sigma[b], rates[b]);
        // Normal: F_n = ρ_n r_n where pressed, else σ_n.
        let pressed = sn - rho_n * rn > 0.0;
        f[b] = if pressed { rho_n * rn } else { sn };
        if let Some(j) = jac.as_deref_mut() {
            let row = &mut j[b * m..(b + 1) * m];
            if pressed || (sn - rho_n * rn).abs() <= band * (sn.abs() + (rho_n * rn).abs()) {
                for (x, wv) in row.iter_mut().zip(&w[b * m..(b + 1) * m]) {
                    *x = rho_n * wv;
                }
            } else {
                row.fill(0.0);
                row[b] = 1.0;
            }
        }
        // Tangents: F_t = ρ_t r_t inside the disc of radius R = µ max(σ_n, 0), else σ_t − R ẑ.
        let radius = mu_k * sn.max(0.0);
        let st = [sigma[b + 1], sigma[b + 2]];
        let z = [st[0] - rho_t * rates[b + 1], st[1] - rho_t * rates[b + 2]];
        let zl = z[0].hypot(z[1]);
        let inside = zl <= radius;
        if inside {
            f[b + 1] = rho_t * rates[b + 1];
            f[b + 2] = rho_t * rates[b + 2];
        } else if radius > 0.0 {
            f[b + 1] = st[0] - radius * z[0] / zl;
            f[b + 2] = st[1] - radius * z[1] / zl;
        } else {
            f[b + 1] = st[0];
            f[b + 2] = st[1];
        }
        let Some(j) = jac.as_deref_mut() else {
            continue;
        };
        let stick_piece = inside || (zl - radius).abs() <= band * radius;
        for t in 0..2 {
            let at = (b + 1 + t) * m;
            if stick_piece {
                for (x, wv) in j[at..at + m].iter_mut().zip(&w[at..at + m]) {
                    *x = rho_t * wv;
                }
            } else if radius > 0.0 {
                // dF_t = E_t − ẑ µ e_nᵀ − (R/|z|)(I − ẑẑᵀ)(E_t − ρ_t W_t).
                let u = [z[0] / zl, z[1] / zl];
                let c = radius / zl;
                let unit = |i: usize| if i == t { 1.0 } else { 0.0 };
                let p = [c * (unit(0) - u[t] * u[0]), c * (unit(1) - u[t] * u[1])];
                let (w1, w2) = (&w[(b + 1) * m..(b + 2) * m], &w[(b + 2) * m..(b + 3) * m]);
                for ((x, a1), a2) in j[at..at + m].iter_mut().zip(w1).zip(w2) {
                    *x = rho_t * (p[0] * a1 + p[1] * a2);
                }
                j[at + b] -= u[t] * mu_k;
                j[at + b + 1] -= p[0];
                j[at + b + 2] -= p[1];
                j[at + b + 1 + t] += 1.0;
            } else {
                j[at..at + m].fill(0.0);
                j[at + b + 1 + t] = 1.0;
            }
        }
    }
    0.5 * f.iter().map(|x| x * x).sum::<f64>()
}

/// Finish the cone problem `r = r₀ + W σ` (`W` dense, row-major) by semismooth Newton from
/// `sigma` (module docs); on success `sigma` and `rates` hold the solution and it returns
/// true, else both are left as they were.
pub(super) fn newton(
    w: &[f64],
    r0: &[f64],
    mu: &[f64],
    sigma: &mut [f64],
    rates: &mut [f64],
    tol: f64,
    s: &mut Newton,
) -> bool {
    let m = r0.len();
    if m == 0 || m > MAX_ROWS {
        return false;
    }
    s.scale.clear();
    for (k, &mu_k) in mu.iter().enumerate() {
        let b = 3 * k;
        let (wn, wt) = (w[b * m + b], w[(b + 1) * m + b + 1].max(w[(b + 2) * m + b + 2]));
        if wn <= 0.0 || (mu_k > 0.0 && wt <= 0.0) {
            return false;
        }
        s.scale.push([1.0 / wn, if wt > 0.0 { 1.0 / wt } else { 0.0 }]);
    }
    for v in [
        &mut s.f,
        &mut s.step,
        &mut s.rates,
        &mut s.trial,
        &mut s.trial_rates,
        &mut s.trial_f,
    ] {
        v.clear();
        v.resize(m, 0.0);
    }
    s.jac.clear();
    s.jac.resize(m * m, 0.0);
    s.normal.clear();
    s.normal.resize(m * m, 0.0);
    s.sigma.clear();
    s.sigma.extend_from_slice(sigma);
    super::cone::rates_at(w, r0, &s.sigma, &mut s.rates);
    // Degenerate contacts (on the kink between stick and slip, or touch and lift) take
    // the stick (pressed) piece of the Jacobian after a short step.
    let mut band = 0.0;
    let mut phi = residual(w, mu, &s.scale, &s.sigma, &s.rates, &mut s.f, Some(&mut s.jac), band);
    let mut stagnant = 0;
    for it in 0..=MAX_ITERATIONS {
        // Accept the iterate projected on the cones where it obeys the law.
        s.trial.copy_from_slice(&s.sigma);
        project(mu, &mut s.trial);
        super::cone::rates_at(w, r0, &s.trial, &mut s.trial_rates);
        if super::cone::violation(&s.trial_rates, &s.trial, mu) <= tol {
            sigma.copy_from_slice(&s.trial);
            rates.copy_from_slice(&s.trial_rates);
            return true;
        }
        // (Checked after the law, so a last step that reached it is kept.)
        if it == MAX_ITERATIONS || stagnant >= STAGNANT {
            break;
        }
        // (JᵀJ + λ I) Δ = −Jᵀ F, the lower triangle, row by row of J over its nonzeros
        // (a row of J is a row of W or a unit row: sparse where the contacts share few
        // bodies).
        let (jac, normal) = (&s.jac, &mut s.normal);
        normal.fill(0.0);
        s.step.fill(0.0);
        for e in 0..m {
            let row = &jac[e * m..(e + 1) * m];
            s.nonzero.clear();
            s.nonzero.extend((0..m).filter(|&i| row[i] != 0.0));
            let fe = s.f[e];
            for (a, &i) in s.nonzero.iter().enumerate() {
                let ji = row[i];
                s.step[i] -= ji * fe;
                let target = &mut normal[i * m..i * m + i + 1];
                for &j in &s.nonzero[..=a] {
                    target[j] += ji * row[j];
                }
            }
        }
        let diag = (0..m).fold(0.0f64, |x, i| x.max(normal[i * m + i]));
        if diag.is_nan() || diag <= 0.0 {
            return false;
        }
        for i in 0..m {
            normal[i * m + i] += 1e-12 * diag;
        }
        if crate::linalg::cholesky_in_place(normal, m).is_err() {
            return false;
        }
        crate::linalg::cholesky_solve(normal, m, &mut s.step);
        // Backtracking on ½|F|² (the direction descends: it is −(JᵀJ + λI)⁻¹ ∇(½|F|²)).
        let mut t = 1.0;
        loop {
            for ((x, sg), d) in s.trial.iter_mut().zip(&s.sigma).zip(&s.step) {
                *x = sg + t * d;
            }
            super::cone::rates_at(w, r0, &s.trial, &mut s.trial_rates);
            let trial_phi = residual(w, mu, &s.scale, &s.trial, &s.trial_rates, &mut s.trial_f, None, 0.0);
            if trial_phi <= (1.0 - 1e-4 * t) * phi {
                break;
            }
            t *= 0.5;
            if t < 1e-9 {
                return false;
            }
        }
        core::mem::swap(&mut s.sigma, &mut s.trial);
        core::mem::swap(&mut s.rates, &mut s.trial_rates);
        band = if t < 0.1 { 1e-3 } else { 0.0 };
        let before = phi;
        phi = residual(w, mu, &s.scale, &s.sigma, &s.rates, &mut s.f, Some(&mut s.jac), band);
        stagnant = if phi > 0.5 * before { stagnant + 1 } else { 0 };
    }
    false
}

/// Each contact's force onto its cone: `σ_n ≥ 0`, `|σ_t| ≤ µ σ_n`.
fn project(mu: &[f64], sigma: &mut [f64]) {
    for (c, &mu) in sigma.chunks_exact_mut(3).zip(mu) {
        c[0] = c[0].max(0.0);
        let (l, bound) = (c[1].hypot(c[2]), mu * c[0]);
        if l > bound {
            let f = if l > 0.0 { bound / l } else { 0.0 };
            c[1] *= f;
            c[2] *= f;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::cone;
    use super::*;

    /// A unit cube (mass 1, half-edge `a`) standing on four corners, normals along z:
    /// `W` and the rates `r₀` of its velocity `(v, ω)` (rows normal, x, y per corner).
    fn cube(a: f64, v: [f64; 3], omega: [f64; 3]) -> (Vec<f64>, Vec<f64>) {
        let inertia = 2.0 * a * a / 3.0;
        let mut rows = Vec::new();
        for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
            let x = [sx * a, sy * a, -a];
            for d in [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
                let moment = [
                    x[1] * d[2] - x[2] * d[1],
                    x[2] * d[0] - x[0] * d[2],
                    x[0] * d[1] - x[1] * d[0],
                ];
                rows.push((d, moment));
            }
        }
        let m = rows.len();
        let mut w = vec![0.0; m * m];
        for (i, (di, ti)) in rows.iter().enumerate() {
            for (j, (dj, tj)) in rows.iter().enumerate() {
                w[i * m + j] = (0..3).map(|k| di[k] * dj[k] + ti[k] * tj[k] / inertia).sum();
            }
        }
        let r0 = rows
            .iter()
            .map(|(d, t)| (0..3).map(|k| d[k] * v[k] + t[k] * omega[k]).sum())
            .collect();
        (w, r0)
    }

    #[test]
    fn newton_solves_a_cube_on_four_corners_sticking_sliding_and_lifting() {
        let mu = [0.6; 4];
        // Falling onto the floor while moving along it slowly (sticks), fast (slides), and
        // turning onto one edge (two corners lift, the others slide or stick).
        for (v, omega) in [
            ([0.1, 0.0, -1.0], [0.0; 3]),
            ([2.0, 0.5, -1.0], [0.0; 3]),
            ([0.3, -0.2, -1.0], [0.5, -0.8, 0.3]),
            ([0.0, 0.1, -0.2], [3.0, 0.0, 0.0]),
        ] {
            let (w, r0) = cube(0.5, v, omega);
            // Newton alone from no force, and as the finish of Gauss–Seidel.
            let (mut sigma, mut rates) = (vec![0.0; 12], vec![0.0; 12]);
            let mut scratch = Newton::default();
            let alone = newton(&w, &r0, &mu, &mut sigma, &mut rates, 1e-13, &mut scratch);
            if alone {
                assert!(cone::violation(&rates, &sigma, &mu) <= 1e-13);
                for c in sigma.chunks(3) {
                    assert!(c[0] >= 0.0 && c[1].hypot(c[2]) <= 0.6 * c[0] * (1.0 + 1e-15));
                }
            }
            let (mut sigma, mut kept) = (vec![0.0; 12], r0.clone());
            let mut dense = cone::Dense {
                w: &w,
                rates: &mut kept,
            };
            dense.start(&r0, &sigma);
            let done = cone::solve(
                &mut dense,
                &mu,
                &mut sigma,
                &mut rates,
                cone::Tolerance {
                    exact: 1e-13,
                    loose: 0.0,
                    plain_after_stall: false,
                },
                &mut cone::Memory::default(),
                |d, sigma, _| newton(&w, &r0, &mu, sigma, d.rates, 1e-13, &mut scratch),
            );
            assert!(
                done.converged && cone::violation(&rates, &sigma, &mu) <= 1e-13,
                "v = {v:?}, ω = {omega:?}"
            );
            // From no force Newton solves the falling, sliding and turning cube (not the one
            // tipping onto an edge, which Gauss–Seidel solves).
            assert_eq!(alone, omega[0] != 3.0, "v = {v:?}, ω = {omega:?}");
        }
    }

    #[test]
    fn newton_refuses_rows_without_response() {
        let (mut sigma, mut rates) = (vec![0.0; 3], vec![0.0; 3]);
        assert!(!newton(
            &[0.0; 9],
            &[-1.0, 0.0, 0.0],
            &[0.5],
            &mut sigma,
            &mut rates,
            1e-12,
            &mut Newton::default()
        ));
    }

    /// A cone problem on which Gauss–Seidel was slow (captured from
    /// `benchmarks/models/contact_tilted_cube.xml` at h = 1e-3: the cube's four corners as its
    /// face slaps down, µ = 0.6), with the Gauss–Seidel forces at the first finish.
    const STALLED_W: [f64; 144] = [
        0.0019999999999997307,
        0.0007219454935807431,
        0.0007770422796080075,
        0.000499999999999831,
        0.0007219454935806941,
        0.0007770422796079546,
        -0.0010000000000000005,
        0.0007219454935806127,
        0.0007770422796078671,
        0.0004999999999998991,
        0.0007219454935806616,
        0.0007770422796079196,
        0.0007219454935807431,
        0.0020550596057312054,
        -0.0007479762294461765,
        0.0007770422796079784,
        0.0005020237705537341,
        -0.0008050596057310722,
        -0.0007219454935809087,
        0.0004449403942687536,
        0.0007479762294463479,
        -0.000777042279608144,
        0.001997976229446225,
        0.0008050596057312437,
        0.0007770422796080074,
        -0.0007479762294461765,
        0.0019449403942687318,
        -0.0007219454935808795,
        0.0006949403942687604,
        0.0019979762294462,
        -0.0007770422796081149,
        0.0007479762294462799,
        0.0005550596057311791,
        0.000721945493580772,
        -0.0006949403942686569,
        0.0005020237705537103,
        0.0004999999999998309,
        0.0007770422796079784,
        -0.0007219454935808796,
        0.0019999999999999333,
        0.0007770422796079258,
        -0.0007219454935808306,
        0.0005000000000001018,
        0.0007770422796078381,
        -0.0007219454935807492,
        -0.0010000000000000005,
        0.0007770422796078907,
        -0.000721945493580798,
        0.0007219454935806941,
        0.0005020237705537341,
        0.0006949403942687604,
        0.0007770422796079257,
        0.0019449403942688936,
        0.00074797622944629,
        -0.0007219454935808597,
        0.001997976229446338,
        -0.0006949403942689197,
        -0.0007770422796080914,
        0.000555059605731179,
        -0.0007479762294464493,
        0.0007770422796079547,
        -0.0008050596057310722,
        0.0019979762294462006,
        -0.0007219454935808306,
        0.00074797622944629,
        0.002055059605731043,
        -0.0007770422796080622,
        0.0008050596057311836,
        0.0005020237705535965,
        0.0007219454935807232,
        -0.0007479762294461786,
        0.0004449403942687537,
        -0.0010000000000000009,
        -0.0007219454935809087,
        -0.000777042279608115,
        0.0005000000000001018,
        -0.0007219454935808597,
        -0.0007770422796080622,
        0.0020000000000002724,
        -0.0007219454935807781,
        -0.0007770422796079747,
        0.0005000000000001695,
        -0.000721945493580827,
        -0.0007770422796080272,
        0.0007219454935806126,
        0.0004449403942687536,
        0.0007479762294462799,
        0.000777042279607838,
        0.001997976229446338,
        0.0008050596057311836,
        -0.0007219454935807782,
        0.002055059605731157,
        -0.0007479762294464513,
        -0.0007770422796080036,
        0.0005020237705535725,
        -0.000805059605731355,
        0.0007770422796078671,
        0.0007479762294463479,
        0.0005550596057311791,
        -0.0007219454935807491,
        -0.0006949403942689197,
        0.0005020237705535965,
        -0.0007770422796079746,
        -0.0007479762294464513,
        0.0019449403942687791,
        0.0007219454935806415,
        0.0006949403942688162,
        0.001997976229446362,
        0.0004999999999998991,
        -0.000777042279608144,
        0.0007219454935807722,
        -0.0010000000000000005,
        -0.0007770422796080914,
        0.000721945493580723,
        0.0005000000000001696,
        -0.0007770422796080036,
        0.0007219454935806417,
        0.0020000000000000694,
        -0.0007770422796080563,
        0.0007219454935806905,
        0.0007219454935806615,
        0.001997976229446225,
        -0.000694940394268657,
        0.0007770422796078906,
        0.0005550596057311789,
        -0.0007479762294461786,
        -0.000721945493580827,
        0.0005020237705535725,
        0.0006949403942688163,
        -0.0007770422796080561,
        0.0019449403942686182,
        0.0007479762294463378,
        0.0007770422796079196,
        0.0008050596057312437,
        0.0005020237705537103,
        -0.0007219454935807979,
        -0.0007479762294464493,
        0.0004449403942687536,
        -0.0007770422796080271,
        -0.000805059605731355,
        0.001997976229446362,
        0.0007219454935806905,
        0.0007479762294463379,
        0.002055059605731318,
    ];
    const STALLED_R0: [f64; 12] = [
        -0.004904999996288124,
        0.0005304351241038859,
        0.0033878719690099935,
        -0.004905000005917305,
        0.0008922535787680613,
        0.00340117096606247,
        -0.0049050000096290325,
        0.0009055525758205376,
        0.0030393525113982947,
        -0.004904999999999851,
        0.0005437341211563622,
        0.0030260535143458184,
    ];
    const STALLED_SIGMA: [f64; 12] = [
        5.287750342466814,
        -0.6838218909709802,
        -3.0980795580103684,
        0.35495277164890565,
        -0.05747672464670645,
        -0.20506914775346669,
        1.7078932485700176,
        -0.316008780375777,
        -0.974793422315411,
        2.453290244523526,
        -0.2225018873320865,
        -1.4550604106800542,
    ];
    const STALLED_TOL: f64 = 3.132091952673165e-12;

    #[test]
    fn newton_finishes_in_one_call_a_problem_that_takes_gauss_seidel_dozens_of_sweeps() {
        let mu = [0.6; 4];
        // Gauss–Seidel alone from its own forces: 46 sweeps with its extrapolation (more
        // than 100 without, which is what this problem was dumped for).
        let (mut sigma, mut rates, mut kept) = (STALLED_SIGMA.to_vec(), vec![0.0; 12], vec![0.0; 12]);
        let mut dense = cone::Dense {
            w: &STALLED_W,
            rates: &mut kept,
        };
        dense.start(&STALLED_R0, &sigma);
        let alone = cone::solve(
            &mut dense,
            &mu,
            &mut sigma,
            &mut rates,
            cone::Tolerance {
                exact: STALLED_TOL,
                loose: 0.0,
                plain_after_stall: false,
            },
            &mut cone::Memory::extrapolating(),
            |_, _, _| false,
        );
        assert!(alone.converged && (40..60).contains(&alone.sweeps), "{alone:?}");
        // Newton from the same forces, in a few iterations.
        let mut sigma = STALLED_SIGMA.to_vec();
        let mut scratch = Newton::default();
        assert!(newton(
            &STALLED_W,
            &STALLED_R0,
            &mu,
            &mut sigma,
            &mut rates,
            STALLED_TOL,
            &mut scratch
        ));
        assert!(cone::violation(&rates, &sigma, &mu) <= STALLED_TOL);
    }
}
