//! The midpoint equation on SO(3) and its Newton solver.
//!
//! Every midpoint Lie method solves, for the incremental rotation vector `Ψ`,
//!
//! ```text
//! (1/h) I Ψ = exp(−Ψ/2) P                                            (M)
//! ```
//!
//! We solve the equivalent, better scaled `g(Ψ) = I Ψ − h exp(−Ψ/2) P = 0` whose exact
//! Jacobian is `∂g/∂Ψ = I − (h/2) exp(−Ψ/2) hat(P) Jr(−Ψ/2)`, by Newton's method from the
//! explicit guess `Ψ₀ = h I⁻¹ P` (the Lie-Euler increment). A typical step converges
//! quadratically in 2 to 4 iterations; the iteration stops when the Newton correction is
//! a few ulps of `|Ψ|`.

use crate::error::Error;
use crate::inertia::{Inertia, InertiaOperator};
use crate::linalg::{Mat3, Vec3};
use crate::so3;

/// Iteration cap of the Newton solvers.
pub const MAX_ITERATIONS: u32 = 50;
/// Converged when the correction is at most this many ulps of the unknown.
pub(crate) const CONVERGED_ULPS: f64 = 4.0;
/// Below this many ulps, a correction that no longer halves is round-off noise.
pub(crate) const STAGNATION_ULPS: f64 = 256.0;

/// The largest accepted rotation increment `|Ψ|` per (sub)step: beyond a half turn the
/// midpoint equation has several solutions and the step cannot resolve the rotation.
pub const MAX_INCREMENT_ANGLE: f64 = std::f64::consts::PI;

/// Why a Newton solve failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NotConverged {
    /// No convergence within [`MAX_ITERATIONS`], or the iterate became non-finite.
    Iterations {
        /// Residual norm relative to the scale of the equation.
        residual: f64,
        /// Iterations taken.
        iterations: u32,
    },
    /// Converged to a rotation increment of more than [`MAX_INCREMENT_ANGLE`].
    IncrementTooLarge {
        /// `|Ψ|` (rad).
        angle: f64,
    },
}

/// The stopping rule shared by all Newton iterations of the crate: converged when the
/// correction `|δ|` is a few ulps of `|x|`, or when, below a few hundred ulps, it stops
/// halving (round-off has been reached).
#[derive(Clone, Copy, Debug)]
pub(crate) struct NewtonStop {
    previous: f64,
}

impl NewtonStop {
    pub(crate) fn new() -> Self {
        NewtonStop {
            previous: f64::INFINITY,
        }
    }

    /// Whether the iteration is done after a correction of norm `delta` to an unknown of
    /// norm `x`.
    #[inline]
    pub(crate) fn done(&mut self, delta: f64, x: f64) -> bool {
        let ulp = f64::EPSILON * x;
        let done = delta <= CONVERGED_ULPS * ulp || (delta <= STAGNATION_ULPS * ulp && delta > 0.5 * self.previous);
        self.previous = delta;
        done
    }
}

/// The residual `g(Ψ) = I Ψ − h exp(−Ψ/2) P` of the (scaled) midpoint equation.
#[must_use]
pub fn residual(inertia: &Inertia, p: Vec3, h: f64, psi: Vec3) -> Vec3 {
    inertia.apply(psi) - so3::exp(-psi * 0.5) * p * h
}

/// The exact Jacobian `∂g/∂Ψ = I − (h/2) exp(−Ψ/2) hat(P) Jr(−Ψ/2)` of [`residual`].
#[must_use]
pub fn jacobian(inertia: &Inertia, p: Vec3, h: f64, psi: Vec3) -> Mat3 {
    let half = -psi * 0.5;
    *inertia.matrix() - so3::exp(half) * so3::hat(p) * so3::right_jacobian(half) * (0.5 * h)
}

