//! The exact tangent stiffness of the corotational element, by forward-mode automatic
//! differentiation of [`super::element::end_forces`] (dual numbers).
//!
//! The element's forces depend on the chord `d = x_b − x_a` and the end triads
//! `T = R exp(ε̂) C` (body-frame rotation increments `ε`, as Newmark updates
//! `R ← R exp(δθ)`); the generalised forces are the spatial forces and the body-frame
//! moments `(R exp(ε̂))ᵀ M`. Every quantity carries its value and its derivatives along the
//! nine directions `(δd, ε_a, ε_b)`; `∂/∂x_a = −∂/∂d`, `∂/∂x_b = ∂/∂d`. The same arithmetic
//! as the forces (the local logarithm's series below `|sin θ| = 0.01`, the inverse Jacobian's
//! series below `θ = 0.1`), so the tangent is the derivative of the computed forces to
//! round-off, where central differences (24 evaluations) carry an `O(ε²)` truncation and an
//! `O(u/ε)` rounding error.
//!
//! ## Reference
//! A. Griewank, A. Walther, *Evaluating Derivatives*, 2nd ed., SIAM (2008), chapter 3;
//! M. A. Crisfield, Comput. Methods Appl. Mech. Engrg. 81 (1990) (the element).

// Dual arithmetic reads as the formulas with the derivative index spelled out.
#![allow(clippy::needless_range_loop)]

use std::ops::{Add, Div, Mul, Neg, Sub};

use super::element::ElementStiffness;
use crate::linalg::{Mat3, Vec3};

/// Directions of the derivatives: the chord (3), the rotation of end a (3), of end b (3).
const N: usize = 9;

/// A number with its derivatives along [`N`] directions.
#[derive(Clone, Copy, Debug)]
struct D {
    v: f64,
    d: [f64; N],
}

impl D {
    const ZERO: D = D { v: 0.0, d: [0.0; N] };
    fn c(v: f64) -> D {
        D { v, d: [0.0; N] }
    }
    fn var(v: f64, k: usize) -> D {
        let mut d = [0.0; N];
        d[k] = 1.0;
        D { v, d }
    }
    /// `f(self)` with `f' = df`.
    #[inline]
    fn chain(self, v: f64, df: f64) -> D {
        let mut d = self.d;
        d.iter_mut().for_each(|x| *x *= df);
        D { v, d }
    }
    fn sqrt(self) -> D {
        let r = self.v.sqrt();
        self.chain(r, 0.5 / r)
    }
    fn sin_cos(self) -> (D, D) {
        let (s, c) = self.v.sin_cos();
        (self.chain(s, c), self.chain(c, -s))
    }
    fn atan2(self, x: D) -> D {
        // d atan2(y, x) = (x dy − y dx)/(x² + y²)
        let r2 = self.v * self.v + x.v * x.v;
        let mut d = [0.0; N];
        for k in 0..N {
            d[k] = (x.v * self.d[k] - self.v * x.d[k]) / r2;
        }
        D {
            v: self.v.atan2(x.v),
            d,
        }
    }
}

impl Add for D {
    type Output = D;
    #[inline]
    fn add(self, o: D) -> D {
        let mut d = self.d;
        for k in 0..N {
            d[k] += o.d[k];
        }
        D { v: self.v + o.v, d }
    }
}
impl Sub for D {
    type Output = D;
    #[inline]
    fn sub(self, o: D) -> D {
        let mut d = self.d;
        for k in 0..N {
            d[k] -= o.d[k];
        }
        D { v: self.v - o.v, d }
    }
}
impl Neg for D {
    type Output = D;
    #[inline]
    fn neg(self) -> D {
        self.chain(-self.v, -1.0)
    }
}
impl Mul for D {
    type Output = D;
    #[inline]
    fn mul(self, o: D) -> D {
        let mut d = [0.0; N];
        for k in 0..N {
            d[k] = self.v * o.d[k] + o.v * self.d[k];
        }
        D { v: self.v * o.v, d }
    }
}
impl Mul<f64> for D {
    type Output = D;
    #[inline]
    fn mul(self, o: f64) -> D {
        self.chain(self.v * o, o)
    }
}
impl Div for D {
    type Output = D;
    #[inline]
    fn div(self, o: D) -> D {
        let inv = 1.0 / o.v;
        let q = self.v * inv;
        let mut d = [0.0; N];
        for k in 0..N {
            d[k] = (self.d[k] - q * o.d[k]) * inv;
        }
        D { v: q, d }
    }
}

/// A 3-vector of duals.
#[derive(Clone, Copy, Debug)]
struct V([D; 3]);

