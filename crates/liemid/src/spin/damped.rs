//! The exact damped flows of the splitting's parts (Gilbert damping `α > 0`).
//!
//! LLG for a part `E_p` of the energy, with every other spin frozen, is
//! `dS/dt = −k [S × F + α S × (S × F)]`, `F = −∂E_p/∂S`, `k = γ/((1+α²) μ_s μ_B)`. For each
//! part of the splitting this flow has a closed form (docs/theory/spins.md §4, checked there
//! against DOP853 to 1e-13): the undamped rotation plus a relaxation of one angle.
//!
//! - Bond `−J S_i·S_j`, `c = kJ`, `δ = 2cαh`: `L = S_i + S_j` keeps its direction, `u =
//!   S_i·S_j` follows `artanh u(h) = artanh u₀ + δ`, and both spins turn about `L̂` by
//!   `Φ = (asinh z₁ − asinh z₀)/α`, `z = e^{artanh u}`. With `p = 1 + u₀ = |L|²/2`,
//!   `q = 1 − u₀ = 2|d|²`, `d = (S_i − S_j)/2` (no cancellation near `u₀ = ±1`) and
//!   `W = √(q + p e^{2δ})` this is
//!
//!   ```text
//!   Φ = √p G,  G = r(D) E/(√2 e^δ + W),  E = expm1(2δ)/α,  D = α√p E/(√2 e^δ + W),
//!   S_i' = e^δ/(√2 W) L + (√2/W) [cos Φ d + sin Φ L̂ × d],   S_j' = the same with −d,
//!   ```
//!
//!   `r(x) = asinh(x)/x` (`asinh a − asinh b = asinh((a² − b²)/(a√(1+b²) + b√(1+a²)))`),
//!   and `sin Φ L̂ × d = sinc(Φ) G/√2 · L × d` is regular at `L = 0`.
//! - Zeeman `−μ_s μ_B B·S`, `c_B = γ|B|/(1+α²)`, `b = B̂`, `τ = tanh(c_B α h)`: with
//!   `c₀ = S·b`, `cos ϑ(h) = (c₀ + τ)/(1 + c₀τ)` (the `tanh` addition formula), and the
//!   perpendicular part turns by `c_B h` about `b` and scales by `sech(c_B α h)/(1 + c₀τ)`.
//! - Anisotropy `−K (S·n)²`, `c_K = 2kK`, `g = c_K α h`: with `w₀ = S·n`,
//!   `s₀² = |S|² − w₀²`, `V = √(s₀² + w₀² e^{2g})`: `S' = (rot(n, Φ) S + w₀ expm1(g) n)/V`,
//!   `Φ = r(D) w₀ F/(e^g + V)`, `F = expm1(2g)/α`, `D = α w₀ F/(e^g + V)`.
//!
//! Every per-step constant (`e^δ`, `expm1`, `tanh`, Rodrigues' coefficients of the field
//! rotation) is computed once per sweep; per bond the flow costs one square root, two
//! divisions and the series of `sinc`, `cos` and `r`. As `α → 0` each flow tends to the
//! undamped one (`E → 4ch`, `W → √2`, `r → 1`); at `α = 0` the undamped code runs.
//!
//! Reference: the flows of J. Frank, W. Huang, B. Leimkuhler, J. Comput. Phys. 133 (1997)
//! and R. I. McLachlan, K. Modin, O. Verdier, Phys. Rev. E 89 (2014), with the damped
//! relaxation of LLG in the form of G. P. Müller et al., Phys. Rev. B 99, 224414 (2019).

use super::hamiltonian::Rates;
use super::lanes::{asinh_ratio, sinc_cos};
use super::lanes::{
    asinh_ratio_short, damped_anisotropy_flow, damped_bond_flow, damped_zeeman_flow, rodrigues_series,
    ASINH_SHORT_LIMIT, SERIES_LIMIT,
};
use crate::linalg::Vec3;
use crate::so3::rodrigues;

/// Rodrigues' `(sin θ/θ, (1 − cos θ)/θ²)` from `θ²`.
#[inline(always)]
fn rodrigues_coefficients(t: f64) -> (f64, f64) {
    if t < SERIES_LIMIT {
        rodrigues_series(t)
    } else {
        rodrigues(t)
    }
}

