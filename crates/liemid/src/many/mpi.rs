//! The dipolar fluid over MPI by spatial domain decomposition, with the same bits on any
//! number of ranks (the `mpi` feature).
//!
//! **Domains.** The periodic box `[0, L)³` is cut into `R` slabs along x, `[r L/R,
//! (r + 1) L/R)` for rank `r`; a body belongs to the slab of its position wrapped into the
//! box. Slabs must be at least the Verlet list's reach `r_c + skin` wide (so a slab's
//! ghosts come from the two slabs beside it), and the box must hold a cell list at that
//! reach (3 cells a side).
//!
//! **Ghosts and migration** (LAMMPS's `comm` as in Plimpton 1995): at each build of the
//! Verlet list, decided for the whole system exactly as one process decides it (some body
//! moved more than half the skin since the last build: an `MPI_Allreduce` of the flag each
//! step), bodies move to the rank of their slab (27 numbers each), then each rank sends to
//! its neighbours the identity and position of every body within the reach of their slab
//! (periodic distance in x), and builds its owned bodies' lists ([`DomainForces`]). Between
//! builds the ghosts are fixed and only their positions and dipoles (6 numbers) travel, one
//! `MPI_Alltoallv` before each force evaluation. Positions are never wrapped: a ghost keeps
//! its owner's coordinates and the cell list and minimum image find its periodic images, as
//! in one process.
//!
//! **The order of sums.** Each body's force and torque are summed over its full list in the
//! order of the whole system's list (the stencil's cells, then identities; see
//! [`DomainForces`]) with the whole system's kernel, so they are the bits of one process's
//! full list (`Dipoles::half_list_max_bodies = 0`), on any number of ranks and threads.
//! The step is [`Bodies::step`]'s, body by body. The half list (each pair once, the default
//! of one process) sums in another order: the same physics, other bits.
//!
//! **Checkpoints.** A run's state is every body's state plus the positions at the last list
//! build ([`DomainRun::reference`]); a run started from them (on any number of ranks, or
//! in one process) builds the same lists and continues with the bits of an uninterrupted run.
//!
//! Reference: S. Plimpton, Fast parallel algorithms for short-range molecular dynamics,
//! J. Comput. Phys. 117 (1995) 1-19.

use mpi::collective::SystemOperation;
use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Count;

use crate::interactions::{Dipoles, DomainForces};
use crate::linalg::{Mat3, Vec3};
use crate::many::Bodies;

/// Numbers per migrating body: identity, mass, moments, free, position, momentum,
/// attitude, body angular momentum, reference position.
pub const MIGRATE_RECORD: usize = 27;
/// Numbers per ghost at a list build: identity and reference position.
pub const GHOST_SETUP_RECORD: usize = 4;
/// Numbers per ghost per step: position and dipole.
pub const GHOST_RECORD: usize = 6;

/// Why a decomposed run cannot start or go on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DomainError {
    /// Bad use (the same on every rank): the command's exit 2.
    Input(String),
    /// A failed step (on some rank; every rank returns it): exit 1.
    Run(String),
}

impl std::fmt::Display for DomainError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DomainError::Input(m) | DomainError::Run(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for DomainError {}

/// The slabs of the periodic box.
#[derive(Clone, Copy, Debug)]
struct Slabs {
    box_length: f64,
    ranks: usize,
    width: f64,
    /// Ghost margin: the reach plus a relative 1e-9 of the box (extra ghosts cost a little,
    /// missing ones would change the lists).
    reach: f64,
}

impl Slabs {
    fn wrap(&self, x: f64) -> f64 {
        let l = self.box_length;
        let w = x - (x / l).floor() * l;
        if w >= l {
            0.0
        } else {
            w
        }
    }

    fn owner(&self, x: f64) -> usize {
        ((self.wrap(x) / self.width) as usize).min(self.ranks - 1)
    }

    /// Whether wrapped `x` lies within the reach of slab `r` (periodic distance in x).
    fn near(&self, x: f64, r: usize) -> bool {
        let (lo, hi) = (r as f64 * self.width, (r + 1) as f64 * self.width);
        let l = self.box_length;
        let m = |v: f64| v - (v / l).floor() * l;
        (x >= lo && x < hi) || m(lo - x) <= self.reach || m(x - hi) <= self.reach
    }
}

/// Communication counted by a [`DomainRun`] on its rank (payload bytes it sends).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CommStats {
    /// Force evaluations (each with one ghost exchange and one flag reduction).
    pub evaluations: u64,
    /// Verlet-list builds (each with a migration and a ghost setup).
    pub builds: u64,
    /// Payload bytes of the per-step ghost exchanges.
    pub ghost_bytes: u64,
    /// Point-to-point partners of the per-step ghost exchanges, summed over evaluations.
    pub ghost_messages: u64,
    /// Payload bytes of migrations and ghost setups.
    pub build_bytes: u64,
    /// Ghosts held at the last build.
    pub ghosts: usize,
    /// Bodies owned at the last build.
    pub owned: usize,
}

