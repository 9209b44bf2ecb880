//! The half list's pair pass ([`HalfPass`]) and its evaluation by a team of threads
//! ([`DipoleTeam`], the [`TeamForces`] of [`Dipoles`]).

use super::{body_at, place_of, Dipoles, PairConstants, Scratch};
use crate::linalg::{Mat3, Vec3};
use crate::many::half_list::HalfList;
use crate::many::{Configuration, TeamForces};

/// `Σ f(k)` over `k < items`, each term computed in parallel and the terms added in order:
/// the same bits for any number of threads.
pub(super) fn sum_in_order(items: usize, f: impl Fn(usize) -> f64 + Sync + Send) -> f64 {
    #[cfg(feature = "parallel")]
    let terms: Vec<f64> = {
        use rayon::prelude::*;
        (0..items).into_par_iter().map(f).collect()
    };
    #[cfg(not(feature = "parallel"))]
    let terms: Vec<f64> = (0..items).map(f).collect();
    terms.iter().sum()
}

/// This step's positions and dipoles in place order (`order[place]` is a body; the
/// identity without the spatial sort), in parallel over chunks of places.
pub(super) fn gather_places(s: &mut Scratch, position: &[Vec3], dipoles: &[Vec3]) {
    let n = position.len();
    s.sorted_position.resize(n, Vec3::ZERO);
    s.sorted_dipole.resize(n, Vec3::ZERO);
    place_into(&s.order, &mut s.sorted_position, &mut s.sorted_dipole, position, |i| {
        dipoles[i]
    });
}

/// `x[place] = position[body]` and `m[place] = dipole(body)` for the body at each place
/// (`order[place]`), in parallel over chunks of places.
fn place_into(order: &[u32], x: &mut [Vec3], m: &mut [Vec3], position: &[Vec3], dipole: impl Fn(usize) -> Vec3 + Sync) {
    let place = |first: usize, x: &mut [Vec3], m: &mut [Vec3]| {
        for (q, (x, m)) in x.iter_mut().zip(m.iter_mut()).enumerate() {
            let i = body_at(order, first + q);
            (*x, *m) = (position[i], dipole(i));
        }
    };
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        let chunk = crate::many::CHUNK;
        crate::many::contiguous_per_thread(x.par_chunks_mut(chunk).zip(m.par_chunks_mut(chunk)).enumerate())
            .for_each(|(k, (x, m))| place(k * chunk, x, m));
    }
    #[cfg(not(feature = "parallel"))]
    place(0, x, m);
}

/// `f(p, own, scratch)` for each partition `p` of `half` from `first` on, with its owners'
/// sums (`own` starts at partition `first`'s first owner) and its scratch, in parallel:
/// halves of the partitions by `rayon::join` (contiguous runs of partitions per thread,
/// nothing allocated).
pub(super) fn each_partition(
    half: &HalfList,
    first: usize,
    own: &mut [[Vec3; 2]],
    scratch: &mut [PartitionScratch],
    f: &(impl Fn(usize, &mut [[Vec3; 2]], &mut PartitionScratch) + Sync),
) {
    match scratch {
        [] => {}
        [one] => f(first, own, one),
        _ => {
            let mid = scratch.len() / 2;
            let cut = half.owners(first + mid).start - half.owners(first).start;
            let (own_a, own_b) = own.split_at_mut(cut);
            let (scratch_a, scratch_b) = scratch.split_at_mut(mid);
            #[cfg(feature = "parallel")]
            rayon::join(
                || each_partition(half, first, own_a, scratch_a, f),
                || each_partition(half, first + mid, own_b, scratch_b, f),
            );
            #[cfg(not(feature = "parallel"))]
            {
                each_partition(half, first, own_a, scratch_a, f);
                each_partition(half, first + mid, own_b, scratch_b, f);
            }
        }
    }
}

/// A partition's scratch in the half list's pair pass: its window of the partners' shares
/// and one owner's shares on the way, on cache lines of its own (aligned to 128 bytes, the
/// pair of lines Intel's adjacent-line prefetcher fetches together). Adjacent in one
/// vector, the two `Vec` headers of neighbouring partitions shared a line, and two threads
/// writing a share buffer's length for every owner made it bounce between the cores.
#[repr(align(128))]
#[derive(Debug, Default)]
pub(super) struct PartitionScratch {
    pub(super) window: Vec<[Vec3; 2]>,
    share: Vec<[Vec3; 2]>,
}

/// The pair pass of the half list over partitions of owners: what it reads.
pub(super) struct HalfPass<'a> {
    model: &'a Dipoles,
    constants: &'a PairConstants,
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    lanes: (bool, crate::many::lanes::PairKernel),
    position: &'a [Vec3],
    dipoles: &'a [Vec3],
    half: &'a HalfList,
}

impl<'a> HalfPass<'a> {
    pub(super) fn new(
        model: &'a Dipoles,
        constants: &'a PairConstants,
        position: &'a [Vec3],
        dipoles: &'a [Vec3],
        half: &'a HalfList,
    ) -> Self {
        HalfPass {
            model,
            constants,
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            lanes: (crate::many::lanes::use_avx(), model.lane_kernel(constants)),
            position,
            dipoles,
            half,
        }
    }

