//! The rotation group SO(3): hat and vee, the exponential and logarithm maps, their
//! Jacobians, the Cayley map, unit quaternions and re-orthonormalisation.
//!
//! Conventions (see docs/theory/rigid.md §1):
//! - `hat(a)` is the skew matrix with `hat(a) b = a × b`; [`vee`] is its inverse.
//! - `exp(a) = I + (sin θ/θ) hat(a) + ((1 − cos θ)/θ²) hat(a)²`, `θ = |a|` (Rodrigues).
//! - Right Jacobian `Jr(a) = I − ((1 − cos θ)/θ²) hat(a) + ((θ − sin θ)/θ³) hat(a)²`, so that
//!   `exp(a + δ) = exp(a) exp(Jr(a) δ) + O(δ²)`; left Jacobian `Jl(a) = Jr(−a)`, so that
//!   `exp(a + δ) = exp(Jl(a) δ) exp(a) + O(δ²)`.
//!
//! Every coefficient that cancels near `θ = 0` switches to its Taylor series there, so all
//! maps are accurate to a few ulps for every `θ`, including `θ = 0` exactly.

use std::ops::{Add, Mul, Sub};

use crate::linalg::{Mat3, Vec3};

/// Below this angle (squared: 0.01) all coefficients use their Taylor series up to `θ⁸`,
/// whose truncation error is below `3e-17` relative at the switch; above it the closed
/// forms are accurate, since every coefficient multiplies a power of `hat(v)` that scales
/// its own round-off down to a few ulps of the result.
pub(crate) const SERIES_ANGLE_SQUARED: f64 = 0.01;
/// Below this angle squared (`θ < 1`) the coefficients use their series to `θ¹⁶`.
const LONG_SERIES_ANGLE_SQUARED: f64 = 1.0;
/// Below this angle squared (`θ < 2`) the coefficients use their series to `θ²²`.
const LONGER_SERIES_ANGLE_SQUARED: f64 = 4.0;
/// Below this angle squared (`θ < 4`) the coefficients are doubled from the series.
const DOUBLING_ANGLE_SQUARED: f64 = 16.0;
#[cfg(test)]
const EXP_SERIES_ANGLE: f64 = 0.1;
/// Below this angle the inverse-Jacobian coefficient uses its Taylor series.
const JAC_SERIES_ANGLE: f64 = 0.1;

/// The coefficients `(sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³)` of Rodrigues' formula and
/// of the Jacobians, from `θ²`, without calling `sin` or `cos` below `θ = 4`:
///
/// - `θ < 0.1`: their Taylor series to `θ⁸` (truncation below `3e-17` relative);
/// - `θ < 1`: their Taylor series to `θ¹⁶` (the first omitted term, `θ¹⁸/19!` for `a`,
///   is below `1e-17` relative);
/// - `θ < 2`: their Taylor series to `θ²²` (first omitted term below `3e-18` relative; the
///   largest term, `θ²/6` in `a`, is at most 1.5 times the sum, so rounding stays an ulp
///   or two);
/// - `θ < 4`: the series at `θ/2`, doubled once by the exact half-angle identities (no
///   cancellation; the doubling adds about an ulp)
///
/// ```text
/// a(θ) = a(θ/2) cos(θ/2),  b(θ) = a(θ/2)² / 2,  c(θ) = (c(θ/2) + a(θ/2) b(θ/2)) / 4,
/// cos(θ/2) = 1 − (θ/2)² b(θ/2);
/// ```
///
/// - beyond: the closed forms with one `sin_cos`.
#[inline]
pub(crate) fn coefficients(t2: f64) -> (f64, f64, f64) {
    some_coefficients::<true>(t2)
}

/// `(a, b)` of [`coefficients`], bit for bit, without the work for `c` (what `exp` and the
/// rotation of a vector need).
#[inline]
pub(crate) fn rodrigues(t2: f64) -> (f64, f64) {
    let (a, b, _) = some_coefficients::<false>(t2);
    (a, b)
}

/// [`coefficients`]; with `WITH_C = false` the third is not computed (0).
///
/// The short series is inlined into the caller and the longer branches are a call, so the
/// common case needs no call and returns its coefficients in registers (the Lie-Euler
/// floor's step went from 26 to 24 ns; EA's did not change measurably).
#[inline(always)]
fn some_coefficients<const WITH_C: bool>(t2: f64) -> (f64, f64, f64) {
    if t2 < SERIES_ANGLE_SQUARED {
        short_series(t2)
    } else {
        long_coefficients::<WITH_C>(t2)
    }
}

/// [`some_coefficients`] from `θ = 0.1` on.
#[inline(never)]
fn long_coefficients<const WITH_C: bool>(t2: f64) -> (f64, f64, f64) {
    if t2 < LONG_SERIES_ANGLE_SQUARED {
        by_series::<WITH_C>(t2, series8)
    } else if t2 < LONGER_SERIES_ANGLE_SQUARED {
        by_series::<WITH_C>(t2, series11)
    } else if t2 < DOUBLING_ANGLE_SQUARED {
        doubled::<WITH_C>(t2)
    } else {
        let theta = t2.sqrt();
        let (s, co) = theta.sin_cos();
        (s / theta, (1.0 - co) / t2, (theta - s) / (theta * t2))
    }
}

