//! The two-node corotational beam element: linear elastic (Euler-Bernoulli) in a frame
//! that follows the element, exact rigid-body invariance, forces that are the exact
//! gradient of its strain energy.
//!
//! Each end carries a triad `T = R C` (the node's attitude `R` times the constant map `C`
//! from the node's body axes to the element's initial axes). The corotated frame
//! `E = [e₁ e₂ e₃]` has `e₁` along the chord `x_b − x_a` (length `l`), and `e₃ ∝ e₁ × q`
//! with `q = (T_a ê₂ + T_b ê₂)/2` the mean of the end triads' second axes, `e₂ = e₃ × e₁`.
//! The local deformations are the stretch `u = l − L₀` and the end rotations
//! `θ_a = log(Eᵀ T_a)`, `θ_b = log(Eᵀ T_b)` (torsion `θ·e₁`, bending `θ·e₂`, `θ·e₃`), and
//! the strain energy is that of the linear Euler-Bernoulli element in the corotated frame:
//!
//! ```text
//! V = EA/(2L₀) u² + GJ/(2L₀) (θ_b1 − θ_a1)²
//!   + Σ_{k=2,3} EI_k/(2L₀) (4 θ_ak² + 4 θ_ak θ_bk + 4 θ_bk²)
//! ```
//!
//! Its variation under spatial virtual rotations `w` of the triads (`δT = ŵ T`) and
//! displacements `δx` is, with `m = ∂V/∂θ`, `M = E Jr⁻¹(θ) m` (since
//! `δθ = Jl⁻¹(θ) Eᵀ (w − w_E)` and `Jl⁻ᵀ = Jr⁻¹`) and `S = M_a + M_b`,
//!
//! ```text
//! δV = g·(δx_b − δx_a) + τ_a·w_a + τ_b·w_b,
//! g  = N e₁ + (S·e₂ + S·e₁ (q·e₁)/(q·e₂)) e₃/l − (S·e₃) e₂/l,
//! τ  = M − (S·e₁)/(2 q·e₂) (T ê₂ × e₃),
//! ```
//!
//! from the spin of the corotated frame, `w_E·e₂ = −e₃·Δ/l`, `w_E·e₃ = e₂·Δ/l`,
//! `w_E·e₁ = ((q·e₁)(w_E·e₂) + e₃·δq)/(q·e₂)`. The nodal forces are `−∂V`: `F_a = g`,
//! `F_b = −g`, moments `−τ_a`, `−τ_b`; they sum to zero force and zero moment about any
//! point (`τ_a + τ_b = −(x_b − x_a) × g`), so internal forces keep the total linear and
//! angular momentum.
//!
//! Euler-Bernoulli rather than Timoshenko: the benchmarks are slender (the right-angle
//! cantilever's global shear flexibility `EI/(κ G A L²)` is about 2e-4 of its bending
//! flexibility), and the element then needs no shear-locking treatment.
//!
//! ## Reference
//! M. A. Crisfield, *A consistent co-rotational formulation for non-linear,
//! three-dimensional, beam-elements*, Comput. Methods Appl. Mech. Engrg. 81 (1990);
//! J.-M. Battini, C. Pacoste, *Co-rotational beam elements with warping effects in
//! instability problems*, Comput. Methods Appl. Mech. Engrg. 191 (2002).

use crate::linalg::{Mat3, Vec3};
use crate::so3;

/// The stiffness constants of one element (per its initial length `L₀`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementStiffness {
    /// Initial length `L₀`.
    pub length: f64,
    /// `EA/L₀`.
    pub axial: f64,
    /// `GJ/L₀`.
    pub torsion: f64,
    /// `EI₂/L₀` (bending about `e₂`).
    pub bending2: f64,
    /// `EI₃/L₀` (bending about `e₃`).
    pub bending3: f64,
}

/// The nodal forces and moments (spatial) that one element exerts on its two nodes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EndForces {
    /// Force on end a.
    pub force_a: Vec3,
    /// Moment on end a.
    pub moment_a: Vec3,
    /// Force on end b.
    pub force_b: Vec3,
    /// Moment on end b.
    pub moment_b: Vec3,
}

