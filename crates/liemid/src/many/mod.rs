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
//! With [`FreeRotation::Exact`] ([`Bodies::set_free_rotation`]) the torque-free rotation
//! is the exact flow ([`FreeFlow`]) instead of the two midpoint half steps: for one body it
//! is then LIEMID\[EX\], with the same structure and no Newton solve. With
//! [`FreeRotation::Variational`] each half step solves the variational equation
//! `(1/h) I Ψ = Jr(Ψ) P`, `Π ← exp(−Ψ) P` (V) instead of (M): for one body it is then
//! LIEMID\[EAV\].
//!
//! For one body with a torque it is exactly LIEMID\[EA\]; it is time reversible (not
//! symplectic with the midpoint rotation: EA's midpoint drift has a Lie–Poisson defect of
//! `O(h³)` per step (docs/theory/rigid.md §9)), and keeps the total linear and angular
//! momentum (orbital plus spin) of any translation- and rotation-invariant interaction to
//! round-off. With the exact or the variational rotation every piece is a symplectic map
//! (the kicks are exact flows of the potential, the drift the exact flow of `|p|²/2m`, the
//! rotation a Lie–Poisson map), so the step keeps the canonical form of
//! `T*(ℝ³ × SO(3))ⁿ` (measured: `tests/many/structure.rs`). Work is split into
//! chunks of [`CHUNK`] bodies; each body's force is gathered from its neighbours in a fixed
//! order and every reduction runs in index order, so results are bit-for-bit identical for
//! any number of threads.

mod advance;
mod dipoles;
mod half_list;
pub mod interactions;
#[cfg(all(feature = "simd", target_arch = "x86_64"))]
mod lanes;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod observables;
pub mod problems;
mod rotation;
pub mod thermostat;

use std::sync::Mutex;

use crate::composition::Scheme;
use crate::error::{Error, Result};
use crate::inertia::Inertia;
use crate::inertia::PrincipalInertia;
use crate::linalg::{Mat3, Vec3};
use crate::midpoint;
use crate::midpoint::newton_error;
use crate::rigid::free_flow::FreeFlow;
use crate::variational::Drift;
pub(crate) use rotation::free_rotation_by;
pub use rotation::FreeRotation;
use rotation::{lanes_available, rotate_group, GROUP};

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
    /// The exact torque-free flow of each body, when [`FreeRotation::Exact`] is chosen
    /// (empty otherwise).
    flows: Vec<FreeFlow>,
    rotation_kind: FreeRotation,
    /// Langevin steps taken: the step counter of the thermostat's noise.
    pub langevin_steps: u64,
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
    /// `true` when each body's force and torque depend only on that body's own entries of
    /// the configuration (no coupling). [`Bodies::step`] then evaluates them run by run of
    /// bodies with [`Interaction::compute_local`], in the same pass over memory as the
    /// rotation. The default is `false`.
    fn is_local(&self) -> bool {
        false
    }
    /// For a local interaction, the forces and torques of the run of consecutive bodies that
    /// `config` holds, on the calling thread; must write what [`Interaction::compute`] writes
    /// for these bodies. The default calls `compute`.
    fn compute_local(&self, config: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        self.compute(config, force, torque);
    }
    /// For [`Bodies::advance`]: call `team` with an evaluation of the forces of `bodies`
    /// bodies in phases by a team of threads, if the interaction has what it needs ready
    /// (e.g. the neighbour list of the last evaluation); `false` when it has not called it.
    /// The default is `false`: `advance` then takes ordinary steps.
    fn team_forces(&self, bodies: usize, team: &mut dyn FnMut(&dyn TeamForces)) -> bool {
        let _ = (bodies, team);
        false
    }
}

