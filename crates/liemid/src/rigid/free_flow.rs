//! The exact torque-free flow of a rigid body, `(Π, R, h) ↦ (Π(h), R(h))`.
//!
//! In principal axes, `Π' = Π × Ω`, `Ω = I⁻¹ Π`, `R' = R hat(Ω)`; `|Π|`, the energy
//! `H = ½ Π·I⁻¹Π` and the spatial momentum `π = R Π` are constants.
//!
//! - **Symmetric bodies** (`I_a = I_b ≠ I_s`): `Π` turns about the symmetry axis `e_s` at
//!   `−λ`, `λ = Π_s (1/I_s − 1/I_a)`, and `R(h) = exp(h π/I_a) R exp(h λ e_s)` (a sphere
//!   has `λ = 0`).
//! - **Asymmetric bodies**: in axes `(1, 2, 3)` with 3 the axis the momentum circulates
//!   about (the largest moment when `|Π|²/2H > I_mid`, the smallest otherwise) and 2 the
//!   middle one, `Π = (A cn u, B sn u, C dn u)`, `u = u₀ + ω t`, `k² = r B²/C²`,
//!   `r = (a₁ − a₂)/(a₁ − a₃)`, `a_i = 1/I_i`, `ω = (a₁ − a₃) A C / B`; the attitude is
//!   `R(t) = R₀ B(n₀)ᵀ Rot₃(ψ) B(n(t))`, where `B(n)` turns `n = Π/|Π|` to `e₃` and the
//!   precession angle is
//!   `ψ = a₃ |Π| t + (B|Π|/(A C)) ΔΠ(ν; am u | k²) − A B ΔG`, with `ν = −r B²/A²`, `Π` the
//!   incomplete elliptic integral of the third kind and `G(φ) = ∫ dφ/(A² + r B² sin² φ)`
//!   (elementary). Jacobi functions by the arithmetic-geometric mean, `K`, `F` and `Π` by
//!   Carlson's `R_F` and `R_J` (the `ellip` crate); every branch (circulation about either
//!   extreme axis, the separatrix `k = 1`, steady rotation about a principal axis, `Π = 0`)
//!   is handled.
//!
//! A full inertia tensor is diagonalised once, when the flow is built.
//!
//! ## References
//! E. Celledoni, F. Fassò, N. Säfström, A. Zanna, *The exact computation of the free rigid
//! body motion and its use in splitting methods*, SIAM J. Sci. Comput. 30 (2008);
//! B. C. Carlson, *Numerical computation of real or complex elliptic integrals*, Numer.
//! Algorithms 10 (1995); M. Abramowitz, I. Stegun, *Handbook*, 16.4 (the AGM scheme).

use crate::error::Result;
use crate::inertia::Inertia;
use crate::linalg::symmetric_eigen;
use crate::linalg::{Mat3, Vec3};
use crate::so3;

/// The exact torque-free flow of one rigid body (its principal axes and moments).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeFlow {
    /// Principal moments.
    moments: [f64; 3],
    /// Principal axes (body frame) as a unit quaternion and its matrix, `None` when the
    /// tensor is diagonal.
    axes: Option<(so3::Quaternion, Mat3)>,
    shape: Shape,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Shape {
    /// Three equal moments.
    Sphere,
    /// Two equal moments: the index of the distinct (symmetry) axis.
    Symmetric(usize),
    /// Three distinct moments: indices of the smallest, middle and largest.
    Asymmetric([usize; 3]),
}

/// Moments equal to this relative difference are treated as equal (the symmetric closed
/// form is then exact to round-off for the body as given).
const EQUAL: f64 = 8.0 * f64::EPSILON;

/// The unit quaternion of the rotation vector `v`.
fn quaternion_of(v: Vec3) -> so3::Quaternion {
    let angle = v.norm();
    if angle == 0.0 {
        return so3::Quaternion::IDENTITY;
    }
    let (s, c) = (0.5 * angle).sin_cos();
    let k = s / angle;
    so3::Quaternion::new(c, v.x * k, v.y * k, v.z * k)
}

