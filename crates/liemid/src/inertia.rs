//! The body inertia tensor: a constant symmetric positive definite 3x3 matrix, with a fast
//! path for principal (diagonal) tensors.

use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};

/// A validated body inertia tensor `I` (kg m²) with its inverse.
///
/// Principal tensors (diagonal in the body frame) multiply and solve componentwise; full
/// tensors use the matrix and its inverse, formed once at construction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertia {
    matrix: Mat3,
    inverse: Mat3,
    principal: Option<(Vec3, Vec3)>,
    inverse_norm: f64,
}

impl Inertia {
    /// A principal inertia tensor `diag(I₁, I₂, I₃)`; every moment must be finite and
    /// positive, and they must satisfy the triangle inequality `I_i ≤ I_j + I_k` of every
    /// physical body (equality, a planar body, is allowed).
    pub fn principal(moments: [f64; 3]) -> Result<Self> {
        for (k, &m) in moments.iter().enumerate() {
            if m == 0.0 {
                return Err(Error::InvalidInertia {
                    reason: format!(
                        "principal moment I{} = 0: bodies with a zero moment (linear molecules, point masses) are not \
                         supported, since the rotation about that axis is undefined; give the axis a small positive \
                         moment (for a symmetric linear body whose torques are normal to its axis, the spin about the \
                         axis then stays zero and the dynamics are unchanged)",
                        k + 1
                    ),
                });
            }
            if !m.is_finite() || m < 0.0 {
                return Err(Error::InvalidInertia {
                    reason: format!(
                        "principal moment I{} = {} must be finite and positive",
                        k + 1,
                        crate::error::Num(m)
                    ),
                });
            }
        }
        // A physical body has I_i = ∫ (r² − x_i²) dm ≤ I_j + I_k = ∫ (r² + x_i²) dm, with
        // equality for planar bodies (allowed, to a relative 8 ulps).
        let [a, b, c] = moments;
        for (k, (m, others)) in [(a, b + c), (b, a + c), (c, a + b)].into_iter().enumerate() {
            if m > others * (1.0 + 8.0 * f64::EPSILON) {
                let (j, l) = [(2, 3), (1, 3), (1, 2)][k];
                return Err(Error::InvalidInertia {
                    reason: format!(
                        "principal moments violate the triangle inequality: I{} = {} > I{j} + I{l} = {} \
                         (no rigid body has these moments)",
                        k + 1,
                        crate::error::Num(m),
                        crate::error::Num(others)
                    ),
                });
            }
        }
        let d = Vec3::from_array(moments);
        let inv = Vec3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
        Ok(Inertia {
            matrix: Mat3::from_diagonal(d),
            inverse: Mat3::from_diagonal(inv),
            principal: Some((d, inv)),
            inverse_norm: inv.max_abs(),
        })
    }

    /// A full inertia tensor given by its rows. It must be finite, symmetric (to a relative
    /// `1e-12`), positive definite (all Cholesky pivots positive) and physical: its principal
    /// moments satisfy the triangle inequality, i.e. `tr(I)/2 · 1 − I` is positive
    /// semidefinite. A diagonal matrix takes
    /// the principal fast path.
    pub fn from_matrix(rows: [[f64; 3]; 3]) -> Result<Self> {
        let m = Mat3::from_rows(rows);
        if !m.is_finite() {
            return Err(Error::InvalidInertia {
                reason: "entries must be finite".into(),
            });
        }
        let scale = m.max_abs();
        for i in 0..3 {
            for j in (i + 1)..3 {
                if (m.m[i][j] - m.m[j][i]).abs() > 1e-12 * scale {
                    return Err(Error::InvalidInertia {
                        reason: format!(
                            "not symmetric: I[{i}][{j}] = {} but I[{j}][{i}] = {}",
                            crate::error::Num(m.m[i][j]),
                            crate::error::Num(m.m[j][i])
                        ),
                    });
                }
            }
        }
        if m.m[0][1] == 0.0 && m.m[0][2] == 0.0 && m.m[1][2] == 0.0 {
            return Inertia::principal([m.m[0][0], m.m[1][1], m.m[2][2]]);
        }
        // Cholesky pivots of the symmetrised matrix.
        let s = (m + m.transpose()) * 0.5;
        let a = &s.m;
        let d0 = a[0][0];
        let d1 = if d0 > 0.0 { a[1][1] - a[0][1] * a[0][1] / d0 } else { d0 };
        let d2 = s.determinant();
        if d0 <= 0.0 || d1 <= 0.0 || d2 <= 0.0 {
            return Err(Error::InvalidInertia {
                reason: format!(
                    "not positive definite (leading principal minors {d0:e}, {:e}, {d2:e})",
                    d0 * d1
                ),
            });
        }
        // The triangle inequality of the (unknown) principal moments: the second-moment
        // tensor C = (tr I / 2) 1 − I = ∫ x xᵀ dm must be positive semidefinite. Its
        // principal minors, to a relative 1e-12 of the scale.
        let c = Mat3::IDENTITY * (0.5 * (a[0][0] + a[1][1] + a[2][2])) - s;
        let cm = &c.m;
        let minors = [
            cm[0][0] / scale,
            cm[1][1] / scale,
            cm[2][2] / scale,
            (cm[0][0] * cm[1][1] - cm[0][1] * cm[0][1]) / (scale * scale),
            (cm[0][0] * cm[2][2] - cm[0][2] * cm[0][2]) / (scale * scale),
            (cm[1][1] * cm[2][2] - cm[1][2] * cm[1][2]) / (scale * scale),
            c.determinant() / (scale * scale * scale),
        ];
        if minors.iter().any(|&m| m < -1e-12) {
            return Err(Error::InvalidInertia {
                reason: "its principal moments violate the triangle inequality (I_i > I_j + I_k: \
                         tr(I)/2 - I is not positive semidefinite); no rigid body has this tensor"
                    .into(),
            });
        }
        let inverse = s.inverse().ok_or_else(|| Error::InvalidInertia {
            reason: "singular".into(),
        })?;
        let inverse = (inverse + inverse.transpose()) * 0.5;
        Ok(Inertia {
            matrix: s,
            inverse,
            principal: None,
            inverse_norm: inverse.norm_frobenius(),
        })
    }

