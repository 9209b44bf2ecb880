//! The structure of the many-body step with each free rotation, measured, and the
//! variational rotation's own properties:
//!
//! - the torque-free rotation of one rotor on the momentum sphere (the Lie–Poisson defect,
//!   as `tests/rigid/lie_poisson.rs` measures the rigid methods);
//! - the whole step of three interacting dipoles as a map of `(x, p, R, Π)`: its defect in
//!   the canonical form of `T*(ℝ³ × SO(3))³` (`tests/common/cotangent.rs`);
//! - with the variational rotation: one body is LIEMID[EAV], order 2 (and 4 composed)
//!   against a tight reference, time reversible to round-off, the momenta of an isolated
//!   cluster kept to round-off, the same bits on 1, 2 and 3 threads.

use crate::cotangent::{defect, Body};
use liemid::interactions::{Dipoles, Independent};
use liemid::many::{Bodies, FreeRotation};
use liemid::random::Rng;
use liemid::{rigid::problems, so3, Mat3, RotationIntegrator, RotationMethod, Scheme, Vec3};

/// The Lie–Poisson defect `max |J hat(Π) Jᵀ − hat(Π⁺)| / |Π|` of the many-body step's
/// torque-free rotation of one rotor (`I = diag(1, 2, 2.5)`, `|Π| = 2`) with `rotation`, `J`
/// by central differences extrapolated once (resolution about 1e-12 here); as
/// `tests/rigid/lie_poisson.rs` measures the rigid methods.
fn rotation_defect(rotation: FreeRotation, h: f64) -> f64 {
    let pi0 = Vec3::new(0.9, -1.1, 1.3) * (2.0 / Vec3::new(0.9, -1.1, 1.3).norm());
    let image = |pi: Vec3| {
        let mut b = Bodies::new();
        b.push(
            1.0,
            Vec3::new(1.0, 2.0, 2.5),
            false,
            Vec3::ZERO,
            Vec3::ZERO,
            Mat3::IDENTITY,
            pi,
        )
        .unwrap();
        b.set_free_rotation(rotation).unwrap();
        b.step(&Independent::torque_free(), h).unwrap();
        b.pi[0]
    };
    let central = |e: f64| {
        let cols: Vec<Vec3> = [Vec3::new(e, 0.0, 0.0), Vec3::new(0.0, e, 0.0), Vec3::new(0.0, 0.0, e)]
            .iter()
            .map(|&d| (image(pi0 + d) - image(pi0 - d)) * (0.5 / e))
            .collect();
        Mat3::from_rows([
            [cols[0].x, cols[1].x, cols[2].x],
            [cols[0].y, cols[1].y, cols[2].y],
            [cols[0].z, cols[1].z, cols[2].z],
        ])
    };
    let j = (central(1e-3) * 4.0 - central(2e-3)) * (1.0 / 3.0);
    (j * so3::hat(pi0) * j.transpose() - so3::hat(image(pi0))).max_abs() / pi0.norm()
}

#[test]
fn the_exact_and_variational_rotations_are_lie_poisson_and_the_midpoint_rotation_is_not() {
    for h in [0.2, 0.1] {
        let [exact, variational, midpoint] =
            [FreeRotation::Exact, FreeRotation::Variational, FreeRotation::Midpoint].map(|r| rotation_defect(r, h));
        println!("h = {h}: rotation defect exact {exact:.2e}, variational {variational:.2e}, midpoint {midpoint:.2e}");
        // The differences resolve about 1e-12 here (exact: 5e-13 to 6e-13).
        assert!(exact < 1e-11, "exact at h = {h}: {exact:e}");
        assert!(variational < 1e-11, "variational at h = {h}: {variational:e}");
        assert!(midpoint > 1e-7, "midpoint at h = {h}: {midpoint:e}");
    }
}

