//! Hinge armature, exact in maximal coordinates: the constant rotational mass matrix
//! `𝕁 = blockdiag(I_i) + Σ_hinges a u uᵀ` of the stacked body-frame rates and its
//! solves in tree order.
//!
//! A hinge with axis `n_c` (child frame) and `n_p` (parent frame) has the rate
//! `q̇ = n_c·W_c − n_p·W_p` (`W` the body-frame angular velocities), so the armature's
//! `½ a q̇²` is `½ a (uᵀW)²` with `u` = `n_c` in the child's slot and `−n_p` in the
//! parent's. `𝕁` has the diagonal blocks `I_i + Σ a n nᵀ` (over the armatured hinges that
//! touch body `i`) and, per armatured hinge with a parent body, the coupling
//! `𝕁_cp = −a n_c n_pᵀ` between child and parent: the tree's pattern. A block `LDUᵀ`
//! eliminated from the leaves to the root (children have larger indices than their
//! parents) has no fill-in: eliminating child `b` changes only its parent's pivot,
//! `D_p ← D_p − 𝕁_pb D_b⁻¹ 𝕁_bp = D_p − k² (n_c·D_b⁻¹ n_c) n_p n_pᵀ` (`k` the
//! coupling's scale). The same routine factors the Jacobian of the coupled drift
//! (`𝕁/τ` plus a non-symmetric block per body): the pivots are general 3x3 blocks,
//! inverted once per factorization. Factor and solve cost O(bodies) and allocate nothing.
//!
//! Reference: docs/theory/multibody.md §7.

use crate::linalg::{Mat3, Vec3};

/// One armatured hinge between a child body and its parent body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Coupling {
    /// The armature `a` (kg m²).
    pub(super) a: f64,
    /// The axis in the child's frame.
    pub(super) n_c: Vec3,
    /// The axis in the parent's frame.
    pub(super) n_p: Vec3,
    /// The parent body.
    pub(super) parent: usize,
}

/// `𝕁` of a system with hinge armature: per-body blocks, couplings, and its factor.
///
/// Reference: docs/theory/multibody.md §7.
#[derive(Clone, Debug)]
pub(super) struct Armature {
    /// `𝕁_ii = I_i + Σ a n nᵀ`.
    pub(super) block: Vec<Mat3>,
    /// `Σ a n nᵀ` alone (the armature's part of `𝕁_ii`).
    pub(super) extra: Vec<Mat3>,
    /// The coupling of tree joint `b` (child body `b`) to its parent body, if armatured.
    pub(super) coupling: Vec<Option<Coupling>>,
    /// The inverted pivots of `𝕁` itself (constant).
    dinv: Vec<Mat3>,
}

impl Armature {
    /// `𝕁` from the inertia tensors and the armatured tree hinges `(child, a, n_c, n_p,
    /// parent)`; `None` when a pivot is singular (never for positive inertia).
    pub(super) fn new(inertia: &[Mat3], hinges: &[(usize, f64, Vec3, Vec3, Option<usize>)]) -> Option<Self> {
        let nb = inertia.len();
        let mut extra = vec![Mat3::ZERO; nb];
        let mut coupling = vec![None; nb];
        for &(child, a, n_c, n_p, parent) in hinges {
            extra[child] = extra[child] + Mat3::outer(n_c, n_c) * a;
            if let Some(p) = parent {
                extra[p] = extra[p] + Mat3::outer(n_p, n_p) * a;
                coupling[child] = Some(Coupling { a, n_c, n_p, parent: p });
            }
        }
        let block: Vec<Mat3> = inertia.iter().zip(&extra).map(|(i, e)| *i + *e).collect();
        let mut arm = Armature {
            block,
            extra,
            coupling,
            dinv: vec![Mat3::ZERO; nb],
        };
        let mut dinv = vec![Mat3::ZERO; nb];
        let block = arm.block.clone();
        if !arm.factor(1.0, |i| block[i], &mut dinv) {
            return None;
        }
        arm.dinv = dinv;
        Some(arm)
    }

