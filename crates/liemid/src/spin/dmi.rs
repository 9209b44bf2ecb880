//! The exact flows of a bond with Dzyaloshinskii-Moriya interaction, undamped and damped.
//!
//! `E = −J S_i·S_j − D·(S_i × S_j) = −S_iᵀ A S_j`, `A = J 1 − skew(D)`. With
//! `ρ = √(J² + |D|²)`, `φ = atan2(|D|, J)`, `u = D/|D|` and `Q = rot(u, −φ)`,
//! `A = ρ Q − g u uᵀ`, `g = ρ (1 − cos φ) = ρ − J`, so the bond is the sum of two parts whose
//! flows are exact (LLG `dS/dt = −k [S × F + α S × (S × F)]`, `k = γ/((1+α²) μ_s μ_B)`):
//!
//! - **rotated exchange** `−ρ S_i·(Q S_j)`: with `T = Q S_j` the pair `(S_i, T)` moves as an
//!   exchange bond of strength `ρ` (rotations commute with the cross products of LLG), then
//!   `S_j = Qᵀ T`; damped, the exact damped bond flow of `spin::damped` on `(S_i, T)`;
//! - **Ising along `u`** `+g a_i a_j`, `a = S·u`: undamped both `a` are constant and `S_i`
//!   turns about `u` by `−k g a_j h` (`S_j` by `−k g a_i h`). Damped, `a_i` and `a_j`
//!   follow `a_i' = −c a_j (1 − a_i²)`, `c = kαg`, and its mirror. In `x = artanh a`
//!   this is `x_i' = −c tanh x_j`; `cosh x_i / cosh x_j` is constant, so `w = sinh x_i`,
//!   `v = sinh x_j` obey the linear `w' = −c r v`, `v' = −c w / r` (`r = cosh x_i / cosh x_j`),
//!   with the closed form below (found for this code, where integrating the pair
//!   numerically was the first plan). With `p_i = |S_i − a_i u|`, `N_i = a_i cosh ch − a_j sinh ch` and
//!   `R_i = √(N_i² + p_i²)`:
//!
//!   ```text
//!   S_i(h) = (N_i u + rot(u, Φ_i) (S_i − a_i u)) / R_i,
//!   Φ_i = (artanh a_i(h) − artanh a_i)/α = asinh(Δ_i)/α,
//!   Δ_i = sinh(x_i(h) − x_i) = (N_i − a_i) / (1 + a_i (N_i − a_i)/(R_i + 1)),
//!   ```
//!
//!   where `N_i − a_i = a_i (cosh ch − 1) − a_j sinh ch` is formed from `(cosh ch − 1)/α`
//!   and `sinh(ch)/α` without cancellation, so `Φ_i → −k g a_j h` as `α → 0` with no loss;
//!   `S_j` by exchanging `i` and `j`. A spin along `±u` stays (`p = 0`, `R = 1`).
//!
//! The bond's flow is Strang within the bond: Ising `h/2`, rotated exchange `h`, Ising
//! `h/2`: second order, symmetric (each piece is an exact flow, `flow(−h) = flow(h)⁻¹`)
//! and, undamped, a Poisson map. The bond colouring and the outer compositions stay as
//! they are, so `split4`, `split6`, `split8` reach orders 4, 6, 8 with DMI too.
//!
//! Reference: the splitting of `A` is docs/theory/spins.md §6 ("A bond with
//! Dzyaloshinskii-Moriya interaction"); the bond flows of R. I. McLachlan, K. Modin,
//! O. Verdier, *Symplectic integrators for spin systems*, Phys. Rev. E 89 (2014); LLG in
//! the form of G. P. Müller et al., Phys. Rev. B 99, 224414 (2019).

use super::damped;
use super::lanes::{asinh_ratio, sinc_cos};
use super::lanes::{bond_flow, rodrigues_series, sinc_cos_short, Lane, SERIES_LIMIT, SHORT_LIMIT, V};
use crate::linalg::Vec3;
use crate::so3::rodrigues;

