//! Many interacting rigid bodies, stepped in parallel with results independent of the
//! thread count.
//!
//! [`Bodies`] stores N bodies structure-of-arrays ([`BYTES_PER_BODY`] = 249 bytes per body:
//! mass, principal inertia and its reciprocal, joint, position, linear momentum, attitude,
//! body angular momentum, and the force and torque of the last evaluation). An [`Interaction`] computes
//! every force (spatial) and torque (body frame) from the positions and attitudes.
//!
//! [`Bodies::step`] is the splitting integrator built from the paper's pieces, with one
//! force and torque evaluation per step:
//!
//! ```text
//! p ← p + (h/2) F,  Π ← Π + (h/2) T              (impulse at the start)
//! x ← x + h p / m                                 (free bodies only)
//! (Π, R) ← torque-free midpoint Lie rotation: solve (M) with (Π, h/2) → Ψ₁,
//!          R ← R exp(Ψ₁), Π ← exp(−Ψ₁) Π, then again → Ψ₂
//! F, T ← forces and torques at the new configuration
//! p ← p + (h/2) F,  Π ← Π + (h/2) T              (impulse at the end)
//! ```
//!
//! For one body with a torque it is exactly LIEMID[EA]; it is symplectic and time
//! reversible, and keeps the total linear and angular momentum (orbital plus spin) of any
//! translation- and rotation-invariant interaction to round-off. Work is split into
//! chunks of [`CHUNK`] bodies; each body's force is gathered from its neighbours in a fixed
//! order and every reduction runs in index order, so results are bit-for-bit identical for
//! any number of threads.

use std::sync::Mutex;

use crate::composition::Scheme;
use crate::error::{Error, Result};
use crate::inertia::{InertiaOperator, PrincipalInertia};
use crate::lanes::LANES;
use crate::linalg::{Mat3, Vec3};
use crate::midpoint;
use crate::rotation::newton_error;
use crate::so3;

/// Bodies per parallel work item (fixed, so that results do not depend on the threads).
pub const CHUNK: usize = 256;

/// N rigid bodies, structure-of-arrays.
#[derive(Clone, Debug, Default)]
pub struct Bodies {
    /// Masses.
    pub mass: Vec<f64>,
    /// Principal inertia tensors (body frame).
    pub inertia: Vec<PrincipalInertia>,
    /// `true` for a free body (translates), `false` for a rotor about a fixed point.
    pub free: Vec<bool>,
    /// Positions (centre of mass of a free body, pivot of a rotor).
    pub position: Vec<Vec3>,
    /// Linear momenta (zero for rotors).
    pub momentum: Vec<Vec3>,
    /// Attitudes.
    pub rotation: Vec<Mat3>,
    /// Body angular momenta.
    pub pi: Vec<Vec3>,
    /// Forces of the last evaluation (spatial).
    pub force: Vec<Vec3>,
    /// Torques of the last evaluation (body frame).
    pub torque: Vec<Vec3>,
    /// Time.
    pub t: f64,
    forces_valid: bool,
}

/// Bytes of state per body.
pub const BYTES_PER_BODY: usize = std::mem::size_of::<f64>()
    + std::mem::size_of::<PrincipalInertia>()
    + std::mem::size_of::<bool>()
    + 5 * std::mem::size_of::<Vec3>()
    + std::mem::size_of::<Mat3>();

/// Read-only view of a configuration, for interactions.
#[derive(Clone, Copy, Debug)]
pub struct Configuration<'a> {
    /// Time.
    pub t: f64,
    /// Masses.
    pub mass: &'a [f64],
    /// Free or rotor.
    pub free: &'a [bool],
    /// Positions.
    pub position: &'a [Vec3],
    /// Attitudes.
    pub rotation: &'a [Mat3],
}

/// Forces and torques of all bodies from their positions and attitudes.
pub trait Interaction: Sync {
    /// Write every body's spatial force and body-frame torque.
    fn compute(&self, config: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]);
    /// The potential energy of the configuration.
    fn potential_energy(&self, config: Configuration<'_>) -> f64;
}

/// Totals of a many-body state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Totals {
    /// Kinetic (translation and rotation) plus potential energy.
    pub energy: f64,
    /// Total linear momentum `Σ p`.
    pub linear_momentum: Vec3,
    /// Total angular momentum about the origin, orbital plus spin: `Σ x × p + R Π`.
    pub angular_momentum: Vec3,
}

