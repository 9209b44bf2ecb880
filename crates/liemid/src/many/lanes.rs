//! The torque-free midpoint Lie rotation of four bodies at once, in AVX lanes.
//!
//! [`free_rotation_x4`] performs, for four bodies with diagonal inertia, what the many-body
//! step does body by body: two half steps of `solve (M) → Ψ; R ← R exp(Ψ); Π ← exp(−Ψ) Π`.
//! Every lane performs exactly the floating-point operations of the scalar path, in the
//! same order ([`crate::midpoint::solve_increment`] on its diagonal path, with the
//! increment's coefficients from [`crate::so3::Increment::from_half_angle`]), without
//! contraction into FMA, so the results are the same bit for bit; a lane whose
//! Newton iteration has converged is no longer updated. Only the common case runs in
//! lanes: small increments (`|Ψ| < 0.1`, where the coefficients come from their short
//! series). Anything else (a large increment, a singular Jacobian, a non-finite value, a
//! slow convergence) returns `false` with nothing written, and the caller takes the scalar
//! path, which is the reference and reports errors. The variational drift (V)
//! ([`super::FreeRotation::Variational`]) has no lanes: it always takes the scalar path
//! (its Newton terms, `Jr(Ψ) P` and its exact Jacobian, are a second kernel to vectorise;
//! not done).
//!
//! The module exists with the `simd` feature on x86-64. A lane value is one 256-bit AVX
//! register; the kernels are compiled for AVX and the caller runs them only where the
//! processor has AVX ([`use_avx`], checked at run time), taking the scalar path elsewhere.
//! The pair kernels have a second build with AVX-512VL, the same 256-bit operations with 32
//! registers instead of 16 (fewer spills), run where the processor has it ([`use_avx512`]);
//! the same bits (test).

use std::arch::x86_64::{
    __m256d, _mm256_add_pd, _mm256_and_pd, _mm256_andnot_pd, _mm256_blendv_pd, _mm256_cmp_pd, _mm256_div_pd,
    _mm256_loadu_pd, _mm256_max_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_or_pd, _mm256_set1_pd, _mm256_set_pd,
    _mm256_setzero_pd, _mm256_sqrt_pd, _mm256_storeu_pd, _mm256_sub_pd, _mm256_xor_pd, _CMP_EQ_OQ, _CMP_GT_OQ,
    _CMP_LE_OQ, _CMP_NEQ_UQ,
};
use std::ops::{Add, Mul, Neg, Sub};

use crate::linalg::{Mat3, Vec3};
use crate::midpoint::{CONVERGED_ULPS, MAX_INCREMENT_ANGLE, STAGNATION_ULPS};
use crate::so3::{short_series, SERIES_ANGLE_SQUARED};

/// Bodies per kernel call.
pub(crate) const LANES: usize = 4;

/// Newton iterations the lanes try before handing over to the scalar path.
const MAX_LANE_ITERATIONS: u32 = 6;

// SAFETY (every `unsafe` block below): the AVX intrinsics are reached only from
// `kernel_avx` and the pair kernels' builds (`builds!`), which are
// `#[target_feature(enable = "avx")]` (or that and AVX-512VL) and called only after
// `use_avx` (and `use_avx512`) detected the features; the helpers are `#[inline(always)]`,
// so they are compiled inside them. Unaligned loads and stores go through references to `[f64; 4]`.

/// Four `f64`, one per body, in one AVX register.
#[derive(Clone, Copy, Debug)]
struct F(__m256d);

/// A lane mask: all ones where a comparison held, zero elsewhere.
#[derive(Clone, Copy, Debug)]
struct Mask(__m256d);