/// `matrix(q) − I` for a unit quaternion, without subtracting from 1 (so that it is
/// accurate relative to itself for rotations near the identity).
fn increment_of(q: &so3::Quaternion) -> Mat3 {
    let (w, x, y, z) = (q.w, q.x, q.y, q.z);
    Mat3::from_rows([
        [-2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), -2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), -2.0 * (x * x + y * y)],
    ])
}

impl FreeFlow {
    /// The flow of a body with inertia `inertia` (a full tensor is diagonalised here).
    ///
    /// # Errors
    /// A full tensor whose eigen decomposition does not converge (not expected for a
    /// symmetric positive definite matrix).
    pub fn new(inertia: &Inertia) -> Result<Self> {
        let (moments, axes) = match inertia.principal_moments() {
            Some(d) => (d.to_array(), None),
            None => {
                let (values, vectors) = symmetric_eigen(inertia.matrix())?;
                let q = so3::Quaternion::from_matrix(&vectors).normalized();
                (values, Some((q, q.to_matrix())))
            }
        };
        let eq = |x: f64, y: f64| (x - y).abs() <= EQUAL * x.max(y);
        let [a, b, c] = moments;
        let shape = match (eq(a, b), eq(b, c), eq(a, c)) {
            (true, true, _) | (true, _, true) | (_, true, true) => Shape::Sphere,
            (true, false, false) => Shape::Symmetric(2),
            (false, true, false) => Shape::Symmetric(0),
            (false, false, true) => Shape::Symmetric(1),
            (false, false, false) => {
                let mut order = [0, 1, 2];
                order.sort_by(|&i, &j| moments[i].total_cmp(&moments[j]));
                Shape::Asymmetric(order)
            }
        };
        Ok(FreeFlow { moments, axes, shape })
    }

    /// The principal moments (in the order of the principal axes).
    #[must_use]
    pub fn moments(&self) -> [f64; 3] {
        self.moments
    }

    /// The torque-free motion over `h` (any sign, any size) from `(Π, R)`.
    ///
    /// The attitude is updated in increment form, `R + R (exp(·) − I)`, from a unit
    /// quaternion of the body-frame turn, so that rounding is relative to the change and
    /// the result is a rotation to an ulp; `|Π|` is restored exactly.
    #[must_use]
    pub fn flow(&self, pi: Vec3, rotation: &Mat3, h: f64) -> (Vec3, Mat3) {
        if pi.norm_squared() == 0.0 || h == 0.0 {
            return (pi, *rotation);
        }
        let (p_end, turn) = match &self.axes {
            None => self.principal_flow(pi, h),
            Some((q, m)) => {
                // In principal axes: Qᵀ Π; the turn back in the body frame: Q t Qᵀ.
                let (p, turn) = self.principal_flow(m.tr_mul_vec(pi), h);
                let back = q.mul(&turn).mul(&so3::Quaternion::new(q.w, -q.x, -q.y, -q.z));
                (*m * p, back)
            }
        };
        let p_end = p_end * (pi.norm() / p_end.norm());
        let d = increment_of(&turn.normalized());
        (p_end, *rotation + *rotation * d)
    }

    /// `(Π(h), turn)` in principal axes, with `R(h) = R · matrix(turn)`.
    fn principal_flow(&self, pi: Vec3, h: f64) -> (Vec3, so3::Quaternion) {
        match self.shape {
            Shape::Sphere => {
                let i = (self.moments[0] + self.moments[1] + self.moments[2]) / 3.0;
                (pi, quaternion_of(pi * (h / i)))
            }
            Shape::Symmetric(s) => symmetric(self.moments[(s + 1) % 3], s, self.moments[s], pi, h),
            Shape::Asymmetric(order) => asymmetric(self.moments, order, pi, h),
        }
    }