/// A matrix from its three columns.
#[inline]
pub(crate) fn from_columns(a: Vec3, b: Vec3, c: Vec3) -> Mat3 {
    Mat3::from_rows([[a.x, b.x, c.x], [a.y, b.y, c.y], [a.z, b.z, c.z]])
}

/// The local deformations `(u, θ_a, θ_b)` and what the forces need of the frame.
struct Local {
    frame: Mat3,
    e: [Vec3; 3],
    l: f64,
    q: Vec3,
    stretch: f64,
    theta_a: Vec3,
    theta_b: Vec3,
}

/// `log(Q)` for the small local rotations of an element: below `|sin θ| = 0.1` (and
/// `cos θ > 0`) by the series of `θ/sin θ = asin(s)/s = Σ_k (2k)!/(4^k (k!)² (2k+1)) s^{2k}`
/// through `s¹⁶` (the first term left out, `0.0086 s¹⁸`, is below 1e-20), without the
/// `atan2` of [`so3::log`], which it calls otherwise (10 % of the splitting's step on the
/// right-angle cantilever went to `atan2`: its local angles lie mostly between 0.01 and 0.1).
#[inline]
fn local_log(q: &Mat3) -> Vec3 {
    let w = so3::vee(q);
    let s2 = w.norm_squared();
    if s2 < 1e-2 && q.trace() > 1.0 {
        let f = 1.0
            + s2 * (1.0 / 6.0
                + s2 * (3.0 / 40.0
                    + s2 * (5.0 / 112.0
                        + s2 * (35.0 / 1152.0
                            + s2 * (63.0 / 2816.0
                                + s2 * (231.0 / 13312.0 + s2 * (143.0 / 10240.0 + s2 * (6435.0 / 557_056.0))))))));
        w * f
    } else {
        so3::log(q)
    }
}

#[inline]
fn local(k: &ElementStiffness, xa: Vec3, xb: Vec3, ta: &Mat3, tb: &Mat3) -> Local {
    let d = xb - xa;
    let l = d.norm();
    let e1 = d * (1.0 / l);
    let q = (ta.col(1) + tb.col(1)) * 0.5;
    let n3 = e1.cross(q);
    let e3 = n3 * (1.0 / n3.norm());
    let e2 = e3.cross(e1);
    let frame = from_columns(e1, e2, e3);
    let ft = frame.transpose();
    Local {
        frame,
        e: [e1, e2, e3],
        l,
        q,
        stretch: l - k.length,
        theta_a: local_log(&(ft * *ta)),
        theta_b: local_log(&(ft * *tb)),
    }
}

/// `∂V/∂θ_a`, `∂V/∂θ_b` in the corotated frame.
#[inline]
fn local_moments(k: &ElementStiffness, a: Vec3, b: Vec3) -> (Vec3, Vec3) {
    let torsion = k.torsion * (b.x - a.x);
    (
        Vec3::new(
            -torsion,
            k.bending2 * (4.0 * a.y + 2.0 * b.y),
            k.bending3 * (4.0 * a.z + 2.0 * b.z),
        ),
        Vec3::new(
            torsion,
            k.bending2 * (2.0 * a.y + 4.0 * b.y),
            k.bending3 * (2.0 * a.z + 4.0 * b.z),
        ),
    )
}

/// The strain energy `V` of the element at nodal positions `xa`, `xb` and end triads
/// `ta`, `tb` (columns: the element's axes as carried by each node).
#[must_use]
pub fn strain_energy(k: &ElementStiffness, xa: Vec3, xb: Vec3, ta: &Mat3, tb: &Mat3) -> f64 {
    let s = local(k, xa, xb, ta, tb);
    let (ma, mb) = local_moments(k, s.theta_a, s.theta_b);
    0.5 * (k.axial * s.stretch * s.stretch + ma.dot(s.theta_a) + mb.dot(s.theta_b))
}

/// The forces and moments `−∂V` on the element's nodes (see the module documentation).
#[must_use]
#[inline]
pub fn end_forces(k: &ElementStiffness, xa: Vec3, xb: Vec3, ta: &Mat3, tb: &Mat3) -> EndForces {
    end_forces_of::<true>(k, xa, xb, ta, tb)
}

