//! Selective mass scaling of the axial waves: a larger stable step for the explicit
//! splitting at a stated change of the axial inertia only.
//!
//! The splitting's step is set by the axial waves (`ω_a/ω_b = 5.7` on the right-angle
//! cantilever at 16 elements per leg, [`super::impulse`]). Standard in explicit finite
//! elements is to add mass that only the stiff modes see. Here each element gets the
//! inertia of its **rate of stretch**: with `l = |x_b − x_a|` its chord length and `m_e =
//! ρA L₀` its mass, the kinetic energy becomes
//!
//! ```text
//! T = Σ_i |v_i|²  m_i/2 + Σ_e β m_e l̇_e²/2,        l̇_e = e_e·(v_b − v_a),  e_e = (x_b − x_a)/l
//! ```
//!
//! i.e. the mass matrix `M(x) = M₀ + Σ_e β m_e [[1, −1], [−1, 1]] ⊗ e_e e_eᵀ` with the
//! element's current direction. Rigid motions (`l̇ = 0`) and the bending (across the chord)
//! keep their lumped inertia; the element's axial mode gets `(1 + 4β)` times its inertia,
//! so its bound `ω² = 2(EA/L₀)/m` (per lumped end mass `m = m_e/2`) falls by `1 + 4β`
//! (Irons' bound holds for the assembled, now non-diagonal, mass). The default `β` brings
//! the axial bound down to the bending one: `β = ((ω_a/ω_b)² − 1)/4`. What it changes is
//! the axial inertia alone, whose modes lie far above the structure's response (the
//! right-angle cantilever's lowest axial frequency 157 rad/s against a response near 1);
//! its effect on a history is measured, not bounded (`liemid beam work-precision`).
//!
//! The kinetic energy depends on the configuration, so the translation drift is the
//! discrete Euler-Lagrange map of
//! `L_d(x₀, x₁) = h [ |x₁ − x₀|²_{M₀}/(2h²) + Σ_e β m_e (l_e(x₁) − l_e(x₀))²/(2h²) ]`
//! (a variational integrator of the free translation):
//!
//! ```text
//! p ← p + (h/2) F,  Π ← Π + (h/2) T              half impulse
//! (Π, R) ← torque-free midpoint rotation over h  (as in the splitting)
//! solve for μ:  x₁ = x₀ + M₀⁻¹ (h p − G(x₀) μ),   μ_e = β m_e (l_e(x₁) − l_e(x₀))
//! p ← p + (G(x₁) − G(x₀)) μ / h
//! F, T at the new configuration;  p ← p + (h/2) F,  Π ← Π + (h/2) T
//! ```
//!
//! with `G(x)` the columns `∇l_e` (`−e_e` at end a, `e_e` at end b). The equations for `μ`
//! (one unknown per element) are solved by Newton's method with the matrix
//! `A = Gᵀ M₀⁻¹ G + diag(1/(β m_e))` at `x₀`, symmetric positive definite and banded in
//! element order (elements couple through shared nodes); each iteration costs one
//! evaluation of the chord lengths and a banded solve. It stops when the last correction
//! is below 1e-13 of the element lengths: three iterations per step on the right-angle
//! cantilever. (Stopping one iteration earlier by Hairer and Wanner's contraction
//! estimate, θ/(1 − θ)|δμ| below the tolerance, was tried: a step forward and back then
//! missed the start by 1e-9 instead of 2e-12.) The step is a symmetric composition: time reversible (to the solve's
//! tolerance), order 2 (not symplectic: the rotation is EA's midpoint drift, docs/theory/rigid.md §9); `L_d` is invariant under rigid motions,
//! so a free structure keeps its total linear and angular momentum. The momenta `p` are the
//! canonical ones, `p = M(x) v`; the kinetic energy is `pᵀ M⁻¹ p/2 = Σ |p_i|²/(2 m_i) −
//! zᵀ A⁻¹ z/2` with `z = Gᵀ M₀⁻¹ p` (Woodbury; [`super::BeamSystem::totals_for`]).
//!
//! ## Reference
//! L. Olovsson, K. Simonsson, M. Unosson, *Selective mass scaling for explicit finite
//! element analyses*, Int. J. Numer. Meth. Engng. 63 (2005) 1436-1445; J. E. Marsden,
//! M. West, *Discrete mechanics and variational integrators*, Acta Numerica 10 (2001).

