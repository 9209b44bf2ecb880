//! Block Cholesky of the symmetric tree system for `A = G M⁻¹ Gᵀ` (both sides at the same
//! configuration): the matrix of the velocity solve, and the quasi-Newton matrix of the
//! position solve.
//!
//! With `ν = −λ` the augmented system
//!
//! ```text
//! [ M  Gᵀ ] [x]   [b]
//! [ G  0  ] [ν] = [r]
//! ```
//!
//! is symmetric, with the tree's block graph (one node per body, one per joint). Eliminated
//! from the leaves to the root (Baraff 1996), every body pivot
//! `D_b = M_b + Σ_children G_{j,b}ᵀ S_j⁻¹ G_{j,b}` is symmetric positive definite and every
//! joint pivot is `−S_j`, `S_j = G_{j,c} D_c⁻¹ G_{j,c}ᵀ` (`c` the joint's child), also
//! definite while the tree rows are independent. Each pivot is factored by Cholesky,
//! `D_b = L_b L_bᵀ`, `S_j = L_j L_jᵀ`, and the couplings stored as
//! `Y_b = L_b⁻¹ G_{j,b}ᵀ` (6 × rows of the body's own joint) and `Y_j = L_j⁻¹ G_{j,p}`
//! (rows × 6, `p` the joint's parent body), so that the Schur updates are
//! `S_j = Y_bᵀ Y_b` and `D_p += Y_jᵀ Y_j`. Factor and solve cost O(bodies) with fixed-size
//! kernels (6 for a body, the joint's row count for a joint, monomorphized): about half the
//! work of the general block LU of [`super::solver`], which serves the non-symmetric
//! matrices of the position solve's fallback.
//!
//! After the couplings are formed, each pivot's factor is replaced by its inverse
//! (`L_b⁻¹`, `L_j⁻¹`, lower triangular): a solve then applies them as matrix-vector
//! products, whose dot products are independent, instead of substitutions, whose steps
//! each wait on the last (chain-1000 4.8 % and the double pendulum's liemid4 7 % less CPU
//! per step; the same solution to round-off).
//!
//! A pivot `≤ 1e-13` of its block's largest diagonal entry is reported as dependent rows
//! and never divided by (as the LU's).
//!
//! Reference: D. Baraff, "Linear-time dynamics using Lagrange multipliers", SIGGRAPH 1996;
//! G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., 4.2 (Cholesky).

// Small dense blocks with explicit row and column bounds read best as index loops.
#![allow(clippy::needless_range_loop)]

use crate::linalg::Mat3;

use super::armature::Coupling;
use super::blocks::{child_part, dot6_pairwise, parent_part, Blk, SingularPivot, PIVOT_TOLERANCE, V6};
use super::constraints::JointRows;

/// The factor data of one body and its own (tree) joint, contiguous for locality.
#[derive(Clone, Copy, Debug)]
struct BodyFactor {
    /// `D_b` (lower triangle), then its Cholesky factor `L_b` in place, then `L_b⁻¹`.
    l: Blk,
    /// `1 / (L_b)_kk`.
    il: V6,
    /// Columns `k` of `Y_b = L_b⁻¹ G_{j,b}ᵀ`.
    yb: Blk,
    /// `S_j`, then `L_j` in place, then `L_j⁻¹`.
    lj: Blk,
    /// `1 / (L_j)_kk`.
    ilj: V6,
    /// Rows `k` of `Y_j = L_j⁻¹ G_{j,p}`.
    yj: Blk,
    /// Active rows of the joint.
    s: usize,
}

const ZERO_FACTOR: BodyFactor = BodyFactor {
    l: [[0.0; 6]; 6],
    il: [0.0; 6],
    yb: [[0.0; 6]; 6],
    lj: [[0.0; 6]; 6],
    ilj: [0.0; 6],
    yj: [[0.0; 6]; 6],
    s: 0,
};

/// The block Cholesky factorization of the symmetric tree system, preallocated for a
/// model's tree.
///
/// Reference: D. Baraff, SIGGRAPH 1996 (see the module documentation).
#[derive(Clone, Debug)]
pub(super) struct SymmetricTree {
    parent: Vec<Option<usize>>,
    factors: Vec<BodyFactor>,
    /// Hinge armature's child–parent couplings (empty: none) and, per coupled body `b`,
    /// `z_b = −a L_b⁻¹ (0, n_c)`: the coupling `𝕁_bp = −a (0, n_c)(0, n_p)ᵀ` after `L_b`.
    arm: Vec<Option<Coupling>>,
    za: Vec<V6>,
}

