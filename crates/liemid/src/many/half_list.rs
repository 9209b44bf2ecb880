//! The half neighbour list: each pair once, with the partner's share accumulated per
//! partition of owners and reduced in a fixed order.
//!
//! Pair `(i, j)` is kept by the body the other lies ahead of in the half stencil of the
//! list build (the cells ahead in (z, y, x) order, the later bodies of its own cell), so
//! each body owns about half its pairs, spatially, whatever the order of the indices (with
//! "the lower index owns" the low indices own nearly all their pairs once the fluid has
//! mixed, and the first thread did 75 % of the pair work on two threads). The owners
//! (places in cell order with the spatial sort) are cut into [`PARTITIONS`] runs of places
//! (fewer below 16 chunks of places, one per chunk) of equal work by the list's pair counts
//! ([`OWNER_COST`]), a cut fixed by the list alone. Evaluating a
//! partition sums each owner's force and field from its partners, and adds the partners'
//! shares, pair by pair in list order, into the partition's *window*: a buffer over the
//! chunks of places its partners lie in (with the spatial sort a few planes of cells, a
//! buffer that stays in cache, instead of one slot per pair in memory). A body's total is
//! its own sum plus the entries of the windows covering its place, in partition order.
//! Every sum runs in an order fixed by the list, so the result does not depend on how the
//! partitions are shared among threads.
//!
//! Reference: the partition-and-reduce form of Newton's third law in parallel MD codes,
//! e.g. LAMMPS's OPENMP package (per-thread force arrays); here the partitions are fixed
//! independently of the threads.

use std::ops::Range;

use crate::linalg::Vec3;
use crate::many::CHUNK;

/// Partitions of the owners (fewer when there are fewer chunks of places: as many as
/// chunks). Cut by work, not whole chunks: at 10³ bodies four partitions of 256, 256, 256
/// and 232 places gave the first of two threads 5.6 % more pairs than the second.
pub(crate) const PARTITIONS: usize = 16;

/// An owner's cost in the pair pass over its own pairs, in pairs: the partitions are cut at
/// equal `pairs + OWNER_COST · owners`. Measured on the fluid at 10⁵ bodies (one thread,
/// partitions of 6250 owners): 146.6 k pairs took 345 µs, the last partition's 106.4 k
/// (the start's lattice of 47³ sites leaves its top two planes nearly empty) 268 µs, about
/// 1.9 ns a pair and 10 ns an owner. With equal places that partition gave the second of
/// two threads 3.5 % fewer pairs, and it waited 7 % of the step.
const OWNER_COST: usize = 5;

/// The half list over places and its partitions' windows.
#[derive(Debug, Default)]
pub(crate) struct HalfList {
    /// The pairs owned by place `i` are `start[i]..start[i + 1]`.
    pub(crate) start: Vec<usize>,
    /// Per pair, the partner's place.
    pub(crate) partner: Vec<u32>,
    /// Per pair, the partner's entry in its partition's window.
    pub(crate) partner_slot: Vec<u32>,
    /// The owner places of partition `p` are `partition_start[p]..partition_start[p + 1]`.
    partition_start: Vec<usize>,
    /// Per partition, the chunks of places its window covers, increasing.
    window_chunks: Vec<Vec<u32>>,
    /// The windows covering chunk `c` of places: `cover[cover_start[c]..cover_start[c + 1]]`,
    /// as (partition, chunk index in its window), in partition order.
    cover_start: Vec<usize>,
    cover: Vec<(u32, u32)>,
    /// Scratch of the build, per partition: each chunk's index in its window.
    marks: Vec<Vec<u32>>,
}

impl HalfList {
    /// Whether the list is built for `n` bodies.
    pub(crate) fn is_built_for(&self, n: usize) -> bool {
        self.start.len() == n + 1
    }

    /// Forget the list (not in use).
    pub(crate) fn clear(&mut self) {
        self.start.clear();
        self.partner.clear();
        self.partner_slot.clear();
        self.partition_start.clear();
        self.window_chunks.clear();
        self.cover_start.clear();
        self.cover.clear();
    }

