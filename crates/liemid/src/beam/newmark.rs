//! The baseline structural codes use: implicit Newmark (average acceleration,
//! `β = 1/4`, `γ = 1/2`) with Newton's method, on the same corotational model.
//!
//! Translations follow the Newmark formulas; each nodal rotation is updated as
//! `R_{n+1} = R_n exp(Θ)` with the body-frame increment `Θ` treated by the same formulas
//! (the material form of Simo and Vu-Quoc, with body angular velocity `W` and acceleration
//! `A`):
//!
//! ```text
//! Δx = h v_n + h²/4 (a_n + a_{n+1}),   v_{n+1} = v_n + h/2 (a_n + a_{n+1})
//! Θ  = h W_n + h²/4 (A_n + A_{n+1}),   W_{n+1} = W_n + h/2 (A_n + A_{n+1})
//! m a_{n+1} = F(x_{n+1}, R_{n+1}, t_{n+1}),   J A_{n+1} + W_{n+1} × J W_{n+1} = T(…)
//! ```
//!
//! Each Newton iteration assembles `4M/h² + K` (banded, `K` the exact derivative of the
//! element forces by dual numbers, [`super::tangent`], or by central differences,
//! [`Tangent`], element by element) and corrects `x ← x + δx`, `R ← R exp(δθ)` until
//! the largest correction is below `1e-10` of the structure's size. Second order; the
//! average-acceleration rule keeps the energy of linear problems but neither it nor the
//! momenta of nonlinear ones exactly.
//!
//! ## Reference
//! N. M. Newmark, *A method of computation for structural dynamics*, J. Eng. Mech. Div.
//! ASCE 85 (1959); J. C. Simo, L. Vu-Quoc, Comput. Methods Appl. Mech. Engrg. 66 (1988);
//! P. Krysl, FinEtoolsFlexBeams.jl (dynamic examples at `dt = 0.05`).

use super::{BeamSystem, NodeRef};
use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};
use crate::many::{Configuration, Interaction};
use crate::so3;

/// A banded matrix (half bandwidth `w`), factorised by Gaussian elimination without
/// pivoting (the effective stiffness `4M/h² + K` is positive definite near equilibrium).
#[derive(Clone, Debug)]
struct Banded {
    n: usize,
    w: usize,
    a: Vec<f64>,
}

impl Banded {
    fn new(n: usize, w: usize) -> Self {
        Banded {
            n,
            w,
            a: vec![0.0; n * (2 * w + 1)],
        }
    }
    #[inline]
    fn at(&mut self, i: usize, j: usize) -> &mut f64 {
        &mut self.a[i * (2 * self.w + 1) + (j + self.w - i)]
    }
    fn clear(&mut self) {
        self.a.iter_mut().for_each(|x| *x = 0.0);
    }
    /// Solve in place (destroys the matrix); `false` for a zero pivot.
    #[allow(clippy::needless_range_loop)]
    fn solve(&mut self, b: &mut [f64]) -> bool {
        let (n, w) = (self.n, self.w);
        for k in 0..n {
            let pivot = *self.at(k, k);
            if pivot == 0.0 || !pivot.is_finite() {
                return false;
            }
            for i in k + 1..(k + w + 1).min(n) {
                let f = *self.at(i, k) / pivot;
                if f == 0.0 {
                    continue;
                }
                for j in k..(k + w + 1).min(n) {
                    let v = *self.at(k, j);
                    *self.at(i, j) -= f * v;
                }
                b[i] -= f * b[k];
            }
        }
        for k in (0..n).rev() {
            let mut s = b[k];
            for j in k + 1..(k + w + 1).min(n) {
                s -= *self.at(k, j) * b[j];
            }
            b[k] = s / *self.at(k, k);
        }
        true
    }
}