use super::{BeamSystem, NodeRef};
use crate::error::{Error, Result};
use crate::linalg::Vec3;

/// Newton iterations before the step is given up.
const MAX_ITERATIONS: u32 = 30;

/// The solve's tolerance on the stretch increments, relative to the element length.
const TOLERANCE: f64 = 1e-13;

/// The mass scaling's constants and per-step arrays (sized when the system is built).
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch {
    /// `β`: added stretch inertia as a multiple of the element mass (0: none).
    pub(crate) beta: f64,
    /// Each element's mass `ρA L₀`.
    element_mass: Vec<f64>,
    /// Each element's free (translating) body ends with the sign of `∇l` there.
    ends: Vec<[(usize, f64); 2]>,
    /// How many of `ends` are used.
    end_count: Vec<u8>,
    /// Half bandwidth of `A` in element order.
    width: usize,
    /// The band of `A`'s Cholesky factor, row by row (`width + 1` per row).
    band: Vec<f64>,
    /// The reciprocals of the factor's diagonal.
    inverse_diagonal: Vec<f64>,
    /// Newton iterations of the stretch equations so far.
    pub(crate) iterations: u64,
    /// Chord directions and lengths at the start of the step.
    direction: Vec<Vec3>,
    length: Vec<f64>,
    /// The unknowns, the residual.
    mu: Vec<f64>,
    residual: Vec<f64>,
    /// Positions at the start of the step, and after the unscaled drift.
    start: Vec<Vec3>,
    drift: Vec<Vec3>,
}

impl Scratch {
    /// The arrays for `system`'s elements and bodies, with `β = beta`.
    pub(crate) fn new(system: &BeamSystem, beta: f64) -> Self {
        let s = &system.structure;
        let b = &system.bodies;
        let ne = s.elements.len();
        let mut ends = vec![[(0usize, 0.0); 2]; ne];
        let mut end_count = vec![0u8; ne];
        for (k, e) in s.elements.iter().enumerate() {
            for (end, node) in e.ends.iter().enumerate() {
                if let NodeRef::Body(i) = *node {
                    if b.free[i] {
                        ends[k][end_count[k] as usize] = (i, if end == 0 { -1.0 } else { 1.0 });
                        end_count[k] += 1;
                    }
                }
            }
        }
        let mut width = 0;
        for i in 0..b.len() {
            let slots = &s.incidence[s.incidence_start[i]..s.incidence_start[i + 1]];
            if let (Some(lo), Some(hi)) = (
                slots.iter().map(|x| (x >> 1) as usize).min(),
                slots.iter().map(|x| (x >> 1) as usize).max(),
            ) {
                width = width.max(hi - lo);
            }
        }
        let element_mass = s
            .elements
            .iter()
            .zip(&system.frame.elements)
            .map(|(e, spec)| spec.section.mass_per_length * e.stiffness.length)
            .collect();
        Scratch {
            beta,
            element_mass,
            ends,
            end_count,
            width,
            band: vec![0.0; ne * (width + 1)],
            inverse_diagonal: vec![0.0; ne],
            iterations: 0,
            direction: vec![Vec3::ZERO; ne],
            length: vec![0.0; ne],
            mu: vec![0.0; ne],
            residual: vec![0.0; ne],
            start: vec![Vec3::ZERO; b.len()],
            drift: vec![Vec3::ZERO; b.len()],
        }
    }

    #[inline]
    fn at(&mut self, i: usize, j: usize) -> &mut f64 {
        &mut self.band[i * (self.width + 1) + (j + self.width - i)]
    }