/// Taylor series to `θ⁸` for `θ² < 0.01`, by Estrin's scheme with constant coefficients: no
/// division, and half the dependency chain of Horner's rule (these sit on the critical
/// path of every step). Generic so that the SIMD lanes of the many-body kernel evaluate
/// exactly the same operations as the scalar path.
#[inline(always)]
pub(crate) fn short_series<T>(t: T) -> (T, T, T)
where
    T: Copy + From<f64> + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let k = T::from;
    let (tt, tttt) = (t * t, (t * t) * (t * t));
    let a = (k(1.0) - t * k(1.0 / 6.0)) + tt * (k(1.0 / 120.0) - t * k(1.0 / 5040.0)) + tttt * k(1.0 / 362_880.0);
    let b = (k(0.5) - t * k(1.0 / 24.0)) + tt * (k(1.0 / 720.0) - t * k(1.0 / 40_320.0)) + tttt * k(1.0 / 3_628_800.0);
    let c = (k(1.0 / 6.0) - t * k(1.0 / 120.0))
        + tt * (k(1.0 / 5040.0) - t * k(1.0 / 362_880.0))
        + tttt * k(1.0 / 39_916_800.0);
    (a, b, c)
}

/// `Σ_{k ≤ 8} (−t)ᵏ / (2k + n)!` by Estrin's scheme, from the reciprocal factorials `f[k]`.
#[inline]
fn series8(t: f64, f: &[f64; 12]) -> f64 {
    let (t2, t4) = (t * t, (t * t) * (t * t));
    let low = (f[0] - t * f[1]) + t2 * (f[2] - t * f[3]);
    let high = (f[4] - t * f[5]) + t2 * (f[6] - t * f[7]);
    low + t4 * (high + t4 * f[8])
}

/// `Σ_{k ≤ 11} (−t)ᵏ / (2k + n)!` by Estrin's scheme, from the reciprocal factorials `f[k]`.
#[inline]
fn series11(t: f64, f: &[f64; 12]) -> f64 {
    let (t2, t4) = (t * t, (t * t) * (t * t));
    let p0 = (f[0] - t * f[1]) + t2 * (f[2] - t * f[3]);
    let p1 = (f[4] - t * f[5]) + t2 * (f[6] - t * f[7]);
    let p2 = (f[8] - t * f[9]) + t2 * (f[10] - t * f[11]);
    p0 + t4 * (p1 + t4 * p2)
}

/// `1/(2k + offset)!` for `k = 0..N`: the Taylor coefficients of `sin θ/θ`, `cos θ`,
/// `(1 − cos θ)/θ²` and their kin, computed at compile time (each factorial a product in
/// increasing order, then one division). The one copy for every series in the crate.
pub(crate) const fn reciprocal_factorials<const N: usize>(offset: u32) -> [f64; N] {
    let mut out = [0.0; N];
    let mut k = 0;
    while k < N {
        let mut f = 1.0;
        let mut j = 2;
        while j <= 2 * k as u32 + offset {
            f *= j as f64;
            j += 1;
        }
        out[k] = 1.0 / f;
        k += 1;
    }
    out
}

const A_SERIES: [f64; 12] = reciprocal_factorials(1);
const B_SERIES: [f64; 12] = reciprocal_factorials(2);
const C_SERIES: [f64; 12] = reciprocal_factorials(3);

/// The three coefficients from one truncated series, `series(t, f)` with the reciprocal
/// factorials `f` of each: [`series8`] (to `θ¹⁶`) for `θ² < 1`, [`series11`] (to `θ²²`) for
/// `θ² < 4`.
#[inline]
fn by_series<const WITH_C: bool>(t: f64, series: impl Fn(f64, &[f64; 12]) -> f64) -> (f64, f64, f64) {
    let c = if WITH_C { series(t, &C_SERIES) } else { 0.0 };
    (series(t, &A_SERIES), series(t, &B_SERIES), c)
}

/// For `4 ≤ θ² < 16`: the series at `θ/2`, doubled once.
#[inline(never)]
fn doubled<const WITH_C: bool>(t2: f64) -> (f64, f64, f64) {
    let t = 0.25 * t2;
    let (a, b, c) = by_series::<WITH_C>(t, series11);
    let cos_half = 1.0 - t * b;
    let c = if WITH_C { 0.25 * (c + a * b) } else { 0.0 };
    (a * cos_half, 0.5 * a * a, c)
}

/// `hat(a)`: the skew-symmetric matrix with `hat(a) b = a × b`.
#[must_use]
#[inline]
pub fn hat(a: Vec3) -> Mat3 {
    Mat3::from_rows([[0.0, -a.z, a.y], [a.z, 0.0, -a.x], [-a.y, a.x, 0.0]])
}

/// `vee(A)`: the vector of the skew-symmetric part of `A`, `vee(hat(a)) = a`.
#[must_use]
#[inline]
pub fn vee(a: &Mat3) -> Vec3 {
    let m = &a.m;
    Vec3::new(
        0.5 * (m[2][1] - m[1][2]),
        0.5 * (m[0][2] - m[2][0]),
        0.5 * (m[1][0] - m[0][1]),
    )
}

