//! The Lie–Poisson structure of every rotation method, measured: the torque-free map
//! `Φ: Π ↦ Π⁺` of one step (the body momentum evolves on its own when there is no torque)
//! is a Lie–Poisson map exactly when its Jacobian `J = DΦ(Π)` carries the Poisson tensor
//! `B(Π) = hat(Π)` of so(3)* to the one at the image: `J hat(Π) Jᵀ = hat(Φ(Π))`
//! (docs/theory/rigid.md §9). The defect `max |J hat(Π) Jᵀ − hat(Φ(Π))| / |Π|` is measured
//! at `|Π| = 2`:
//!
//! - for every method of `RotationMethod::ALL`, on the method's own step, on the body
//!   `I = diag(1, 2, 2.5)`, with `J` from central differences extrapolated once
//!   (Richardson), which resolve about 1e-10;
//! - for the drifts (M) and (V) themselves on `I = diag(1, 2, 3.5)` (the moments the defect
//!   was first measured on; not a physical body, 3.5 > 1 + 2, which the equations do not
//!   need) with the exact `J` from the implicit function theorem at the solver's root,
//!   which resolves round-off.
//!
//! A method is called Lie–Poisson (symplectic on the momentum sphere) only where the defect
//! is at that resolution; the docs' table (docs/rigid.md) is this test's output.

use liemid::so3::{self, hat};
use liemid::{
    midpoint, variational, FreeBody, Inertia, Mat3, PrincipalInertia, RigidState, RotationIntegrator, RotationMethod,
    Vec3,
};

fn body() -> FreeBody {
    FreeBody::new(Inertia::principal([1.0, 2.0, 2.5]).unwrap())
}

/// The moments of the drifts' exact test.
fn moments() -> Vec3 {
    Vec3::new(1.0, 2.0, 3.5)
}

/// A momentum of norm 2 off every principal axis.
fn start() -> Vec3 {
    let v = Vec3::new(0.9, -1.1, 1.3);
    v * (2.0 / v.norm())
}

/// One torque-free step of `method` from `Π` (attitude irrelevant).
fn map(method: RotationMethod, pi: Vec3, h: f64) -> Vec3 {
    let mut integrator = method.integrator();
    let mut state = RigidState::new(0.0, pi, Mat3::IDENTITY);
    integrator.step(&body(), &mut state, h).unwrap();
    state.pi
}

/// `DΦ` by central differences at `e` and `e/2`, extrapolated: error `O(e⁴)` plus round-off
/// `u |Π| / e`.
fn jacobian_fd(f: impl Fn(Vec3) -> Vec3, x: Vec3) -> Mat3 {
    let central = |e: f64| {
        let cols: Vec<Vec3> = (0..3)
            .map(|k| {
                let d = [Vec3::new(e, 0.0, 0.0), Vec3::new(0.0, e, 0.0), Vec3::new(0.0, 0.0, e)][k];
                (f(x + d) - f(x - d)) * (0.5 / e)
            })
            .collect();
        Mat3::from_rows([
            [cols[0].x, cols[1].x, cols[2].x],
            [cols[0].y, cols[1].y, cols[2].y],
            [cols[0].z, cols[1].z, cols[2].z],
        ])
    };
    let (coarse, fine) = (central(2e-3), central(1e-3));
    (fine * 4.0 - coarse) * (1.0 / 3.0)
}

/// The Lie–Poisson defect of a map with Jacobian `j` at `pi` (image `image`).
fn defect(j: &Mat3, pi: Vec3, image: Vec3) -> f64 {
    (*j * hat(pi) * j.transpose() - hat(image)).max_abs() / pi.norm()
}

/// The methods whose torque-free map is claimed Lie–Poisson: the exact free flow with
/// impulses (EX), Fassò's split of the free flow (FS), the variational drift (EAV), and
/// their compositions.
fn claimed_poisson(method: RotationMethod) -> bool {
    let key = method.key();
    key.starts_with("liemid-ex") || key.starts_with("liemid-fs") || key.starts_with("liemid-eav")
}