/// The constants of a DMI bond flow over a time `h`: `Q = rot(u, −φ)` by `cos φ`, `sin φ`;
/// `rho_h = kρh`, `ising_half = k g h/2`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DmiStep {
    pub(crate) cos: f64,
    pub(crate) sin: f64,
    pub(crate) rho_h: f64,
    pub(crate) ising_half: f64,
    /// Whether every Ising angle is below √[`SHORT_LIMIT`] (`|a| ≤ 1`).
    pub(crate) short: bool,
}

/// The axis `u` of a DMI bond's turns (on `f64` or on lanes).
pub(crate) trait TurnAxis<T: Lane>: Copy {
    /// `u·s`.
    fn along(self, s: V<T>) -> T;
    /// `rot(u, α) s` from `cos α`, `sin α` and `a = u·s`.
    fn turn(self, cos: T, sin: T, a: T, s: V<T>) -> V<T>;
}

/// Any unit `u`: `rot(u, α) s = cos α s + sin α (u × s) + (1 − cos α) a u`.
#[derive(Clone, Copy)]
pub(crate) struct AnyAxis<T>(pub(crate) V<T>);

impl<T: Lane> TurnAxis<T> for AnyAxis<T> {
    #[inline(always)]
    fn along(self, s: V<T>) -> T {
        s.dot(self.0)
    }
    #[inline(always)]
    fn turn(self, cos: T, sin: T, a: T, s: V<T>) -> V<T> {
        let u = self.0;
        s.scale(cos)
            .add(u.cross(s).scale(sin))
            .add(u.scale((T::from(1.0) - cos) * a))
    }
}

/// `u = σ e_K` with `σ = ±1` (per lane): the turn keeps the `K` component exactly and turns
/// the other two in their plane, 6 operations instead of 20 (interfacial DMI on the square
/// and triangular lattices, bulk DMI on the cubic one, have only such axes).
#[derive(Clone, Copy)]
pub(crate) struct CoordinateAxis<const K: usize, T> {
    pub(crate) sign: T,
}

impl<const K: usize, T: Lane> TurnAxis<T> for CoordinateAxis<K, T> {
    #[inline(always)]
    fn along(self, s: V<T>) -> T {
        self.sign
            * match K {
                0 => s.x,
                1 => s.y,
                _ => s.z,
            }
    }
    #[inline(always)]
    fn turn(self, cos: T, sin: T, _a: T, s: V<T>) -> V<T> {
        let sin = sin * self.sign;
        match K {
            0 => V {
                x: s.x,
                y: cos * s.y - sin * s.z,
                z: sin * s.y + cos * s.z,
            },
            1 => V {
                x: sin * s.z + cos * s.x,
                y: s.y,
                z: cos * s.z - sin * s.x,
            },
            _ => V {
                x: cos * s.x - sin * s.y,
                y: sin * s.x + cos * s.y,
                z: s.z,
            },
        }
    }
}

/// `Some((K, σ))` when the unit vector `u` is `σ e_K` (its other two components exactly 0).
#[inline(always)]
pub(crate) fn coordinate_axis(u: Vec3) -> Option<(usize, f64)> {
    match (u.x == 0.0, u.y == 0.0, u.z == 0.0) {
        (false, true, true) => Some((0, u.x.signum())),
        (true, false, true) => Some((1, u.y.signum())),
        (true, true, false) => Some((2, u.z.signum())),
        _ => None,
    }
}

/// `rot(u, θ + ψ) s`, `a = u·s`, with `ψ` given by `(cos ψ, sin ψ)` or absent; `(sin θ/θ,
/// cos θ)` from `coefficients`.
#[inline(always)]
fn ising_turn<T: Lane, A: TurnAxis<T>>(
    u: A,
    a: T,
    theta: T,
    offset: Option<(T, T)>,
    s: V<T>,
    coefficients: &mut impl FnMut(T) -> (T, T),
) -> V<T> {
    let (sinc, cos) = coefficients(theta * theta);
    let sin = theta * sinc;
    match offset {
        None => u.turn(cos, sin, a, s),
        Some((c, n)) => u.turn(cos * c - sin * n, sin * c + cos * n, a, s),
    }
}