    /// Partition `p` of owners: each owner's force and field from the partners it owns
    /// into `own` (the partition's places), the partners' shares added into its window in
    /// pair order.
    #[cfg_attr(
        not(all(feature = "simd", target_arch = "x86_64")),
        allow(clippy::unnecessary_literal_unwrap)
    )]
    pub(super) fn partition(&self, p: usize, own: &mut [[Vec3; 2]], scratch: &mut PartitionScratch) {
        let PartitionScratch { window, share } = scratch;
        let half = self.half;
        let (position, dipoles) = (self.position, self.dipoles);
        let first = half.owners(p).start;
        window.clear();
        window.resize(half.window_len(p), [Vec3::ZERO; 2]);
        for (q, o) in own.iter_mut().enumerate() {
            let i = first + q;
            let range = half.start[i]..half.start[i + 1];
            let partners = &half.partner[range.clone()];
            share.clear();
            share.resize(partners.len(), [Vec3::ZERO; 2]);
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            let lanes = crate::many::lanes::half_pairs_x4(
                self.lanes.0,
                &self.lanes.1,
                position[i],
                dipoles[i],
                position,
                dipoles,
                partners,
                share,
            );
            #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
            let lanes: Option<(Vec3, Vec3)> = None;
            let (fi, bi) = lanes.unwrap_or_else(|| {
                self.model.half_pairs(
                    self.constants,
                    position[i],
                    dipoles[i],
                    position,
                    dipoles,
                    partners,
                    share,
                )
            });
            for (s, &slot) in share.iter().zip(&half.partner_slot[range]) {
                let w = &mut window[slot as usize];
                w[0] += s[0];
                w[1] += s[1];
            }
            *o = [fi, bi];
        }
    }
}

/// A body's force and torque from its force and field `[f, b]`: the torque is
/// `Rᵀ (m × B)` in the body frame.
#[inline]
pub(super) fn force_and_torque([f, b]: [Vec3; 2], rotation: &Mat3, dipole: Vec3) -> (Vec3, Vec3) {
    (f, rotation.tr_mul_vec(dipole.cross(b)))
}

/// The half-list evaluation of [`Dipoles`] by a team of threads ([`TeamForces`]), on the
/// list of the last build: `prepare` puts each body's position and dipole at its place and
/// checks its displacement against the skin, `pairs` is [`HalfPass::partition`] over the
/// part's partitions, `forces` is [`HalfList::total`] at each body's place: the operations
/// of `Dipoles::compute`'s half-list path, so the same bits. The buffers the phases
/// share are taken from the scratch for the team's life.
pub(super) struct DipoleTeam<'a> {
    model: &'a Dipoles,
    /// The lock on the scratch, held for the team's life.
    _guard: std::sync::MutexGuard<'a, Scratch>,
    /// The scratch the guard holds, read (and by `refresh` written) through this pointer
    /// only while the team lives.
    scratch_ptr: *mut Scratch,
    constants: PairConstants,
    limit: f64,
    n: usize,
    /// Taken from the scratch (given back on drop), written by the phases through the
    /// pointers below: positions and dipoles by place, each place's own sums, each
    /// partition's window and share buffer.
    place_position: Vec<Vec3>,
    place_dipole: Vec<Vec3>,
    own: Vec<[Vec3; 2]>,
    partitions: Vec<PartitionScratch>,
    position_ptr: *mut Vec3,
    dipole_ptr: *mut Vec3,
    own_ptr: *mut [Vec3; 2],
    partitions_ptr: *mut PartitionScratch,
}

// SAFETY: the phases write disjoint entries of the buffers (a part writes the places of
// the bodies of the chunks it takes, and the sums, windows and shares of the partitions it
// takes) and read others' only in a later phase, after a barrier, except that `forces` of
// a chunk reads the places of that chunk's bodies alone, which `prepare` of other chunks
// does not write (the calling order of `TeamForces`).
unsafe impl Sync for DipoleTeam<'_> {}

impl<'a> DipoleTeam<'a> {
    /// The team on the current list, if the last evaluation used the half list for `n`
    /// bodies (otherwise `None`: the list is missing, or the full list is in use).
    pub(super) fn new(model: &'a Dipoles, n: usize) -> Option<Self> {
        model.cutoff?;
        let mut scratch = model.scratch.lock().expect("not poisoned");
        let scratch_ptr: *mut Scratch = &mut *scratch;
        // SAFETY: the guard is held for the team's life.
        let s = unsafe { &mut *scratch_ptr };
        let parts = s.half.partitions();
        let ready = n > 0
            && n <= model.half_list_max_bodies
            && model.list_matches(n, s)
            && (s.rank.is_empty() || s.rank.len() == n)
            && s.sorted_position.len() == n
            && s.sorted_dipole.len() == n
            && s.own.len() == n
            && s.partitions.len() == parts;
        if !ready {
            return None;
        }
        let (mut place_position, mut place_dipole, mut own, mut partitions) = (
            std::mem::take(&mut s.sorted_position),
            std::mem::take(&mut s.sorted_dipole),
            std::mem::take(&mut s.own),
            std::mem::take(&mut s.partitions),
        );
        let (position_ptr, dipole_ptr, own_ptr, partitions_ptr) = (
            place_position.as_mut_ptr(),
            place_dipole.as_mut_ptr(),
            own.as_mut_ptr(),
            partitions.as_mut_ptr(),
        );
        Some(DipoleTeam {
            model,
            _guard: scratch,
            scratch_ptr,
            constants: model.constants(),
            limit: (0.5 * model.skin) * (0.5 * model.skin),
            n,
            place_position,
            place_dipole,
            own,
            partitions,
            position_ptr,
            dipole_ptr,
            own_ptr,
            partitions_ptr,
        })
    }