    /// Directions and lengths of the chords at `position`, `A` there, factorised.
    fn factor(&mut self, system_position: &[Vec3], fixed: impl Fn(usize, &[Vec3], usize) -> Vec3, mass: &[f64]) {
        let ne = self.element_mass.len();
        for k in 0..ne {
            let d = fixed(k, system_position, 1) - fixed(k, system_position, 0);
            let l = d.norm();
            self.length[k] = l;
            self.direction[k] = d * (1.0 / l);
        }
        self.band.iter_mut().for_each(|v| *v = 0.0);
        for k in 0..ne {
            let mut diag = 1.0 / (self.beta * self.element_mass[k]);
            for &(i, _) in &self.ends[k][..self.end_count[k] as usize] {
                diag += 1.0 / mass[i];
            }
            *self.at(k, k) = diag;
            // Couplings with the earlier elements that share a translating body.
            let lo = k.saturating_sub(self.width);
            for j in lo..k {
                let mut v = 0.0;
                for &(i, si) in &self.ends[k][..self.end_count[k] as usize] {
                    for &(jb, sj) in &self.ends[j][..self.end_count[j] as usize] {
                        if jb == i {
                            v += si * sj * self.direction[k].dot(self.direction[j]) / mass[i];
                        }
                    }
                }
                *self.at(k, j) = v;
            }
        }
        // Banded Cholesky, in place.
        let w = self.width;
        for i in 0..ne {
            for j in i.saturating_sub(w)..=i {
                let mut s = *self.at(i, j);
                for k in i.saturating_sub(w).max(j.saturating_sub(w))..j {
                    s -= *self.at(i, k) * *self.at(j, k);
                }
                if i == j {
                    let d = s.sqrt();
                    *self.at(i, i) = d;
                    self.inverse_diagonal[i] = 1.0 / d;
                } else {
                    *self.at(i, j) = s * self.inverse_diagonal[j];
                }
            }
        }
    }

    /// `residual ← A⁻¹ residual` with the factor.
    fn solve(&mut self) {
        let (ne, w) = (self.element_mass.len(), self.width);
        for i in 0..ne {
            let mut s = self.residual[i];
            for k in i.saturating_sub(w)..i {
                s -= *self.at(i, k) * self.residual[k];
            }
            self.residual[i] = s * self.inverse_diagonal[i];
        }
        for i in (0..ne).rev() {
            let mut s = self.residual[i];
            for k in i + 1..(i + w + 1).min(ne) {
                s -= *self.at(k, i) * self.residual[k];
            }
            self.residual[i] = s * self.inverse_diagonal[i];
        }
    }
}

impl BeamSystem {
    /// The added stretch inertia `β` of [`super::BeamMethod::MassScaled`] (a multiple of
    /// each element's mass; see [`super::mass_scaling`]).
    #[must_use]
    pub fn axial_mass(&self) -> f64 {
        self.mass_scaling.beta
    }

    /// Newton iterations of [`BeamSystem::step_mass_scaled`]'s stretch equations so far.
    #[must_use]
    pub fn stretch_iterations(&self) -> u64 {
        self.mass_scaling.iterations
    }