/// Solve the midpoint equation (M) for `Ψ` from the initial guess `guess`.
///
/// `extra(Ψ)` adds a term to the right-hand side, `I Ψ = h exp(−Ψ/2) P + extra(Ψ)`; it is
/// frozen in the Jacobian (a simplified Newton iteration for that term, which converges
/// linearly with a rate of order `h²` times the torque stiffness). Pass `|_| Vec3::ZERO`
/// for the plain equation, which then converges quadratically.
///
/// Returns `Ψ` and the number of iterations; an error with the last residual when
/// `MAX_ITERATIONS` pass without convergence or the iterate becomes non-finite, or with the
/// angle when the solution turns by more than [`MAX_INCREMENT_ANGLE`] (a spurious root of
/// a step far too large for the rotation rate).
#[inline]
pub fn solve_with(
    inertia: &Inertia,
    p: Vec3,
    h: f64,
    guess: Vec3,
    mut extra: impl FnMut(Vec3) -> Vec3,
) -> Result<(Vec3, u32), NotConverged> {
    let scale = (p * h).norm() + f64::MIN_POSITIVE;
    let mut psi = guess;
    let mut stop = NewtonStop::new();
    let mut g = Vec3::ZERO;
    for it in 1..=MAX_ITERATIONS {
        let half = -psi * 0.5;
        let e = so3::exp(half);
        let ep = e * p;
        g = inertia.apply(psi) - ep * h - extra(psi);
        // ∂/∂Ψ of h exp(−Ψ/2) P is (h/2) exp(−Ψ/2) hat(P) Jr(−Ψ/2).
        let j = *inertia.matrix() - e * so3::hat(p) * so3::right_jacobian(half) * (0.5 * h);
        let Some(delta) = j.solve(g) else {
            break;
        };
        psi -= delta;
        if !psi.is_finite() {
            break;
        }
        if stop.done(delta.norm(), psi.norm()) {
            let angle = psi.norm();
            if angle > MAX_INCREMENT_ANGLE {
                return Err(NotConverged::IncrementTooLarge { angle });
            }
            return Ok((psi, it));
        }
    }
    Err(NotConverged::Iterations {
        residual: g.norm() / scale,
        iterations: MAX_ITERATIONS,
    })
}

/// Solve the plain midpoint equation (M): the lean kernel of every explicit midpoint Lie
/// step.
///
/// - Guess: the third-order predictor `Ψ₁ = h I⁻¹ (P + ½ P × Ψ₀)`, `Ψ₀ = h I⁻¹ P`, from
///   `exp(−Ψ/2) P = P + ½ P × Ψ + O(Ψ²)`. It is better than a warm start from an earlier
///   increment, whose error is the change of `Ψ` over a step: on the fast top over
///   `t ∈ [0, 0.8]` the predictor is within 6.5e-8 (relative) of the root at `h = 1e-4`
///   and 6.6e-6 at `h = 1e-3`, the previous step's increment only within 1.2e-5 and
///   1.2e-4, enough to cost a second Newton iteration (`examples/newton_guess.rs`).
/// - Newton with the exact Jacobian written as `I − (h/2) hat(Q) Jl(−Ψ/2)`,
///   `Q = exp(−Ψ/2) P` (since `exp(a) hat(P) Jr(a) = hat(exp(a) P) Jl(a)`), so one set of
///   coefficients serves the residual and the Jacobian; the 3x3 system is solved by the
///   adjugate.
/// - Stop when the predicted next correction is below an ulp of `|Ψ|`: the second
///   derivative of `h exp(−Ψ/2) P` is at most `h |P| / 4`, so Newton's error after a
///   correction `δ` is about `‖J⁻¹‖ h |P| |δ|² / 8 ≤ h |P| |δ|² / (8 λ_min)`; we stop when
///   `h |P| |δ|² / λ_min ≤ u |Ψ|` (a factor 8 to spare), or when the correction itself is
///   at round-off. The predictor is accurate to `O(|Ψ|³)`, so typical steps
///   (`|Ψ| ≲ 0.2`) take one iteration (measured on the fast top at `h = 1e-4`: one
///   iteration in every step). Large increments take two: on the fast top the
///   compositions' half steps of 1 to 2.6 rad (EA4 at `h = 8.1e-3`, EA6 at `5.75e-3`)
///   average 2.0 to 2.1 iterations. Refining the predictor by fixed-point steps
///   `Ψ ← h I⁻¹ exp(−Ψ/2) P` first (each contracts the error about 40 times there) took
///   2.2 to 2.4 of them plus 1.2 to 1.3 Newton iterations, and 8 to 13% more time.
///
/// Returns `Ψ` and the number of iterations.
#[inline]
pub fn solve<I: InertiaOperator + ?Sized>(inertia: &I, p: Vec3, h: f64) -> Result<(Vec3, u32), NotConverged> {
    solve_increment(inertia, p, h).map(|(inc, it)| (inc.psi(), it))
}