    /// Factor `K = blockdiag(diag(i)) + scale · (𝕁's couplings)` into `dinv` (the inverted
    /// pivots). Returns false on a singular pivot.
    pub(super) fn factor(&self, scale: f64, diag: impl Fn(usize) -> Mat3, dinv: &mut [Mat3]) -> bool {
        for (i, d) in dinv.iter_mut().enumerate() {
            *d = diag(i);
        }
        for b in (0..dinv.len()).rev() {
            let Some(inv) = dinv[b].inverse() else { return false };
            dinv[b] = inv;
            if let Some(c) = self.coupling[b] {
                let k = scale * c.a;
                let s = c.n_c.dot(inv * c.n_c);
                dinv[c.parent] = dinv[c.parent] - Mat3::outer(c.n_p, c.n_p) * (k * k * s);
            }
        }
        true
    }

    /// Solve `K x = r` in place (`K` factored by [`Armature::factor`] with `scale` into
    /// `dinv`).
    pub(super) fn solve_with(&self, scale: f64, dinv: &[Mat3], x: &mut [Vec3]) {
        for b in (0..x.len()).rev() {
            if let Some(c) = self.coupling[b] {
                let k = scale * c.a;
                let y = dinv[b] * x[b];
                x[c.parent] += c.n_p * (k * c.n_c.dot(y));
            }
        }
        for b in 0..x.len() {
            let mut r = x[b];
            if let Some(c) = self.coupling[b] {
                let k = scale * c.a;
                r += c.n_c * (k * c.n_p.dot(x[c.parent]));
            }
            x[b] = dinv[b] * r;
        }
    }

    /// `x ← 𝕁⁻¹ x` (momenta to body-frame rates), in tree order.
    pub(super) fn solve(&self, x: &mut [Vec3]) {
        self.solve_with(1.0, &self.dinv, x);
    }

    /// `out += scale · (𝕁's couplings) w`.
    pub(super) fn add_couplings(&self, scale: f64, w: &[Vec3], out: &mut [Vec3]) {
        for b in 0..w.len() {
            if let Some(c) = self.coupling[b] {
                let k = scale * c.a;
                out[b] -= c.n_c * (k * c.n_p.dot(w[c.parent]));
                out[c.parent] -= c.n_p * (k * c.n_c.dot(w[b]));
            }
        }
    }

    /// `u·𝕁_iiᵀ⁻¹ u`-free estimate of a row's own rotational response at body `i`:
    /// `w·𝕁_ii⁻¹ w` (the diagonal block's inverse; the dampers' stiffness test).
    pub(super) fn own_response(&self, i: usize, w: Vec3) -> f64 {
        self.block[i].solve(w).map_or(0.0, |x| w.dot(x))
    }
}

