//! The executor of the splitting's bond sweeps in AVX lanes: four bonds at a time, the
//! kernels of `lanes.rs` on `__m256d` registers (the same IEEE operations in the same order
//! as the scalar path, so the same bits), gathering each bond's two spins, applying a
//! sweep's pieces in registers and scattering them back; lane groups outside the inline
//! series' range are redone on the scalar path. Compiled with the `simd` feature on x86-64,
//! used where the processor has AVX.
//!
//! Reference: R. I. McLachlan, K. Modin, O. Verdier, *Symplectic integrators for spin
//! systems*, Phys. Rev. E 89 (2014) (the bond flow); docs/theory/spins.md §2-§3.

use std::arch::x86_64::{
    __m256d, _mm256_add_pd, _mm256_cmp_pd, _mm256_div_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_set1_pd,
    _mm256_set_pd, _mm256_sqrt_pd, _mm256_storeu_pd, _mm256_sub_pd, _CMP_LT_OQ,
};
use std::ops::{Add, Div, Mul, Sub};

use super::damped::SiteStep;
use super::dmi::{coordinate_axis, dmi_bond_flow, AnyAxis, CoordinateAxis, DmiStep, TurnAxis};
use super::lanes::{
    asinh_ratio_series, asinh_ratio_short, bond_flow, damped_anisotropy_flow, damped_bond_flow, damped_zeeman_flow,
    rodrigues_series, sinc_cos_series, sinc_cos_short, site_flow, unit, Real, ASINH_LIMIT, SERIES_LIMIT, V,
};
use super::pieces::{DampedPiece, Kernel, Piece};
use crate::linalg::Vec3;

// SAFETY (every `unsafe` block in this module): the AVX intrinsics are reached only
// from `sweep_avx`, which is `#[target_feature(enable = "avx")]` and called only after
// `use_avx` detected AVX; the helpers are `#[inline(always)]`, so they are compiled
// inside it.

/// Four `f64`, one per bond, in one AVX register.
#[derive(Clone, Copy)]
struct F(__m256d);

impl From<f64> for F {
    #[inline(always)]
    fn from(x: f64) -> F {
        F(unsafe { _mm256_set1_pd(x) })
    }
}
impl Add for F {
    type Output = F;
    #[inline(always)]
    fn add(self, b: F) -> F {
        F(unsafe { _mm256_add_pd(self.0, b.0) })
    }
}
impl Sub for F {
    type Output = F;
    #[inline(always)]
    fn sub(self, b: F) -> F {
        F(unsafe { _mm256_sub_pd(self.0, b.0) })
    }
}
impl Mul for F {
    type Output = F;
    #[inline(always)]
    fn mul(self, b: F) -> F {
        F(unsafe { _mm256_mul_pd(self.0, b.0) })
    }
}
impl Div for F {
    type Output = F;
    #[inline(always)]
    fn div(self, b: F) -> F {
        F(unsafe { _mm256_div_pd(self.0, b.0) })
    }
}
impl Real for F {
    #[inline(always)]
    fn sqrt(self) -> F {
        F(unsafe { _mm256_sqrt_pd(self.0) })
    }
}
impl F {
    /// Whether every lane is below `limit`.
    #[inline(always)]
    fn all_below(self, limit: f64) -> bool {
        unsafe { _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(self.0, _mm256_set1_pd(limit))) == 0b1111 }
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        let mut x = [0.0; 4];
        unsafe { _mm256_storeu_pd(x.as_mut_ptr(), self.0) };
        x
    }
}

/// Four spins, one per lane.
#[inline(always)]
fn gather(s: [Vec3; 4]) -> V<F> {
    unsafe {
        V {
            x: F(_mm256_set_pd(s[3].x, s[2].x, s[1].x, s[0].x)),
            y: F(_mm256_set_pd(s[3].y, s[2].y, s[1].y, s[0].y)),
            z: F(_mm256_set_pd(s[3].z, s[2].z, s[1].z, s[0].z)),
        }
    }
}

#[inline(always)]
fn scatter(v: V<F>) -> [Vec3; 4] {
    let (x, y, z) = (v.x.to_array(), v.y.to_array(), v.z.to_array());
    std::array::from_fn(|k| Vec3::new(x[k], y[k], z[k]))
}

/// Whether [`sweep_avx`] can run here (cached by the standard library).
#[inline]
pub(crate) fn use_avx() -> bool {
    std::is_x86_feature_detected!("avx")
}