#[inline(always)]
fn axpy6(s: f64, x: &V6, y: &mut V6) {
    for c in 0..6 {
        y[c] += s * x[c];
    }
}

/// Cholesky of the leading `N×N` of `a` in place (lower triangle), `1/L_kk` into `inv`;
/// the relative pivot when one is not positive beyond the tolerance.
#[inline(always)]
fn cholesky<const N: usize>(a: &mut Blk, inv: &mut V6) -> Result<(), f64> {
    let mut scale = 0.0f64;
    for k in 0..N {
        scale = scale.max(a[k][k].abs());
    }
    for k in 0..N {
        let mut v = a[k][k];
        for j in 0..k {
            v -= a[k][j] * a[k][j];
        }
        if v.is_nan() || v <= PIVOT_TOLERANCE * scale {
            return Err(if scale > 0.0 && v.is_finite() {
                v.max(0.0) / scale
            } else {
                0.0
            });
        }
        let l = v.sqrt();
        let il = 1.0 / l;
        a[k][k] = l;
        inv[k] = il;
        for i in k + 1..N {
            let mut w = a[i][k];
            for j in 0..k {
                w -= a[i][j] * a[k][j];
            }
            a[i][k] = w * il;
        }
    }
    Ok(())
}

/// `b ← L⁻¹ b` for the leading `N×N` lower factor.
#[inline(always)]
fn forward<const N: usize>(l: &Blk, inv: &V6, b: &mut V6) {
    for k in 0..N {
        let mut v = b[k];
        for j in 0..k {
            v -= l[k][j] * b[j];
        }
        b[k] = v * inv[k];
    }
}

/// `L ← L⁻¹` in place for the leading `N×N` lower factor with `inv[k] = 1/L_kk`, column by
/// column: `X_kk = 1/L_kk`, `X_ik = −(1/L_ii) Σ_{k≤j<i} L_ij X_jk` (the entries `L_ij`, `j > k`,
/// are not yet overwritten when column `k` is formed).
#[inline(always)]
fn invert_lower<const N: usize>(l: &mut Blk, inv: &V6) {
    for k in 0..N {
        l[k][k] = inv[k];
        for i in k + 1..N {
            let mut s = 0.0;
            for j in k..i {
                s += l[i][j] * l[j][k];
            }
            l[i][k] = -s * inv[i];
        }
    }
}

/// `b ← X b` for the leading `N×N` lower `X = L⁻¹` ([`invert_lower`]): independent dot
/// products instead of the substitution's chain of dependent ones.
#[inline(always)]
fn apply_lower<const N: usize>(x: &Blk, b: &mut V6) {
    let v = *b;
    for k in 0..N {
        let mut s = 0.0;
        for j in 0..=k {
            s += x[k][j] * v[j];
        }
        b[k] = s;
    }
}

/// `b ← Xᵀ b` for the leading `N×N` lower `X = L⁻¹`, that is `b ← L⁻ᵀ b`.
#[inline(always)]
fn apply_lower_t<const N: usize>(x: &Blk, b: &mut V6) {
    let v = *b;
    for k in 0..N {
        let mut s = 0.0;
        for j in k..N {
            s += x[j][k] * v[j];
        }
        b[k] = s;
    }
}

impl SymmetricTree {
    /// The structure: `parents[b]` the parent body of tree joint `b` (child `b`).
    pub(super) fn new(parents: &[Option<usize>]) -> Self {
        SymmetricTree {
            parent: parents.to_vec(),
            factors: vec![ZERO_FACTOR; parents.len()],
            arm: Vec::new(),
            za: Vec::new(),
        }
    }

