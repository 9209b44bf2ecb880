//! Small fixed-size linear algebra: 3-vectors and 3x3 matrices on the stack.
//!
//! Everything here is `Copy`, allocation free and written out component by component, so
//! the stepping kernels compile to straight-line floating-point code.

use core::ops::{Add, AddAssign, Index, IndexMut, Mul, Neg, Sub, SubAssign};

use crate::error::{Error, Result};

/// A 3-vector of `f64`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec3 {
    /// First component.
    pub x: f64,
    /// Second component.
    pub y: f64,
    /// Third component.
    pub z: f64,
}

impl Vec3 {
    /// The zero vector.
    pub const ZERO: Vec3 = Vec3::new(0.0, 0.0, 0.0);

    /// A vector from its components.
    #[must_use]
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Vec3 { x, y, z }
    }

    /// A vector from an array `[x, y, z]`.
    #[must_use]
    pub const fn from_array(a: [f64; 3]) -> Self {
        Vec3::new(a[0], a[1], a[2])
    }

    /// The components as an array `[x, y, z]`.
    #[must_use]
    pub const fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }

    /// `*v`, read as three separate 8-byte loads.
    ///
    /// For vectors that a step reads right after the previous step stored them (the state's
    /// momentum, the cached torque). A plain copy may read two components with one 16-byte
    /// load that straddles two earlier stores (one of `x`, one of `(y, z)`), which the
    /// processor cannot forward from its store buffer: the load waits until both stores
    /// complete, on the critical path of the step. Timed through the integrator API on the
    /// fast top, LIEMID\[EA\] took 168-170 ns per step without this and 156 ns with it.
    #[must_use]
    #[inline(always)]
    pub(crate) fn load_split(v: &Vec3) -> Vec3 {
        // SAFETY: `v` is a valid, aligned reference, so each of its fields may be read.
        unsafe {
            Vec3::new(
                core::ptr::read_volatile(&v.x),
                core::ptr::read_volatile(&v.y),
                core::ptr::read_volatile(&v.z),
            )
        }
    }

    /// Dot product `a · b`.
    #[must_use]
    #[inline]
    pub fn dot(self, b: Vec3) -> f64 {
        self.x * b.x + self.y * b.y + self.z * b.z
    }

    /// Cross product `a × b`.
    #[must_use]
    #[inline]
    pub fn cross(self, b: Vec3) -> Vec3 {
        Vec3::new(
            self.y * b.z - self.z * b.y,
            self.z * b.x - self.x * b.z,
            self.x * b.y - self.y * b.x,
        )
    }

    /// Squared Euclidean norm.
    #[must_use]
    #[inline]
    pub fn norm_squared(self) -> f64 {
        self.dot(self)
    }

    /// Euclidean norm.
    #[must_use]
    #[inline]
    pub fn norm(self) -> f64 {
        self.norm_squared().sqrt()
    }

    /// Largest absolute component.
    #[must_use]
    pub fn max_abs(self) -> f64 {
        self.x.abs().max(self.y.abs()).max(self.z.abs())
    }

    /// True when every component is finite.
    #[must_use]
    #[inline]
    #[allow(clippy::eq_op)] // `v − v` is the point: 0 for finite `v`, NaN otherwise.
    pub fn is_finite(self) -> bool {
        // `v − v` is 0 for a finite `v` and NaN otherwise: one branch for all components.
        ((self.x - self.x) + (self.y - self.y) + (self.z - self.z)) == 0.0
    }

    /// Componentwise product.
    #[must_use]
    #[inline]
    pub fn component_mul(self, b: Vec3) -> Vec3 {
        Vec3::new(self.x * b.x, self.y * b.y, self.z * b.z)
    }
}

impl Index<usize> for Vec3 {
    type Output = f64;
    fn index(&self, i: usize) -> &f64 {
        match i {
            0 => &self.x,
            1 => &self.y,
            2 => &self.z,
            _ => panic!("Vec3 index {i} out of range"),
        }
    }
}

