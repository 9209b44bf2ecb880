//! The impulse method (multiple time stepping): the stiff axial forces in substeps, the
//! bending, torsion and load forces at the outer step.
//!
//! The explicit splitting's step is set by the axial waves: an element's axial mode has
//! `ω² = 2(EA/L₀)/m`, its bending mode `24 (EI/L₀)/(L₀² m) + 6 (EI/L₀)/J`
//! ([`super::element::omega_squared_bounds`]); on the right-angle cantilever
//! (`EA/EI = 10³`) the axial bound is 5.7 times the bending one at 16 elements per leg and
//! 11.4 times at 8. Split the Hamiltonian as
//!
//! ```text
//! H = [T_trans(p) + T_rot(Π) + V_a(x)] + V_b(x, R) + V_load(x, R, t),
//! V_a = Σ EA/(2L₀) (|x_b − x_a| − L₀)²   (positions only),   V_b = V − V_a
//! ```
//!
//! and step (Grubmüller et al., Tuckerman et al.'s r-RESPA; for rigid bodies with the
//! rotation of the splitting):
//!
//! ```text
//! p ← p + (h/2) F_b,  Π ← Π + (h/2) T_b          slow half kick (bending, torsion, loads)
//! (Π, R) ← torque-free midpoint rotation over h     (T_rot: as in the splitting)
//! m times, δ = h/m:                                  Verlet on T_trans + V_a
//!     p ← p + (δ/2) F_a,  x ← x + δ p/m,  F_a(x),  p ← p + (δ/2) F_a
//! F_b, T_b at the new configuration and t + h
//! p ← p + (h/2) F_b,  Π ← Π + (h/2) T_b          slow half kick
//! ```
//!
//! `T_rot` acts on `(R, Π)` and `T_trans + V_a` on `(x, p)`, so the two inner flows commute
//! and the inner map is their product. Every piece is a symmetric map, so the step is time
//! reversible, of order 2 (not symplectic: the rotation is EA's midpoint drift, docs/theory/rigid.md §9), and keeps the total momenta of a free
//! structure (the axial forces are pairwise and central). It costs one bending evaluation
//! per outer step (the element's corotational kernel without the axial term) and `m` axial
//! evaluations (one chord length per element). It is stable for
//! `h ω_b < 2` with `ω_b` the bending-torsion bound and `δ ω_a < 2` with `ω_a` the axial
//! one; [`substeps`] takes `m = ⌈h ω_a / 1.8⌉` (0.9 of the inner limit). Impulse methods can
//! resonate when `h ω_a` is near a multiple of `π` where the slow and fast forces couple;
//! in a straight member the two act on orthogonal directions (along the chord and across
//! it) and couple only through the rotation of the chord.
//!
//! ## Reference
//! H. Grubmüller, H. Heller, A. Windemuth, K. Schulten, Mol. Simul. 6 (1991) 121-142;
//! M. Tuckerman, B. J. Berne, G. J. Martyna, J. Chem. Phys. 97 (1992) 1990-2001;
//! E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., Springer
//! (2006), section VIII.4.

use super::{BeamSystem, NodeRef};
use crate::error::{Error, Result};
use crate::linalg::Vec3;
use crate::many::Configuration;
use crate::midpoint::newton_error;

/// The forces the impulse method keeps between steps.
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch {
    /// Slow forces (spatial) and torques (body frame): bending, torsion, loads, gravity.
    slow_force: Vec<Vec3>,
    slow_torque: Vec<Vec3>,
    /// Axial forces (spatial).
    axial_force: Vec<Vec3>,
    /// Whether the arrays belong to the current state.
    pub(crate) valid: bool,
    /// The axial waves' bound `ω_a` (set when the system is built).
    pub(crate) omega_axial: f64,
}

impl Scratch {
    pub(crate) fn new(bodies: usize) -> Self {
        Scratch {
            slow_force: vec![Vec3::ZERO; bodies],
            slow_torque: vec![Vec3::ZERO; bodies],
            axial_force: vec![Vec3::ZERO; bodies],
            valid: false,
            omega_axial: 0.0,
        }
    }
}

/// The inner steps of an outer step `h`: `⌈|h| ω_a / 1.8⌉` (at least 1), with `ω_a` the
/// axial waves' bound ([`super::Stability::omega_axial_bound`]).
#[must_use]
pub fn substeps(h: f64, omega_axial: f64) -> usize {
    let m = (h.abs() * omega_axial / 1.8).ceil();
    if m.is_finite() && m >= 1.0 {
        m as usize
    } else {
        1
    }
}

