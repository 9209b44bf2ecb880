//! The Newton finish where `W` is not formed (free bodies with many contacts, `Local` in
//! `step.rs`): the contacts around the worst one, found breadth first through the bodies
//! they share, at most [`MOST`], their block of `W` formed from the contacts' rows, and
//! their forces solved by semismooth Newton (`newton.rs`) with every other force held. It
//! is a block Gauss–Seidel step whose block is solved exactly: a pile's slow part is a
//! cluster of bodies pressed together (a stack inside the pile), and the sweeps converge on
//! the rest.
//!
//! Reference: docs/theory/multibody.md §6.

use super::cone::{self, Response};
use super::newton::{self, Newton};

/// Most contacts in a cluster (120 rows: a Newton iteration stays near a millisecond).
pub(super) const MOST: usize = 40;

/// A response that can say which bodies a contact acts on and form the coupling block
/// `W_ij` of two contacts.
pub(super) trait Coupled: Response {
    /// The bodies contact `k` acts on (the world: `None`).
    fn bodies(&self, k: usize) -> [Option<usize>; 2];
    /// The 3x3 block of `W` coupling contact `i`'s rates to contact `j`'s force.
    fn coupling(&self, i: usize, j: usize) -> [[f64; 3]; 3];
}

/// Scratch of [`finish`].
#[derive(Clone, Debug, Default)]
pub(super) struct Cluster {
    /// Per body, the contacts on it.
    touching: Vec<Vec<usize>>,
    member: Vec<bool>,
    members: Vec<usize>,
    w: Vec<f64>,
    r0: Vec<f64>,
    mu: Vec<f64>,
    sigma: Vec<f64>,
    rates: Vec<f64>,
    newton: Newton,
}

/// Solve the cluster around the contact that violates the law most (module docs) from the
/// current forces `sigma` and rates `rates` (`r₀ + W σ` of every contact); `bodies` is the
/// number of bodies. Returns whether it changed the forces (and the response).
pub(super) fn finish<R: Coupled>(
    response: &mut R,
    bodies: usize,
    mu: &[f64],
    sigma: &mut [f64],
    rates: &[f64],
    tol: f64,
    c: &mut Cluster,
) -> bool {
    let n = mu.len();
    let mut worst = (tol, usize::MAX);
    for k in 0..n {
        let b = 3 * k;
        let v = cone::violation(&rates[b..b + 3], &sigma[b..b + 3], &mu[k..=k]);
        if v > worst.0 {
            worst = (v, k);
        }
    }
    if worst.1 == usize::MAX {
        return false;
    }
    let Cluster {
        touching,
        member,
        members,
        w,
        r0,
        mu: cmu,
        sigma: csigma,
        rates: crates,
        newton: scratch,
    } = c;
    if touching.len() < bodies {
        touching.resize_with(bodies, Vec::new);
    }
    touching.iter_mut().for_each(Vec::clear);
    for k in 0..n {
        for b in response.bodies(k).into_iter().flatten() {
            touching[b].push(k);
        }
    }
    member.clear();
    member.resize(n, false);
    members.clear();
    members.push(worst.1);
    member[worst.1] = true;
    let mut head = 0;
    while head < members.len() && members.len() < MOST {
        let k = members[head];
        head += 1;
        for b in response.bodies(k).into_iter().flatten() {
            for &j in &touching[b] {
                if !member[j] && members.len() < MOST {
                    member[j] = true;
                    members.push(j);
                }
            }
        }
    }
    let m = 3 * members.len();
    w.clear();
    w.resize(m * m, 0.0);
    for (a, &i) in members.iter().enumerate() {
        for (b, &j) in members.iter().enumerate() {
            let block = if i == j {
                response.block(i)
            } else {
                response.coupling(i, j)
            };
            for (r, row) in block.iter().enumerate() {
                w[(3 * a + r) * m + 3 * b..(3 * a + r) * m + 3 * b + 3].copy_from_slice(row);
            }
        }
    }
    csigma.clear();
    crates.clear();
    cmu.clear();
    for &k in members.iter() {
        csigma.extend_from_slice(&sigma[3 * k..3 * k + 3]);
        crates.extend_from_slice(&rates[3 * k..3 * k + 3]);
        cmu.push(mu[k]);
    }
    // r₀ of the cluster: its rates without its own forces (the others held).
    r0.clear();
    for i in 0..m {
        let own: f64 = w[i * m..(i + 1) * m]
            .iter()
            .zip(csigma.iter())
            .map(|(x, y)| x * y)
            .sum();
        r0.push(crates[i] - own);
    }
    if !newton::newton(w, r0, cmu, csigma, crates, tol, scratch) {
        return false;
    }
    let mut changed = false;
    for (a, &k) in members.iter().enumerate() {
        let delta: [f64; 3] = core::array::from_fn(|i| csigma[3 * a + i] - sigma[3 * k + i]);
        if delta != [0.0; 3] {
            sigma[3 * k..3 * k + 3].copy_from_slice(&csigma[3 * a..3 * a + 3]);
            response.add(k, delta);
            changed = true;
        }
    }
    changed
}