/// The coupled torque-free solve of one half drift: `Ψ` (stacked over the bodies) from
/// `g(Ψ) = 𝕁Ψ − τ f(Ψ) = 0` with `f_i = exp(−Ψ_i/2) P_i` (midpoint, (M)) or
/// `Jr(Ψ_i) P_i` (variational, (V)). Written per body as `g_i = E_i Ψ_i + (𝕁's couplings
/// Ψ)_i + g⁰_i(Ψ_i)`, `E_i` the armature's part of `𝕁_ii` and `g⁰_i` the single-body
/// residual of the drift's equation with `I_i`; Newton's Jacobian is `𝕁` with the
/// diagonal blocks `E_i + ∂g⁰_i/∂Ψ_i`, factored in tree order. Starts from the third-order
/// predictor `Ψ = τ 𝕁⁻¹ (P + ½ P × Ψ₀)`, `Ψ₀ = τ 𝕁⁻¹ P` (or from `psi` itself with `warm`),
/// stops by the crate's rule on `max_i |δ_i|` (a correction at round-off of `Ψ`). The
/// iteration is a simplified Newton one: the Jacobian is factored at the first iterate (or,
/// with `reuse`, the factor in `dinv` from the last solve of the same equation is kept) and
/// again only after a correction that did not shrink fourfold. The Jacobian moves with
/// `Ψ` and `P` by `O(τ |P| |ΔΨ|)` against `𝕁`, so the chord contracts about as fast as
/// Newton does from these starts. Measured in instructions (callgrind) against Newton
/// factoring at every iterate: the standing quadruped with contacts to 0.3 s, 639 → 545 M;
/// the humanoid and the arm of `benchmarks/models` with armature 0.1 and damping 1 on
/// every hinge to 0.5 s, 431 → 348 M and 227 → 189 M.
///
/// Reference: docs/theory/multibody.md §7.
#[allow(clippy::too_many_arguments)]
pub(super) fn coupled_increments(
    arm: &Armature,
    inertia: &[crate::inertia::Inertia],
    drift: super::method::Drift,
    p: &[Vec3],
    tau: f64,
    warm: bool,
    reuse: bool,
    psi: &mut [Vec3],
    dinv: &mut [Mat3],
    g: &mut [Vec3],
) -> Result<u32, crate::midpoint::NotConverged> {
    use super::method::Drift;
    use crate::midpoint::{NewtonStop, NotConverged, MAX_INCREMENT_ANGLE, MAX_ITERATIONS};
    let n = p.len();
    if !warm {
        for i in 0..n {
            psi[i] = p[i] * tau;
        }
        arm.solve(psi);
        for i in 0..n {
            g[i] = (p[i] + p[i].cross(psi[i]) * 0.5) * tau;
        }
        arm.solve(g);
        psi.copy_from_slice(g);
    }
    let mut stop = NewtonStop::new();
    let (mut refactor, mut previous) = (!reuse, f64::INFINITY);
    for it in 1..=MAX_ITERATIONS {
        for i in 0..n {
            let own = match drift {
                Drift::Midpoint => crate::midpoint::residual(&inertia[i], p[i], tau, psi[i]),
                Drift::Variational => crate::variational::residual(&inertia[i], p[i], tau, psi[i]),
            };
            g[i] = own + arm.extra[i] * psi[i];
        }
        arm.add_couplings(1.0, psi, g);
        let diag = |i: usize| {
            arm.extra[i]
                + match drift {
                    Drift::Midpoint => crate::midpoint::jacobian(&inertia[i], p[i], tau, psi[i]),
                    Drift::Variational => crate::variational::jacobian(&inertia[i], p[i], tau, psi[i]),
                }
        };
        let residual = g.iter().fold(0.0f64, |m, v| m.max(v.max_abs()));
        let scale = p.iter().fold(0.0f64, |m, v| m.max(v.max_abs())) * tau.abs();
        let fail = NotConverged::Iterations {
            residual: if scale > 0.0 { residual / scale } else { residual },
            iterations: it - 1,
        };
        if refactor && !arm.factor(1.0, diag, dinv) {
            return Err(fail);
        }
        arm.solve_with(1.0, dinv, g);
        let (mut dmax, mut xmax) = (0.0f64, 0.0f64);
        for i in 0..n {
            psi[i] -= g[i];
            dmax = dmax.max(g[i].max_abs());
            xmax = xmax.max(psi[i].max_abs());
        }
        if !(dmax.is_finite() && xmax.is_finite()) {
            return Err(fail);
        }
        refactor = dmax > 0.25 * previous;
        previous = dmax;
        if stop.done(dmax, xmax) || dmax == 0.0 {
            if let Some(angle) = psi.iter().map(|v| v.norm()).find(|a| *a > MAX_INCREMENT_ANGLE) {
                return Err(NotConverged::IncrementTooLarge { angle });
            }
            return Ok(it);
        }
    }
    let residual = g.iter().fold(0.0f64, |m, v| m.max(v.max_abs()));
    Err(NotConverged::Iterations {
        residual,
        iterations: MAX_ITERATIONS,
    })
}