/// The pieces applied to four bonds' spins in lanes; `None` when a lane needs the
/// scalar path's longer branches.
#[target_feature(enable = "avx")]
#[inline]
fn group(kernel: &Kernel, pieces: &[Piece], si: [Vec3; 4], sj: [Vec3; 4]) -> Option<([Vec3; 4], [Vec3; 4])> {
    let (mut a, mut b) = (gather(si), gather(sj));
    let (mut site_ok, mut bond_ok) = (true, true);
    let axis = V {
        x: F::from(kernel.axis.x),
        y: F::from(kernel.axis.y),
        z: F::from(kernel.axis.z),
    };
    let field = V {
        x: F::from(kernel.field.x),
        y: F::from(kernel.field.y),
        z: F::from(kernel.field.z),
    };
    let k = F::from(kernel.anisotropy);
    let mut site = |t2: F| {
        site_ok &= t2.all_below(SERIES_LIMIT);
        rodrigues_series(t2)
    };
    for p in pieces {
        match *p {
            Piece::Site(t) if kernel.onsite_terms => {
                a = site_flow(axis, k, field, F::from(t), a, &mut site);
                b = site_flow(axis, k, field, F::from(t), b, &mut site);
            }
            Piece::Site(_) => {}
            Piece::Bond(t) => {
                (a, b) = bond_flow(F::from(kernel.rate * t), a, b, |t2: F| {
                    bond_ok &= t2.all_below(SERIES_LIMIT);
                    sinc_cos_series(t2)
                });
            }
            Piece::Unit => (a, b) = (unit(a), unit(b)),
        }
    }
    (site_ok && bond_ok).then(|| (scatter(a), scatter(b)))
}

/// [`group`] for DMI bonds of one `|D|`: `steps[k]` holds the constants of piece `k`
/// when it is a bond piece, `u` the four bonds' unit vectors.
#[target_feature(enable = "avx")]
#[inline]
fn group_dmi<A: TurnAxis<F>>(
    kernel: &Kernel,
    pieces: &[Piece],
    steps: &[Option<DmiStep>],
    u: A,
    si: [Vec3; 4],
    sj: [Vec3; 4],
) -> Option<([Vec3; 4], [Vec3; 4])> {
    let (mut a, mut b) = (gather(si), gather(sj));
    let (mut site_ok, mut bond_ok) = (true, true);
    let (axis, field) = (splat(kernel.axis), splat(kernel.field));
    let k = F::from(kernel.anisotropy);
    let mut site = |t2: F| {
        site_ok &= t2.all_below(SERIES_LIMIT);
        rodrigues_series(t2)
    };
    for (n, p) in pieces.iter().enumerate() {
        match *p {
            Piece::Site(t) if kernel.onsite_terms => {
                a = site_flow(axis, k, field, F::from(t), a, &mut site);
                b = site_flow(axis, k, field, F::from(t), b, &mut site);
            }
            Piece::Site(_) => {}
            Piece::Bond(_) => {
                let c = steps[n]?;
                let mut ising_ok = true;
                (a, b) = dmi_bond_flow(
                    u,
                    F::from(c.cos),
                    F::from(c.sin),
                    F::from(c.rho_h),
                    F::from(c.ising_half),
                    a,
                    b,
                    |t2: F| {
                        if c.short {
                            sinc_cos_short(t2)
                        } else {
                            ising_ok &= t2.all_below(SERIES_LIMIT);
                            sinc_cos_series(t2)
                        }
                    },
                    |t2: F| {
                        bond_ok &= t2.all_below(SERIES_LIMIT);
                        sinc_cos_series(t2)
                    },
                );
                bond_ok &= ising_ok;
            }
            Piece::Unit => (a, b) = (unit(a), unit(b)),
        }
    }
    (site_ok && bond_ok).then(|| (scatter(a), scatter(b)))
}