    /// Fassò's symmetric + asymmetric splitting of the torque-free motion over `h`: an
    /// approximation of [`FreeFlow::flow`] that avoids the elliptic functions.
    ///
    /// With `a_i = 1/I_i` and `p` the extreme axis whose `a_p` is nearer the middle axis's
    /// `a_m`, `H = H_sym + ½ (a_m − a_p) Π_m²`, where `H_sym` is the energy of the symmetric
    /// body with `a_m` replaced by `a_p`. Both parts flow exactly: `H_sym` in closed form,
    /// the rest as a turn about the middle body axis at the constant rate `(a_m − a_p) Π_m`.
    /// Composed Strang-fashion (rest `h/2`, symmetric `h`, rest `h/2`): second order,
    /// symmetric, a Poisson map that keeps `|Π|` and `π = R Π` exactly; the energy error is
    /// `O(h²)` and vanishes with `a_m − a_p`. Symmetric bodies and spheres get the exact flow.
    ///
    /// Reference: F. Fassò, *Comparison of splitting algorithms for the rigid body*, J.
    /// Comput. Phys. 189 (2003).
    #[must_use]
    pub fn split_flow(&self, pi: Vec3, rotation: &Mat3, h: f64) -> (Vec3, Mat3) {
        let Shape::Asymmetric([lo, mid, hi]) = self.shape else {
            return self.flow(pi, rotation, h);
        };
        if pi.norm_squared() == 0.0 || h == 0.0 {
            return (pi, *rotation);
        }
        let m = &self.moments;
        let a = [1.0 / m[0], 1.0 / m[1], 1.0 / m[2]];
        let (partner, axis) = if (a[mid] - a[lo]).abs() <= (a[hi] - a[mid]).abs() {
            (lo, hi)
        } else {
            (hi, lo)
        };
        let rate = a[mid] - a[partner];
        let local = |p: Vec3| match &self.axes {
            None => p,
            Some((_, q)) => q.tr_mul_vec(p),
        };
        // The rest: Π_m is constant, the turn is about e_m by (h/2) (a_m − a_p) Π_m.
        let rest = |p: Vec3| {
            let mut v = [0.0; 3];
            v[mid] = 0.5 * h * rate * p.to_array()[mid];
            let v = Vec3::from_array(v);
            (so3::exp(v).tr_mul_vec(p), quaternion_of(v))
        };
        let p0 = local(pi);
        let (p1, q1) = rest(p0);
        let (p2, q2) = symmetric(m[partner], axis, m[axis], p1, h);
        let (p3, q3) = rest(p2);
        let mut turn = q1.mul(&q2).mul(&q3);
        let mut p_end = p3;
        if let Some((q, mat)) = &self.axes {
            turn = q.mul(&turn).mul(&so3::Quaternion::new(q.w, -q.x, -q.y, -q.z));
            p_end = *mat * p_end;
        }
        let p_end = p_end * (pi.norm() / p_end.norm());
        let d = increment_of(&turn.normalized());
        (p_end, *rotation + *rotation * d)
    }
}

/// The flow of a symmetric body (moments `I_a` about the two axes other than `s`, `I_s`
/// about `e_s`) in principal axes: `Π(h) = exp(h λ e_s)ᵀ Π` and the turn
/// `exp(h Π/I_a) exp(h λ e_s)`, `λ = Π_s (1/I_s − 1/I_a)`, because
/// `R(h) = exp(h π/I_a) R exp(h λ e_s) = R exp(h Π/I_a) exp(h λ e_s)`.
fn symmetric(ia: f64, s: usize, is: f64, pi: Vec3, h: f64) -> (Vec3, so3::Quaternion) {
    let lambda = pi.to_array()[s] * (1.0 / is - 1.0 / ia);
    let mut axis = [0.0; 3];
    axis[s] = h * lambda;
    let spin = quaternion_of(Vec3::from_array(axis));
    let turn = quaternion_of(pi * (h / ia)).mul(&spin);
    (so3::exp(Vec3::from_array(axis)).tr_mul_vec(pi), turn)
}

