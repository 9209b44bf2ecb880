//! The torque-free midpoint Lie rotation of four bodies at once, in SIMD lanes.
//!
//! [`free_rotation_x4`] performs, for four bodies with diagonal inertia, what the many-body
//! step does body by body: two half steps of `solve (M) → Ψ; R ← R exp(Ψ); Π ← exp(−Ψ) Π`.
//! Every lane performs exactly the floating-point operations of the scalar path, in the
//! same order ([`crate::midpoint::solve`] on its diagonal path, [`crate::so3::Increment`]),
//! so the results are the same bit for bit; a lane whose Newton iteration has converged is
//! no longer updated. Only the common case runs in lanes: small increments (`|Ψ| < 0.1`,
//! where the predictor is used without fixed-point refinement and the coefficients come
//! from their short series). Anything else (a large increment, a singular Jacobian, a
//! non-finite value, a slow convergence) returns `false` with nothing written, and the
//! caller takes the scalar path, which is the reference and reports errors.
//!
//! With the `simd` feature, on x86-64 processors with AVX, the kernel is compiled a second
//! time for AVX (four `f64` per instruction) and chosen at run time; without it the same
//! code uses SSE2 (two per instruction). IEEE arithmetic without contraction into FMA gives
//! the same results either way.

use std::ops::{Add, Mul, Neg, Sub};

use crate::linalg::{Mat3, Vec3};
use crate::midpoint::MAX_INCREMENT_ANGLE;
use crate::so3::{short_series, SERIES_ANGLE_SQUARED};

/// Bodies per kernel call.
pub(crate) const LANES: usize = 4;

/// Newton iterations the lanes try before handing over to the scalar path.
const MAX_LANE_ITERATIONS: u32 = 6;

/// Four `f64`, one per body.
#[derive(Clone, Copy, Debug)]
struct F([f64; LANES]);

impl F {
    #[inline(always)]
    fn splat(x: f64) -> F {
        F([x; LANES])
    }
    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> F {
        F([f(self.0[0]), f(self.0[1]), f(self.0[2]), f(self.0[3])])
    }
    #[inline(always)]
    fn zip(self, b: F, f: impl Fn(f64, f64) -> f64) -> F {
        F([
            f(self.0[0], b.0[0]),
            f(self.0[1], b.0[1]),
            f(self.0[2], b.0[2]),
            f(self.0[3], b.0[3]),
        ])
    }
    #[inline(always)]
    fn any(self, f: impl Fn(f64) -> bool) -> bool {
        f(self.0[0]) | f(self.0[1]) | f(self.0[2]) | f(self.0[3])
    }
}

impl From<f64> for F {
    #[inline(always)]
    fn from(x: f64) -> F {
        F::splat(x)
    }
}

