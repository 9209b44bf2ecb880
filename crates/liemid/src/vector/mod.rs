//! Mechanical systems on a vector space, `p' = f(u, t)`, `u' = M⁻¹ p`, and the impulse
//! integrators they are built from (docs/theory/rigid.md §2):
//!
//! | method | step | order |
//! |---|---|---|
//! | [`SymplecticEuler`] `Φ_h` (impulse at start) | `p⁺ = p + h f(u, t)`; `u⁺ = u + h M⁻¹ p⁺` | 1 |
//! | [`SymplecticEulerAdjoint`] `Φ*_h` (impulse at end) | `u⁺ = u + h M⁻¹ p`; `p⁺ = p + h f(u⁺, t + h)` | 1 |
//! | [`Verlet`] `Φ*_{h/2} ∘ Φ_{h/2}` | `p½ = p + (h/2) f(u, t)`; `u⁺ = u + h M⁻¹ p½`; `p⁺ = p½ + (h/2) f(u⁺, t + h)` | 2 |
//! | [`ExplicitNewmark`] (`β = 0`, any `γ`) | `u⁺ = u + h M⁻¹ (p + (h/2) f_n)`; `p⁺ = p + h((1−γ) f_n + γ f⁺)` | 2 if `γ = ½`, else 1 |
//!
//! All are symplectic (Newmark for `γ = ½`) and keep linear and angular momentum when the
//! forces do. Verlet and Newmark reuse the end force of a step as the start force of the
//! next: one force evaluation per step. Scratch buffers live in the integrator and are
//! sized on the first step, so stepping allocates nothing afterwards.

use crate::composition::Composition;
use crate::error::{Error, Result};

pub mod problems;

/// A constant symmetric positive definite mass matrix.
#[derive(Clone, Debug, PartialEq)]
pub enum MassMatrix {
    /// A diagonal mass matrix, stored as its diagonal.
    Diagonal(Vec<f64>),
    /// A dense mass matrix, stored as its lower Cholesky factor `L` (`M = L Lᵀ`), row-major.
    Dense {
        /// Dimension.
        n: usize,
        /// Row-major lower Cholesky factor.
        cholesky: Vec<f64>,
    },
}

impl MassMatrix {
    /// A diagonal mass matrix; every entry finite and positive.
    pub fn diagonal(masses: Vec<f64>) -> Result<Self> {
        if let Some((i, m)) = masses.iter().enumerate().find(|(_, m)| !(m.is_finite() && **m > 0.0)) {
            return Err(Error::InvalidMass {
                reason: format!("diagonal entry {i} = {m} must be finite and positive"),
            });
        }
        Ok(MassMatrix::Diagonal(masses))
    }

    /// A dense mass matrix from its row-major entries (`n²` of them); must be symmetric
    /// (to a relative 1e-12) and positive definite.
    pub fn dense(n: usize, entries: &[f64]) -> Result<Self> {
        if entries.len() != n * n {
            return Err(Error::InvalidMass {
                reason: format!("expected {} entries for n = {n}, got {}", n * n, entries.len()),
            });
        }
        let scale = entries.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for i in 0..n {
            for j in 0..i {
                let (a, b) = (entries[i * n + j], entries[j * n + i]);
                if !(a.is_finite() && b.is_finite()) || (a - b).abs() > 1e-12 * scale {
                    return Err(Error::InvalidMass {
                        reason: format!("not symmetric at ({i}, {j}): {a} vs {b}"),
                    });
                }
            }
        }
        let mut l = entries.to_vec();
        if let Err((j, d)) = crate::linalg::cholesky_in_place(&mut l, n) {
            return Err(Error::InvalidMass {
                reason: format!("not positive definite (Cholesky pivot {j} = {d:e})"),
            });
        }
        // The factor alone: zero above the diagonal.
        for i in 0..n {
            l[i * n + i + 1..(i + 1) * n].fill(0.0);
        }
        Ok(MassMatrix::Dense { n, cholesky: l })
    }

