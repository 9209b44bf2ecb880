//! A small, seeded, reproducible random number generator (SplitMix64) for test problems,
//! ensembles of initial conditions and property tests. Not for cryptography.

use crate::linalg::{Mat3, Vec3};
use crate::so3::Quaternion;

/// SplitMix64: a 64-bit state, full period, passes BigCrush; the same seed gives the same
/// sequence on every platform.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

impl Rng {
    /// A generator seeded with `seed`.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Rng { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // in (0, 1]
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// A uniformly distributed unit vector.
    pub fn unit_vector(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.normal(), self.normal(), self.normal());
            let n = v.norm();
            if n > 1e-12 {
                return v * (1.0 / n);
            }
        }
    }

    /// A uniformly distributed (Haar) random rotation, from a normalised Gaussian
    /// quaternion.
    pub fn rotation(&mut self) -> Mat3 {
        let q = Quaternion::new(self.normal(), self.normal(), self.normal(), self.normal());
        q.normalized().to_matrix()
    }
}
