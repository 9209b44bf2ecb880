//! Symmetric compositions of a symmetric one-step method `Φ`:
//! `Ψ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h}` with palindromic `γ` (`γ_i = γ_{s+1−i}`) summing to 1.
//!
//! Composing a symmetric method of order 2 (LIEMID\[EA\], Verlet) raises the order while
//! keeping what the base method keeps (symplecticity where the base has it, time
//! reversibility, the momentum invariants), since each stage keeps them. Each stage of EA reuses the previous stage's end
//! torque, so a composition of `s` stages costs `s` torque evaluations per step.
//!
//! ## Reference
//! E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., Springer
//! (2006), section V.3; W. Kahan, R.-C. Li, *Composition constants for raising the orders
//! of unconventional schemes for ordinary differential equations*, Math. Comp. 66 (1997);
//! M. Suzuki, Phys. Lett. A 146 (1990); H. Yoshida, Phys. Lett. A 150 (1990).

/// A palindromic set of composition coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scheme {
    /// Short name, e.g. `suzuki4`.
    pub name: &'static str,
    /// Order reached from a symmetric second-order base method.
    pub order: u32,
    /// The first half of the coefficients, including the middle one when `s` is odd.
    half: &'static [f64],
    /// Number of stages `s`.
    pub(crate) stages: usize,
}

// The constants are written with the digits the papers publish.
#[allow(clippy::excessive_precision)]
impl Scheme {
    /// The coefficient of stage `i` (0-based).
    #[must_use]
    #[inline]
    pub fn gamma(&self, i: usize) -> f64 {
        let k = if i < self.half.len() { i } else { self.stages - 1 - i };
        self.half[k]
    }

    /// Number of stages.
    #[must_use]
    pub fn stages(&self) -> usize {
        self.stages
    }

    /// Suzuki's 5-stage fourth-order scheme: `γ₁ = γ₂ = γ₄ = γ₅ = 1/(4 − 4^{1/3})`,
    /// `γ₃ = 1 − 4 γ₁`.
    pub const SUZUKI4: Scheme = Scheme {
        name: "Suzuki 5-stage",
        order: 4,
        half: &[
            0.414_490_771_794_375_7,
            0.414_490_771_794_375_7,
            -0.657_963_087_177_502_9,
        ],
        stages: 5,
    };

    /// Yoshida's triple jump, fourth order: `γ₁ = γ₃ = 1/(2 − 2^{1/3})`, `γ₂ = 1 − 2 γ₁`.
    pub const YOSHIDA4: Scheme = Scheme {
        name: "Yoshida triple jump",
        order: 4,
        half: &[1.351_207_191_959_657_8, -1.702_414_383_919_315_3],
        stages: 3,
    };

    /// Kahan and Li's 9-stage sixth-order scheme (s9odr6a).
    pub const KAHAN_LI6: Scheme = Scheme {
        name: "Kahan-Li 9-stage",
        order: 6,
        half: &[
            0.392_161_444_007_314_14,
            0.332_599_136_789_359_44,
            -0.706_246_172_557_639_4,
            0.082_213_596_293_550_8,
            0.798_543_990_934_829_96,
        ],
        stages: 9,
    };

    /// Kahan and Li's 17-stage eighth-order scheme (s17odr8a).
    pub const KAHAN_LI8: Scheme = Scheme {
        name: "Kahan-Li 17-stage",
        order: 8,
        half: &[
            0.130_202_483_088_890_08,
            0.561_162_981_775_108_4,
            -0.389_474_962_644_847_3,
            0.158_841_906_555_155_6,
            -0.395_903_894_133_237_6,
            0.184_539_640_978_315_7,
            0.258_374_387_686_322_05,
            0.295_011_723_609_310_3,
            -0.605_508_533_830_034_5,
        ],
        stages: 17,
    };
}

/// The composition `Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h}` of a symmetric base method `Φ` by `scheme`.
///
/// Implements [`RotationIntegrator`](crate::RotationIntegrator) when the base does (then a
/// failing stage leaves the state as it was before the step) and
/// [`VectorIntegrator`](crate::vector::VectorIntegrator) when the base does.
#[derive(Clone, Debug)]
pub struct Composition<M> {
    pub(crate) base: M,
    pub(crate) scheme: Scheme,
    pub(crate) name: &'static str,
}

impl<M> Composition<M> {
    /// Compose `base` by `scheme`; `name` is the composed method's name.
    pub fn new(base: M, scheme: Scheme, name: &'static str) -> Self {
        Composition { base, scheme, name }
    }

    /// The scheme.
    #[must_use]
    pub fn scheme(&self) -> &Scheme {
        &self.scheme
    }

    /// The base method.
    #[must_use]
    pub fn base(&self) -> &M {
        &self.base
    }

    /// The base method, mutably (to restore its cache).
    pub fn base_mut(&mut self) -> &mut M {
        &mut self.base
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coefficients_are_palindromic_and_consistent() {
        for s in [Scheme::SUZUKI4, Scheme::YOSHIDA4, Scheme::KAHAN_LI6, Scheme::KAHAN_LI8] {
            let g: Vec<f64> = (0..s.stages()).map(|i| s.gamma(i)).collect();
            let sum: f64 = g.iter().sum();
            assert!((sum - 1.0).abs() < 4e-16, "{}: sum {sum}", s.name);
            // Third-order condition of every symmetric composition: Σ γ³ = 0.
            let cubes: f64 = g.iter().map(|x| x * x * x).sum();
            assert!(cubes.abs() < 1e-15, "{}: sum of cubes {cubes}", s.name);
            for i in 0..g.len() {
                assert_eq!(g[i], g[g.len() - 1 - i]);
            }
        }
        let c = 4f64.cbrt();
        assert!((Scheme::SUZUKI4.gamma(0) - 1.0 / (4.0 - c)).abs() < 1e-16);
        let c = 2f64.cbrt();
        assert!((Scheme::YOSHIDA4.gamma(0) - 1.0 / (2.0 - c)).abs() < 1e-15);
    }
}