    /// Build for `n` places from the pairs found in parallel over fixed chunks of places:
    /// per chunk, each place's count of owned pairs and the partners, in place order.
    /// The partitions' windows are found in parallel over the partitions.
    pub(crate) fn build(&mut self, n: usize, chunk_pairs: &[(Vec<u32>, Vec<u32>)]) {
        self.clear();
        self.start.push(0);
        for (partners, counts) in chunk_pairs {
            for &count in counts {
                self.start.push(self.start[self.start.len() - 1] + count as usize);
            }
            self.partner.extend_from_slice(partners);
        }
        assert_eq!(self.start.len(), n + 1, "a count per place");
        let chunks = n.div_ceil(CHUNK);
        let parts = if n == 0 { 0 } else { chunks.clamp(1, PARTITIONS) };
        // Cut where the work `start[q] + OWNER_COST · q` of the owners before place `q`
        // first reaches the partition's share of the whole.
        let total = self.start[n] + OWNER_COST * n;
        self.partition_start.clear();
        self.partition_start.push(0);
        for p in 1..parts {
            let share = p * total / parts;
            let start = &self.start;
            let cut = partition_point(n, |q| start[q] + OWNER_COST * q < share);
            self.partition_start.push(cut);
        }
        if parts > 0 {
            self.partition_start.push(n);
        }
        self.partner_slot.resize(self.partner.len(), 0);
        self.window_chunks.resize_with(parts, Vec::new);
        self.marks.resize_with(parts, Vec::new);
        // Each partition's pairs are a contiguous range: split the slots accordingly.
        let mut slots: Vec<&mut [u32]> = Vec::with_capacity(parts);
        let mut rest = self.partner_slot.as_mut_slice();
        for p in 0..parts {
            let owners = self.partition_start[p]..self.partition_start[p + 1];
            let len = self.start[owners.end] - self.start[owners.start];
            let (head, tail) = rest.split_at_mut(len);
            slots.push(head);
            rest = tail;
        }
        let (start, partner, cuts) = (&self.start, &self.partner, &self.partition_start);
        let one = |p: usize, slot: &mut [u32], window: &mut Vec<u32>, mark: &mut Vec<u32>| {
            let owners = cuts[p]..cuts[p + 1];
            let pairs = &partner[start[owners.start]..start[owners.end]];
            mark.clear();
            mark.resize(chunks, u32::MAX);
            window.clear();
            for &j in pairs {
                let c = j as usize / CHUNK;
                if mark[c] == u32::MAX {
                    mark[c] = 0;
                    window.push(c as u32);
                }
            }
            window.sort_unstable();
            for (k, &c) in window.iter().enumerate() {
                mark[c as usize] = k as u32;
            }
            for (slot, &j) in slot.iter_mut().zip(pairs) {
                let j = j as usize;
                *slot = (mark[j / CHUNK] as usize * CHUNK + j % CHUNK) as u32;
            }
        };
        #[cfg(feature = "parallel")]
        {
            use rayon::prelude::*;
            slots
                .into_par_iter()
                .zip(self.window_chunks.par_iter_mut())
                .zip(self.marks.par_iter_mut())
                .enumerate()
                .for_each(|(p, ((slot, window), mark))| one(p, slot, window, mark));
        }
        #[cfg(not(feature = "parallel"))]
        for (p, ((slot, window), mark)) in slots
            .into_iter()
            .zip(self.window_chunks.iter_mut())
            .zip(self.marks.iter_mut())
            .enumerate()
        {
            one(p, slot, window, mark);
        }
        // The covers of each chunk, in partition order (a counting sort by chunk).
        let mut per_chunk = std::mem::take(&mut self.cover_start);
        per_chunk.clear();
        per_chunk.resize(chunks + 1, 0);
        for window in &self.window_chunks {
            for &c in window {
                per_chunk[c as usize + 1] += 1;
            }
        }
        for c in 0..chunks {
            per_chunk[c + 1] += per_chunk[c];
        }
        self.cover.resize(per_chunk[chunks], (0, 0));
        // Fill each chunk's covers in partition order, advancing its start, then restore
        // the starts (each advanced by its count, that is to the next chunk's start).
        for (p, window) in self.window_chunks.iter().enumerate() {
            for (k, &c) in window.iter().enumerate() {
                self.cover[per_chunk[c as usize]] = (p as u32, k as u32);
                per_chunk[c as usize] += 1;
            }
        }
        for c in (1..=chunks).rev() {
            per_chunk[c] = per_chunk[c - 1];
        }
        if chunks > 0 {
            per_chunk[0] = 0;
        }
        self.cover_start = per_chunk;
    }

    /// Number of partitions.
    pub(crate) fn partitions(&self) -> usize {
        self.window_chunks.len()
    }

    /// The owner places of partition `p`.
    pub(crate) fn owners(&self, p: usize) -> Range<usize> {
        self.partition_start[p]..self.partition_start[p + 1]
    }

    /// Entries of partition `p`'s window.
    pub(crate) fn window_len(&self, p: usize) -> usize {
        self.window_chunks[p].len() * CHUNK
    }

    /// The force and field at place `q`: its own sums plus the entries of the windows
    /// covering it, in partition order (`window(p)` is partition `p`'s window).
    #[inline]
    pub(crate) fn total<'w>(&self, q: usize, own: [Vec3; 2], window: impl Fn(usize) -> &'w [[Vec3; 2]]) -> [Vec3; 2] {
        let (c, r) = (q / CHUNK, q % CHUNK);
        let [mut f, mut b] = own;
        for &(p, k) in &self.cover[self.cover_start[c]..self.cover_start[c + 1]] {
            let w = window(p as usize)[k as usize * CHUNK + r];
            f += w[0];
            b += w[1];
        }
        [f, b]
    }
}

/// The first `q` in `0..=n` with `!below(q)`, for `below` true up to some point and false
/// after (a binary search).
fn partition_point(n: usize, below: impl Fn(usize) -> bool) -> usize {
    let (mut lo, mut hi) = (0, n + 1);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if below(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo.min(n)
}
