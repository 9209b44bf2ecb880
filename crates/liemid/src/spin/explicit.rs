//! The explicit baselines of atomistic spin dynamics codes (Spirit, UppASD, VAMPIRE), on
//! `dS_i/dt = Ω_i(S) × S_i`:
//!
//! - **Heun**: `S* = S + h f(S)`, `S⁺ = S + (h/2)(f(S) + f(S*))`, each spin renormalised;
//!   second order, keeps nothing exactly (the renormalisation keeps `|S|`).
//! - **Depondt-Mertens**: Heun on the rotation: `S* = exp(h Ω(S)) S`,
//!   `S⁺ = exp(h (Ω(S) + Ω(S*))/2) S`; second order, keeps `|S|`.
//! - **RK4**: classical fourth-order Runge-Kutta on `f`, each spin renormalised after the
//!   step.
//!
//! None keeps the energy or `Σ S_z`: their errors drift.
//!
//! References: P. Depondt, F. G. Mertens, J. Phys.: Condens. Matter 21, 336005 (2009);
//! G. P. Müller et al., Phys. Rev. B 99, 224414 (2019) (Spirit's solvers).

use super::hamiltonian::SpinSystem;
use super::sweep::{map_sites, update_sites};
use crate::linalg::Vec3;
use crate::so3::exp_apply;

/// `s / |s|`.
#[inline(always)]
fn unit(s: Vec3) -> Vec3 {
    s * (1.0 / s.norm())
}

/// One Heun step; `k1` and `predicted` are scratch of the spins' length.
pub(crate) fn heun(system: &SpinSystem, spins: &mut [Vec3], h: f64, k1: &mut Vec<Vec3>, predicted: &mut Vec<Vec3>) {
    let rates = system.rates();
    let lattice = &system.lattice;
    k1.resize(spins.len(), Vec3::ZERO);
    predicted.resize(spins.len(), Vec3::ZERO);
    {
        let s: &[Vec3] = spins;
        map_sites(k1, |i| rates.omega(lattice, s, i).cross(s[i]));
    }
    {
        let (s, k): (&[Vec3], &[Vec3]) = (spins, k1);
        map_sites(predicted, |i| s[i] + k[i] * h);
    }
    let (k, p): (&[Vec3], &[Vec3]) = (k1, predicted);
    update_sites(spins, |i, s| {
        let k2 = rates.omega(lattice, p, i).cross(p[i]);
        unit(s + (k[i] + k2) * (0.5 * h))
    });
}

/// One Depondt-Mertens step; `omega0` and `predicted` are scratch.
pub(crate) fn depondt(
    system: &SpinSystem,
    spins: &mut [Vec3],
    h: f64,
    omega0: &mut Vec<Vec3>,
    predicted: &mut Vec<Vec3>,
) {
    let rates = system.rates();
    let lattice = &system.lattice;
    omega0.resize(spins.len(), Vec3::ZERO);
    predicted.resize(spins.len(), Vec3::ZERO);
    {
        let s: &[Vec3] = spins;
        map_sites(omega0, |i| rates.omega(lattice, s, i));
    }
    {
        let (s, w): (&[Vec3], &[Vec3]) = (spins, omega0);
        map_sites(predicted, |i| exp_apply(w[i] * h, s[i]));
    }
    let (w, p): (&[Vec3], &[Vec3]) = (omega0, predicted);
    update_sites(spins, |i, s| {
        let mean = (w[i] + rates.omega(lattice, p, i)) * (0.5 * h);
        exp_apply(mean, s)
    });
}

/// One RK4 step; `sum`, `stage` and `k` are scratch.
pub(crate) fn rk4(
    system: &SpinSystem,
    spins: &mut [Vec3],
    h: f64,
    sum: &mut Vec<Vec3>,
    stage: &mut Vec<Vec3>,
    k: &mut Vec<Vec3>,
) {
    let rates = system.rates();
    let lattice = &system.lattice;
    let n = spins.len();
    sum.resize(n, Vec3::ZERO);
    stage.resize(n, Vec3::ZERO);
    k.resize(n, Vec3::ZERO);
    // k1 at S.
    {
        let s: &[Vec3] = spins;
        map_sites(k, |i| rates.omega(lattice, s, i).cross(s[i]));
    }
    sum.copy_from_slice(k);
    // k2 = f(S + h/2 k1), k3 = f(S + h/2 k2), k4 = f(S + h k3).
    for (c, weight) in [(0.5, 2.0), (0.5, 2.0), (1.0, 1.0)] {
        {
            let (s, kk): (&[Vec3], &[Vec3]) = (spins, k);
            map_sites(stage, |i| s[i] + kk[i] * (c * h));
        }
        {
            let y: &[Vec3] = stage;
            map_sites(k, |i| rates.omega(lattice, y, i).cross(y[i]));
        }
        for (a, b) in sum.iter_mut().zip(k.iter()) {
            *a += *b * weight;
        }
    }
    let acc: &[Vec3] = sum;
    update_sites(spins, |i, s| unit(s + acc[i] * (h / 6.0)));
}