    /// Dimension.
    #[must_use]
    pub fn dim(&self) -> usize {
        match self {
            MassMatrix::Diagonal(d) => d.len(),
            MassMatrix::Dense { n, .. } => *n,
        }
    }

    /// `x ← M⁻¹ x`, in place, without allocation.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        match self {
            MassMatrix::Diagonal(d) => x.iter_mut().zip(d).for_each(|(x, m)| *x /= m),
            MassMatrix::Dense { n, cholesky: l } => crate::linalg::cholesky_solve(l, *n, x),
        }
    }

    /// The kinetic energy `½ pᵀ M⁻¹ p`; `scratch` must have the system's dimension.
    pub fn kinetic_energy(&self, p: &[f64], scratch: &mut [f64]) -> f64 {
        scratch.copy_from_slice(p);
        self.solve_in_place(scratch);
        0.5 * p.iter().zip(scratch.iter()).map(|(a, b)| a * b).sum::<f64>()
    }
}

/// A mechanical system `p' = f(u, t)`, `u' = M⁻¹ p` on `ℝⁿ`.
pub trait MechanicalSystem {
    /// The constant mass matrix `M`.
    fn mass(&self) -> &MassMatrix;

    /// Write the force `f(u, t)` into `f`.
    fn force(&self, u: &[f64], t: f64, f: &mut [f64]);

    /// The potential energy `V(u, t)` with `f = −∇V`, for the energy diagnostic.
    fn potential_energy(&self, _u: &[f64], _t: f64) -> f64 {
        0.0
    }

    /// Dimension `n`.
    fn dim(&self) -> usize {
        self.mass().dim()
    }

    /// Total energy `½ pᵀ M⁻¹ p + V(u, t)` of a state (allocates a scratch vector).
    fn energy(&self, state: &PhaseState) -> f64 {
        let mut scratch = vec![0.0; self.dim()];
        self.mass().kinetic_energy(&state.p, &mut scratch) + self.potential_energy(&state.u, state.t)
    }
}

/// A state `(t, p, u)` of a [`MechanicalSystem`].
#[derive(Clone, Debug, PartialEq)]
pub struct PhaseState {
    /// Time.
    pub t: f64,
    /// Momenta.
    pub p: Vec<f64>,
    /// Positions.
    pub u: Vec<f64>,
}

impl PhaseState {
    /// A state from its parts; `p` and `u` must have the same length.
    pub fn new(t: f64, p: Vec<f64>, u: Vec<f64>) -> Result<Self> {
        if p.len() != u.len() {
            return Err(Error::InvalidMass {
                reason: format!("state dimensions differ: p has {}, u has {}", p.len(), u.len()),
            });
        }
        let s = PhaseState { t, p, u };
        s.check_finite()?;
        Ok(s)
    }

    /// An error naming the first non-finite field.
    pub fn check_finite(&self) -> Result<()> {
        if !self.t.is_finite() {
            return Err(Error::NonFiniteState { field: "t", t: self.t });
        }
        if !self.p.iter().all(|v| v.is_finite()) {
            return Err(Error::NonFiniteState { field: "p", t: self.t });
        }
        if !self.u.iter().all(|v| v.is_finite()) {
            return Err(Error::NonFiniteState { field: "u", t: self.t });
        }
        Ok(())
    }
}

/// A one-step method for [`MechanicalSystem`]s.
pub trait VectorIntegrator {
    /// The method's name.
    fn name(&self) -> &'static str;
    /// The classical order.
    fn order(&self) -> u32;
    /// Advance `state` by one step `h` (non-zero, finite, possibly negative).
    fn step<S: MechanicalSystem + ?Sized>(&mut self, system: &S, state: &mut PhaseState, h: f64) -> Result<()>;
}