/// [`solve`], returning the increment `exp(Ψ)` with its Rodrigues coefficients ready for the
/// updates `R exp(Ψ)` and `exp(−Ψ) x`. They come from the coefficients of `exp(−Ψ_k/2)` that
/// Newton's last iteration computed at its iterate `Ψ_k` (see
/// [`so3::Increment::from_half_angle`]), so no further series is evaluated: the trig of
/// `exp(−Ψ/2)` and `exp(Ψ)` is shared.
#[inline(always)]
pub(crate) fn solve_increment<I: InertiaOperator + ?Sized>(
    inertia: &I,
    p: Vec3,
    h: f64,
) -> Result<(so3::Increment, u32), NotConverged> {
    // The solvers take `P` in three registers. Passed by reference, it sat in memory the
    // caller had just written one component and then two, and the solver's 16-byte load of
    // two of them straddled both stores, which the processor cannot forward: the load waited
    // on the step's critical path (EA 191 → 171 ns per step on the fast top).
    let (x, y, z) = (p.x, p.y, p.z);
    match inertia.diagonal() {
        Some((d, d_inv)) => solve_diagonal(d, d_inv, inertia.inverse_norm_bound(), x, y, z, h),
        None => solve_general(inertia, x, y, z, h),
    }
}

/// [`solve_increment`] from the guess `guess` instead of the predictor: the same Newton
/// iteration and stopping rule. For an outer iteration that solves (M) again with a
/// momentum `P` changed by a small correction (the multibody position solve): the last
/// root is then within the change, and Newton's first correction is already below the
/// quadratic stopping rule, where the predictor's `O(|Ψ|³)` error takes two.
#[inline(always)]
pub(crate) fn solve_increment_from<I: InertiaOperator + ?Sized>(
    inertia: &I,
    p: Vec3,
    h: f64,
    guess: Vec3,
) -> Result<(so3::Increment, u32), NotConverged> {
    match inertia.diagonal() {
        Some((d, _)) => {
            let hn = h * inertia.inverse_norm_bound();
            let quadratic2 = p.norm_squared() * hn * hn;
            lean_newton(p, h, guess, quadratic2, |psi| diagonal_newton_terms(d, p, h, psi))
        }
        None => {
            let quadratic2 = p.norm_squared() * h * h * inertia.inverse_norm_bound().powi(2);
            lean_newton(p, h, guess, quadratic2, |psi| general_newton_terms(inertia, p, h, psi))
        }
    }
}

/// [`solve_increment`] for a full tensor.
#[inline(never)]
fn solve_general<I: InertiaOperator + ?Sized>(
    inertia: &I,
    px: f64,
    py: f64,
    pz: f64,
    h: f64,
) -> Result<(so3::Increment, u32), NotConverged> {
    let p = Vec3::new(px, py, pz);
    let psi0 = inertia.apply_inverse(p) * h;
    let psi = inertia.apply_inverse(p + p.cross(psi0) * 0.5) * h;
    // The stopping rule h|P| |δ|² / λ_min ≤ u |Ψ|, squared to avoid square roots.
    let quadratic2 = p.norm_squared() * h * h * inertia.inverse_norm_bound().powi(2);
    lean_newton(p, h, psi, quadratic2, |psi| general_newton_terms(inertia, p, h, psi))
}

/// The residual, Jacobian and half-angle coefficients of (M) at `psi` for a full tensor.
#[inline(always)]
fn general_newton_terms<I: InertiaOperator + ?Sized>(
    inertia: &I,
    p: Vec3,
    h: f64,
    psi: Vec3,
) -> (Vec3, Mat3, [f64; 4]) {
    let (v, q, [t2, a, b, c]) = half_rotation(p, psi);
    let g = inertia.apply(psi) - q * h;
    // J = I − (h/2) hat(Q) Jl(v), Jl(v) = I + b hat(v) + c hat(v)²; columns q × Jl e_k.
    let jl = so3::i_plus_hat_plus_hat2(v, b, c);
    let s = -0.5 * h;
    let (c0, c1, c2) = (q.cross(jl.col(0)) * s, q.cross(jl.col(1)) * s, q.cross(jl.col(2)) * s);
    let j = inertia.plus(&Mat3::from_rows([
        [c0.x, c1.x, c2.x],
        [c0.y, c1.y, c2.y],
        [c0.z, c1.z, c2.z],
    ]));
    (g, j, [t2, a, b, c])
}

