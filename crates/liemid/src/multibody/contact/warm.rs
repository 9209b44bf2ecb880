//! The warm start of the contact problems: each contact found again since the last step
//! starts from its last force (docs/theory/multibody.md §6).

use super::super::constraints::JointRows;
use super::super::system::MultibodySystem;
use super::detect::ContactPoint;
use super::response::free_bodies;

/// How far a contact may have moved since the last step and still start from its force.
/// On free bodies [`WarmReach::Exact`] (a resting contact): measured on 100 spheres falling
/// into a bin, seeds 1-3 to 2 s, a reach of `1e-3` (in the position solve, taking a
/// contact's force once it had been found two steps running) cost 3.2 → 3.9-4.4 position
/// iterations a step and 6.7-9.8 → 8.0-13.3 s, and a pile of boxes and spheres (seed 2)
/// penetrated 4.3e-5 m. On jointed bodies [`WarmReach::Near`]: a standing robot's foot
/// rocks on its sphere by more than `1e-9` of the length a step, and without its force each
/// drift of the contact iteration re-solved the joints' multipliers from a residual of
/// 3.9e-3 (the standing quadruped: 1.9 → 1.2 contact iterations a step, 342 → 244 µs a
/// step; the humanoid lying on the floor: 653 → 572 µs, 132 → 2 steps at the acceptance).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum WarmReach {
    /// The same bodies, each material point within `1e-9` of the length and the normal in
    /// `b`'s frame within `1e-9`: the first such contact.
    Exact,
    /// The same bodies, the material points' moves summing to at most `1e-3` of the length
    /// and the normal within `1e-3`: the nearest such, its friction carried into the new
    /// tangents.
    Near,
}

impl WarmReach {
    /// [`WarmReach::Near`] where the bodies are jointed (joint rows or armature), else
    /// [`WarmReach::Exact`].
    pub(super) fn of(sys: &MultibodySystem, rows: &[JointRows]) -> WarmReach {
        if free_bodies(sys, rows) {
            WarmReach::Exact
        } else {
            WarmReach::Near
        }
    }
}

/// Start each of `points` from the force of the nearest contact in `last` within `reach`
/// (the same bodies; the material points and the normal in `b`'s frame moved by at most
/// `reach`): `sigma`, its friction carried into the new tangents (zero elsewhere). `order`
/// is scratch: `last` sorted by its bodies, searched by bisection.
pub(super) fn warm(
    points: &[ContactPoint],
    last: &[ContactPoint],
    last_sigma: &[f64],
    length: f64,
    reach: WarmReach,
    sigma: &mut [f64],
    order: &mut Vec<(f64, usize)>,
) {
    let key = |p: &ContactPoint| (p.a.unwrap_or(usize::MAX), p.b.unwrap_or(usize::MAX));
    let exact = reach == WarmReach::Exact;
    let (close, turn) = if exact {
        (1e-9 * length, 1e-9)
    } else {
        (1e-3 * length, 1e-3)
    };
    order.clear();
    order.extend((0..last.len()).map(|j| (0.0, j)));
    order.sort_unstable_by_key(|&(_, j)| (key(&last[j]), j));
    for (k, p) in points.iter().enumerate() {
        let want = key(p);
        let from = order.partition_point(|&(_, j)| key(&last[j]) < want);
        let mut nearest: Option<(f64, usize)> = None;
        for &(_, j) in order[from..].iter().take_while(|&&(_, j)| key(&last[j]) == want) {
            let q = &last[j];
            let (da, db) = ((q.pa - p.pa).norm(), (q.pb - p.pb).norm());
            let within = if exact {
                // Each point to round-off, the first such (as this start always was).
                da <= close && db <= close
            } else {
                da + db <= close
            };
            if within && (q.nb - p.nb).norm() <= turn && nearest.is_none_or(|(d, _)| da + db < d) {
                nearest = Some((da + db, j));
                if exact {
                    break;
                }
            }
        }
        if let Some((_, j)) = nearest {
            let (q, last) = (&last[j], &last_sigma[3 * j..3 * j + 3]);
            let friction = q.t1 * last[1] + q.t2 * last[2];
            sigma[3 * k] = last[0];
            if exact {
                sigma[3 * k + 1] = last[1];
                sigma[3 * k + 2] = last[2];
            } else {
                sigma[3 * k + 1] = friction.dot(p.t1);
                sigma[3 * k + 2] = friction.dot(p.t2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{warm, WarmReach};
    use crate::linalg::Vec3;
    use crate::multibody::contact::detect::{tangents, ContactPoint};

    /// A foot's contact that rocked by `1e-6` of the length and turned its normal by `1e-4`
    /// starts from its last force under [`WarmReach::Near`] (the nearest of two candidates,
    /// the friction force the same vector in the new tangents) and from zero under
    /// [`WarmReach::Exact`]; one that did not move starts from its force under both.
    #[test]
    fn a_contact_that_moved_a_little_starts_from_its_last_force_where_the_reach_allows() {
        let point = |pa: Vec3, nb: Vec3| {
            let (t1, t2) = tangents(nb);
            ContactPoint {
                a: Some(3),
                b: None,
                pa,
                nb,
                t1,
                t2,
                ..ContactPoint::default()
            }
        };
        let n0 = Vec3::new(0.0, 0.0, 1.0);
        let n1 = Vec3::new(1e-4, 0.0, 1.0);
        let n1 = n1 * (1.0 / n1.norm());
        let last = [
            point(Vec3::new(0.0, 0.0, -0.02), n0),
            point(Vec3::new(5e-4, 0.0, -0.02), n0),
        ];
        let last_sigma = [5.0, 0.3, -0.4, 7.0, 0.0, 0.0];
        let moved = [point(Vec3::new(1e-6, 0.0, -0.02), n1)];
        let (mut sigma, mut order) = ([0.0; 3], Vec::new());
        warm(&moved, &last, &last_sigma, 1.0, WarmReach::Near, &mut sigma, &mut order);
        assert_eq!(sigma[0], 5.0);
        let friction = |p: &ContactPoint, s: &[f64]| p.t1 * s[1] + p.t2 * s[2];
        let (was, now) = (friction(&last[0], &last_sigma), friction(&moved[0], &sigma));
        // The new tangents span the old friction force but for its part along the turned
        // normal (1e-4 of it).
        assert!((was - now).norm() <= 1e-4 * was.norm(), "{was:?} → {now:?}");
        sigma = [0.0; 3];
        warm(
            &moved,
            &last,
            &last_sigma,
            1.0,
            WarmReach::Exact,
            &mut sigma,
            &mut order,
        );
        assert_eq!(sigma, [0.0; 3]);
        for reach in [WarmReach::Exact, WarmReach::Near] {
            sigma = [0.0; 3];
            warm(&last[1..], &last, &last_sigma, 1.0, reach, &mut sigma, &mut order);
            assert_eq!(sigma, [7.0, 0.0, 0.0]);
        }
    }
}