#[test]
fn every_method_measured_only_the_claimed_ones_are_lie_poisson() {
    // A defect that is not structural falls with the method's order (`h^(p+1)` per step),
    // so the high-order compositions are measured at larger steps to stand clear of the
    // resolution: h₀ = 0.2 for order ≤ 2, 0.4 for order 4, 0.8 for order 6, 1.2 for order 8
    // (the defect then falls as h^(p+1) between h₀ and h₀/2, and the test prints the order).
    let pi = start();
    println!("method        claim          h0    defect h0   defect h0/2  order");
    for method in RotationMethod::ALL {
        let h0 = match method.order() {
            0..=2 => 0.2,
            3..=4 => 0.4,
            5..=6 => 0.8,
            _ => 1.2,
        };
        let d: Vec<f64> = [h0, h0 / 2.0]
            .iter()
            .map(|&h| {
                let j = jacobian_fd(|x| map(method, x, h), pi);
                defect(&j, pi, map(method, pi, h))
            })
            .collect();
        let order = (d[0] / d[1]).log2();
        let claim = if claimed_poisson(method) {
            "Lie-Poisson"
        } else {
            "not Poisson"
        };
        println!(
            "{:<13} {claim:<14} {h0:<5} {:<11.2e} {:<12.2e} {order:.2}",
            method.key(),
            d[0],
            d[1]
        );
        if claimed_poisson(method) {
            // The finite differences' resolution: the extrapolated error e⁴ f⁽⁵⁾ and the
            // round-off u |Π| / e (e = 1e-3) are near 1e-13; EA8's measured defect at h = 0.4
            // is 2e-13.
            assert!(d.iter().all(|&x| x < 1e-11), "{}: defect {d:?}", method.key());
        } else {
            // Measured, well above the resolution: the claim "not Lie-Poisson" holds.
            assert!(d[0] > 1e-10, "{}: defect {d:?} is at the resolution", method.key());
        }
    }
}

#[test]
fn the_midpoint_drift_has_a_defect_of_order_h_cubed_and_the_variational_none() {
    // Exact Jacobians of one torque-free step of (M) and of (V) at the solver's root:
    // g(Ψ, P) = 0 gives dΨ/dP = (∂g/∂Ψ)⁻¹ h ∂(rhs)/∂P, and Π⁺ = exp(−Ψ) P gives
    // dΠ⁺/dP = exp(−Ψ) + exp(−Ψ) hat(P) Jr(−Ψ) dΨ/dP.
    let inertia = PrincipalInertia::new(moments());
    let pi = start();
    let image_and_jacobian = |psi: Vec3, dpsi: Mat3| {
        let e = so3::exp(-psi);
        (e * pi, e + e * hat(pi) * so3::right_jacobian(-psi) * dpsi)
    };
    let midpoint_step = |h: f64| {
        let (psi, _) = midpoint::solve(&inertia, pi, h).unwrap();
        // ∂g/∂Ψ = I − (h/2) exp(−Ψ/2) hat(P) Jr(−Ψ/2) (crate::midpoint::jacobian).
        let half = -psi * 0.5;
        let dg = Mat3::from_diagonal(moments()) - so3::exp(half) * hat(pi) * so3::right_jacobian(half) * (0.5 * h);
        let dpsi = dg.inverse().unwrap() * so3::exp(-psi * 0.5) * h;
        image_and_jacobian(psi, dpsi)
    };
    let variational_step = |h: f64| {
        let (inc, _) = variational::solve_increment(&inertia, pi, h).unwrap();
        let psi = inc.psi();
        let dpsi = variational::jacobian(&inertia, pi, h, psi).inverse().unwrap() * so3::right_jacobian(psi) * h;
        image_and_jacobian(psi, dpsi)
    };
    let mut previous: Option<f64> = None;
    for h in [0.2, 0.1, 0.05, 0.025] {
        let (image, j) = midpoint_step(h);
        let d_m = defect(&j, pi, image);
        let (image, j) = variational_step(h);
        let d_v = defect(&j, pi, image);
        println!("h = {h:<6} (M) defect {d_m:.3e}   (V) defect {d_v:.3e}");
        assert!(d_v < 1e-13, "(V) at h = {h}: {d_v:e}");
        if let Some(p) = previous {
            let order = (p / d_m).log2();
            assert!((order - 3.0).abs() < 0.1, "(M) defect order {order} at h = {h}");
        }
        previous = Some(d_m);
    }
}

#[test]
fn the_exact_jacobian_agrees_with_the_differences_on_the_methods_own_step() {
    // The implicit-function Jacobian of (V) is the Jacobian of what the code computes: both
    // measure the same defect for EAV's single drift.
    let inertia = PrincipalInertia::new(moments());
    let pi = start();
    let h = 0.1;
    let step = |x: Vec3| {
        let (inc, _) = variational::solve_increment(&inertia, x, h).unwrap();
        inc.inverse_apply(x)
    };
    let fd = jacobian_fd(step, pi);
    let (inc, _) = variational::solve_increment(&inertia, pi, h).unwrap();
    let psi = inc.psi();
    let dpsi = variational::jacobian(&inertia, pi, h, psi).inverse().unwrap() * so3::right_jacobian(psi) * h;
    let e = so3::exp(-psi);
    let exact = e + e * hat(pi) * so3::right_jacobian(-psi) * dpsi;
    assert!((fd - exact).max_abs() < 1e-9, "{:e}", (fd - exact).max_abs());
}