    /// Couple the rotational parts of hinge armature's children and parents (the body
    /// blocks passed to [`SymmetricTree::factor`] must then be `𝕁`'s diagonal blocks).
    /// Eliminating a coupled child `b` fills only its joint's parent block,
    /// `G'_{j,p} = G_{j,p} − (Y_bᵀ z_b)(0, n_p)ᵀ`, and lowers the parent's pivot by
    /// `|z_b|² (0, n_p)(0, n_p)ᵀ`: the tree's pattern (docs/theory/multibody.md §7).
    pub(super) fn set_armature(&mut self, coupling: &[Option<Coupling>]) {
        self.arm = coupling.to_vec();
        self.za = vec![[0.0; 6]; coupling.len()];
    }

    #[inline]
    fn coupling(&self, b: usize) -> Option<Coupling> {
        if self.arm.is_empty() {
            None
        } else {
            self.arm[b]
        }
    }

    /// Factor with `rows[b]` the rows of tree joint `b` (its child is body `b`).
    pub(super) fn factor(&mut self, mass: &[f64], inertia: &[Mat3], rows: &[JointRows]) -> Result<(), SingularPivot> {
        for (b, link) in self.factors.iter_mut().enumerate() {
            let l = &mut link.l;
            *l = [[0.0; 6]; 6];
            for k in 0..3 {
                l[k][k] = mass[b];
                for c in 0..=k {
                    l[3 + k][3 + c] = inertia[b].m[k][c];
                }
            }
        }
        for b in (0..self.factors.len()).rev() {
            let s = rows[b].n;
            let result = match s {
                0 => self.body(b).map(|()| {
                    let link = &mut self.factors[b];
                    invert_lower::<6>(&mut link.l, &link.il);
                }),
                1 => self.link::<1>(b, &rows[b]),
                2 => self.link::<2>(b, &rows[b]),
                3 => self.link::<3>(b, &rows[b]),
                4 => self.link::<4>(b, &rows[b]),
                5 => self.link::<5>(b, &rows[b]),
                _ => self.link::<6>(b, &rows[b]),
            };
            result?;
        }
        Ok(())
    }

    fn body(&mut self, b: usize) -> Result<(), SingularPivot> {
        let link = &mut self.factors[b];
        link.s = 0;
        cholesky::<6>(&mut link.l, &mut link.il).map_err(|ratio| SingularPivot {
            joint: None,
            body: Some(b),
            ratio,
        })
    }

    #[inline(always)]
    fn link<const S: usize>(&mut self, b: usize, rows: &JointRows) -> Result<(), SingularPivot> {
        self.body(b)?;
        let parent = self.parent[b];
        let link = &mut self.factors[b];
        link.s = S;
        for k in 0..S {
            let mut col = child_part(&rows.grad[k]);
            forward::<6>(&link.l, &link.il, &mut col);
            link.yb[k] = col;
        }
        for i in 0..S {
            for j in 0..=i {
                link.lj[i][j] = dot6_pairwise(&link.yb[i], &link.yb[j]);
            }
        }
        cholesky::<S>(&mut link.lj, &mut link.ilj).map_err(|ratio| SingularPivot {
            joint: Some(b),
            body: None,
            ratio,
        })?;
        let Some(p) = parent else {
            invert_lower::<6>(&mut link.l, &link.il);
            invert_lower::<S>(&mut link.lj, &link.ilj);
            return Ok(());
        };
        let arm = if self.arm.is_empty() { None } else { self.arm[b] };
        let mut za = [0.0; 6];
        if let Some(c) = arm {
            za = [0.0, 0.0, 0.0, -c.a * c.n_c.x, -c.a * c.n_c.y, -c.a * c.n_c.z];
            forward::<6>(&link.l, &link.il, &mut za);
            self.za[b] = za;
        }
        for k in 0..S {
            let mut v = parent_part(&rows.grad[k]);
            if let Some(c) = arm {
                let d = dot6_pairwise(&link.yb[k], &za);
                v[3] -= d * c.n_p.x;
                v[4] -= d * c.n_p.y;
                v[5] -= d * c.n_p.z;
            }
            for j in 0..k {
                let f = -link.lj[k][j];
                let yj = link.yj[j];
                axpy6(f, &yj, &mut v);
            }
            link.yj[k] = v.map(|x| x * link.ilj[k]);
        }
        invert_lower::<6>(&mut link.l, &link.il);
        invert_lower::<S>(&mut link.lj, &link.ilj);
        let yj = link.yj;
        let d = &mut self.factors[p].l;
        for r in 0..6 {
            for c in 0..=r {
                let mut acc = 0.0;
                for k in 0..S {
                    acc += yj[k][r] * yj[k][c];
                }
                d[r][c] += acc;
            }
        }
        if let Some(c) = arm {
            let zz = dot6_pairwise(&za, &za);
            let n = [c.n_p.x, c.n_p.y, c.n_p.z];
            for r in 0..3 {
                for q in 0..=r {
                    d[3 + r][3 + q] -= zz * n[r] * n[q];
                }
            }
        }
        Ok(())
    }