/// One rank's share of a dipolar fluid decomposed into slabs (see the module).
pub struct DomainRun<'a> {
    comm: &'a SimpleCommunicator,
    rank: usize,
    model: &'a Dipoles,
    slabs: Slabs,
    /// The owned bodies, in increasing identity.
    pub bodies: Bodies,
    /// The identities (indices in the whole system) of the owned bodies.
    pub ids: Vec<u64>,
    reference: Vec<Vec3>,
    /// The bodies held (owned and ghosts) in increasing identity.
    local_id: Vec<u64>,
    local_position: Vec<Vec3>,
    local_dipole: Vec<Vec3>,
    /// The local index of each owned body, and of each ghost in the order received.
    owned_local: Vec<u32>,
    ghost_local: Vec<u32>,
    /// The owned bodies sent as ghosts, grouped by destination rank.
    send_index: Vec<u32>,
    send_counts: Vec<Count>,
    send_displs: Vec<Count>,
    recv_counts: Vec<Count>,
    recv_displs: Vec<Count>,
    send_buffer: Vec<f64>,
    recv_buffer: Vec<f64>,
    forces: DomainForces,
    /// Counted communication.
    pub stats: CommStats,
}

fn displacements(counts: &[Count]) -> Vec<Count> {
    let mut d = vec![0; counts.len()];
    displace(counts, &mut d);
    d
}

/// The displacements of `counts` (their running sums from 0) into `d`, without allocating.
fn displace(counts: &[Count], d: &mut [Count]) {
    let mut acc = 0;
    for (c, d) in counts.iter().zip(d) {
        *d = acc;
        acc += c;
    }
}

fn count(n: usize) -> Count {
    Count::try_from(n).expect("message within MPI's count range")
}

impl<'a> DomainRun<'a> {
    /// Rank `comm.rank()`'s share of `all` (the whole system, the same on every rank) with
    /// `model`: the bodies of its slab by `reference` (the positions at the list's last build,
    /// from a checkpoint) or by their positions, the ghosts, the lists and the forces.
    ///
    /// # Errors
    /// [`DomainError::Input`], the same on every rank: a model without a cutoff or periodic
    /// box, a box too small for a cell list at the reach, slabs thinner than the reach (too
    /// many ranks), a reference of the wrong length.
    pub fn new(
        comm: &'a SimpleCommunicator,
        model: &'a Dipoles,
        all: &Bodies,
        reference: Option<&[Vec3]>,
    ) -> Result<Self, DomainError> {
        let ranks = comm.size() as usize;
        let rank = comm.rank() as usize;
        let (Some(cutoff), Some(box_length), Some(reach)) = (model.cutoff, model.box_length, model.reach()) else {
            return Err(DomainError::Input(
                "MPI decomposes a periodic system with a cutoff: this one is not periodic (its box is shorter than \
                 twice the cutoff, so all pairs interact in open space)"
                    .into(),
            ));
        };
        if box_length < 3.0 * reach {
            return Err(DomainError::Input(format!(
                "the box {box_length:.4} is too small for the decomposition at this cutoff: it needs at least 3 \
                 cells of the reach {reach:.4} (cutoff {cutoff} + skin {}) a side",
                model.skin
            )));
        }
        let max_ranks = (box_length / reach).floor() as usize;
        if ranks > max_ranks {
            return Err(DomainError::Input(format!(
                "{ranks} ranks are more than the {max_ranks} slabs the box {box_length:.4} allows at the reach \
                 {reach:.4} (cutoff + skin): each slab must be at least the reach wide"
            )));
        }
        let n = all.len();
        if let Some(r) = reference {
            if r.len() != n {
                return Err(DomainError::Input(format!(
                    "the checkpoint's reference positions are {} for {n} bodies",
                    r.len()
                )));
            }
        }
        let slabs = Slabs {
            box_length,
            ranks,
            width: box_length / ranks as f64,
            reach: reach + 1e-9 * box_length,
        };
        let reference = reference.unwrap_or(&all.position);
        let mut bodies = Bodies::new();
        bodies
            .set_free_rotation(all.free_rotation())
            .map_err(|e| DomainError::Input(e.to_string()))?;
        bodies.t = all.t;
        bodies.langevin_steps = all.langevin_steps;
        let mut ids = Vec::new();
        let mut own_reference = Vec::new();
        for (i, x0) in reference.iter().enumerate() {
            if slabs.owner(x0.x) == rank {
                push_body(&mut bodies, all, i).map_err(DomainError::Input)?;
                ids.push(i as u64);
                own_reference.push(*x0);
            }
        }
        let mut run = DomainRun {
            comm,
            rank,
            model,
            slabs,
            bodies,
            ids,
            reference: own_reference,
            local_id: Vec::new(),
            local_position: Vec::new(),
            local_dipole: Vec::new(),
            owned_local: Vec::new(),
            ghost_local: Vec::new(),
            send_index: Vec::new(),
            send_counts: vec![0; ranks],
            send_displs: vec![0; ranks],
            recv_counts: vec![0; ranks],
            recv_displs: vec![0; ranks],
            send_buffer: Vec::new(),
            recv_buffer: Vec::new(),
            forces: DomainForces::new(),
            stats: CommStats::default(),
        };
        run.build()?;
        run.exchange_and_forces();
        Ok(run)
    }