/// Forces and torques evaluated by a team of threads in three phases per step, for
/// [`Bodies::advance`]: `prepare` (per body, after its motion), `pairs` (per chunk of
/// work item, reading every body), `forces` (per body). It must give exactly what
/// [`Interaction::compute`] gives, bit for bit.
///
/// # Safety (of the calls)
/// [`Bodies::advance`] makes the calls in this order, which implementations may rely on
/// for the buffers they share between threads: every step, the parts call `prepare` for
/// every chunk of bodies, each chunk by one part, meet at a barrier, call `pairs` for every
/// work item, each item by one part, meet again, and call `forces` for every chunk, each
/// chunk by one part, which then calls the next step's `prepare` of that chunk, while other
/// parts may still be in `forces` of other chunks (so `forces` of a chunk reads nothing that
/// `prepare` of another chunk writes). Which part takes which chunk or item is decided at
/// run time. When a `prepare` returned `false`, one part calls `refresh` after the first
/// barrier while the others wait, and the parts meet again before `pairs`. Nothing else is
/// called while the team lives.
pub trait TeamForces: Sync {
    /// After the motion of the run of bodies `run` (chunk `first / CHUNK`), starting at
    /// body `first`: prepare their per-body data. `false` when what the evaluation was
    /// built on no longer holds for one of them (a body moved beyond the neighbour list's
    /// skin): the team then stops and [`Interaction::compute`] completes the step.
    ///
    /// # Safety
    /// See the trait.
    unsafe fn prepare(&self, first: usize, run: Configuration<'_>) -> bool;
    /// After a `prepare` found the evaluation stale: bring it up to date for `config`
    /// (every body, moved), e.g. rebuild the neighbour list, so that the step goes on with
    /// `pairs`. Called by one part while the others wait and help with the pool's parallel
    /// work; `false` when it cannot (the team then stops and [`Interaction::compute`]
    /// completes the step). The default is `false`.
    ///
    /// # Safety
    /// See the trait; nothing else is called while it runs.
    unsafe fn refresh(&self, config: Configuration<'_>) -> bool {
        let _ = config;
        false
    }
    /// The number of work items of the pair pass (fixed while the team lives).
    fn pair_items(&self) -> usize;
    /// The pair pass of the work items `items`; `config` is every body.
    ///
    /// # Safety
    /// See the trait.
    unsafe fn pairs(&self, items: std::ops::Range<usize>, config: Configuration<'_>);
    /// The forces and torques of the run of bodies `run` starting at body `first`.
    ///
    /// # Safety
    /// See the trait.
    unsafe fn forces(&self, first: usize, run: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]);
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

/// Split `chunks` into one contiguous run per thread of the current pool, instead of
/// rayon's adaptive splitting into many pieces: each thread then steps the same bodies in
/// every pass and every step, and finds them in its own caches (measured: 2 threads went
/// from 1.3-1.6 to 1.7-1.8 times the speed of 1 for 10⁴ to 10⁶ torque-free bodies).
#[cfg(feature = "parallel")]
pub(crate) fn contiguous_per_thread<I: rayon::iter::IndexedParallelIterator>(chunks: I) -> rayon::iter::MinLen<I> {
    let threads = rayon::current_num_threads().max(1);
    let per_thread = (chunks.len() / threads).max(1);
    chunks.with_min_len(per_thread)
}

/// Run `f(first_index, chunk_a, chunk_b)` over matching chunks of two slices.
fn chunks2<A: Send, B: Send>(a: &mut [A], b: &mut [B], f: impl Fn(usize, &mut [A], &mut [B]) + Sync + Send) {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        contiguous_per_thread(a.par_chunks_mut(CHUNK).zip(b.par_chunks_mut(CHUNK)).enumerate())
            .for_each(|(k, (x, y))| f(k * CHUNK, x, y));
    }
    #[cfg(not(feature = "parallel"))]
    for (k, (x, y)) in a.chunks_mut(CHUNK).zip(b.chunks_mut(CHUNK)).enumerate() {
        f(k * CHUNK, x, y);
    }
}

/// The mutable state of a run of consecutive bodies, for one pass of a step.
struct Chunk<'a> {
    momentum: &'a mut [Vec3],
    pi: &'a mut [Vec3],
    position: &'a mut [Vec3],
    rotation: &'a mut [Mat3],
    force: &'a mut [Vec3],
    torque: &'a mut [Vec3],
}

