//! The cell list and the Verlet list of [`Dipoles`]: cells half the reach wide, the stencil
//! visited as contiguous runs per row, candidates against their images in the stencil
//! cells, the half list found in the build itself.

use super::{body_at, Dipoles, Scratch};
use crate::linalg::Vec3;
use crate::many::Configuration;

/// A cell list over the bodies' bounding box (or the periodic box).
pub(super) struct Cells<'a> {
    n: [usize; 3],
    origin: Vec3,
    size: f64,
    /// Cells each way the neighbours can lie in (cells at least `cutoff / reach` wide).
    reach: isize,
    /// The periodic box as the cells see it (`n · size`), and the bodies' positions wrapped
    /// into it in cell order (`wrapped[k]` is body `sorted[k]`; the positions themselves
    /// without a box): a candidate in a stencil cell reached across the box lies at its
    /// wrapped position plus the run's offset (multiples of `span`).
    span: f64,
    wrapped: &'a [Vec3],
    /// Each body's index in cell order.
    cell_rank: &'a [u32],
    periodic: bool,
    start: &'a [usize],
    sorted: &'a [usize],
}

impl Dipoles {
    /// Whether the list of the last build is the one to use for `n` bodies: built for this
    /// many, half or full as the limit asks (it may have changed), sorted as asked.
    pub(super) fn list_matches(&self, n: usize, s: &Scratch) -> bool {
        s.reference.len() == n
            && if n <= self.half_list_max_bodies {
                s.half.is_built_for(n) && s.list_start.is_empty()
            } else {
                s.list_start.len() == n + 1 && !s.half.is_built_for(n)
            }
            && s.sort_requested == self.spatial_sort
    }

    /// Whether the Verlet list of the last build holds for `c`: it is the one to use
    /// ([`Dipoles::list_matches`]) and no body has moved more than half the skin since.
    pub(super) fn list_is_fresh(&self, c: &Configuration<'_>, s: &Scratch) -> bool {
        let limit = (0.5 * self.skin) * (0.5 * self.skin);
        self.list_matches(c.position.len(), s)
            && c.position
                .iter()
                .zip(&s.reference)
                .all(|(x, x0)| (*x - *x0).norm_squared() <= limit)
    }