/// Whether every `asinh(x)/x` argument `x² = α² p (E/m)²` of a sweep stays below
/// [`ASINH_SHORT_LIMIT`], from the step's constants alone: `e = e^δ` (or `e^g`), `big_e =
/// expm1(2δ)/α` (or `expm1(2g)/α`). For `δ ≥ 0`, `W ≥ √2` (and `V ≥ 1`), so `m ≥ √2 (e + 1)`
/// and `x² ≤ α² E²/(e + 1)²`; for `δ < 0`, `W ≥ √2 e`, so `x² ≤ α² E²/(4e²)` (with `p ≤ 2`,
/// `|w₀| ≤ 1`). A 1 % margin covers spins off the unit sphere by round-off.
fn short_ratio_holds(alpha2: f64, e: f64, big_e: f64) -> bool {
    let bound = alpha2 * big_e * big_e / ((e + 1.0) * (e + 1.0)).min(4.0 * e * e);
    1.01 * bound < ASINH_SHORT_LIMIT
}

/// The constants of the damped flow over `h` of an exchange bond of damped rate `c`
/// (`δ = 2cαh`).
pub(crate) fn bond_step(c: f64, alpha: f64, h: f64) -> BondStep {
    let delta = 2.0 * c * alpha * h;
    let e = delta.exp();
    let big_e = (2.0 * delta).exp_m1() / alpha;
    let alpha2 = alpha * alpha;
    BondStep {
        e,
        e2: e * e,
        big_e,
        alpha2,
        short: short_ratio_holds(alpha2, e, big_e),
    }
}

/// The damped rates of a system (rad/ps, already divided by `1 + α²`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DampedRates {
    alpha: f64,
    /// `c = γJ/((1+α²) μ_s μ_B)`.
    exchange: f64,
    /// `γB/(1+α²)`.
    field: Vec3,
    /// `|γB|/(1+α²)`.
    field_norm: f64,
    /// `c_K = γ 2K/((1+α²) μ_s μ_B)`.
    anisotropy: f64,
    axis: Vec3,
}

/// The constants of one bond flow over a time `h`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BondStep {
    /// `e^δ`.
    pub(crate) e: f64,
    /// `e^{2δ}`.
    pub(crate) e2: f64,
    /// `expm1(2δ)/α`.
    pub(crate) big_e: f64,
    pub(crate) alpha2: f64,
    /// Whether the sweep may use the short `asinh(x)/x` series ([`short_ratio_holds`]).
    pub(crate) short: bool,
}

/// The constants of the Zeeman flow over a time `h`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ZeemanStep {
    /// The rotation vector `γB h/(1+α²)` and its Rodrigues coefficients.
    pub(crate) v: Vec3,
    pub(crate) a: f64,
    pub(crate) b: f64,
    /// `B̂`.
    pub(crate) unit: Vec3,
    pub(crate) tau: f64,
    pub(crate) sech: f64,
}

/// The constants of the anisotropy flow over a time `h`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AnisotropyStep {
    pub(crate) axis: Vec3,
    pub(crate) eg: f64,
    pub(crate) e2g: f64,
    pub(crate) expm1g: f64,
    /// `expm1(2g)/α`.
    pub(crate) f: f64,
    pub(crate) alpha2: f64,
    /// Whether the sweep may use the short `asinh(x)/x` series ([`short_ratio_holds`]).
    pub(crate) short: bool,
}

/// The constants of the on-site flow over a time `h`: the one term's exact flow, or the
/// Strang split field(h/2) ∘ anisotropy(h) ∘ field(h/2) when both are present (their damped
/// flows do not commute even for `B ∥ n`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SiteStep {
    pub(crate) zeeman: Option<ZeemanStep>,
    pub(crate) anisotropy: Option<AnisotropyStep>,
}

impl DampedRates {
    pub(crate) fn new(rates: &Rates) -> Self {
        let f = rates.damping_factor;
        DampedRates {
            alpha: rates.damping,
            exchange: rates.exchange * f,
            field: rates.field * f,
            field_norm: rates.field.norm() * f,
            anisotropy: rates.anisotropy * f,
            axis: rates.axis,
        }
    }

    /// Whether the on-site flow over `h₁ + h₂` is the composition of those over `h₁` and
    /// `h₂` (at most one on-site term).
    pub(crate) fn onsite_is_group(&self) -> bool {
        self.anisotropy == 0.0 || self.field_norm == 0.0
    }

    pub(crate) fn bond_step(&self, h: f64) -> BondStep {
        bond_step(self.exchange, self.alpha, h)
    }

    fn zeeman_step(&self, h: f64) -> ZeemanStep {
        let v = self.field * h;
        let (a, b) = rodrigues_coefficients(v.norm_squared());
        let x = self.field_norm * self.alpha * h;
        ZeemanStep {
            v,
            a,
            b,
            unit: self.field * (1.0 / self.field_norm),
            tau: x.tanh(),
            sech: 1.0 / x.cosh(),
        }
    }

