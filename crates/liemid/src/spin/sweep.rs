//! Parallel sweeps over sites and over the bonds of one colour, with results independent
//! of the thread count: every output element is computed from shared inputs alone, and the
//! only reduction (a maximum) does not depend on the order.

use crate::linalg::Vec3;
pub(crate) use crate::team::{Part, SpinBarrier};

/// Sites per parallel work item.
pub const CHUNK: usize = 1024;

/// `out[i] = f(i)` for every site.
pub(crate) fn map_sites(out: &mut [Vec3], f: impl Fn(usize) -> Vec3 + Sync + Send) {
    #[cfg(feature = "parallel")]
    if out.len() > CHUNK {
        use rayon::prelude::*;
        out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, chunk)| {
            for (k, o) in chunk.iter_mut().enumerate() {
                *o = f(c * CHUNK + k);
            }
        });
        return;
    }
    for (i, o) in out.iter_mut().enumerate() {
        *o = f(i);
    }
}

/// `out[i] = f(i)` for every site, returning `max_i g(i, out[i])`.
pub(crate) fn map_sites_max(
    out: &mut [Vec3],
    f: impl Fn(usize) -> Vec3 + Sync + Send,
    g: impl Fn(usize, Vec3) -> f64 + Sync + Send,
) -> f64 {
    let run = |start: usize, chunk: &mut [Vec3]| {
        let mut worst = 0.0f64;
        for (k, o) in chunk.iter_mut().enumerate() {
            *o = f(start + k);
            worst = worst.max(g(start + k, *o));
        }
        worst
    };
    #[cfg(feature = "parallel")]
    if out.len() > CHUNK {
        use rayon::prelude::*;
        return out
            .par_chunks_mut(CHUNK)
            .enumerate()
            .map(|(c, chunk)| run(c * CHUNK, chunk))
            .reduce(|| 0.0, f64::max);
    }
    run(0, out)
}

/// `s[i] ← f(s[i])` for every site.
pub(crate) fn update_sites(spins: &mut [Vec3], f: impl Fn(usize, Vec3) -> Vec3 + Sync + Send) {
    #[cfg(feature = "parallel")]
    if spins.len() > CHUNK {
        use rayon::prelude::*;
        spins.par_chunks_mut(CHUNK).enumerate().for_each(|(c, chunk)| {
            for (k, s) in chunk.iter_mut().enumerate() {
                *s = f(c * CHUNK + k, *s);
            }
        });
        return;
    }
    for (i, s) in spins.iter_mut().enumerate() {
        *s = f(i, *s);
    }
}

/// A pointer to the spins shared by the workers of one sweep.
#[derive(Clone, Copy)]
pub(crate) struct Shared(*mut Vec3, usize);
// SAFETY: used only through `Shared::update_bond_range` and `Shared::update_site_range`,
// whose callers give each worker disjoint bonds of a matching
// or disjoint sites, so no two workers read or write the same element in one sweep, and
// sweeps are separated by a barrier.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

impl Shared {
    /// The spins, shared.
    pub(crate) fn new(spins: &mut [Vec3]) -> Self {
        Shared(spins.as_mut_ptr(), spins.len())
    }

    /// The pointer and the length (for the lane kernels, under the same contract).
    #[cfg_attr(not(all(feature = "simd", target_arch = "x86_64")), allow(dead_code))]
    pub(crate) fn raw(&self) -> (*mut Vec3, usize) {
        (self.0, self.1)
    }

    /// `(s[i], s[j]) ← f(s[i], s[j])` for the bonds of a matching.
    ///
    /// # Safety
    /// No other thread may touch these bonds' sites until the next barrier, and the
    /// spins must outlive the call.
    #[inline]
    pub(crate) unsafe fn update_bond_range(&self, bonds: &[[u32; 2]], f: &impl Fn(Vec3, Vec3) -> (Vec3, Vec3)) {
        for b in bonds {
            let (i, j) = (b[0] as usize, b[1] as usize);
            assert!(i < self.1 && j < self.1 && i != j);
            // SAFETY: in bounds (checked), distinct, and owned by this worker (the caller's
            // contract).
            unsafe {
                let (a, c) = f(*self.0.add(i), *self.0.add(j));
                *self.0.add(i) = a;
                *self.0.add(j) = c;
            }
        }
    }

    /// `(s[i], s[j]) ← f(base + k, s[i], s[j])` for the `k`-th bond of a matching, which
    /// is bond `base + k` of the lattice.
    ///
    /// # Safety
    /// As for [`Shared::update_bond_range`].
    #[inline]
    pub(crate) unsafe fn update_bond_range_indexed(
        &self,
        bonds: &[[u32; 2]],
        base: usize,
        f: &impl Fn(usize, Vec3, Vec3) -> (Vec3, Vec3),
    ) {
        for (k, b) in bonds.iter().enumerate() {
            let (i, j) = (b[0] as usize, b[1] as usize);
            assert!(i < self.1 && j < self.1 && i != j);
            // SAFETY: in bounds (checked), distinct, and owned by this worker (the caller's
            // contract).
            unsafe {
                let (a, c) = f(base + k, *self.0.add(i), *self.0.add(j));
                *self.0.add(i) = a;
                *self.0.add(j) = c;
            }
        }
    }

    /// `s[i] ← f(s[i])` for `i` in `range`.
    ///
    /// # Safety
    /// As for [`Shared::update_bond_range`], for these sites.
    #[inline]
    pub(crate) unsafe fn update_site_range(&self, range: std::ops::Range<usize>, f: &impl Fn(Vec3) -> Vec3) {
        assert!(range.end <= self.1);
        for i in range {
            // SAFETY: in bounds (checked) and owned by this worker.
            unsafe { *self.0.add(i) = f(*self.0.add(i)) };
        }
    }
}

/// Sites below which a team is one thread (the barriers would cost more than they save).
#[cfg_attr(not(feature = "parallel"), allow(dead_code))]
pub const TEAM_SITES: usize = 2048;

/// [`crate::team::run`] for a sweep over `sites` sites: one thread below [`TEAM_SITES`].
pub(crate) fn team(sites: usize, work: impl Fn(Part, &SpinBarrier) + Sync) {
    crate::team::run(sites >= TEAM_SITES, work);
}