impl Add for F {
    type Output = F;
    #[inline(always)]
    fn add(self, b: F) -> F {
        self.zip(b, |x, y| x + y)
    }
}
impl Sub for F {
    type Output = F;
    #[inline(always)]
    fn sub(self, b: F) -> F {
        self.zip(b, |x, y| x - y)
    }
}
impl Mul for F {
    type Output = F;
    #[inline(always)]
    fn mul(self, b: F) -> F {
        self.zip(b, |x, y| x * y)
    }
}
impl Mul<f64> for F {
    type Output = F;
    #[inline(always)]
    fn mul(self, b: f64) -> F {
        self.map(|x| x * b)
    }
}
impl Neg for F {
    type Output = F;
    #[inline(always)]
    fn neg(self) -> F {
        self.map(|x| -x)
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
    #[inline(always)]
    fn gather(v: [Vec3; LANES]) -> V {
        V {
            x: F([v[0].x, v[1].x, v[2].x, v[3].x]),
            y: F([v[0].y, v[1].y, v[2].y, v[3].y]),
            z: F([v[0].z, v[1].z, v[2].z, v[3].z]),
        }
    }
    #[inline(always)]
    fn lane(&self, k: usize) -> Vec3 {
        Vec3::new(self.x.0[k], self.y.0[k], self.z.0[k])
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
    fn is_finite(self) -> [bool; LANES] {
        #[allow(clippy::eq_op)] // `v − v` is 0 for finite `v`, NaN otherwise.
        let s = ((self.x - self.x) + (self.y - self.y)) + (self.z - self.z);
        s.0.map(|x| x == 0.0)
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

/// The diagonal Newton solve of (M) in lanes; `None` hands the four bodies to the scalar path.
#[inline(always)]
fn solve(d: V, d_inv: V, inverse_norm: F, p: V, h: f64) -> Option<V> {
    let hd = d_inv.scale_by(h);
    let psi0 = hd.component_mul(p);
    let mut psi = hd.component_mul(p + p.cross(psi0).scale_by(0.5));
    if psi.norm_squared().any(|x| x > SERIES_ANGLE_SQUARED) {
        return None; // the scalar path refines large increments by fixed-point steps
    }
    let hn = inverse_norm * h;
    let quadratic2 = p.norm_squared() * hn * hn;
    let s = 0.5 * h;
    let mut done = [false; LANES];
    let mut previous = [f64::INFINITY; LANES];
    for _ in 0..MAX_LANE_ITERATIONS {
        let v = psi.scale_by(-0.5);
        let t2 = v.norm_squared();
        if t2.any(|x| x >= SERIES_ANGLE_SQUARED) {
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
        if det.any(|x| x == 0.0 || !x.is_finite()) {
            return None;
        }
        let inv = F::splat(1.0).zip(det, |one, x| one / x);
        let delta = (c0.scale(g.x) + r2.cross(r0).scale(g.y) + r0.cross(r1).scale(g.z)).scale(inv);
        let next = psi - delta;
        if next.is_finite().contains(&false) {
            return None;
        }
        let (d2, x2) = (delta.norm_squared(), next.norm_squared());
        let mut all = true;
        for k in 0..LANES {
            if done[k] {
                continue;
            }
            psi.x.0[k] = next.x.0[k];
            psi.y.0[k] = next.y.0[k];
            psi.z.0[k] = next.z.0[k];
            let (d2, x2) = (d2.0[k], x2.0[k]);
            // `NewtonStop::done` of the scalar path.
            let (delta, x) = (d2.sqrt(), x2.sqrt());
            let ulp = f64::EPSILON * x;
            let stagnated = delta <= 4.0 * ulp || (delta <= 256.0 * ulp && delta > 0.5 * previous[k]);
            previous[k] = delta;
            if quadratic2.0[k] * d2 * d2 <= f64::EPSILON * f64::EPSILON * x2 || stagnated {
                if x2 > MAX_INCREMENT_ANGLE * MAX_INCREMENT_ANGLE {
                    return None;
                }
                done[k] = true;
            } else {
                all = false;
            }
        }
        if all {
            return Some(psi);
        }
    }
    None
}

/// `R exp(Ψ)` and `exp(−Ψ) Π` as [`crate::so3::Increment`] computes them.
#[inline(always)]
fn increment(psi: V, r: &mut [Mat3; LANES], pi: V) -> Option<V> {
    let t = psi.norm_squared();
    if t.any(|x| x >= SERIES_ANGLE_SQUARED) {
        return None;
    }
    let (a, b, _) = short_series(t);
    // `a hat(Ψ) + b hat(Ψ)²`, then `R + R (…)` for each body.
    let (x, y, z) = (psi.x, psi.y, psi.z);
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let e = [
        [-(b * (yy + zz)), b * x * y - a * z, b * x * z + a * y],
        [b * x * y + a * z, -(b * (xx + zz)), b * y * z - a * x],
        [b * x * z - a * y, b * y * z + a * x, -(b * (xx + yy))],
    ];
    for (k, r) in r.iter_mut().enumerate() {
        let m = Mat3::from_rows([
            [e[0][0].0[k], e[0][1].0[k], e[0][2].0[k]],
            [e[1][0].0[k], e[1][1].0[k], e[1][2].0[k]],
            [e[2][0].0[k], e[2][1].0[k], e[2][2].0[k]],
        ]);
        *r = *r + *r * m;
    }
    let px = psi.cross(pi);
    Some(pi - px.scale(a) + psi.cross(px).scale(b))
}

/// Two torque-free midpoint Lie half steps of `h` each for four bodies with diagonal
/// inertia `d` (reciprocals `d_inv`, `‖D⁻¹‖` bound `inverse_norm`). Returns `false`, with
/// `rotation` and `pi` untouched, when any body needs the scalar path.
#[inline(always)]
fn kernel(
    d: [Vec3; LANES],
    d_inv: [Vec3; LANES],
    inverse_norm: [f64; LANES],
    rotation: &mut [Mat3; LANES],
    pi: &mut [Vec3; LANES],
    h: f64,
) -> bool {
    let (d, d_inv, inverse_norm) = (V::gather(d), V::gather(d_inv), F(inverse_norm));
    let mut p = V::gather(*pi);
    let mut r = *rotation;
    for _ in 0..2 {
        let Some(psi) = solve(d, d_inv, inverse_norm, p, h) else {
            return false;
        };
        let Some(next) = increment(psi, &mut r, p) else {
            return false;
        };
        p = next;
    }
    *rotation = r;
    for (k, pi) in pi.iter_mut().enumerate() {
        *pi = p.lane(k);
    }
    true
}

#[cfg(all(feature = "simd", target_arch = "x86_64"))]
#[target_feature(enable = "avx")]
fn kernel_avx(
    d: [Vec3; LANES],
    d_inv: [Vec3; LANES],
    inverse_norm: [f64; LANES],
    rotation: &mut [Mat3; LANES],
    pi: &mut [Vec3; LANES],
    h: f64,
) -> bool {
    kernel(d, d_inv, inverse_norm, rotation, pi, h)
}

/// Whether the AVX build of the kernel can run here (checked once per call site and
/// cached by the standard library).
#[inline]
pub(crate) fn use_avx() -> bool {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    {
        std::is_x86_feature_detected!("avx")
    }
    #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
    {
        false
    }
}

/// Two torque-free midpoint Lie half steps of `h` for four bodies; see the module docs.
#[inline]
pub(crate) fn free_rotation_x4(
    avx: bool,
    d: [Vec3; LANES],
    d_inv: [Vec3; LANES],
    inverse_norm: [f64; LANES],
    rotation: &mut [Mat3; LANES],
    pi: &mut [Vec3; LANES],
    h: f64,
) -> bool {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    if avx {
        // SAFETY: `avx` is true only when `use_avx` detected AVX on this processor.
        return unsafe { kernel_avx(d, d_inv, inverse_norm, rotation, pi, h) };
    }
    let _ = avx;
    kernel(d, d_inv, inverse_norm, rotation, pi, h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inertia::PrincipalInertia;
    use crate::many::free_rotation;
    use crate::random::Rng;

    /// Lanes and the scalar path agree bit for bit, and the lanes take the common case.
    #[test]
    fn lanes_equal_the_scalar_path_bit_for_bit() {
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
            // Mostly small increments; some large enough to leave the lanes.
            let h = if trial % 10 == 0 {
                0.05
            } else {
                1e-3 * (1.0 + rng.uniform())
            };
            let (mut r_lanes, mut pi_lanes) = (r, pi);
            let ok = free_rotation_x4(
                use_avx(),
                inertia.map(|i| i.moments),
                inertia.map(|i| i.inverse),
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
                free_rotation(&inertia[k], &mut rs, &mut ps, h).unwrap();
                assert!(rs.bitwise_eq(&r_lanes[k]), "attitude, trial {trial}, lane {k}");
                assert_eq!(
                    ps.to_array().map(f64::to_bits),
                    pi_lanes[k].to_array().map(f64::to_bits)
                );
            }
        }
        assert!(taken > 1500, "lanes took only {taken} of 2000 groups");
    }
}
