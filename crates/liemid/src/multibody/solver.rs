//! Linear-time solution of `A λ = r`, `A = G(q') M⁻¹ G(q)ᵀ`, for a tree of joints with a
//! small Schur complement for loop-closing joints.
//!
//! **Tree.** With `x = M⁻¹ G(q)ᵀ λ` the system is the augmented one
//!
//! ```text
//! [ M     −G(q)ᵀ ] [x]   [0]
//! [ G(q')   0    ] [λ] = [r]
//! ```
//!
//! whose block graph, one node per body (6 unknowns: `v`, `Ω`) and one per joint (its
//! rows), is the tree itself: a joint touches its parent and its child body only. Ordered
//! parents before children and eliminated from the leaves to the root, a block LU has no
//! fill-in (Baraff 1996): each node's pivot block `D_n` (at most 6x6, LU with partial
//! pivoting) is updated once by each child, `D_p ← D_p − H_pn D_n⁻¹ H_np`, so factor and
//! solve cost O(bodies). Body pivots are `M_i` plus positive terms, joint pivots
//! `G' D⁻¹ Gᵀ` of the child subtree; a pivot below `1e-13` of its block is reported as
//! dependent rows (never divided by). Joint sets that meet at a body (siblings) cause no
//! fill-in here, unlike the joint-only matrix `A`.
//!
//! **Loops.** The rows `L` of loop-closing joints couple two branches. With the tree part
//! `K` factored, `W = K⁻¹ C` (one tree solve per loop row, at factor time) gives the Schur
//! complement `S = −D W` (`C`, `D` the loop rows' columns and rows in the augmented
//! system), and a solve is `z₀ = K⁻¹ b`, `S λ_L = r_L − D z₀`, `z = z₀ − W λ_L`.
//!
//! **Redundancy.** A loop may have dependent rows (the planar four-bar of four hinges: 3 of
//! its 5 loop rows). `S` is then singular. It is decomposed by a one-sided Jacobi SVD and
//! `λ_L` taken as the minimum-norm least-squares solution `S⁺ (r_L − D z₀)`, singular
//! values below [`PSEUDO_INVERSE_TOLERANCE`] times the largest dropped. The constraint
//! forces `Gᵀλ` of a consistent system are the same for every solution; the choice among
//! the multipliers is the minimum-norm one over the loop rows given the tree rows.
//!
//! Reference: D. Baraff, "Linear-time dynamics using Lagrange multipliers", SIGGRAPH
//! 1996; G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., 8.6.3 (one-sided
//! Jacobi SVD) and 5.5 (minimum-norm least squares).

// Small dense blocks with explicit row and column bounds read best as index loops.
#![allow(clippy::needless_range_loop)]

use crate::linalg::Mat3;

use super::blocks::{child_part, dot6_sequential, parent_part, Blk, V6};
pub use super::blocks::{SingularPivot, PIVOT_TOLERANCE};
use super::cholesky::SymmetricTree;
use super::constraints::{JointRows, Row};

/// Relative cut-off of the pseudo-inverse of the loop Schur complement: singular values
/// below this times the largest are treated as zero. Round-off puts the singular values of
/// dependent rows at a few `1e-16` relative; the smallest non-zero one of the test
/// four-bar is about `1e-2` relative, so `1e-10` separates them with margin both ways.
pub const PSEUDO_INVERSE_TOLERANCE: f64 = 1e-10;

#[derive(Clone, Copy, Debug)]
enum NodeKind {
    Body(usize),
    Joint(usize),
}

#[derive(Clone, Copy, Debug)]
struct Node {
    kind: NodeKind,
    parent: Option<usize>,
    size: usize,
}

/// The factorization of `A = G(q') M⁻¹ G(q)ᵀ`, preallocated for a model's tree and loops.
///
/// Reference: D. Baraff, SIGGRAPH 1996 (see the module documentation).
#[derive(Clone, Debug)]
pub struct TreeSolver {
    nodes: Vec<Node>,
    body_node: Vec<usize>,
    joint_node: Vec<Option<usize>>,
    d: Vec<Blk>,
    piv: Vec<[usize; 6]>,
    up: Vec<Blk>,
    down: Vec<Blk>,
    x: Vec<Blk>,
    z: Vec<V6>,
    loops: Vec<usize>,
    loop_rows: Vec<(usize, usize)>,
    loop_left: Vec<Row>,
    w: Vec<Vec<V6>>,
    s: Vec<f64>,
    sv: Vec<f64>,
    sigma: Vec<f64>,
    rhs_l: Vec<f64>,
    lam_l: Vec<f64>,
    rank: usize,
    sym: SymmetricTree,
    symmetric: bool,
}

