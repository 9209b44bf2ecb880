//! The splitting's per-bond work written once, generic over a lane type (the kernels);
//! `avx.rs` runs them on four bonds at a time in AVX lanes where the processor has AVX.
//!
//! [`bond_flow`], [`site_flow`] and [`unit()`] are the exact bond flow, the on-site flow (when
//! anisotropy and field commute) and the renormalisation, on [`V`] vectors of any lane type:
//! `f64` for the scalar path, and four `f64` in one AVX register (`avx.rs`). Both
//! perform the same IEEE operations in the same order (no FMA contraction), so a bond gives
//! the same bits in a lane as alone. A lane group whose rotation angles leave the range of
//! the inline series (`θ ≥ 1`) is redone on the
//! scalar path, which has the longer branches; so is a sweep with non-commuting on-site
//! terms. A sweep in lanes gathers each bond's two spins (24 scalar loads per four bonds),
//! applies all its pieces in registers and scatters them back.
//!
//! Reference: R. I. McLachlan, K. Modin, O. Verdier, *Symplectic integrators for spin
//! systems*, Phys. Rev. E 89 (2014) (the bond flow); operation counts and timings in
//! `docs/spins.md`.

use std::ops::{Add, Div, Mul, Sub};

use crate::linalg::Vec3;
use crate::so3::reciprocal_factorials;

/// What a lane value needs: the four operations the flows use, and splatting constants.
pub(crate) trait Lane: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + From<f64> {}
impl<T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T> + From<f64>> Lane for T {}

/// A lane value with the correctly rounded division and square root (the same bits in
/// every lane as on `f64`), for the damped flows.
pub(crate) trait Real: Lane + Div<Output = Self> {
    fn sqrt(self) -> Self;
}

impl Real for f64 {
    #[inline(always)]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
}

/// A 3-vector of lanes, with the operations of [`Vec3`] in the same order.
#[derive(Clone, Copy)]
pub(crate) struct V<T> {
    pub x: T,
    pub y: T,
    pub z: T,
}