/// The forces and moments `−∂V_b` of the bending and torsion energy alone,
/// `V_b = V − EA/(2L₀) u²`: [`end_forces`] without the axial term `N e₁` of `g`. With
/// [`axial_force`] they sum to [`end_forces`] (the slow and fast parts of the impulse
/// method, [`super::impulse`]).
#[must_use]
#[inline]
pub fn bending_end_forces(k: &ElementStiffness, xa: Vec3, xb: Vec3, ta: &Mat3, tb: &Mat3) -> EndForces {
    end_forces_of::<false>(k, xa, xb, ta, tb)
}

/// The axial force on end a, `−∂V_a/∂x_a = EA/L₀ (l − L₀) e₁` of the axial energy
/// `V_a = EA/(2L₀) (|x_b − x_a| − L₀)²` (end b gets its negative; no moments).
#[must_use]
#[inline]
pub fn axial_force(k: &ElementStiffness, xa: Vec3, xb: Vec3) -> Vec3 {
    let d = xb - xa;
    let l = d.norm();
    d * (k.axial * (l - k.length) / l)
}

#[inline]
fn end_forces_of<const AXIAL: bool>(k: &ElementStiffness, xa: Vec3, xb: Vec3, ta: &Mat3, tb: &Mat3) -> EndForces {
    let s = local(k, xa, xb, ta, tb);
    let [e1, e2, e3] = s.e;
    let (ma, mb) = local_moments(k, s.theta_a, s.theta_b);
    let sa = s.frame * so3::right_jacobian_inverse_apply(s.theta_a, ma);
    let sb = s.frame * so3::right_jacobian_inverse_apply(s.theta_b, mb);
    let sum = sa + sb;
    let (s1, s2, s3) = (sum.dot(e1), sum.dot(e2), sum.dot(e3));
    let (q1, q2) = (s.q.dot(e1), s.q.dot(e2));
    let axial = if AXIAL { k.axial * s.stretch } else { 0.0 };
    let g = e1 * axial + e3 * ((s2 + s1 * q1 / q2) / s.l) - e2 * (s3 / s.l);
    let c = s1 / (2.0 * q2);
    let tau_a = sa - ta.col(1).cross(e3) * c;
    let tau_b = sb - tb.col(1).cross(e3) * c;
    EndForces {
        force_a: g,
        moment_a: -tau_a,
        force_b: -g,
        moment_b: -tau_b,
    }
}

/// The largest eigenvalue `ω²` of the element's linearised stiffness against its share of
/// the lumped masses (`m = ρA L₀/2` and rotary `J = ρI L₀/2` at each end), in closed form:
/// axial `2(EA/L₀)/m`, torsion `2(GJ/L₀)/J₁`, bending `24 (EI/L₀)/(L₀² m) + 6 (EI/L₀)/J`
/// (the antisymmetric mode, `w_a = −w_b`, `θ_a = θ_b`; the symmetric one is `2 (EI/L₀)/J`). By Irons' theorem the
/// largest of these over the elements bounds the assembled structure's `ω²_max` from above.
///
/// ## Reference
/// B. M. Irons, *Applications of a theorem on eigenvalues to finite element problems*,
/// University of Wales, Swansea, CR/132/70 (1970); T. Belytschko, W. K. Liu, B. Moran,
/// *Nonlinear Finite Elements for Continua and Structures*, Wiley (2000), section 6.3.
#[must_use]
pub fn omega_squared_bound(k: &ElementStiffness, mass: f64, rotary: Vec3) -> f64 {
    let (axial, rest) = omega_squared_bounds(k, mass, rotary);
    axial.max(rest)
}

/// [`omega_squared_bound`] in two parts: the axial mode's `2(EA/L₀)/m`, and the largest of
/// the torsion and bending modes' (the bound of the impulse method's outer step, whose
/// axial forces are substepped).
#[must_use]
pub fn omega_squared_bounds(k: &ElementStiffness, mass: f64, rotary: Vec3) -> (f64, f64) {
    let l2 = k.length * k.length;
    let axial = 2.0 * k.axial / mass;
    let torsion = 2.0 * k.torsion / rotary.x;
    let bend2 = 24.0 * k.bending2 / (l2 * mass) + 6.0 * k.bending2 / rotary.y;
    let bend3 = 24.0 * k.bending3 / (l2 * mass) + 6.0 * k.bending3 / rotary.z;
    (axial, torsion.max(bend2).max(bend3))
}