    /// The scratch (list, order, reference positions).
    #[inline]
    fn s(&self) -> &Scratch {
        // SAFETY: written only by `refresh`, while no other phase runs.
        unsafe { &*self.scratch_ptr }
    }

    /// The place of body `i`.
    #[inline]
    fn place(&self, i: usize) -> usize {
        place_of(&self.s().rank, i)
    }
}

impl Drop for DipoleTeam<'_> {
    fn drop(&mut self) {
        // SAFETY: the team is over; the guard is still held.
        let s = unsafe { &mut *self.scratch_ptr };
        s.sorted_position = std::mem::take(&mut self.place_position);
        s.sorted_dipole = std::mem::take(&mut self.place_dipole);
        s.own = std::mem::take(&mut self.own);
        s.partitions = std::mem::take(&mut self.partitions);
    }
}

impl TeamForces for DipoleTeam<'_> {
    unsafe fn prepare(&self, first: usize, run: Configuration<'_>) -> bool {
        let len = run.position.len();
        assert!(first + len <= self.n);
        let reference = &self.s().reference[first..first + len];
        let mut fresh = true;
        for (q, x0) in reference.iter().enumerate() {
            let p = self.place(first + q);
            assert!(p < self.n);
            // SAFETY: the places of this part's bodies are written by it alone, and read by
            // nobody, in this phase.
            unsafe {
                *self.position_ptr.add(p) = run.position[q];
                *self.dipole_ptr.add(p) = run.rotation[q] * self.model.moment;
            }
            fresh &= (run.position[q] - *x0).norm_squared() <= self.limit;
        }
        fresh
    }

    unsafe fn refresh(&self, config: Configuration<'_>) -> bool {
        // SAFETY: the other parts wait at a barrier; nothing else reads the scratch now.
        let s = unsafe { &mut *self.scratch_ptr };
        if !self.model.update_list(&config, s)
            || !self.model.list_matches(self.n, s)
            || s.half.partitions() != self.partitions.len()
        {
            return false;
        }
        // This step's positions and dipoles at the new places.
        // SAFETY: the places are read by nobody in this phase.
        let (x, m) = unsafe {
            (
                std::slice::from_raw_parts_mut(self.position_ptr, self.n),
                std::slice::from_raw_parts_mut(self.dipole_ptr, self.n),
            )
        };
        place_into(&s.order, x, m, config.position, |i| {
            config.rotation[i] * self.model.moment
        });
        true
    }

    fn pair_items(&self) -> usize {
        self.s().half.partitions()
    }

    unsafe fn pairs(&self, items: std::ops::Range<usize>, config: Configuration<'_>) {
        let half = &self.s().half;
        assert!(config.position.len() == self.n && items.end <= half.partitions());
        // SAFETY: no position or dipole is written in this phase.
        let (position, dipoles) = unsafe {
            (
                std::slice::from_raw_parts(self.position_ptr, self.n),
                std::slice::from_raw_parts(self.dipole_ptr, self.n),
            )
        };
        let pass = HalfPass::new(self.model, &self.constants, position, dipoles, half);
        for p in items {
            let owners = half.owners(p);
            // SAFETY: partition `p`'s sums, window and shares are this part's alone in this
            // phase.
            let (own, scratch) = unsafe {
                (
                    std::slice::from_raw_parts_mut(self.own_ptr.add(owners.start), owners.len()),
                    &mut *self.partitions_ptr.add(p),
                )
            };
            pass.partition(p, own, scratch);
        }
    }

    unsafe fn forces(&self, first: usize, run: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        let len = run.position.len();
        assert!(first + len <= self.n && force.len() == len && torque.len() == len);
        let half = &self.s().half;
        let window = |p: usize| -> &[[Vec3; 2]] {
            assert!(p < half.partitions());
            // SAFETY: windows are not written in this phase.
            unsafe { (*self.partitions_ptr.add(p)).window.as_slice() }
        };
        for q in 0..len {
            let p = self.place(first + q);
            assert!(p < self.n);
            // SAFETY: sums and dipoles are not written in this phase.
            let (own, dipole) = unsafe { (*self.own_ptr.add(p), *self.dipole_ptr.add(p)) };
            (force[q], torque[q]) = force_and_torque(half.total(p, own, window), &run.rotation[q], dipole);
        }
    }
}