/// Three free dipoles (no cutoff, no box) with asymmetric inertia, close enough to push
/// and turn each other, every body moving and spinning: a generic state.
fn three_dipoles(rotation: FreeRotation) -> (Bodies, Dipoles) {
    let dipoles = Dipoles::new(Vec3::new(0.0, 0.0, 1.0), 1.0, 1.0, None, None).unwrap();
    let mut b = Bodies::new();
    b.set_free_rotation(rotation).unwrap();
    let place = [
        (
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.3, -0.2, 0.1),
            Vec3::new(0.3, -0.5, 0.4),
        ),
        (
            Vec3::new(1.25, 0.1, -0.05),
            Vec3::new(-0.1, 0.25, -0.2),
            Vec3::new(-0.2, 0.4, 0.6),
        ),
        (
            Vec3::new(0.55, 1.15, 0.2),
            Vec3::new(0.05, -0.15, 0.3),
            Vec3::new(0.5, 0.1, -0.3),
        ),
    ];
    for (k, (x, p, pi)) in place.into_iter().enumerate() {
        let r = so3::exp(Vec3::new(0.4 * k as f64 + 0.2, -0.3, 0.5 - 0.2 * k as f64));
        b.push(1.0, Vec3::new(0.1, 0.2, 0.25), true, x, p, r, pi).unwrap();
    }
    (b, dipoles)
}

fn state_of(b: &Bodies) -> Vec<Body> {
    (0..b.len())
        .map(|i| Body {
            x: b.position[i],
            p: b.momentum[i],
            r: b.rotation[i],
            pi: b.pi[i],
        })
        .collect()
}

/// The canonical-form defect of one step of `h` of the three dipoles with `rotation`.
fn step_defect(rotation: FreeRotation, h: f64) -> f64 {
    let (base, dipoles) = three_dipoles(rotation);
    let map = |s: &[Body]| -> Vec<Body> {
        let mut b = base.clone();
        for (i, body) in s.iter().enumerate() {
            (b.position[i], b.momentum[i], b.rotation[i], b.pi[i]) = (body.x, body.p, body.r, body.pi);
        }
        b.evaluate(&dipoles);
        b.step(&dipoles, h).unwrap();
        state_of(&b)
    };
    defect(&map, &state_of(&base), true)
}

#[test]
fn with_the_exact_or_variational_rotation_the_step_keeps_the_symplectic_form() {
    // The kicks are exact flows of the dipole energy, the translation drift the exact flow
    // of |p|²/2m; the rotation decides. The step is h = 0.04 (the fastest spin, |Ω| ≈ 3.6,
    // turns 0.14 rad) and its half.
    println!("rotation     defect h = 0.04  h = 0.02   order");
    let mut measured = Vec::new();
    for rotation in FreeRotation::ALL {
        let d = [0.04, 0.02].map(|h| step_defect(rotation, h));
        let order = (d[0] / d[1]).log2();
        println!("{:<12} {:<16.2e} {:<10.2e} {order:.2}", rotation.key(), d[0], d[1]);
        measured.push((rotation, d, order));
    }
    for (rotation, d, order) in measured {
        if rotation == FreeRotation::Midpoint {
            // Not symplectic: EA's drift changes the form at O(h³) per step.
            assert!(d[1] > 1e-8, "midpoint: defect {d:?} at the resolution");
            assert!((order - 3.0).abs() < 0.3, "midpoint: the defect falls at order {order}");
        } else {
            // The differences resolve about 1e-11 here.
            assert!(d.iter().all(|&x| x < 1e-10), "{}: defect {d:?}", rotation.key());
        }
    }
}