fn lu(a: &mut Blk, n: usize, piv: &mut [usize; 6]) -> Result<(), f64> {
    let mut scale = 0.0f64;
    for row in a.iter().take(n) {
        for v in row.iter().take(n) {
            scale = scale.max(v.abs());
        }
    }
    for k in 0..n {
        let mut p = k;
        for i in k + 1..n {
            if a[i][k].abs() > a[p][k].abs() {
                p = i;
            }
        }
        piv[k] = p;
        let pivot = a[p][k];
        if !pivot.is_finite() || pivot.abs() <= PIVOT_TOLERANCE * scale {
            return Err(if scale > 0.0 { pivot.abs() / scale } else { 0.0 });
        }
        a.swap(k, p);
        let inv = 1.0 / a[k][k];
        for i in k + 1..n {
            let f = a[i][k] * inv;
            a[i][k] = f;
            for j in k + 1..n {
                a[i][j] -= f * a[k][j];
            }
        }
    }
    Ok(())
}

fn lu_solve(a: &Blk, n: usize, piv: &[usize; 6], b: &mut V6) {
    // The factorization swapped whole rows (multipliers included), so `P A = L U` with the
    // final `L`: permute `b` completely before the forward substitution.
    for k in 0..n {
        b.swap(k, piv[k]);
    }
    for k in 0..n {
        for i in k + 1..n {
            b[i] -= a[i][k] * b[k];
        }
    }
    for k in (0..n).rev() {
        let mut s = b[k];
        for j in k + 1..n {
            s -= a[k][j] * b[j];
        }
        b[k] = s / a[k][k];
    }
}

impl TreeSolver {
    /// The structure of a model: `parents[j]` the parent body of tree joint `j` (child `j`),
    /// `tree_rows[j]` whether it has rows (not free), `loops` the loop joints with their
    /// parent (`None`: world) and child bodies.
    #[must_use]
    pub fn new(parents: &[Option<usize>], tree_rows: &[bool], loops: &[(usize, Option<usize>, usize)]) -> Self {
        let nb = parents.len();
        let mut nodes = Vec::with_capacity(2 * nb);
        let mut body_node = vec![0; nb];
        let mut joint_node = vec![None; nb + loops.len()];
        for j in 0..nb {
            let body_parent = if tree_rows[j] {
                let parent = parents[j].map(|p| body_node[p]);
                joint_node[j] = Some(nodes.len());
                nodes.push(Node {
                    kind: NodeKind::Joint(j),
                    parent,
                    size: 0,
                });
                Some(nodes.len() - 1)
            } else {
                None
            };
            body_node[j] = nodes.len();
            nodes.push(Node {
                kind: NodeKind::Body(j),
                parent: body_parent,
                size: 6,
            });
        }
        let nn = nodes.len();
        let nl_max = 6 * loops.len();
        TreeSolver {
            nodes,
            body_node,
            joint_node,
            d: vec![[[0.0; 6]; 6]; nn],
            piv: vec![[0; 6]; nn],
            up: vec![[[0.0; 6]; 6]; nn],
            down: vec![[[0.0; 6]; 6]; nn],
            x: vec![[[0.0; 6]; 6]; nn],
            z: vec![[0.0; 6]; nn],
            loops: loops.iter().map(|l| l.0).collect(),
            loop_rows: Vec::with_capacity(nl_max),
            loop_left: Vec::with_capacity(nl_max),
            w: vec![vec![[0.0; 6]; nn]; nl_max],
            s: vec![0.0; nl_max * nl_max],
            sv: vec![0.0; nl_max * nl_max],
            sigma: vec![0.0; nl_max],
            rhs_l: vec![0.0; nl_max],
            lam_l: vec![0.0; nl_max],
            rank: 0,
            sym: SymmetricTree::new(parents),
            symmetric: false,
        }
    }