/// The loop every lane sweep shares: each group of four bonds gathered, `lanes(at, si,
/// sj)` applied (`at` the group's first position in `bonds`), its result scattered back,
/// or, where it gives `None`, each bond by `scalar(at, si, sj)`; the remainder by
/// `scalar`.
///
/// # Safety
/// As for [`sweep_avx`].
#[inline(always)]
unsafe fn sweep_groups(
    spins: *mut Vec3,
    len: usize,
    bonds: &[[u32; 2]],
    lanes: impl Fn(usize, [Vec3; 4], [Vec3; 4]) -> Option<([Vec3; 4], [Vec3; 4])>,
    scalar: impl Fn(usize, Vec3, Vec3) -> (Vec3, Vec3),
) {
    let mut groups = bonds.chunks_exact(4);
    let mut at = 0;
    for g in &mut groups {
        let idx: [(usize, usize); 4] = std::array::from_fn(|k| (g[k][0] as usize, g[k][1] as usize));
        for &(i, j) in &idx {
            assert!(i < len && j < len && i != j);
        }
        // SAFETY: in bounds (checked), distinct within a bond, and the bonds of a
        // matching are disjoint and owned by this worker (the caller's contract).
        unsafe {
            let si = idx.map(|(i, _)| *spins.add(i));
            let sj = idx.map(|(_, j)| *spins.add(j));
            match lanes(at, si, sj) {
                Some((a, b)) => {
                    for k in 0..4 {
                        *spins.add(idx[k].0) = a[k];
                        *spins.add(idx[k].1) = b[k];
                    }
                }
                None => {
                    for k in 0..4 {
                        let (a, b) = scalar(at + k, si[k], sj[k]);
                        *spins.add(idx[k].0) = a;
                        *spins.add(idx[k].1) = b;
                    }
                }
            }
        }
        at += 4;
    }
    for b in groups.remainder() {
        let (i, j) = (b[0] as usize, b[1] as usize);
        assert!(i < len && j < len && i != j);
        // SAFETY: as above.
        unsafe {
            let (a, c) = scalar(at, *spins.add(i), *spins.add(j));
            *spins.add(i) = a;
            *spins.add(j) = c;
        }
        at += 1;
    }
}

/// [`sweep_avx`] for DMI bonds of one `|D|`: `units[k]` is the unit DMI vector of
/// `bonds[k]`, which is bond `base + k` of the lattice (the index `scalar` takes).
///
/// # Safety
/// As for [`sweep_avx`]; `units` as long as `bonds`.
#[target_feature(enable = "avx")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn sweep_avx_dmi(
    spins: *mut Vec3,
    len: usize,
    bonds: &[[u32; 2]],
    base: usize,
    units: &[Vec3],
    kernel: &Kernel,
    pieces: &[Piece],
    steps: &[Option<DmiStep>],
    scalar: &impl Fn(usize, Vec3, Vec3) -> (Vec3, Vec3),
) {
    assert_eq!(units.len(), bonds.len());
    // SAFETY: the caller's contract, passed on.
    unsafe {
        sweep_groups(
            spins,
            len,
            bonds,
            |at, si, sj| {
                let u: [Vec3; 4] = std::array::from_fn(|k| units[at + k]);
                // One coordinate axis in all four lanes (signs may differ): the turns
                // in its plane, as the scalar path takes them for such a bond.
                let axes = u.map(coordinate_axis);
                let shared = match axes {
                    [Some((k, _)), ..] if axes.iter().all(|a| matches!(a, Some((j, _)) if *j == k)) => Some(k),
                    _ => None,
                };
                let sign = || {
                    let s = axes.map(|a| a.map_or(1.0, |(_, s)| s));
                    F(_mm256_set_pd(s[3], s[2], s[1], s[0]))
                };
                match shared {
                    Some(0) => group_dmi(kernel, pieces, steps, CoordinateAxis::<0, F> { sign: sign() }, si, sj),
                    Some(1) => group_dmi(kernel, pieces, steps, CoordinateAxis::<1, F> { sign: sign() }, si, sj),
                    Some(_) => group_dmi(kernel, pieces, steps, CoordinateAxis::<2, F> { sign: sign() }, si, sj),
                    None => group_dmi(kernel, pieces, steps, AnyAxis(gather(u)), si, sj),
                }
            },
            |at, si, sj| scalar(base + at, si, sj),
        )
    }
}

#[inline(always)]
fn splat(v: Vec3) -> V<F> {
    V {
        x: F::from(v.x),
        y: F::from(v.y),
        z: F::from(v.z),
    }
}

