//! The symplectic form of `T*(ℝ³ × SO(3))ⁿ` in the coordinates the library steps (for each
//! body: position `x`, momentum `p`, attitude `R`, body angular momentum `Π`), and the
//! defect `max |ω(DΦ u_a, DΦ u_b) − ω(u_a, u_b)|` of a map `Φ` over a basis of tangent
//! vectors, measured by central differences extrapolated once (Richardson).
//!
//! A tangent vector is `(δx, δp, ξ, δΠ)` with `δR = R hat(ξ)` (the body-frame variation).
//! The canonical one-form `θ = p · δx + Π · ξ` gives, with left-invariant `ξ` fields
//! (`[ξ₁, ξ₂] = ξ₁ × ξ₂`),
//!
//! ```text
//! ω(u, v) = δx_u · δp_v − δx_v · δp_u + ξ_u · δΠ_v − ξ_v · δΠ_u + Π · (ξ_u × ξ_v)
//! ```
//!
//! (up to an overall sign, which the test does not see). A map is symplectic exactly when it
//! keeps `ω`; the exact flows (LIEMID[EX]'s free flow, the kicks of a potential) do, which
//! checks the sign of the last term.
//!
//! The differences' step is `10⁻⁴` along every direction unless [`defect_with_steps`] is
//! given others. The truncation error of the extrapolated differences is `O(e⁴)` times the
//! map's fifth derivative along the direction, which is large along `Π` for bodies of small
//! inertia (a change `δΠ` turns a body by `h δΠ / I`): there a smaller step along `Π` keeps
//! the truncation below the rounding, which grows as `u/e`.
//!
//! Reference: J. E. Marsden, T. S. Ratiu, *Introduction to Mechanics and Symmetry*, 2nd ed.,
//! Springer 1999, §4.4 and §13.
#![allow(dead_code)]

use liemid::{so3, Mat3, Vec3};

/// One body's coordinates.
#[derive(Clone, Copy, Debug)]
pub struct Body {
    pub x: Vec3,
    pub p: Vec3,
    pub r: Mat3,
    pub pi: Vec3,
}

/// One body's tangent vector.
#[derive(Clone, Copy, Debug, Default)]
pub struct Tangent {
    pub dx: Vec3,
    pub dp: Vec3,
    pub xi: Vec3,
    pub dpi: Vec3,
}

fn axis(k: usize) -> Vec3 {
    [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
    ][k]
}

/// `state` moved by `e` along basis direction `d` of body `i` (`d < 12`: `x`, `p`, `ξ`,
/// `Π`, three each); `translations` false leaves `x`, `p` out (rotors).
fn moved(state: &[Body], i: usize, d: usize, e: f64) -> Vec<Body> {
    let mut s = state.to_vec();
    let v = axis(d % 3) * e;
    match d / 3 {
        0 => s[i].x += v,
        1 => s[i].p += v,
        2 => s[i].r = s[i].r * so3::exp(v),
        _ => s[i].pi += v,
    }
    s
}

/// The central differences' step along each kind of basis direction.
#[derive(Clone, Copy, Debug)]
pub struct Steps {
    pub x: f64,
    pub p: f64,
    pub xi: f64,
    pub pi: f64,
}

impl Steps {
    /// `10⁻⁴` along every direction.
    pub const UNIFORM: Steps = Steps {
        x: 1e-4,
        p: 1e-4,
        xi: 1e-4,
        pi: 1e-4,
    };

    /// The step along basis direction `d` (`x`, `p`, `ξ`, `Π`, three each).
    fn along(&self, d: usize) -> f64 {
        [self.x, self.p, self.xi, self.pi][d / 3]
    }
}