/// `v = −Ψ/2`, `Q = exp(v) P = P + a v × P + b v × (v × P)` and the coefficients
/// `[θ², a, b, c]` of `exp(v)` (`θ = |v|`): the part of an iteration of (M) that the general
/// and the diagonal solver share.
#[inline(always)]
fn half_rotation(p: Vec3, psi: Vec3) -> (Vec3, Vec3, [f64; 4]) {
    let v = psi * -0.5;
    let t2 = v.norm_squared();
    let (a, b, c) = so3::coefficients(t2);
    let vp = v.cross(p);
    (v, p + vp * a + v.cross(vp) * b, [t2, a, b, c])
}

/// The Newton iteration of [`solve`] from the guess `psi`: `residual_and_jacobian(Ψ)`
/// returns `(g(Ψ), ∂g/∂Ψ)`, the correction comes from the adjugate, and the iteration
/// stops by the quadratic rule `quadratic2 |δ|⁴ ≤ u² |Ψ|²` or at round-off.
#[inline(always)]
fn lean_newton(
    p: Vec3,
    h: f64,
    mut psi: Vec3,
    quadratic2: f64,
    mut residual_and_jacobian: impl FnMut(Vec3) -> (Vec3, Mat3, [f64; 4]),
) -> Result<(so3::Increment, u32), NotConverged> {
    let mut stop = NewtonStop::new();
    let mut g = Vec3::ZERO;
    for it in 1..=MAX_ITERATIONS {
        let (j, half);
        (g, j, half) = residual_and_jacobian(psi);
        let Some(delta) = j.solve_adjugate(g) else {
            break;
        };
        psi -= delta;
        if !psi.is_finite() {
            break;
        }
        let (d2, x2) = (delta.norm_squared(), psi.norm_squared());
        if quadratic2 * d2 * d2 <= f64::EPSILON * f64::EPSILON * x2 || stop.done(d2.sqrt(), x2.sqrt()) {
            if x2 > MAX_INCREMENT_ANGLE * MAX_INCREMENT_ANGLE {
                return Err(NotConverged::IncrementTooLarge { angle: x2.sqrt() });
            }
            return Ok((so3::Increment::from_half_angle(psi, half), it));
        }
    }
    let scale = (p * h).norm() + f64::MIN_POSITIVE;
    Err(NotConverged::Iterations {
        residual: g.norm() / scale,
        iterations: MAX_ITERATIONS,
    })
}

/// [`solve`] for a diagonal tensor `D = diag(d)`, written out in scalars.
///
/// With `Jl(v) = (1 − c θ²) I + b hat(v) + c v vᵀ` and `hat(q) hat(v) = v qᵀ − (q·v) I`, the
/// Jacobian is diagonal plus skew plus two rank-one terms,
///
/// ```text
/// J = D + β (q·v) I − α hat(q) − β v qᵀ − γ (q × v) vᵀ,
/// α = (h/2)(1 − c θ²),  β = (h/2) b,  γ = (h/2) c,
/// ```
///
/// built entry by entry and solved by the adjugate; same iterates as the general path up to
/// rounding.
///
/// `#[inline]` leaves the choice to the compiler, which keeps it a call in the integrators'
/// steps (forced inline there, EA took 196 ns per step instead of 156) and inlines it into
/// the many-body loop (as a call, the scalar many-body path ran at 5.1 M body-steps/s
/// instead of 6.3 M).
#[inline]
fn solve_diagonal(
    d: Vec3,
    d_inv: Vec3,
    inverse_norm: f64,
    px: f64,
    py: f64,
    pz: f64,
    h: f64,
) -> Result<(so3::Increment, u32), NotConverged> {
    let p = Vec3::new(px, py, pz);
    let hd = d_inv * h;
    // P × (h D⁻¹ P) = h (d⁻¹_z − d⁻¹_y) P_y P_z, …: two products on the critical path
    // instead of a cross product of a product.
    let k = Vec3::new(d_inv.z - d_inv.y, d_inv.x - d_inv.z, d_inv.y - d_inv.x) * (0.5 * h);
    let pp = Vec3::new(p.y * p.z, p.z * p.x, p.x * p.y);
    let psi = hd.component_mul(p) + hd.component_mul(k).component_mul(pp);
    let quadratic2 = p.norm_squared() * (h * inverse_norm) * (h * inverse_norm);
    lean_newton(p, h, psi, quadratic2, |psi| diagonal_newton_terms(d, p, h, psi))
}