/// The Rodrigues coefficients `(sin θ/θ, (1 − cos θ)/θ²)` as functions of `θ`.
#[cfg(test)]
fn rodrigues_coefficients(theta: f64) -> (f64, f64) {
    let (a, b) = rodrigues(theta * theta);
    (a, b)
}

/// `I + a hat(v) + b hat(v)²`, written out with `hat(v)² = v vᵀ − |v|² I`.
#[inline]
pub(crate) fn i_plus_hat_plus_hat2(v: Vec3, a: f64, b: f64) -> Mat3 {
    let t2 = v.norm_squared();
    let d = 1.0 - b * t2;
    let (x, y, z) = (v.x, v.y, v.z);
    Mat3::from_rows([
        [d + b * x * x, b * x * y - a * z, b * x * z + a * y],
        [b * x * y + a * z, d + b * y * y, b * y * z - a * x],
        [b * x * z - a * y, b * y * z + a * x, d + b * z * z],
    ])
}

/// The exponential map `exp(hat(v))` (Rodrigues' formula); exact rotation for every `v`,
/// accurate to round-off including at and near `v = 0`.
#[must_use]
#[inline]
pub fn exp(v: Vec3) -> Mat3 {
    let (a, b) = rodrigues(v.norm_squared());
    i_plus_hat_plus_hat2(v, a, b)
}

/// `exp(v) − I = a hat(v) + b hat(v)²`: the increment of a rotation, accurate to a few
/// ulps of itself (not of the identity), so that updates `R + R (exp(v) − I)` round
/// relative to the change and not to `R`.
#[must_use]
#[inline]
pub fn exp_increment(v: Vec3) -> Mat3 {
    let (a, b) = rodrigues(v.norm_squared());
    i_plus_hat_plus_hat2_minus_identity(v, a, b)
}

/// A rotation increment `exp(Ψ)` with its Rodrigues coefficients computed once, for the
/// updates of a step: `R exp(Ψ)` and `exp(−Ψ) x`, both in increment form.
#[derive(Clone, Copy, Debug)]
pub struct Increment {
    psi: Vec3,
    a: f64,
    b: f64,
}

impl Increment {
    /// The increment `exp(Ψ)`.
    #[must_use]
    #[inline]
    pub fn new(psi: Vec3) -> Self {
        let (a, b) = rodrigues(psi.norm_squared());
        Increment { psi, a, b }
    }

    /// The increment `exp(Ψ)` from the coefficients `[t, a, b, c]` of `exp(v)` at a nearby
    /// half angle, `v = −Ψ_k/2`, `t = |v|²` (what the last Newton iteration of the midpoint
    /// solve computed, before its final correction `Ψ = Ψ_k − δ`), without evaluating a
    /// series. With `t* = |Ψ|²/4` and `Δ = t* − t`, first order in `Δ` moves the half-angle
    /// coefficients to `Ψ/2`,
    ///
    /// ```text
    /// a(t*) = a + (c − b) Δ / 2,   cos(√t*) = 1 − t b − a Δ / 2
    /// ```
    ///
    /// (`da/dt = (c − b)/2`, `d cos √t / dt = −a/2`), and one exact doubling gives those of
    /// `Ψ`: `sin θ/θ = a(t*) cos(√t*)`, `(1 − cos θ)/θ² = a(t*)²/2`. The neglected
    /// second-order terms are `Δ²/2` times second derivatives of at most 1/12. Newton stops
    /// when its predicted next error is below an ulp of `|Ψ|`, which bounds the last
    /// correction by `|δ| ≤ √u` (u the unit round-off), so `Δ ≈ |Ψ| |δ|/2` gives
    /// `Δ² ≤ u t*` and the terms stay below `u t*/24`, a tenth of an ulp for `|Ψ| ≤ π`.
    #[must_use]
    #[inline]
    pub(crate) fn from_half_angle(psi: Vec3, [t, a, b, c]: [f64; 4]) -> Self {
        let delta = 0.25 * psi.norm_squared() - t;
        let a_half = a + 0.5 * (c - b) * delta;
        let cos_half = (1.0 - t * b) - 0.5 * a * delta;
        Increment {
            psi,
            a: a_half * cos_half,
            b: 0.5 * a_half * a_half,
        }
    }

    /// The increment `exp(Ψ)` from its Rodrigues coefficients `a = sin θ/θ`,
    /// `b = (1 − cos θ)/θ²` computed elsewhere (the variational solve's, moved to its root).
    #[must_use]
    #[inline]
    pub(crate) fn from_coefficients(psi: Vec3, a: f64, b: f64) -> Self {
        Increment { psi, a, b }
    }

    /// The rotation vector `Ψ`.
    #[must_use]
    #[inline]
    pub fn psi(&self) -> Vec3 {
        self.psi
    }

    /// `R exp(Ψ) = R + R (exp(Ψ) − I)`.
    #[must_use]
    #[inline]
    pub fn rotate(&self, r: &Mat3) -> Mat3 {
        *r + *r * i_plus_hat_plus_hat2_minus_identity(self.psi, self.a, self.b)
    }