impl<T: Lane> V<T> {
    #[inline(always)]
    pub(crate) fn add(self, b: Self) -> Self {
        V {
            x: self.x + b.x,
            y: self.y + b.y,
            z: self.z + b.z,
        }
    }
    #[inline(always)]
    pub(crate) fn sub(self, b: Self) -> Self {
        V {
            x: self.x - b.x,
            y: self.y - b.y,
            z: self.z - b.z,
        }
    }
    #[inline(always)]
    pub(crate) fn scale(self, s: T) -> Self {
        V {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    pub(crate) fn dot(self, b: Self) -> T {
        self.x * b.x + self.y * b.y + self.z * b.z
    }
    #[inline(always)]
    pub(crate) fn cross(self, b: Self) -> Self {
        V {
            x: self.y * b.z - self.z * b.y,
            y: self.z * b.x - self.x * b.z,
            z: self.x * b.y - self.y * b.x,
        }
    }
}

impl From<Vec3> for V<f64> {
    #[inline(always)]
    fn from(v: Vec3) -> Self {
        V { x: v.x, y: v.y, z: v.z }
    }
}

impl From<V<f64>> for Vec3 {
    #[inline(always)]
    fn from(v: V<f64>) -> Self {
        Vec3::new(v.x, v.y, v.z)
    }
}

/// `(sin θ/θ, cos θ)` from `t = θ²` by their Taylor series, `Σ_{k≤9} (−t)ᵏ/(2k+1)!` and
/// `Σ_{k≤10} (−t)ᵏ/(2k)!`, for `t < 1` (first omitted terms `t¹⁰/21!` and `t¹¹/22!`, below
/// `2e-20` and `1e-21`), by Estrin's scheme: 41 operations, no call, no division.
#[inline(always)]
pub(crate) fn sinc_cos_series<T: Lane>(t: T) -> (T, T) {
    let k = T::from;
    let (t2, t4) = (t * t, (t * t) * (t * t));
    let t8 = t4 * t4;
    let f = &SINC;
    let sinc = ((k(f[0]) - t * k(f[1])) + t2 * (k(f[2]) - t * k(f[3])))
        + t4 * ((k(f[4]) - t * k(f[5])) + t2 * (k(f[6]) - t * k(f[7])))
        + t8 * (k(f[8]) - t * k(f[9]));
    let g = &COS;
    let cos = ((k(g[0]) - t * k(g[1])) + t2 * (k(g[2]) - t * k(g[3])))
        + t4 * ((k(g[4]) - t * k(g[5])) + t2 * (k(g[6]) - t * k(g[7])))
        + t8 * ((k(g[8]) - t * k(g[9])) + t2 * k(g[10]));
    (sinc, cos)
}

/// Rodrigues' `(sin θ/θ, (1 − cos θ)/θ²)` from `t = θ²` by their Taylor series,
/// `Σ_{k≤9} (−t)ᵏ/(2k+1)!` and `Σ_{k≤9} (−t)ᵏ/(2k+2)!`, for `t < 1` (first omitted terms
/// below `2e-20`), by Estrin's scheme.
#[inline(always)]
pub(crate) fn rodrigues_series<T: Lane>(t: T) -> (T, T) {
    (series10(t, &SINC), series10(t, &VERSIN))
}

/// `Σ_{k<10} (−t)ᵏ f[k]` by Estrin's scheme.
#[inline(always)]
fn series10<T: Lane>(t: T, f: &[f64; 10]) -> T {
    let k = T::from;
    let (t2, t4) = (t * t, (t * t) * (t * t));
    let t8 = t4 * t4;
    ((k(f[0]) - t * k(f[1])) + t2 * (k(f[2]) - t * k(f[3])))
        + t4 * ((k(f[4]) - t * k(f[5])) + t2 * (k(f[6]) - t * k(f[7])))
        + t8 * (k(f[8]) - t * k(f[9]))
}

/// Where [`sinc_cos_series`] and [`rodrigues_series`] hold: `θ² < 1`.
pub(crate) const SERIES_LIMIT: f64 = 1.0;

/// `(sin θ/θ, cos θ)` from `t = θ²` on the scalar path: the inline series below `θ = 1`,
/// one `sin_cos` beyond (no cancellation there).
#[inline(always)]
pub(crate) fn sinc_cos(t: f64) -> (f64, f64) {
    if t < SERIES_LIMIT {
        sinc_cos_series(t)
    } else {
        sinc_cos_closed(t)
    }
}

#[inline(never)]
fn sinc_cos_closed(t: f64) -> (f64, f64) {
    let theta = t.sqrt();
    let (s, c) = theta.sin_cos();
    (s / theta, c)
}

/// `1/(2k+1)!` and `1/(2k)!` ([`crate::so3::reciprocal_factorials`]).
const SINC: [f64; 10] = reciprocal_factorials::<10>(1);
const COS: [f64; 11] = reciprocal_factorials::<11>(0);
/// `1/(2k+2)!`.
const VERSIN: [f64; 10] = reciprocal_factorials::<10>(2);

/// The exact flow of one bond over a time whose `rate · time` is `ch` (`rate = γJ/(μ_s
/// μ_B)`): both spins turn about `L = S_i + S_j` by `θ = ch |L|`. Written with the half
/// difference `d = (S_i − S_j)/2`, perpendicular to `L` (`|S_i| = |S_j|`), which turns
/// while `L` stays:
///
/// ```text
/// d' = cos θ d + ch (sin θ/θ) (L × d),   S_i' = L/2 + d',   S_j' = L/2 − d'
/// ```
///
/// one cross product and one `(sin θ/θ, cos θ)` pair from `θ²` (`coefficients`; 41
/// operations by [`sinc_cos_series`]), 44 operations besides it: 85 per bond. The two
/// Rodrigues rotations this replaces took four cross products and 90 operations (with a
/// shorter series valid only to `θ = 0.1`, and a call beyond). `S_i + S_j` is kept to
/// rounding by construction.
#[inline(always)]
pub(crate) fn bond_flow<T: Lane>(ch: T, si: V<T>, sj: V<T>, mut coefficients: impl FnMut(T) -> (T, T)) -> (V<T>, V<T>) {
    let l = si.add(sj);
    let d = si.sub(sj).scale(T::from(0.5));
    let (sinc, cos) = coefficients(ch * ch * l.dot(l));
    let half = l.scale(T::from(0.5));
    let turned = d.scale(cos).add(l.cross(d).scale(ch * sinc));
    (half.add(turned), half.sub(turned))
}

/// The exact on-site flow over `h` when anisotropy and field commute: one rotation by
/// `v = (k (S·n) n + γB) h` (`S·n` is constant), Rodrigues' `(a, b)` of `|v|²` from
/// `coefficients`: `S' = S + a v × S + b v × (v × S)`; 50 operations besides the
/// coefficients (39 by [`rodrigues_series`]).
#[inline(always)]
pub(crate) fn site_flow<T: Lane>(
    axis: V<T>,
    k: T,
    field: V<T>,
    h: T,
    s: V<T>,
    mut coefficients: impl FnMut(T) -> (T, T),
) -> V<T> {
    let v = axis.scale(k * s.dot(axis)).add(field).scale(h);
    let (a, b) = coefficients(v.dot(v));
    let vx = v.cross(s);
    s.add(vx.scale(a)).add(v.cross(vx).scale(b))
}

/// Where [`asinh_ratio_series`] holds: `x² < 0.01`.
pub(crate) const ASINH_LIMIT: f64 = 0.01;

/// `asinh(x)/x` from `x²` by its series to `x¹⁴` (for `x² < 0.01` the first omitted term
/// is below `1.2e-18`), by Estrin's scheme.
#[inline(always)]
pub(crate) fn asinh_ratio_series<T: Lane>(x2: T) -> T {
    const C: [f64; 8] = [
        1.0,
        -1.0 / 6.0,
        3.0 / 40.0,
        -5.0 / 112.0,
        35.0 / 1152.0,
        -63.0 / 2816.0,
        231.0 / 13312.0,
        -143.0 / 10240.0,
    ];
    let k = T::from;
    let (x4, x8) = (x2 * x2, (x2 * x2) * (x2 * x2));
    ((k(C[0]) + x2 * k(C[1])) + x4 * (k(C[2]) + x2 * k(C[3])))
        + x8 * ((k(C[4]) + x2 * k(C[5])) + x4 * (k(C[6]) + x2 * k(C[7])))
}

/// `asinh(x)/x` from `x²` on the scalar path: the series below `x² = 0.01`, `asinh`
/// itself beyond.
#[inline(always)]
pub(crate) fn asinh_ratio(x2: f64) -> f64 {
    if x2 < ASINH_LIMIT {
        asinh_ratio_series(x2)
    } else {
        asinh_ratio_closed(x2)
    }
}

#[inline(never)]
fn asinh_ratio_closed(x2: f64) -> f64 {
    let x = x2.sqrt();
    x.asinh() / x
}

/// Where [`asinh_ratio_short`] holds: `x² < 1e-4`.
pub(crate) const ASINH_SHORT_LIMIT: f64 = 1e-4;

/// `asinh(x)/x` from `x²` by its series to `x⁶` (for `x² < 1e-4` the first omitted term
/// is below `3.1e-18`): 7 operations. The damped flows use it for a whole sweep when a
/// bound on the sweep's `x²` (from the step's constants) is below [`ASINH_SHORT_LIMIT`].
#[inline(always)]
pub(crate) fn asinh_ratio_short<T: Lane>(x2: T) -> T {
    let k = T::from;
    let x4 = x2 * x2;
    (k(1.0) + x2 * k(-1.0 / 6.0)) + x4 * (k(3.0 / 40.0) + x2 * k(-5.0 / 112.0))
}

/// The exact damped flow of one bond (`spin::damped`): `e = e^δ`, `e2 = e^{2δ}`,
/// `big_e = expm1(2δ)/α`, `alpha2 = α²`; `ratio` gives `asinh(x)/x` from `x²` and
/// `coefficients` `(sin θ/θ, cos θ)` from `θ²`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn damped_bond_flow<T: Real>(
    e: T,
    e2: T,
    big_e: T,
    alpha2: T,
    si: V<T>,
    sj: V<T>,
    mut ratio: impl FnMut(T) -> T,
    mut coefficients: impl FnMut(T) -> (T, T),
) -> (V<T>, V<T>) {
    const SQRT_2: f64 = std::f64::consts::SQRT_2;
    let l = si.add(sj);
    let d = si.sub(sj).scale(T::from(0.5));
    // `p = |L|²/2` and `q = 2|d|²` from the vectors themselves (not `1 ± S_i·S_j`): then
    // `|S_i'|² = (e² p + q)/W²` is 1 to round-off for spins off the sphere by round-off.
    let p = T::from(0.5) * l.dot(l);
    let q = T::from(2.0) * d.dot(d);
    let w = (q + p * e2).sqrt();
    // One division for `1/(√2 e + w)` and `1/w`.
    let m = T::from(SQRT_2) * e + w;
    let r = T::from(1.0) / (w * m);
    let base = big_e * (w * r);
    let g = base * ratio(alpha2 * p * base * base);
    let (sinc, cos) = coefficients(p * g * g);
    let inv_w = m * r;
    let half = l.scale(e * inv_w * T::from(0.5 * SQRT_2));
    // `(√2/W) [cos Φ d + (sinc Φ G/√2) L × d]` with the factors folded.
    let turned = d
        .scale(cos * (T::from(SQRT_2) * inv_w))
        .add(l.cross(d).scale(sinc * g * inv_w));
    (half.add(turned), half.sub(turned))
}

/// The exact damped Zeeman flow: the rotation `v` (Rodrigues' `(a, b)`), `unit = B̂`,
/// `tau = tanh(c_B α h)`, `sech = sech(c_B α h)`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn damped_zeeman_flow<T: Real>(v: V<T>, a: T, b: T, unit: V<T>, tau: T, sech: T, s: V<T>) -> V<T> {
    let c0 = s.dot(unit);
    let inv = T::from(1.0) / (T::from(1.0) + c0 * tau);
    let ratio = sech * inv;
    let vx = v.cross(s);
    let turned = s.add(vx.scale(a)).add(v.cross(vx).scale(b));
    turned.scale(ratio).add(unit.scale((c0 + tau) * inv - ratio * c0))
}