impl BeamSystem {
    /// The axial forces at the bodies' current positions, summed per body in element order.
    fn axial_forces(&mut self) {
        let s = &self.structure;
        let b = &self.bodies;
        let out = &mut self.impulse.axial_force;
        out.iter_mut().for_each(|f| *f = Vec3::ZERO);
        for e in &s.elements {
            let (xa, _) = s.pose(&b.position, &b.rotation, e.ends[0]);
            let (xb, _) = s.pose(&b.position, &b.rotation, e.ends[1]);
            let f = super::element::axial_force(&e.stiffness, xa, xb);
            if let NodeRef::Body(i) = e.ends[0] {
                out[i] += f;
            }
            if let NodeRef::Body(i) = e.ends[1] {
                out[i] -= f;
            }
        }
    }

    /// The slow forces: bending and torsion, loads and gravity at the bodies' time.
    fn slow_forces(&mut self) {
        let b = &self.bodies;
        let (force, torque) = (&mut self.impulse.slow_force, &mut self.impulse.slow_torque);
        self.structure.bending_forces(&b.position, &b.rotation, force, torque);
        let config = Configuration {
            t: b.t,
            mass: &b.mass,
            free: &b.free,
            position: &b.position,
            rotation: &b.rotation,
        };
        self.structure.add_loads(&config, force, torque);
    }

    /// One step of the impulse method (see [`super::impulse`]) with outer step `h` and
    /// [`substeps`] inner axial steps. The bodies' `force` and `torque` are left as the sum of
    /// the slow and axial parts, so that [`BeamSystem::step`] can follow.
    ///
    /// # Errors
    /// A bad step, or a body whose midpoint rotation fails (the system is then left
    /// mid-step).
    pub fn step_impulse(&mut self, h: f64) -> Result<()> {
        if !(h.is_finite() && h != 0.0) {
            return Err(Error::InvalidStep { h });
        }
        let m = substeps(h, self.impulse.omega_axial);
        self.step_impulse_with(h, m)
    }

    /// [`BeamSystem::step_impulse`] with `m` inner steps (at least 1).
    ///
    /// # Errors
    /// As [`BeamSystem::step_impulse`].
    pub fn step_impulse_with(&mut self, h: f64, m: usize) -> Result<()> {
        if !(h.is_finite() && h != 0.0) {
            return Err(Error::InvalidStep { h });
        }
        let m = m.max(1);
        if !self.impulse.valid {
            self.slow_forces();
            self.axial_forces();
            self.impulse.valid = true;
        }
        let (hh, d) = (0.5 * h, h / m as f64);
        let t = self.bodies.t;
        self.slow_kick(hh);
        {
            let b = &mut self.bodies;
            for i in 0..b.len() {
                if let Err((equation, e)) = b.rotate_free(i, h) {
                    self.impulse.valid = false;
                    return Err(newton_error("impulse method", equation, t, h, e));
                }
            }
        }
        let dh = 0.5 * d;
        for _ in 0..m {
            let b = &mut self.bodies;
            for i in 0..b.len() {
                if b.free[i] {
                    b.momentum[i] += self.impulse.axial_force[i] * dh;
                    b.position[i] += b.momentum[i] * (d / b.mass[i]);
                }
            }
            self.axial_forces();
            let b = &mut self.bodies;
            for i in 0..b.len() {
                if b.free[i] {
                    b.momentum[i] += self.impulse.axial_force[i] * dh;
                }
            }
        }
        self.bodies.t = t + h;
        self.slow_forces();
        self.slow_kick(hh);
        let (b, s) = (&mut self.bodies, &self.impulse);
        for i in 0..b.len() {
            b.force[i] = s.slow_force[i] + s.axial_force[i];
            b.torque[i] = s.slow_torque[i];
        }
        Ok(())
    }

    /// `p ← p + τ F_b` (free bodies), `Π ← Π + τ T_b`.
    fn slow_kick(&mut self, tau: f64) {
        let (b, s) = (&mut self.bodies, &self.impulse);
        for i in 0..b.len() {
            if b.free[i] {
                b.momentum[i] += s.slow_force[i] * tau;
            }
            b.pi[i] += s.slow_torque[i] * tau;
        }
    }
}