    fn anisotropy_step(&self, h: f64) -> AnisotropyStep {
        let g = self.anisotropy * self.alpha * h;
        let eg = g.exp();
        let f = (2.0 * g).exp_m1() / self.alpha;
        let alpha2 = self.alpha * self.alpha;
        AnisotropyStep {
            axis: self.axis,
            eg,
            e2g: eg * eg,
            expm1g: g.exp_m1(),
            f,
            alpha2,
            short: short_ratio_holds(alpha2, eg, f),
        }
    }

    pub(crate) fn site_step(&self, h: f64) -> SiteStep {
        let both = !self.onsite_is_group();
        SiteStep {
            zeeman: (self.field_norm != 0.0).then(|| self.zeeman_step(if both { 0.5 * h } else { h })),
            anisotropy: (self.anisotropy != 0.0).then(|| self.anisotropy_step(h)),
        }
    }
}

/// The exact damped flow of one bond (module docs).
#[inline(always)]
pub(crate) fn bond(c: &BondStep, si: Vec3, sj: Vec3) -> (Vec3, Vec3) {
    let (a, b) = damped_bond_flow(
        c.e,
        c.e2,
        c.big_e,
        c.alpha2,
        si.into(),
        sj.into(),
        |x2| {
            if c.short {
                asinh_ratio_short(x2)
            } else {
                asinh_ratio(x2)
            }
        },
        sinc_cos,
    );
    (a.into(), b.into())
}

#[inline(always)]
fn zeeman(z: &ZeemanStep, s: Vec3) -> Vec3 {
    damped_zeeman_flow(z.v.into(), z.a, z.b, z.unit.into(), z.tau, z.sech, s.into()).into()
}

#[inline(always)]
fn anisotropy(k: &AnisotropyStep, s: Vec3) -> Vec3 {
    damped_anisotropy_flow(
        k.axis.into(),
        k.eg,
        k.e2g,
        k.expm1g,
        k.f,
        k.alpha2,
        s.into(),
        |x2| {
            if k.short {
                asinh_ratio_short(x2)
            } else {
                asinh_ratio(x2)
            }
        },
        rodrigues_coefficients,
    )
    .into()
}

/// The exact damped on-site flow of one spin (Strang-split when both terms are present).
#[inline(always)]
pub(crate) fn site(c: &SiteStep, s: Vec3) -> Vec3 {
    match (&c.zeeman, &c.anisotropy) {
        (Some(z), Some(k)) => zeeman(z, anisotropy(k, zeeman(z, s))),
        (Some(z), None) => zeeman(z, s),
        (None, Some(k)) => anisotropy(k, s),
        (None, None) => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The short series agrees with `asinh(x)/x` to round-off below its limit, and the
    /// sweep bound holds: for random unit spin pairs at steps where it chose the short
    /// series, the argument stays below the limit (forward and backward steps).
    #[test]
    fn the_short_asinh_series_holds_where_the_sweep_bound_chooses_it() {
        for k in 0..=1000 {
            let x2 = ASINH_SHORT_LIMIT * k as f64 / 1000.0;
            let closed = if x2 == 0.0 { 1.0 } else { x2.sqrt().asinh() / x2.sqrt() };
            assert!(
                (asinh_ratio_short(x2) - closed).abs() <= 2.0 * f64::EPSILON,
                "x² = {x2}"
            );
        }
        let mut rng = crate::random::Rng::new(7);
        let mut unit = || rng.unit_vector();
        let mut chosen = 0;
        for &alpha in &[0.01, 0.1, 0.3, 1.0] {
            for &h in &[0.3, 0.1, 0.03, 0.01, -0.01, -0.03, -0.1, -0.3] {
                let rates = DampedRates {
                    alpha,
                    exchange: 3.0,
                    field: Vec3::ZERO,
                    field_norm: 0.0,
                    anisotropy: 2.0,
                    axis: Vec3::new(0.0, 0.0, 1.0),
                };
                let (b, a) = (rates.bond_step(h), rates.anisotropy_step(h));
                for _ in 0..200 {
                    let (si, sj) = (unit(), unit());
                    if b.short {
                        chosen += 1;
                        // The argument `α² p (E/m)²` of the bond flow (lanes.rs).
                        let p = 1.0 + si.dot(sj);
                        let w = (1.0 - si.dot(sj) + p * b.e2).sqrt();
                        let base = b.big_e / (std::f64::consts::SQRT_2 * b.e + w);
                        assert!(b.alpha2 * p * base * base < ASINH_SHORT_LIMIT);
                    }
                    if a.short {
                        let w0 = si.dot(a.axis);
                        let v = (1.0 - w0 * w0 + w0 * w0 * a.e2g).sqrt();
                        let base = w0 * a.f / (a.eg + v);
                        assert!(a.alpha2 * base * base < ASINH_SHORT_LIMIT);
                    }
                }
            }
        }
        assert!(chosen > 0);
    }
}