/// The undamped Ising flow of a DMI bond: `S_i` about `u` by `−angle a_j`, `S_j` by
/// `−angle a_i`.
#[inline(always)]
pub(crate) fn dmi_ising<T: Lane, A: TurnAxis<T>>(
    u: A,
    angle: T,
    si: V<T>,
    sj: V<T>,
    coefficients: &mut impl FnMut(T) -> (T, T),
) -> (V<T>, V<T>) {
    let (ai, aj) = (u.along(si), u.along(sj));
    let zero = T::from(0.0);
    (
        ising_turn(u, ai, zero - angle * aj, None, si, coefficients),
        ising_turn(u, aj, zero - angle * ai, None, sj, coefficients),
    )
}

/// The exact undamped flow of one DMI bond over `h`, Strang within the bond: Ising `h/2`,
/// the exchange flow of `(S_i, Q S_j)` at `kρ`, `S_j = Qᵀ T`, Ising `h/2`. `Q = rot(u, −φ)`
/// and the Ising flow both turn `S_j` about `u`, so each Ising turn of `S_j` and its
/// neighbouring `Q` or `Qᵀ` are one turn by the sum of the angles (`S·u`, which fixes the
/// Ising angles, is the same before and after a turn about `u`): four turns per bond, not
/// six. `ising` gives `(sin θ/θ, cos θ)` of the Ising angles, `coefficients` of the
/// exchange's.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn dmi_bond_flow<T: Lane, A: TurnAxis<T>>(
    u: A,
    cos: T,
    sin: T,
    rho_h: T,
    ising_half: T,
    si: V<T>,
    sj: V<T>,
    mut ising: impl FnMut(T) -> (T, T),
    coefficients: impl FnMut(T) -> (T, T),
) -> (V<T>, V<T>) {
    let zero = T::from(0.0);
    let (ai, aj) = (u.along(si), u.along(sj));
    let si = ising_turn(u, ai, zero - ising_half * aj, None, si, &mut ising);
    let t = ising_turn(u, aj, zero - ising_half * ai, Some((cos, zero - sin)), sj, &mut ising);
    let (si, t) = bond_flow(rho_h, si, t, coefficients);
    let (bi, bj) = (u.along(si), u.along(t));
    (
        ising_turn(u, bi, zero - ising_half * bj, None, si, &mut ising),
        ising_turn(u, bj, zero - ising_half * bi, Some((cos, sin)), t, &mut ising),
    )
}

/// `Q v = rot(u, −φ) v` by `cos φ`, `sin φ`, `1 − cos φ`.
#[inline(always)]
fn dmi_q(u: Vec3, cos: f64, sin: f64, versine: f64, v: Vec3) -> Vec3 {
    v * cos - u.cross(v) * sin + u * (versine * u.dot(v))
}

/// `Qᵀ v = rot(u, φ) v`.
#[inline(always)]
fn dmi_q_t(u: Vec3, cos: f64, sin: f64, versine: f64, v: Vec3) -> Vec3 {
    v * cos + u.cross(v) * sin + u * (versine * u.dot(v))
}

/// The constants of the DMI bonds of one `|D|` (rates in rad/ps, divided by `1 + α²`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DmiShape {
    /// `cos φ`, `sin φ`, `1 − cos φ` of `Q = rot(u, −φ)`.
    pub(crate) cos: f64,
    pub(crate) sin: f64,
    pub(crate) versine: f64,
    /// `k ρ`.
    pub(crate) rho: f64,
    /// `k g`.
    pub(crate) ising: f64,
}

impl DmiShape {
    /// For `|D| = dn > 0` (meV), exchange `exchange` (meV) and `k = γ/((1+α²) μ_s μ_B)`.
    #[inline(always)]
    pub(crate) fn new(dn: f64, exchange: f64, k: f64) -> Self {
        let d2 = dn * dn;
        let rho = (exchange * exchange + d2).sqrt();
        // g = ρ − J without cancellation for J > 0.
        let g = if exchange > 0.0 {
            d2 / (rho + exchange)
        } else {
            rho - exchange
        };
        let inv = 1.0 / rho;
        DmiShape {
            cos: exchange * inv,
            sin: dn * inv,
            versine: g * inv,
            rho: k * rho,
            ising: k * g,
        }
    }

    /// The undamped flow's constants over `h`.
    #[inline(always)]
    pub(crate) fn step(&self, h: f64) -> DmiStep {
        let ising_half = self.ising * (0.5 * h);
        DmiStep {
            cos: self.cos,
            sin: self.sin,
            rho_h: self.rho * h,
            ising_half,
            short: ising_half * ising_half < SHORT_LIMIT,
        }
    }
}