#[test]
fn the_variational_splitting_for_one_body_is_liemid_eav() {
    let top = problems::fast_top();
    let mut bodies = Bodies::new();
    bodies.set_free_rotation(FreeRotation::Variational).unwrap();
    let moments = top.system.inertia.principal_moments().unwrap();
    bodies
        .push(
            top.system.mass,
            moments,
            false,
            Vec3::ZERO,
            Vec3::ZERO,
            top.initial.rotation,
            top.initial.pi,
        )
        .unwrap();
    let gravity = Independent {
        gravity: top.system.gravity,
        center_of_mass: top.system.center_of_mass,
    };
    let mut eav = RotationMethod::LieVariationalAlternating.integrator();
    let mut state = top.initial;
    for _ in 0..1000 {
        bodies.step(&gravity, 1e-4).unwrap();
        eav.step(&top.system, &mut state, 1e-4).unwrap();
    }
    let dp = (bodies.pi[0] - state.pi).max_abs() / state.pi.norm();
    let dr = (bodies.rotation[0] - state.rotation).max_abs();
    assert!(dp <= 1e-15 && dr <= 1e-15, "splitting vs EAV: {dp:e} {dr:e}");
}

/// Eight free dipoles with asymmetric inertia on a jittered cube of side 1.3, random
/// attitudes, momenta and spins, no cutoff, no box, with the WCA repulsion of strength
/// `epsilon` (0 for the convergence test: the repulsion's force has a jump in its
/// derivative at `2^(1/6) σ`, which a high-order composition sees as a loss of order; 1
/// for long runs, where the dipoles would otherwise fall onto each other).
fn dipole_cube(rotation: FreeRotation, epsilon: f64) -> (Bodies, Dipoles) {
    let dipoles = Dipoles::new(Vec3::new(0.0, 0.0, 1.0), 1.0, epsilon, None, None).unwrap();
    let mut rng = Rng::new(11);
    let mut b = Bodies::new();
    b.set_free_rotation(rotation).unwrap();
    for i in 0..8 {
        let corner = Vec3::new((i % 2) as f64, ((i / 2) % 2) as f64, (i / 4) as f64) * 1.3;
        let jitter = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 0.05;
        let p = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3;
        let pi = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3;
        b.push(
            1.0,
            Vec3::new(0.1, 0.2, 0.25),
            true,
            corner + jitter,
            p,
            rng.rotation(),
            pi,
        )
        .unwrap();
    }
    (b, dipoles)
}

/// The largest difference of positions, momenta, attitudes and spins between two runs.
fn distance(a: &Bodies, b: &Bodies) -> f64 {
    (0..a.len())
        .map(|i| {
            (a.position[i] - b.position[i])
                .max_abs()
                .max((a.momentum[i] - b.momentum[i]).max_abs())
                .max((a.rotation[i] - b.rotation[i]).max_abs())
                .max((a.pi[i] - b.pi[i]).max_abs())
        })
        .fold(0.0, f64::max)
}

/// The cube after `t` in `n` steps of `rotation`, composed by `scheme` if any.
fn cube_at(rotation: FreeRotation, scheme: Option<&Scheme>, t: f64, n: usize) -> Bodies {
    let (mut b, dipoles) = dipole_cube(rotation, 0.0);
    let h = t / n as f64;
    for _ in 0..n {
        match scheme {
            None => b.step(&dipoles, h).unwrap(),
            Some(s) => b.step_composed(&dipoles, h, s).unwrap(),
        }
    }
    b
}

#[test]
fn the_variational_splitting_is_second_order_and_fourth_composed() {
    // The reference: the exact rotation composed to order 8 at 400 steps over t = 0.4 (its
    // error, against 800 steps, is printed; far below the errors measured).
    let t = 0.4;
    let reference = cube_at(FreeRotation::Exact, Some(&Scheme::KAHAN_LI8), t, 400);
    let check = cube_at(FreeRotation::Exact, Some(&Scheme::KAHAN_LI8), t, 800);
    println!("reference's own error {:.2e}", distance(&reference, &check));
    for (scheme, order, steps) in [(None, 2.0, [40, 80, 160]), (Some(&Scheme::SUZUKI4), 4.0, [40, 80, 160])] {
        let errors = steps.map(|n| distance(&cube_at(FreeRotation::Variational, scheme, t, n), &reference));
        let orders = [(errors[0] / errors[1]).log2(), (errors[1] / errors[2]).log2()];
        println!(
            "variational, order {order}: errors {:.2e} {:.2e} {:.2e}, observed orders {orders:.3?}",
            errors[0], errors[1], errors[2]
        );
        assert!(
            (orders[1] - order).abs() < 0.1,
            "observed order {orders:?} against {order}"
        );
    }
}

