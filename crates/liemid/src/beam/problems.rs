//! Named beam benchmarks.
//!
//! - `cantilever-vibration`: small free vibration of a straight cantilever (`L = 1`,
//!   `EI = 1`, `ρA = 1`, square section `a = 0.01`), started in one Euler-Bernoulli mode
//!   shape; the frequencies are `ω_n = (β_n L)² √(EI/(ρA L⁴))`, `β_n L` = 1.8751, 4.6941,
//!   7.8548.
//! - `right-angle-cantilever`: Simo and Vu-Quoc's (1988) right-angle cantilever, legs of
//!   length 10 from `(0, 10, 0)` (clamped) to the elbow `(10, 10, 0)` and the tip
//!   `(10, 0, 0)`; their coefficients `EA = 10⁶`, `GJ = EI = 10³`, `Aρ = 1`,
//!   `I_ρ = diag(20, 10, 10)`; out-of-plane elbow force `F_z = 50 t` for `t < 1`,
//!   `50 (2 − t)` for `1 ≤ t < 2`, then 0; `t_end = 30`. The published response: the elbow
//!   rises to 5.5 near `t = 3` and swings to −3.9 near `t = 10.8`; the tip rises to 8.3
//!   near `t = 7.5` and swings to −9.7 near `t = 16`.
//! - `flying-beam`: a free beam of length 10 from `(6, 0, 0)` to `(0, 0, 8)` (`EA = 10⁴`,
//!   `GJ = EI = 500`, `ρA = 1`, rotary inertia `(20, 10, 10)` per length, after Simo and
//!   Vu-Quoc's free-flying beam), pushed at its lower end by `F = p(t)/10 (0, 1, 0)` and
//!   `M = p(t) (0, −1/2, 1)` with `p` rising linearly to 50 at `t = 2.5` and back to 0 at
//!   `t = 5`; after that it flies free, keeping its momenta.
//! - `tower`: a 25-storey steel frame for throughput ([`tower`]).
//!
//! ## Reference
//! J. C. Simo, L. Vu-Quoc, *On the dynamics in space of rods undergoing large motions — a
//! geometrically exact approach*, Comput. Methods Appl. Mech. Engrg. 66 (1988) 125-161;
//! R. D. Blevins, *Formulas for Natural Frequency and Mode Shape*, Krieger (1979), table 8-1.

use super::model::{Frame, History, NodalLoad, Section, Support};
use super::BeamSystem;
use crate::error::{Error, Result};
use crate::linalg::Vec3;
use crate::so3;

/// `β_n L` of the first three bending modes of a clamped-free Euler-Bernoulli beam.
pub const CANTILEVER_BETA_L: [f64; 3] = [1.875_104_068_711_961, 4.694_091_132_974_175, 7.854_757_438_237_613];

/// A named benchmark: its model, end time, tracked nodes, and initial deflection.
#[derive(Clone, Debug)]
pub struct BeamProblem {
    /// The name on the command line.
    pub name: &'static str,
    /// One line on what it is.
    pub description: &'static str,
    /// The model.
    pub frame: Frame,
    /// End time.
    pub t_end: f64,
    /// For `cantilever-vibration`: the mode and tip amplitude of the initial deflection.
    pub initial_mode: Option<(usize, f64)>,
}

/// The problems' names.
pub const NAMES: [&str; 4] = ["cantilever-vibration", "right-angle-cantilever", "flying-beam", "tower"];

/// Default elements per member of each problem.
#[must_use]
pub fn default_elements(name: &str) -> usize {
    match name {
        "cantilever-vibration" => 20,
        "right-angle-cantilever" => 8,
        "tower" => 50,
        _ => 10,
    }
}

/// The problem called `name` with `elements` per member (the default when `None`).
///
/// # Errors
/// An unknown name (the message lists the known ones) or zero elements.
pub fn by_name(name: &str, elements: Option<usize>) -> Result<BeamProblem> {
    let n = elements.unwrap_or_else(|| default_elements(name));
    match name {
        "cantilever-vibration" => cantilever_vibration(n, 1),
        "right-angle-cantilever" => right_angle_cantilever(n),
        "flying-beam" => flying_beam(n),
        "tower" => tower(25, n),
        _ => Err(Error::InvalidModel {
            reason: format!("unknown beam problem `{name}` (known: {})", NAMES.join(", ")),
        }),
    }
}