    /// Couple the symmetric factorization's rotational parts along the armatured hinges
    /// (see `cholesky.rs`); the general block LU ([`TreeSolver::factor`]) is not used with
    /// armature.
    pub(super) fn set_armature(&mut self, coupling: &[Option<super::armature::Coupling>]) {
        self.sym.set_armature(coupling);
    }

    /// Whether the model has loop joints (rows outside the tree, eliminated by the Schur
    /// complement): known from the structure, before any factorization.
    #[must_use]
    pub fn has_loops(&self) -> bool {
        !self.loops.is_empty()
    }

    /// The numerical rank of the loop Schur complement at the last factorization, and its
    /// size (equal when the loop rows are independent).
    #[must_use]
    pub fn loop_rank(&self) -> (usize, usize) {
        (self.rank, self.loop_rows.len())
    }

    /// Factor `A = G(q') M⁻¹ G(q)ᵀ` with `left` the rows at `q'` and `right` at `q` (the
    /// same active row counts), masses `mass` and body inertia tensors `inertia`.
    /// `joints[k] = (parent, child)` for every joint.
    ///
    /// # Errors
    /// A vanishing tree pivot (rows of the tree that depend on each other).
    pub fn factor(
        &mut self,
        mass: &[f64],
        inertia: &[Mat3],
        joints: &[(Option<usize>, usize)],
        left: &[JointRows],
        right: &[JointRows],
    ) -> Result<(), SingularPivot> {
        self.symmetric = false;
        for n in 0..self.nodes.len() {
            let node = self.nodes[n];
            let d = &mut self.d[n];
            *d = [[0.0; 6]; 6];
            match node.kind {
                NodeKind::Body(b) => {
                    for k in 0..3 {
                        d[k][k] = mass[b];
                        for l in 0..3 {
                            d[3 + k][3 + l] = inertia[b].m[k][l];
                        }
                    }
                    if let Some(NodeKind::Joint(j)) = node.parent.map(|p| self.nodes[p].kind) {
                        let s = left[j].n;
                        for k in 0..s {
                            let g = child_part(&right[j].grad[k]);
                            let gp = child_part(&left[j].grad[k]);
                            for r in 0..6 {
                                self.up[n][r][k] = -g[r];
                                self.down[n][k][r] = gp[r];
                            }
                        }
                    }
                }
                NodeKind::Joint(j) => {
                    let s = left[j].n;
                    self.nodes[n].size = s;
                    if node.parent.is_some() {
                        for k in 0..s {
                            let gp = parent_part(&left[j].grad[k]);
                            let g = parent_part(&right[j].grad[k]);
                            for r in 0..6 {
                                self.up[n][k][r] = gp[r];
                                self.down[n][r][k] = -g[r];
                            }
                        }
                    }
                }
            }
        }
        for n in (0..self.nodes.len()).rev() {
            let node = self.nodes[n];
            let s = node.size;
            if let Err(ratio) = lu(&mut self.d[n], s, &mut self.piv[n]) {
                return Err(match node.kind {
                    NodeKind::Body(b) => SingularPivot {
                        joint: None,
                        body: Some(b),
                        ratio,
                    },
                    NodeKind::Joint(j) => SingularPivot {
                        joint: Some(j),
                        body: None,
                        ratio,
                    },
                });
            }
            if let Some(p) = node.parent {
                let sp = self.nodes[p].size;
                let mut x = [[0.0; 6]; 6];
                for c in 0..sp {
                    let mut col = [0.0; 6];
                    for (r, v) in col.iter_mut().enumerate().take(s) {
                        *v = self.up[n][r][c];
                    }
                    lu_solve(&self.d[n], s, &self.piv[n], &mut col);
                    for (r, v) in col.iter().enumerate().take(s) {
                        x[r][c] = *v;
                    }
                }
                self.x[n] = x;
                let down = &self.down[n];
                let dp = &mut self.d[p];
                for (r, dpr) in dp.iter_mut().enumerate().take(sp) {
                    for (c, v) in dpr.iter_mut().enumerate().take(sp) {
                        let mut acc = 0.0;
                        for k in 0..s {
                            acc += down[r][k] * x[k][c];
                        }
                        *v -= acc;
                    }
                }
            }
        }
        self.factor_loops(joints, left, right);
        Ok(())
    }

