//! Parallel sweeps over sites and over the bonds of one colour, with results independent
//! of the thread count: every output element is computed from shared inputs alone, and the
//! only reduction (a maximum) does not depend on the order.

use crate::linalg::Vec3;

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

/// A pointer to the spins shared by the workers of one bond colour.
#[derive(Clone, Copy)]
struct Shared(*mut Vec3);
// SAFETY: used only by `update_bonds`, whose bonds form a matching: no two bonds touch the
// same site, so no two workers read or write the same element.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

/// `(s[i], s[j]) ← f(s[i], s[j])` for every bond `[i, j]` of a matching (no two bonds share
/// a site, which [`super::Lattice`] guarantees for each colour).
pub(crate) fn update_bonds(
    bonds: &[[u32; 2]],
    spins: &mut [Vec3],
    f: impl Fn(Vec3, Vec3) -> (Vec3, Vec3) + Sync + Send,
) {
    let n = spins.len();
    let shared = Shared(spins.as_mut_ptr());
    let run = move |chunk: &[[u32; 2]]| {
        let ptr = shared;
        for b in chunk {
            let (i, j) = (b[0] as usize, b[1] as usize);
            assert!(i < n && j < n && i != j);
            // SAFETY: i and j are in bounds (checked) and distinct, and no other bond of
            // the matching touches them, so these are the only accesses to the two
            // elements while the sweep runs.
            unsafe {
                let (a, c) = f(*ptr.0.add(i), *ptr.0.add(j));
                *ptr.0.add(i) = a;
                *ptr.0.add(j) = c;
            }
        }
    };
    #[cfg(feature = "parallel")]
    if bonds.len() > CHUNK {
        use rayon::prelude::*;
        bonds.par_chunks(CHUNK).for_each(run);
        return;
    }
    run(bonds);
}