    /// Number of ranks.
    #[must_use]
    pub fn ranks(&self) -> usize {
        self.slabs.ranks
    }

    /// This rank.
    #[must_use]
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// The owned bodies' positions at the list's last build (in the order of
    /// [`DomainRun::ids`]).
    #[must_use]
    pub fn reference(&self) -> &[Vec3] {
        &self.reference
    }

    /// The ranks whose slabs can lie within reach of this one's (the slabs beside it).
    fn neighbours(&self) -> Vec<usize> {
        let r = self.slabs.ranks;
        let mut out = vec![(self.rank + r - 1) % r, (self.rank + 1) % r];
        out.sort_unstable();
        out.dedup();
        out.retain(|&k| k != self.rank);
        out
    }

    /// `MPI_Alltoallv` of `send_buffer` by `send_counts` into `recv_buffer` (counts in
    /// numbers): first the counts, unless `counts_known`.
    fn all_to_all(&mut self, counts_known: bool) {
        displace(&self.send_counts, &mut self.send_displs);
        if !counts_known {
            self.comm
                .all_to_all_into(&self.send_counts[..], &mut self.recv_counts[..]);
            displace(&self.recv_counts, &mut self.recv_displs);
        }
        let total: usize = self.recv_counts.iter().map(|&c| c as usize).sum();
        self.recv_buffer.resize(total, 0.0);
        let send = Partition::new(&self.send_buffer[..], &self.send_counts[..], &self.send_displs[..]);
        let mut recv = PartitionMut::new(&mut self.recv_buffer[..], &self.recv_counts[..], &self.recv_displs[..]);
        self.comm.all_to_all_varcount_into(&send, &mut recv);
    }