/// The residual, Jacobian and half-angle coefficients of (M) at `psi` for `D = diag(d)`
/// (see [`solve_diagonal`]).
#[inline(always)]
fn diagonal_newton_terms(d: Vec3, p: Vec3, h: f64, psi: Vec3) -> (Vec3, Mat3, [f64; 4]) {
    let s = 0.5 * h;
    let (v, q, [t2, a, b, c]) = half_rotation(p, psi);
    let g = d.component_mul(psi) - q * h;
    let w = q.cross(v);
    let (alpha, beta, gamma) = (s * (1.0 - c * t2), s * b, s * c);
    let diag = beta * q.dot(v);
    let (bv, gw, aq) = (v * beta, w * gamma, q * alpha);
    let j = Mat3::from_rows([
        [
            d.x + diag - bv.x * q.x - gw.x * v.x,
            aq.z - bv.x * q.y - gw.x * v.y,
            -aq.y - bv.x * q.z - gw.x * v.z,
        ],
        [
            -aq.z - bv.y * q.x - gw.y * v.x,
            d.y + diag - bv.y * q.y - gw.y * v.y,
            aq.x - bv.y * q.z - gw.y * v.z,
        ],
        [
            aq.y - bv.z * q.x - gw.z * v.x,
            -aq.x - bv.z * q.y - gw.z * v.y,
            d.z + diag - bv.z * q.z - gw.z * v.z,
        ],
    ]);
    (g, j, [t2, a, b, c])
}