/// Run `f(first_index, chunk)` over the chunks of [`CHUNK`] bodies of `b`, in parallel with the
/// `parallel` feature; every body is in exactly one chunk, whatever the thread count.
fn for_each_chunk(b: Chunk<'_>, f: impl Fn(usize, Chunk<'_>) + Sync + Send) {
    #[cfg(feature = "parallel")]
    use rayon::prelude::{IndexedParallelIterator, ParallelIterator, ParallelSliceMut as _};
    macro_rules! split {
        ($chunks:ident) => {
            (
                b.momentum.$chunks(CHUNK),
                b.pi.$chunks(CHUNK),
                b.position.$chunks(CHUNK),
                b.rotation.$chunks(CHUNK),
                b.force.$chunks(CHUNK),
                b.torque.$chunks(CHUNK),
            )
        };
    }
    #[cfg(feature = "parallel")]
    let (p, pi, x, r, fo, to) = split!(par_chunks_mut);
    #[cfg(not(feature = "parallel"))]
    let (p, pi, x, r, fo, to) = split!(chunks_mut);
    let all = p.zip(pi).zip(x).zip(r).zip(fo).zip(to).enumerate();
    #[cfg(feature = "parallel")]
    let all = contiguous_per_thread(all);
    all.for_each(|(k, (((((momentum, pi), position), rotation), force), torque))| {
        f(
            k * CHUNK,
            Chunk {
                momentum,
                pi,
                position,
                rotation,
                force,
                torque,
            },
        );
    });
}

/// Record the failure of body `i` unless a body of lower index already failed, so that the
/// error reported does not depend on which thread found its failure first.
fn keep_first_failure(failure: &Mutex<Option<(usize, Error)>>, i: usize, e: Error) {
    let mut f = failure.lock().expect("not poisoned");
    if f.as_ref().is_none_or(|(j, _)| i < *j) {
        *f = Some((i, e));
    }
}

/// Half kick of a run of bodies: `p ← p + (h/2) F` (free bodies), `Π ← Π + (h/2) T`.
#[inline]
fn kick_chunk(free: &[bool], p: &mut [Vec3], pi: &mut [Vec3], force: &[Vec3], torque: &[Vec3], hh: f64) {
    for k in 0..p.len() {
        if free[k] {
            p[k] += force[k] * hh;
        }
        pi[k] += torque[k] * hh;
    }
}

#[derive(Clone, Copy)]
/// What the motion of a step between the impulses reads: the bodies' constants, the free
/// rotation, the step.
struct Motion<'a> {
    inertia: &'a [PrincipalInertia],
    free: &'a [bool],
    mass: &'a [f64],
    /// The exact flows, for [`FreeRotation::Exact`].
    exact: Option<&'a [FreeFlow]>,
    /// The equation of the rotation's half steps otherwise.
    rotation_drift: Drift,
    /// Whether the SIMD lanes take groups of bodies (the midpoint drift only).
    lanes: bool,
    h: f64,
    /// The time at the start of the step (for error messages).
    t: f64,
    /// Whether free bodies drift (`x ← x + h p/m`); `false` when the caller moves the
    /// translations itself ([`Bodies::kick_rotate`]).
    drift: bool,
}