#[test]
fn the_variational_splitting_is_time_reversible_to_round_off() {
    let (mut b, dipoles) = dipole_cube(FreeRotation::Variational, 1.0);
    let start = b.clone();
    for _ in 0..200 {
        b.step(&dipoles, 2e-3).unwrap();
    }
    let moved = distance(&b, &start);
    for _ in 0..200 {
        b.step(&dipoles, -2e-3).unwrap();
    }
    let back = distance(&b, &start);
    println!("200 steps forward and back: moved {moved:.2e}, back to {back:.2e}");
    // Each step is symmetric up to its Newton solves' round-off: 400 steps of a few ulps of
    // an O(1) state, amplified by the cluster's sensitivity over t = 0.4.
    assert!(moved > 0.1 && back < 1e-12, "moved {moved:e}, back {back:e}");
}

#[test]
fn the_variational_splitting_keeps_the_momenta_of_an_isolated_cluster() {
    let (mut b, dipoles) = dipole_cube(FreeRotation::Variational, 1.0);
    b.evaluate(&dipoles);
    let start = b.totals(&dipoles);
    let p_scale: f64 = b.momentum.iter().map(|p| p.norm()).sum();
    let l_scale: f64 = (0..b.len())
        .map(|i| b.position[i].cross(b.momentum[i]).norm() + (b.rotation[i] * b.pi[i]).norm())
        .sum();
    let (mut dp, mut dl) = (0.0f64, 0.0f64);
    for _ in 0..2000 {
        b.step(&dipoles, 2e-3).unwrap();
        let now = b.totals(&dipoles);
        dp = dp.max((now.linear_momentum - start.linear_momentum).norm() / p_scale);
        dl = dl.max((now.angular_momentum - start.angular_momentum).norm() / l_scale);
    }
    println!("variational, 2000 steps: |ΔP| {dp:.2e}, |ΔL| {dl:.2e}");
    assert!(dp < 1e-13 && dl < 1e-13, "momenta drifted: {dp:e} {dl:e}");
}

#[test]
fn the_variational_rotation_gives_the_same_bits_on_one_two_and_three_threads() {
    // More than two chunks of bodies, so that the threads share them.
    let (dipoles, mut start) = (
        Dipoles::new(Vec3::new(0.0, 0.0, 1.0), 1.0, 1.0, Some(3.0), Some(9.1)).unwrap(),
        Bodies::new(),
    );
    start.set_free_rotation(FreeRotation::Variational).unwrap();
    let mut rng = Rng::new(7);
    for i in 0..729 {
        let (x, y, z) = (i % 9, (i / 9) % 9, i / 81);
        let pos = Vec3::new(x as f64, y as f64, z as f64) * (9.1 / 9.0);
        let p = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 0.5;
        let pi = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 0.05;
        start
            .push(1.0, Vec3::new(0.1, 0.2, 0.25), true, pos, p, rng.rotation(), pi)
            .unwrap();
    }
    let run = |threads: usize| {
        let mut b = start.clone();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            for _ in 0..20 {
                b.step(&dipoles, 2e-3).unwrap();
            }
        });
        b
    };
    let one = run(1);
    for threads in [2, 3] {
        let other = run(threads);
        assert!(
            one.position == other.position
                && one.momentum == other.momentum
                && one.rotation == other.rotation
                && one.pi == other.pi,
            "{threads} threads differ from one"
        );
    }
    // The variational rotation is really in use: the midpoint run differs.
    let mut midpoint = start.clone();
    midpoint.set_free_rotation(FreeRotation::Midpoint).unwrap();
    for _ in 0..20 {
        midpoint.step(&dipoles, 2e-3).unwrap();
    }
    assert!(midpoint.rotation != one.rotation);
}