impl IndexMut<usize> for Vec3 {
    fn index_mut(&mut self, i: usize) -> &mut f64 {
        match i {
            0 => &mut self.x,
            1 => &mut self.y,
            2 => &mut self.z,
            _ => panic!("Vec3 index {i} out of range"),
        }
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    #[inline]
    fn add(self, b: Vec3) -> Vec3 {
        Vec3::new(self.x + b.x, self.y + b.y, self.z + b.z)
    }
}

impl AddAssign for Vec3 {
    #[inline]
    fn add_assign(&mut self, b: Vec3) {
        *self = *self + b;
    }
}

impl Sub for Vec3 {
    type Output = Vec3;
    #[inline]
    fn sub(self, b: Vec3) -> Vec3 {
        Vec3::new(self.x - b.x, self.y - b.y, self.z - b.z)
    }
}

impl SubAssign for Vec3 {
    #[inline]
    fn sub_assign(&mut self, b: Vec3) {
        *self = *self - b;
    }
}

impl Neg for Vec3 {
    type Output = Vec3;
    #[inline]
    fn neg(self) -> Vec3 {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}

impl Mul<f64> for Vec3 {
    type Output = Vec3;
    #[inline]
    fn mul(self, s: f64) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Mul<Vec3> for f64 {
    type Output = Vec3;
    #[inline]
    fn mul(self, v: Vec3) -> Vec3 {
        v * self
    }
}

/// A 3x3 matrix of `f64`, stored row-major: `m[i][j]` is row `i`, column `j`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mat3 {
    /// Rows of the matrix.
    pub m: [[f64; 3]; 3],
}

impl Mat3 {
    /// The identity matrix.
    pub const IDENTITY: Mat3 = Mat3 {
        m: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    };
    /// The zero matrix.
    pub const ZERO: Mat3 = Mat3 { m: [[0.0; 3]; 3] };

    /// A matrix from its rows.
    #[must_use]
    pub const fn from_rows(m: [[f64; 3]; 3]) -> Self {
        Mat3 { m }
    }

    /// A matrix from 9 entries in row-major order.
    #[must_use]
    pub const fn from_row_major(a: [f64; 9]) -> Self {
        Mat3 {
            m: [[a[0], a[1], a[2]], [a[3], a[4], a[5]], [a[6], a[7], a[8]]],
        }
    }

    /// The 9 entries in row-major order.
    #[must_use]
    pub const fn to_row_major(&self) -> [f64; 9] {
        let m = &self.m;
        [
            m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2], m[2][0], m[2][1], m[2][2],
        ]
    }

    /// A diagonal matrix.
    #[must_use]
    pub const fn from_diagonal(d: Vec3) -> Self {
        Mat3 {
            m: [[d.x, 0.0, 0.0], [0.0, d.y, 0.0], [0.0, 0.0, d.z]],
        }
    }

    /// The outer product `a bᵀ`.
    #[must_use]
    pub fn outer(a: Vec3, b: Vec3) -> Self {
        Mat3::from_rows([
            [a.x * b.x, a.x * b.y, a.x * b.z],
            [a.y * b.x, a.y * b.y, a.y * b.z],
            [a.z * b.x, a.z * b.y, a.z * b.z],
        ])
    }

    /// Row `i`.
    #[must_use]
    #[inline]
    pub fn row(&self, i: usize) -> Vec3 {
        Vec3::from_array(self.m[i])
    }

    /// Column `j`.
    #[must_use]
    #[inline]
    pub fn col(&self, j: usize) -> Vec3 {
        Vec3::new(self.m[0][j], self.m[1][j], self.m[2][j])
    }

    /// The transpose.
    #[must_use]
    #[inline]
    pub fn transpose(&self) -> Mat3 {
        let m = &self.m;
        Mat3::from_rows([
            [m[0][0], m[1][0], m[2][0]],
            [m[0][1], m[1][1], m[2][1]],
            [m[0][2], m[1][2], m[2][2]],
        ])
    }

    /// `Aᵀ v`, without forming the transpose.
    #[must_use]
    #[inline]
    pub fn tr_mul_vec(&self, v: Vec3) -> Vec3 {
        self.row(0) * v.x + self.row(1) * v.y + self.row(2) * v.z
    }

    /// The trace.
    #[must_use]
    pub fn trace(&self) -> f64 {
        self.m[0][0] + self.m[1][1] + self.m[2][2]
    }

    /// The determinant.
    #[must_use]
    pub fn determinant(&self) -> f64 {
        self.row(0).dot(self.row(1).cross(self.row(2)))
    }

    /// The inverse by the adjugate, or `None` when the matrix is singular (determinant 0
    /// or not finite).
    #[must_use]
    pub fn inverse(&self) -> Option<Mat3> {
        let (r0, r1, r2) = (self.row(0), self.row(1), self.row(2));
        let c0 = r1.cross(r2);
        let c1 = r2.cross(r0);
        let c2 = r0.cross(r1);
        let det = r0.dot(c0);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv_det = 1.0 / det;
        // The inverse's columns are the cross products divided by the determinant.
        Some(Mat3::from_rows([[c0.x, c1.x, c2.x], [c0.y, c1.y, c2.y], [c0.z, c1.z, c2.z]]) * inv_det)
    }