impl Motion<'_> {
    /// The start impulse, the drift of free bodies and the torque-free rotation (exact, or
    /// two half steps of the midpoint rule as in EA, four bodies at a time in SIMD lanes
    /// where they take the common path, or of the variational equation as in EAV) of the
    /// run of bodies `c` starting at `start`. `false` when a body's equation failed
    /// (recorded in `failure`; the run is then left part-way).
    #[inline]
    fn move_chunk(&self, start: usize, c: &mut Chunk<'_>, failure: &Mutex<Option<(usize, Error)>>) -> bool {
        let (h, hh) = (self.h, 0.5 * self.h);
        let n = c.momentum.len();
        let (free, mass, inertia) = (
            &self.free[start..start + n],
            &self.mass[start..start + n],
            &self.inertia[start..start + n],
        );
        let (p, pi, x, r) = (&mut *c.momentum, &mut *c.pi, &mut *c.position, &mut *c.rotation);
        kick_chunk(free, p, pi, c.force, c.torque, hh);
        if self.drift {
            for k in 0..n {
                if free[k] {
                    x[k] += p[k] * (h / mass[k]);
                }
            }
        }
        if let Some(flows) = self.exact {
            for k in 0..n {
                let (p_end, r_end) = flows[start + k].flow(Vec3::load_split(&pi[k]), &r[k], h);
                (pi[k], r[k]) = (p_end, r_end);
            }
            return true;
        }
        let mut k = 0;
        while k < n {
            let end = (k + GROUP).min(n);
            if rotate_group(self.lanes, &inertia[k..end], &mut r[k..end], &mut pi[k..end], hh) {
                k = end;
                continue;
            }
            // The scalar path: the rest of the chunk, and groups the lanes hand over.
            for k in k..end {
                if let Err(e) = free_rotation_by(self.rotation_drift, &inertia[k], &mut r[k], &mut pi[k], hh) {
                    let err = newton_error("many-body splitting", self.rotation_drift.equation(), self.t, h, e);
                    keep_first_failure(failure, start + k, err);
                    return false;
                }
            }
            k = end;
        }
        true
    }
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

    /// The free rotation the step uses.
    #[must_use]
    pub fn free_rotation(&self) -> FreeRotation {
        self.rotation_kind
    }

    /// Choose the free rotation of [`Bodies::step`] (the default is
    /// [`FreeRotation::Midpoint`]); for [`FreeRotation::Exact`] each body's flow is built
    /// here and for every body pushed later. It also sets the rotation of the steps built
    /// on the bodies (the Langevin step, the beams' methods).
    ///
    /// # Errors
    /// Not expected: the moments were checked when the bodies were pushed.
    pub fn set_free_rotation(&mut self, kind: FreeRotation) -> Result<()> {
        self.flows.clear();
        if kind == FreeRotation::Exact {
            self.flows.reserve(self.len());
            for g in &self.inertia {
                self.flows
                    .push(FreeFlow::new(&Inertia::principal(g.moments.to_array())?)?);
            }
        }
        self.rotation_kind = kind;
        Ok(())
    }

    /// The torque-free rotation of body `i` over `h` by the chosen free rotation (the exact
    /// flow, or two half steps of (M) or (V)), for the steps built on the bodies that move
    /// one body at a time (the beams' impulse method). On an error nothing is written; the
    /// error names the equation.
    pub(crate) fn rotate_free(
        &mut self,
        i: usize,
        h: f64,
    ) -> std::result::Result<(), (&'static str, midpoint::NotConverged)> {
        match self.rotation_kind.drift() {
            None => {
                let (pi, r) = self.flows[i].flow(Vec3::load_split(&self.pi[i]), &self.rotation[i], h);
                (self.pi[i], self.rotation[i]) = (pi, r);
                Ok(())
            }
            Some(drift) => free_rotation_by(drift, &self.inertia[i], &mut self.rotation[i], &mut self.pi[i], 0.5 * h)
                .map_err(|e| (drift.equation(), e)),
        }
    }

    /// Turn the bodies by two half steps of `drift`'s equation ([`FreeRotation::Midpoint`]
    /// or [`FreeRotation::Variational`]); [`Bodies::set_free_rotation`] without the exact
    /// flow, which alone can fail to build.
    pub fn set_drift(&mut self, drift: Drift) {
        self.flows.clear();
        self.rotation_kind = match drift {
            Drift::Midpoint => FreeRotation::Midpoint,
            Drift::Variational => FreeRotation::Variational,
        };
    }

    /// Bytes of state per body with the chosen free rotation.
    #[must_use]
    pub fn bytes_per_body(&self) -> usize {
        self.rotation_kind.bytes_per_body()
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
        let tensor = Inertia::principal(moments.to_array())?;
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
        if self.rotation_kind == FreeRotation::Exact {
            self.flows.push(FreeFlow::new(&tensor)?);
        }
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
            let range = start..start + p.len();
            kick_chunk(&free[range.clone()], p, pi, &force[range.clone()], &torque[range], hh);
        });
    }

    /// The step's [`Motion`] (constants) and its mutable state, borrowed apart.
    fn split(&mut self, h: f64) -> (Motion<'_>, Chunk<'_>) {
        let motion = Motion {
            inertia: &self.inertia,
            free: &self.free,
            mass: &self.mass,
            exact: (self.rotation_kind == FreeRotation::Exact).then_some(self.flows.as_slice()),
            rotation_drift: self.rotation_kind.drift().unwrap_or_default(),
            lanes: lanes_available() && self.rotation_kind == FreeRotation::Midpoint,
            h,
            t: self.t,
            drift: true,
        };
        let state = Chunk {
            momentum: &mut self.momentum,
            pi: &mut self.pi,
            position: &mut self.position,
            rotation: &mut self.rotation,
            force: &mut self.force,
            torque: &mut self.torque,
        };
        (motion, state)
    }

    /// One step of the splitting integrator (see the module documentation).
    ///
    /// # Errors
    /// A bad step, or a body whose rotation's equation, (M) or (V), fails (the step is then
    /// too large for its spin); the system is then left mid-step.
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
        let local = interaction.is_local();
        let (motion, all) = self.split(h);
        let (free, mass) = (motion.free, motion.mass);
        // One pass over each chunk: the motion (`Motion::move_chunk`); for a local
        // interaction also the new forces and torques and the end impulse, so the step
        // sweeps memory once.
        for_each_chunk(all, |start, mut c| {
            if !motion.move_chunk(start, &mut c, failure_ref) {
                return;
            }
            let n = c.momentum.len();
            let (free, mass) = (&free[start..start + n], &mass[start..start + n]);
            let (p, pi, x, r) = (c.momentum, c.pi, c.position, c.rotation);
            if local {
                let config = Configuration {
                    t: t + h,
                    mass,
                    free,
                    position: x,
                    rotation: r,
                };
                interaction.compute_local(config, c.force, c.torque);
                kick_chunk(free, p, pi, c.force, c.torque, hh);
            }
        });
        if let Some((_, e)) = failure.into_inner().expect("not poisoned") {
            self.forces_valid = false;
            return Err(e);
        }
        self.t = t + h;
        if local {
            self.forces_valid = true;
        } else {
            self.evaluate(interaction);
            self.kick(h);
        }
        Ok(())
    }

    /// The first half of a step whose translations the caller moves: the start impulse
    /// `p ← p + (h/2) F`, `Π ← Π + (h/2) T` and the torque-free rotation over `h`, no drift
    /// (forces evaluated first if they are stale). [`Bodies::finish_step`] completes it.
    ///
    /// # Errors
    /// A bad step, or a body whose rotation's equation fails.
    pub(crate) fn kick_rotate<I: Interaction + ?Sized>(&mut self, interaction: &I, h: f64) -> Result<()> {
        if !(h.is_finite() && h != 0.0) {
            return Err(Error::InvalidStep { h });
        }
        if !self.forces_valid {
            self.evaluate(interaction);
        }
        let failure: Mutex<Option<(usize, Error)>> = Mutex::new(None);
        let failure_ref = &failure;
        let (mut motion, all) = self.split(h);
        motion.drift = false;
        for_each_chunk(all, |start, mut c| {
            motion.move_chunk(start, &mut c, failure_ref);
        });
        if let Some((_, e)) = failure.into_inner().expect("not poisoned") {
            self.forces_valid = false;
            return Err(e);
        }
        Ok(())
    }

    /// The end of a step begun by [`Bodies::kick_rotate`], once the translations have
    /// moved: `t ← t + h`, the forces at the new configuration, the end impulse.
    pub(crate) fn finish_step<I: Interaction + ?Sized>(&mut self, interaction: &I, h: f64) {
        self.t += h;
        self.evaluate(interaction);
        self.kick(h);
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
