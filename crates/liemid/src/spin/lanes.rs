//! The splitting's per-bond work written once, generic over a lane type, and run on four
//! bonds at a time in AVX lanes where the processor has AVX.
//!
//! [`bond_flow`], [`site_flow`] and [`unit()`] are the exact bond flow, the on-site flow (when
//! anisotropy and field commute) and the renormalisation, on [`V`] vectors of any lane type:
//! `f64` for the scalar path, and four `f64` in one AVX register ([`sweep_avx`]). Both
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

/// `1/(2k+1)!` and `1/(2k)!`.
const SINC: [f64; 10] = reciprocal_factorials::<10>(1);
const COS: [f64; 11] = reciprocal_factorials::<11>(0);
/// `1/(2k+2)!`.
const VERSIN: [f64; 10] = reciprocal_factorials::<10>(2);

const fn reciprocal_factorials<const N: usize>(offset: u32) -> [f64; N] {
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

#[cfg(all(feature = "simd", target_arch = "x86_64"))]
pub(crate) use avx::{sweep_avx, sweep_avx_damped, sweep_avx_dmi, use_avx};

#[cfg(all(feature = "simd", target_arch = "x86_64"))]
mod avx {
    use std::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_cmp_pd, _mm256_div_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_set1_pd,
        _mm256_set_pd, _mm256_sqrt_pd, _mm256_storeu_pd, _mm256_sub_pd, _CMP_LT_OQ,
    };
    use std::ops::{Add, Div, Mul, Sub};

    use super::{
        asinh_ratio_series, asinh_ratio_short, bond_flow, damped_anisotropy_flow, damped_bond_flow, damped_zeeman_flow,
        rodrigues_series, sinc_cos_series, sinc_cos_short, site_flow, unit, Real, ASINH_LIMIT, SERIES_LIMIT, V,
    };
    use crate::linalg::Vec3;
    use crate::spin::damped::SiteStep;
    use crate::spin::dmi::{coordinate_axis, dmi_bond_flow, AnyAxis, CoordinateAxis, DmiStep, TurnAxis};
    use crate::spin::splitting::{DampedPiece, Kernel, Piece};

    // SAFETY (every `unsafe` block in this module): the AVX intrinsics are reached only
    // from `sweep_avx`, which is `#[target_feature(enable = "avx")]` and called only after
    // `use_avx` detected AVX; the helpers are `#[inline(always)]`, so they are compiled
    // inside it.

    /// Four `f64`, one per bond, in one AVX register.
    #[derive(Clone, Copy)]
    struct F(__m256d);

    impl From<f64> for F {
        #[inline(always)]
        fn from(x: f64) -> F {
            F(unsafe { _mm256_set1_pd(x) })
        }
    }
    impl Add for F {
        type Output = F;
        #[inline(always)]
        fn add(self, b: F) -> F {
            F(unsafe { _mm256_add_pd(self.0, b.0) })
        }
    }
    impl Sub for F {
        type Output = F;
        #[inline(always)]
        fn sub(self, b: F) -> F {
            F(unsafe { _mm256_sub_pd(self.0, b.0) })
        }
    }
    impl Mul for F {
        type Output = F;
        #[inline(always)]
        fn mul(self, b: F) -> F {
            F(unsafe { _mm256_mul_pd(self.0, b.0) })
        }
    }
    impl Div for F {
        type Output = F;
        #[inline(always)]
        fn div(self, b: F) -> F {
            F(unsafe { _mm256_div_pd(self.0, b.0) })
        }
    }
    impl Real for F {
        #[inline(always)]
        fn sqrt(self) -> F {
            F(unsafe { _mm256_sqrt_pd(self.0) })
        }
    }
    impl F {
        /// Whether every lane is below `limit`.
        #[inline(always)]
        fn all_below(self, limit: f64) -> bool {
            unsafe { _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(self.0, _mm256_set1_pd(limit))) == 0b1111 }
        }
        #[inline(always)]
        fn to_array(self) -> [f64; 4] {
            let mut x = [0.0; 4];
            unsafe { _mm256_storeu_pd(x.as_mut_ptr(), self.0) };
            x
        }
    }

    /// Four spins, one per lane.
    #[inline(always)]
    fn gather(s: [Vec3; 4]) -> V<F> {
        unsafe {
            V {
                x: F(_mm256_set_pd(s[3].x, s[2].x, s[1].x, s[0].x)),
                y: F(_mm256_set_pd(s[3].y, s[2].y, s[1].y, s[0].y)),
                z: F(_mm256_set_pd(s[3].z, s[2].z, s[1].z, s[0].z)),
            }
        }
    }

    #[inline(always)]
    fn scatter(v: V<F>) -> [Vec3; 4] {
        let (x, y, z) = (v.x.to_array(), v.y.to_array(), v.z.to_array());
        std::array::from_fn(|k| Vec3::new(x[k], y[k], z[k]))
    }

    /// Whether [`sweep_avx`] can run here (cached by the standard library).
    #[inline]
    pub(crate) fn use_avx() -> bool {
        std::is_x86_feature_detected!("avx")
    }

    /// The pieces applied to four bonds' spins in lanes; `None` when a lane needs the
    /// scalar path's longer branches.
    #[target_feature(enable = "avx")]
    #[inline]
    fn group(kernel: &Kernel, pieces: &[Piece], si: [Vec3; 4], sj: [Vec3; 4]) -> Option<([Vec3; 4], [Vec3; 4])> {
        let (mut a, mut b) = (gather(si), gather(sj));
        let (mut site_ok, mut bond_ok) = (true, true);
        let axis = V {
            x: F::from(kernel.axis.x),
            y: F::from(kernel.axis.y),
            z: F::from(kernel.axis.z),
        };
        let field = V {
            x: F::from(kernel.field.x),
            y: F::from(kernel.field.y),
            z: F::from(kernel.field.z),
        };
        let k = F::from(kernel.anisotropy);
        let mut site = |t2: F| {
            site_ok &= t2.all_below(SERIES_LIMIT);
            rodrigues_series(t2)
        };
        for p in pieces {
            match *p {
                Piece::Site(t) if kernel.onsite_terms => {
                    a = site_flow(axis, k, field, F::from(t), a, &mut site);
                    b = site_flow(axis, k, field, F::from(t), b, &mut site);
                }
                Piece::Site(_) => {}
                Piece::Bond(t) => {
                    (a, b) = bond_flow(F::from(kernel.rate * t), a, b, |t2: F| {
                        bond_ok &= t2.all_below(SERIES_LIMIT);
                        sinc_cos_series(t2)
                    });
                }
                Piece::Unit => (a, b) = (unit(a), unit(b)),
            }
        }
        (site_ok && bond_ok).then(|| (scatter(a), scatter(b)))
    }

    /// [`group`] for DMI bonds of one `|D|`: `steps[k]` holds the constants of piece `k`
    /// when it is a bond piece, `u` the four bonds' unit vectors.
    #[target_feature(enable = "avx")]
    #[inline]
    fn group_dmi<A: TurnAxis<F>>(
        kernel: &Kernel,
        pieces: &[Piece],
        steps: &[Option<DmiStep>],
        u: A,
        si: [Vec3; 4],
        sj: [Vec3; 4],
    ) -> Option<([Vec3; 4], [Vec3; 4])> {
        let (mut a, mut b) = (gather(si), gather(sj));
        let (mut site_ok, mut bond_ok) = (true, true);
        let (axis, field) = (splat(kernel.axis), splat(kernel.field));
        let k = F::from(kernel.anisotropy);
        let mut site = |t2: F| {
            site_ok &= t2.all_below(SERIES_LIMIT);
            rodrigues_series(t2)
        };
        for (n, p) in pieces.iter().enumerate() {
            match *p {
                Piece::Site(t) if kernel.onsite_terms => {
                    a = site_flow(axis, k, field, F::from(t), a, &mut site);
                    b = site_flow(axis, k, field, F::from(t), b, &mut site);
                }
                Piece::Site(_) => {}
                Piece::Bond(_) => {
                    let c = steps[n]?;
                    let mut ising_ok = true;
                    (a, b) = dmi_bond_flow(
                        u,
                        F::from(c.cos),
                        F::from(c.sin),
                        F::from(c.rho_h),
                        F::from(c.ising_half),
                        a,
                        b,
                        |t2: F| {
                            if c.short {
                                sinc_cos_short(t2)
                            } else {
                                ising_ok &= t2.all_below(SERIES_LIMIT);
                                sinc_cos_series(t2)
                            }
                        },
                        |t2: F| {
                            bond_ok &= t2.all_below(SERIES_LIMIT);
                            sinc_cos_series(t2)
                        },
                    );
                    bond_ok &= ising_ok;
                }
                Piece::Unit => (a, b) = (unit(a), unit(b)),
            }
        }
        (site_ok && bond_ok).then(|| (scatter(a), scatter(b)))
    }

    /// The loop every lane sweep shares: each group of four bonds gathered, `lanes(at, si,
    /// sj)` applied (`at` the group's first position in `bonds`), its result scattered back,
    /// or, where it gives `None`, each bond by `scalar(at, si, sj)`; the remainder by
    /// `scalar`.
    ///
    /// # Safety
    /// As for [`sweep_avx`].
    #[inline(always)]
    unsafe fn sweep_groups(
        spins: *mut Vec3,
        len: usize,
        bonds: &[[u32; 2]],
        lanes: impl Fn(usize, [Vec3; 4], [Vec3; 4]) -> Option<([Vec3; 4], [Vec3; 4])>,
        scalar: impl Fn(usize, Vec3, Vec3) -> (Vec3, Vec3),
    ) {
        let mut groups = bonds.chunks_exact(4);
        let mut at = 0;
        for g in &mut groups {
            let idx: [(usize, usize); 4] = std::array::from_fn(|k| (g[k][0] as usize, g[k][1] as usize));
            for &(i, j) in &idx {
                assert!(i < len && j < len && i != j);
            }
            // SAFETY: in bounds (checked), distinct within a bond, and the bonds of a
            // matching are disjoint and owned by this worker (the caller's contract).
            unsafe {
                let si = idx.map(|(i, _)| *spins.add(i));
                let sj = idx.map(|(_, j)| *spins.add(j));
                match lanes(at, si, sj) {
                    Some((a, b)) => {
                        for k in 0..4 {
                            *spins.add(idx[k].0) = a[k];
                            *spins.add(idx[k].1) = b[k];
                        }
                    }
                    None => {
                        for k in 0..4 {
                            let (a, b) = scalar(at + k, si[k], sj[k]);
                            *spins.add(idx[k].0) = a;
                            *spins.add(idx[k].1) = b;
                        }
                    }
                }
            }
            at += 4;
        }
        for b in groups.remainder() {
            let (i, j) = (b[0] as usize, b[1] as usize);
            assert!(i < len && j < len && i != j);
            // SAFETY: as above.
            unsafe {
                let (a, c) = scalar(at, *spins.add(i), *spins.add(j));
                *spins.add(i) = a;
                *spins.add(j) = c;
            }
            at += 1;
        }
    }

    /// [`sweep_avx`] for DMI bonds of one `|D|`: `units[k]` is the unit DMI vector of
    /// `bonds[k]`, which is bond `base + k` of the lattice (the index `scalar` takes).
    ///
    /// # Safety
    /// As for [`sweep_avx`]; `units` as long as `bonds`.
    #[target_feature(enable = "avx")]
    #[allow(clippy::too_many_arguments)]
    pub(crate) unsafe fn sweep_avx_dmi(
        spins: *mut Vec3,
        len: usize,
        bonds: &[[u32; 2]],
        base: usize,
        units: &[Vec3],
        kernel: &Kernel,
        pieces: &[Piece],
        steps: &[Option<DmiStep>],
        scalar: &impl Fn(usize, Vec3, Vec3) -> (Vec3, Vec3),
    ) {
        assert_eq!(units.len(), bonds.len());
        // SAFETY: the caller's contract, passed on.
        unsafe {
            sweep_groups(
                spins,
                len,
                bonds,
                |at, si, sj| {
                    let u: [Vec3; 4] = std::array::from_fn(|k| units[at + k]);
                    // One coordinate axis in all four lanes (signs may differ): the turns
                    // in its plane, as the scalar path takes them for such a bond.
                    let axes = u.map(coordinate_axis);
                    let shared = match axes {
                        [Some((k, _)), ..] if axes.iter().all(|a| matches!(a, Some((j, _)) if *j == k)) => Some(k),
                        _ => None,
                    };
                    let sign = || {
                        let s = axes.map(|a| a.map_or(1.0, |(_, s)| s));
                        F(_mm256_set_pd(s[3], s[2], s[1], s[0]))
                    };
                    match shared {
                        Some(0) => group_dmi(kernel, pieces, steps, CoordinateAxis::<0, F> { sign: sign() }, si, sj),
                        Some(1) => group_dmi(kernel, pieces, steps, CoordinateAxis::<1, F> { sign: sign() }, si, sj),
                        Some(_) => group_dmi(kernel, pieces, steps, CoordinateAxis::<2, F> { sign: sign() }, si, sj),
                        None => group_dmi(kernel, pieces, steps, AnyAxis(gather(u)), si, sj),
                    }
                },
                |at, si, sj| scalar(base + at, si, sj),
            )
        }
    }

    #[inline(always)]
    fn splat(v: Vec3) -> V<F> {
        V {
            x: F::from(v.x),
            y: F::from(v.y),
            z: F::from(v.z),
        }
    }

    /// The damped on-site flow of four spins (as `spin::damped::site`).
    #[target_feature(enable = "avx")]
    #[inline]
    fn damped_site(c: &SiteStep, s: V<F>, ok: &mut bool) -> V<F> {
        let zeeman = |s: V<F>| match &c.zeeman {
            Some(z) => damped_zeeman_flow(
                splat(z.v),
                F::from(z.a),
                F::from(z.b),
                splat(z.unit),
                F::from(z.tau),
                F::from(z.sech),
                s,
            ),
            None => s,
        };
        let s = if c.anisotropy.is_some() && c.zeeman.is_some() {
            zeeman(s)
        } else {
            s
        };
        let s = match &c.anisotropy {
            Some(k) => {
                let (mut ok_r, mut ok_s) = (true, true);
                let out = damped_anisotropy_flow(
                    splat(k.axis),
                    F::from(k.eg),
                    F::from(k.e2g),
                    F::from(k.expm1g),
                    F::from(k.f),
                    F::from(k.alpha2),
                    s,
                    |x2: F| {
                        if k.short {
                            return asinh_ratio_short(x2);
                        }
                        ok_r &= x2.all_below(ASINH_LIMIT);
                        asinh_ratio_series(x2)
                    },
                    |t2: F| {
                        ok_s &= t2.all_below(SERIES_LIMIT);
                        rodrigues_series(t2)
                    },
                );
                *ok &= ok_r && ok_s;
                out
            }
            None => s,
        };
        zeeman(s)
    }

    /// The damped pieces applied to four bonds' spins in lanes; `None` when a lane needs
    /// the scalar path's longer branches.
    #[target_feature(enable = "avx")]
    #[inline]
    fn group_damped(pieces: &[DampedPiece], si: [Vec3; 4], sj: [Vec3; 4]) -> Option<([Vec3; 4], [Vec3; 4])> {
        let (mut a, mut b) = (gather(si), gather(sj));
        let mut ok = true;
        for p in pieces {
            match p {
                DampedPiece::Site(c) => {
                    a = damped_site(c, a, &mut ok);
                    b = damped_site(c, b, &mut ok);
                }
                DampedPiece::Skip => {}
                DampedPiece::Bond(c) => {
                    let mut ok_r = true;
                    let mut ok_s = true;
                    (a, b) = damped_bond_flow(
                        F::from(c.e),
                        F::from(c.e2),
                        F::from(c.big_e),
                        F::from(c.alpha2),
                        a,
                        b,
                        |x2: F| {
                            if c.short {
                                return asinh_ratio_short(x2);
                            }
                            ok_r &= x2.all_below(ASINH_LIMIT);
                            asinh_ratio_series(x2)
                        },
                        |t2: F| {
                            ok_s &= t2.all_below(SERIES_LIMIT);
                            sinc_cos_series(t2)
                        },
                    );
                    ok &= ok_r && ok_s;
                }
                DampedPiece::Unit => (a, b) = (unit(a), unit(b)),
            }
        }
        ok.then(|| (scatter(a), scatter(b)))
    }

    /// [`sweep_avx`] for the damped pieces.
    ///
    /// # Safety
    /// As for [`sweep_avx`].
    #[target_feature(enable = "avx")]
    pub(crate) unsafe fn sweep_avx_damped(
        spins: *mut Vec3,
        len: usize,
        bonds: &[[u32; 2]],
        pieces: &[DampedPiece],
        scalar: &impl Fn(Vec3, Vec3) -> (Vec3, Vec3),
    ) {
        // SAFETY: the caller's contract, passed on.
        unsafe {
            sweep_groups(
                spins,
                len,
                bonds,
                |_, si, sj| group_damped(pieces, si, sj),
                |_, si, sj| scalar(si, sj),
            )
        }
    }

    /// `(s[i], s[j]) ← pieces(s[i], s[j])` for the bonds of a matching, four at a time in
    /// lanes, the rest (and any group a lane of which leaves the series' range) by
    /// `scalar`, which must be the same pieces on the scalar path. The on-site flows in
    /// lanes assume commuting anisotropy and field (the caller's choice).
    ///
    /// # Safety
    /// AVX must be available ([`use_avx`]); `spins` must point to `len` spins, every bond
    /// index must be below `len` with `i ≠ j`, and no other thread may touch these bonds'
    /// sites until the caller's next barrier.
    #[target_feature(enable = "avx")]
    pub(crate) unsafe fn sweep_avx(
        spins: *mut Vec3,
        len: usize,
        bonds: &[[u32; 2]],
        kernel: &Kernel,
        pieces: &[Piece],
        scalar: &impl Fn(Vec3, Vec3) -> (Vec3, Vec3),
    ) {
        // SAFETY: the caller's contract, passed on.
        unsafe {
            sweep_groups(
                spins,
                len,
                bonds,
                |_, si, sj| group(kernel, pieces, si, sj),
                |_, si, sj| scalar(si, sj),
            )
        }
    }
}
