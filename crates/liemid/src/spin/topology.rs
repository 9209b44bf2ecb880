//! The topological charge of a spin texture on a square lattice, and the relaxation of a
//! texture to a nearby energy minimum.
//!
//! **Charge** (Berg and Lüscher): every plaquette `(x, y)` is cut into the triangles
//! `(s₀₀, s₁₀, s₁₁)` and `(s₀₀, s₁₁, s₀₁)`, counter-clockwise; a triangle of unit spins
//! spans the signed solid angle `Ω = 2 atan2(s₁·(s₂ × s₃), 1 + s₁·s₂ + s₂·s₃ + s₃·s₁)` in
//! `(−2π, 2π)`, and `Q = Σ Ω / (4π)`. On a periodic lattice (a torus) `Q` is an integer
//! for any texture with no triangle at `Ω = ±2π`; on an open lattice only the plaquettes
//! inside are counted. A skyrmion with its core along `−z` in a `+z` background has
//! `Q = −1`.
//!
//! **Relaxation** by velocity projection (Bessarab, Uzdin, Jónsson): with the tangent
//! force `f_i = F_i − (F_i·S_i) S_i`, `F_i = −∂E/∂S_i` (meV), a velocity `v` kept only along
//! `f` where it points with it (`v ← (v·f/|f|²) f` if `v·f > 0`, else 0, summed over all
//! spins), `v ← v + τ f`, `S_i ← (S_i + τ v_i)/|…|`; it stops when `max_i |f_i|` is below
//! the tolerance. Its fixed points are exactly the stationary points of `E` (unlike the
//! fixed points of a damped splitting, off by `O(h²)`).
//!
//! References: B. Berg, M. Lüscher, *Definition and statistical distributions of a
//! topological number in the lattice O(3) σ-model*, Nucl. Phys. B 190 (1981);
//! P. F. Bessarab, V. M. Uzdin, H. Jónsson, Comput. Phys. Commun. 196 (2015) 335
//! (velocity projection on the unit sphere, as Spirit's `VP` solver).

use super::hamiltonian::SpinSystem;
use super::lattice::LatticeKind;
use super::MU_B;
use crate::error::{Error, Result};
use crate::linalg::Vec3;

/// The Berg-Lüscher topological charge of `spins` on a square lattice (module docs).
///
/// # Errors
/// A lattice that is not square, or a spin array of the wrong length.
pub fn topological_charge(system: &SpinSystem, spins: &[Vec3]) -> Result<f64> {
    let lattice = &system.lattice;
    if lattice.kind() != LatticeKind::Square {
        return Err(Error::InvalidParameter {
            name: "lattice",
            value: lattice.size()[0] as f64,
            reason: "the topological charge is defined here on a square lattice",
        });
    }
    if spins.len() != lattice.sites() {
        return Err(Error::InvalidParameter {
            name: "spins",
            value: spins.len() as f64,
            reason: "must have one spin per site",
        });
    }
    let [nx, ny, _] = lattice.size();
    let periodic = lattice.periodic();
    let (px, py) = if periodic {
        (nx, ny)
    } else {
        (nx.saturating_sub(1), ny.saturating_sub(1))
    };
    let solid = |a: Vec3, b: Vec3, c: Vec3| 2.0 * a.dot(b.cross(c)).atan2(1.0 + a.dot(b) + b.dot(c) + c.dot(a));
    let mut total = 0.0;
    for y in 0..py {
        for x in 0..px {
            let (x1, y1) = ((x + 1) % nx, (y + 1) % ny);
            let s00 = spins[x + nx * y];
            let s10 = spins[x1 + nx * y];
            let s11 = spins[x1 + nx * y1];
            let s01 = spins[x + nx * y1];
            total += solid(s00, s10, s11) + solid(s00, s11, s01);
        }
    }
    Ok(total / (4.0 * std::f64::consts::PI))
}

/// What a relaxation did.
#[derive(Clone, Copy, Debug)]
pub struct Relaxation {
    /// Iterations taken.
    pub iterations: usize,
    /// `max_i |f_i|` at the end (meV).
    pub force: f64,
}

/// Relax `spins` to a stationary point of the energy of `system` by velocity projection
/// (module docs), until the largest tangent force is at most `tolerance` (meV).
///
/// # Errors
/// A spin array of the wrong length, a tolerance that is not positive, or no convergence
/// within `max_iterations` (the spins are then left where the iteration stopped).
pub fn relax(system: &SpinSystem, spins: &mut [Vec3], tolerance: f64, max_iterations: usize) -> Result<Relaxation> {
    let n = system.len();
    if spins.len() != n {
        return Err(Error::InvalidParameter {
            name: "spins",
            value: spins.len() as f64,
            reason: "must have one spin per site",
        });
    }
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(Error::InvalidParameter {
            name: "tolerance",
            value: tolerance,
            reason: "must be a positive force (meV)",
        });
    }
    // The step from a bound on the energy's curvature.
    let degree = (0..n).map(|i| system.lattice.neighbours(i).len()).max().unwrap_or(0) as f64;
    let dmi = system
        .dmi_vectors()
        .map_or(0.0, |d| d.iter().map(|v| v.norm()).fold(0.0, f64::max));
    let moment = system.mu_s * MU_B;
    let curvature =
        2.0 * (system.exchange.abs() + dmi) * degree + 2.0 * system.anisotropy.abs() + moment * system.field.norm();
    let tau = 1.0 / curvature.max(1e-300).sqrt();
    let force = |s: &[Vec3], f: &mut [Vec3]| -> f64 {
        let mut worst = 0.0f64;
        for (i, fi) in f.iter_mut().enumerate() {
            let b = system.effective_field(s, i) * moment;
            let t = b - s[i] * b.dot(s[i]);
            worst = worst.max(t.norm());
            *fi = t;
        }
        worst
    };
    let mut f = vec![Vec3::ZERO; n];
    let mut v = vec![Vec3::ZERO; n];
    let mut worst = force(spins, &mut f);
    for iteration in 0..max_iterations {
        if worst <= tolerance {
            return Ok(Relaxation {
                iterations: iteration,
                force: worst,
            });
        }
        let (mut vf, mut ff) = (0.0, 0.0);
        for (vi, fi) in v.iter().zip(&f) {
            vf += vi.dot(*fi);
            ff += fi.dot(*fi);
        }
        let scale = if vf > 0.0 { vf / ff } else { 0.0 };
        for ((s, vi), fi) in spins.iter_mut().zip(v.iter_mut()).zip(&f) {
            *vi = *fi * scale + *fi * tau;
            let x = *s + *vi * tau;
            *s = x * (1.0 / x.norm());
        }
        worst = force(spins, &mut f);
        if !worst.is_finite() {
            break;
        }
    }
    Err(Error::InvalidParameter {
        name: "max_iterations",
        value: max_iterations as f64,
        reason: "the relaxation did not bring the largest force below the tolerance in this many iterations",
    })
}