    /// Solve `A x = b` by the adjugate (Cramer's rule): branch-free and fast for the
    /// well-conditioned matrices of Newton iterations; `None` when `A` is singular.
    #[must_use]
    #[inline]
    pub fn solve_adjugate(&self, b: Vec3) -> Option<Vec3> {
        let (r0, r1, r2) = (self.row(0), self.row(1), self.row(2));
        let c0 = r1.cross(r2);
        let det = r0.dot(c0);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let x = c0 * b.x + r2.cross(r0) * b.y + r0.cross(r1) * b.z;
        Some(x * (1.0 / det))
    }

    /// Solve `A x = b` by Gaussian elimination with partial pivoting; `None` when `A` is
    /// singular to working precision.
    #[must_use]
    pub fn solve(&self, b: Vec3) -> Option<Vec3> {
        let mut a = self.m;
        let mut r = b.to_array();
        for k in 0..3 {
            let mut p = k;
            for i in (k + 1)..3 {
                if a[i][k].abs() > a[p][k].abs() {
                    p = i;
                }
            }
            if a[p][k] == 0.0 || !a[p][k].is_finite() {
                return None;
            }
            a.swap(k, p);
            r.swap(k, p);
            let inv = 1.0 / a[k][k];
            let pivot_row = a[k];
            for i in (k + 1)..3 {
                let f = a[i][k] * inv;
                for (aij, akj) in a[i].iter_mut().zip(pivot_row.iter()).skip(k) {
                    *aij -= f * akj;
                }
                r[i] -= f * r[k];
            }
        }
        let z = r[2] / a[2][2];
        let y = (r[1] - a[1][2] * z) / a[1][1];
        let x = (r[0] - a[0][1] * y - a[0][2] * z) / a[0][0];
        Some(Vec3::new(x, y, z))
    }

    /// Frobenius norm `‖A‖_F`.
    #[must_use]
    pub fn norm_frobenius(&self) -> f64 {
        self.m.iter().flatten().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// Largest absolute entry.
    #[must_use]
    pub fn max_abs(&self) -> f64 {
        self.m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()))
    }

    /// True when every entry is finite.
    #[must_use]
    #[inline]
    #[allow(clippy::eq_op)] // `v − v` is the point: 0 for finite `v`, NaN otherwise.
    pub fn is_finite(&self) -> bool {
        // `v − v` is 0 for a finite `v` and NaN otherwise: one branch for all entries.
        self.m.iter().flatten().fold(0.0, |acc, v| acc + (v - v)) == 0.0
    }

    /// True when `self` and `other` are the same bit for bit (unlike `==`, which treats
    /// `0.0` and `−0.0` as equal and NaN as unequal).
    #[must_use]
    #[inline]
    pub fn bitwise_eq(&self, other: &Mat3) -> bool {
        let diff = self
            .m
            .iter()
            .flatten()
            .zip(other.m.iter().flatten())
            .fold(0u64, |acc, (a, b)| acc | (a.to_bits() ^ b.to_bits()));
        diff == 0
    }
}

impl Index<(usize, usize)> for Mat3 {
    type Output = f64;
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        &self.m[i][j]
    }
}

impl Add for Mat3 {
    type Output = Mat3;
    #[inline]
    fn add(self, b: Mat3) -> Mat3 {
        let mut r = self;
        for i in 0..3 {
            for j in 0..3 {
                r.m[i][j] += b.m[i][j];
            }
        }
        r
    }
}

impl Sub for Mat3 {
    type Output = Mat3;
    #[inline]
    fn sub(self, b: Mat3) -> Mat3 {
        let mut r = self;
        for i in 0..3 {
            for j in 0..3 {
                r.m[i][j] -= b.m[i][j];
            }
        }
        r
    }
}

impl Mul<f64> for Mat3 {
    type Output = Mat3;
    #[inline]
    fn mul(self, s: f64) -> Mat3 {
        let mut r = self;
        for row in r.m.iter_mut() {
            for v in row.iter_mut() {
                *v *= s;
            }
        }
        r
    }
}

impl Mul<Vec3> for Mat3 {
    type Output = Vec3;
    #[inline]
    fn mul(self, v: Vec3) -> Vec3 {
        Vec3::new(self.row(0).dot(v), self.row(1).dot(v), self.row(2).dot(v))
    }
}

impl Mul<Vec3> for &Mat3 {
    type Output = Vec3;
    #[inline]
    fn mul(self, v: Vec3) -> Vec3 {
        *self * v
    }
}

impl Mul for Mat3 {
    type Output = Mat3;
    #[inline]
    fn mul(self, b: Mat3) -> Mat3 {
        let mut r = Mat3::ZERO;
        for i in 0..3 {
            for j in 0..3 {
                r.m[i][j] = self.m[i][0] * b.m[0][j] + self.m[i][1] * b.m[1][j] + self.m[i][2] * b.m[2][j];
            }
        }
        r
    }
}