/// The asymmetric flow: choose the canonical axes, solve there, map back.
fn asymmetric(moments: [f64; 3], [lo, mid, hi]: [usize; 3], pi: Vec3, h: f64) -> (Vec3, so3::Quaternion) {
    let m = pi.to_array();
    let a = [1.0 / moments[0], 1.0 / moments[1], 1.0 / moments[2]];
    // 2H − a_mid |Π|² > 0: the momentum circulates about the smallest moment's axis.
    let excess = (a[lo] - a[mid]) * m[lo] * m[lo] + (a[hi] - a[mid]) * m[hi] * m[hi];
    let (other, circ) = if excess > 0.0 { (hi, lo) } else { (lo, hi) };
    let perm = [other, mid, circ];
    let parity = if matches!(perm, [0, 1, 2] | [1, 2, 0] | [2, 0, 1]) {
        1.0
    } else {
        -1.0
    };
    let s3 = if m[circ] < 0.0 { -1.0 } else { 1.0 };
    let signs = [s3 * parity, 1.0, s3];
    // P: canonical = P · principal, a signed permutation with det +1.
    let mut p = [[0.0; 3]; 3];
    for (row, (&axis, &sign)) in perm.iter().zip(&signs).enumerate() {
        p[row][axis] = sign;
    }
    let p = Mat3::from_rows(p);
    let ac = [a[other], a[mid], a[circ]];
    let (m1, turn) = canonical(ac, p * pi, h);
    // The turn in principal axes: Pᵀ t P.
    let pq = so3::Quaternion::from_matrix(&p).normalized();
    let back = so3::Quaternion::new(pq.w, -pq.x, -pq.y, -pq.z).mul(&turn).mul(&pq);
    (p.tr_mul_vec(m1), back)
}

/// The rotation `B(n)` taking the unit vector `n` (with `n₃ > −1`) to `e₃` about `n × e₃`,
/// as a unit quaternion: `cos(θ/2) = sqrt((1 + n₃)/2)`, `sin(θ/2) â = (n × e₃)/(2 cos(θ/2))`.
fn to_e3(n: Vec3) -> so3::Quaternion {
    let c = (0.5 * (1.0 + n.z)).sqrt();
    let s = 0.5 / c;
    so3::Quaternion::new(c, n.y * s, -n.x * s, 0.0).normalized()
}

/// The flow in canonical axes: 3 the circulation axis with `m₃ > 0`, 2 the middle axis.
fn canonical(a: [f64; 3], m: Vec3, h: f64) -> (Vec3, so3::Quaternion) {
    let (m1, m2, m3) = (m.x, m.y, m.z);
    let norm = m.norm();
    let r = (a[0] - a[1]) / (a[0] - a[2]);
    let aa = (m1 * m1 + (a[1] - a[2]) / (a[0] - a[2]) * m2 * m2).sqrt();
    let bb = ((a[0] - a[2]) / (a[1] - a[2]) * m1 * m1 + m2 * m2).sqrt();
    let cc = (m3 * m3 + r * m2 * m2).sqrt();
    if aa == 0.0 || bb == 0.0 {
        // Steady rotation about the circulation axis.
        return (m, quaternion_of(Vec3::new(0.0, 0.0, a[2] * m3 * h)));
    }
    if m1 == 0.0 && m3 == 0.0 {
        // The unstable equilibrium about the middle axis (on the separatrix, reached only
        // after infinite time).
        return (m, quaternion_of(Vec3::new(0.0, a[1] * m2 * h, 0.0)));
    }
    let k2 = (r * bb * bb / (cc * cc)).min(1.0);
    let omega = (a[0] - a[2]) * aa * cc / bb;
    let phi0 = (m2 / bb).atan2(m1 / aa);
    let ell = Elliptic::new(k2);
    let u1 = ell.f(phi0) + omega * h;
    let (sn, cn, dn, phi1) = ell.jacobi(u1);
    // |Π| is a Casimir: the end point is put back on its sphere (the elliptic functions
    // round it by a fraction of an ulp per call, with a bias near symmetry).
    let raw = Vec3::new(aa * cn, bb * sn, cc * dn);
    let n1 = raw * (1.0 / raw.norm());
    let m_end = n1 * norm;
    let nu = -r * bb * bb / (aa * aa);
    let d_pi = ell.pi3(nu, phi1) - ell.pi3(nu, phi0);
    let (ga, gb) = (aa * aa, r * bb * bb);
    let d_g = g_integral(ga, gb, phi1) - g_integral(ga, gb, phi0);
    let psi = a[2] * norm * h + bb * norm / (aa * cc) * d_pi - aa * bb * d_g;
    // Each direction divided by its own length, so that B(n) is orthogonal to round-off.
    let n0 = m * (1.0 / norm);
    // B(n₀)ᵀ Rot₃(ψ) B(n₁) as a product of unit quaternions, normalised once: a rotation to
    // an ulp whatever the rounding of n₀ and n₁ (the matrices B(n) are orthogonal only as
    // far as |n| = 1).
    let (sh, ch) = (0.5 * psi).sin_cos();
    let b0 = to_e3(n0);
    let turn = so3::Quaternion::new(b0.w, -b0.x, -b0.y, -b0.z)
        .mul(&so3::Quaternion::new(ch, 0.0, 0.0, sh))
        .mul(&to_e3(n1));
    (m_end, turn)
}

