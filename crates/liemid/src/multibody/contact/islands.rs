//! Contacts over free bodies grouped into islands: two contacts are in one island when a
//! chain of contacts joins them through moving bodies (static geometry joins nothing). Over
//! free bodies `W` couples only contacts that share a body, so `W` is block diagonal over
//! the islands and the cone problem splits into one independent problem per island: each
//! is solved to the same tolerance on its own (a settled island stops sweeping while
//! another is still falling), and in a small scene each island takes the dense response with
//! its finishes (`polish.rs`, `newton.rs`) at the cost of its own size, not the scene's.
//!
//! Reference: docs/theory/multibody.md §6.

use crate::inertia::Inertia;
use crate::linalg::Vec3;

use super::scratch::{Islands, Rows};

impl Islands {
    /// Group `rows` (contacts between free bodies, `bodies` of them) into islands, in the
    /// order of each island's first contact, and gather the rows and `blocks` in that order.
    pub(super) fn build(&mut self, rows: &[Rows], blocks: &[[[f64; 3]; 3]], bodies: usize) {
        self.parent.clear();
        self.parent.extend(0..bodies);
        for r in rows {
            if let (Some(a), Some(b)) = (r.a, r.b) {
                let (ra, rb) = (self.find(a), self.find(b));
                if ra != rb {
                    self.parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        self.label.clear();
        self.label.resize(bodies, usize::MAX);
        self.island_of.clear();
        self.starts.clear();
        for r in rows {
            // (A contact without a moving body has no response: an island of its own.)
            let root = r.a.or(r.b).map(|body| self.find(body));
            let island = match root.map(|root| (root, self.label[root])) {
                Some((_, island)) if island != usize::MAX => island,
                found => {
                    if let Some((root, _)) = found {
                        self.label[root] = self.starts.len();
                    }
                    self.starts.push(0);
                    self.starts.len() - 1
                }
            };
            self.starts[island] += 1;
            self.island_of.push(island);
        }
        // Counts to starts (exclusive prefix sums), then the contacts in place.
        let mut at = 0;
        for s in self.starts.iter_mut() {
            let count = *s;
            *s = at;
            at += count;
        }
        self.starts.push(at);
        self.order.clear();
        self.order.resize(rows.len(), 0);
        for (k, &island) in self.island_of.iter().enumerate() {
            self.order[self.starts[island]] = k;
            self.starts[island] += 1;
        }
        // Each start moved to the next island's: shift them back.
        for i in (1..self.starts.len()).rev() {
            self.starts[i] = self.starts[i - 1];
        }
        self.starts[0] = 0;
        self.rows.clear();
        self.rows.extend(self.order.iter().map(|&k| rows[k]));
        self.blocks.clear();
        self.blocks.extend(self.order.iter().map(|&k| blocks[k]));
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }
}

/// `W = (h/2) D M⁻¹ Dᵀ` of contacts between free bodies, dense (row-major, `3n × 3n`, into
/// `w`): the 3x3 block of contacts `k`, `l` is `h/2 Σ s_k s_l (d_kᵢ·d_lⱼ / m + t_kᵢ · I⁻¹
/// t_lⱼ)` over the bodies they share (`s = +1` on a contact's body `a`, `−1` on `b`; `t` the
/// body-frame moments of the rows).
pub(super) fn dense_w(mass: &[f64], inertia: &[Inertia], rows: &[Rows], hh: f64, w: &mut Vec<f64>) {
    let m = 3 * rows.len();
    w.clear();
    w.resize(m * m, 0.0);
    let sides = |r: &Rows| [(r.a, r.ta, 1.0), (r.b, r.tb, -1.0)];
    for (l, rl) in rows.iter().enumerate() {
        for (body_l, tl, sl) in sides(rl) {
            let Some(i) = body_l else { continue };
            let inv_m = 1.0 / mass[i];
            let it: [Vec3; 3] = core::array::from_fn(|j| inertia[i].apply_inverse(tl[j]));
            for (k, rk) in rows.iter().enumerate() {
                for (body_k, tk, sk) in sides(rk) {
                    if body_k != Some(i) {
                        continue;
                    }
                    let s = sk * sl * hh;
                    for r in 0..3 {
                        for c in 0..3 {
                            w[(3 * k + r) * m + 3 * l + c] += s * (rk.dir[r].dot(rl.dir[c]) * inv_m + tk[r].dot(it[c]));
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::Rng;

    fn rows(a: Option<usize>, b: Option<usize>, rng: &mut Rng) -> Rows {
        let mut v = || Vec3::new(rng.normal(), rng.normal(), rng.normal());
        Rows {
            a,
            b,
            dir: [v(), v(), v()],
            ta: [v(), v(), v()],
            tb: [v(), v(), v()],
        }
    }

    /// Contacts join an island through the moving bodies they share, never through static
    /// geometry; islands come in the order of their first contact, each in contact order.
    #[test]
    fn islands_join_contacts_through_moving_bodies_only() {
        let mut rng = Rng::new(7);
        let pairs = [
            (Some(0), Some(1)),
            (Some(2), None),
            (Some(3), Some(1)),
            (None, Some(2)),
            (Some(4), None),
            (Some(0), None),
            (Some(5), None),
            (Some(5), Some(3)),
        ];
        let rows: Vec<Rows> = pairs.iter().map(|&(a, b)| rows(a, b, &mut rng)).collect();
        let blocks: Vec<[[f64; 3]; 3]> = (0..rows.len()).map(|k| [[k as f64; 3]; 3]).collect();
        let mut islands = Islands::default();
        islands.build(&rows, &blocks, 6);
        assert_eq!(islands.order, [0, 2, 5, 6, 7, 1, 3, 4]);
        assert_eq!(islands.starts, [0, 5, 7, 8]);
        for (j, &k) in islands.order.iter().enumerate() {
            assert_eq!(islands.blocks[j], blocks[k]);
            assert_eq!((islands.rows[j].a, islands.rows[j].b), pairs[k]);
        }
        // Built again (fewer bodies, fewer contacts), nothing of the last build is left.
        islands.build(&rows[1..2], &blocks[1..2], 3);
        assert_eq!(
            (islands.order.as_slice(), islands.starts.as_slice()),
            (&[0][..], &[0, 1][..])
        );
    }

    /// `W`'s column of a row is the rates of all rows after a half-kick by a unit force on
    /// that row, the bodies free: `dense_w` against that definition, on contacts between
    /// bodies of unequal mass and full inertia tensors, to round-off; and `W` is symmetric.
    #[test]
    fn dense_w_is_the_rates_of_unit_half_kicks() {
        let mut rng = Rng::new(11);
        let bodies = 4;
        let mass: Vec<f64> = (0..bodies).map(|i| 0.5 + i as f64).collect();
        let inertia: Vec<Inertia> = (0..bodies)
            .map(|i| {
                let d = 0.1 * (1.0 + i as f64);
                Inertia::from_matrix([
                    [2.0 * d, 0.1 * d, 0.0],
                    [0.1 * d, 3.0 * d, 0.2 * d],
                    [0.0, 0.2 * d, 4.0 * d],
                ])
                .unwrap()
            })
            .collect();
        let pairs = [
            (Some(0), Some(1)),
            (Some(1), None),
            (Some(2), Some(1)),
            (None, Some(2)),
            (Some(3), Some(0)),
        ];
        let rows: Vec<Rows> = pairs.iter().map(|&(a, b)| rows(a, b, &mut rng)).collect();
        let hh = 5e-4;
        let mut w = Vec::new();
        dense_w(&mass, &inertia, &rows, hh, &mut w);
        let m = 3 * rows.len();
        let largest = w.iter().fold(0.0f64, |x, y| x.max(y.abs()));
        for col in 0..m {
            let (mut lin, mut ang) = (vec![Vec3::ZERO; bodies], vec![Vec3::ZERO; bodies]);
            rows[col / 3].apply(col % 3, hh, &mut lin, &mut ang);
            let vel: Vec<Vec3> = lin.iter().zip(&mass).map(|(p, m)| *p * (1.0 / m)).collect();
            let omega: Vec<Vec3> = ang.iter().zip(&inertia).map(|(l, i)| i.apply_inverse(*l)).collect();
            for row in 0..m {
                let rate = rows[row / 3].rate(row % 3, &vel, &omega);
                assert!((w[row * m + col] - rate).abs() <= 1e-14 * largest, "W[{row}][{col}]");
                assert!((w[row * m + col] - w[col * m + row]).abs() <= 1e-14 * largest);
            }
        }
        // Contacts 3 and 4 share no body: their block is zero.
        assert!((0..3).all(|i| (0..3).all(|j| w[(9 + i) * m + 12 + j] == 0.0)));
    }
}