impl V {
    fn dot(self, o: V) -> D {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    fn cross(self, o: V) -> V {
        let (a, b) = (self.0, o.0);
        V([
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ])
    }
    fn scale(self, s: D) -> V {
        V(self.0.map(|x| x * s))
    }
    fn scale_f(self, s: f64) -> V {
        V(self.0.map(|x| x * s))
    }
    fn add(self, o: V) -> V {
        V([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
    fn sub(self, o: V) -> V {
        V([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}

/// A 3x3 matrix of duals, row-major.
#[derive(Clone, Copy, Debug)]
struct M([[D; 3]; 3]);

impl M {
    fn c(a: &Mat3) -> M {
        M(a.m.map(|r| r.map(D::c)))
    }
    fn mul(&self, o: &M) -> M {
        let mut r = [[D::ZERO; 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = self.0[i][0] * o.0[0][j] + self.0[i][1] * o.0[1][j] + self.0[i][2] * o.0[2][j];
            }
        }
        M(r)
    }
    fn tr_mul(&self, o: &M) -> M {
        let mut r = [[D::ZERO; 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = self.0[0][i] * o.0[0][j] + self.0[1][i] * o.0[1][j] + self.0[2][i] * o.0[2][j];
            }
        }
        M(r)
    }
    fn apply(&self, v: V) -> V {
        V([0, 1, 2].map(|i| self.0[i][0] * v.0[0] + self.0[i][1] * v.0[1] + self.0[i][2] * v.0[2]))
    }
    fn tr_apply(&self, v: V) -> V {
        V([0, 1, 2].map(|i| self.0[0][i] * v.0[0] + self.0[1][i] * v.0[1] + self.0[2][i] * v.0[2]))
    }
    fn col(&self, j: usize) -> V {
        V([self.0[0][j], self.0[1][j], self.0[2][j]])
    }
    fn from_columns(a: V, b: V, c: V) -> M {
        M([0, 1, 2].map(|i| [a.0[i], b.0[i], c.0[i]]))
    }
    fn trace(&self) -> D {
        self.0[0][0] + self.0[1][1] + self.0[2][2]
    }
    fn vee(&self) -> V {
        let m = &self.0;
        V([
            (m[2][1] - m[1][2]) * 0.5,
            (m[0][2] - m[2][0]) * 0.5,
            (m[1][0] - m[0][1]) * 0.5,
        ])
    }
}

/// `R exp(ε̂) C` to first order in `ε` (exact derivatives at `ε = 0`): `R (I + ε̂) C`, with
/// `ε` the directions `first..first + 3`.
fn perturbed(r: &Mat3, c: &Mat3, first: usize) -> M {
    let e = [0, 1, 2].map(|k| D::var(0.0, first + k));
    let one = D::c(1.0);
    let hat = M([[one, -e[2], e[1]], [e[2], one, -e[0]], [-e[1], e[0], one]]);
    M::c(r).mul(&hat).mul(&M::c(c))
}

/// [`super::element`]'s `local_log` in duals.
fn local_log(q: &M) -> V {
    let w = q.vee();
    let s2 = w.dot(w);
    let tr = q.trace();
    if s2.v < 1e-2 && tr.v > 1.0 {
        let f = D::c(1.0)
            + s2 * (D::c(1.0 / 6.0)
                + s2 * (D::c(3.0 / 40.0)
                    + s2 * (D::c(5.0 / 112.0)
                        + s2 * (D::c(35.0 / 1152.0)
                            + s2 * (D::c(63.0 / 2816.0)
                                + s2 * (D::c(231.0 / 13312.0)
                                    + s2 * (D::c(143.0 / 10240.0) + s2 * (6435.0 / 557_056.0))))))));
        w.scale(f)
    } else {
        let s = s2.sqrt();
        let c = (tr - D::c(1.0)) * 0.5;
        let theta = s.atan2(c);
        w.scale(theta / s)
    }
}

/// `Jr⁻¹(v) x = x + ½ v × x + c(θ) v × (v × x)` in duals (the series of `so3` below 0.1).
fn right_jacobian_inverse_apply(v: V, x: V) -> V {
    let t2 = v.dot(v);
    let c = if t2.v.sqrt() < 0.1 {
        D::c(1.0 / 12.0)
            + t2 * (D::c(1.0 / 720.0)
                + t2 * (D::c(1.0 / 30_240.0) + t2 * (D::c(1.0 / 1_209_600.0) + t2 * (1.0 / 47_900_160.0))))
    } else {
        let theta = t2.sqrt();
        let (s, co) = theta.sin_cos();
        D::c(1.0) / t2 - (D::c(1.0) + co) / (theta * s * 2.0)
    };
    let vx = v.cross(x);
    x.add(vx.scale_f(0.5)).add(v.cross(vx).scale(c))
}

/// The element's generalised forces `(F_a, T_a, F_b, T_b)` (spatial forces, body-frame
/// moments) in duals.
fn generalised_forces(k: &ElementStiffness, d0: Vec3, ra: &Mat3, ca: &Mat3, rb: &Mat3, cb: &Mat3) -> [V; 4] {
    let d = V([D::var(d0.x, 0), D::var(d0.y, 1), D::var(d0.z, 2)]);
    let ta = perturbed(ra, ca, 3);
    let tb = perturbed(rb, cb, 6);
    let l = d.dot(d).sqrt();
    let e1 = d.scale(D::c(1.0) / l);
    let q = ta.col(1).add(tb.col(1)).scale_f(0.5);
    let n3 = e1.cross(q);
    let e3 = n3.scale(D::c(1.0) / n3.dot(n3).sqrt());
    let e2 = e3.cross(e1);
    let frame = M::from_columns(e1, e2, e3);
    let theta_a = local_log(&frame.tr_mul(&ta));
    let theta_b = local_log(&frame.tr_mul(&tb));
    let (a, b) = (theta_a.0, theta_b.0);
    let torsion = (b[0] - a[0]) * k.torsion;
    let ma = V([
        -torsion,
        (a[1] * 4.0 + b[1] * 2.0) * k.bending2,
        (a[2] * 4.0 + b[2] * 2.0) * k.bending3,
    ]);
    let mb = V([
        torsion,
        (a[1] * 2.0 + b[1] * 4.0) * k.bending2,
        (a[2] * 2.0 + b[2] * 4.0) * k.bending3,
    ]);
    let sa = frame.apply(right_jacobian_inverse_apply(theta_a, ma));
    let sb = frame.apply(right_jacobian_inverse_apply(theta_b, mb));
    let sum = sa.add(sb);
    let (s1, s2, s3) = (sum.dot(e1), sum.dot(e2), sum.dot(e3));
    let (q1, q2) = (q.dot(e1), q.dot(e2));
    let axial = (l - D::c(k.length)) * k.axial;
    let g = e1
        .scale(axial)
        .add(e3.scale((s2 + s1 * q1 / q2) / l))
        .sub(e2.scale(s3 / l));
    let c = s1 / (q2 * 2.0);
    let tau_a = sa.sub(ta.col(1).cross(e3).scale(c));
    let tau_b = sb.sub(tb.col(1).cross(e3).scale(c));
    // Body-frame moments: (R (I + ε̂))ᵀ (−τ).
    let body = |r: &Mat3, first: usize, m: V| {
        let e = [0, 1, 2].map(|k| D::var(0.0, first + k));
        let one = D::c(1.0);
        let hat_t = M([[one, e[2], -e[1]], [-e[2], one, e[0]], [e[1], -e[0], one]]);
        hat_t.apply(M::c(r).tr_apply(m))
    };
    let zero = V([D::ZERO; 3]);
    [
        g,
        body(ra, 3, zero.sub(tau_a)),
        zero.sub(g),
        body(rb, 6, zero.sub(tau_b)),
    ]
}

/// The element's tangent stiffness `K = −∂Q/∂q` (12 x 12, row-major), rows and columns
/// ordered `(x_a, θ_a, x_b, θ_b)` with `θ` the body-frame rotation increments of the nodes
/// (`R ← R exp(θ̂)`), at node poses `(xa, ra)`, `(xb, rb)` and with the element's constant
/// maps `ca`, `cb` from the nodes' body axes to its initial axes.
#[must_use]
#[allow(clippy::too_many_arguments)]
pub fn element_tangent(
    k: &ElementStiffness,
    xa: Vec3,
    xb: Vec3,
    ra: &Mat3,
    rb: &Mat3,
    ca: &Mat3,
    cb: &Mat3,
) -> [[f64; 12]; 12] {
    let q = generalised_forces(k, xb - xa, ra, ca, rb, cb);
    let mut kt = [[0.0; 12]; 12];
    for (block, v) in q.iter().enumerate() {
        for (r, x) in v.0.iter().enumerate() {
            let row = &mut kt[3 * block + r];
            for c in 0..3 {
                // x_a moves the chord by −δ, x_b by +δ.
                row[c] = x.d[c];
                row[6 + c] = -x.d[c];
                row[3 + c] = -x.d[3 + c];
                row[9 + c] = -x.d[6 + c];
            }
        }
    }
    kt
}

/// The generalised forces' values (for tests: they equal [`super::element::end_forces`]
/// with body-frame moments).
#[must_use]
pub fn generalised_force_values(
    k: &ElementStiffness,
    xa: Vec3,
    xb: Vec3,
    ra: &Mat3,
    rb: &Mat3,
    ca: &Mat3,
    cb: &Mat3,
) -> [Vec3; 4] {
    generalised_forces(k, xb - xa, ra, ca, rb, cb).map(|v| Vec3::new(v.0[0].v, v.0[1].v, v.0[2].v))
}