/// `∫₀^φ dθ / (a + b sin²θ)` for `a > 0`, `b ≥ 0`, continuous in `φ`.
fn g_integral(a: f64, b: f64, phi: f64) -> f64 {
    let j = (phi / std::f64::consts::PI).round();
    let rest = phi - j * std::f64::consts::PI;
    let s = (a * (a + b)).sqrt();
    (j * std::f64::consts::PI + (((a + b) / a).sqrt() * rest.tan()).atan()) / s
}

/// Elliptic functions and integrals of one parameter `m = k²` in `[0, 1]`.
struct Elliptic {
    m: f64,
    /// `K(m)`, infinite at `m = 1`.
    k: f64,
}

fn rf(x: f64, y: f64, z: f64) -> f64 {
    ellip::elliprf(x, y, z).unwrap_or(f64::NAN)
}

fn rj(x: f64, y: f64, z: f64, p: f64) -> f64 {
    ellip::elliprj(x, y, z, p).unwrap_or(f64::NAN)
}

impl Elliptic {
    fn new(m: f64) -> Self {
        let k = if m < 1.0 { rf(0.0, 1.0 - m, 1.0) } else { f64::INFINITY };
        Elliptic { m, k }
    }

    /// `F(φ | m)`, continuous in `φ` (`F(φ + jπ) = F(φ) + 2jK`).
    fn f(&self, phi: f64) -> f64 {
        let (j, rest) = split(phi);
        let (s, c) = rest.sin_cos();
        let base = s * rf(c * c, 1.0 - self.m * s * s, 1.0);
        if j == 0.0 {
            base
        } else {
            2.0 * j * self.k + base
        }
    }

    /// `Π(ν; φ | m)` for `ν ≤ 0`, continuous in `φ`.
    fn pi3(&self, nu: f64, phi: f64) -> f64 {
        let (j, rest) = split(phi);
        let (s, c) = rest.sin_cos();
        let y = 1.0 - self.m * s * s;
        let base = s * rf(c * c, y, 1.0) + nu / 3.0 * s * s * s * rj(c * c, y, 1.0, 1.0 - nu * s * s);
        if j == 0.0 {
            base
        } else {
            let complete = self.k + nu / 3.0 * rj(0.0, 1.0 - self.m, 1.0, 1.0 - nu);
            2.0 * j * complete + base
        }
    }