    /// `exp(−Ψ) x = x − a Ψ × x + b Ψ × (Ψ × x)`.
    #[must_use]
    #[inline]
    pub fn inverse_apply(&self, x: Vec3) -> Vec3 {
        let px = self.psi.cross(x);
        x - px * self.a + self.psi.cross(px) * self.b
    }
}

/// `a hat(v) + b hat(v)²`.
#[inline]
fn i_plus_hat_plus_hat2_minus_identity(v: Vec3, a: f64, b: f64) -> Mat3 {
    let (x, y, z) = (v.x, v.y, v.z);
    let (xx, yy, zz) = (x * x, y * y, z * z);
    Mat3::from_rows([
        [-b * (yy + zz), b * x * y - a * z, b * x * z + a * y],
        [b * x * y + a * z, -b * (xx + zz), b * y * z - a * x],
        [b * x * z - a * y, b * y * z + a * x, -b * (xx + yy)],
    ])
}

/// `R exp(v)`, computed as `R + R (exp(v) − I)`: for the small increments of a time step
/// this rounds relative to the increment, so the attitude does not pick up a systematic
/// phase drift of an ulp of `R` per step.
#[must_use]
#[inline]
pub fn rotate_right(r: &Mat3, v: Vec3) -> Mat3 {
    *r + *r * exp_increment(v)
}

/// `exp(v) x` without forming the matrix: `x + a v × x + b v × (v × x)`; like
/// [`rotate_right`], it rounds relative to the change of `x`.
#[must_use]
#[inline]
pub fn exp_apply(v: Vec3, x: Vec3) -> Vec3 {
    let (a, b) = rodrigues(v.norm_squared());
    let vx = v.cross(x);
    x + vx * a + v.cross(vx) * b
}

/// The logarithm map: the rotation vector `v` with `|v| ≤ π` and `exp(v) = R`.
///
/// The angle comes from `atan2(|vee(R − Rᵀ)|/2, (tr R − 1)/2)`, never from `acos` of the
/// trace alone, and for angles above `π/2` the axis comes from the symmetric part
/// `(R + Rᵀ)/2 − cos θ I = (1 − cos θ) n nᵀ`, so the map is accurate near 0 and near `π`.
/// `R` is assumed orthogonal; for a matrix that is not, the result is the rotation vector
/// of a nearby rotation.
#[must_use]
pub fn log(r: &Mat3) -> Vec3 {
    let w = vee(r); // sin θ n
    let s = w.norm();
    let c = 0.5 * (r.trace() - 1.0);
    let theta = s.atan2(c);
    if c >= 0.0 {
        // θ ≤ π/2: v = θ n = (θ / sin θ) w; atan2 keeps θ/s accurate for tiny s.
        return if s > 0.0 { w * (theta / s) } else { Vec3::ZERO };
    }
    // θ > π/2: axis from the symmetric part, sign from the skew part.
    let m = &r.m;
    let diag = [m[0][0] - c, m[1][1] - c, m[2][2] - c];
    let k = if diag[0] >= diag[1] && diag[0] >= diag[2] {
        0
    } else if diag[1] >= diag[2] {
        1
    } else {
        2
    };
    let mut col = Vec3::new(
        0.5 * (m[0][k] + m[k][0]),
        0.5 * (m[1][k] + m[k][1]),
        0.5 * (m[2][k] + m[k][2]),
    );
    // The diagonal entry of the column carries −cos θ from the identity part.
    match k {
        0 => col.x -= c,
        1 => col.y -= c,
        _ => col.z -= c,
    }
    let mut n = col * (1.0 / col.norm());
    if n.dot(w) < 0.0 {
        n = -n;
    }
    n * theta
}

/// The coefficient `(θ − sin θ)/θ³` of `hat²` in the Jacobians of `exp`.
#[cfg(test)]
fn jacobian_b(theta: f64) -> f64 {
    coefficients(theta * theta).2
}

/// The coefficient `1/θ² − (1 + cos θ)/(2 θ sin θ)` of `hat²` in the inverse Jacobians.
#[inline]
fn jacobian_inv_c(theta: f64) -> f64 {
    if theta < JAC_SERIES_ANGLE {
        let t2 = theta * theta;
        1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30_240.0 + t2 * t2 * t2 / 1_209_600.0 + t2 * t2 * t2 * t2 / 47_900_160.0
    } else {
        let (s, co) = theta.sin_cos();
        1.0 / (theta * theta) - (1.0 + co) / (2.0 * theta * s)
    }
}

/// Right Jacobian of `exp`: `Jr(v) = I − ((1 − cos θ)/θ²) hat(v) + ((θ − sin θ)/θ³) hat(v)²`.
/// Then `exp(v + δ) = exp(v) exp(Jr(v) δ) + O(δ²)`.
#[must_use]
pub fn right_jacobian(v: Vec3) -> Mat3 {
    let (_, a, b) = coefficients(v.norm_squared());
    i_plus_hat_plus_hat2(v, -a, b)
}