    /// Solve the tree system in place: `z[body_node[b]]` the body parts (6), `z[joint_node[b]]`
    /// the joint parts (rows); on return the body parts hold `x` and the joint parts `λ = −ν`
    /// (the sign convention of the general solver's unknowns).
    pub(super) fn solve(&self, z: &mut [V6], body_node: &[usize], joint_node: &[Option<usize>]) {
        for b in (0..self.factors.len()).rev() {
            let link = &self.factors[b];
            match link.s {
                0 => apply_lower::<6>(&link.l, &mut z[body_node[b]]),
                1 => self.forward_link::<1>(b, z, body_node, joint_node),
                2 => self.forward_link::<2>(b, z, body_node, joint_node),
                3 => self.forward_link::<3>(b, z, body_node, joint_node),
                4 => self.forward_link::<4>(b, z, body_node, joint_node),
                5 => self.forward_link::<5>(b, z, body_node, joint_node),
                _ => self.forward_link::<6>(b, z, body_node, joint_node),
            }
        }
        for b in 0..self.factors.len() {
            let link = &self.factors[b];
            match link.s {
                0 => apply_lower_t::<6>(&link.l, &mut z[body_node[b]]),
                1 => self.backward_link::<1>(b, z, body_node, joint_node),
                2 => self.backward_link::<2>(b, z, body_node, joint_node),
                3 => self.backward_link::<3>(b, z, body_node, joint_node),
                4 => self.backward_link::<4>(b, z, body_node, joint_node),
                5 => self.backward_link::<5>(b, z, body_node, joint_node),
                _ => self.backward_link::<6>(b, z, body_node, joint_node),
            }
        }
    }

    #[inline(always)]
    fn forward_link<const S: usize>(&self, b: usize, z: &mut [V6], body_node: &[usize], joint_node: &[Option<usize>]) {
        let link = &self.factors[b];
        let bn = body_node[b];
        let jn = joint_node[b].unwrap_or(bn);
        let mut u = z[bn];
        apply_lower::<6>(&link.l, &mut u);
        z[bn] = u;
        let mut w = z[jn];
        for k in 0..S {
            w[k] -= dot6_pairwise(&link.yb[k], &u);
        }
        apply_lower::<S>(&link.lj, &mut w);
        z[jn] = w;
        if let Some(p) = self.parent[b] {
            let zp = &mut z[body_node[p]];
            for k in 0..S {
                axpy6(w[k], &link.yj[k], zp);
            }
            if let Some(c) = self.coupling(b) {
                let f = dot6_pairwise(&self.za[b], &u);
                zp[3] -= f * c.n_p.x;
                zp[4] -= f * c.n_p.y;
                zp[5] -= f * c.n_p.z;
            }
        }
    }

    #[inline(always)]
    fn backward_link<const S: usize>(&self, b: usize, z: &mut [V6], body_node: &[usize], joint_node: &[Option<usize>]) {
        let link = &self.factors[b];
        let bn = body_node[b];
        let jn = joint_node[b].unwrap_or(bn);
        let mut w = z[jn];
        if let Some(p) = self.parent[b] {
            let xp = z[body_node[p]];
            for k in 0..S {
                w[k] -= dot6_pairwise(&link.yj[k], &xp);
            }
        }
        apply_lower_t::<S>(&link.lj, &mut w);
        z[jn] = w;
        // The body's right side is u_b − Y_b ν = u_b + Y_b λ.
        let mut u = z[bn];
        for k in 0..S {
            axpy6(w[k], &link.yb[k], &mut u);
        }
        if let (Some(c), Some(p)) = (self.coupling(b), self.parent[b]) {
            let xp = &z[body_node[p]];
            let f = c.n_p.x * xp[3] + c.n_p.y * xp[4] + c.n_p.z * xp[5];
            axpy6(-f, &self.za[b], &mut u);
        }
        apply_lower_t::<6>(&link.l, &mut u);
        z[bn] = u;
    }
}