/// One DMI bond: its unit vector and its shape.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DmiBond {
    /// `u = D/|D|`.
    pub(crate) unit: Vec3,
    pub(crate) shape: DmiShape,
}

impl DmiBond {
    /// The bond with DMI vector `d` (meV) and exchange `exchange` (meV), with
    /// `k = γ/((1+α²) μ_s μ_B)`; `None` for `d = 0`.
    #[inline(always)]
    pub(crate) fn new(d: Vec3, exchange: f64, k: f64) -> Option<Self> {
        let d2 = d.norm_squared();
        if d2 == 0.0 {
            return None;
        }
        let dn = d2.sqrt();
        Some(DmiBond {
            unit: d * (1.0 / dn),
            shape: DmiShape::new(dn, exchange, k),
        })
    }

    /// `Q v = rot(u, −φ) v`.
    #[inline(always)]
    fn q(&self, v: Vec3) -> Vec3 {
        let c = &self.shape;
        dmi_q(self.unit, c.cos, c.sin, c.versine, v)
    }

    /// `Qᵀ v = rot(u, φ) v`.
    #[inline(always)]
    fn q_t(&self, v: Vec3) -> Vec3 {
        let c = &self.shape;
        dmi_q_t(self.unit, c.cos, c.sin, c.versine, v)
    }
}

/// `rot(u, θ) s` for a unit `u` (Rodrigues), for the damped flows.
#[inline(always)]
fn rotate(u: Vec3, theta: f64, s: Vec3) -> Vec3 {
    let t = theta * theta;
    let (a, b) = if t < SERIES_LIMIT {
        rodrigues_series(t)
    } else {
        rodrigues(t)
    };
    let v = u * theta;
    let vx = v.cross(s);
    s + vx * a + v.cross(vx) * b
}

/// The exact undamped flow of a DMI bond with unit vector `u` over the time of `c`
/// ([`dmi_bond_flow`] on the scalar path, with the axis the lanes choose: their bits).
#[inline(always)]
pub(crate) fn flow(u: Vec3, c: &DmiStep, si: Vec3, sj: Vec3) -> (Vec3, Vec3) {
    match coordinate_axis(u) {
        Some((0, sign)) => flow_about(CoordinateAxis::<0, f64> { sign }, c, si, sj),
        Some((1, sign)) => flow_about(CoordinateAxis::<1, f64> { sign }, c, si, sj),
        Some((_, sign)) => flow_about(CoordinateAxis::<2, f64> { sign }, c, si, sj),
        None => flow_about(AnyAxis(V::from(u)), c, si, sj),
    }
}

#[inline(always)]
fn flow_about<A: TurnAxis<f64>>(u: A, c: &DmiStep, si: Vec3, sj: Vec3) -> (Vec3, Vec3) {
    let short = c.short;
    let (a, b) = dmi_bond_flow(
        u,
        c.cos,
        c.sin,
        c.rho_h,
        c.ising_half,
        si.into(),
        sj.into(),
        |t| if short { sinc_cos_short(t) } else { sinc_cos(t) },
        sinc_cos,
    );
    (a.into(), b.into())
}

/// One spin of the damped Ising flow (module docs): `a` its own `S·u`, `other` the other's,
/// `ch1 = (cosh ch − 1)/α`, `sh = sinh(ch)/α`.
#[inline(always)]
fn damped_ising_spin(u: Vec3, alpha: f64, ch1: f64, sh: f64, s: Vec3, a: f64, other: f64) -> Vec3 {
    let perp = s - u * a;
    // (N − a)/α and N.
    let dn = a * ch1 - other * sh;
    let n = a + alpha * dn;
    let r = (n * n + perp.norm_squared()).sqrt();
    let delta = dn / (1.0 + a * (alpha * dn) / (r + 1.0));
    let x = alpha * delta;
    let phi = delta * asinh_ratio(x * x);
    (u * n + rotate(u, phi, perp)) * (1.0 / r)
}