/// Left Jacobian of `exp`: `Jl(v) = Jr(−v)`, with `exp(v + δ) = exp(Jl(v) δ) exp(v) + O(δ²)`.
#[must_use]
pub fn left_jacobian(v: Vec3) -> Mat3 {
    right_jacobian(-v)
}

/// Inverse of the right Jacobian:
/// `Jr⁻¹(v) = I + ½ hat(v) + (1/θ² − (1 + cos θ)/(2θ sin θ)) hat(v)²`, for `|v| < 2π`.
#[must_use]
pub fn right_jacobian_inverse(v: Vec3) -> Mat3 {
    let theta = v.norm();
    i_plus_hat_plus_hat2(v, 0.5, jacobian_inv_c(theta))
}

/// `Jr⁻¹(v) x = x + ½ v × x + c(θ) v × (v × x)` without forming the matrix.
#[must_use]
#[inline]
pub fn right_jacobian_inverse_apply(v: Vec3, x: Vec3) -> Vec3 {
    let c = jacobian_inv_c(v.norm());
    let vx = v.cross(x);
    x + vx * 0.5 + v.cross(vx) * c
}

/// Inverse of the left Jacobian, `Jl⁻¹(v) = Jr⁻¹(−v)`, for `|v| < 2π`.
#[must_use]
pub fn left_jacobian_inverse(v: Vec3) -> Mat3 {
    right_jacobian_inverse(-v)
}

/// The Cayley map `cay(ξ) = I + 4/(4 + |ξ|²) (hat ξ + hat(ξ)²/2)`, a rotation that agrees
/// with `exp(ξ)` to second order.
#[must_use]
pub fn cayley(xi: Vec3) -> Mat3 {
    let f = 4.0 / (4.0 + xi.norm_squared());
    i_plus_hat_plus_hat2(xi, f, 0.5 * f)
}

/// The orthogonality defect `‖RᵀR − I‖_F`.
#[must_use]
pub fn orthogonality_defect(r: &Mat3) -> f64 {
    (r.transpose() * *r - Mat3::IDENTITY).norm_frobenius()
}

/// The nearest rotation to `R` in the Frobenius norm (its polar factor), by the Newton
/// iteration `X ← ½ (X + X⁻ᵀ)`, which converges quadratically. `None` when `R` is singular,
/// not finite, or has a negative determinant (it is then no perturbed rotation).
#[must_use]
pub fn orthonormalize(r: &Mat3) -> Option<Mat3> {
    if !r.is_finite() || r.determinant() <= 0.0 {
        return None;
    }
    let mut x = *r;
    for _ in 0..60 {
        let next = (x + x.inverse()?.transpose()) * 0.5;
        let change = (next - x).max_abs();
        x = next;
        if change <= 4.0 * f64::EPSILON {
            break;
        }
    }
    Some(x)
}

/// A unit quaternion `w + x i + y j + z k`, scalar first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quaternion {
    /// Scalar part.
    pub w: f64,
    /// First vector component.
    pub x: f64,
    /// Second vector component.
    pub y: f64,
    /// Third vector component.
    pub z: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Quaternion::IDENTITY
    }
}