    /// At a list build (the reference positions set): migrate the bodies that left the
    /// slab, send the ghosts, index the held bodies by identity, build the lists.
    fn build(&mut self) -> Result<(), DomainError> {
        let ranks = self.slabs.ranks;
        // Migration: the bodies whose reference lies in another slab, grouped by rank.
        let mut leaving: Vec<Vec<usize>> = vec![Vec::new(); ranks];
        for (q, x) in self.reference.iter().enumerate() {
            let r = self.slabs.owner(x.x);
            if r != self.rank {
                leaving[r].push(q);
            }
        }
        self.send_buffer.clear();
        for (r, qs) in leaving.iter().enumerate() {
            for &q in qs {
                pack_body(&self.bodies, q, self.ids[q], self.reference[q], &mut self.send_buffer);
            }
            self.send_counts[r] = count(qs.len() * MIGRATE_RECORD);
        }
        self.stats.build_bytes += 8 * self.send_buffer.len() as u64;
        self.all_to_all(false);
        if leaving.iter().any(|l| !l.is_empty()) || !self.recv_buffer.is_empty() {
            let mut gone = vec![false; self.bodies.len()];
            leaving.iter().flatten().for_each(|&q| gone[q] = true);
            self.rebuild_owned(&gone)?;
        }
        // Ghosts: identity and reference position to each neighbouring slab within reach.
        let neighbours = self.neighbours();
        self.send_buffer.clear();
        self.send_index.clear();
        self.send_counts.iter_mut().for_each(|c| *c = 0);
        for &r in &neighbours {
            let before = self.send_index.len();
            for (q, x) in self.reference.iter().enumerate() {
                if self.slabs.near(self.slabs.wrap(x.x), r) {
                    self.send_index.push(q as u32);
                    self.send_buffer.push(f64::from_bits(self.ids[q]));
                    self.send_buffer.extend_from_slice(&[x.x, x.y, x.z]);
                }
            }
            self.send_counts[r] = count((self.send_index.len() - before) * GHOST_SETUP_RECORD);
        }
        self.stats.build_bytes += 8 * self.send_buffer.len() as u64;
        self.all_to_all(false);
        // The held bodies in increasing identity: (identity, owned index or ghost number).
        let ghosts = self.recv_buffer.len() / GHOST_SETUP_RECORD;
        let mut held: Vec<(u64, u32, bool)> = Vec::with_capacity(self.ids.len() + ghosts);
        held.extend(self.ids.iter().enumerate().map(|(q, &id)| (id, q as u32, true)));
        held.extend((0..ghosts).map(|g| (self.recv_buffer[g * GHOST_SETUP_RECORD].to_bits(), g as u32, false)));
        held.sort_unstable();
        if held.windows(2).any(|w| w[0].0 == w[1].0) {
            return Err(DomainError::Run(
                "a body is held twice (a ghost of its own slab): the decomposition is inconsistent".into(),
            ));
        }
        let m = held.len();
        self.local_id.clear();
        self.local_position.clear();
        self.local_position.resize(m, Vec3::ZERO);
        self.local_dipole.clear();
        self.local_dipole.resize(m, Vec3::ZERO);
        self.owned_local.clear();
        self.owned_local.resize(self.ids.len(), 0);
        self.ghost_local.clear();
        self.ghost_local.resize(ghosts, 0);
        for (k, &(id, index, owned)) in held.iter().enumerate() {
            self.local_id.push(id);
            let index = index as usize;
            if owned {
                self.owned_local[index] = k as u32;
                self.local_position[k] = self.reference[index];
            } else {
                self.ghost_local[index] = k as u32;
                let g = &self.recv_buffer[index * GHOST_SETUP_RECORD + 1..(index + 1) * GHOST_SETUP_RECORD];
                self.local_position[k] = Vec3::new(g[0], g[1], g[2]);
            }
        }
        if !self.forces.build(self.model, &self.local_position, &self.owned_local) {
            return Err(DomainError::Input(
                "the box is too small for a cell list at this cutoff and skin".into(),
            ));
        }
        // The per-step exchange: the same bodies, 6 numbers each.
        for c in &mut self.send_counts {
            *c = *c / count(GHOST_SETUP_RECORD) * count(GHOST_RECORD);
        }
        for c in &mut self.recv_counts {
            *c = *c / count(GHOST_SETUP_RECORD) * count(GHOST_RECORD);
        }
        displace(&self.recv_counts, &mut self.recv_displs);
        self.stats.builds += 1;
        self.stats.ghosts = ghosts;
        self.stats.owned = self.ids.len();
        Ok(())
    }

    /// The owned bodies after a migration: those not `gone`, and those received (in
    /// `recv_buffer`), in increasing identity.
    fn rebuild_owned(&mut self, gone: &[bool]) -> Result<(), DomainError> {
        let mut records: Vec<f64> = Vec::new();
        for q in (0..self.bodies.len()).filter(|&q| !gone[q]) {
            pack_body(&self.bodies, q, self.ids[q], self.reference[q], &mut records);
        }
        records.extend_from_slice(&self.recv_buffer);
        let mut order: Vec<(u64, usize)> = records
            .chunks_exact(MIGRATE_RECORD)
            .enumerate()
            .map(|(k, r)| (r[0].to_bits(), k))
            .collect();
        order.sort_unstable();
        let mut bodies = Bodies::new();
        bodies
            .set_free_rotation(self.bodies.free_rotation())
            .map_err(|e| DomainError::Run(e.to_string()))?;
        (bodies.t, bodies.langevin_steps) = (self.bodies.t, self.bodies.langevin_steps);
        self.ids.clear();
        self.reference.clear();
        for &(id, k) in &order {
            let r = &records[k * MIGRATE_RECORD..(k + 1) * MIGRATE_RECORD];
            unpack_body(&mut bodies, r).map_err(DomainError::Run)?;
            self.ids.push(id);
            self.reference.push(Vec3::new(r[24], r[25], r[26]));
        }
        self.bodies = bodies;
        Ok(())
    }