    /// Factor the symmetric `A = G(q) M⁻¹ G(q)ᵀ` (`rows` at `q`) by the block Cholesky of
    /// `cholesky.rs`, loops as in [`TreeSolver::factor`]. Solves then agree with those
    /// after `factor(mass, inertia, joints, rows, rows)` to round-off.
    ///
    /// # Errors
    /// A vanishing tree pivot (rows of the tree that depend on each other).
    pub fn factor_symmetric(
        &mut self,
        mass: &[f64],
        inertia: &[Mat3],
        joints: &[(Option<usize>, usize)],
        rows: &[JointRows],
    ) -> Result<(), SingularPivot> {
        self.symmetric = true;
        let nb = self.body_node.len();
        self.sym.factor(mass, inertia, &rows[..nb])?;
        self.factor_loops(joints, rows, rows);
        Ok(())
    }

    fn factor_loops(&mut self, joints: &[(Option<usize>, usize)], left: &[JointRows], right: &[JointRows]) {
        self.loop_rows.clear();
        self.loop_left.clear();
        for &k in &self.loops {
            for r in 0..left[k].n {
                self.loop_rows.push((k, r));
                self.loop_left.push(left[k].grad[r]);
            }
        }
        let nl = self.loop_rows.len();
        if nl == 0 {
            self.rank = 0;
            return;
        }
        for l in 0..nl {
            let (k, r) = self.loop_rows[l];
            let (pa, ch) = joints[k];
            let g = &right[k].grad[r];
            self.z.iter_mut().for_each(|v| *v = [0.0; 6]);
            if let Some(p) = pa {
                let gp = parent_part(g);
                self.z[self.body_node[p]] = gp.map(|v| -v);
            }
            let gc = child_part(g);
            self.z[self.body_node[ch]] = gc.map(|v| -v);
            self.tree_solve();
            self.w[l].copy_from_slice(&self.z);
        }
        for l in 0..nl {
            let (k, _) = self.loop_rows[l];
            let (pa, ch) = joints[k];
            let g = self.loop_left[l];
            for m in 0..nl {
                let wm = &self.w[m];
                let mut v = dot6_sequential(&child_part(&g), &wm[self.body_node[ch]]);
                if let Some(p) = pa {
                    v += dot6_sequential(&parent_part(&g), &wm[self.body_node[p]]);
                }
                self.s[l * nl + m] = -v;
            }
        }
        self.rank = jacobi_svd(
            &mut self.s[..nl * nl],
            &mut self.sv[..nl * nl],
            &mut self.sigma[..nl],
            nl,
        );
    }

    /// Leaves-to-root forward elimination and root-to-leaves back substitution on `self.z`.
    fn tree_solve(&mut self) {
        if self.symmetric {
            self.sym.solve(&mut self.z, &self.body_node, &self.joint_node);
            return;
        }
        for n in (0..self.nodes.len()).rev() {
            let s = self.nodes[n].size;
            let mut y = self.z[n];
            lu_solve(&self.d[n], s, &self.piv[n], &mut y);
            self.z[n] = y;
            if let Some(p) = self.nodes[n].parent {
                let sp = self.nodes[p].size;
                for r in 0..sp {
                    let mut acc = 0.0;
                    for k in 0..s {
                        acc += self.down[n][r][k] * y[k];
                    }
                    self.z[p][r] -= acc;
                }
            }
        }
        for n in 0..self.nodes.len() {
            if let Some(p) = self.nodes[n].parent {
                let (s, sp) = (self.nodes[n].size, self.nodes[p].size);
                let zp = self.z[p];
                for r in 0..s {
                    let mut acc = 0.0;
                    for c in 0..sp {
                        acc += self.x[n][r][c] * zp[c];
                    }
                    self.z[n][r] -= acc;
                }
            }
        }
    }

