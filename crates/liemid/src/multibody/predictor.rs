//! The start of the position solve: the multipliers `λ` extrapolated from the converged
//! values of the last stages (only the iteration's start: the solution is the same to
//! round-off), so that a stage usually takes one or two quasi-Newton iterations.
//!
//! Reference: docs/theory/multibody.md §3; E. Hairer, C. Lubich, G. Wanner, *Geometric
//! Numerical Integration*, 2nd ed., Springer 2006, VII.1 (starting approximations).

use super::workspace::{Workspace, HISTORY};

/// `BINOMIAL[n - 1][j] = (−1)ʲ C(n, j + 1)`: the weights of the polynomial extrapolation
/// through `n` equally spaced values, newest first (`λ = Σ_j w_j λₙ₋ⱼ`).
const BINOMIAL: [[f64; HISTORY]; HISTORY] = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [2.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0, -3.0, 1.0, 0.0, 0.0, 0.0, 0.0],
    [4.0, -6.0, 4.0, -1.0, 0.0, 0.0, 0.0],
    [5.0, -10.0, 10.0, -5.0, 1.0, 0.0, 0.0],
    [6.0, -15.0, 20.0, -15.0, 6.0, -1.0, 0.0],
    [7.0, -21.0, 35.0, -35.0, 21.0, -7.0, 1.0],
];

/// The polynomial extrapolation to the next of equally spaced values, newest first:
/// constant, linear, ..., degree `n − 1` through the first `n = same` of `hist` (at most
/// `hist.len() ≤ HISTORY`).
#[inline]
pub(super) fn extrapolate(same: usize, hist: &[[f64; 6]]) -> [f64; 6] {
    let n = same.clamp(1, hist.len());
    let w = &BINOMIAL[n - 1];
    let mut out = [0.0; 6];
    for (wj, hj) in w[..n].iter().zip(hist) {
        for (o, v) in out.iter_mut().zip(hj) {
            *o += wj * v;
        }
    }
    out
}

/// Shift `new` in at the front of a history (newest first), dropping the oldest.
#[inline]
pub(super) fn push_front<T: Copy, const N: usize>(hist: &mut [T; N], new: T) {
    hist.copy_within(0..N - 1, 1);
    hist[0] = new;
}

/// How many of the latest `steps` (newest first) equal `h` to `1e-9` relative.
fn same_steps(steps: &[f64], h: f64) -> usize {
    steps.iter().take_while(|&&s| (s - h).abs() <= 1e-9 * h.abs()).count()
}

impl Workspace {
    /// The start of the position solve, an extrapolation of earlier converged `λ` (only
    /// the iteration's start: the solution is the same to round-off).
    ///
    /// - Stage `k` of a composition, after steps of the same `h` whose stage `k` converged
    ///   with the same rows: the polynomial of degree 6 through stage `k` of the last
    ///   [`HISTORY`] = 7 steps, `λ = 7 λₙ − 21 λₙ₋₁ + 35 λₙ₋₂ − 35 λₙ₋₃ + 21 λₙ₋₄ − 7 λₙ₋₅ +
    ///   λₙ₋₆` (an `O(h⁷)` error; the one through fewer values after fewer such steps). The
    ///   stages of one step differ in their sub-step (and sign), and RATTLE's `λ` is the
    ///   constraint force plus a term odd in the sub-step, so the previous stage's `λ` is a
    ///   poor start there.
    /// - Otherwise (the base step, or a composition's first steps): the cubic
    ///   `λ = 4 λₙ − 6 λₙ₋₁ + 4 λₙ₋₂ − λₙ₋₃` over the last stages when they took the same
    ///   step `h` with the same rows (the quadratic or linear one after three or two, the
    ///   previous `λ` after fewer). At the base step's usual small steps the cubic's error is
    ///   already near the round-off of the converged values, which the higher degrees
    ///   amplify (iterations per step at h = 1e-4, degree 3 / 4 / 6: spacecraft 0.80 / 0.85 /
    ///   0.97, chain-1000 0.93 / 1.00 / 1.00).
    ///
    /// Steps count as the same when they agree to `1e-9` relative (a driver's steps
    /// `t_{k+1} − t_k` differ from `h` in the last bits). Returns whether the start is an
    /// extrapolation (the last `λ` is then in `lambda_prev[..][0]`: a position solve that
    /// fails from the extrapolation is restarted from it) and how many of a stage's
    /// converged values it used (0 for the base step's). On the spacecraft (liemid6,
    /// `h = 2.5e-3`) the degree-6 start took 2.0 quasi-Newton iterations per stage, the
    /// cubic 3.1, the quadratic 3.7 and the previous stage's `λ` 4.6
    /// (`examples/profile_multibody.rs`).
    pub(super) fn start_multipliers(&mut self, h: f64, stage: Option<(usize, f64)>) -> (bool, usize) {
        if let Some((k, step)) = stage {
            let same = same_steps(&self.scheme_steps, step);
            if same > 0 {
                let nj = self.lambda.len();
                let hist = &self.stage_lambda[k * nj..(k + 1) * nj];
                // The higher degree only where it agrees with the cubic to a tenth of the
                // cubic's change from the last value: a history that is not smooth on the
                // step's scale (steps too long for the motion) keeps the cubic.
                let (mut gap, mut change) = (0.0f64, 0.0f64);
                if same > 4 {
                    for hist in hist {
                        let (high, cubic) = (extrapolate(same, hist), extrapolate(4, hist));
                        for r in 0..6 {
                            gap = gap.max((high[r] - cubic[r]).abs());
                            change = change.max((cubic[r] - hist[0][r]).abs());
                        }
                    }
                }
                let points = if gap <= 0.1 * change { same } else { 4 };
                for ((l, prev), hist) in self.lambda.iter_mut().zip(&mut self.lambda_prev).zip(hist) {
                    push_front(prev, *l);
                    *l = extrapolate(points, hist);
                }
                return (true, points);
            }
        }
        let same = same_steps(&self.lambda_steps, h);
        for (l, prev) in self.lambda.iter_mut().zip(&mut self.lambda_prev) {
            let hist = [*l, prev[0], prev[1], prev[2]];
            *prev = [hist[0], hist[1], hist[2]];
            if same >= 2 {
                *l = extrapolate(same, &hist);
            }
        }
        (same >= 2, 0)
    }
}
