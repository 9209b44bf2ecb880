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
//! With Gilbert damping the same schedule composes the exact damped flows of the same parts
//! (`spin::damped`): each is still an exact flow, so the Strang step stays symmetric and
//! second order and its compositions reach 4, 6, 8; it is no longer a Poisson map.
//!
//! References: J. Frank, W. Huang, B. Leimkuhler, *Geometric integrators for classical spin
//! systems*, J. Comput. Phys. 133 (1997); R. I. McLachlan, K. Modin, O. Verdier,
//! *Symplectic integrators for spin systems*, Phys. Rev. E 89 (2014).

use super::damped::{self, DampedRates};
use super::dmi::DmiStep;
use super::dmi::{self, DmiBond, DmiShape};
use super::hamiltonian::{Rates, SpinSystem};
use super::lanes::sinc_cos;
use super::lanes::{bond_flow, rodrigues_series, site_flow, unit, SERIES_LIMIT};
use super::pieces::{DampedPiece, Kernel, Piece};
use super::sweep::{team, Shared};
use crate::linalg::Vec3;
use crate::so3::rodrigues;

/// `exp(v) x` with Rodrigues' coefficients `(a, b)` of `|v|²`.
#[inline(always)]
fn turn(v: Vec3, a: f64, b: f64, x: Vec3) -> Vec3 {
    let vx = v.cross(x);
    x + vx * a + v.cross(vx) * b
}

/// The exact flow of the on-site terms of one spin over `h`.
#[inline(always)]
fn onsite_turn(rates: &Rates, commute: bool, s: Vec3, h: f64) -> Vec3 {
    let (axis, k, b) = (rates.axis, rates.anisotropy, rates.field);
    if commute {
        site_flow(axis.into(), k, b.into(), h, s.into(), |t| {
            if t < SERIES_LIMIT {
                rodrigues_series(t)
            } else {
                rodrigues(t)
            }
        })
        .into()
    } else {
        let half = b * (0.5 * h);
        let (za, zb) = rodrigues(half.norm_squared());
        let s = turn(half, za, zb, s);
        let v = axis * (k * s.dot(axis) * h);
        let (ca, cb) = rodrigues(v.norm_squared());
        turn(half, za, zb, turn(v, ca, cb, s))
    }
}

/// The exact flow of one bond over `h` ([`bond_flow`] on the scalar path).
#[inline(always)]
fn bond_turn(rate: f64, si: Vec3, sj: Vec3, h: f64) -> (Vec3, Vec3) {
    let (a, b) = bond_flow(rate * h, si.into(), sj.into(), sinc_cos);
    (a.into(), b.into())
}

/// `s (3 − |s|²)/2`: one Newton step towards `|s| = 1`, which removes the rounding the
/// rotations leave in `|s|` (about an ulp per rotation, a random walk that reached
/// 1.5e-13 over 10⁵ steps of the 64×64 lattice without it) to second order, with no
/// square root or division. Applied once per step.
#[inline(always)]
fn renormalize(s: Vec3) -> Vec3 {
    unit(s.into()).into()
}

/// Whether the bond sweeps can run in AVX lanes here.
fn avx_available() -> bool {
    #[cfg(all(feature = "simd", target_arch = "x86_64"))]
    {
        super::avx::use_avx()
    }
    #[cfg(not(all(feature = "simd", target_arch = "x86_64")))]
    {
        false
    }
}

/// One pass over the spins.
enum Sweep<'p> {
    /// The on-site flow of every spin over this time.
    Site(f64),
    /// The flow of the bonds of a colour over this time.
    Colour(usize, f64),
    /// Pieces applied in turn to each bond of colour 0 (a perfect matching).
    Fused(&'p [Piece]),
    /// [`renormalize`] every spin (the end of a step).
    Unit,
}