/// Run `f(first_index, chunk_a, chunk_b)` over matching chunks of two slices.
fn chunks2<A: Send, B: Send>(a: &mut [A], b: &mut [B], f: impl Fn(usize, &mut [A], &mut [B]) + Sync + Send) {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        a.par_chunks_mut(CHUNK)
            .zip(b.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(k, (x, y))| f(k * CHUNK, x, y));
    }
    #[cfg(not(feature = "parallel"))]
    for (k, (x, y)) in a.chunks_mut(CHUNK).zip(b.chunks_mut(CHUNK)).enumerate() {
        f(k * CHUNK, x, y);
    }
}

/// Run `f(first_index, chunk_a, chunk_b, chunk_c, chunk_d)` over matching chunks of four
/// slices of the same length.
fn chunks4<A: Send, B: Send, C: Send, D: Send>(
    a: &mut [A],
    b: &mut [B],
    c: &mut [C],
    d: &mut [D],
    f: impl Fn(usize, &mut [A], &mut [B], &mut [C], &mut [D]) + Sync + Send,
) {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        a.par_chunks_mut(CHUNK)
            .zip(b.par_chunks_mut(CHUNK))
            .zip(c.par_chunks_mut(CHUNK))
            .zip(d.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(k, (((a, b), c), d))| f(k * CHUNK, a, b, c, d));
    }
    #[cfg(not(feature = "parallel"))]
    for (k, (((a, b), c), d)) in a
        .chunks_mut(CHUNK)
        .zip(b.chunks_mut(CHUNK))
        .zip(c.chunks_mut(CHUNK))
        .zip(d.chunks_mut(CHUNK))
        .enumerate()
    {
        f(k * CHUNK, a, b, c, d);
    }
}

/// The torque-free midpoint Lie rotation of one body: two half steps
/// `solve (M) → Ψ; R ← R exp(Ψ); Π ← exp(−Ψ) Π`.
#[inline]
pub(crate) fn free_rotation(
    inertia: &PrincipalInertia,
    r: &mut Mat3,
    pi: &mut Vec3,
    hh: f64,
) -> std::result::Result<(), midpoint::NotConverged> {
    for _ in 0..2 {
        let (psi, _) = midpoint::solve(inertia, *pi, hh)?;
        let inc = so3::Increment::new(psi);
        *r = inc.rotate(r);
        *pi = inc.inverse_apply(*pi);
    }
    Ok(())
}