    /// `(sn, cn, dn, am)` at `u` (`am` continuous).
    fn jacobi(&self, u: f64) -> (f64, f64, f64, f64) {
        if self.k.is_infinite() {
            // The separatrix: sn = tanh, cn = dn = sech, am = gd(u).
            let (sn, sech) = (u.tanh(), 1.0 / u.cosh());
            return (sn, sech, sech, sn.atan2(sech));
        }
        let period = 2.0 * self.k;
        let j = (u / period).round();
        let rest = u - j * period;
        let (sn, cn, dn, am) = jacobi_agm(rest, self.m);
        let sign = if (j as i64).rem_euclid(2) == 0 { 1.0 } else { -1.0 };
        (sign * sn, sign * cn, dn, j * std::f64::consts::PI + am)
    }
}

/// `φ = jπ + rest` with `rest ∈ [−π/2, π/2]`.
fn split(phi: f64) -> (f64, f64) {
    let j = (phi / std::f64::consts::PI).round();
    (j, phi - j * std::f64::consts::PI)
}

/// `(sn, cn, dn, am)` for `|u| ≤ K(m)`, `0 ≤ m < 1`, by the descending arithmetic-geometric
/// mean (Abramowitz and Stegun 16.4).
fn jacobi_agm(u: f64, m: f64) -> (f64, f64, f64, f64) {
    if m < 1e-300 {
        let (s, c) = u.sin_cos();
        return (s, c, 1.0, u);
    }
    let mut a = [0.0f64; 16];
    let mut c = [0.0f64; 16];
    a[0] = 1.0;
    let mut b = (1.0 - m).sqrt();
    c[0] = m.sqrt();
    let mut n = 0;
    while n < 15 && c[n].abs() > f64::EPSILON * a[n] {
        a[n + 1] = 0.5 * (a[n] + b);
        c[n + 1] = 0.5 * (a[n] - b);
        b = (a[n] * b).sqrt();
        n += 1;
    }
    let mut phi = (1u64 << n) as f64 * a[n] * u;
    for i in (1..=n).rev() {
        phi = 0.5 * (phi + (c[i] / a[i] * phi.sin()).asin());
    }
    let (s, co) = phi.sin_cos();
    // dn² = 1 − m sn² = cn² + (1 − m) sn²: a sum of positive terms, no cancellation.
    let dn = (co * co + (1.0 - m) * s * s).sqrt();
    (s, co, dn, phi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_functions_satisfy_their_identities() {
        for m in [0.0, 1e-8, 0.3, 0.9, 0.999999] {
            let e = Elliptic::new(m);
            for u in [-7.3, -1.0, 0.0, 0.4, 2.5, 30.0] {
                let (sn, cn, dn, am) = e.jacobi(u);
                // Each function to an ulp or two; the identities to a few ulps of 1.
                assert!((sn * sn + cn * cn - 1.0).abs() < 4.0 * f64::EPSILON, "m {m} u {u}");
                assert!((dn * dn + m * sn * sn - 1.0).abs() < 4.0 * f64::EPSILON, "m {m} u {u}");
                // am carries the rounding of its own size.
                let tol = 4.0 * f64::EPSILON * am.abs().max(1.0);
                assert!(
                    (am.sin() - sn).abs() < tol && (am.cos() - cn).abs() < tol,
                    "m {m} u {u}"
                );
                // F(am(u)) = u: the error of am, (F(am) − u) dn, to 1e-14 (F's slope 1/dn
                // reaches 1/sqrt(1 − m) = 1000 near the separatrix).
                let backward = (e.f(am) - u) * dn;
                assert!(backward.abs() < 1e-14 * u.abs().max(1.0), "m {m} u {u}: {backward:e}");
            }
        }
    }

    #[test]
    fn full_tensors_are_diagonalised_into_a_rotation() {
        let r = so3::exp(Vec3::new(0.4, -0.3, 0.8));
        let m = r * Mat3::from_diagonal(Vec3::new(1.0, 2.0, 2.5)) * r.transpose();
        let (values, q) = symmetric_eigen(&m).unwrap();
        assert!((q.determinant() - 1.0).abs() < 1e-14);
        let back = q * Mat3::from_diagonal(Vec3::from_array(values)) * q.transpose();
        assert!((back - m).max_abs() < 1e-14);
    }
}
