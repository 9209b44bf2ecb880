//! The splitting's per-bond work written once, generic over a lane type, and run on four
//! bonds at a time in AVX lanes where the processor has AVX.
//!
//! [`bond_flow`], [`site_flow`] and [`unit`] are the exact bond flow, the on-site flow (when
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

use std::ops::{Add, Mul, Sub};

use crate::linalg::Vec3;

/// What a lane value needs: the four operations the flows use, and splatting constants.
pub(crate) trait Lane: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + From<f64> {}
impl<T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T> + From<f64>> Lane for T {}

/// A 3-vector of lanes, with the operations of [`Vec3`] in the same order.
#[derive(Clone, Copy)]
pub(crate) struct V<T> {
    pub x: T,
    pub y: T,
    pub z: T,
}

impl<T: Lane> V<T> {
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        V {
            x: self.x + b.x,
            y: self.y + b.y,
            z: self.z + b.z,
        }
    }
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        V {
            x: self.x - b.x,
            y: self.y - b.y,
            z: self.z - b.z,
        }
    }
    #[inline(always)]
    fn scale(self, s: T) -> Self {
        V {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    fn dot(self, b: Self) -> T {
        self.x * b.x + self.y * b.y + self.z * b.z
    }
    #[inline(always)]
    fn cross(self, b: Self) -> Self {
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

/// `s (3 − |s|²)/2`: one Newton step towards `|s| = 1`.
#[inline(always)]
pub(crate) fn unit<T: Lane>(s: V<T>) -> V<T> {
    s.scale(T::from(1.5) - T::from(0.5) * s.dot(s))
}

#[cfg(all(feature = "simd", target_arch = "x86_64"))]
pub(crate) use avx::{sweep_avx, use_avx};

#[cfg(all(feature = "simd", target_arch = "x86_64"))]
mod avx {
    use std::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_cmp_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_set1_pd, _mm256_set_pd,
        _mm256_storeu_pd, _mm256_sub_pd, _CMP_LT_OQ,
    };
    use std::ops::{Add, Mul, Sub};

    use super::{bond_flow, rodrigues_series, sinc_cos_series, site_flow, unit, SERIES_LIMIT, V};
    use crate::linalg::Vec3;
    use crate::spin::splitting::{Kernel, Piece};

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
        let mut groups = bonds.chunks_exact(4);
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
                match group(kernel, pieces, si, sj) {
                    Some((a, b)) => {
                        for k in 0..4 {
                            *spins.add(idx[k].0) = a[k];
                            *spins.add(idx[k].1) = b[k];
                        }
                    }
                    None => {
                        for k in 0..4 {
                            let (a, b) = scalar(si[k], sj[k]);
                            *spins.add(idx[k].0) = a;
                            *spins.add(idx[k].1) = b;
                        }
                    }
                }
            }
        }
        for b in groups.remainder() {
            let (i, j) = (b[0] as usize, b[1] as usize);
            assert!(i < len && j < len && i != j);
            // SAFETY: as above.
            unsafe {
                let (a, c) = scalar(*spins.add(i), *spins.add(j));
                *spins.add(i) = a;
                *spins.add(j) = c;
            }
        }
    }
}