impl Quaternion {
    /// The identity rotation.
    pub const IDENTITY: Quaternion = Quaternion {
        w: 1.0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    /// A quaternion from its components, scalar first.
    #[must_use]
    pub const fn new(w: f64, x: f64, y: f64, z: f64) -> Self {
        Quaternion { w, x, y, z }
    }

    /// The vector part.
    #[must_use]
    pub fn vector(&self) -> Vec3 {
        Vec3::new(self.x, self.y, self.z)
    }

    /// Euclidean norm of the four components.
    #[must_use]
    pub fn norm(&self) -> f64 {
        (self.w * self.w + self.x * self.x + self.y * self.y + self.z * self.z).sqrt()
    }

    /// This quaternion scaled to unit norm.
    #[must_use]
    pub fn normalized(&self) -> Quaternion {
        let s = 1.0 / self.norm();
        Quaternion::new(self.w * s, self.x * s, self.y * s, self.z * s)
    }

    /// The Hamilton product `self ⊗ b`.
    #[must_use]
    #[inline]
    pub fn mul(&self, b: &Quaternion) -> Quaternion {
        let (a, u) = (self, b);
        Quaternion::new(
            a.w * u.w - a.x * u.x - a.y * u.y - a.z * u.z,
            a.w * u.x + a.x * u.w + a.y * u.z - a.z * u.y,
            a.w * u.y - a.x * u.z + a.y * u.w + a.z * u.x,
            a.w * u.z + a.x * u.y - a.y * u.x + a.z * u.w,
        )
    }

    /// The rotation matrix of a unit quaternion.
    #[must_use]
    #[inline]
    pub fn to_matrix(&self) -> Mat3 {
        let (w, x, y, z) = (self.w, self.x, self.y, self.z);
        Mat3::from_rows([
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ])
    }

    /// The unit quaternion of a rotation matrix (Shepperd's method: divide by the largest
    /// of the four candidate pivots), with non-negative scalar part.
    #[must_use]
    pub fn from_matrix(r: &Mat3) -> Quaternion {
        let m = &r.m;
        let tr = r.trace();
        let q = if tr >= m[0][0] && tr >= m[1][1] && tr >= m[2][2] {
            let s = 2.0 * (1.0 + tr).sqrt();
            Quaternion::new(
                0.25 * s,
                (m[2][1] - m[1][2]) / s,
                (m[0][2] - m[2][0]) / s,
                (m[1][0] - m[0][1]) / s,
            )
        } else if m[0][0] >= m[1][1] && m[0][0] >= m[2][2] {
            let s = 2.0 * (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt();
            Quaternion::new(
                (m[2][1] - m[1][2]) / s,
                0.25 * s,
                (m[0][1] + m[1][0]) / s,
                (m[0][2] + m[2][0]) / s,
            )
        } else if m[1][1] >= m[2][2] {
            let s = 2.0 * (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt();
            Quaternion::new(
                (m[0][2] - m[2][0]) / s,
                (m[0][1] + m[1][0]) / s,
                0.25 * s,
                (m[1][2] + m[2][1]) / s,
            )
        } else {
            let s = 2.0 * (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt();
            Quaternion::new(
                (m[1][0] - m[0][1]) / s,
                (m[0][2] + m[2][0]) / s,
                (m[1][2] + m[2][1]) / s,
                0.25 * s,
            )
        };
        let q = q.normalized();
        if q.w < 0.0 {
            Quaternion::new(-q.w, -q.x, -q.y, -q.z)
        } else {
            q
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The coefficients against independent references over `0 < θ < 4`: `sin θ / θ`,
    /// `2 sin²(θ/2) / θ²` and the Taylor series of `(θ − sin θ)/θ³` summed to 40 terms
    /// (alternating terms at most 3x the sum, so a few ulps), in every branch.
    #[test]
    fn coefficients_match_references_in_every_branch() {
        let mut worst = [0.0f64; 3];
        for i in 1..=4000 {
            let theta = 4.0 * f64::from(i) / 4000.0 * (1.0 - 1e-12);
            let t2 = theta * theta;
            let (a, b, c) = coefficients(t2);
            let a_ref = theta.sin() / theta;
            let b_ref = 2.0 * ((0.5 * theta).sin() / theta).powi(2);
            let mut c_ref = 0.0;
            for k in (0..40).rev() {
                let mut f = 1.0;
                for j in 2..=(2 * k + 3) {
                    f *= f64::from(j);
                }
                c_ref = c_ref * -t2 + 1.0 / f;
            }
            // `a` relative to its bound 1 (it vanishes at θ = π), `b` and `c` relative.
            for (w, (x, r, scale)) in worst
                .iter_mut()
                .zip([(a, a_ref, 1.0), (b, b_ref, b_ref), (c, c_ref, c_ref)])
            {
                *w = w.max((x - r).abs() / (scale * f64::EPSILON));
            }
        }
        // One doubling of about an ulp, plus the references' own rounding.
        eprintln!("worst errors in ulps: {worst:?}");
        assert!(worst.iter().all(|&w| w < 8.0), "worst errors in ulps: {worst:?}");
    }

    use crate::random::Rng;

    /// Increments from the half-angle coefficients of a nearby Newton iterate are as accurate
    /// as those evaluated at `Ψ` itself, over `|Ψ| ≤ π` and for last corrections up to `√u`
    /// (radians), against the references `sin θ/θ` and `2 sin²(θ/2)/θ²`: a few ulps, where
    /// leaving out the first-order terms would be off by up to about 1e-8.
    #[test]
    fn increments_from_half_angle_coefficients_are_accurate() {
        let mut rng = Rng::new(21);
        let (mut shared_worst, mut direct_worst) = ([0.0f64; 2], [0.0f64; 2]);
        for _ in 0..20_000 {
            let psi = random_vector(&mut rng, std::f64::consts::PI);
            let delta = rng.unit_vector() * (f64::EPSILON.sqrt() * rng.uniform());
            let v = (psi + delta) * -0.5;
            let t = v.norm_squared();
            let (a, b, c) = coefficients(t);
            let theta = psi.norm();
            let a_ref = theta.sin() / theta;
            let b_ref = 2.0 * ((0.5 * theta).sin() / theta).powi(2);
            for (worst, inc) in [
                (&mut shared_worst, Increment::from_half_angle(psi, [t, a, b, c])),
                (&mut direct_worst, Increment::new(psi)),
            ] {
                // `a` against its bound 1 (it vanishes at π), `b` relative.
                worst[0] = worst[0].max((inc.a - a_ref).abs() / f64::EPSILON);
                worst[1] = worst[1].max((inc.b - b_ref).abs() / (b_ref * f64::EPSILON));
            }
        }
        eprintln!("worst errors in ulps: shared {shared_worst:?}, direct {direct_worst:?}");
        assert!(shared_worst.iter().all(|&w| w < 6.0), "shared: {shared_worst:?}");
        // As accurate as the direct evaluation, to within an ulp.
        assert!(
            shared_worst.iter().zip(&direct_worst).all(|(s, d)| *s <= d + 1.0),
            "shared {shared_worst:?} vs direct {direct_worst:?}"
        );
    }

    fn random_vector(rng: &mut Rng, max_norm: f64) -> Vec3 {
        let d = rng.unit_vector();
        d * (max_norm * rng.uniform())
    }

    #[test]
    fn hat_vee_round_trip_and_cross_product() {
        let mut rng = Rng::new(1);
        for _ in 0..100 {
            let a = random_vector(&mut rng, 10.0);
            let b = random_vector(&mut rng, 10.0);
            assert_eq!(vee(&hat(a)), a);
            assert!((hat(a) * b - a.cross(b)).max_abs() <= 1e-13);
        }
    }

    #[test]
    fn exp_is_a_rotation_and_matches_taylor_near_zero() {
        let mut rng = Rng::new(2);
        for scale in [1e-12, 1e-8, 1e-4, 9e-3, 1.1e-2, 1.0, 3.0, 20.0] {
            for _ in 0..50 {
                let v = rng.unit_vector() * scale;
                let r = exp(v);
                assert!(orthogonality_defect(&r) < 4e-15, "scale {scale}");
                assert!((r.determinant() - 1.0).abs() < 4e-15);
                // exp(v) v = v: the axis is fixed.
                assert!((r * v - v).max_abs() <= 4e-16 * scale.max(1.0) * scale);
            }
        }
        // Second-order Taylor expansion at tiny angles, where it is exact to round-off.
        let v = Vec3::new(3e-6, -2e-6, 1e-6);
        let k = hat(v);
        assert!((exp_increment(v) - (k + k * k * 0.5)).max_abs() < 1e-17);
        let r = rng.rotation();
        assert!((rotate_right(&r, v) - r * exp(v)).max_abs() < 4e-16);
        let x = rng.unit_vector();
        assert!((exp_apply(v, x) - exp(v) * x).max_abs() < 4e-16);
        let w = rng.unit_vector() * 0.3;
        let inc = Increment::new(w);
        assert!((inc.rotate(&r) - r * exp(w)).max_abs() < 4e-16);
        assert!((inc.inverse_apply(x) - exp(-w) * x).max_abs() < 4e-16);
        let taylor = Mat3::IDENTITY + k + k * k * 0.5;
        assert!((exp(v) - taylor).max_abs() < 3e-16);
        assert_eq!(exp(Vec3::ZERO), Mat3::IDENTITY);
        // The series and the closed forms agree where they switch.
        let t = EXP_SERIES_ANGLE;
        let (a, b) = rodrigues_coefficients(t * (1.0 - 1e-15));
        let (a2, b2) = (t.sin() / t, 2.0 * (0.5 * t).sin().powi(2) / (t * t));
        assert!((a - a2).abs() < 4e-16 && (b - b2).abs() < 4e-16, "{a} {a2} {b} {b2}");
        let (a3, b3) = rodrigues_coefficients(t * (1.0 + 1e-15));
        // The closed form of (1 − cos θ)/θ² loses u/θ² ≈ 2e-14 relative at the switch; it
        // multiplies hat(v)², of size θ², so exp keeps a few ulps.
        assert!(
            (a3 - a2).abs() < 4e-16 && (b3 - b2).abs() < 2.5e-14,
            "{a3} {a2} {b3} {b2}"
        );
        let t = JAC_SERIES_ANGLE;
        let b_direct = (t - t.sin()) / (t * t * t);
        let c_direct = 1.0 / (t * t) - (1.0 + t.cos()) / (2.0 * t * t.sin());
        assert!((jacobian_b(t * (1.0 - 1e-15)) - b_direct).abs() < 1e-14);
        assert!((jacobian_inv_c(t * (1.0 - 1e-15)) - c_direct).abs() < 1e-13);
    }

    #[test]
    fn log_inverts_exp_over_the_whole_ball() {
        let mut rng = Rng::new(3);
        let pi = std::f64::consts::PI;
        let mut worst: f64 = 0.0;
        for norm in [
            0.0,
            1e-300,
            1e-12,
            1e-9,
            3e-8,
            1e-5,
            0.3,
            1.0,
            pi / 2.0,
            2.0,
            3.0,
            pi - 1e-6,
            pi - 1e-7,
            pi - 1e-9,
        ] {
            for _ in 0..200 {
                let v = rng.unit_vector() * norm;
                let back = log(&exp(v));
                let err = (back - v).norm() / norm.max(1.0);
                worst = worst.max(err);
                assert!(err < 1e-14, "|v| = {norm}: log(exp(v)) - v = {err:e}");
            }
        }
        for _ in 0..2000 {
            let v = random_vector(&mut rng, pi);
            let err = (log(&exp(v)) - v).norm();
            worst = worst.max(err);
            assert!(err < 1e-14, "|v| = {}: err {err:e}", v.norm());
        }
        assert!(worst < 1e-14);
        // Exactly π: either sign of the axis is a valid logarithm.
        let v = Vec3::new(0.0, 0.0, pi);
        let l = log(&exp(v));
        assert!((l.norm() - pi).abs() < 1e-15 && (l.z.abs() - pi).abs() < 1e-15);
    }

    #[test]
    fn exp_inverts_log_for_random_rotations() {
        let mut rng = Rng::new(4);
        for _ in 0..2000 {
            let r = rng.rotation();
            let back = exp(log(&r));
            assert!((back - r).max_abs() < 2e-15);
            assert!(log(&r).norm() <= std::f64::consts::PI + 1e-15);
        }
    }

    fn central_difference_jacobian(f: impl Fn(Vec3) -> Vec3, at: Vec3, eps: f64) -> Mat3 {
        let mut j = Mat3::ZERO;
        for k in 0..3 {
            let mut e = [0.0; 3];
            e[k] = eps;
            let d = (f(at + Vec3::from_array(e)) - f(at - Vec3::from_array(e))) * (0.5 / eps);
            j.m[0][k] = d.x;
            j.m[1][k] = d.y;
            j.m[2][k] = d.z;
        }
        j
    }

    #[test]
    fn inverse_jacobian_applied_equals_the_matrix_times_the_vector() {
        let mut rng = crate::random::Rng::new(3);
        for scale in [1e-9, 1e-3, 0.3, 2.5] {
            let v = rng.unit_vector() * scale;
            let x = rng.unit_vector();
            let d = right_jacobian_inverse_apply(v, x) - right_jacobian_inverse(v) * x;
            assert!(d.norm() < 4.0 * f64::EPSILON, "{scale}: {d:?}");
        }
    }

    #[test]
    fn jacobians_match_central_differences() {
        let mut rng = Rng::new(5);
        for scale in [1e-6, 0.05, 0.099, 0.101, 1.0, 2.5, 3.1] {
            for _ in 0..30 {
                let v = rng.unit_vector() * scale;
                let r = exp(v);
                // Right Jacobian: log(exp(v)ᵀ exp(v + δ)) = Jr(v) δ.
                let fd_r = central_difference_jacobian(|x| log(&(r.transpose() * exp(x))), v, 1e-6);
                let fd_l = central_difference_jacobian(|x| log(&(exp(x) * r.transpose())), v, 1e-6);
                // Central differences: truncation O(ε²) and round-off O(u/ε).
                assert!((right_jacobian(v) - fd_r).max_abs() < 1e-9, "Jr, |v| = {scale}");
                assert!((left_jacobian(v) - fd_l).max_abs() < 1e-9, "Jl, |v| = {scale}");
                let e1 = (right_jacobian(v) * right_jacobian_inverse(v) - Mat3::IDENTITY).max_abs();
                let e2 = (left_jacobian(v) * left_jacobian_inverse(v) - Mat3::IDENTITY).max_abs();
                assert!(
                    e1 < 1e-14 && e2 < 1e-14,
                    "inverse Jacobians at |v| = {scale}: {e1:e} {e2:e}"
                );
            }
        }
    }

    #[test]
    fn cayley_is_a_rotation_close_to_exp() {
        let mut rng = Rng::new(6);
        for _ in 0..100 {
            let xi = random_vector(&mut rng, 5.0);
            let c = cayley(xi);
            assert!(orthogonality_defect(&c) < 1e-14);
            assert!((c.determinant() - 1.0).abs() < 1e-14);
        }
        // cay(ξ) − exp(ξ) = O(|ξ|³).
        let d = rng.unit_vector();
        let e1 = (cayley(d * 1e-2) - exp(d * 1e-2)).max_abs();
        let e2 = (cayley(d * 5e-3) - exp(d * 5e-3)).max_abs();
        let order = (e1 / e2).log2();
        assert!((order - 3.0).abs() < 0.05, "cay - exp order {order}");
    }

    #[test]
    fn quaternion_round_trips() {
        let mut rng = Rng::new(7);
        for _ in 0..2000 {
            let r = rng.rotation();
            let q = Quaternion::from_matrix(&r);
            assert!((q.norm() - 1.0).abs() < 1e-15);
            assert!((q.to_matrix() - r).max_abs() < 2e-15);
        }
        // Rotations by π about each axis exercise the non-trace branches.
        for axis in [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ] {
            let r = exp(axis * std::f64::consts::PI);
            assert!((Quaternion::from_matrix(&r).to_matrix() - r).max_abs() < 1e-15);
        }
        // Composition: q1 ⊗ q2 represents R1 R2.
        let (r1, r2) = (rng.rotation(), rng.rotation());
        let q = Quaternion::from_matrix(&r1).mul(&Quaternion::from_matrix(&r2));
        assert!((q.to_matrix() - r1 * r2).max_abs() < 2e-15);
    }

    #[test]
    fn orthonormalize_restores_a_perturbed_rotation() {
        let mut rng = Rng::new(8);
        for _ in 0..100 {
            let r = rng.rotation();
            let mut p = r;
            for row in p.m.iter_mut() {
                for v in row.iter_mut() {
                    *v += 1e-6 * (rng.uniform() - 0.5);
                }
            }
            let q = orthonormalize(&p).unwrap();
            assert!(orthogonality_defect(&q) < 1e-15);
            assert!((q - r).max_abs() < 2e-6);
        }
        let reflection = Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0));
        assert!(orthonormalize(&reflection).is_none());
        assert!(orthonormalize(&Mat3::ZERO).is_none());
    }
}