/// Implicit Newmark with Newton on a [`BeamSystem`]'s model (see the module documentation).
#[derive(Clone, Debug)]
pub struct Newmark {
    system: BeamSystem,
    /// The motion at the start of the step, and that of the current Newton iterate.
    now: Motion,
    next: Motion,
    /// The configuration at the start of the step, and the Newton right-hand side.
    start_position: Vec<Vec3>,
    start_rotation: Vec<Mat3>,
    rhs: Vec<f64>,
    /// First degree of freedom of each body (translations first for free bodies).
    offset: Vec<usize>,
    dofs: usize,
    matrix: Banded,
    force: Vec<Vec3>,
    torque: Vec<Vec3>,
    scale: f64,
    /// How the element stiffness is formed.
    tangent: Tangent,
    /// Newton iterations taken so far.
    pub iterations: u64,
    /// Steps taken so far.
    pub steps: u64,
}

impl Newmark {
    /// Start from the system's current state (velocities from its momenta, accelerations
    /// from its forces).
    #[must_use]
    pub fn new(system: &BeamSystem) -> Self {
        let mut system = system.clone();
        let b = &mut system.bodies;
        b.evaluate(&system.structure);
        let n = b.len();
        let mut offset = Vec::with_capacity(n);
        let mut dofs = 0;
        for i in 0..n {
            offset.push(dofs);
            dofs += if b.free[i] { 6 } else { 3 };
        }
        let mut w = 5;
        for e in &system.structure.elements {
            if let [NodeRef::Body(i), NodeRef::Body(j)] = e.ends {
                let (lo, hi) = (i.min(j), i.max(j));
                let width = offset[hi] + if b.free[hi] { 6 } else { 3 } - 1 - offset[lo];
                w = w.max(width);
            }
        }
        let inv = |i: usize| b.inertia[i].inverse;
        let velocity = (0..n).map(|i| b.momentum[i] * (1.0 / b.mass[i])).collect();
        let omega = (0..n).map(|i| inv(i).component_mul(b.pi[i])).collect::<Vec<_>>();
        let acceleration = (0..n)
            .map(|i| {
                if b.free[i] {
                    b.force[i] * (1.0 / b.mass[i])
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        let alpha = (0..n)
            .map(|i| {
                let m = b.inertia[i].moments;
                inv(i).component_mul(b.torque[i] - omega[i].cross(m.component_mul(omega[i])))
            })
            .collect();
        let extent = system
            .frame
            .nodes
            .iter()
            .map(|x| x.max_abs())
            .fold(0.0, f64::max)
            .max(1e-300);
        Newmark {
            matrix: Banded::new(dofs, w),
            force: vec![Vec3::ZERO; n],
            torque: vec![Vec3::ZERO; n],
            system,
            next: Motion::zeros(n),
            now: Motion {
                acceleration,
                alpha,
                velocity,
                omega,
            },
            start_position: vec![Vec3::ZERO; n],
            start_rotation: vec![Mat3::IDENTITY; n],
            rhs: vec![0.0; dofs],
            offset,
            dofs,
            scale: extent,
            tangent: Tangent::Analytic,
            iterations: 0,
            steps: 0,
        }
    }

    /// Form the element stiffness by `tangent` (the default is [`Tangent::Analytic`]).
    #[must_use]
    pub fn with_tangent(mut self, tangent: Tangent) -> Self {
        self.tangent = tangent;
        self
    }

    /// How the element stiffness is formed.
    #[must_use]
    pub fn tangent(&self) -> Tangent {
        self.tangent
    }

    /// The state as a [`BeamSystem`] (positions and attitudes current; momenta not kept).
    #[must_use]
    pub fn system(&self) -> &BeamSystem {
        &self.system
    }

    /// The momenta of body `i` at the current state, `(m v, J W)`: the linear momentum
    /// (zero for a rotor) and the body angular momentum, the explicit methods' `p` and `Π`
    /// (the canonical momenta of `(x, R)`).
    ///
    /// # Panics
    /// `i` not a body of the system.
    #[must_use]
    pub fn momenta(&self, i: usize) -> (Vec3, Vec3) {
        let b = &self.system.bodies;
        let p = if b.free[i] {
            self.now.velocity[i] * b.mass[i]
        } else {
            Vec3::ZERO
        };
        (p, b.inertia[i].moments.component_mul(self.now.omega[i]))
    }

    /// Time.
    #[must_use]
    pub fn t(&self) -> f64 {
        self.system.bodies.t
    }

    /// Degrees of freedom.
    #[must_use]
    pub fn dofs(&self) -> usize {
        self.dofs
    }

    /// One step; returns the Newton iterations it took.
    ///
    /// # Errors
    /// [`Error::NewtonDidNotConverge`] after 30 iterations (the state is then left as it
    /// was), or a bad step.
    #[allow(clippy::needless_range_loop)]
    pub fn step(&mut self, h: f64) -> Result<u32> {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::InvalidStep { h });
        }
        let n = self.system.bodies.len();
        let t_new = self.system.bodies.t + h;
        self.start_position.copy_from_slice(&self.system.bodies.position);
        self.start_rotation.copy_from_slice(&self.system.bodies.rotation);
        // Predictor: a_{n+1} = a_n.
        let now = &self.now;
        let b = &mut self.system.bodies;
        for i in 0..n {
            if b.free[i] {
                b.position[i] = b.position[i] + now.velocity[i] * h + now.acceleration[i] * (0.5 * h * h);
            }
            b.rotation[i] = b.rotation[i] * so3::exp(now.omega[i] * h + now.alpha[i] * (0.5 * h * h));
        }
        let c = 4.0 / (h * h);
        let mut last = f64::INFINITY;
        let mut iterations = 0;
        while iterations < MAX_ITERATIONS {
            // Accelerations of the iterate, and the residual r = f − inertia.
            self.next.of_iterate(
                &self.now,
                &self.system.bodies,
                &self.start_position,
                &self.start_rotation,
                h,
            );
            let b = &self.system.bodies;
            let config = Configuration {
                t: t_new,
                mass: &b.mass,
                free: &b.free,
                position: &b.position,
                rotation: &b.rotation,
            };
            self.system.structure.compute(config, &mut self.force, &mut self.torque);
            let next = &self.next;
            for i in 0..n {
                let mut k = self.offset[i];
                if b.free[i] {
                    let r = self.force[i] - next.acceleration[i] * b.mass[i];
                    self.rhs[k..k + 3].copy_from_slice(&r.to_array());
                    k += 3;
                }
                let (m, w) = (b.inertia[i].moments, next.omega[i]);
                let r = self.torque[i] - m.component_mul(next.alpha[i]) - w.cross(m.component_mul(w));
                self.rhs[k..k + 3].copy_from_slice(&r.to_array());
            }
            self.assemble(c, h);
            if !self.matrix.solve(&mut self.rhs) {
                break;
            }
            iterations += 1;
            let rhs = &self.rhs;
            let b = &mut self.system.bodies;
            let mut largest: f64 = 0.0;
            for i in 0..n {
                let mut k = self.offset[i];
                if b.free[i] {
                    let d = Vec3::new(rhs[k], rhs[k + 1], rhs[k + 2]);
                    b.position[i] += d;
                    largest = largest.max(d.max_abs() / self.scale);
                    k += 3;
                }
                let d = Vec3::new(rhs[k], rhs[k + 1], rhs[k + 2]);
                b.rotation[i] = b.rotation[i] * so3::exp(d);
                largest = largest.max(d.max_abs());
            }
            self.iterations += 1;
            last = largest;
            if largest < 1e-10 {
                self.next.of_iterate(
                    &self.now,
                    &self.system.bodies,
                    &self.start_position,
                    &self.start_rotation,
                    h,
                );
                std::mem::swap(&mut self.now, &mut self.next);
                self.system.bodies.t = t_new;
                self.steps += 1;
                return Ok(iterations);
            }
        }
        self.system.bodies.position.copy_from_slice(&self.start_position);
        self.system.bodies.rotation.copy_from_slice(&self.start_rotation);
        Err(Error::NewtonDidNotConverge {
            method: "Newmark (average acceleration)",
            equation: "the equations of motion at the end of the step (largest correction as the residual)",
            t: t_new - h,
            h,
            residual: last,
            iterations,
        })
    }

    /// `4M/h² + K` at the current iterate, `K` by central differences element by element.
    fn assemble(&mut self, c: f64, h: f64) {
        let (r0, omega) = (&self.start_rotation, &self.next.omega);
        self.matrix.clear();
        let b = &self.system.bodies;
        for i in 0..b.len() {
            let mut k = self.offset[i];
            if b.free[i] {
                for d in 0..3 {
                    *self.matrix.at(k + d, k + d) += c * b.mass[i];
                }
                k += 3;
            }
            // d(J A + W × J W)/dδ for R ← R exp(δ): Θ = log(R₀ᵀ R) moves by Jr⁻¹(Θ) δ,
            // A by c of that and W by 2/h of it.
            let m = b.inertia[i].moments;
            let theta = so3::log(&(r0[i].transpose() * b.rotation[i]));
            let w = omega[i];
            let gyro = so3::hat(w) * Mat3::from_diagonal(m) - so3::hat(m.component_mul(w));
            let block = (Mat3::from_diagonal(m * c) + gyro * (2.0 / h)) * so3::right_jacobian_inverse(theta);
            for r in 0..3 {
                for q in 0..3 {
                    *self.matrix.at(k + r, k + q) += block.m[r][q];
                }
            }
        }
        let structure = &self.system.structure;
        if self.tangent == Tangent::Analytic {
            for e in &structure.elements {
                let mut columns: [(usize, usize); 4] = [(0, usize::MAX); 4];
                let mut count = 0;
                for (end, node) in e.ends.iter().enumerate() {
                    if let NodeRef::Body(i) = *node {
                        let mut k = self.offset[i];
                        if b.free[i] {
                            columns[count] = (6 * end, k);
                            count += 1;
                            k += 3;
                        }
                        columns[count] = (6 * end + 3, k);
                        count += 1;
                    }
                }
                let (xa, ra) = structure.pose(&b.position, &b.rotation, e.ends[0]);
                let (xb, rb) = structure.pose(&b.position, &b.rotation, e.ends[1]);
                let kt = super::tangent::element_tangent(&e.stiffness, xa, xb, &ra, &rb, &e.axes[0], &e.axes[1]);
                for &(kc, col0) in &columns[..count] {
                    for &(kr, row0) in &columns[..count] {
                        for r in 0..3 {
                            for d in 0..3 {
                                *self.matrix.at(row0 + r, col0 + d) += kt[kr + r][kc + d];
                            }
                        }
                    }
                }
            }
            return;
        }
        let eps_x = 1e-7 * self.scale;
        let eps_r = 1e-7;
        for e in &structure.elements {
            // The element's degrees of freedom: (end, kind 0 = translation / 1 = rotation).
            let mut columns: [(usize, usize, usize); 4] = [(0, 0, usize::MAX); 4];
            let mut count = 0;
            for (end, node) in e.ends.iter().enumerate() {
                if let NodeRef::Body(i) = *node {
                    let mut k = self.offset[i];
                    if b.free[i] {
                        columns[count] = (end, 0, k);
                        count += 1;
                        k += 3;
                    }
                    columns[count] = (end, 1, k);
                    count += 1;
                }
            }
            let poses = |end: usize| structure.pose(&b.position, &b.rotation, e.ends[end]);
            for &(end, kind, col0) in &columns[..count] {
                for d in 0..3 {
                    let mut f = [[Vec3::ZERO; 2]; 2];
                    let mut t = [[Vec3::ZERO; 2]; 2];
                    for (s, sign) in [1.0, -1.0].into_iter().enumerate() {
                        let mut p = [poses(0), poses(1)];
                        let mut unit = [0.0; 3];
                        unit[d] = 1.0;
                        let unit = Vec3::from_array(unit);
                        let eps = if kind == 0 { eps_x } else { eps_r };
                        if kind == 0 {
                            p[end].0 += unit * (sign * eps);
                        } else {
                            p[end].1 = p[end].1 * so3::exp(unit * (sign * eps));
                        }
                        let ef = super::element::end_forces(
                            &e.stiffness,
                            p[0].0,
                            p[1].0,
                            &(p[0].1 * e.axes[0]),
                            &(p[1].1 * e.axes[1]),
                        );
                        f[s] = [ef.force_a, ef.force_b];
                        t[s] = [p[0].1.tr_mul_vec(ef.moment_a), p[1].1.tr_mul_vec(ef.moment_b)];
                    }
                    let eps = if kind == 0 { eps_x } else { eps_r };
                    for &(row_end, row_kind, row0) in &columns[..count] {
                        let (plus, minus) = if row_kind == 0 {
                            (f[0][row_end], f[1][row_end])
                        } else {
                            (t[0][row_end], t[1][row_end])
                        };
                        // K = −∂(generalised force)/∂q.
                        let column = (plus - minus) * (-0.5 / eps);
                        for r in 0..3 {
                            *self.matrix.at(row0 + r, col0 + d) += column.to_array()[r];
                        }
                    }
                }
            }
        }
    }

    /// The displacement of node `node` from its initial position.
    #[must_use]
    pub fn displacement(&self, node: usize) -> Vec3 {
        self.system.displacement(node)
    }
}

/// How Newmark's Newton iteration forms the element stiffness.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tangent {
    /// Exact derivatives of the element forces by dual numbers ([`super::tangent`]): one
    /// evaluation in nine-direction duals per element.
    #[default]
    Analytic,
    /// Central differences of the element forces: 24 evaluations per element.
    FiniteDifference,
}