/// The sweeps of `Φ_{γ_{s−1} h} ∘ … ∘ Φ_{γ_0 h}` (Strang steps), in order.
///
/// Within a step, with `merge` (the on-site flow is exact: anisotropy and field commute),
/// the closing on-site half flow of one stage and the opening one of the next are one flow, `site(τ_k/2) ∘ site(τ_{k+1}/2) = site((τ_k + τ_{k+1})/2)` (the exact
/// flow of one term is a one-parameter group), so a composition of `s` stages sweeps the
/// on-site terms `s + 1` times rather than `2s`. Between steps they stay apart (the
/// renormalisation sits between them), so `k` single steps and one `advance` of `k` steps
/// are the same bits.
///
/// With `perfect` (colour 0 covers every site: every periodic lattice of even sizes, and
/// open ones with an even count along the first axis), the on-site flows next to colour 0,
/// and the two colour-0 sweeps where one stage ends and the next begins, become one fused
/// sweep: per spin the same operations in the same order, so bit for bit the same result,
/// with fewer passes over memory and fewer barriers between threads.
fn schedule(
    m: usize,
    perfect: bool,
    merge: bool,
    h: f64,
    gammas: impl Iterator<Item = (f64, bool)>,
    mut emit: impl FnMut(Sweep<'_>),
) {
    let mut stages = gammas.map(|(g, last)| (g * h, last)).peekable();
    // The on-site time that joins the next stage's opening half flow (a stage that ended
    // inside a step left it).
    let merged = |tau: f64, next: f64| 0.5 * tau + 0.5 * next;
    if !perfect {
        let mut opening: Option<f64> = None;
        while let Some((tau, last)) = stages.next() {
            emit(Sweep::Site(opening.take().unwrap_or(0.5 * tau)));
            if m > 0 {
                for c in 0..m - 1 {
                    emit(Sweep::Colour(c, 0.5 * tau));
                }
                emit(Sweep::Colour(m - 1, tau));
                for c in (0..m - 1).rev() {
                    emit(Sweep::Colour(c, 0.5 * tau));
                }
            }
            match stages.peek() {
                Some(&(next, _)) if merge && !last => opening = Some(merged(tau, next)),
                _ => {
                    emit(Sweep::Site(0.5 * tau));
                    if last {
                        emit(Sweep::Unit);
                    }
                }
            }
        }
        return;
    }
    // The closing on-site flow of the previous stage (and whether it ended a step), not
    // yet swept.
    let mut carried: Option<(f64, bool)> = None;
    while let Some((tau, last)) = stages.next() {
        let next = stages.peek().map(|&(t, _)| t);
        if m == 1 {
            // O(τ/2) B(τ) O(τ/2); the closing half joins the next stage's sweep.
            let mut pieces = [Piece::Unit; 6];
            let mut k = 0;
            let mut push = |p: Piece| {
                pieces[k] = p;
                k += 1;
            };
            match carried.take() {
                // Already the merged time.
                Some((c, false)) if merge => push(Piece::Site(c)),
                Some((c, ended)) => {
                    push(Piece::Site(c));
                    if ended {
                        push(Piece::Unit);
                    }
                    push(Piece::Site(0.5 * tau));
                }
                None => push(Piece::Site(0.5 * tau)),
            }
            push(Piece::Bond(tau));
            match next {
                None => {
                    push(Piece::Site(0.5 * tau));
                    if last {
                        push(Piece::Unit);
                    }
                }
                Some(t) if merge && !last => carried = Some((merged(tau, t), false)),
                Some(_) => carried = Some((0.5 * tau, last)),
            }
            emit(Sweep::Fused(&pieces[..k]));
            continue;
        }
        if carried.is_none() {
            emit(Sweep::Fused(&[Piece::Site(0.5 * tau), Piece::Bond(0.5 * tau)]));
        }
        for c in 1..m - 1 {
            emit(Sweep::Colour(c, 0.5 * tau));
        }
        emit(Sweep::Colour(m - 1, tau));
        for c in (1..m - 1).rev() {
            emit(Sweep::Colour(c, 0.5 * tau));
        }
        let closing = Piece::Bond(0.5 * tau);
        match (next, last) {
            (Some(t), false) if merge => {
                emit(Sweep::Fused(&[
                    closing,
                    Piece::Site(merged(tau, t)),
                    Piece::Bond(0.5 * t),
                ]));
                carried = Some((0.5 * t, false));
            }
            (Some(t), false) => {
                emit(Sweep::Fused(&[
                    closing,
                    Piece::Site(0.5 * tau),
                    Piece::Site(0.5 * t),
                    Piece::Bond(0.5 * t),
                ]));
                carried = Some((0.5 * t, false));
            }
            (Some(t), true) => {
                emit(Sweep::Fused(&[
                    closing,
                    Piece::Site(0.5 * tau),
                    Piece::Unit,
                    Piece::Site(0.5 * t),
                    Piece::Bond(0.5 * t),
                ]));
                carried = Some((0.5 * t, false));
            }
            (None, false) => emit(Sweep::Fused(&[closing, Piece::Site(0.5 * tau)])),
            (None, true) => emit(Sweep::Fused(&[closing, Piece::Site(0.5 * tau), Piece::Unit])),
        }
    }
}

/// The composition `Φ_{γ_{s−1} h} ∘ … ∘ Φ_{γ_0 h}` of Strang steps (one step of `h` for
/// `gammas = [1]`), by a team of the pool's threads that split every sweep into fixed
/// contiguous shares and meet at a barrier after each. `gammas` yields each stage's
/// fraction of `h` and whether it ends a step (after which every spin is renormalised).
pub(crate) fn composed(
    system: &SpinSystem,
    spins: &mut [Vec3],
    h: f64,
    gammas: impl Iterator<Item = (f64, bool)> + Clone + Sync,
) {
    run(system, spins, h, gammas, true);
}

fn run(
    system: &SpinSystem,
    spins: &mut [Vec3],
    h: f64,
    gammas: impl Iterator<Item = (f64, bool)> + Clone + Sync,
    fuse: bool,
) {
    let rates = system.rates();
    // With damping every part's flow is the damped one (`damped`), on the scalar path.
    let damped = (rates.damping != 0.0).then(|| DampedRates::new(&rates));
    let commute = system.onsite_commutes();
    let lattice = &system.lattice;
    let m = lattice.colours();
    let n = spins.len();
    let perfect = fuse && m > 0 && 2 * lattice.colour(0).len() == n;
    let onsite_terms = !(rates.anisotropy == 0.0 && rates.field == Vec3::ZERO);
    let rate = rates.exchange;
    let rates = &rates;
    let kernel = Kernel {
        rate,
        axis: rates.axis,
        field: rates.field,
        anisotropy: rates.anisotropy,
        onsite_terms,
    };
    // Four bonds at a time in AVX lanes (the same bits), where the processor has AVX and
    // the on-site flow is one rotation; the unfused path (for tests) stays scalar.
    // Bonds with DMI run on their own path (`dmi`); without DMI the paths are unchanged.
    let dmi_vectors = system.dmi_bonds();
    let lanes = fuse && (commute || !onsite_terms) && damped.is_none() && dmi_vectors.is_none() && avx_available();
    // The damped flows run in lanes too (they have no branch on the terms' directions).
    let damped_lanes = fuse && damped.is_some() && dmi_vectors.is_none() && avx_available();
    let _ = damped_lanes;
    // Adjacent on-site half flows join only where the on-site flow is exact (one rotation);
    // a Strang-split field and anisotropy is not a one-parameter group (with damping, not
    // even for a field along the axis).
    let merge = match &damped {
        Some(d) => d.onsite_is_group(),
        None => commute || !onsite_terms,
    };
    let (exchange, k_dmi, alpha) = (system.exchange, rates.per_moment * rates.damping_factor, rates.damping);
    // Bonds of one |D| share their constants; undamped, they run in lanes under the same
    // conditions as the bonds without DMI.
    let dmi_shape = dmi_vectors
        .and_then(|d| d.uniform)
        .map(|dn| DmiShape::new(dn, exchange, k_dmi));
    let dmi_lanes = fuse && dmi_shape.is_some() && damped.is_none() && (commute || !onsite_terms) && avx_available();
    let _ = dmi_lanes;
    // `bonds` starts at index `base` of the lattice's bonds.
    let bond_sweep = |shared: &Shared, bonds: &[[u32; 2]], base: usize, pieces: &[Piece]| {
        if let Some(db) = dmi_vectors {
            // The damped on-site constants and the DMI bond constants once per sweep.
            let mut sites: [Option<damped::SiteStep>; 6] = [None; 6];
            let mut steps: [Option<DmiStep>; 6] = [None; 6];
            for (k, p) in pieces.iter().enumerate() {
                match (*p, &damped, &dmi_shape) {
                    (Piece::Site(t), Some(d), _) => sites[k] = Some(d.site_step(t)),
                    (Piece::Bond(t), None, Some(shape)) => steps[k] = Some(shape.step(t)),
                    _ => {}
                }
            }
            let steps = &steps[..pieces.len()];
            let scalar = |index: usize, mut si: Vec3, mut sj: Vec3| {
                let (unit, norm) = (db.unit[index], db.norm[index]);
                for (k, p) in pieces.iter().enumerate() {
                    match *p {
                        Piece::Site(t) if onsite_terms => match &sites[k] {
                            Some(c) => (si, sj) = (damped::site(c, si), damped::site(c, sj)),
                            None => {
                                si = onsite_turn(rates, commute, si, t);
                                sj = onsite_turn(rates, commute, sj, t);
                            }
                        },
                        Piece::Site(_) => {}
                        Piece::Bond(t) => {
                            (si, sj) = match &damped {
                                None if norm == 0.0 => bond_turn(rate, si, sj, t),
                                Some(d) if norm == 0.0 => damped::bond(&d.bond_step(t), si, sj),
                                None => {
                                    let c = steps[k].unwrap_or_else(|| DmiShape::new(norm, exchange, k_dmi).step(t));
                                    dmi::flow(unit, &c, si, sj)
                                }
                                Some(_) => {
                                    let shape = dmi_shape.unwrap_or_else(|| DmiShape::new(norm, exchange, k_dmi));
                                    dmi::damped_flow(&DmiBond { unit, shape }, alpha, si, sj, t)
                                }
                            }
                        }
                        Piece::Unit => (si, sj) = (renormalize(si), renormalize(sj)),
                    }
                }
                (si, sj)
            };
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            if dmi_lanes {
                let (ptr, len) = shared.raw();
                let units = &db.unit[base..base + bonds.len()];
                // SAFETY: AVX was detected; the pointer and length are the spins'; the bonds
                // are this part's share of a matching, alone until the barrier.
                unsafe { super::avx::sweep_avx_dmi(ptr, len, bonds, base, units, &kernel, pieces, steps, &scalar) };
                return;
            }
            // SAFETY: this part's bonds of a matching, alone until the barrier.
            unsafe { shared.update_bond_range_indexed(bonds, base, &scalar) };
            return;
        }
        if let Some(d) = &damped {
            // Each piece's constants once per sweep, then the damped flows per bond.
            let mut steps = [DampedPiece::Unit; 6];
            for (k, p) in pieces.iter().enumerate() {
                steps[k] = match *p {
                    Piece::Site(t) if onsite_terms => DampedPiece::Site(d.site_step(t)),
                    Piece::Site(_) => DampedPiece::Skip,
                    Piece::Bond(t) => DampedPiece::Bond(d.bond_step(t)),
                    Piece::Unit => DampedPiece::Unit,
                };
            }
            let steps = &steps[..pieces.len()];
            let scalar = |mut si: Vec3, mut sj: Vec3| {
                for p in steps {
                    match p {
                        DampedPiece::Site(c) => (si, sj) = (damped::site(c, si), damped::site(c, sj)),
                        DampedPiece::Skip => {}
                        DampedPiece::Bond(c) => (si, sj) = damped::bond(c, si, sj),
                        DampedPiece::Unit => (si, sj) = (renormalize(si), renormalize(sj)),
                    }
                }
                (si, sj)
            };
            #[cfg(all(feature = "simd", target_arch = "x86_64"))]
            if damped_lanes {
                let (ptr, len) = shared.raw();
                // SAFETY: AVX was detected; the pointer and length are the spins'; the bonds
                // are this part's share of a matching, alone until the barrier.
                unsafe { super::avx::sweep_avx_damped(ptr, len, bonds, steps, &scalar) };
                return;
            }
            // SAFETY: this part's bonds of a matching, alone until the barrier.
            unsafe { shared.update_bond_range(bonds, &scalar) };
            return;
        }
        let scalar = |mut si: Vec3, mut sj: Vec3| {
            for p in pieces {
                match *p {
                    Piece::Site(t) if onsite_terms => {
                        si = onsite_turn(rates, commute, si, t);
                        sj = onsite_turn(rates, commute, sj, t);
                    }
                    Piece::Site(_) => {}
                    Piece::Bond(t) => (si, sj) = bond_turn(rate, si, sj, t),
                    Piece::Unit => (si, sj) = (renormalize(si), renormalize(sj)),
                }
            }
            (si, sj)
        };
        #[cfg(all(feature = "simd", target_arch = "x86_64"))]
        if lanes {
            let (ptr, len) = shared.raw();
            // SAFETY: AVX was detected; the pointer and length are the spins'; the bonds are
            // this part's share of a matching, alone until the barrier.
            unsafe { super::avx::sweep_avx(ptr, len, bonds, &kernel, pieces, &scalar) };
            return;
        }
        let _ = (&kernel, lanes);
        // SAFETY: this part's bonds of a matching, alone until the barrier.
        unsafe { shared.update_bond_range(bonds, &scalar) };
    };
    let shared = Shared::new(spins);
    team(n, |part, barrier| {
        schedule(m, perfect, merge, h, gammas.clone(), |sweep| {
            match sweep {
                Sweep::Site(t) => {
                    if !onsite_terms {
                        return;
                    }
                    if let Some(d) = &damped {
                        let c = d.site_step(t);
                        // SAFETY: this part's sites, alone until the barrier.
                        unsafe { shared.update_site_range(part.range(n), &|s| damped::site(&c, s)) };
                    } else {
                        // SAFETY: this part's sites, alone until the barrier.
                        unsafe { shared.update_site_range(part.range(n), &|s| onsite_turn(rates, commute, s, t)) };
                    }
                }
                Sweep::Unit => {
                    // SAFETY: this part's sites, alone until the barrier.
                    unsafe { shared.update_site_range(part.range(n), &renormalize) };
                }
                Sweep::Colour(c, t) => {
                    let bonds = lattice.colour(c);
                    let range = part.range(bonds.len());
                    let base = lattice.colour_offset(c) + range.start;
                    bond_sweep(&shared, &bonds[range], base, &[Piece::Bond(t)]);
                }
                Sweep::Fused(pieces) => {
                    let bonds = lattice.colour(0);
                    let range = part.range(bonds.len());
                    let base = lattice.colour_offset(0) + range.start;
                    bond_sweep(&shared, &bonds[range], base, pieces);
                }
            }
            barrier.wait();
        });
    });
}

/// Strang steps sweep by sweep, without fusing the on-site flows into the colour-0
/// sweeps (for tests of the fused path).
pub(crate) fn composed_unfused(system: &SpinSystem, spins: &mut [Vec3], h: f64, gammas: &[f64]) {
    let n = gammas.len();
    run(
        system,
        spins,
        h,
        gammas.iter().enumerate().map(|(k, &g)| (g, k + 1 == n)),
        false,
    );
}