/// The exact damped anisotropy flow: `eg = e^g`, `e2g = e^{2g}`, `expm1g = expm1(g)`,
/// `f = expm1(2g)/α`; `ratio` and `coefficients` (Rodrigues' pair from `Φ²`) as above.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn damped_anisotropy_flow<T: Real>(
    axis: V<T>,
    eg: T,
    e2g: T,
    expm1g: T,
    f: T,
    alpha2: T,
    s: V<T>,
    mut ratio: impl FnMut(T) -> T,
    mut coefficients: impl FnMut(T) -> (T, T),
) -> V<T> {
    let w0 = s.dot(axis);
    let s02 = s.dot(s) - w0 * w0;
    let v = (s02 + w0 * w0 * e2g).sqrt();
    // One division for `1/(e^g + V)` and `1/V`.
    let m = eg + v;
    let r = T::from(1.0) / (v * m);
    let base = w0 * f * (v * r);
    let phi = base * ratio(alpha2 * base * base);
    let rot = axis.scale(phi);
    let (a, b) = coefficients(phi * phi);
    let vx = rot.cross(s);
    let turned = s.add(vx.scale(a)).add(rot.cross(vx).scale(b));
    turned.add(axis.scale(w0 * expm1g)).scale(m * r)
}

/// `(sin θ/θ, cos θ)` from `t = θ²` by the first 5 and 6 terms of their series, for
/// `t < 0.009` (first omitted terms `t⁵/11!` and `t⁶/12!`, below `2e-18` and `2e-21`): the
/// small rotations of a DMI bond's Ising part.
#[inline(always)]
pub(crate) fn sinc_cos_short<T: Lane>(t: T) -> (T, T) {
    let k = T::from;
    let t2 = t * t;
    let f = &SINC;
    let g = &COS;
    let sinc = (k(f[0]) - t * k(f[1])) + t2 * ((k(f[2]) - t * k(f[3])) + t2 * k(f[4]));
    let cos = (k(g[0]) - t * k(g[1])) + t2 * ((k(g[2]) - t * k(g[3])) + t2 * (k(g[4]) - t * k(g[5])));
    (sinc, cos)
}

/// Where [`sinc_cos_short`] holds: `θ² < 0.009`.
pub(crate) const SHORT_LIMIT: f64 = 0.009;

/// `s (3 − |s|²)/2`: one Newton step towards `|s| = 1`.
#[inline(always)]
pub(crate) fn unit<T: Lane>(s: V<T>) -> V<T> {
    s.scale(T::from(1.5) - T::from(0.5) * s.dot(s))
}