/// The damped on-site flow of four spins (as `spin::damped::site`).
#[target_feature(enable = "avx")]
#[inline]
fn damped_site(c: &SiteStep, s: V<F>, ok: &mut bool) -> V<F> {
    let zeeman = |s: V<F>| match &c.zeeman {
        Some(z) => damped_zeeman_flow(
            splat(z.v),
            F::from(z.a),
            F::from(z.b),
            splat(z.unit),
            F::from(z.tau),
            F::from(z.sech),
            s,
        ),
        None => s,
    };
    let s = if c.anisotropy.is_some() && c.zeeman.is_some() {
        zeeman(s)
    } else {
        s
    };
    let s = match &c.anisotropy {
        Some(k) => {
            let (mut ok_r, mut ok_s) = (true, true);
            let out = damped_anisotropy_flow(
                splat(k.axis),
                F::from(k.eg),
                F::from(k.e2g),
                F::from(k.expm1g),
                F::from(k.f),
                F::from(k.alpha2),
                s,
                |x2: F| {
                    if k.short {
                        return asinh_ratio_short(x2);
                    }
                    ok_r &= x2.all_below(ASINH_LIMIT);
                    asinh_ratio_series(x2)
                },
                |t2: F| {
                    ok_s &= t2.all_below(SERIES_LIMIT);
                    rodrigues_series(t2)
                },
            );
            *ok &= ok_r && ok_s;
            out
        }
        None => s,
    };
    zeeman(s)
}

/// The damped pieces applied to four bonds' spins in lanes; `None` when a lane needs
/// the scalar path's longer branches.
#[target_feature(enable = "avx")]
#[inline]
fn group_damped(pieces: &[DampedPiece], si: [Vec3; 4], sj: [Vec3; 4]) -> Option<([Vec3; 4], [Vec3; 4])> {
    let (mut a, mut b) = (gather(si), gather(sj));
    let mut ok = true;
    for p in pieces {
        match p {
            DampedPiece::Site(c) => {
                a = damped_site(c, a, &mut ok);
                b = damped_site(c, b, &mut ok);
            }
            DampedPiece::Skip => {}
            DampedPiece::Bond(c) => {
                let mut ok_r = true;
                let mut ok_s = true;
                (a, b) = damped_bond_flow(
                    F::from(c.e),
                    F::from(c.e2),
                    F::from(c.big_e),
                    F::from(c.alpha2),
                    a,
                    b,
                    |x2: F| {
                        if c.short {
                            return asinh_ratio_short(x2);
                        }
                        ok_r &= x2.all_below(ASINH_LIMIT);
                        asinh_ratio_series(x2)
                    },
                    |t2: F| {
                        ok_s &= t2.all_below(SERIES_LIMIT);
                        sinc_cos_series(t2)
                    },
                );
                ok &= ok_r && ok_s;
            }
            DampedPiece::Unit => (a, b) = (unit(a), unit(b)),
        }
    }
    ok.then(|| (scatter(a), scatter(b)))
}

/// [`sweep_avx`] for the damped pieces.
///
/// # Safety
/// As for [`sweep_avx`].
#[target_feature(enable = "avx")]
pub(crate) unsafe fn sweep_avx_damped(
    spins: *mut Vec3,
    len: usize,
    bonds: &[[u32; 2]],
    pieces: &[DampedPiece],
    scalar: &impl Fn(Vec3, Vec3) -> (Vec3, Vec3),
) {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        sweep_groups(
            spins,
            len,
            bonds,
            |_, si, sj| group_damped(pieces, si, sj),
            |_, si, sj| scalar(si, sj),
        )
    }
}

/// `(s[i], s[j]) ← pieces(s[i], s[j])` for the bonds of a matching, four at a time in
/// lanes, the rest (and any group a lane of which leaves the series' range) by
/// `scalar`, which must be the same pieces on the scalar path. The on-site flows in
/// lanes assume commuting anisotropy and field (the caller's choice).
///
/// # Safety
/// AVX must be available ([`use_avx`]); `spins` must point to `len` spins, every bond
/// index must be below `len` with `i ≠ j`, and no other thread may touch these bonds'
/// sites until the caller's next barrier.
#[target_feature(enable = "avx")]
pub(crate) unsafe fn sweep_avx(
    spins: *mut Vec3,
    len: usize,
    bonds: &[[u32; 2]],
    kernel: &Kernel,
    pieces: &[Piece],
    scalar: &impl Fn(Vec3, Vec3) -> (Vec3, Vec3),
) {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        sweep_groups(
            spins,
            len,
            bonds,
            |_, si, sj| group(kernel, pieces, si, sj),
            |_, si, sj| scalar(si, sj),
        )
    }
}
