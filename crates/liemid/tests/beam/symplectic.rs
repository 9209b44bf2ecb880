//! Symplecticity of the explicit beam methods, measured on `T*(ℝ³ × SO(3))ⁿ`: one step of a
//! two-element cantilever (two free nodes, each a rigid body with `x`, `p`, `R`, `Π`), from a
//! generic deformed and moving state, as a map of the nodes' coordinates; its defect in the
//! canonical symplectic form (`tests/common/cotangent.rs`) at two steps. The nodes turn by
//! EA's midpoint drift, so the methods are not expected to keep the form; the test measures
//! by how much and at what order. The control is the same splitting with the nodes' exact
//! free rotation (a composition of exact flows, the kicks being the exact gradient of the
//! strain energy): its defect is two to three orders of magnitude smaller at the same
//! step, so the midpoint drift is what breaks the form. The control's own defect, 8e-8 at
//! half the critical step, falls as h⁷ and is not the differences' resolution (a few 1e-12
//! on the rigid body); its cause is not identified (a candidate: the free flow of nodes
//! whose two equal moments differ by rounding, which takes the elliptic branch), and it is
//! reported, not asserted. (Newmark carries accelerations in its state, so its step is not
//! a map of these coordinates alone; it is not measured here.)

use crate::cotangent::{defect, Body};
use liemid::beam::{problems, BeamMethod, BeamSystem};
use liemid::many::FreeRotation;
use liemid::{so3, Vec3};

fn state_of(system: &BeamSystem) -> Vec<Body> {
    let b = &system.bodies;
    (0..b.len())
        .map(|i| Body {
            x: b.position[i],
            p: b.momentum[i],
            r: b.rotation[i],
            pi: b.pi[i],
        })
        .collect()
}

#[test]
fn the_explicit_beam_methods_do_not_keep_the_symplectic_form_measured() {
    let problem = problems::cantilever_vibration(2, 1).unwrap();
    let mut base = problem.system().unwrap();
    // A generic state: bent, twisted and moving (a rest state or a pure mode would hide
    // terms of the defect by symmetry).
    {
        let b = &mut base.bodies;
        for i in 0..b.len() {
            let k = i as f64 + 1.0;
            b.position[i] += Vec3::new(0.01 * k, 0.02 * k, -0.015 * k);
            b.momentum[i] += Vec3::new(0.003, -0.002 * k, 0.004);
            b.rotation[i] = b.rotation[i] * so3::exp(Vec3::new(0.05 * k, -0.03, 0.04 * k));
            b.pi[i] += Vec3::new(1e-6 * k, -2e-6, 1.5e-6 * k);
        }
    }
    let start = state_of(&base);
    let critical = base.stability(0).critical_step(BeamMethod::Splitting);
    println!("critical step of the splitting {critical:.3e}");
    println!("method      rotation  h0/critical  defect h0   defect h0/2  order");
    let mut midpoint_defects = Vec::new();
    let mut control = f64::NAN;
    for (method, exact) in BeamMethod::ALL
        .into_iter()
        .map(|m| (m, false))
        .chain([(BeamMethod::Splitting, true)])
    {
        let h0 = 0.5 * base.stability(0).critical_step(method);
        let d: Vec<f64> = [h0, h0 / 2.0]
            .iter()
            .map(|&h| {
                let map = |s: &[Body]| -> Vec<Body> {
                    let mut system = base.clone();
                    if exact {
                        system.bodies.set_free_rotation(FreeRotation::Exact).unwrap();
                    }
                    {
                        let b = &mut system.bodies;
                        for (i, body) in s.iter().enumerate() {
                            (b.position[i], b.momentum[i], b.rotation[i], b.pi[i]) = (body.x, body.p, body.r, body.pi);
                        }
                        b.evaluate(&system.structure);
                    }
                    system.step_with(method, h).unwrap();
                    state_of(&system)
                };
                defect(&map, &start, true)
            })
            .collect();
        let order = (d[0] / d[1]).log2();
        let rotation = if exact { "exact" } else { "midpoint" };
        println!(
            "{:<11} {rotation:<9} {:<12.2} {:<11.2e} {:<12.2e} {order:.2}",
            method.key(),
            h0 / critical,
            d[0],
            d[1]
        );
        if exact {
            control = d[0];
        } else {
            midpoint_defects.push((method, d[0]));
        }
    }
    // Not symplectic: every method's defect stands a hundred times above the control's at
    // the same step (the half critical step of the splitting for the splitting itself).
    for (method, d) in midpoint_defects {
        assert!(
            d > 100.0 * control,
            "{}: defect {d:e} against the control's {control:e}",
            method.key()
        );
    }
}