/// The clamped-free Euler-Bernoulli mode `φ(x)` and its slope for `β`, length `l`.
#[must_use]
pub fn cantilever_mode(beta: f64, l: f64, x: f64) -> (f64, f64) {
    let bl = beta * l;
    let sigma = (bl.cosh() + bl.cos()) / (bl.sinh() + bl.sin());
    let bx = beta * x;
    let phi = bx.cosh() - bx.cos() - sigma * (bx.sinh() - bx.sin());
    let slope = beta * (bx.sinh() + bx.sin() - sigma * (bx.cosh() - bx.cos()));
    (phi, slope)
}

/// The cantilever of `cantilever-vibration`, started in mode `mode` (1, 2 or 3) with a
/// tip deflection of `1e-4 L`.
///
/// # Errors
/// Zero elements or a mode outside 1..=3.
pub fn cantilever_vibration(elements: usize, mode: usize) -> Result<BeamProblem> {
    if !(1..=3).contains(&mode) {
        return Err(Error::InvalidModel {
            reason: format!("cantilever mode {mode}: only modes 1, 2 and 3 are tabulated"),
        });
    }
    let a: f64 = 0.01;
    let (ei, rho_a) = (1.0, 1.0);
    let e = ei * 12.0 / a.powi(4);
    let section = Section::rectangle(e, 0.0, rho_a / (a * a), a, a)?;
    let mut frame = Frame::new();
    let nodes = frame.add_member(
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 0.0),
        elements,
        section,
        Vec3::new(0.0, 0.0, 1.0),
    )?;
    frame.support(nodes[0], Support::Clamped)?;
    frame.name("tip", nodes[elements])?;
    frame.name("middle", nodes[elements / 2])?;
    let t_end = 12.0 * std::f64::consts::TAU / cantilever_omega(mode);
    Ok(BeamProblem {
        name: "cantilever-vibration",
        description:
            "small free vibration of a clamped-free beam started in a bending mode shape (L = 1, EI = 1, rho A = 1)",
        frame,
        t_end,
        initial_mode: Some((mode, 1e-4)),
    })
}

/// `ω_n` of the `cantilever-vibration` beam (`L = EI = ρA = 1`).
#[must_use]
pub fn cantilever_omega(mode: usize) -> f64 {
    CANTILEVER_BETA_L[mode - 1].powi(2)
}

/// Simo and Vu-Quoc's right-angle cantilever with `per_leg` elements per leg.
///
/// # Errors
/// Zero elements.
pub fn right_angle_cantilever(per_leg: usize) -> Result<BeamProblem> {
    // Simo and Vu-Quoc's coefficients: EA = 10⁶, GJ = EI = 10³, Aρ = 1, I_ρ = diag(20, 10, 10)
    // (a square section with a² = 0.012 gives the same EA, EI and Aρ, but a rotary inertia
    // of 1e-3: the published curves need the published I_ρ).
    let section = Section {
        axial_stiffness: 1e6,
        torsional_stiffness: 1e3,
        bending_stiffness_2: 1e3,
        bending_stiffness_3: 1e3,
        mass_per_length: 1.0,
        rotary_inertia: Vec3::new(20.0, 10.0, 10.0),
    };
    let mut frame = Frame::new();
    let up = Vec3::new(0.0, 0.0, 1.0);
    let (root, elbow, tip) = (
        Vec3::new(0.0, 10.0, 0.0),
        Vec3::new(10.0, 10.0, 0.0),
        Vec3::new(10.0, 0.0, 0.0),
    );
    let leg1 = frame.add_member(root, elbow, per_leg, section, up)?;
    let leg2 = frame.add_member(elbow, tip, per_leg, section, up)?;
    frame.support(leg1[0], Support::Clamped)?;
    frame.name("elbow", leg2[0])?;
    frame.name("tip", leg2[per_leg])?;
    frame.load(NodalLoad {
        node: leg2[0],
        force: Vec3::new(0.0, 0.0, 1.0),
        moment: Vec3::ZERO,
        follower: false,
        history: History::new(vec![(0.0, 0.0), (1.0, 50.0), (2.0, 0.0)])?,
    })?;
    Ok(BeamProblem {
        name: "right-angle-cantilever",
        description: "Simo and Vu-Quoc (1988): right-angle cantilever struck out of plane at the elbow",
        frame,
        t_end: 30.0,
        initial_mode: None,
    })
}