/// Eigenvalues and eigenvectors (columns, a rotation) of a symmetric 3x3 matrix by cyclic
/// Jacobi rotations.
pub(crate) fn symmetric_eigen(m: &Mat3) -> Result<([f64; 3], Mat3)> {
    let mut a = m.m;
    let mut v = Mat3::IDENTITY.m;
    for _sweep in 0..50 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let scale = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= 1e-34 * scale {
            let mut vectors = Mat3::from_rows(v);
            let values = [a[0][0], a[1][1], a[2][2]];
            if vectors.determinant() < 0.0 {
                for row in &mut vectors.m {
                    row[2] = -row[2];
                }
            }
            return Ok((values, vectors));
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut a {
                let (x, y) = (row[p], row[q]);
                row[p] = c * x - s * y;
                row[q] = s * x + c * y;
            }
            let (row_p, row_q) = (a[p], a[q]);
            for (k, (x, y)) in row_p.into_iter().zip(row_q).enumerate() {
                a[p][k] = c * x - s * y;
                a[q][k] = s * x + c * y;
            }
            for row in &mut v {
                let (x, y) = (row[p], row[q]);
                row[p] = c * x - s * y;
                row[q] = s * x + c * y;
            }
        }
    }
    Err(Error::InvalidInertia {
        reason: "the eigen decomposition did not converge".into(),
    })
}

/// Cholesky factorization `A = L Lᵀ` in place of the lower triangle of `a` (`n × n`,
/// row-major; the upper triangle is left as it was and never read). On failure, the pivot's
/// index and value (not positive, or not finite).
///
/// Reference: G. H. Golub, C. F. Van Loan, "Matrix Computations" (4th ed., 2013), §4.2.
pub(crate) fn cholesky_in_place(a: &mut [f64], n: usize) -> core::result::Result<(), (usize, f64)> {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return Err((j, d));
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut v = a[i * n + j];
            for k in 0..j {
                v -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = v / d;
        }
    }
    Ok(())
}

/// `x ← (L Lᵀ)⁻¹ x` with the factor of [`cholesky_in_place`] (forward, then back
/// substitution).
pub(crate) fn cholesky_solve(l: &[f64], n: usize, x: &mut [f64]) {
    for i in 0..n {
        let mut v = x[i];
        for k in 0..i {
            v -= l[i * n + k] * x[k];
        }
        x[i] = v / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut v = x[i];
        for k in i + 1..n {
            v -= l[k * n + i] * x[k];
        }
        x[i] = v / l[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finiteness_and_bitwise_equality() {
        assert!(Vec3::new(1.0, -2.0, 1e308).is_finite());
        assert!(Mat3::IDENTITY.is_finite());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for k in 0..3 {
                let mut v = [1.0; 3];
                v[k] = bad;
                assert!(!Vec3::from_array(v).is_finite());
            }
            for k in 0..9 {
                let mut m = Mat3::IDENTITY;
                m.m[k / 3][k % 3] = bad;
                assert!(!m.is_finite());
            }
        }
        let mut m = Mat3::IDENTITY;
        assert!(m.bitwise_eq(&Mat3::IDENTITY));
        m.m[1][2] = -0.0;
        assert!(!m.bitwise_eq(&Mat3::IDENTITY) && m == Mat3::IDENTITY);
    }

    #[test]
    fn inverse_and_solve_agree() {
        let a = Mat3::from_rows([[4.0, 1.0, -2.0], [0.5, 3.0, 1.0], [2.0, -1.0, 5.0]]);
        let inv = a.inverse().unwrap();
        let e = (a * inv - Mat3::IDENTITY).max_abs();
        assert!(e < 1e-15, "A A^-1 - I = {e}");
        let b = Vec3::new(1.0, -2.0, 3.0);
        let x = a.solve(b).unwrap();
        assert!((a * x - b).max_abs() < 1e-15);
        assert!((inv * b - x).max_abs() < 1e-15);
        assert!((a.solve_adjugate(b).unwrap() - x).max_abs() < 1e-15);
        assert!(Mat3::ZERO.solve_adjugate(b).is_none());
        assert!(Mat3::ZERO.inverse().is_none());
        assert!(Mat3::ZERO.solve(b).is_none());
    }

    #[test]
    fn cross_and_transpose() {
        let a = Vec3::new(1.0, 2.0, 3.0);
        let b = Vec3::new(-1.0, 0.5, 2.0);
        assert_eq!(a.cross(b).dot(a), 0.0);
        let m = Mat3::from_row_major([1., 2., 3., 4., 5., 6., 7., 8., 10.]);
        assert_eq!(m.tr_mul_vec(a), m.transpose() * a);
        assert!((m.determinant() + 3.0).abs() < 1e-13);
    }
}