    /// The ghosts' positions and dipoles from their owners, then the owned bodies' forces.
    fn exchange_and_forces(&mut self) {
        let moment = self.model.moment;
        for (q, &k) in self.owned_local.iter().enumerate() {
            self.local_position[k as usize] = self.bodies.position[q];
            self.local_dipole[k as usize] = self.bodies.rotation[q] * moment;
        }
        self.send_buffer.clear();
        for &q in &self.send_index {
            let k = self.owned_local[q as usize] as usize;
            let (x, m) = (self.local_position[k], self.local_dipole[k]);
            self.send_buffer.extend_from_slice(&[x.x, x.y, x.z, m.x, m.y, m.z]);
        }
        self.stats.ghost_bytes += 8 * self.send_buffer.len() as u64;
        self.stats.ghost_messages += self.send_counts.iter().filter(|&&c| c > 0).count() as u64;
        self.all_to_all(true);
        for (g, &k) in self.ghost_local.iter().enumerate() {
            let v = &self.recv_buffer[g * GHOST_RECORD..(g + 1) * GHOST_RECORD];
            self.local_position[k as usize] = Vec3::new(v[0], v[1], v[2]);
            self.local_dipole[k as usize] = Vec3::new(v[3], v[4], v[5]);
        }
        self.forces.forces(
            self.model,
            &self.local_position,
            &self.local_dipole,
            &self.owned_local,
            &self.bodies.rotation,
            &mut self.bodies.force,
            &mut self.bodies.torque,
        );
        self.bodies.forces_valid = true;
        self.stats.evaluations += 1;
    }

    /// The forces at the current configuration, after this rank's motion (`failed`: its
    /// motion failed): one reduction decides, for every rank alike, whether a step failed
    /// somewhere and whether the list is stale (some body moved more than half the skin
    /// since the last build, the test of one process); then a build if stale, the ghost
    /// exchange and the forces.
    fn evaluate(&mut self, failed: Option<&crate::Error>) -> Result<(), DomainError> {
        let limit = (0.5 * self.model.skin) * (0.5 * self.model.skin);
        let stale = !self
            .bodies
            .position
            .iter()
            .zip(&self.reference)
            .all(|(x, x0)| (*x - *x0).norm_squared() <= limit);
        let ranks = self.slabs.ranks as i64;
        let local = [
            i64::from(stale),
            if failed.is_some() { ranks - self.rank as i64 } else { 0 },
        ];
        let mut global = [0i64; 2];
        self.comm
            .all_reduce_into(&local[..], &mut global[..], SystemOperation::max());
        if global[1] > 0 {
            let first = (ranks - global[1]) as usize;
            return Err(DomainError::Run(match failed {
                Some(e) if first == self.rank => e.to_string(),
                _ => format!("stopped: rank {first} failed its step"),
            }));
        }
        if global[0] > 0 {
            self.reference.clear();
            self.reference.extend_from_slice(&self.bodies.position);
            self.build()?;
        }
        self.exchange_and_forces();
        Ok(())
    }

    /// One step of [`Bodies::step`] on every rank: the start impulse, the drift and the
    /// torque-free rotation of the owned bodies, the forces at the new configuration (with
    /// the ghosts, after a list build with migration when some body moved more than half the
    /// skin), the end impulse. The same bits as one process's step with the full list.
    ///
    /// # Errors
    /// [`DomainError::Run`] on every rank when some rank's step failed (a bad step, or a
    /// midpoint equation that does not converge).
    pub fn step(&mut self, h: f64) -> Result<(), DomainError> {
        let moved = self.bodies.kick_rotate(self.model, h);
        if moved.is_ok() {
            let b = &mut self.bodies;
            for k in 0..b.len() {
                if b.free[k] {
                    b.position[k] += b.momentum[k] * (h / b.mass[k]);
                }
            }
        }
        self.bodies.t += h;
        self.evaluate(moved.as_ref().err())?;
        self.bodies.kick(h);
        Ok(())
    }