/// Map a failed Newton solve to the library's error.
pub(crate) fn newton_error(method: &'static str, equation: &'static str, t: f64, h: f64, e: NotConverged) -> Error {
    match e {
        NotConverged::Iterations { residual, iterations } => Error::NewtonDidNotConverge {
            method,
            equation,
            t,
            h,
            residual,
            iterations,
        },
        NotConverged::IncrementTooLarge { angle } => Error::StepTooLarge { method, t, h, angle },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::Rng;

    #[test]
    fn jacobian_matches_central_differences() {
        let mut rng = Rng::new(11);
        let inertia = Inertia::from_matrix([[2.0, 0.3, -0.1], [0.3, 3.0, 0.2], [-0.1, 0.2, 4.0]]).unwrap();
        for _ in 0..50 {
            let p = rng.unit_vector() * (5.0 * rng.uniform() + 0.1);
            let h = 0.5 * rng.uniform() + 0.01;
            let psi = rng.unit_vector() * (3.0 * rng.uniform());
            let j = jacobian(&inertia, p, h, psi);
            let eps = 1e-6;
            for k in 0..3 {
                let mut e = [0.0; 3];
                e[k] = eps;
                let e = Vec3::from_array(e);
                let fd = (residual(&inertia, p, h, psi + e) - residual(&inertia, p, h, psi - e)) * (0.5 / eps);
                let col = j.col(k);
                assert!(
                    (fd - col).max_abs() < 1e-8 * (1.0 + col.max_abs()),
                    "column {k}: {fd:?} vs {col:?}"
                );
            }
        }
    }

    #[test]
    fn solves_to_round_off_in_few_iterations() {
        let mut rng = Rng::new(12);
        let inertia = Inertia::principal([1.0, 2.0, 3.0]).unwrap();
        let mut max_it = 0;
        for _ in 0..200 {
            let p = rng.unit_vector() * 2.0;
            let h = 0.2 * rng.uniform() + 1e-3; // |Ψ| up to about 0.4
            let (psi, it) = solve(&inertia, p, h).unwrap();
            max_it = max_it.max(it);
            let r = residual(&inertia, p, h, psi).norm() / (h * p.norm());
            assert!(r < 1e-15, "relative residual {r:e}");
        }
        assert!(max_it <= 5, "Newton took {max_it} iterations");
        // The lean solver (diagonal fast path, and the general path for a full tensor)
        // agrees with the general one.
        let full = Inertia::from_matrix([[2.0, 0.3, -0.1], [0.3, 3.0, 0.2], [-0.1, 0.2, 4.0]]).unwrap();
        for inertia in [inertia, full] {
            for _ in 0..100 {
                let p = rng.unit_vector() * 2.0;
                let h = 0.2 * rng.uniform() + 1e-3;
                let (a, _) = solve(&inertia, p, h).unwrap();
                let (b, _) = solve_with(&inertia, p, h, inertia.apply_inverse(p) * h, |_| Vec3::ZERO).unwrap();
                assert!((a - b).norm() <= 4.0 * f64::EPSILON * a.norm(), "{a:?} vs {b:?}");
            }
        }
        // Large increments of asymmetric bodies, far from the one-iteration regime of the
        // predictor: same root as plain Newton from Ψ₀, to round-off.
        for _ in 0..500 {
            // Moments in [1, 5], drawn until they are those of a body (triangle inequality).
            let inertia = loop {
                let moments = [
                    1.0 + 4.0 * rng.uniform(),
                    1.0 + 4.0 * rng.uniform(),
                    1.0 + 4.0 * rng.uniform(),
                ];
                if let Ok(inertia) = Inertia::principal(moments) {
                    break inertia;
                }
            };
            let p = rng.unit_vector() * 2.0;
            let h = 2.5 * rng.uniform() + 1e-3; // |Ψ| up to about 2.5
            let (a, _) = match solve(&inertia, p, h) {
                Ok(r) => r,
                Err(NotConverged::IncrementTooLarge { .. }) => continue,
                Err(e) => panic!("{e:?}"),
            };
            let r = residual(&inertia, p, h, a).norm() / (h * p.norm());
            assert!(r < 1e-14, "relative residual {r:e}");
            if let Ok((b, _)) = solve_with(&inertia, p, h, inertia.apply_inverse(p) * h, |_| Vec3::ZERO) {
                assert!((a - b).norm() <= 1e-13 * a.norm(), "{a:?} vs {b:?}");
            }
        }
        // Large increments of a fast symmetric top (the fast top's inertia, half steps
        // turning by 0.5 to 2.6 rad as the compositions' largest steps do). With the
        // momentum a fraction ε off the axis, the predictor is within about ε/30 of the root
        // (relative) and Newton's error after one iteration is 0.3 to 0.7 times its square:
        // up to ε = 0.3% two iterations reach round-off, up to ε = 1% at most three (the
        // fast top's nutation takes its momentum up to 0.8% off axis).
        let top = Inertia::principal([0.045_489_6, 0.045_489_6, 0.001_399_68]).unwrap();
        let spin_rate = 313.0 * std::f64::consts::PI;
        let spin = spin_rate * 0.001_399_68;
        for (off_axis, most) in [(0.003, 2), (0.01, 3)] {
            let mut iterations = [0u32; 5];
            for _ in 0..2000 {
                let p = Vec3::new(0.0, 0.0, spin) + rng.unit_vector() * (off_axis * spin * rng.uniform());
                let h = (0.5 + 2.1 * rng.uniform()) / spin_rate;
                let (psi, it) = solve(&top, p, h).unwrap();
                let r = residual(&top, p, h, psi).norm() / (h * p.norm());
                assert!(r < 1e-15, "relative residual {r:e}");
                iterations[(it as usize).min(4)] += 1;
            }
            assert!(
                iterations[most + 1..].iter().all(|&n| n == 0),
                "off axis {off_axis}: iterations 0, 1, 2, 3, >3: {iterations:?}"
            );
        }
        // Zero momentum: Ψ = 0 exactly, at once.
        assert_eq!(solve(&inertia, Vec3::ZERO, 0.1).unwrap(), (Vec3::ZERO, 1));
    }
}