/// The free-flying beam with `elements` elements.
///
/// # Errors
/// Zero elements.
pub fn flying_beam(elements: usize) -> Result<BeamProblem> {
    let section = Section {
        axial_stiffness: 1e4,
        torsional_stiffness: 500.0,
        bending_stiffness_2: 500.0,
        bending_stiffness_3: 500.0,
        mass_per_length: 1.0,
        rotary_inertia: Vec3::new(20.0, 10.0, 10.0),
    };
    let mut frame = Frame::new();
    let nodes = frame.add_member(
        Vec3::new(6.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 8.0),
        elements,
        section,
        Vec3::new(0.0, 1.0, 0.0),
    )?;
    frame.name("lower", nodes[0])?;
    frame.name("upper", nodes[elements])?;
    let p = History::new(vec![(0.0, 0.0), (2.5, 50.0), (5.0, 0.0)])?;
    frame.load(NodalLoad {
        node: nodes[0],
        force: Vec3::new(0.0, 0.1, 0.0),
        moment: Vec3::new(0.0, -0.5, 1.0),
        follower: false,
        history: p,
    })?;
    Ok(BeamProblem {
        name: "flying-beam",
        description: "a free beam pushed at one end by a force and a moment that ramp up and down, then flying free",
        frame,
        t_end: 30.0,
        initial_mode: None,
    })
}

/// A steel tower frame for throughput: `stories` storeys of 4 m, a 6 m square plan, four
/// columns and four beams per storey, each member cut into `elements` elements
/// (`8 · stories · elements` elements: 10⁴ for 25 storeys of 50), clamped at the base,
/// under gravity and a lateral gust at the top (100 kN for 0.1 s).
///
/// # Errors
/// Zero elements or storeys.
pub fn tower(stories: usize, elements: usize) -> Result<BeamProblem> {
    if stories == 0 {
        return Err(Error::InvalidModel {
            reason: "a tower needs at least one storey".into(),
        });
    }
    let steel = Section::rectangle(210e9, 0.3, 7850.0, 0.3, 0.3)?;
    let mut frame = Frame::new();
    let corners = [(0.0, 0.0), (6.0, 0.0), (6.0, 6.0), (0.0, 6.0)];
    for s in 0..stories {
        let (z0, z1) = (4.0 * s as f64, 4.0 * (s + 1) as f64);
        for &(x, y) in &corners {
            let nodes = frame.add_member(
                Vec3::new(x, y, z0),
                Vec3::new(x, y, z1),
                elements,
                steel,
                Vec3::new(1.0, 0.0, 0.0),
            )?;
            if s == 0 {
                frame.support(nodes[0], Support::Clamped)?;
            }
        }
        for k in 0..4 {
            let ((xa, ya), (xb, yb)) = (corners[k], corners[(k + 1) % 4]);
            frame.add_member(
                Vec3::new(xa, ya, z1),
                Vec3::new(xb, yb, z1),
                elements,
                steel,
                Vec3::new(0.0, 0.0, 1.0),
            )?;
        }
    }
    let top = frame
        .node_at(Vec3::new(0.0, 0.0, 4.0 * stories as f64), 1e-9)
        .expect("the top corner exists");
    frame.name("top", top)?;
    frame.gravity = Vec3::new(0.0, 0.0, -9.81);
    frame.load(NodalLoad {
        node: top,
        force: Vec3::new(1e5, 0.0, 0.0),
        moment: Vec3::ZERO,
        follower: false,
        history: History::new(vec![(0.0, 1.0), (0.1, 1.0), (0.1 + 1e-9, 0.0)])?,
    })?;
    Ok(BeamProblem {
        name: "tower",
        description: "a 25-storey steel tower frame (10^4 elements at 50 per member) under gravity and a gust",
        frame,
        t_end: 0.05,
        initial_mode: None,
    })
}

impl BeamProblem {
    /// Build the system, with the initial deflection of `cantilever-vibration`.
    ///
    /// # Errors
    /// As [`Frame::build`].
    pub fn system(&self) -> Result<BeamSystem> {
        let mut s = self.frame.build()?;
        if let Some((mode, amplitude)) = self.initial_mode {
            let beta = CANTILEVER_BETA_L[mode - 1];
            let (tip, _) = cantilever_mode(beta, 1.0, 1.0);
            for node in 0..s.frame.nodes.len() {
                let x = s.frame.nodes[node].x;
                let (w, slope) = cantilever_mode(beta, 1.0, x);
                let (w, slope) = (amplitude * w / tip, amplitude * slope / tip);
                let position = s.frame.nodes[node] + Vec3::new(0.0, 0.0, w);
                s.set_pose(node, position, so3::exp(Vec3::new(0.0, -slope, 0.0)));
            }
        }
        Ok(s)
    }

    /// The tracked nodes' names.
    #[must_use]
    pub fn tracked(&self) -> Vec<String> {
        self.frame.names.iter().map(|(n, _)| n.clone()).collect()
    }
}
