//! Spatial algebra for the joint-space reference: 6-vectors `(angular; linear)`, 6x6
//! matrices, the motion and force cross products, Plücker transforms of a child frame in
//! its parent, and a small dense inverse.
//!
//! ## Reference
//!
//! R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, ch. 2.

// Small dense blocks (6x6, the joint's nd x nd) are indexed as in the formulas.
#![allow(clippy::needless_range_loop)]

use crate::linalg::{Mat3, Vec3};
use crate::so3::hat;

/// A spatial vector `(angular; linear)`.
pub(super) type SV = [f64; 6];
/// A 6x6 matrix, row-major.
pub(super) type M6 = [[f64; 6]; 6];

pub(super) const ZERO6: SV = [0.0; 6];
pub(super) const ZERO66: M6 = [[0.0; 6]; 6];

#[inline]
pub(super) fn sv(a: Vec3, l: Vec3) -> SV {
    [a.x, a.y, a.z, l.x, l.y, l.z]
}

/// The `k`-th unit vector.
#[inline]
pub(super) fn basis(k: usize) -> Vec3 {
    let mut a = [0.0; 3];
    a[k] = 1.0;
    Vec3::from_array(a)
}

#[inline]
pub(super) fn ang(s: &SV) -> Vec3 {
    Vec3::new(s[0], s[1], s[2])
}

#[inline]
pub(super) fn lin(s: &SV) -> Vec3 {
    Vec3::new(s[3], s[4], s[5])
}

#[inline]
pub(super) fn add6(a: &SV, b: &SV) -> SV {
    core::array::from_fn(|k| a[k] + b[k])
}

#[inline]
pub(super) fn dot6(a: &SV, b: &SV) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The motion cross product `v × m = (ω × m_ω; ω × m_v + v × m_ω)`.
#[inline]
pub(super) fn cross_motion(v: &SV, m: &SV) -> SV {
    let (w, l) = (ang(v), lin(v));
    let (mw, ml) = (ang(m), lin(m));
    sv(w.cross(mw), w.cross(ml) + l.cross(mw))
}

/// The force cross product `v ×* f = (ω × n + v × f; ω × f)`.
#[inline]
pub(super) fn cross_force(v: &SV, f: &SV) -> SV {
    let (w, l) = (ang(v), lin(v));
    let (n, ff) = (ang(f), lin(f));
    sv(w.cross(n) + l.cross(ff), w.cross(ff))
}

#[inline]
pub(super) fn mul6(a: &M6, x: &SV) -> SV {
    core::array::from_fn(|i| dot6(&a[i], x))
}

/// `Xᵀ A X` for 6x6 matrices.
pub(super) fn congruence(x: &M6, a: &M6) -> M6 {
    let mut ax = ZERO66;
    for i in 0..6 {
        for j in 0..6 {
            ax[i][j] = (0..6).map(|k| a[i][k] * x[k][j]).sum();
        }
    }
    let mut out = ZERO66;
    for i in 0..6 {
        for j in 0..6 {
            out[i][j] = (0..6).map(|k| x[k][i] * ax[k][j]).sum();
        }
    }
    out
}

pub(super) fn add66(a: &mut M6, b: &M6) {
    for i in 0..6 {
        for j in 0..6 {
            a[i][j] += b[i][j];
        }
    }
}

/// The pose `(r, E)` of a child frame in its parent frame: the Plücker transform
/// `ⁱX_λ = [[Eᵀ, 0]; [−Eᵀ r̂, Eᵀ]]` from parent to child coordinates.
#[derive(Clone, Copy, Debug)]
pub(super) struct Xform {
    /// Child-to-parent rotation.
    pub(super) e: Mat3,
    /// The child frame's origin in parent coordinates.
    pub(super) r: Vec3,
}

impl Xform {
    pub(super) const IDENTITY: Xform = Xform {
        e: Mat3::IDENTITY,
        r: Vec3::ZERO,
    };

    /// A motion vector from parent to child coordinates: `(Eᵀ ω; Eᵀ (v − r × ω))`.
    #[inline]
    pub(super) fn motion(&self, m: &SV) -> SV {
        let w = ang(m);
        sv(self.e.tr_mul_vec(w), self.e.tr_mul_vec(lin(m) - self.r.cross(w)))
    }

    /// A force vector from child to parent coordinates, `Xᵀ f = (E n + r × E f; E f)`.
    #[inline]
    pub(super) fn force_to_parent(&self, f: &SV) -> SV {
        let ef = self.e * lin(f);
        sv(self.e * ang(f) + self.r.cross(ef), ef)
    }

    /// The 6x6 matrix `ⁱX_λ`.
    pub(super) fn matrix(&self) -> M6 {
        let et = self.e.transpose();
        let b = (et * hat(self.r)) * -1.0;
        let mut x = ZERO66;
        for i in 0..3 {
            for j in 0..3 {
                x[i][j] = et.m[i][j];
                x[i + 3][j + 3] = et.m[i][j];
                x[i + 3][j] = b.m[i][j];
            }
        }
        x
    }
}

/// Invert a small symmetric positive definite matrix (`n ≤ 6`, in the top-left corner) by
/// Gauss-Jordan elimination with partial pivoting; `None` on a pivot at round-off.
pub(super) fn invert_small(a: &M6, n: usize) -> Option<M6> {
    let mut m = *a;
    let mut inv = ZERO66;
    for (i, row) in inv.iter_mut().enumerate().take(n) {
        row[i] = 1.0;
    }
    let scale = (0..n).map(|i| a[i][i].abs()).fold(0.0, f64::max);
    for col in 0..n {
        let piv = (col..n).max_by(|&x, &y| m[x][col].abs().total_cmp(&m[y][col].abs()))?;
        let p = m[piv][col];
        if !p.is_finite() || p.abs() <= 1e-14 * scale {
            return None;
        }
        m.swap(col, piv);
        inv.swap(col, piv);
        for j in 0..n {
            m[col][j] /= p;
            inv[col][j] /= p;
        }
        for r in 0..n {
            if r != col {
                let f = m[r][col];
                if f != 0.0 {
                    for j in 0..n {
                        m[r][j] -= f * m[col][j];
                        inv[r][j] -= f * inv[col][j];
                    }
                }
            }
        }
    }
    Some(inv)
}
