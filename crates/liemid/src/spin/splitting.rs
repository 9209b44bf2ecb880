//! The explicit symplectic splitting of the spin Hamiltonian into exactly solvable parts.
//!
//! `E = Σ_c E_c + E_site`: each colour `c` of the bonds is a matching, so `E_c` is a sum of
//! independent two-spin terms `−J S_i·S_j`, whose flow turns both spins about their
//! constant sum `L = S_i + S_j` by the angle `h γJ|L|/(μ_s μ_B)`; the on-site part turns
//! each spin about `n` at the rate `γ 2K (S·n)/(μ_s μ_B)` (`S·n` is constant) and about `B`
//! at `γ|B|` (one rotation when they commute, Strang-split otherwise). Every part is the
//! exact Hamiltonian flow of its term, so the Strang composition
//!
//! ```text
//! Φ_h = site(h/2) ∘ c₀(h/2) ∘ … ∘ c_{m−2}(h/2) ∘ c_{m−1}(h) ∘ c_{m−2}(h/2) ∘ … ∘ c₀(h/2) ∘ site(h/2)
//! ```
//!
//! is second order, symplectic (a Poisson map of the product of spheres), symmetric, keeps
//! every `|S_i|` and the total spin `Σ S_i` of the exchange exactly (each bond keeps
//! `S_i + S_j`), hence `Σ S_z` when `n` and `B` are along `z`, and has a bounded energy
//! error. Its symmetric compositions (Suzuki, Kahan-Li) reach orders 4, 6 and 8. Colouring
//! bonds rather than sites is what keeps `Σ S`: turning one sublattice about the field of
//! the frozen other (Krech, Bunker and Landau 1998) changes the total spin at every step
//! and is not a Poisson map.
//!
//! References: J. Frank, W. Huang, B. Leimkuhler, *Geometric integrators for classical spin
//! systems*, J. Comput. Phys. 133 (1997); R. I. McLachlan, K. Modin, O. Verdier,
//! *Symplectic integrators for spin systems*, Phys. Rev. E 89 (2014).

use super::hamiltonian::{Rates, SpinSystem};
use super::sweep::{update_bonds, update_sites};
use crate::linalg::Vec3;
use crate::so3::rodrigues;

/// `exp(v) x` with Rodrigues' coefficients `(a, b)` of `|v|²`.
#[inline(always)]
fn turn(v: Vec3, a: f64, b: f64, x: Vec3) -> Vec3 {
    let vx = v.cross(x);
    x + vx * a + v.cross(vx) * b
}

/// The exact flow of the on-site terms over `h`.
pub(crate) fn onsite(rates: &Rates, commute: bool, spins: &mut [Vec3], h: f64) {
    if rates.anisotropy == 0.0 && rates.field == Vec3::ZERO {
        return;
    }
    let (axis, k, b) = (rates.axis, rates.anisotropy, rates.field);
    if commute {
        update_sites(spins, |_, s| {
            let v = (axis * (k * s.dot(axis)) + b) * h;
            let (ca, cb) = rodrigues(v.norm_squared());
            turn(v, ca, cb, s)
        });
    } else {
        let half = b * (0.5 * h);
        let (za, zb) = rodrigues(half.norm_squared());
        update_sites(spins, |_, s| {
            let s = turn(half, za, zb, s);
            let v = axis * (k * s.dot(axis) * h);
            let (ca, cb) = rodrigues(v.norm_squared());
            turn(half, za, zb, turn(v, ca, cb, s))
        });
    }
}

/// The exact flow of the bonds of colour `c` over `h`.
pub(crate) fn bonds(system: &SpinSystem, rates: &Rates, c: usize, spins: &mut [Vec3], h: f64) {
    let rate = rates.exchange * h;
    if rate == 0.0 {
        return;
    }
    update_bonds(system.lattice.colour(c), spins, |si, sj| {
        let v = (si + sj) * rate;
        let (a, b) = rodrigues(v.norm_squared());
        (turn(v, a, b, si), turn(v, a, b, sj))
    });
}

/// One Strang step `Φ_h` (see the module documentation).
pub(crate) fn strang(system: &SpinSystem, spins: &mut [Vec3], h: f64) {
    let rates = system.rates();
    let commute = system.onsite_commutes();
    let m = system.lattice.colours();
    onsite(&rates, commute, spins, 0.5 * h);
    if m > 0 {
        for c in 0..m - 1 {
            bonds(system, &rates, c, spins, 0.5 * h);
        }
        bonds(system, &rates, m - 1, spins, h);
        for c in (0..m - 1).rev() {
            bonds(system, &rates, c, spins, 0.5 * h);
        }
    }
    onsite(&rates, commute, spins, 0.5 * h);
}