/// The exact damped Ising flow over `t`.
#[inline(always)]
fn damped_ising(b: &DmiBond, alpha: f64, si: Vec3, sj: Vec3, t: f64) -> (Vec3, Vec3) {
    let x = b.shape.ising * alpha * t;
    let half = (0.5 * x).sinh();
    let ch1 = 2.0 * half * half / alpha;
    let sh = x.sinh() / alpha;
    let (ai, aj) = (si.dot(b.unit), sj.dot(b.unit));
    (
        damped_ising_spin(b.unit, alpha, ch1, sh, si, ai, aj),
        damped_ising_spin(b.unit, alpha, ch1, sh, sj, aj, ai),
    )
}

/// The exact damped flow of a DMI bond over `h` (Strang within the bond), `α > 0`.
#[inline(always)]
pub(crate) fn damped_flow(b: &DmiBond, alpha: f64, si: Vec3, sj: Vec3, h: f64) -> (Vec3, Vec3) {
    let (si, sj) = damped_ising(b, alpha, si, sj, 0.5 * h);
    let (si, t) = damped::bond(&damped::bond_step(b.shape.rho, alpha, h), si, b.q(sj));
    damped_ising(b, alpha, si, b.q_t(t), 0.5 * h)
}

/// The pieces one at a time, for tests against a reference: `which` 0 the Ising part, 1 the
/// rotated exchange, 2 the Strang bond flow; `d` (meV), `exchange` (meV), `k` as in
/// [`DmiBond::new`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn piece_flow(
    which: u8,
    d: Vec3,
    exchange: f64,
    k: f64,
    alpha: f64,
    si: Vec3,
    sj: Vec3,
    h: f64,
) -> (Vec3, Vec3) {
    let Some(b) = DmiBond::new(d, exchange, k) else {
        return (si, sj);
    };
    let ising = |angle: f64, si: Vec3, sj: Vec3| {
        let (a, c) = dmi_ising(AnyAxis(V::from(b.unit)), angle, si.into(), sj.into(), &mut sinc_cos);
        (a.into(), c.into())
    };
    match (which, alpha == 0.0) {
        (0, true) => ising(b.shape.ising * h, si, sj),
        (0, false) => damped_ising(&b, alpha, si, sj, h),
        (1, true) => {
            let (a, t) = bond_flow(b.shape.rho * h, si.into(), b.q(sj).into(), sinc_cos);
            (a.into(), b.q_t(t.into()))
        }
        (1, false) => {
            let (a, t) = damped::bond(&damped::bond_step(b.shape.rho, alpha, h), si, b.q(sj));
            (a, b.q_t(t))
        }
        (_, true) => flow(b.unit, &b.shape.step(h), si, sj),
        (_, false) => damped_flow(&b, alpha, si, sj, h),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bond whose axis is `±e_K` flows on the coordinate path (the `K` component kept
    /// exactly by each turn, the other two turned in their plane) as on the general one, to
    /// round-off: random spin pairs, both signs, each axis, steps of both signs and with
    /// the long and the short Ising series.
    #[test]
    fn a_coordinate_axis_bond_flows_as_the_general_axis() {
        let mut rng = crate::random::Rng::new(11);
        let shape = DmiShape::new(0.3, 1.0, 0.176);
        let mut long = false;
        for k in 0..3 {
            for sign in [1.0, -1.0] {
                let mut u = Vec3::ZERO;
                match k {
                    0 => u.x = sign,
                    1 => u.y = sign,
                    _ => u.z = sign,
                }
                assert_eq!(coordinate_axis(u), Some((k, sign)));
                for h in [0.05, -0.05, 2.0, -2.0, 30.0, -30.0] {
                    let c = shape.step(h);
                    long |= !c.short;
                    for _ in 0..100 {
                        let (si, sj) = (rng.unit_vector(), rng.unit_vector());
                        let (a, b) = flow(u, &c, si, sj);
                        let (ga, gb) = flow_about(AnyAxis(V::from(u)), &c, si, sj);
                        assert!((a - ga).max_abs() <= 8.0 * f64::EPSILON, "axis {k} sign {sign} h {h}");
                        assert!((b - gb).max_abs() <= 8.0 * f64::EPSILON, "axis {k} sign {sign} h {h}");
                    }
                }
            }
        }
        assert!(long);
        assert_eq!(coordinate_axis(Vec3::new(0.6, 0.8, 0.0)), None);
    }
}