fn check(system_dim: usize, state: &PhaseState, h: f64) -> Result<()> {
    if !(h.is_finite() && h != 0.0) {
        return Err(Error::InvalidStep { h });
    }
    if state.p.len() != system_dim || state.u.len() != system_dim {
        return Err(Error::InvalidMass {
            reason: format!("state has dimension {} but the system has {system_dim}", state.p.len()),
        });
    }
    Ok(())
}

/// Scratch space and the cached end force, shared by the methods below.
#[derive(Clone, Debug, Default)]
struct Workspace {
    force: Vec<f64>,
    velocity: Vec<f64>,
    /// The force at `(cached_t, cached_u)`, valid when `cached` is set.
    cached: bool,
    cached_t: f64,
    cached_u: Vec<f64>,
}

impl Workspace {
    fn size(&mut self, n: usize) {
        if self.force.len() != n {
            self.force = vec![0.0; n];
            self.velocity = vec![0.0; n];
            self.cached_u = vec![0.0; n];
            self.cached = false;
        }
    }

    /// Fill `self.force` with `f(u, t)`, from the cache when it holds that configuration.
    fn start_force<S: MechanicalSystem + ?Sized>(&mut self, system: &S, u: &[f64], t: f64) {
        if !(self.cached && self.cached_t == t && self.cached_u == u) {
            system.force(u, t, &mut self.force);
        }
    }

    fn remember(&mut self, u: &[f64], t: f64) {
        self.cached_u.copy_from_slice(u);
        self.cached_t = t;
        self.cached = true;
    }

    /// `u ← u + h M⁻¹ p`.
    fn drift<S: MechanicalSystem + ?Sized>(&mut self, system: &S, p: &[f64], u: &mut [f64], h: f64) {
        self.velocity.copy_from_slice(p);
        system.mass().solve_in_place(&mut self.velocity);
        u.iter_mut().zip(&self.velocity).for_each(|(u, v)| *u += h * v);
    }
}

fn kick(p: &mut [f64], f: &[f64], h: f64) {
    p.iter_mut().zip(f).for_each(|(p, f)| *p += h * f);
}

/// Symplectic Euler `Φ_h`, impulse at the start: `p⁺ = p + h f(u, t)`, `u⁺ = u + h M⁻¹ p⁺`.
/// First order, symplectic.
#[derive(Clone, Debug, Default)]
pub struct SymplecticEuler {
    ws: Workspace,
}

impl VectorIntegrator for SymplecticEuler {
    fn name(&self) -> &'static str {
        "symplectic Euler"
    }
    fn order(&self) -> u32 {
        1
    }
    fn step<S: MechanicalSystem + ?Sized>(&mut self, system: &S, state: &mut PhaseState, h: f64) -> Result<()> {
        check(system.dim(), state, h)?;
        self.ws.size(system.dim());
        self.ws.cached = false;
        system.force(&state.u, state.t, &mut self.ws.force);
        kick(&mut state.p, &self.ws.force, h);
        self.ws.drift(system, &state.p, &mut state.u, h);
        state.t += h;
        Ok(())
    }
}

/// The adjoint of symplectic Euler `Φ*_h`, impulse at the end:
/// `u⁺ = u + h M⁻¹ p`, `p⁺ = p + h f(u⁺, t + h)`. First order, symplectic.
#[derive(Clone, Debug, Default)]
pub struct SymplecticEulerAdjoint {
    ws: Workspace,
}

impl VectorIntegrator for SymplecticEulerAdjoint {
    fn name(&self) -> &'static str {
        "adjoint symplectic Euler"
    }
    fn order(&self) -> u32 {
        1
    }
    fn step<S: MechanicalSystem + ?Sized>(&mut self, system: &S, state: &mut PhaseState, h: f64) -> Result<()> {
        check(system.dim(), state, h)?;
        self.ws.size(system.dim());
        self.ws.drift(system, &state.p, &mut state.u, h);
        state.t += h;
        system.force(&state.u, state.t, &mut self.ws.force);
        kick(&mut state.p, &self.ws.force, h);
        Ok(())
    }
}