/// Newton iterations before a step is given up.
const MAX_ITERATIONS: u32 = 30;

/// Per body: acceleration, angular acceleration (body frame), velocity, angular velocity
/// (body frame).
#[derive(Clone, Debug)]
struct Motion {
    acceleration: Vec<Vec3>,
    alpha: Vec<Vec3>,
    velocity: Vec<Vec3>,
    omega: Vec<Vec3>,
}

impl Motion {
    fn zeros(n: usize) -> Self {
        Motion {
            acceleration: vec![Vec3::ZERO; n],
            alpha: vec![Vec3::ZERO; n],
            velocity: vec![Vec3::ZERO; n],
            omega: vec![Vec3::ZERO; n],
        }
    }

    /// The motion at the end of the step for the iterate `b`, from the step's start
    /// (`x0`, `r0`, motion `now`): `a = 4(Δx − h v)/h² − a_n`, `A = 4(Θ − h W)/h² − A_n`
    /// with `Θ = log(R₀ᵀ R)`, and the velocities by the trapezoidal rule.
    fn of_iterate(&mut self, now: &Motion, b: &crate::many::Bodies, x0: &[Vec3], r0: &[Mat3], h: f64) {
        let c = 4.0 / (h * h);
        for i in 0..b.len() {
            let a = if b.free[i] {
                (b.position[i] - x0[i] - now.velocity[i] * h) * c - now.acceleration[i]
            } else {
                Vec3::ZERO
            };
            let theta = so3::log(&(r0[i].transpose() * b.rotation[i]));
            let alpha = (theta - now.omega[i] * h) * c - now.alpha[i];
            self.acceleration[i] = a;
            self.alpha[i] = alpha;
            self.velocity[i] = now.velocity[i] + (now.acceleration[i] + a) * (0.5 * h);
            self.omega[i] = now.omega[i] + (now.alpha[i] + alpha) * (0.5 * h);
        }
    }
}
