//! The 6x6 blocks both factorizations of `G M⁻¹ Gᵀ` are built of (the general block LU of
//! `solver.rs`, the block Cholesky of `cholesky.rs`): a body's or joint's block, a row's
//! parent and child parts as 6-vectors, their dot products, and the pivot test.
//!
//! Two summation orders of the 6-term dot product are kept on purpose: the Cholesky's
//! pairwise one (three independent pairs, which the compiler keeps in registers) and the
//! LU's left-to-right one. Each is the order its factorization has always used, so the
//! results are the same bit for bit as before they were gathered here; making them one
//! would change the general solver's last bits (loops, the exact drift Jacobian).
//!
//! Reference: docs/theory/multibody.md §4; D. Baraff, "Linear-time dynamics using Lagrange
//! multipliers", SIGGRAPH 1996.

use super::constraints::Row;

/// A 6x6 block (rows of a joint against a body's six velocities, or a body or joint block).
pub(super) type Blk = [[f64; 6]; 6];
/// A 6-vector (a body's linear and angular parts, or a joint's multipliers).
pub(super) type V6 = [f64; 6];

/// Relative pivot below which a tree block is singular.
pub const PIVOT_TOLERANCE: f64 = 1e-13;

/// A tree block whose pivot vanished: the rows of a joint depend on others.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingularPivot {
    /// The joint of the block, or `None` for a body block.
    pub joint: Option<usize>,
    /// The body of the block, or `None` for a joint block.
    pub body: Option<usize>,
    /// The pivot relative to the block's largest entry.
    pub ratio: f64,
}

/// A row's gradient with respect to the parent body, `(∂g/∂c_i, ∂g/∂θ_i)`.
#[inline(always)]
pub(super) fn parent_part(r: &Row) -> V6 {
    [r.ci.x, r.ci.y, r.ci.z, r.ti.x, r.ti.y, r.ti.z]
}

/// A row's gradient with respect to the child body, `(∂g/∂c_j, ∂g/∂θ_j)`.
#[inline(always)]
pub(super) fn child_part(r: &Row) -> V6 {
    [r.cj.x, r.cj.y, r.cj.z, r.tj.x, r.tj.y, r.tj.z]
}

/// `a·b` summed in three pairs, `(a₀b₀ + a₁b₁) + (a₂b₂ + a₃b₃) + (a₄b₄ + a₅b₅)` (the
/// block Cholesky's order).
#[inline(always)]
pub(super) fn dot6_pairwise(a: &V6, b: &V6) -> f64 {
    (a[0] * b[0] + a[1] * b[1]) + (a[2] * b[2] + a[3] * b[3]) + (a[4] * b[4] + a[5] * b[5])
}

/// `a·b` summed left to right (the general block LU's order).
#[inline(always)]
pub(super) fn dot6_sequential(a: &V6, b: &V6) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