    /// Rebuild the Verlet list if it is missing, stale (a body moved more than `skin/2`
    /// since the last build) or for another number of bodies; `true` when there is one.
    pub(super) fn update_list(&self, c: &Configuration<'_>, s: &mut Scratch) -> bool {
        let Some(cutoff) = self.cutoff else {
            return false;
        };
        let n = c.position.len();
        let half = n <= self.half_list_max_bodies;
        if self.list_is_fresh(c, s) {
            return true;
        }
        let reach = cutoff + self.skin;
        let reach2 = reach * reach;
        let constants = self.constants();
        let mut list_start = std::mem::take(&mut s.list_start);
        let mut list = std::mem::take(&mut s.list);
        list_start.clear();
        list.clear();
        list_start.push(0);
        // In parallel over fixed chunks of bodies, then joined in chunk order: the same list
        // as a sequential build, for any number of threads.
        let chunk = crate::many::CHUNK;
        let mut chunks = std::mem::take(&mut s.chunk_lists);
        chunks.resize_with(n.div_ceil(chunk), Default::default);
        let sort = self.spatial_sort;
        let (mut order, mut rank) = (std::mem::take(&mut s.order), std::mem::take(&mut s.rank));
        {
            let cells = self.build_cells_of(c, s, reach);
            let cells = cells.as_ref();
            order.clear();
            rank.clear();
            if let (true, Some(cells)) = (sort, cells) {
                // The bodies in cell order; the list then names neighbours by their place.
                order.extend(cells.sorted.iter().map(|&i| i as u32));
                rank.resize(n, 0);
                for (k, &i) in order.iter().enumerate() {
                    rank[i as usize] = k as u32;
                }
            }
            let (order, rank) = (&*order, &*rank);
            // Distances to the candidates' images in the stencil cells (no minimum image per
            // candidate) where that image is the nearest one: in a box at least twice the
            // reach, or without a box.
            let images = cells
                .filter(|cl| !cl.periodic || cl.span >= 2.0 * reach)
                .map(|cl| (cl.wrapped, cl.cell_rank));
            let fill = |k: usize, (entries, counts): &mut (Vec<u32>, Vec<u32>)| {
                entries.clear();
                counts.clear();
                for place in k * chunk..((k + 1) * chunk).min(n) {
                    let i = body_at(order, place);
                    let before = entries.len();
                    let xi = c.position[i];
                    // Body i's wrapped position (its entry in cell order).
                    let xi_wrapped = images.map_or(Vec3::ZERO, |(w, cell_rank)| w[cell_rank[i] as usize]);
                    // Branch-free: every candidate of a run is written, and kept when within
                    // reach (a branch taken by a quarter of the candidates at random was
                    // mispredicted often).
                    self.for_neighbour_runs(i, c, cells, half, |run, first, offset| {
                        // Written into the spare capacity, every candidate, the count of
                        // kept ones advancing only past those within reach (no resize, which
                        // was a call per run).
                        entries.reserve(run.len());
                        let spare = &mut entries.spare_capacity_mut()[..run.len()];
                        let mut kept = 0;
                        let sorted = !rank.is_empty();
                        let mut keep = |k: usize, j: usize, within: bool| {
                            // With the sort, the place of the body at `first + k` in cell
                            // order is that index itself.
                            let entry = if sorted { first + k } else { j };
                            spare[kept].write(entry as u32);
                            // (`&`, not `&&`: no branch on the random `within`.)
                            kept += usize::from(within & (j != i));
                        };
                        match images {
                            // The candidate's image in this stencil cell, read in cell order:
                            // the nearest one within reach, as the box is at least twice the
                            // reach.
                            Some((w, _)) => {
                                for (k, (&j, wj)) in run.iter().zip(&w[first..first + run.len()]).enumerate() {
                                    keep(k, j, (xi_wrapped - (*wj + offset)).norm_squared() <= reach2);
                                }
                            }
                            None => {
                                for (k, &j) in run.iter().enumerate() {
                                    keep(
                                        k,
                                        j,
                                        Self::separation(&constants, xi, c.position[j]).norm_squared() <= reach2,
                                    );
                                }
                            }
                        }
                        let len = entries.len() + kept;
                        // SAFETY: the first `kept` spare entries were written (each kept
                        // entry was written before the count passed it).
                        unsafe { entries.set_len(len) };
                    });
                    counts.push((entries.len() - before) as u32);
                }
            };
            #[cfg(feature = "parallel")]
            {
                use rayon::prelude::*;
                chunks.par_iter_mut().enumerate().for_each(|(k, ch)| fill(k, ch));
            }
            #[cfg(not(feature = "parallel"))]
            for (k, ch) in chunks.iter_mut().enumerate() {
                fill(k, ch);
            }
        }
        s.order = order;
        s.rank = rank;
        s.sort_requested = sort;
        // The half list and its partitions' windows, or the full list, joined in chunk order.
        if half {
            s.half.build(n, &chunks);
            list_start.clear();
        } else {
            s.half.clear();
            for (entries, counts) in &chunks {
                for &count in counts {
                    list_start.push(list_start[list_start.len() - 1] + count as usize);
                }
                list.extend_from_slice(entries);
            }
        }
        s.chunk_lists = chunks;
        s.list_start = list_start;
        s.list = list;
        s.reference.clear();
        s.reference.extend_from_slice(c.position);
        s.builds += 1;
        true
    }

    pub(super) fn build_cells<'a>(&self, c: &Configuration<'_>, s: &'a mut Scratch) -> Option<Cells<'a>> {
        let cutoff = self.cutoff?;
        self.build_cells_of(c, s, cutoff)
    }