    /// One BAOAB Langevin step ([`Bodies::step_langevin`]) on every rank, the noise of each
    /// body keyed by (seed, its identity, step) as in one process: the same bits for any
    /// number of ranks. `h` is the step (the caller keeps the time).
    ///
    /// # Errors
    /// [`DomainError::Run`] on every rank when some rank's step failed.
    pub fn step_langevin(&mut self, h: f64, thermostat: &crate::many::thermostat::Langevin) -> Result<(), DomainError> {
        if !(h.is_finite() && h > 0.0) {
            return Err(DomainError::Input(format!(
                "the step must be positive and finite, found {h}"
            )));
        }
        let ids = std::mem::take(&mut self.ids);
        let moved = self.bodies.langevin_motion(h, thermostat, Some(&ids));
        self.ids = ids;
        self.evaluate(moved.as_ref().err())?;
        self.bodies.kick(h);
        Ok(())
    }

    /// The whole system on rank 0 (`None` elsewhere), in body order, with the positions at
    /// the list's last build: every rank must call it.
    #[must_use]
    pub fn gather(&self) -> Option<(Bodies, Vec<Vec3>)> {
        let mut records = Vec::with_capacity(self.bodies.len() * MIGRATE_RECORD);
        for q in 0..self.bodies.len() {
            pack_body(&self.bodies, q, self.ids[q], self.reference[q], &mut records);
        }
        let root = self.comm.process_at_rank(0);
        let mine = count(records.len());
        if self.rank != 0 {
            root.gather_into(&mine);
            root.gather_varcount_into(&records[..]);
            return None;
        }
        let mut counts = vec![0 as Count; self.slabs.ranks];
        root.gather_into_root(&mine, &mut counts[..]);
        let displs = displacements(&counts);
        let mut all = vec![0.0f64; counts.iter().map(|&c| c as usize).sum()];
        {
            let mut part = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
            root.gather_varcount_into_root(&records[..], &mut part);
        }
        let n = all.len() / MIGRATE_RECORD;
        let mut at = vec![usize::MAX; n];
        for (k, r) in all.chunks_exact(MIGRATE_RECORD).enumerate() {
            let id = r[0].to_bits() as usize;
            if id < n {
                at[id] = k;
            }
        }
        let mut bodies = Bodies::new();
        bodies.set_free_rotation(self.bodies.free_rotation()).ok()?;
        (bodies.t, bodies.langevin_steps) = (self.bodies.t, self.bodies.langevin_steps);
        let mut reference = Vec::with_capacity(n);
        for &k in &at {
            let r = all.get(k * MIGRATE_RECORD..(k + 1) * MIGRATE_RECORD)?;
            unpack_body(&mut bodies, r).ok()?;
            reference.push(Vec3::new(r[24], r[25], r[26]));
        }
        Some((bodies, reference))
    }

    /// The sum over ranks of `value` (e.g. counted bytes), on every rank.
    #[must_use]
    pub fn sum(&self, value: u64) -> u64 {
        let mut out = 0u64;
        self.comm.all_reduce_into(&value, &mut out, SystemOperation::sum());
        out
    }
}

/// Append body `q`'s [`MIGRATE_RECORD`] numbers (identity bits first).
fn pack_body(b: &Bodies, q: usize, id: u64, reference: Vec3, out: &mut Vec<f64>) {
    let (x, p, r, pi, g) = (
        b.position[q],
        b.momentum[q],
        &b.rotation[q],
        b.pi[q],
        b.inertia[q].moments,
    );
    out.push(f64::from_bits(id));
    out.extend_from_slice(&[b.mass[q], g.x, g.y, g.z, f64::from(u8::from(b.free[q]))]);
    out.extend_from_slice(&[x.x, x.y, x.z, p.x, p.y, p.z]);
    out.extend_from_slice(&r.m.concat());
    out.extend_from_slice(&[pi.x, pi.y, pi.z, reference.x, reference.y, reference.z]);
}

/// Push the body of a [`MIGRATE_RECORD`].
fn unpack_body(b: &mut Bodies, r: &[f64]) -> Result<(), String> {
    let v = |k: usize| Vec3::new(r[k], r[k + 1], r[k + 2]);
    let rotation = Mat3 {
        m: [[r[12], r[13], r[14]], [r[15], r[16], r[17]], [r[18], r[19], r[20]]],
    };
    b.push(r[1], v(2), r[5] != 0.0, v(6), v(9), rotation, v(21))
        .map_err(|e| e.to_string())
}

/// Push body `i` of `all` onto `b`.
fn push_body(b: &mut Bodies, all: &Bodies, i: usize) -> Result<(), String> {
    b.push(
        all.mass[i],
        all.inertia[i].moments,
        all.free[i],
        all.position[i],
        all.momentum[i],
        all.rotation[i],
        all.pi[i],
    )
    .map_err(|e| e.to_string())
}