/// The tangent image of the basis direction `(i, d)`: central differences at `2e` and `e`,
/// extrapolated, `e` the step along the direction.
fn pushed(
    map: &dyn Fn(&[Body]) -> Vec<Body>,
    state: &[Body],
    image: &[Body],
    (i, d): (usize, usize),
    steps: &Steps,
) -> Vec<Tangent> {
    let central = |e: f64| -> Vec<Tangent> {
        let (a, b) = (map(&moved(state, i, d, e)), map(&moved(state, i, d, -e)));
        a.iter()
            .zip(&b)
            .zip(image)
            .map(|((a, b), c)| Tangent {
                dx: (a.x - b.x) * (0.5 / e),
                dp: (a.p - b.p) * (0.5 / e),
                // ξ = vee(Rᵀ δR), the skew part of Rᵀ (R₊ − R₋)/(2e).
                xi: {
                    let m = c.r.transpose() * (a.r - b.r) * (0.5 / e);
                    Vec3::new(m.m[2][1] - m.m[1][2], m.m[0][2] - m.m[2][0], m.m[1][0] - m.m[0][1]) * 0.5
                },
                dpi: (a.pi - b.pi) * (0.5 / e),
            })
            .collect()
    };
    let e = steps.along(d);
    let (coarse, fine) = (central(2.0 * e), central(e));
    fine.iter()
        .zip(&coarse)
        .map(|(f, c)| Tangent {
            dx: (f.dx * 4.0 - c.dx) * (1.0 / 3.0),
            dp: (f.dp * 4.0 - c.dp) * (1.0 / 3.0),
            xi: (f.xi * 4.0 - c.xi) * (1.0 / 3.0),
            dpi: (f.dpi * 4.0 - c.dpi) * (1.0 / 3.0),
        })
        .collect()
}

/// `ω(u, v)` at `state`.
pub fn omega(state: &[Body], u: &[Tangent], v: &[Tangent]) -> f64 {
    state
        .iter()
        .zip(u.iter().zip(v))
        .map(|(s, (u, v))| {
            u.dx.dot(v.dp) - v.dx.dot(u.dp) + u.xi.dot(v.dpi) - v.xi.dot(u.dpi) + s.pi.dot(u.xi.cross(v.xi))
        })
        .sum()
}

/// The basis tangent vector `(i, d)` at the start.
fn basis(n: usize, i: usize, d: usize) -> Vec<Tangent> {
    let mut t = vec![Tangent::default(); n];
    let v = axis(d % 3);
    match d / 3 {
        0 => t[i].dx = v,
        1 => t[i].dp = v,
        2 => t[i].xi = v,
        _ => t[i].dpi = v,
    }
    t
}

/// The symplecticity defect of `map` at `state`: `max |ω(DΦ u_a, DΦ u_b) − ω(u_a, u_b)|`
/// over the basis, with `translations` false for rotors (no `x`, `p` directions), relative
/// to the largest `|ω(u_a, u_b)|`.
pub fn defect(map: &dyn Fn(&[Body]) -> Vec<Body>, state: &[Body], translations: bool) -> f64 {
    defect_with_steps(map, state, translations, &Steps::UNIFORM)
}

/// [`defect`] with the differences' `steps` along each kind of direction.
pub fn defect_with_steps(map: &dyn Fn(&[Body]) -> Vec<Body>, state: &[Body], translations: bool, steps: &Steps) -> f64 {
    let n = state.len();
    let image = map(state);
    let directions: Vec<(usize, usize)> = (0..n)
        .flat_map(|i| (if translations { 0 } else { 6 }..12).map(move |d| (i, d)))
        .collect();
    let images: Vec<Vec<Tangent>> = directions
        .iter()
        .map(|&direction| pushed(map, state, &image, direction, steps))
        .collect();
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    for (a, &(ia, da)) in directions.iter().enumerate() {
        for (b, &(ib, db)) in directions.iter().enumerate() {
            let before = omega(state, &basis(n, ia, da), &basis(n, ib, db));
            let after = omega(&image, &images[a], &images[b]);
            worst = worst.max((after - before).abs());
            scale = scale.max(before.abs());
        }
    }
    worst / scale
}