/// Explicit Newmark with `β = 0` and free `γ`:
/// `u⁺ = u + h M⁻¹ (p + (h/2) f_n)`, `p⁺ = p + h ((1 − γ) f_n + γ f_{n+1})`.
/// Second order and symplectic for `γ = ½` (where it is [`Verlet`]), first order otherwise.
/// One force evaluation per step (the end force is cached).
#[derive(Clone, Debug)]
pub struct ExplicitNewmark {
    gamma: f64,
    ws: Workspace,
}

impl ExplicitNewmark {
    /// Newmark with parameter `γ` (finite).
    pub fn new(gamma: f64) -> Result<Self> {
        if !gamma.is_finite() {
            return Err(Error::InvalidParameter {
                name: "gamma",
                value: gamma,
                reason: "must be finite",
            });
        }
        Ok(ExplicitNewmark {
            gamma,
            ws: Workspace::default(),
        })
    }

    /// The parameter `γ`.
    #[must_use]
    pub fn gamma(&self) -> f64 {
        self.gamma
    }
}

impl VectorIntegrator for ExplicitNewmark {
    fn name(&self) -> &'static str {
        "explicit Newmark"
    }
    fn order(&self) -> u32 {
        if self.gamma == 0.5 {
            2
        } else {
            1
        }
    }
    fn step<S: MechanicalSystem + ?Sized>(&mut self, system: &S, state: &mut PhaseState, h: f64) -> Result<()> {
        check(system.dim(), state, h)?;
        let ws = &mut self.ws;
        ws.size(system.dim());
        ws.start_force(system, &state.u, state.t);
        // Drift with p + (h/2) f_n, then kick with (1 − γ) f_n.
        kick(&mut state.p, &ws.force, 0.5 * h);
        ws.drift(system, &state.p, &mut state.u, h);
        kick(&mut state.p, &ws.force, (0.5 - self.gamma) * h);
        state.t += h;
        system.force(&state.u, state.t, &mut ws.force);
        kick(&mut state.p, &ws.force, self.gamma * h);
        ws.remember(&state.u, state.t);
        Ok(())
    }
}

/// Störmer-Verlet `Ξ_h = Φ*_{h/2} ∘ Φ_{h/2}`:
/// `p½ = p + (h/2) f(u, t)`, `u⁺ = u + h M⁻¹ p½`, `p⁺ = p½ + (h/2) f(u⁺, t + h)`.
/// Second order, symplectic, time-reversible; one force evaluation per step.
#[derive(Clone, Debug)]
pub struct Verlet {
    inner: ExplicitNewmark,
}

impl Default for Verlet {
    fn default() -> Self {
        Verlet {
            inner: ExplicitNewmark::new(0.5).expect("finite"),
        }
    }
}

impl VectorIntegrator for Verlet {
    fn name(&self) -> &'static str {
        "Verlet"
    }
    fn order(&self) -> u32 {
        2
    }
    fn step<S: MechanicalSystem + ?Sized>(&mut self, system: &S, state: &mut PhaseState, h: f64) -> Result<()> {
        self.inner.step(system, state, h)
    }
}

impl<M: VectorIntegrator> VectorIntegrator for Composition<M> {
    fn name(&self) -> &'static str {
        self.name
    }
    fn order(&self) -> u32 {
        self.scheme.order
    }
    fn step<S: MechanicalSystem + ?Sized>(&mut self, system: &S, state: &mut PhaseState, h: f64) -> Result<()> {
        // The vector methods fail only on a bad step or dimension, before any stage moves.
        for i in 0..self.scheme.stages {
            self.base.step(system, state, self.scheme.gamma(i) * h)?;
        }
        Ok(())
    }
}
