//! Contact with Coulomb friction (docs/theory/multibody.md §9) against closed forms.

use liemid::multibody::{mjcf, Model, MultibodyMethod, Simulation};

const G: f64 = 9.81;

/// A 1 kg box of half-edge 0.1 m on a floor tilted by `slope` (rad) about y, friction `mu`,
/// starting at rest on it (its centre 0.1 m above the plane) with velocity `v0` down the
/// slope's x axis.
fn box_on_plane(mu: f64, slope: f64, v0: f64) -> Model {
    let (s, c) = slope.sin_cos();
    // The plane's attitude: a turn by `slope` about y (its normal (s, 0, c)... tilted so
    // that x goes downhill).
    let (nx, nz) = (s, c);
    let (px, pz) = (0.1 * nx, 0.1 * nz);
    let half = slope / 2.0;
    let (qw, qy) = (half.cos(), half.sin());
    let (vx, vz) = (v0 * c, -v0 * s);
    let text = format!(
        "<mujoco><worldbody><geom name=\"floor\" type=\"plane\" size=\"0 0 1\" euler=\"0 {deg} 0\" friction=\"{mu}\"/>\
         <body name=\"box\"><freejoint/><geom type=\"box\" size=\"0.1 0.1 0.1\" mass=\"1\" friction=\"{mu}\"/></body>\
         </worldbody><keyframe><key qpos=\"{px} 0 {pz} {qw} 0 {qy} 0\" qvel=\"{vx} 0 {vz} 0 0 0\"/></keyframe></mujoco>",
        deg = slope.to_degrees(),
    );
    mjcf::parse(&text, "box.xml").unwrap().model
}

