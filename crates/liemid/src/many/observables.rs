//! Observables of a many-body configuration: the radial distribution function `g(r)` and
//! the orientational order of the body-frame dipole direction.
//!
//! `g(r)` counts the pairs at distance `r` (minimum image in a periodic box) against an
//! ideal gas of the same density: `g(r_k) = n_k / (½ N ρ · 4π/3 (r_{k+1}³ − r_k³))`, so
//! `g → 1` for uncorrelated positions. The polar order is `P₁ = |Σ u_i| / N` and the nematic
//! order `P₂` the largest eigenvalue of `Q = (1/N) Σ (3/2 u_i u_iᵀ − ½ I)`, for the unit
//! directions `u_i = R_i m/|m|`.
//!
//! Reference: M. P. Allen, D. J. Tildesley, *Computer Simulation of Liquids*, 2nd ed.
//! (2017), §8.2 and §2.7.

use crate::linalg::{Mat3, Vec3};

/// A histogram of pair distances, accumulated over configurations.
#[derive(Clone, Debug)]
pub struct PairHistogram {
    r_max: f64,
    counts: Vec<u64>,
    /// Configurations added.
    pub samples: u64,
    /// Bodies per configuration (the last added).
    bodies: usize,
    /// Volume (the box's, or that of the bounding sphere of open configurations).
    volume: f64,
}

impl PairHistogram {
    /// Bins of width `r_max / bins` from 0 to `r_max`.
    #[must_use]
    pub fn new(r_max: f64, bins: usize) -> Self {
        PairHistogram {
            r_max,
            counts: vec![0; bins.max(1)],
            samples: 0,
            bodies: 0,
            volume: 0.0,
        }
    }

    /// Add the pairs of one configuration; `box_length` for a periodic cube (minimum image).
    /// Without a box the volume is that of the configuration's bounding box.
    pub fn add(&mut self, positions: &[Vec3], box_length: Option<f64>) {
        let n = positions.len();
        let bins = self.counts.len();
        let width = self.r_max / bins as f64;
        for i in 0..n {
            for j in i + 1..n {
                let mut d = positions[j] - positions[i];
                if let Some(l) = box_length {
                    d = Vec3::new(
                        d.x - l * (d.x / l).round(),
                        d.y - l * (d.y / l).round(),
                        d.z - l * (d.z / l).round(),
                    );
                }
                let r = d.norm();
                if r < self.r_max {
                    self.counts[((r / width) as usize).min(bins - 1)] += 1;
                }
            }
        }
        self.samples += 1;
        self.bodies = n;
        self.volume = match box_length {
            Some(l) => l * l * l,
            None => {
                let (lo, hi) = positions.iter().fold(
                    (
                        Vec3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
                        -Vec3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
                    ),
                    |(lo, hi), p| {
                        (
                            Vec3::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z)),
                            Vec3::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z)),
                        )
                    },
                );
                let e = hi - lo;
                (e.x * e.y * e.z).max(f64::MIN_POSITIVE)
            }
        };
    }

    /// `(r at the bin's centre, g(r))` for every bin.
    #[must_use]
    pub fn g(&self) -> Vec<(f64, f64)> {
        let bins = self.counts.len();
        let width = self.r_max / bins as f64;
        let n = self.bodies as f64;
        let density = n / self.volume;
        (0..bins)
            .map(|k| {
                let (r0, r1) = (k as f64 * width, (k + 1) as f64 * width);
                let shell = 4.0 / 3.0 * std::f64::consts::PI * (r1 * r1 * r1 - r0 * r0 * r0);
                let ideal = 0.5 * n * density * shell * self.samples as f64;
                (
                    0.5 * (r0 + r1),
                    if ideal > 0.0 {
                        self.counts[k] as f64 / ideal
                    } else {
                        0.0
                    },
                )
            })
            .collect()
    }
}

/// `(P₁, P₂)`: the polar and nematic order of the directions `R_i m / |m|`.
#[must_use]
pub fn orientational_order(rotations: &[Mat3], moment: Vec3) -> (f64, f64) {
    let n = rotations.len();
    if n == 0 || moment.norm() == 0.0 {
        return (0.0, 0.0);
    }
    let m = moment * (1.0 / moment.norm());
    let mut sum = Vec3::ZERO;
    let mut q = [[0.0f64; 3]; 3];
    for r in rotations {
        let u = *r * m;
        sum += u;
        let u = u.to_array();
        for a in 0..3 {
            for b in 0..3 {
                q[a][b] += 1.5 * u[a] * u[b];
            }
        }
    }
    for (a, row) in q.iter_mut().enumerate() {
        for (b, x) in row.iter_mut().enumerate() {
            *x = *x / n as f64 - if a == b { 0.5 } else { 0.0 };
        }
    }
    (sum.norm() / n as f64, largest_eigenvalue(q))
}

/// The largest eigenvalue of a symmetric 3×3 matrix (trigonometric closed form).
fn largest_eigenvalue(a: [[f64; 3]; 3]) -> f64 {
    let p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    let tr = a[0][0] + a[1][1] + a[2][2];
    if p1 == 0.0 {
        return a[0][0].max(a[1][1]).max(a[2][2]);
    }
    let q = tr / 3.0;
    let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b = |i: usize, j: usize| (a[i][j] - if i == j { q } else { 0.0 }) / p;
    let det = b(0, 0) * (b(1, 1) * b(2, 2) - b(1, 2) * b(2, 1)) - b(0, 1) * (b(1, 0) * b(2, 2) - b(1, 2) * b(2, 0))
        + b(0, 2) * (b(1, 0) * b(2, 1) - b(1, 1) * b(2, 0));
    let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    q + 2.0 * p * phi.cos()
}
