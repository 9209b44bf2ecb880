//! The half neighbour list: each pair once, with the partner's share accumulated per
//! partition of owners and reduced in a fixed order.
//!
//! Pair `(i, j)` is kept by the body [`owns_pair`] names, so each body owns about half its
//! pairs whatever the order of the indices. The owners (places in cell order with the
//! spatial sort) are cut into partitions of [`HalfList::partition_places`] places, a
//! number fixed by the body count alone (about [`PARTITIONS`] of them). Evaluating a
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

/// About this many partitions (at least one chunk of places each).
pub(crate) const PARTITIONS: usize = 16;

/// Which body of a pair keeps it in the half list: the lower index when `i + j` is even,
/// the higher when it is odd. Each body then owns about half of its pairs whatever the
/// order of the indices (with "the lower index owns" the low indices own nearly all their
/// pairs once the fluid has mixed, and the first thread did 75 % of the pair work on two
/// threads).
#[inline]
pub(crate) fn owns_pair(i: usize, j: usize) -> bool {
    if (i + j) % 2 == 0 {
        i < j
    } else {
        j < i
    }
}

/// The half list over places and its partitions' windows.
#[derive(Debug, Default)]
pub(crate) struct HalfList {
    /// The pairs owned by place `i` are `start[i]..start[i + 1]`.
    pub(crate) start: Vec<usize>,
    /// Per pair, the partner's place.
    pub(crate) partner: Vec<u32>,
    /// Per pair, the partner's entry in its partition's window.
    pub(crate) partner_slot: Vec<u32>,
    /// Places per partition (a multiple of [`CHUNK`]).
    pub(crate) partition_places: usize,
    /// Per partition, the chunks of places its window covers, increasing.
    window_chunks: Vec<Vec<u32>>,
    /// The windows covering chunk `c` of places: `cover[cover_start[c]..cover_start[c + 1]]`,
    /// as (partition, chunk index in its window), in partition order.
    cover_start: Vec<usize>,
    cover: Vec<(u32, u32)>,
    /// Scratch of the build: per chunk, the last partition that marked it and its index.
    mark: Vec<(u32, u32)>,
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
        self.window_chunks.clear();
        self.cover_start.clear();
        self.cover.clear();
    }

    /// Build from the full list of `n` places (`list[list_start[i]..list_start[i + 1]]`
    /// the neighbours of place `i`).
    pub(crate) fn build(&mut self, n: usize, list_start: &[usize], list: &[u32]) {
        self.clear();
        self.start.push(0);
        for i in 0..n {
            for &j in &list[list_start[i]..list_start[i + 1]] {
                if owns_pair(i, j as usize) {
                    self.partner.push(j);
                }
            }
            self.start.push(self.partner.len());
        }
        let chunks = n.div_ceil(CHUNK);
        self.partition_places = (chunks / PARTITIONS).max(1) * CHUNK;
        let parts = n.div_ceil(self.partition_places);
        self.mark.clear();
        self.mark.resize(chunks, (u32::MAX, 0));
        self.partner_slot.resize(self.partner.len(), 0);
        let mut per_chunk = std::mem::take(&mut self.cover_start);
        per_chunk.clear();
        per_chunk.resize(chunks + 1, 0);
        self.window_chunks.resize_with(parts, Vec::new);
        for p in 0..parts {
            let owners = self.owners(p, n);
            let pairs = self.start[owners.start]..self.start[owners.end];
            let window = &mut self.window_chunks[p];
            window.clear();
            for &j in &self.partner[pairs.clone()] {
                let c = j as usize / CHUNK;
                if self.mark[c].0 != p as u32 {
                    self.mark[c] = (p as u32, 0);
                    window.push(c as u32);
                }
            }
            window.sort_unstable();
            for (k, &c) in window.iter().enumerate() {
                self.mark[c as usize].1 = k as u32;
                per_chunk[c as usize + 1] += 1;
            }
            for q in pairs {
                let j = self.partner[q] as usize;
                self.partner_slot[q] = (self.mark[j / CHUNK].1 as usize * CHUNK + j % CHUNK) as u32;
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

    /// The owner places of partition `p` of `n`.
    pub(crate) fn owners(&self, p: usize, n: usize) -> Range<usize> {
        (p * self.partition_places).min(n)..((p + 1) * self.partition_places).min(n)
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