impl Bodies {
    /// An empty system at `t = 0`.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of bodies.
    #[must_use]
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    /// Whether there are no bodies.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Add a body; mass and moments must be positive and finite, the state finite.
    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        mass: f64,
        moments: Vec3,
        free: bool,
        position: Vec3,
        momentum: Vec3,
        rotation: Mat3,
        pi: Vec3,
    ) -> Result<()> {
        if !(mass.is_finite() && mass > 0.0) {
            return Err(Error::InvalidParameter {
                name: "mass",
                value: mass,
                reason: "must be finite and positive",
            });
        }
        crate::inertia::Inertia::principal(moments.to_array())?;
        let t = self.t;
        for (field, ok) in [
            ("position", position.is_finite()),
            ("momentum", momentum.is_finite()),
            ("rotation", rotation.is_finite()),
            ("pi", pi.is_finite()),
        ] {
            if !ok {
                return Err(Error::NonFiniteState { field, t });
            }
        }
        self.mass.push(mass);
        self.inertia.push(PrincipalInertia::new(moments));
        self.free.push(free);
        self.position.push(position);
        self.momentum.push(if free { momentum } else { Vec3::ZERO });
        self.rotation.push(rotation);
        self.pi.push(pi);
        self.force.push(Vec3::ZERO);
        self.torque.push(Vec3::ZERO);
        self.forces_valid = false;
        Ok(())
    }

    /// The configuration, for interactions.
    #[must_use]
    pub fn configuration(&self) -> Configuration<'_> {
        Configuration {
            t: self.t,
            mass: &self.mass,
            free: &self.free,
            position: &self.position,
            rotation: &self.rotation,
        }
    }

    /// Evaluate forces and torques at the current configuration (the step does this on
    /// its own; call it after changing the state by hand).
    pub fn evaluate<I: Interaction + ?Sized>(&mut self, interaction: &I) {
        let config = Configuration {
            t: self.t,
            mass: &self.mass,
            free: &self.free,
            position: &self.position,
            rotation: &self.rotation,
        };
        interaction.compute(config, &mut self.force, &mut self.torque);
        self.forces_valid = true;
    }

    /// Half kick `p ← p + (h/2) F`, `Π ← Π + (h/2) T`.
    fn kick(&mut self, h: f64) {
        let hh = 0.5 * h;
        let (force, torque, free) = (&self.force, &self.torque, &self.free);
        chunks2(&mut self.momentum, &mut self.pi, |start, p, pi| {
            for (k, (p, pi)) in p.iter_mut().zip(pi.iter_mut()).enumerate() {
                let i = start + k;
                if free[i] {
                    *p += force[i] * hh;
                }
                *pi += torque[i] * hh;
            }
        });
    }

    /// One step of the splitting integrator (see the module documentation).
    ///
    /// # Errors
    /// A bad step, or a body whose midpoint equation fails (the step is then too large for
    /// its spin); the system is then left mid-step.
    pub fn step<I: Interaction + ?Sized>(&mut self, interaction: &I, h: f64) -> Result<()> {
        if !(h.is_finite() && h != 0.0) {
            return Err(Error::InvalidStep { h });
        }
        if !self.forces_valid {
            self.evaluate(interaction);
        }
        let hh = 0.5 * h;
        let t = self.t;
        let failure: Mutex<Option<(usize, Error)>> = Mutex::new(None);
        let failure_ref = &failure;
        let (inertia, free, mass, force, torque) = (&self.inertia, &self.free, &self.mass, &self.force, &self.torque);
        let avx = crate::lanes::use_avx();
        // One pass over each chunk: the start impulse, the drift of free bodies, and the
        // torque-free midpoint Lie rotation (two half steps as in EA), four bodies at a
        // time in SIMD lanes where they take the common path.
        chunks4(
            &mut self.momentum,
            &mut self.pi,
            &mut self.position,
            &mut self.rotation,
            |start, p, pi, x, r| {
                for k in 0..p.len() {
                    let i = start + k;
                    if free[i] {
                        p[k] += force[i] * hh;
                    }
                    pi[k] += torque[i] * hh;
                    if free[i] {
                        x[k] += p[k] * (h / mass[i]);
                    }
                }
                let mut k = 0;
                while k < r.len() {
                    let i = start + k;
                    if cfg!(feature = "simd") && k + LANES <= r.len() {
                        let group: [PrincipalInertia; LANES] = std::array::from_fn(|j| inertia[i + j]);
                        let (rs, ps) = (
                            <&mut [Mat3; LANES]>::try_from(&mut r[k..k + LANES]).expect("four"),
                            <&mut [Vec3; LANES]>::try_from(&mut pi[k..k + LANES]).expect("four"),
                        );
                        if crate::lanes::free_rotation_x4(
                            avx,
                            group.map(|g| g.moments),
                            group.map(|g| g.inverse),
                            group.map(|g| g.inverse_norm_bound()),
                            rs,
                            ps,
                            hh,
                        ) {
                            k += LANES;
                            continue;
                        }
                    }
                    // The scalar path: the rest of the chunk, and groups the lanes hand over.
                    let end = (k + LANES).min(r.len());
                    for k in k..end {
                        let i = start + k;
                        if let Err(e) = free_rotation(&inertia[i], &mut r[k], &mut pi[k], hh) {
                            let mut f = failure_ref.lock().expect("not poisoned");
                            let err = newton_error("many-body splitting", "midpoint equation (M)", t, h, e);
                            if f.as_ref().map_or(true, |(j, _)| i < *j) {
                                *f = Some((i, err));
                            }
                            return;
                        }
                    }
                    k = end;
                }
            },
        );
        if let Some((_, e)) = failure.into_inner().expect("not poisoned") {
            self.forces_valid = false;
            return Err(e);
        }
        self.t = t + h;
        self.evaluate(interaction);
        self.kick(h);
        Ok(())
    }

    /// One step of a symmetric composition of the splitting integrator.
    pub fn step_composed<I: Interaction + ?Sized>(&mut self, interaction: &I, h: f64, scheme: &Scheme) -> Result<()> {
        for k in 0..scheme.stages() {
            self.step(interaction, scheme.gamma(k) * h)?;
        }
        Ok(())
    }

    /// Energy, total linear and angular momentum (sums in index order).
    #[must_use]
    pub fn totals<I: Interaction + ?Sized>(&self, interaction: &I) -> Totals {
        let mut kinetic = 0.0;
        let mut lin = Vec3::ZERO;
        let mut ang = Vec3::ZERO;
        for i in 0..self.len() {
            let w = self.inertia[i].inverse.component_mul(self.pi[i]);
            kinetic += 0.5 * self.pi[i].dot(w);
            if self.free[i] {
                kinetic += 0.5 * self.momentum[i].norm_squared() / self.mass[i];
            }
            lin += self.momentum[i];
            ang += self.position[i].cross(self.momentum[i]) + self.rotation[i] * self.pi[i];
        }
        Totals {
            energy: kinetic + interaction.potential_energy(self.configuration()),
            linear_momentum: lin,
            angular_momentum: ang,
        }
    }
}