    /// The tensor `I` as a matrix.
    #[must_use]
    pub fn matrix(&self) -> &Mat3 {
        &self.matrix
    }

    /// The inverse `I⁻¹`.
    #[must_use]
    pub fn inverse(&self) -> &Mat3 {
        &self.inverse
    }

    /// An upper bound of `‖I⁻¹‖₂ = 1/λ_min` (exact for principal tensors, `‖I⁻¹‖_F`
    /// otherwise).
    #[must_use]
    pub fn inverse_norm_bound(&self) -> f64 {
        self.inverse_norm
    }

    /// The principal moments, when the tensor is diagonal.
    #[must_use]
    pub fn principal_moments(&self) -> Option<Vec3> {
        self.principal.map(|(d, _)| d)
    }

    /// `I v`.
    #[must_use]
    #[inline]
    pub fn apply(&self, v: Vec3) -> Vec3 {
        match &self.principal {
            Some((d, _)) => d.component_mul(v),
            None => self.matrix * v,
        }
    }

    /// `I⁻¹ v`: the body angular velocity of the momentum `v`.
    #[must_use]
    #[inline]
    pub fn apply_inverse(&self, v: Vec3) -> Vec3 {
        match &self.principal {
            Some((_, inv)) => inv.component_mul(v),
            None => self.inverse * v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_tensors_with_reasons() {
        let e = Inertia::principal([1.0, 0.0, 2.0]).unwrap_err();
        assert!(e.to_string().contains("I2 = 0"), "{e}");
        assert!(Inertia::principal([1.0, f64::NAN, 2.0]).is_err());
        assert!(Inertia::principal([-1.0, 1.0, 2.0]).is_err());
        let e = Inertia::from_matrix([[1.0, 0.5, 0.0], [0.4, 1.0, 0.0], [0.0, 0.0, 1.0]]).unwrap_err();
        assert!(e.to_string().contains("not symmetric"), "{e}");
        let e = Inertia::from_matrix([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).unwrap_err();
        assert!(e.to_string().contains("not positive definite"), "{e}");
        assert!(Inertia::from_matrix([[1.0, 0.0, 0.0], [0.0, f64::INFINITY, 0.0], [0.0, 0.0, 1.0]]).is_err());
    }

    #[test]
    fn refuses_moments_no_body_has() {
        // Issue 14, item 7: [1, 1, 3] violates I3 <= I1 + I2.
        let e = Inertia::principal([1.0, 1.0, 3.0]).unwrap_err().to_string();
        assert!(
            e.contains("triangle inequality") && e.contains("I3 = 3 > I1 + I2 = 2"),
            "{e}"
        );
        let e = Inertia::principal([3.0, 1.0, 1.0]).unwrap_err().to_string();
        assert!(e.contains("I1 = 3 > I2 + I3 = 2"), "{e}");
        // Equality is a planar body (a thin plate): allowed, also after rounding.
        assert!(Inertia::principal([1.0, 1.0, 2.0]).is_ok());
        assert!(Inertia::principal([0.1, 0.2, 0.1 + 0.2]).is_ok());
        // The same for full tensors: R diag(d) Rᵀ for an oblique R.
        let r = crate::so3::exp(Vec3::new(0.3, -0.7, 0.5));
        let rotated = |d: [f64; 3]| {
            let m = r * Mat3::from_diagonal(Vec3::from_array(d)) * r.transpose();
            // Symmetric to the bit: the upper triangle mirrored.
            let u = m.m;
            Inertia::from_matrix([
                [u[0][0], u[0][1], u[0][2]],
                [u[0][1], u[1][1], u[1][2]],
                [u[0][2], u[1][2], u[2][2]],
            ])
        };
        let e = rotated([1.0, 1.0, 3.0]).unwrap_err().to_string();
        assert!(e.contains("triangle inequality"), "{e}");
        assert!(rotated([1.0, 1.0, 2.1]).unwrap_err().to_string().contains("triangle"));
        assert!(rotated([1.0, 2.0, 3.0]).is_ok());
        assert!(rotated([1.0, 2.0, 2.5]).is_ok());
    }

    #[test]
    fn full_tensor_applies_and_inverts() {
        let i = Inertia::from_matrix([[2.0, 0.3, -0.1], [0.3, 3.0, 0.2], [-0.1, 0.2, 4.0]]).unwrap();
        assert!(i.principal_moments().is_none());
        let v = Vec3::new(0.7, -1.1, 2.3);
        assert!((i.apply_inverse(i.apply(v)) - v).max_abs() < 1e-15);
        let d = Inertia::from_matrix([[2.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 4.0]]).unwrap();
        assert_eq!(d.principal_moments(), Some(Vec3::new(2.0, 3.0, 4.0)));
        assert!((d.apply(v) - Vec3::new(1.4, -3.3, 9.2)).max_abs() < 1e-15);
    }
}

/// What the midpoint solver needs of an inertia tensor: `I v`, `I⁻¹ v`, `I + M` and a bound
/// of `‖I⁻¹‖`. Implemented by [`Inertia`] and by the compact [`PrincipalInertia`] that
/// many-body systems store per body.
pub trait InertiaOperator {
    /// `I v`.
    fn apply(&self, v: Vec3) -> Vec3;
    /// `I⁻¹ v`.
    fn apply_inverse(&self, v: Vec3) -> Vec3;
    /// `I + m`.
    fn plus(&self, m: &Mat3) -> Mat3;
    /// An upper bound of `‖I⁻¹‖₂`.
    fn inverse_norm_bound(&self) -> f64;
    /// `(I₁, I₂, I₃)` and their reciprocals when the tensor is diagonal (the fast path of
    /// the midpoint solver).
    fn diagonal(&self) -> Option<(Vec3, Vec3)>;
}

impl InertiaOperator for Inertia {
    #[inline]
    fn apply(&self, v: Vec3) -> Vec3 {
        Inertia::apply(self, v)
    }
    #[inline]
    fn apply_inverse(&self, v: Vec3) -> Vec3 {
        Inertia::apply_inverse(self, v)
    }
    #[inline]
    fn plus(&self, m: &Mat3) -> Mat3 {
        self.matrix + *m
    }
    #[inline]
    fn inverse_norm_bound(&self) -> f64 {
        self.inverse_norm
    }
    #[inline]
    fn diagonal(&self) -> Option<(Vec3, Vec3)> {
        self.principal
    }
}

/// A principal inertia tensor stored as its moments and their reciprocals (48 bytes), for
/// systems of many bodies. Not validated: build it from validated moments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipalInertia {
    /// `(I₁, I₂, I₃)`.
    pub moments: Vec3,
    /// `(1/I₁, 1/I₂, 1/I₃)`.
    pub inverse: Vec3,
}

impl PrincipalInertia {
    /// From positive moments (checked by the caller).
    #[must_use]
    pub fn new(moments: Vec3) -> Self {
        PrincipalInertia {
            moments,
            inverse: Vec3::new(1.0 / moments.x, 1.0 / moments.y, 1.0 / moments.z),
        }
    }
}

impl InertiaOperator for PrincipalInertia {
    #[inline]
    fn apply(&self, v: Vec3) -> Vec3 {
        self.moments.component_mul(v)
    }
    #[inline]
    fn apply_inverse(&self, v: Vec3) -> Vec3 {
        self.inverse.component_mul(v)
    }
    #[inline]
    fn plus(&self, m: &Mat3) -> Mat3 {
        let mut r = *m;
        r.m[0][0] += self.moments.x;
        r.m[1][1] += self.moments.y;
        r.m[2][2] += self.moments.z;
        r
    }
    #[inline]
    fn inverse_norm_bound(&self) -> f64 {
        self.inverse.max_abs()
    }
    #[inline]
    fn diagonal(&self) -> Option<(Vec3, Vec3)> {
        Some((self.moments, self.inverse))
    }
}