    /// Set `β` of [`super::BeamMethod::MassScaled`]. The default, set when the system is
    /// built, brings the axial waves' bound down to the bending one:
    /// `β = max(0, ((ω_a/ω_b)² − 1)/4)`. The momenta are canonical (`p = M(x) v`): a
    /// state at rest, or in rigid motion, is the same state for every `β`.
    ///
    /// # Errors
    /// A `β` that is negative or not finite.
    pub fn set_axial_mass(&mut self, beta: f64) -> Result<()> {
        if !(beta.is_finite() && beta >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "axial mass",
                value: beta,
                reason: "the added stretch inertia must be finite and not negative",
            });
        }
        self.mass_scaling.beta = beta;
        Ok(())
    }

    /// The default `β`: `max(0, ((ω_a/ω_b)² − 1)/4)` of the element bounds.
    pub(crate) fn default_axial_mass(&self) -> f64 {
        let st = self.stability(0);
        let r = st.omega_axial_bound / st.omega_bending_bound;
        if r.is_finite() {
            (0.25 * (r * r - 1.0)).max(0.0)
        } else {
            0.0
        }
    }

    /// One step of the mass-scaled splitting (see [`super::mass_scaling`]); with `β = 0`
    /// it is [`BeamSystem::step`].
    ///
    /// # Errors
    /// A bad step, a failing midpoint solve, or the stretch equations not solved in 30
    /// Newton iterations (the system is then left mid-step).
    pub fn step_mass_scaled(&mut self, h: f64) -> Result<()> {
        if self.mass_scaling.beta == 0.0 {
            return self.step(h);
        }
        self.impulse.valid = false;
        let t = self.bodies.t;
        self.bodies.kick_rotate(&self.structure, h)?;
        let ms = &mut self.mass_scaling;
        let b = &mut self.bodies;
        let s = &self.structure;
        ms.start.copy_from_slice(&b.position);
        for i in 0..b.len() {
            ms.drift[i] = if b.free[i] {
                b.position[i] + b.momentum[i] * (h / b.mass[i])
            } else {
                b.position[i]
            };
        }
        let end_position = |k: usize, position: &[Vec3], end: usize| match s.elements[k].ends[end] {
            NodeRef::Body(i) => position[i],
            NodeRef::Fixed(j) => s.fixed_position[j],
        };
        ms.factor(&b.position, end_position, &b.mass);
        ms.mu.iter_mut().for_each(|m| *m = 0.0);
        let ne = ms.mu.len();
        let mut iterations = 0;
        let mut largest = f64::INFINITY;
        let mut converged = false;
        loop {
            // x(μ) = drift − M₀⁻¹ G(x₀) μ.
            b.position.copy_from_slice(&ms.drift);
            for k in 0..ne {
                for &(i, sign) in &ms.ends[k][..ms.end_count[k] as usize] {
                    b.position[i] -= ms.direction[k] * (sign * ms.mu[k] / b.mass[i]);
                }
            }
            if converged || iterations == MAX_ITERATIONS {
                break;
            }
            for k in 0..ne {
                let l = (end_position(k, &b.position, 1) - end_position(k, &b.position, 0)).norm();
                ms.residual[k] = l - ms.length[k] - ms.mu[k] / (ms.beta * ms.element_mass[k]);
            }
            ms.solve();
            largest = 0.0;
            for k in 0..ne {
                ms.mu[k] += ms.residual[k];
                let d = ms.residual[k].abs() / (ms.beta * ms.element_mass[k] * s.elements[k].stiffness.length);
                // A NaN (a chord of zero length) must not pass as converged.
                largest = if d.is_nan() || largest.is_nan() {
                    f64::NAN
                } else {
                    largest.max(d)
                };
            }
            iterations += 1;
            converged = largest <= TOLERANCE;
        }
        ms.iterations += u64::from(iterations);
        if !converged || !largest.is_finite() {
            return Err(Error::NewtonDidNotConverge {
                method: "mass-scaled splitting",
                equation: "the stretch equations of the translation drift (largest relative stretch correction)",
                t,
                h,
                residual: largest,
                iterations: MAX_ITERATIONS,
            });
        }
        // p ← p + (G(x₁) − G(x₀)) μ / h.
        for k in 0..ne {
            let d = end_position(k, &b.position, 1) - end_position(k, &b.position, 0);
            let change = (d * (1.0 / d.norm()) - ms.direction[k]) * (ms.mu[k] / h);
            for &(i, sign) in &ms.ends[k][..ms.end_count[k] as usize] {
                b.momentum[i] += change * sign;
            }
        }
        self.bodies.finish_step(&self.structure, h);
        Ok(())
    }

    /// The kinetic energy's correction for the mass scaling at the current state,
    /// `−zᵀ A⁻¹ z/2` with `z = Gᵀ M₀⁻¹ p` (0 with `β = 0`).
    pub(crate) fn mass_scaling_kinetic_correction(&self) -> f64 {
        if self.mass_scaling.beta == 0.0 {
            return 0.0;
        }
        let mut ms = self.mass_scaling.clone();
        let b = &self.bodies;
        let s = &self.structure;
        let end_position = |k: usize, position: &[Vec3], end: usize| match s.elements[k].ends[end] {
            NodeRef::Body(i) => position[i],
            NodeRef::Fixed(j) => s.fixed_position[j],
        };
        ms.factor(&b.position, end_position, &b.mass);
        let ne = ms.mu.len();
        for k in 0..ne {
            let mut z = 0.0;
            for &(i, sign) in &ms.ends[k][..ms.end_count[k] as usize] {
                z += sign * ms.direction[k].dot(b.momentum[i]) / b.mass[i];
            }
            ms.residual[k] = z;
            ms.mu[k] = z;
        }
        ms.solve();
        -0.5 * (0..ne).map(|k| ms.mu[k] * ms.residual[k]).sum::<f64>()
    }
}