#[cfg(test)]
mod tests {
    use super::super::constraints::pose;
    use super::super::constraints::JointGeometry;
    use super::super::model::{JointKind, Link, Model};
    use super::super::problems;
    use super::super::solver::TreeSolver;
    use crate::linalg::Vec3;
    use crate::random::Rng;
    use crate::so3;

    /// The symmetric block Cholesky and the general block LU solve the same systems to
    /// round-off: branching trees with every joint kind (3, 5 and 6 rows, one limit-sized
    /// row added), and the four-bar's loop with redundant rows.
    #[test]
    fn agrees_with_the_general_solver() {
        let mut tree = problems::chain(7);
        tree.joints[2].kind = JointKind::Hinge {
            axis: Vec3::new(0.0, 0.6, 0.8),
        };
        tree.joints[3].kind = JointKind::Slide {
            axis: Vec3::new(1.0, 0.0, 0.0),
        };
        tree.joints[4].kind = JointKind::Weld;
        tree.joints[5].parent = Link::Body(2);
        tree.joints[6].kind = JointKind::Free;
        tree.qpos = None;
        let mut rng = Rng::new(35);
        check(&tree, true, &mut rng);
        for model in [problems::closed_loop(), problems::spacecraft(), problems::test_chain()] {
            check(&model, false, &mut rng);
        }
    }

    fn check(model: &Model, limit_rows: bool, rng: &mut Rng) {
        let nb = model.bodies.len();
        let mut state = model.initial_state().unwrap();
        for i in 0..nb {
            state.rotation[i] = state.rotation[i] * so3::exp(rng.unit_vector() * 0.3);
            state.c[i] += rng.unit_vector() * 0.01;
        }
        let geometry: Vec<_> = (0..model.joints.len()).map(|k| JointGeometry::new(model, k)).collect();
        let mut rows = vec![super::JointRows::default(); geometry.len()];
        for (k, g) in geometry.iter().enumerate() {
            let (pi, pj) = pose(g, &state.c, &state.rotation);
            g.rows(pi, pj, &mut rows[k]);
            if limit_rows && matches!(g.kind, JointKind::Hinge { .. }) {
                let (_, grad) = g.hinge_angle(pi.1, pj.1);
                rows[k].push(0.0, grad, false);
            }
        }
        let mass: Vec<f64> = model.bodies.iter().map(|b| b.mass).collect();
        let inertia: Vec<_> = (0..nb).map(|i| *model.inertia(i).unwrap().matrix()).collect();
        let pairs: Vec<_> = geometry.iter().map(|g| (g.parent, g.child)).collect();
        let tree_rows: Vec<bool> = geometry[..nb].iter().map(|g| g.kind.rows() > 0).collect();
        let parents: Vec<_> = geometry[..nb].iter().map(|g| g.parent).collect();
        let loops: Vec<_> = (nb..geometry.len())
            .map(|k| (k, geometry[k].parent, geometry[k].child))
            .collect();
        let mut lu = TreeSolver::new(&parents, &tree_rows, &loops);
        let mut chol = lu.clone();
        lu.factor(&mass, &inertia, &pairs, &rows, &rows).unwrap();
        chol.factor_symmetric(&mass, &inertia, &pairs, &rows).unwrap();
        assert_eq!(lu.loop_rank(), chol.loop_rank(), "{}", model.name);
        let r: Vec<[f64; 6]> = (0..geometry.len())
            .map(|_| core::array::from_fn(|_| rng.uniform() - 0.5))
            .collect();
        let (mut a, mut b) = (vec![[0.0; 6]; r.len()], vec![[0.0; 6]; r.len()]);
        lu.solve(&pairs, &r, &mut a);
        chol.solve(&pairs, &r, &mut b);
        let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (k, (x, y)) in a.iter().zip(&b).enumerate() {
            for row in 0..rows[k].n {
                assert!(
                    (x[row] - y[row]).abs() <= 1e-11 * scale,
                    "{}: joint {k} row {row}: {} vs {}",
                    model.name,
                    x[row],
                    y[row]
                );
            }
        }
    }
}