    /// A cell list whose stencil reaches every body within `cutoff`.
    pub(super) fn build_cells_of<'a>(
        &self,
        c: &Configuration<'_>,
        s: &'a mut Scratch,
        cutoff: f64,
    ) -> Option<Cells<'a>> {
        let n_bodies = c.position.len();
        let (origin, extent, periodic) = match self.box_length {
            Some(l) => (Vec3::ZERO, Vec3::new(l, l, l), true),
            None => {
                let mut lo = Vec3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
                let mut hi = -lo;
                for p in c.position {
                    lo = Vec3::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z));
                    hi = Vec3::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z));
                }
                (lo, hi - lo, false)
            }
        };
        // Cells at least half the cutoff wide with a stencil of 5 a side (in a periodic box
        // at least 5 cells a side), else at least the cutoff wide with a stencil of 3; at
        // most 64 a side. The finer cells cover a smaller volume: at 10³ bodies (box 14.9,
        // reach 3.3) 125 of 9³ cells instead of 27 of 4³, 2.5 times fewer candidates.
        let (size, reach) = if periodic {
            let fine = (2.0 * extent.x / cutoff).floor() as usize;
            let coarse = (extent.x / cutoff).floor() as usize;
            if fine >= 5 {
                (extent.x / fine.min(64) as f64, 2)
            } else if coarse >= 3 {
                (extent.x / coarse.min(64) as f64, 1)
            } else {
                return None;
            }
        } else {
            ((0.5 * cutoff).max(extent.max_abs() / 64.0), 2)
        };
        let count = |e: f64| ((e / size).floor() as usize).clamp(1, 64);
        let n = if periodic {
            let k = (extent.x / size).round() as usize;
            [k, k, k]
        } else {
            [count(extent.x), count(extent.y), count(extent.z)]
        };
        let ncells = n[0] * n[1] * n[2];
        let cell = |p: Vec3| {
            let q = p - origin;
            let idx = |v: f64, k: usize| {
                let v = if periodic {
                    v - (v / (k as f64 * size)).floor() * (k as f64 * size)
                } else {
                    v
                };
                ((v / size) as usize).min(k - 1)
            };
            (idx(q.z, n[2]) * n[1] + idx(q.y, n[1])) * n[0] + idx(q.x, n[0])
        };
        s.cell_of.clear();
        s.cell_of.extend(c.position.iter().map(|&p| cell(p)));
        s.cell_start.clear();
        s.cell_start.resize(ncells + 1, 0);
        for &k in &s.cell_of {
            s.cell_start[k + 1] += 1;
        }
        for k in 0..ncells {
            s.cell_start[k + 1] += s.cell_start[k];
        }
        s.sorted.clear();
        s.sorted.resize(n_bodies, 0);
        s.fill.clear();
        s.fill.extend_from_slice(&s.cell_start);
        for (i, &k) in s.cell_of.iter().enumerate() {
            s.sorted[s.fill[k]] = i;
            s.fill[k] += 1;
        }
        s.cell_rank.clear();
        s.cell_rank.resize(n_bodies, 0);
        for (k, &i) in s.sorted.iter().enumerate() {
            s.cell_rank[i] = k as u32;
        }
        let span = n[0] as f64 * size;
        s.wrapped.clear();
        s.wrapped.extend(s.sorted.iter().map(|&i| {
            let p = c.position[i];
            if periodic {
                let wrap = |v: f64| v - (v / span).floor() * span;
                Vec3::new(wrap(p.x), wrap(p.y), wrap(p.z))
            } else {
                p
            }
        }));
        Some(Cells {
            n,
            origin,
            size,
            reach,
            periodic,
            span,
            wrapped: &s.wrapped,
            cell_rank: &s.cell_rank,
            start: &s.cell_start,
            sorted: &s.sorted,
        })
    }

    /// The neighbours `j ≠ i` of body `i` within `reach` by the test and in the order of
    /// the full Verlet list's build ([`Dipoles::update_list`] with `half = false`): the
    /// stencil's cells in (z, y, x) order of their offsets, the bodies of a cell in index
    /// order, each candidate against its image in the stencil cell (or by minimum image in a
    /// box shorter than twice the reach). A domain's list ([`super::domain`]) is built with
    /// it over the bodies it holds, indexed in the order of their identities, so that each
    /// of its bodies gets the same neighbours in the same order as in the whole system.
    pub(super) fn for_listed(
        &self,
        i: usize,
        c: &Configuration<'_>,
        cells: &Cells<'_>,
        reach: f64,
        mut f: impl FnMut(usize),
    ) {
        let reach2 = reach * reach;
        let constants = self.constants();
        let images = (!cells.periodic || cells.span >= 2.0 * reach).then_some((cells.wrapped, cells.cell_rank));
        let xi = c.position[i];
        let xi_wrapped = images.map_or(Vec3::ZERO, |(w, cell_rank)| w[cell_rank[i] as usize]);
        self.for_neighbour_runs(i, c, Some(cells), false, |run, first, offset| match images {
            Some((w, _)) => {
                for (&j, wj) in run.iter().zip(&w[first..first + run.len()]) {
                    if (xi_wrapped - (*wj + offset)).norm_squared() <= reach2 && j != i {
                        f(j);
                    }
                }
            }
            None => {
                for &j in run {
                    if Self::separation(&constants, xi, c.position[j]).norm_squared() <= reach2 && j != i {
                        f(j);
                    }
                }
            }
        });
    }

    /// Visit the neighbours `j ≠ i` of `i` in a fixed order.
    pub(super) fn for_neighbours(
        &self,
        i: usize,
        c: &Configuration<'_>,
        cells: Option<&Cells<'_>>,
        mut f: impl FnMut(usize),
    ) {
        self.for_neighbour_runs(i, c, cells, false, |run, _, _| {
            for &j in run {
                if j != i {
                    f(j);
                }
            }
        });
    }

    /// Visit the candidate neighbours of `i` as runs of bodies, in a fixed order: the bodies
    /// of the stencil's cells (all bodies without a cell list), `i` among them unless
    /// `half`, each run with where it starts in cell order (in [`Cells::sorted`] and
    /// [`Cells::wrapped`]; the first body's index without a cell list) and the offset of its
    /// image (zero without a cell list).
    ///
    /// With `half`, the half stencil, which finds each pair once: the cells ahead of `i`'s
    /// cell in (z, y, x) order among the stencil's offsets (`dz > 0`; `dz = 0, dy > 0`;
    /// `dz = dy = 0, dx > 0`) and, in its own cell, the bodies after it in cell order
    /// (without a cell list, the bodies after it). A pair is then kept by one of its bodies,
    /// the one the other lies ahead of, and each body keeps about half its pairs (LAMMPS's
    /// half list with Newton's third law, `newton on`). Every offset of the stencil is a
    /// different cell (at least `2w + 1` cells a side in a periodic box), so each pair is
    /// seen from exactly one side.
    #[inline(always)]
    fn for_neighbour_runs(
        &self,
        i: usize,
        c: &Configuration<'_>,
        cells: Option<&Cells<'_>>,
        half: bool,
        mut f: impl FnMut(&[usize], usize, Vec3),
    ) {
        let Some(cells) = cells else {
            let mut run = [0usize; 64];
            let from = if half { i + 1 } else { 0 };
            for first in (from..c.position.len()).step_by(run.len()) {
                let len = run.len().min(c.position.len() - first);
                for (k, r) in run[..len].iter_mut().enumerate() {
                    *r = first + k;
                }
                f(&run[..len], first, Vec3::ZERO);
            }
            return;
        };
        let q = c.position[i] - cells.origin;
        let n = cells.n;
        let home = |v: f64, k: usize| {
            let span = k as f64 * cells.size;
            let v = if cells.periodic {
                v - (v / span).floor() * span
            } else {
                v
            };
            ((v / cells.size) as isize).min(k as isize - 1)
        };
        let (cx, cy, cz) = (home(q.x, n[0]), home(q.y, n[1]), home(q.z, n[2]));
        // The stencil's cells along each axis, wrapped once (a periodic box has at least
        // 2w + 1 cells a side) or dropped at an open boundary: computed once per body, not
        // once per cell (`rem_euclid` per cell cost 10 ns per candidate at 10³ bodies).
        let w = cells.reach;
        let axis = |c: isize, k: usize| {
            let k = k as isize;
            // (cell, image offset in boxes, offset in cells) for each stencil cell.
            let mut out = [(0usize, 0.0f64, 0isize); 5];
            let mut len = 0;
            for d in -w..=w {
                let v = c + d;
                let (v, image) = if cells.periodic {
                    if v < 0 {
                        (v + k, -1.0)
                    } else if v >= k {
                        (v - k, 1.0)
                    } else {
                        (v, 0.0)
                    }
                } else if v < 0 || v >= k {
                    continue;
                } else {
                    (v, 0.0)
                };
                out[len] = (v as usize, image, d);
                len += 1;
            }
            (out, len)
        };
        let ((xs, nx), (ys, ny), (zs, nz)) = (axis(cx, n[0]), axis(cy, n[1]), axis(cz, n[2]));
        // Cells of a row that follow each other in x are contiguous in `sorted`: visit the
        // stencil's x cells of a row as at most two runs (two where the box wraps), in the
        // same order as cell by cell, without a loop exit per cell. `ahead` are the runs of
        // the cells from `i`'s own on (`dx ≥ 0`), for the half stencil's own row.
        let merge = |from: isize| {
            let mut runs = [(0usize, 0usize, 0.0f64); 2];
            let mut n_runs = 0;
            for &(x, image, d) in &xs[..nx] {
                if d < from {
                    continue;
                }
                if n_runs > 0 && runs[n_runs - 1].1 == x {
                    runs[n_runs - 1].1 = x + 1;
                } else {
                    runs[n_runs] = (x, x + 1, image);
                    n_runs += 1;
                }
            }
            (runs, n_runs)
        };
        let (all, n_all) = merge(-w);
        // (Only the half stencil visits them.)
        let (ahead, n_ahead) = if half { merge(0) } else { (all, 0) };
        // `i`'s entry in cell order: its own row's first run starts after it.
        let own = cells.cell_rank[i] as usize;
        let span = cells.span;
        for &(z, oz, dz) in &zs[..nz] {
            if half && dz < 0 {
                continue;
            }
            for &(y, oy, dy) in &ys[..ny] {
                if half && dz == 0 && dy < 0 {
                    continue;
                }
                let own_row = half && dz == 0 && dy == 0;
                let row = (z * n[1] + y) * n[0];
                let runs = if own_row { &ahead[..n_ahead] } else { &all[..n_all] };
                for (r, &(lo, hi, ox)) in runs.iter().enumerate() {
                    let offset = Vec3::new(ox * span, oy * span, oz * span);
                    let (mut a, b) = (cells.start[row + lo], cells.start[row + hi]);
                    if own_row && r == 0 {
                        // The run starts at `i`'s own cell: the bodies after `i` in it.
                        a = own + 1;
                    }
                    f(&cells.sorted[a..b], a, offset);
                }
            }
        }
    }
}
