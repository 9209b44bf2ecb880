//! The implicit midpoint rule for spins in Lie form: each spin turns by the Cayley rotation
//! of the angular velocity at the midpoint,
//!
//! ```text
//! S_{n+1,i} = cay(h Ω_i(S_mid)) S_{n,i},  S_mid = (S_n + S_{n+1})/2,
//! cay(w) x = x + 4/(4 + |w|²) (w × x + w × (w × x)/2),
//! ```
//!
//! which is exactly the implicit midpoint rule `S_{n+1} − S_n = h Ω(S_mid) × S_mid` (the
//! Cayley map is the midpoint rule of `x' = w × x`). Second order, symmetric; not
//! symplectic on the product of spheres (the area-form defect of one step is `O(h³)`,
//! measured by `tests/spin/poisson.rs`; the spherical midpoint method of McLachlan, Modin
//! and Verdier would be); it keeps every `|S_i|`, and, being the midpoint rule, every quadratic and linear first
//! integral: undamped, the energy of this quadratic Hamiltonian and `Σ S_z` (with `n` and
//! `B` along `z`) to the solver's tolerance. With damping, the energy falls at every step:
//! `E_{n+1} − E_n = −h μ_s μ_B γ α/(1+α²) Σ_i |S_mid,i × B_i(S_mid)|² ≤ 0`. Solved by
//! fixed-point iteration from an explicit predictor, to round-off. (With `exp` in place of
//! `cay` the map is no longer the midpoint rule and keeps neither the energy nor `Σ S_z`
//! exactly.)
//!
//! References: D. Lewis, N. Nigam, *Geometric integration on spheres and some interesting
//! applications*, J. Comput. Appl. Math. 151 (2003); J. H. Mentink et al., J. Phys.:
//! Condens. Matter 22, 176001 (2010) (SIB, a semi-implicit approximation of this rule).

use super::hamiltonian::SpinSystem;
use super::sweep::{map_sites, map_sites_max};
use crate::error::{Error, Result};
use crate::linalg::Vec3;

/// Iterations before the solve is declared failed.
pub const MAX_ITERATIONS: usize = 100;

/// `cay(w) x`.
#[inline(always)]
fn cayley(w: Vec3, x: Vec3) -> Vec3 {
    let wx = w.cross(x);
    x + (wx + w.cross(wx) * 0.5) * (4.0 / (4.0 + w.norm_squared()))
}

/// One midpoint step; `start`, `mid` and `next` are scratch of the spins' length. Returns
/// the number of fixed-point iterations.
pub(crate) fn step(
    system: &SpinSystem,
    spins: &mut [Vec3],
    h: f64,
    t: f64,
    start: &mut Vec<Vec3>,
    mid: &mut Vec<Vec3>,
    next: &mut Vec<Vec3>,
) -> Result<usize> {
    let rates = system.rates();
    let lattice = &system.lattice;
    start.clear();
    start.extend_from_slice(spins);
    mid.resize(spins.len(), Vec3::ZERO);
    next.resize(spins.len(), Vec3::ZERO);
    // Predictor: the explicit rotation by h Ω(S_n); the iterate lives in `spins`.
    {
        let s0: &[Vec3] = start;
        map_sites(next, |i| cayley(rates.omega(lattice, s0, i) * h, s0[i]));
    }
    spins.copy_from_slice(next);
    let mut last_change = f64::INFINITY;
    let mut stalled = 0;
    for iteration in 1..=MAX_ITERATIONS {
        {
            let (s0, s1): (&[Vec3], &[Vec3]) = (start, spins);
            map_sites(mid, |i| (s0[i] + s1[i]) * 0.5);
        }
        let change = {
            let (s0, m, s1): (&[Vec3], &[Vec3], &[Vec3]) = (start, mid, spins);
            map_sites_max(
                next,
                |i| cayley(rates.omega(lattice, m, i) * h, s0[i]),
                |i, s| (s - s1[i]).max_abs(),
            )
        };
        spins.copy_from_slice(next);
        if !change.is_finite() {
            break;
        }
        // Converged at round-off (2 ulps of a unit spin), or stalled there.
        if change <= 4.0 * f64::EPSILON {
            return Ok(iteration);
        }
        if change >= last_change && change < 1e-12 {
            stalled += 1;
            if stalled >= 3 {
                return Ok(iteration);
            }
        }
        last_change = change;
    }
    spins.copy_from_slice(start);
    Err(Error::NewtonDidNotConverge {
        method: "spin midpoint",
        equation: "the fixed point of the midpoint rule",
        t,
        h,
        residual: last_change,
        iterations: MAX_ITERATIONS as u32,
    })
}