    /// Solve `A λ = r` with the last factorization; `r` and `lambda` hold each joint's rows.
    pub fn solve(&mut self, joints: &[(Option<usize>, usize)], r: &[[f64; 6]], lambda: &mut [[f64; 6]]) {
        for n in 0..self.nodes.len() {
            self.z[n] = match self.nodes[n].kind {
                NodeKind::Body(_) => [0.0; 6],
                NodeKind::Joint(j) => r[j],
            };
        }
        self.tree_solve();
        let nl = self.loop_rows.len();
        if nl > 0 {
            for l in 0..nl {
                let (k, row) = self.loop_rows[l];
                let (pa, ch) = joints[k];
                let g = &self.loop_left[l];
                let mut v = dot6_sequential(&child_part(g), &self.z[self.body_node[ch]]);
                if let Some(p) = pa {
                    v += dot6_sequential(&parent_part(g), &self.z[self.body_node[p]]);
                }
                self.rhs_l[l] = r[k][row] - v;
            }
            pseudo_solve(
                &self.s[..nl * nl],
                &self.sv[..nl * nl],
                &self.sigma[..nl],
                nl,
                &self.rhs_l[..nl],
                &mut self.lam_l[..nl],
            );
            for l in 0..nl {
                let lam = self.lam_l[l];
                for (zn, wn) in self.z.iter_mut().zip(&self.w[l]) {
                    for c in 0..6 {
                        zn[c] -= wn[c] * lam;
                    }
                }
                let (k, row) = self.loop_rows[l];
                lambda[k][row] = lam;
            }
        }
        for (j, node) in self.joint_node.iter().enumerate() {
            if let Some(n) = node {
                lambda[j] = self.z[*n];
            }
        }
    }
}

/// One-sided Jacobi SVD of the `n×n` row-major `a` in place: on return the columns of `a`
/// are `U Σ` and `v` holds `V` (row-major), `sigma` the column norms. Returns the rank
/// at [`PSEUDO_INVERSE_TOLERANCE`].
fn jacobi_svd(a: &mut [f64], v: &mut [f64], sigma: &mut [f64], n: usize) -> usize {
    for i in 0..n {
        for j in 0..n {
            v[i * n + j] = if i == j { 1.0 } else { 0.0 };
        }
    }
    for _sweep in 0..60 {
        let mut rotated = false;
        for p in 0..n {
            for q in p + 1..n {
                let (mut al, mut be, mut ga) = (0.0, 0.0, 0.0);
                for i in 0..n {
                    let (x, y) = (a[i * n + p], a[i * n + q]);
                    al += x * x;
                    be += y * y;
                    ga += x * y;
                }
                if ga == 0.0 || ga.abs() <= f64::EPSILON * (al * be).sqrt() {
                    continue;
                }
                rotated = true;
                let zeta = (be - al) / (2.0 * ga);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                for m in [&mut *a, &mut *v] {
                    for i in 0..n {
                        let (x, y) = (m[i * n + p], m[i * n + q]);
                        m[i * n + p] = c * x - s * y;
                        m[i * n + q] = s * x + c * y;
                    }
                }
            }
        }
        if !rotated {
            break;
        }
    }
    let mut smax: f64 = 0.0;
    for j in 0..n {
        sigma[j] = (0..n).map(|i| a[i * n + j] * a[i * n + j]).sum::<f64>().sqrt();
        smax = smax.max(sigma[j]);
    }
    sigma.iter().filter(|&&s| s > PSEUDO_INVERSE_TOLERANCE * smax).count()
}

/// `x = V Σ⁺ Uᵀ b = Σ_j v_j (a_j · b) / σ_j²` over the kept singular values.
fn pseudo_solve(a: &[f64], v: &[f64], sigma: &[f64], n: usize, b: &[f64], x: &mut [f64]) {
    let smax = sigma.iter().fold(0.0f64, |m, &s| m.max(s));
    x.iter_mut().for_each(|e| *e = 0.0);
    for j in 0..n {
        if sigma[j].is_nan() || sigma[j] <= PSEUDO_INVERSE_TOLERANCE * smax {
            continue;
        }
        let coef = (0..n).map(|i| a[i * n + j] * b[i]).sum::<f64>() / (sigma[j] * sigma[j]);
        for i in 0..n {
            x[i] += v[i * n + j] * coef;
        }
    }
}