/// Run `model` by `liemid` at step `h` for `steps` steps; the centre of mass of body 0 in the
/// plane's frame (x downhill, z along the normal) at each step, and the largest contact count.
fn run_box(model: &Model, slope: f64, h: f64, steps: usize) -> (Vec<[f64; 3]>, u32) {
    let prepared = Simulation::prepare(model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let (sn, cs) = slope.sin_cos();
    let frame = |c: liemid::linalg::Vec3| [c.x * cs - c.z * sn, c.y, c.x * sn + c.z * cs];
    let mut out = vec![frame(s.c[0])];
    let mut most = 0;
    for _ in 0..steps {
        let report = sim.step(&mut s, h).unwrap();
        most = most.max(report.contacts);
        out.push(frame(s.c[0]));
    }
    (out, most)
}

#[test]
fn a_box_launched_on_a_floor_stops_at_the_closed_form_distance_and_rests_at_its_height() {
    let (mu, v0, h) = (0.4, 2.0, 1e-3);
    let (path, contacts) = run_box(&box_on_plane(mu, 0.0, v0), 0.0, h, 1000);
    assert_eq!(contacts, 4, "a box face on the floor: four corners");
    let stop = v0 * v0 / (2.0 * mu * G);
    let end = path.last().unwrap();
    // Kick-drift-kick is exact under the constant friction force; only the stopping step
    // errs, by at most µ g h².
    assert!(
        (end[0] - path[0][0] - stop).abs() <= mu * G * h * h,
        "stopped after {} m, closed form {stop} m",
        end[0] - path[0][0]
    );
    let height = path.iter().fold(0.0f64, |m, p| m.max((p[2] - 0.1).abs()));
    assert!(height <= 1e-12, "the box left its resting height by {height:e} m");
    // At rest after t = v0/(µ g) = 0.51 s: no creep.
    let rest = &path[600..];
    let creep = rest.iter().fold(0.0f64, |m, p| m.max((p[0] - rest[0][0]).abs()));
    assert!(creep <= 1e-12, "crept {creep:e} m at rest");
}

#[test]
fn a_box_on_a_slope_below_its_friction_angle_never_moves() {
    // tan 20° = 0.364 < µ = 0.5: Coulomb says it sticks.
    let slope = 20f64.to_radians();
    let (path, _) = run_box(&box_on_plane(0.5, slope, 0.0), slope, 1e-3, 10_000);
    let moved = path.iter().fold(0.0f64, |m, p| {
        m.max((p[0] - path[0][0]).abs()).max((p[2] - path[0][2]).abs())
    });
    assert!(moved <= 1e-9, "moved {moved:e} m in 10 s");
}

#[test]
fn a_box_on_a_steeper_slope_slides_at_the_closed_form_acceleration() {
    // µ = 0.3 < tan 20°: a = g (sin θ − µ cos θ), from rest.
    let (mu, slope, h) = (0.3, 20f64.to_radians(), 1e-3);
    let (path, _) = run_box(&box_on_plane(mu, slope, 0.0), slope, h, 1000);
    let a = G * (slope.sin() - mu * slope.cos());
    for (k, p) in path.iter().enumerate().skip(1) {
        let t = k as f64 * h;
        let expected = 0.5 * a * t * t;
        let got = p[0] - path[0][0];
        assert!(
            (got - expected).abs() <= 1e-6 * expected,
            "t = {t}: {got} m, closed form {expected} m"
        );
    }
}

#[test]
fn two_balls_in_an_oblique_impact_keep_their_momenta_and_lose_energy() {
    // No gravity; a ball of 1 kg and one of 2 kg, friction 0.5, meeting off-centre with a
    // spin: every contact force acts on both at one point, so the total linear and angular
    // momentum stay to round-off; the plastic impact and the friction dissipate.
    let text = "<mujoco><option gravity=\"0 0 0\"/><worldbody>\
        <body name=\"a\"><freejoint/><geom type=\"sphere\" size=\"0.1\" mass=\"1\" friction=\"0.5\"/></body>\
        <body name=\"b\" pos=\"0.3 0.05 0\"><freejoint/><geom type=\"sphere\" size=\"0.12\" mass=\"2\" friction=\"0.5\"/></body>\
        </worldbody><keyframe><key qpos=\"0 0 0 1 0 0 0 0.3 0.05 0 1 0 0 0\" qvel=\"1.5 0 0.2 0 0 3 -0.5 0 0 1 0 0\"/></keyframe></mujoco>";
    let model = mjcf::parse(text, "balls.xml").unwrap().model;
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let (p0, l0, e0) = (
        sim.system.linear_momentum(&s),
        sim.system.angular_momentum(&s),
        sim.system.energy(&s),
    );
    let mut touched = 0;
    let mut e_prev = e0;
    for _ in 0..400 {
        let report = sim.step(&mut s, 1e-3).unwrap();
        touched = touched.max(report.contacts);
        let e = sim.system.energy(&s);
        assert!(e <= e_prev * (1.0 + 1e-14), "energy gained: {e_prev} -> {e}");
        e_prev = e;
        let dp = (sim.system.linear_momentum(&s) - p0).norm();
        let dl = (sim.system.angular_momentum(&s) - l0).norm();
        assert!(dp <= 1e-14 && dl <= 1e-14, "momenta changed by {dp:e}, {dl:e}");
    }
    assert!(touched > 0, "the balls never met");
    assert!(e_prev < 0.9 * e0, "the impact lost only {} of {e0} J", e0 - e_prev);
}

#[test]
fn a_ball_with_restitution_bounces_to_the_apex_heights_of_newtons_law() {
    // Dropped from h0 = 1 m (gap) with e = 0.8: the k-th apex is e^(2k) h0.
    let (e, h0, r) = (0.8f64, 1.0, 0.05);
    let text = format!(
        "<mujoco><custom><numeric name=\"restitution\" data=\"{e}\"/></custom><worldbody>\
         <geom type=\"plane\" size=\"0 0 1\"/><body name=\"ball\" pos=\"0 0 {z}\"><freejoint/>\
         <geom type=\"sphere\" size=\"{r}\" mass=\"1\"/></body></worldbody></mujoco>",
        z = h0 + r
    );
    let model = mjcf::parse(&text, "ball.xml").unwrap().model;
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let h = 1e-3;
    let (mut apexes, mut rising, mut top, mut lowest) = (Vec::new(), false, 0.0f64, f64::INFINITY);
    while apexes.len() < 10 {
        sim.step(&mut s, h).unwrap();
        let z = s.c[0].z - r;
        lowest = lowest.min(z);
        let v = s.p[0].z;
        if v > 0.0 {
            rising = true;
            top = z;
        } else if rising {
            rising = false;
            apexes.push(top.max(z));
        }
        assert!(s.t < 20.0, "only {} bounces in 20 s", apexes.len());
    }
    for (k, apex) in apexes.iter().enumerate() {
        let expected = e.powi(2 * (k as i32 + 1)) * h0;
        // The apex is sampled at the steps: below the parabola's top by at most g h²/8.
        assert!(
            (apex - expected).abs() <= 1e-3 * expected,
            "apex {}: {apex} m, Newton's law {expected} m",
            k + 1
        );
    }
    assert!(lowest >= -1e-12, "the ball went {:e} m into the floor", -lowest);
}

#[test]
fn a_ball_rolls_down_a_slope_at_five_sevenths_of_the_sliding_acceleration() {
    // A solid ball (I = 2/5 m r²) on a 20° slope with µ = 0.5 > (2/7) tan 20°: it rolls
    // without slipping, a = (5/7) g sin θ.
    let (slope, r) = (20f64.to_radians(), 0.1);
    let (s_, c_) = slope.sin_cos();
    let half = slope / 2.0;
    let text = format!(
        "<mujoco><worldbody><geom type=\"plane\" size=\"0 0 1\" euler=\"0 {deg} 0\" friction=\"0.5\"/>\
         <body name=\"ball\" pos=\"{x} 0 {z}\"><freejoint/><geom type=\"sphere\" size=\"{r}\" mass=\"1\" friction=\"0.5\"/></body>\
         </worldbody><keyframe><key qpos=\"{x} 0 {z} {qw} 0 {qy} 0\"/></keyframe></mujoco>",
        deg = slope.to_degrees(),
        x = r * s_,
        z = r * c_,
        qw = half.cos(),
        qy = half.sin(),
    );
    let model = mjcf::parse(&text, "rolling.xml").unwrap().model;
    let (path, _) = run_box(&model, slope, 1e-3, 1000);
    let a = 5.0 / 7.0 * G * s_;
    for (k, p) in path.iter().enumerate().skip(1) {
        let t = k as f64 * 1e-3;
        let expected = 0.5 * a * t * t;
        let got = p[0] - path[0][0];
        // Kick-drift-kick is exact under the constant force of rolling: round-off only.
        assert!(
            (got - expected).abs() <= 1e-12 * expected,
            "t = {t}: {got} m, rolling {expected} m"
        );
        assert!(
            (p[2] - r).abs() <= 1e-10,
            "t = {t}: the centre is {} m off the slope",
            p[2] - r
        );
    }
}

/// Ten equal boxes stacked square on the floor for 10⁵ steps (100 s at h = 1e-3): every
/// centre stays within 1e-9 m of its start, every attitude within 1e-9 rad, the deepest
/// penetration below 1e-9 m, and the energy is never gained. Four corners per face are
/// redundant rows; equal faces stacked square are where parry's clipping lost a corner
/// (`boxes.rs`), and a stack of three corners tipped the solve.
#[test]
fn a_stack_of_ten_boxes_stays_put() {
    let mut bodies = String::new();
    for k in 0..10 {
        bodies += &format!(
            "<body name=\"b{k}\" pos=\"0 0 {z}\"><freejoint/><geom type=\"box\" size=\"0.1 0.1 0.05\" mass=\"1\"/></body>",
            z = 0.05 + 0.1 * k as f64
        );
    }
    let text = format!("<mujoco><worldbody><geom type=\"plane\" size=\"0 0 1\"/>{bodies}</worldbody></mujoco>");
    let model = mjcf::parse(&text, "stack.xml").unwrap().model;
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let (start, start_rotation) = (s.c.clone(), s.rotation.clone());
    let e0 = sim.system.energy(&s);
    let steps = 100_000;
    let (mut moved, mut turned, mut deepest, mut gained): (f64, f64, f64, f64) = (0.0, 0.0, 0.0, 0.0);
    for _ in 0..steps {
        let report = sim.step(&mut s, 1e-3).unwrap();
        assert_eq!(report.contacts, 40, "t = {}", s.t);
        deepest = deepest.max(report.penetration);
        for ((c, c0), (r, r0)) in s.c.iter().zip(&start).zip(s.rotation.iter().zip(&start_rotation)) {
            moved = moved.max((*c - *c0).norm());
            turned = turned.max(liemid::so3::log(&(*r * r0.transpose())).norm());
        }
        gained = gained.max(sim.system.energy(&s) - e0);
    }
    assert!(moved <= 1e-9, "a centre moved {moved:e} m in {steps} steps");
    assert!(turned <= 1e-9, "a box turned {turned:e} rad");
    assert!(deepest <= 1e-9, "penetration {deepest:e} m");
    assert!(gained <= 1e-12 * e0.abs(), "energy gained {gained:e} J of {e0:e}");
    println!("moved {moved:e} m, turned {turned:e} rad, deepest {deepest:e} m, energy gained {gained:e} J");
}

#[test]
fn a_urdf_cube_falls_onto_its_base_and_rests_there() {
    // URDF `<collision>` shapes touch (MuJoCo's import: friction 1): a massless base link
    // (merged into the world) with a 2 m slab whose top is at z = 0, and a floating 0.2 m
    // cube released 0.4 m above it.
    let text = r#"<robot name="drop">
      <link name="base"><collision><origin xyz="0 0 -0.05"/><geometry><box size="2 2 0.1"/></geometry></collision></link>
      <link name="cube">
        <inertial><mass value="1"/><inertia ixx="0.0067" iyy="0.0067" izz="0.0067" ixy="0" ixz="0" iyz="0"/></inertial>
        <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
      </link>
      <joint name="free" type="floating"><parent link="base"/><child link="cube"/><origin xyz="0 0 0.5"/></joint>
    </robot>"#;
    let loaded = liemid::multibody::urdf::parse(text, "drop.urdf").unwrap();
    assert_eq!(loaded.model.collision.shapes.len(), 2);
    assert!(loaded.model.collision.shapes.iter().all(|s| s.group == 3));
    let (_, s, lowest) = drop_for_a_second(&loaded.model);
    // Plastic: it lands at t = √(2·0.4/g) = 0.29 s and stays, its centre 0.1 m above the top.
    assert!((s.c[0].z - 0.1).abs() <= 1e-9, "rests at {} m", s.c[0].z);
    assert!(lowest >= 0.1 - 1e-9, "went down to {lowest} m");
    assert!(s.p[0].norm() <= 1e-9, "still moving: {:?}", s.p[0]);
}

/// A cube dropped tilted lands on an edge, pivots, and its face slaps down: at friction 0.6
/// and 1.0, tilts 0.05-0.6 rad and steps 5e-4 and 1e-3 it comes to rest on a face at its
/// exact height, and the energy never rises above the start's. (The solve used to stall there:
/// `benchmarks/models/contact_tilted_cube.xml`.)
#[test]
fn a_tilted_cube_lands_on_an_edge_and_comes_to_rest_on_a_face() {
    for mu in [0.6, 1.0] {
        for tilt in [0.05f64, 0.3, 0.6] {
            for h in [1e-3, 5e-4] {
                let (s, c) = ((tilt / 2.0).sin(), (tilt / 2.0).cos());
                let text = format!(
                    "<mujoco><worldbody><geom type=\"plane\" size=\"0 0 1\" friction=\"{mu}\"/>\
                     <body pos=\"0 0 0.2\" quat=\"{c} {s} 0 0\"><freejoint/>\
                     <geom type=\"box\" size=\"0.05 0.05 0.05\" density=\"1000\" friction=\"{mu}\"/></body>\
                     </worldbody></mujoco>"
                );
                let model = mjcf::parse(&text, "cube.xml").unwrap().model;
                let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
                let (mut sim, mut state) = (prepared.simulation, prepared.state);
                let e0 = sim.system.energy(&state);
                let mut e_prev = e0;
                let (mut gained, mut above): (f64, f64) = (0.0, 0.0);
                let steps = (0.6 / h) as usize;
                for _ in 0..steps {
                    sim.step(&mut state, h)
                        .unwrap_or_else(|e| panic!("µ = {mu}, tilt {tilt}, h = {h}: {e}"));
                    let e = sim.system.energy(&state);
                    gained = gained.max(e - e_prev);
                    above = above.max(e - e0);
                    e_prev = e;
                }
                let label = format!("µ = {mu}, tilt {tilt}, h = {h}");
                // Landing and sliding only lose energy: it never rises above the start's.
                // While the cube pivots on a sticking edge (a conservative motion, like a
                // pendulum's) the step's own energy error rises and falls: at most 1.6e-8
                // of the total in a step at h = 1e-3, 2.1e-9 at 5e-4 (O(h³) a step).
                assert!(
                    above <= 1e-12 * e0,
                    "{label}: energy {above:e} J above the start's {e0:e}"
                );
                println!("{label}: largest rise in a step {:.2e} of the total", gained / e0);
                assert!(
                    (state.c[0].z - 0.05).abs() <= 1e-9,
                    "{label}: rests at {}",
                    state.c[0].z
                );
                // A face down: the body's axis closest to the vertical is vertical.
                let r = state.rotation[0];
                let up = (0..3).map(|i| r[(2, i)].abs()).fold(0.0, f64::max);
                assert!((1.0 - up).abs() <= 1e-9, "{label}: tilted by {}", up.acos());
            }
        }
    }
}

/// Newton's cradle: five steel-like balls (radius 0.02 m, 0.1 kg) hung on hinges 0.2 m
/// long with gaps of 1 mm, elastic (`e = 1`) and frictionless (`condim="1"`); the first
/// swings in at 1 m/s. The impacts come one at a time (each ball crosses its gap in 1 ms,
/// ten steps at h = 1e-4), each passing the momentum on: after 10 ms the last ball carries
/// it and the others are nearly still. The energy's rise through the four impacts is what
/// the approach speed's estimate leaves (1.4e-7 of the total at h = 1e-4, 5.6e-8 at 5e-5).
#[test]
fn newtons_cradle_passes_the_momentum_down_the_line() {
    let mut rises = Vec::new();
    for h in [1e-4f64, 5e-5] {
        let (r, gap, length) = (0.02, 1e-3, 0.2);
        let balls: String = (0..5)
            .map(|k| {
                format!(
                    "<body name=\"ball{k}\" pos=\"{x} 0 0.1\"><joint type=\"hinge\" axis=\"0 1 0\" pos=\"0 0 {length}\"/>\
                     <geom type=\"sphere\" size=\"{r}\" mass=\"0.1\" condim=\"1\"/></body>",
                    x = k as f64 * (2.0 * r + gap)
                )
            })
            .collect();
        let text = format!(
            "<mujoco><custom><numeric name=\"restitution\" data=\"1\"/></custom><worldbody>{balls}</worldbody>\
             <keyframe><key qvel=\"-5 0 0 0 0\"/></keyframe></mujoco>"
        );
        let model = mjcf::parse(&text, "cradle.xml").unwrap().model;
        let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
        let (mut sim, mut s) = (prepared.simulation, prepared.state);
        let e0 = sim.system.energy(&s);
        let steps = (0.01 / h).round() as usize;
        for _ in 0..steps {
            sim.step(&mut s, h).unwrap();
        }
        let v: Vec<f64> = s.p.iter().map(|p| p.x / 0.1).collect();
        assert!(v[4] >= 0.998, "h = {h}: the last ball leaves at {} m/s", v[4]);
        for (k, vk) in v[..4].iter().enumerate() {
            assert!(vk.abs() <= 1e-3, "h = {h}: ball {k} keeps {vk} m/s");
        }
        let rise = (sim.system.energy(&s) - e0) / e0;
        assert!(rise.abs() <= 2e-7, "h = {h}: energy changed by {rise:e}");
        rises.push(rise);
    }
    // The rise shrinks with the step (it is the approach speed's estimate, not a gain of
    // the contact law).
    assert!(rises[1] < 0.5 * rises[0], "rises {rises:?}");
}

/// Bad contact input is refused naming what is wrong, or noted when it is only not
/// simulated: negative friction, an `<exclude>` or `<pair>` naming what the model lacks, a
/// plane on a moving body; a mesh geom that would touch is noted (its contacts are not
/// simulated).
#[test]
fn bad_contact_input_is_refused_naming_it_or_noted() {
    let ball =
        "<body name=\"ball\" pos=\"0 0 1\"><freejoint/><geom name=\"ball\" type=\"sphere\" size=\"0.1\"/></body>";
    let model = |world: &str, extra: &str| format!("<mujoco><worldbody>{world}</worldbody>{extra}</mujoco>");
    let floor = "<geom name=\"floor\" type=\"plane\" size=\"0 0 1\"/>";
    let refused = |text: String, wanted: &[&str]| {
        let message = match mjcf::parse(&text, "bad.xml") {
            Ok(_) => panic!("accepted: {text}"),
            Err(e) => e.to_string(),
        };
        for w in wanted {
            assert!(message.contains(w), "{message:?} lacks {w:?}");
        }
    };
    refused(
        model(
            &format!("<geom type=\"plane\" size=\"0 0 1\" friction=\"-0.5\"/>{ball}"),
            "",
        ),
        &["friction", "negative"],
    );
    refused(
        model(
            &format!("{floor}{ball}"),
            "<contact><exclude body1=\"world\" body2=\"nobody\"/></contact>",
        ),
        &["body2=\"nobody\"", "no body"],
    );
    refused(
        model(
            &format!("{floor}{ball}"),
            "<contact><pair geom1=\"floor\" geom2=\"nothere\"/></contact>",
        ),
        &["geom2=\"nothere\"", "no geom"],
    );
    // A plane on a moving body: refused when the system is built, naming the geom.
    let text = model(
        &format!(
            "<body pos=\"0 0 1\"><freejoint/><inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.1 0.1 0.1\"/>\
         <geom name=\"deck\" type=\"plane\" size=\"1 1 0.1\"/></body>{ball}"
        ),
        "",
    );
    let loaded = mjcf::parse(&text, "deck.xml").unwrap();
    let message = match Simulation::prepare(&loaded.model, MultibodyMethod::Liemid) {
        Ok(_) => panic!("a plane on a moving body was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(message.contains("deck") && message.contains("plane"), "{message}");
    // A pair naming geoms that exist is only noted; so is a mesh geom that would touch.
    let loaded = mjcf::parse(
        &model(
            &format!("{floor}{ball}"),
            "<contact><pair geom1=\"floor\" geom2=\"ball\"/></contact>",
        ),
        "pair.xml",
    )
    .unwrap();
    assert!(
        loaded.ignored.iter().any(|n| n.contains("contact pair")),
        "{:?}",
        loaded.ignored
    );
    let loaded = mjcf::parse(
        "<mujoco><asset><mesh name=\"m\" file=\"missing.stl\"/></asset><worldbody>\
         <geom type=\"plane\" size=\"0 0 1\"/><body pos=\"0 0 1\"><freejoint/>\
         <inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.01 0.01 0.01\"/><geom type=\"mesh\" mesh=\"m\"/></body>\
         </worldbody></mujoco>",
        "mesh.xml",
    )
    .unwrap();
    assert!(
        loaded.ignored.iter().any(|n| n.contains("mesh geom contacts")),
        "{:?}",
        loaded.ignored
    );
}

/// A pile of 100 boxes and spheres falling into a bin, to t = 0.36 s (more than 136
/// points): no step starts with a point deeper than the issue's bound, 1e-6 m (measured:
/// 1.8e-8 m, where a contact slid within a step is held at its material points and its
/// closest points are `O(slide²)` deeper). parry's manifold holds the features of the step's
/// start only; a box that turns another corner or edge down within the step is found by
/// detecting again at the drift's end (1.45e-5 m deep at t = 0.28 before that, with the
/// gap of a box's corner on another box's face measured along the wrong box's normal).
/// The step from t = 0.298 failed before stalled solves were taken at the acceptance
/// (`1e-8` of the length) and failed steps split: the steps taken loosely hold the law to
/// the acceptance.
#[test]
fn a_falling_pile_never_starts_a_step_penetrating() {
    let text = include_str!("../data/pile_boxes_spheres.xml");
    let model = mjcf::parse(text, "pile_boxes_spheres.xml").unwrap().model;
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let length = sim.system.contact_length().unwrap();
    let (mut deepest, mut most, mut loose, mut split, mut looseness): (f64, u32, u32, u32, f64) = (0.0, 0, 0, 0, 0.0);
    for k in 0..360 {
        let report = sim.step(&mut s, 1e-3).unwrap_or_else(|e| panic!("step {k}: {e}"));
        deepest = deepest.max(report.penetration);
        most = most.max(report.contacts);
        loose += report.loose_steps;
        split += report.split_steps;
        looseness = looseness.max(report.loose_violation);
    }
    eprintln!("most {most} points, deepest {deepest:e} m, {loose} loose steps (worst {looseness:e}), {split} split");
    assert!(most >= 100, "{most} points");
    assert!(deepest <= 1e-6, "penetration {deepest:e} m (length {length} m)");
    assert!(looseness <= 1e-8, "loose violation {looseness:e}");
}

/// A mesh geom that touches is its file's convex hull (as MuJoCo collides meshes): a cube
/// written as an ASCII STL (twelve triangles, half-edge 0.05 m), its body dropped tilted onto
/// the floor, lands on its hull's corners and rests on a face at its exact height.
#[test]
fn a_mesh_cube_touches_as_its_convex_hull_and_rests_on_a_face() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("contact_mesh");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let a = 0.05;
    write_cube_stl(&dir.join("cube.stl"), a);
    let model_path = dir.join("cube.xml");
    std::fs::write(
        &model_path,
        "<mujoco><asset><mesh name=\"cube\" file=\"cube.stl\"/></asset><worldbody>\
         <geom type=\"plane\" size=\"0 0 1\"/>\
         <body pos=\"0 0 0.2\" quat=\"0.98 0.15 0.1 0\"><freejoint/>\
         <inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.00167 0.00167 0.00167\"/>\
         <geom type=\"mesh\" mesh=\"cube\"/></body></worldbody></mujoco>",
    )
    .unwrap();
    let loaded = mjcf::load(&model_path).unwrap();
    assert!(
        !loaded.ignored.iter().any(|n| n.contains("mesh geom contacts")),
        "{:?}",
        loaded.ignored
    );
    let prepared = Simulation::prepare(&loaded.model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let mut most = 0;
    for _ in 0..1000 {
        let report = sim.step(&mut s, 1e-3).unwrap();
        most = most.max(report.contacts);
    }
    assert!(most >= 3, "{most} points");
    assert!((s.c[0].z - a).abs() <= 1e-9, "rests at {}", s.c[0].z);
    let up = (0..3).map(|i| s.rotation[0][(2, i)].abs()).fold(0.0, f64::max);
    assert!((1.0 - up).abs() <= 1e-9, "tilted by {}", up.acos());
}

/// The example humanoid (capsules, hinges with damping, springs and limits) with its
/// contacts on and a floor, dropped from its standing start: it falls over, lands on its
/// capsules and lies on the floor for 3 s at h = 2e-3. It failed at t = 0.46 s before: a
/// capsule sliding on the floor or along another was found again at each drift's end as a
/// new point beside its own (the problem's point holds its material points), and
/// Gauss–Seidel stalled on the two nearly equal rows. The stalled solves that remain are
/// taken at the acceptance (`1e-8` of the length) or split, and counted; no step starts
/// penetrating by more than 1e-6 m.
#[test]
fn a_humanoid_falls_over_onto_the_floor_and_lies_there() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/multibody/humanoid.xml");
    let text = std::fs::read_to_string(path)
        .unwrap()
        .replace(r#"<flag contact="disable"/>"#, "")
        .replace(
            "<worldbody>",
            r#"<worldbody><geom name="floor" type="plane" size="0 0 1"/>"#,
        );
    let model = mjcf::parse(&text, "humanoid_floor.xml").unwrap().model;
    let prepared = Simulation::prepare(&model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let length = sim.system.contact_length().unwrap();
    let (mut deepest, mut most, mut looseness): (f64, u32, f64) = (0.0, 0, 0.0);
    for k in 0..1500 {
        let report = sim.step(&mut s, 2e-3).unwrap_or_else(|e| panic!("step {k}: {e}"));
        deepest = deepest.max(report.penetration);
        most = most.max(report.contacts);
        looseness = looseness.max(report.loose_violation);
    }
    // Lying down: the torso (body 0) within its capsules' reach of the floor, at rest.
    let before = s.c[0];
    sim.step(&mut s, 2e-3).unwrap();
    let (height, speed) = (s.c[0].z, (s.c[0] - before).norm() / 2e-3);
    eprintln!("most {most} points, deepest {deepest:e} m, loose {looseness:e}; torso at {height} m, {speed} m/s");
    assert!(most >= 6, "{most} points");
    assert!(deepest <= 1e-6, "penetration {deepest:e} m");
    assert!(looseness <= 1e-8, "loose violation {looseness:e}");
    assert!(
        height < 0.3 && speed < 1e-2,
        "torso at {height} m moving at {speed} m/s (length {length})"
    );
}

/// `model` (one free body first) run 1000 steps of 1e-3 s with liemid from its start: the
/// simulation, the final state and the lowest height of body 0's centre along the way.
fn drop_for_a_second(model: &Model) -> (Simulation, liemid::multibody::MultibodyState, f64) {
    let prepared = Simulation::prepare(model, MultibodyMethod::Liemid).unwrap();
    let (mut sim, mut s) = (prepared.simulation, prepared.state);
    let mut lowest = f64::INFINITY;
    for _ in 0..1000 {
        sim.step(&mut s, 1e-3).unwrap();
        lowest = lowest.min(s.c[0].z);
    }
    (sim, s, lowest)
}

/// A cube of half-edge `a` about the origin as an ASCII STL (twelve triangles).
fn write_cube_stl(path: &std::path::Path, a: f64) {
    let corner = |i: usize| [[-a, a][i & 1], [-a, a][(i >> 1) & 1], [-a, a][(i >> 2) & 1]];
    // Each face as two triangles of its four corners (the hull needs the points only).
    let faces = [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 3, 7, 5],
    ];
    let mut stl = String::from("solid cube\n");
    for f in faces {
        for tri in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            stl += "facet normal 0 0 0\nouter loop\n";
            for v in tri {
                let p = corner(v);
                stl += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
            }
            stl += "endloop\nendfacet\n";
        }
    }
    stl += "endsolid cube\n";
    std::fs::write(path, stl).unwrap();
}

/// A URDF `<collision>` mesh touches as its file's convex hull (MuJoCo's import): the cube
/// of `a_urdf_cube_falls_onto_its_base_and_rests_there` with its collision a mesh (the STL
/// cube of half-edge 0.05 m, `scale="2 2 2"`), found next to the file by `urdf::load`, rests
/// on the slab at its exact height (its single-precision vertices' height). Without the
/// file (parsed from text, a missing file, a format not read) the mesh does not touch, and
/// the loader says so.
#[test]
fn a_urdf_collision_mesh_touches_as_its_convex_hull() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("contact_urdf_mesh");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    write_cube_stl(&dir.join("cube.stl"), 0.05);
    let urdf = |file: &str| {
        format!(
            r#"<robot name="drop">
      <link name="base"><collision><origin xyz="0 0 -0.05"/><geometry><box size="2 2 0.1"/></geometry></collision></link>
      <link name="cube">
        <inertial><mass value="1"/><inertia ixx="0.0067" iyy="0.0067" izz="0.0067" ixy="0" ixz="0" iyz="0"/></inertial>
        <collision><geometry><mesh filename="{file}" scale="2 2 2"/></geometry></collision>
      </link>
      <joint name="free" type="floating"><parent link="base"/><child link="cube"/><origin xyz="0 0 0.5"/></joint>
    </robot>"#
        )
    };
    let note = |loaded: &liemid::multibody::Loaded| loaded.ignored.iter().any(|n| n.contains("collision meshes"));
    let path = dir.join("drop.urdf");
    std::fs::write(&path, urdf("cube.stl")).unwrap();
    let loaded = liemid::multibody::urdf::load(&path).unwrap();
    assert_eq!(loaded.model.collision.shapes.len(), 2);
    assert!(!note(&loaded), "{:?}", loaded.ignored);
    assert!(loaded.files.contains(&dir.join("cube.stl")), "{:?}", loaded.files);
    let (sim, s, lowest) = drop_for_a_second(&loaded.model);
    // The STL holds single-precision vertices: the hull's half-edge is 2 × 0.05f32 =
    // 0.1 + 1.49e-9 m, and the cube rests at that height to the position solve's
    // tolerance, 1e-12 of the contact length.
    let height = 2.0 * f64::from(0.05_f32);
    let tol = 1e-12 * sim.system.contact_length().unwrap();
    assert!(
        (s.c[0].z - height).abs() <= tol,
        "rests at {} m, not {height}",
        s.c[0].z
    );
    assert!(lowest >= height - tol, "went down to {lowest} m");
    // From text, with the file missing, and in a format that is not read (COLLADA, common
    // in ROS packages): only the slab touches, noted.
    let from_text = liemid::multibody::urdf::parse(&urdf("cube.stl"), "drop.urdf").unwrap();
    std::fs::write(&path, urdf("missing.stl")).unwrap();
    let missing = liemid::multibody::urdf::load(&path).unwrap();
    std::fs::write(dir.join("cube.dae"), "<COLLADA/>").unwrap();
    std::fs::write(&path, urdf("cube.dae")).unwrap();
    let collada = liemid::multibody::urdf::load(&path).unwrap();
    for loaded in [from_text, missing, collada] {
        assert_eq!(loaded.model.collision.shapes.len(), 1);
        assert!(note(&loaded), "{:?}", loaded.ignored);
        assert!(loaded
            .shapes
            .iter()
            .all(|s| s.collision.is_none() || !matches!(s.kind, liemid::multibody::ShapeKind::Mesh { .. })));
    }
}