impl F {
    #[inline(always)]
    fn splat(x: f64) -> F {
        F(unsafe { _mm256_set1_pd(x) })
    }
    #[inline(always)]
    fn from_array(x: [f64; LANES]) -> F {
        F(unsafe { _mm256_loadu_pd(x.as_ptr()) })
    }
    #[inline(always)]
    fn to_array(self) -> [f64; LANES] {
        let mut x = [0.0; LANES];
        unsafe { _mm256_storeu_pd(x.as_mut_ptr(), self.0) };
        x
    }
    #[inline(always)]
    fn div(self, b: F) -> F {
        F(unsafe { _mm256_div_pd(self.0, b.0) })
    }
    #[inline(always)]
    fn max(self, b: F) -> F {
        F(unsafe { _mm256_max_pd(self.0, b.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> F {
        F(unsafe { _mm256_sqrt_pd(self.0) })
    }
    #[inline(always)]
    fn le(self, b: F) -> Mask {
        Mask(unsafe { _mm256_cmp_pd::<_CMP_LE_OQ>(self.0, b.0) })
    }
    #[inline(always)]
    fn gt(self, b: F) -> Mask {
        Mask(unsafe { _mm256_cmp_pd::<_CMP_GT_OQ>(self.0, b.0) })
    }
    /// Lanes that are zero, NaN or infinite.
    #[inline(always)]
    fn zero_or_not_finite(self) -> Mask {
        // `x − x` is 0 for finite `x` and NaN otherwise.
        let not_finite = unsafe { _mm256_cmp_pd::<_CMP_NEQ_UQ>(_mm256_sub_pd(self.0, self.0), _mm256_setzero_pd()) };
        let zero = unsafe { _mm256_cmp_pd::<_CMP_EQ_OQ>(self.0, _mm256_setzero_pd()) };
        Mask(unsafe { _mm256_or_pd(zero, not_finite) })
    }
    /// `where_true` in the lanes of `mask`, `self` elsewhere.
    #[inline(always)]
    fn replace(self, mask: Mask, where_true: F) -> F {
        F(unsafe { _mm256_blendv_pd(self.0, where_true.0, mask.0) })
    }
}

impl Mask {
    #[inline(always)]
    fn none() -> Mask {
        Mask(unsafe { _mm256_setzero_pd() })
    }
    #[inline(always)]
    fn any(self) -> bool {
        unsafe { _mm256_movemask_pd(self.0) != 0 }
    }
    #[inline(always)]
    fn all(self) -> bool {
        unsafe { _mm256_movemask_pd(self.0) == 0b1111 }
    }
    #[inline(always)]
    fn or(self, b: Mask) -> Mask {
        Mask(unsafe { _mm256_or_pd(self.0, b.0) })
    }
    #[inline(always)]
    fn and(self, b: Mask) -> Mask {
        Mask(unsafe { _mm256_and_pd(self.0, b.0) })
    }
    /// `self` and not `b`.
    #[inline(always)]
    fn and_not(self, b: Mask) -> Mask {
        Mask(unsafe { _mm256_andnot_pd(b.0, self.0) })
    }
}

impl From<f64> for F {
    #[inline(always)]
    fn from(x: f64) -> F {
        F::splat(x)
    }
}

/// The lane-wise binary operators of `F`, each one AVX instruction.
macro_rules! lane_operator {
    ($trait:ident, $method:ident, $intrinsic:ident) => {
        impl $trait for F {
            type Output = F;
            #[inline(always)]
            fn $method(self, b: F) -> F {
                F(unsafe { $intrinsic(self.0, b.0) })
            }
        }
    };
}
lane_operator!(Add, add, _mm256_add_pd);
lane_operator!(Sub, sub, _mm256_sub_pd);
lane_operator!(Mul, mul, _mm256_mul_pd);
impl Neg for F {
    type Output = F;
    /// `−x` as the scalar path negates: the sign bit flipped (so `−0` stays distinct from `0 − 0`).
    #[inline(always)]
    fn neg(self) -> F {
        F(unsafe { _mm256_xor_pd(self.0, _mm256_set1_pd(-0.0)) })
    }
}
impl Mul<f64> for F {
    type Output = F;
    #[inline(always)]
    fn mul(self, b: f64) -> F {
        self * F::splat(b)
    }
}

/// Four 3-vectors, component-major; the operations are those of [`Vec3`], term for term.
#[derive(Clone, Copy, Debug)]
struct V {
    x: F,
    y: F,
    z: F,
}

impl V {
    /// Four vectors straight into the lanes (no round trip through memory).
    #[inline(always)]
    fn set(v: &[Vec3; LANES]) -> V {
        V {
            x: F(unsafe { _mm256_set_pd(v[3].x, v[2].x, v[1].x, v[0].x) }),
            y: F(unsafe { _mm256_set_pd(v[3].y, v[2].y, v[1].y, v[0].y) }),
            z: F(unsafe { _mm256_set_pd(v[3].z, v[2].z, v[1].z, v[0].z) }),
        }
    }
    #[inline(always)]
    fn gather(v: &[Vec3; LANES]) -> V {
        V {
            x: F::from_array([v[0].x, v[1].x, v[2].x, v[3].x]),
            y: F::from_array([v[0].y, v[1].y, v[2].y, v[3].y]),
            z: F::from_array([v[0].z, v[1].z, v[2].z, v[3].z]),
        }
    }
    #[inline(always)]
    fn scatter(self, v: &mut [Vec3; LANES]) {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        for (k, v) in v.iter_mut().enumerate() {
            *v = Vec3::new(x[k], y[k], z[k]);
        }
    }
    #[inline(always)]
    fn dot(self, b: V) -> F {
        self.x * b.x + self.y * b.y + self.z * b.z
    }
    #[inline(always)]
    fn norm_squared(self) -> F {
        self.dot(self)
    }
    #[inline(always)]
    fn cross(self, b: V) -> V {
        V {
            x: self.y * b.z - self.z * b.y,
            y: self.z * b.x - self.x * b.z,
            z: self.x * b.y - self.y * b.x,
        }
    }
    #[inline(always)]
    fn zip(self, b: V, f: impl Fn(F, F) -> F) -> V {
        V {
            x: f(self.x, b.x),
            y: f(self.y, b.y),
            z: f(self.z, b.z),
        }
    }
    #[inline(always)]
    fn component_mul(self, b: V) -> V {
        self.zip(b, |x, y| x * y)
    }
    #[inline(always)]
    fn scale(self, s: F) -> V {
        V {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    fn scale_by(self, s: f64) -> V {
        self.scale(F::splat(s))
    }
    #[inline(always)]
    #[allow(clippy::eq_op)] // `v − v` is 0 for finite `v`, NaN otherwise.
    fn not_finite(self) -> Mask {
        let s = ((self.x - self.x) + (self.y - self.y)) + (self.z - self.z);
        Mask(unsafe { _mm256_cmp_pd::<_CMP_NEQ_UQ>(s.0, _mm256_setzero_pd()) })
    }
    #[inline(always)]
    fn replace(self, mask: Mask, where_true: V) -> V {
        V {
            x: self.x.replace(mask, where_true.x),
            y: self.y.replace(mask, where_true.y),
            z: self.z.replace(mask, where_true.z),
        }
    }
}

impl Add for V {
    type Output = V;
    #[inline(always)]
    fn add(self, b: V) -> V {
        self.zip(b, |x, y| x + y)
    }
}
impl Sub for V {
    type Output = V;
    #[inline(always)]
    fn sub(self, b: V) -> V {
        self.zip(b, |x, y| x - y)
    }
}
impl Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        V {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}
impl Mul<F> for V {
    type Output = V;
    #[inline(always)]
    fn mul(self, s: F) -> V {
        self.scale(s)
    }
}

/// The diagonal Newton solve of (M) in lanes, with the half-angle coefficients `[t, a, b, c]`
/// of each lane's last iteration (for [`increment`]); `None` hands the four bodies to the
/// scalar path.
#[inline(always)]
fn solve(d: V, d_inv: V, inverse_norm: F, p: V, h: f64) -> Option<(V, [F; 4])> {
    let hd = d_inv.scale_by(h);
    let k = V {
        x: d_inv.z - d_inv.y,
        y: d_inv.x - d_inv.z,
        z: d_inv.y - d_inv.x,
    }
    .scale_by(0.5 * h);
    let pp = V {
        x: p.y * p.z,
        y: p.z * p.x,
        z: p.x * p.y,
    };
    let mut psi = hd.component_mul(p) + hd.component_mul(k).component_mul(pp);
    if psi.norm_squared().gt(F::splat(SERIES_ANGLE_SQUARED)).any() {
        return None; // large increments take the longer series of the scalar path
    }
    let hn = inverse_norm * h;
    let quadratic2 = p.norm_squared() * hn * hn;
    let s = 0.5 * h;
    let eps = F::splat(f64::EPSILON);
    let (eps2, max2) = (
        F::splat(f64::EPSILON * f64::EPSILON),
        F::splat(MAX_INCREMENT_ANGLE * MAX_INCREMENT_ANGLE),
    );
    let mut done = Mask::none();
    let mut previous = F::splat(f64::INFINITY);
    let mut half = [F::splat(0.0); 4];
    for _ in 0..MAX_LANE_ITERATIONS {
        let v = psi.scale_by(-0.5);
        let t2 = v.norm_squared();
        if F::splat(SERIES_ANGLE_SQUARED).le(t2).any() {
            return None;
        }
        let (a, b, c) = short_series(t2);
        let vp = v.cross(p);
        let q = p + vp.scale(a) + v.cross(vp).scale(b);
        let g = d.component_mul(psi) - q.scale_by(h);
        let w = q.cross(v);
        let (alpha, beta, gamma) = ((F::splat(1.0) - c * t2) * s, b * s, c * s);
        let diag = beta * q.dot(v);
        let (bv, gw, aq) = (v.scale(beta), w.scale(gamma), q.scale(alpha));
        let r0 = V {
            x: d.x + diag - bv.x * q.x - gw.x * v.x,
            y: aq.z - bv.x * q.y - gw.x * v.y,
            z: -aq.y - bv.x * q.z - gw.x * v.z,
        };
        let r1 = V {
            x: -aq.z - bv.y * q.x - gw.y * v.x,
            y: d.y + diag - bv.y * q.y - gw.y * v.y,
            z: aq.x - bv.y * q.z - gw.y * v.z,
        };
        let r2 = V {
            x: aq.y - bv.z * q.x - gw.z * v.x,
            y: -aq.x - bv.z * q.y - gw.z * v.y,
            z: d.z + diag - bv.z * q.z - gw.z * v.z,
        };
        let c0 = r1.cross(r2);
        let det = r0.dot(c0);
        if det.zero_or_not_finite().any() {
            return None;
        }
        let inv = F::splat(1.0).div(det);
        let delta = (c0.scale(g.x) + r2.cross(r0).scale(g.y) + r0.cross(r1).scale(g.z)).scale(inv);
        let next = psi - delta;
        if next.not_finite().any() {
            return None;
        }
        psi = next.replace(done, psi);
        for (kept, now) in half.iter_mut().zip([t2, a, b, c]) {
            *kept = now.replace(done, *kept);
        }
        let (d2, x2) = (delta.norm_squared(), next.norm_squared());
        // `NewtonStop::done` of the scalar path.
        let (dl, ulp) = (d2.sqrt(), eps * x2.sqrt());
        let stagnated = dl
            .le(ulp * CONVERGED_ULPS)
            .or(dl.le(ulp * STAGNATION_ULPS).and(dl.gt(previous * 0.5)));
        previous = dl.replace(done, previous);
        let converged = (quadratic2 * d2 * d2).le(eps2 * x2).or(stagnated).and_not(done);
        if converged.and(x2.gt(max2)).any() {
            return None;
        }
        done = done.or(converged);
        if done.all() {
            return Some((psi, half));
        }
    }
    None
}

/// Four attitudes, entry by entry.
#[derive(Clone, Copy, Debug)]
struct M([[F; 3]; 3]);

impl M {
    #[inline(always)]
    fn gather(r: &[Mat3; LANES]) -> M {
        let mut m = [[F::splat(0.0); 3]; 3];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, e) in row.iter_mut().enumerate() {
                *e = F::from_array([r[0].m[i][j], r[1].m[i][j], r[2].m[i][j], r[3].m[i][j]]);
            }
        }
        M(m)
    }
    #[inline(always)]
    fn scatter(&self, r: &mut [Mat3; LANES]) {
        for (i, row) in self.0.iter().enumerate() {
            for (j, e) in row.iter().enumerate() {
                let x = e.to_array();
                for k in 0..LANES {
                    r[k].m[i][j] = x[k];
                }
            }
        }
    }
}

/// `R exp(Ψ)` and `exp(−Ψ) Π` as [`crate::so3::Increment`] computes them, with the
/// coefficients from the half-angle ones of the last Newton iteration
/// ([`crate::so3::Increment::from_half_angle`]).
#[inline(always)]
fn increment(psi: V, [t, a, b, c]: [F; 4], r: &mut M, pi: V) -> V {
    let delta = psi.norm_squared() * 0.25 - t;
    let a_half = a + (c - b) * 0.5 * delta;
    let cos_half = (F::splat(1.0) - t * b) - a * 0.5 * delta;
    let (a, b) = (a_half * cos_half, a_half * 0.5 * a_half);
    // `E = a hat(Ψ) + b hat(Ψ)²`, then `R + R E`.
    let (x, y, z) = (psi.x, psi.y, psi.z);
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let e = [
        [-b * (yy + zz), b * x * y - a * z, b * x * z + a * y],
        [b * x * y + a * z, -b * (xx + zz), b * y * z - a * x],
        [b * x * z - a * y, b * y * z + a * x, -b * (xx + yy)],
    ];
    let m = r.0;
    for (i, row) in r.0.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = m[i][j] + (m[i][0] * e[0][j] + m[i][1] * e[1][j] + m[i][2] * e[2][j]);
        }
    }
    let px = psi.cross(pi);
    pi - px.scale(a) + psi.cross(px).scale(b)
}

/// Two torque-free midpoint Lie half steps of `h` each for four bodies with diagonal
/// inertia `d` (reciprocals `d_inv`, `‖D⁻¹‖` bound `inverse_norm`). Returns `false`, with
/// `rotation` and `pi` untouched, when any body needs the scalar path.
#[target_feature(enable = "avx")]
fn kernel_avx(
    d: &[Vec3; LANES],
    d_inv: &[Vec3; LANES],
    inverse_norm: [f64; LANES],
    rotation: &mut [Mat3; LANES],
    pi: &mut [Vec3; LANES],
    h: f64,
) -> bool {
    let (d, d_inv, inverse_norm) = (V::gather(d), V::gather(d_inv), F::from_array(inverse_norm));
    let mut p = V::gather(pi);
    let mut r = M::gather(rotation);
    for _ in 0..2 {
        let Some((psi, half)) = solve(d, d_inv, inverse_norm, p, h) else {
            return false;
        };
        p = increment(psi, half, &mut r, p);
    }
    r.scatter(rotation);
    p.scatter(pi);
    true
}

/// Whether the AVX kernel can run here (cached by the standard library).
#[inline]
pub(crate) fn use_avx() -> bool {
    std::is_x86_feature_detected!("avx")
}

/// Whether the pair kernels' AVX-512 builds can run here: the same 256-bit operations,
/// compiled with AVX-512's 32 vector registers (AVX-512VL), so with fewer values spilled to
/// the stack (the half-list kernel: 102 stack accesses instead of 163). The same
/// operations, so the same bits.
#[inline]
pub(crate) fn use_avx512() -> bool {
    std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512vl")
}

/// Each pair kernel twice, from one body: compiled for AVX, and for AVX with AVX-512VL (more
/// registers, the same operations).
macro_rules! builds {
    ($($avx:ident, $avx512:ident = $body:ident($($arg:ident: $ty:ty),*) -> $ret:ty;)*) => {$(
        #[target_feature(enable = "avx")]
        #[allow(clippy::too_many_arguments)]
        fn $avx($($arg: $ty),*) -> $ret {
            $body($($arg),*)
        }
        #[target_feature(enable = "avx,avx2,avx512f,avx512vl")]
        #[allow(clippy::too_many_arguments)]
        fn $avx512($($arg: $ty),*) -> $ret {
            $body($($arg),*)
        }
    )*};
}

builds! {
    gather_avx, gather_avx512 = gather_body(
        k: &PairKernel, xi: Vec3, mi: Vec3, position: &[Vec3], dipole: &[Vec3], list: &[u32])
        -> Option<(Vec3, Vec3)>;
    half_avx, half_avx512 = half_body(
        k: &PairKernel, xi: Vec3, mi: Vec3, position: &[Vec3], dipole: &[Vec3], list: &[u32],
        slots: &mut [[Vec3; 2]]) -> Option<(Vec3, Vec3)>;
}

/// Two torque-free midpoint Lie half steps of `h` for four bodies; see the module docs.
/// `avx` must be [`use_avx`]; without AVX it returns `false` (the scalar path).
#[inline]
pub(crate) fn free_rotation_x4(
    avx: bool,
    d: &[Vec3; LANES],
    d_inv: &[Vec3; LANES],
    inverse_norm: [f64; LANES],
    rotation: &mut [Mat3; LANES],
    pi: &mut [Vec3; LANES],
    h: f64,
) -> bool {
    // SAFETY: `avx` is true only when `use_avx` detected AVX on this processor. (Its
    // AVX-512VL build was slower: 83 against 63 µs for the motion of 10³ bodies.)
    avx && unsafe { kernel_avx(d, d_inv, inverse_norm, rotation, pi, h) }
}

/// The constants of the dipole pair kernel, as `Dipoles::kernel` uses them: squared cutoff
/// and switch radii, `1/(r_c² − r_s²)`, the periodic box and its inverse, `σ²`, `ε`, and the
/// WCA range `(σ/r)² > 2^{-1/3}`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairKernel {
    pub(crate) c2: f64,
    pub(crate) s2: f64,
    pub(crate) inv_width: f64,
    pub(crate) inv_rc: f64,
    pub(crate) periodic: Option<(f64, f64)>,
    pub(crate) sigma2: f64,
    pub(crate) epsilon: f64,
    pub(crate) wca: f64,
}

/// The force and field on a body at `xi` with dipole `mi` from the neighbours `list`, four
/// pairs at a time: pair `k` is summed in lane `k mod 4`, the lanes are combined as
/// `(l₀ + l₁) + (l₂ + l₃)`, every lane performs the scalar kernel's operations in its order
/// (no FMA), and a pair beyond the cutoff leaves its lane untouched, so the scalar path
/// that sums the same way gives the same bits. `None` (nothing done) when a periodic
/// separation needs the scalar path's large-quotient rounding, or without AVX.
#[inline]
pub(crate) fn gather_pairs_x4(
    avx: bool,
    k: &PairKernel,
    xi: Vec3,
    mi: Vec3,
    position: &[Vec3],
    dipole: &[Vec3],
    list: &[u32],
) -> Option<(Vec3, Vec3)> {
    if !avx {
        return None;
    }
    // SAFETY: as in `free_rotation_x4`.
    unsafe {
        if use_avx512() {
            gather_avx512(k, xi, mi, position, dipole, list)
        } else {
            gather_avx(k, xi, mi, position, dipole, list)
        }
    }
}

/// One group of four pairs `(i, j_lane)`: the lanes within the cutoff, the force on `i`
/// (with WCA), the field of `j` at `i` and of `i` at `j`, as `Dipoles::kernel` computes them
/// (switched); `None` when a periodic separation needs the scalar rounding.
#[inline(always)]
fn pair_group(
    k: &PairKernel,
    xi4: V,
    mi4: V,
    xs: &[Vec3; LANES],
    ms: &[Vec3; LANES],
    live: Mask,
) -> Option<(Mask, V, V, V)> {
    let mut r = xi4 - V::set(xs);
    if let Some((l, inv_l)) = k.periodic {
        // No closures here: a closure is compiled without AVX and would call every
        // intrinsic out of line (measured: 4x slower).
        let (l, inv_l) = (F::splat(l), F::splat(inv_l));
        r = V {
            x: nearest_image(r.x, l, inv_l)?,
            y: nearest_image(r.y, l, inv_l)?,
            z: nearest_image(r.z, l, inv_l)?,
        };
    }
    let mj = V::set(ms);
    let r2 = r.norm_squared();
    let inside = r2.le(F::splat(k.c2)).and(live);
    if !inside.any() {
        return Some((inside, r, r, r));
    }
    let inv2 = F::splat(1.0).div(r2);
    let inv = inv2.sqrt();
    let inv3 = inv * inv2;
    let inv5 = inv3 * inv2;
    let (a, b, ab) = (mi4.dot(r), mj.dot(r), mi4.dot(mj));
    let prod = a * b;
    let force = (r * (ab - F::splat(5.0) * prod * inv2) + (mj * a + mi4 * b)) * (F::splat(3.0) * inv5);
    let field = (r * (F::splat(3.0) * b * inv2) - mj) * inv3;
    let field_j = (r * (F::splat(3.0) * a * inv2) - mi4) * inv3;
    let energy = ab * inv3 - F::splat(3.0) * prod * inv5;
    let (sw, ds) = if k.inv_rc > 0.0 {
        // Shifted force, as the scalar kernel.
        let x = r2 * inv * F::splat(k.inv_rc);
        let x3 = x * x * x;
        (
            F::splat(1.0) - x3 * (F::splat(4.0) - F::splat(3.0) * x),
            F::splat(12.0) * energy * x3 * (F::splat(1.0) - x) * inv2,
        )
    } else {
        let inv_width = F::splat(k.inv_width);
        let t = (r2 - F::splat(k.s2)).max(F::splat(0.0)) * inv_width;
        (
            F::splat(1.0) - t * t * (F::splat(3.0) - F::splat(2.0) * t),
            F::splat(12.0) * energy * t * (F::splat(1.0) - t) * inv_width,
        )
    };
    let force = force * sw + r * ds;
    let (field, field_j) = (field * sw, field_j * sw);
    let s2w = F::splat(k.sigma2) * inv2;
    let repelled = s2w.gt(F::splat(k.wca));
    // The WCA core only where some lane is inside it (few pairs: r < 2^{1/6} σ), the same
    // lanes either way.
    let total = if repelled.any() {
        let s6 = s2w * s2w * s2w;
        let wca = r * (F::splat(24.0 * k.epsilon) * (F::splat(2.0) * s6 * s6 - s6) * inv2);
        force.replace(repelled, force + wca)
    } else {
        force
    };
    Some((inside, total, field, field_j))
}

/// The nearest periodic image of each lane's separation component, as the scalar path
/// rounds it (`x − L ((q + M) − M)`, `q = x/L`); `None` unless `|q| < 2⁵¹` in every lane.
#[inline(always)]
fn nearest_image(x: F, l: F, inv_l: F) -> Option<F> {
    let q = x * inv_l;
    let abs_q = q.max(-q);
    if !abs_q.le(F::splat(2_251_799_813_685_248.0)).all() {
        return None;
    }
    let m = F::splat(6_755_399_441_055_744.0);
    Some(x - ((q + m) - m) * l)
}

/// The lanes of a group that hold a neighbour: the first `n`.
#[inline(always)]
fn first_lanes(n: usize) -> Mask {
    const ON: [[f64; LANES]; LANES + 1] = [
        [0.0, 0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0],
        [1.0, 1.0, 1.0, 0.0],
        [1.0, 1.0, 1.0, 1.0],
    ];
    F::from_array(ON[n]).gt(F::splat(0.0))
}

/// Load a group's neighbours; padded lanes sit on the body itself (masked out).
#[inline(always)]
fn load_group(xi: Vec3, position: &[Vec3], dipole: &[Vec3], group: &[u32]) -> ([Vec3; LANES], [Vec3; LANES]) {
    let mut xs = [xi; LANES];
    let mut ms = [Vec3::ZERO; LANES];
    for (lane, &j) in group.iter().enumerate() {
        xs[lane] = position[j as usize];
        ms[lane] = dipole[j as usize];
    }
    (xs, ms)
}

/// The lanes combined as `(l₀ + l₁) + (l₂ + l₃)`.
#[inline(always)]
fn combine(v: V) -> Vec3 {
    let (x, y, z) = (v.x.to_array(), v.y.to_array(), v.z.to_array());
    Vec3::new(
        (x[0] + x[1]) + (x[2] + x[3]),
        (y[0] + y[1]) + (y[2] + y[3]),
        (z[0] + z[1]) + (z[2] + z[3]),
    )
}

#[inline(always)]
fn splat3(v: Vec3) -> V {
    V {
        x: F::splat(v.x),
        y: F::splat(v.y),
        z: F::splat(v.z),
    }
}

#[inline(always)]
fn gather_body(
    k: &PairKernel,
    xi: Vec3,
    mi: Vec3,
    position: &[Vec3],
    dipole: &[Vec3],
    list: &[u32],
) -> Option<(Vec3, Vec3)> {
    let (mut fa, mut ba) = (splat3(Vec3::ZERO), splat3(Vec3::ZERO));
    let (xi4, mi4) = (splat3(xi), splat3(mi));
    for group in list.chunks(LANES) {
        let (xs, ms) = load_group(xi, position, dipole, group);
        let (inside, total, field, _) = pair_group(k, xi4, mi4, &xs, &ms, first_lanes(group.len()))?;
        if inside.any() {
            fa = fa.replace(inside, fa + total);
            ba = ba.replace(inside, ba + field);
        }
    }
    Some((combine(fa), combine(ba)))
}

/// Each pair of a half list once: for body `i` at `xi` with dipole `mi` and the partners
/// it owns `list`, the force and field on `i` summed in lanes as [`gather_pairs_x4`]
/// sums them, and per pair `p` the force on `j` and the field at `j` into `slots[p]`
/// (zeros beyond the cutoff), every lane as the scalar kernel. `None` (slots possibly
/// written, to be rewritten by the scalar path) when a periodic separation needs the scalar
/// rounding, or without AVX.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn half_pairs_x4(
    avx: bool,
    k: &PairKernel,
    xi: Vec3,
    mi: Vec3,
    position: &[Vec3],
    dipole: &[Vec3],
    list: &[u32],
    slots: &mut [[Vec3; 2]],
) -> Option<(Vec3, Vec3)> {
    if !avx {
        return None;
    }
    // SAFETY: as in `free_rotation_x4`.
    unsafe {
        if use_avx512() {
            half_avx512(k, xi, mi, position, dipole, list, slots)
        } else {
            half_avx(k, xi, mi, position, dipole, list, slots)
        }
    }
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn half_body(
    k: &PairKernel,
    xi: Vec3,
    mi: Vec3,
    position: &[Vec3],
    dipole: &[Vec3],
    list: &[u32],
    slots: &mut [[Vec3; 2]],
) -> Option<(Vec3, Vec3)> {
    let zero = splat3(Vec3::ZERO);
    let (mut fa, mut ba) = (zero, zero);
    let (xi4, mi4) = (splat3(xi), splat3(mi));
    for (group, out) in list.chunks(LANES).zip(slots.chunks_mut(LANES)) {
        let (xs, ms) = load_group(xi, position, dipole, group);
        let (inside, total, field, field_j) = pair_group(k, xi4, mi4, &xs, &ms, first_lanes(group.len()))?;
        if !inside.any() {
            out.iter_mut().for_each(|o| *o = [Vec3::ZERO; 2]);
            continue;
        }
        fa = fa.replace(inside, fa + total);
        ba = ba.replace(inside, ba + field);
        let (mut fj, mut bj) = ([Vec3::ZERO; LANES], [Vec3::ZERO; LANES]);
        zero.replace(inside, -total).scatter(&mut fj);
        zero.replace(inside, field_j).scatter(&mut bj);
        for (lane, o) in out.iter_mut().enumerate() {
            *o = [fj[lane], bj[lane]];
        }
    }
    Some((combine(fa), combine(ba)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inertia::PrincipalInertia;
    use crate::many::free_rotation_by;
    use crate::random::Rng;
    use crate::variational::Drift;

    /// Lanes and the scalar path agree bit for bit, and the lanes take the common case.
    #[test]
    fn lanes_equal_the_scalar_path_bit_for_bit() {
        if !use_avx() {
            eprintln!("no AVX on this processor: the lanes are never used");
            return;
        }
        let mut rng = Rng::new(5);
        let mut taken = 0;
        for trial in 0..2000 {
            let mut inertia = [PrincipalInertia::new(Vec3::new(1.0, 1.0, 1.0)); LANES];
            let mut r = [Mat3::IDENTITY; LANES];
            let mut pi = [Vec3::ZERO; LANES];
            for k in 0..LANES {
                let m = Vec3::new(
                    1.0 + 3.0 * rng.uniform(),
                    1.0 + 3.0 * rng.uniform(),
                    1.0 + 3.0 * rng.uniform(),
                );
                inertia[k] = PrincipalInertia::new(m);
                r[k] = rng.rotation();
                pi[k] = rng.unit_vector() * (20.0 * rng.uniform());
            }
            if trial % 7 == 0 {
                // Exact zeros, whose signs the lanes must reproduce too.
                pi[0] = Vec3::ZERO;
                pi[1] = Vec3::new(0.0, 0.0, -5.0 * rng.uniform());
                r[2] = Mat3::IDENTITY;
            }
            // Mostly small increments; some large enough to leave the lanes.
            let h = if trial % 10 == 0 {
                0.05
            } else {
                1e-3 * (1.0 + rng.uniform())
            };
            let (mut r_lanes, mut pi_lanes) = (r, pi);
            let ok = free_rotation_x4(
                use_avx(),
                &inertia.map(|i| i.moments),
                &inertia.map(|i| i.inverse),
                inertia.map(|i| i.inverse.max_abs()),
                &mut r_lanes,
                &mut pi_lanes,
                h,
            );
            if !ok {
                assert_eq!((r_lanes, pi_lanes), (r, pi), "untouched on hand-over");
                continue;
            }
            taken += 1;
            for k in 0..LANES {
                let (mut rs, mut ps) = (r[k], pi[k]);
                free_rotation_by(Drift::Midpoint, &inertia[k], &mut rs, &mut ps, h).unwrap();
                assert!(rs.bitwise_eq(&r_lanes[k]), "attitude, trial {trial}, lane {k}");
                assert_eq!(
                    ps.to_array().map(f64::to_bits),
                    pi_lanes[k].to_array().map(f64::to_bits)
                );
            }
        }
        assert!(taken > 1500, "lanes took only {taken} of 2000 groups");
    }

    /// The pair kernels' AVX and AVX-512VL builds give the same bits (sums and shares), on
    /// random pairs in a periodic box with both cutoff forms, some inside the WCA core.
    #[test]
    fn the_pair_kernels_avx_512_builds_equal_their_avx_builds_bit_for_bit() {
        if !(use_avx() && use_avx512()) {
            eprintln!("no AVX-512VL on this processor: its builds are never used");
            return;
        }
        let bits = |v: Vec3| v.to_array().map(f64::to_bits);
        let mut rng = Rng::new(23);
        let side = 9.0;
        let (n, mut compared, mut repelled) = (64, 0, 0);
        for inv_rc in [0.0, 1.0 / 3.0] {
            let k = PairKernel {
                c2: 9.0,
                s2: 6.25,
                inv_width: 1.0 / (9.0 - 6.25),
                inv_rc,
                periodic: Some((side, 1.0 / side)),
                sigma2: 1.0,
                epsilon: 1.0,
                wca: 2f64.powf(-1.0 / 3.0),
            };
            let position: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * side)
                .collect();
            let dipole: Vec<Vec3> = (0..n).map(|_| rng.unit_vector()).collect();
            for trial in 0..300 {
                let i = trial % n;
                let list: Vec<u32> = (0..trial % 23)
                    .map(|_| (rng.next_u64() % n as u64) as u32)
                    .filter(|&j| j as usize != i)
                    .collect();
                let (xi, mi) = (position[i], dipole[i]);
                let image = |x: f64| x - side * (x / side).round();
                repelled += list
                    .iter()
                    .map(|&j| xi - position[j as usize])
                    .filter(|d| Vec3::new(image(d.x), image(d.y), image(d.z)).norm() < 1.1225)
                    .count();
                // SAFETY: both feature sets were detected above.
                let (a, b) = unsafe {
                    (
                        gather_avx(&k, xi, mi, &position, &dipole, &list),
                        gather_avx512(&k, xi, mi, &position, &dipole, &list),
                    )
                };
                let (Some(a), Some(b)) = (a, b) else {
                    panic!("a build handed the group over: {a:?} {b:?}");
                };
                assert_eq!((bits(a.0), bits(a.1)), (bits(b.0), bits(b.1)));
                let (mut slots_a, mut slots_b) = (vec![[Vec3::ZERO; 2]; list.len()], vec![[Vec3::ZERO; 2]; list.len()]);
                // SAFETY: as above.
                let (a, b) = unsafe {
                    (
                        half_avx(&k, xi, mi, &position, &dipole, &list, &mut slots_a),
                        half_avx512(&k, xi, mi, &position, &dipole, &list, &mut slots_b),
                    )
                };
                let (Some(a), Some(b)) = (a, b) else {
                    panic!("a build handed the group over");
                };
                assert_eq!((bits(a.0), bits(a.1)), (bits(b.0), bits(b.1)));
                for (x, y) in slots_a.iter().zip(&slots_b) {
                    assert_eq!((bits(x[0]), bits(x[1])), (bits(y[0]), bits(y[1])));
                }
                compared += list.len();
            }
        }
        assert!(compared > 5000, "only {compared} pairs compared");
        assert!(repelled >= 5, "only {repelled} pairs in the WCA core");
    }
}
