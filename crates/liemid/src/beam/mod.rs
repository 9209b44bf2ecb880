//! Finite-element dynamics of flexible 3-D beams whose nodes are rigid bodies, stepped by
//! the explicit midpoint Lie splitting.
//!
//! A [`Frame`] (nodes, members cut into two-node corotational elements, [`Section`]s,
//! [`Support`]s, [`NodalLoad`]s with piecewise-linear [`History`]s, gravity) is built into
//! a [`BeamSystem`]: every node that is not clamped becomes a rigid body of
//! [`crate::many::Bodies`] with the lumped mass `Σ ρA L₀/2` and rotary inertia
//! `Σ E₀ diag(ρ(I₂+I₃), ρI₂, ρI₃) E₀ᵀ L₀/2` of its half elements (body axes: the
//! principal axes of that sum); pinned nodes are rotors (held in place, free to turn).
//! The elements, loads and gravity are the [`Structure`], an
//! [`Interaction`], so a step is [`Bodies::step`]:
//!
//! ```text
//! p ← p + (h/2) F,  Π ← Π + (h/2) T        half impulse of the element forces and moments
//! x ← x + h p/m                              Verlet drift of the translations
//! (Π, R) ← two torque-free midpoint half steps (LIEMID[EA]'s free rotation)
//! F, T ← internal forces at the new configuration (one evaluation per step)
//! p ← p + (h/2) F,  Π ← Π + (h/2) T        half impulse
//! ```
//!
//! It is second order and time reversible (not symplectic: the nodes turn by EA's midpoint
//! drift, whose Lie–Poisson defect is `O(h³)` per step, docs/theory/rigid.md §9); the
//! internal forces sum to zero force and moment ([`element`]), so a free-flying structure
//! keeps its total linear and angular momentum (orbital `Σ x × p` plus nodal spins
//! `Σ R Π`) to round-off. With the variational drift ([`BeamSystem::set_drift`],
//! [`Drift::Variational`]) the nodes turn by two half steps of (V),
//! `(1/h) I Ψ = Jr(Ψ) P` (LIEMID\[EAV\]'s free rotation), a Lie–Poisson map: every piece
//! of the step is then symplectic and so is the step (measured in
//! `tests/beam/symplectic.rs`, docs/beams.md), with the same order, symmetry and
//! momenta. Symmetric
//! compositions ([`BeamSystem::step_composed`]) raise the order to 4 and beyond. The step
//! is explicit: it is stable below `2/ω_max` (Verlet; less for compositions, see
//! [`stability`]); [`BeamSystem::stability`] bounds `ω_max` element by element.
//!
//! The module has the shape of the other domains: [`model`] (the structure as the user
//! gives it), [`element`] (the interaction: the corotational element), [`stability`],
//! [`newmark`] (the implicit baseline structural codes use), [`problems`] (named
//! benchmarks).
//!
//! ## Reference
//! P. Krysl, *Explicit momentum-conserving integrator for dynamics of rigid bodies
//! approximating the midpoint Lie algorithm*, Int. J. Numer. Meth. Engng. 63 (2005);
//! M. A. Crisfield, *Non-linear Finite Element Analysis of Solids and Structures*, vol. 2,
//! Wiley (1997), chapter 17.

pub mod driver;
pub mod element;
pub mod impulse;
pub mod mass_scaling;
pub mod model;
pub mod newmark;
pub mod problems;
pub mod stability;
pub mod tangent;

pub use driver::{BeamDriver, BeamIntegrator, StepPlan};
pub use element::{ElementStiffness, EndForces};
pub use model::{ElementSpec, Frame, History, NodalLoad, Section, Support};
pub use newmark::{Newmark, Tangent};
pub use stability::Stability;

use std::sync::Mutex;

use crate::composition::Scheme;
use crate::error::{Error, Result};
use crate::linalg::symmetric_eigen;
use crate::linalg::{Mat3, Vec3};
use crate::many::{Bodies, Configuration, Interaction, Totals, CHUNK};
pub use crate::variational::Drift;
use element::from_columns;

/// Where a node's pose lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeRef {
    /// A body of [`BeamSystem::bodies`].
    Body(usize),
    /// A clamped node: index into the fixed poses.
    Fixed(usize),
}

/// One element as the interaction stores it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ElementData {
    pub(crate) ends: [NodeRef; 2],
    pub(crate) stiffness: ElementStiffness,
    /// `Bᵀ E₀` at each end: the element's initial axes in the node's body axes.
    pub(crate) axes: [Mat3; 2],
}

/// A load as the interaction applies it, on a body.
#[derive(Clone, Debug)]
struct BodyLoad {
    body: usize,
    free: bool,
    force: Vec3,
    moment: Vec3,
    follower: bool,
    history: History,
    reference: Vec3,
}

/// Elements per parallel work item.
const ELEMENT_CHUNK: usize = 512;

/// The elements, loads and gravity of a beam structure, as a many-body interaction.
#[derive(Debug)]
pub struct Structure {
    pub(crate) elements: Vec<ElementData>,
    fixed_position: Vec<Vec3>,
    fixed_rotation: Vec<Mat3>,
    /// For each body, its element ends (`2 e + end`), in element order.
    incidence_start: Vec<usize>,
    incidence: Vec<u32>,
    loads: Vec<BodyLoad>,
    gravity: Vec3,
    /// Each body's initial attitude (its principal axes), for follower loads.
    body_axes: Vec<Mat3>,
    scratch: Mutex<Vec<EndForces>>,
}

impl Clone for Structure {
    fn clone(&self) -> Self {
        Structure {
            elements: self.elements.clone(),
            fixed_position: self.fixed_position.clone(),
            fixed_rotation: self.fixed_rotation.clone(),
            incidence_start: self.incidence_start.clone(),
            incidence: self.incidence.clone(),
            loads: self.loads.clone(),
            gravity: self.gravity,
            body_axes: self.body_axes.clone(),
            scratch: Mutex::new(vec![EndForces::default(); self.elements.len()]),
        }
    }
}

impl Structure {
    /// Number of elements.
    #[must_use]
    pub fn elements(&self) -> usize {
        self.elements.len()
    }

    #[inline]
    pub(crate) fn pose(&self, position: &[Vec3], rotation: &[Mat3], n: NodeRef) -> (Vec3, Mat3) {
        match n {
            NodeRef::Body(i) => (position[i], rotation[i]),
            NodeRef::Fixed(j) => (self.fixed_position[j], self.fixed_rotation[j]),
        }
    }

    /// The end forces of element `e` at the given body poses.
    #[inline]
    pub(crate) fn element_forces(&self, e: &ElementData, position: &[Vec3], rotation: &[Mat3]) -> EndForces {
        let (xa, ra) = self.pose(position, rotation, e.ends[0]);
        let (xb, rb) = self.pose(position, rotation, e.ends[1]);
        element::end_forces(&e.stiffness, xa, xb, &(ra * e.axes[0]), &(rb * e.axes[1]))
    }

    /// The element (internal) forces on every body: spatial forces and body-frame
    /// torques, no loads or gravity.
    pub fn internal_forces(&self, position: &[Vec3], rotation: &[Mat3], force: &mut [Vec3], torque: &mut [Vec3]) {
        self.internal_forces_of::<true>(position, rotation, force, torque);
    }

    /// The element forces without their axial part ([`element::bending_end_forces`]):
    /// the impulse method's slow internal forces.
    pub fn bending_forces(&self, position: &[Vec3], rotation: &[Mat3], force: &mut [Vec3], torque: &mut [Vec3]) {
        self.internal_forces_of::<false>(position, rotation, force, torque);
    }

    fn internal_forces_of<const AXIAL: bool>(
        &self,
        position: &[Vec3],
        rotation: &[Mat3],
        force: &mut [Vec3],
        torque: &mut [Vec3],
    ) {
        let mut scratch = self.scratch.lock().expect("not poisoned");
        // Every element's end forces, independently.
        let per_element = |k: usize, out: &mut [EndForces]| {
            let first = k * ELEMENT_CHUNK;
            for (o, e) in out.iter_mut().zip(&self.elements[first..]) {
                *o = if AXIAL {
                    self.element_forces(e, position, rotation)
                } else {
                    let (xa, ra) = self.pose(position, rotation, e.ends[0]);
                    let (xb, rb) = self.pose(position, rotation, e.ends[1]);
                    element::bending_end_forces(&e.stiffness, xa, xb, &(ra * e.axes[0]), &(rb * e.axes[1]))
                };
            }
        };
        // One chunk runs on the calling thread: a small structure pays no hand-off.
        #[cfg(feature = "parallel")]
        if scratch.len() > ELEMENT_CHUNK {
            use rayon::prelude::*;
            scratch
                .par_chunks_mut(ELEMENT_CHUNK)
                .enumerate()
                .for_each(|(k, out)| per_element(k, out));
        } else {
            per_element(0, &mut scratch);
        }
        #[cfg(not(feature = "parallel"))]
        for (k, out) in scratch.chunks_mut(ELEMENT_CHUNK).enumerate() {
            per_element(k, out);
        }
        // Each body sums its element ends in element order: independent of the threads.
        let ends = &*scratch;
        let gather = |first: usize, f: &mut [Vec3], t: &mut [Vec3]| {
            for (k, (f, t)) in f.iter_mut().zip(t.iter_mut()).enumerate() {
                let i = first + k;
                let (mut fi, mut mi) = (Vec3::ZERO, Vec3::ZERO);
                for &slot in &self.incidence[self.incidence_start[i]..self.incidence_start[i + 1]] {
                    let ef = &ends[(slot >> 1) as usize];
                    if slot & 1 == 0 {
                        fi += ef.force_a;
                        mi += ef.moment_a;
                    } else {
                        fi += ef.force_b;
                        mi += ef.moment_b;
                    }
                }
                *f = fi;
                *t = rotation[i].tr_mul_vec(mi);
            }
        };
        #[cfg(feature = "parallel")]
        if force.len() <= CHUNK {
            gather(0, force, torque);
        } else {
            use rayon::prelude::*;
            force
                .par_chunks_mut(CHUNK)
                .zip(torque.par_chunks_mut(CHUNK))
                .enumerate()
                .for_each(|(k, (f, t))| gather(k * CHUNK, f, t));
        }
        #[cfg(not(feature = "parallel"))]
        for (k, (f, t)) in force.chunks_mut(CHUNK).zip(torque.chunks_mut(CHUNK)).enumerate() {
            gather(k * CHUNK, f, t);
        }
    }

    /// The strain energy of every element (summed in element order).
    #[must_use]
    pub fn strain_energy(&self, position: &[Vec3], rotation: &[Mat3]) -> f64 {
        self.elements
            .iter()
            .map(|e| {
                let (xa, ra) = self.pose(position, rotation, e.ends[0]);
                let (xb, rb) = self.pose(position, rotation, e.ends[1]);
                element::strain_energy(&e.stiffness, xa, xb, &(ra * e.axes[0]), &(rb * e.axes[1]))
            })
            .sum()
    }

    /// The loads and gravity at time `t` added to `force` and `torque` (in load order).
    pub(crate) fn add_loads(&self, config: &Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        if self.gravity != Vec3::ZERO {
            for (i, f) in force.iter_mut().enumerate() {
                if config.free[i] {
                    *f += self.gravity * config.mass[i];
                }
            }
        }
        for load in &self.loads {
            let s = load.history.value(config.t);
            if s == 0.0 {
                continue;
            }
            let i = load.body;
            let r = &config.rotation[i];
            if load.follower {
                let axes = &self.body_axes[i];
                if load.free {
                    force[i] += *r * axes.tr_mul_vec(load.force) * s;
                }
                torque[i] += axes.tr_mul_vec(load.moment) * s;
            } else {
                if load.free {
                    force[i] += load.force * s;
                }
                torque[i] += r.tr_mul_vec(load.moment) * s;
            }
        }
    }
}

impl Interaction for Structure {
    fn compute(&self, config: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        self.internal_forces(config.position, config.rotation, force, torque);
        self.add_loads(&config, force, torque);
    }

    /// Strain energy, minus `m g·x` for gravity, minus `s(t) F·(x − X)` for the spatial
    /// (non-follower) nodal forces; moments and follower loads have no potential.
    fn potential_energy(&self, config: Configuration<'_>) -> f64 {
        let mut v = self.strain_energy(config.position, config.rotation);
        for i in 0..config.position.len() {
            if config.free[i] {
                v -= config.mass[i] * self.gravity.dot(config.position[i]);
            }
        }
        for load in &self.loads {
            if load.free && !load.follower {
                v -= load.history.value(config.t) * load.force.dot(config.position[load.body] - load.reference);
            }
        }
        v
    }
}

/// A built beam structure: its nodes as bodies and its elements as their interaction.
#[derive(Clone, Debug)]
pub struct BeamSystem {
    /// The nodes that move (all but the clamped ones), as rigid bodies.
    pub bodies: Bodies,
    /// Elements, loads, gravity.
    pub structure: Structure,
    /// Where each node's pose lives.
    pub nodes: Vec<NodeRef>,
    /// The model it was built from.
    pub frame: Frame,
    /// The node of each body.
    pub body_node: Vec<usize>,
    /// Each body's initial attitude (its principal axes).
    body_axes: Vec<Mat3>,
    /// The impulse method's force arrays.
    impulse: impulse::Scratch,
    /// The mass scaling's constants and arrays.
    mass_scaling: mass_scaling::Scratch,
}

/// The explicit beam integrators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BeamMethod {
    /// Verlet translations, LIEMID\[EA\] rotations: order 2.
    Splitting,
    /// Suzuki's 5-stage composition of the splitting: order 4.
    Splitting4,
    /// The impulse method (multiple time stepping): the bending, torsion and load forces
    /// at the outer step, the axial forces in Verlet substeps ([`impulse`]): order 2.
    Impulse,
    /// The splitting with selective mass scaling of the axial waves: each element's rate
    /// of stretch gets the inertia `β ρA L₀` ([`mass_scaling`]), which lowers the axial
    /// frequencies by `√(1 + 4β)` and leaves rigid motion and bending as they are: order 2.
    MassScaled,
}

impl BeamMethod {
    /// Every method.
    pub const ALL: [BeamMethod; 4] = [
        BeamMethod::Splitting,
        BeamMethod::Splitting4,
        BeamMethod::Impulse,
        BeamMethod::MassScaled,
    ];

    /// The name in files and on the command line.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            BeamMethod::Splitting => "liemid",
            BeamMethod::Splitting4 => "liemid4",
            BeamMethod::Impulse => "liemid-mts",
            BeamMethod::MassScaled => "liemid-sms",
        }
    }

    /// By name.
    #[must_use]
    pub fn from_key(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.key() == key)
    }

    /// The composition scheme (none for the base splitting).
    #[must_use]
    pub fn scheme(self) -> Option<&'static Scheme> {
        match self {
            BeamMethod::Splitting | BeamMethod::Impulse | BeamMethod::MassScaled => None,
            BeamMethod::Splitting4 => Some(&Scheme::SUZUKI4),
        }
    }

    /// Order of accuracy.
    #[must_use]
    pub fn order(self) -> u32 {
        match self {
            BeamMethod::Splitting | BeamMethod::Impulse | BeamMethod::MassScaled => 2,
            BeamMethod::Splitting4 => 4,
        }
    }

    /// One line on what the method is.
    #[must_use]
    pub fn description(self) -> &'static str {
        match self {
            BeamMethod::Splitting => "Verlet translations and LIEMID[EA] rotations of the nodes",
            BeamMethod::Splitting4 => "the splitting composed by Suzuki's 5-stage scheme",
            BeamMethod::Impulse => {
                "impulse method: bending, torsion and loads at the step, the axial forces in Verlet substeps"
            }
            BeamMethod::MassScaled => "the splitting with selective mass scaling of the axial waves",
        }
    }

    /// Internal-force evaluations per step.
    #[must_use]
    pub fn evaluations_per_step(self) -> usize {
        self.scheme().map_or(1, Scheme::stages)
    }
}

impl Frame {
    /// Build the structure: lumped nodal masses and rotary inertia, body axes, element
    /// constants, incidence, loads.
    ///
    /// # Errors
    /// A node without elements, a load on a clamped node's translation only, an element
    /// whose ends coincide, or a section coefficient that is not positive.
    pub fn build(&self) -> Result<BeamSystem> {
        let n = self.nodes.len();
        if self.elements.is_empty() {
            return Err(Error::InvalidModel {
                reason: "the model has no elements".into(),
            });
        }
        let mut mass = vec![0.0; n];
        let mut rotary = vec![Mat3::ZERO; n];
        let mut initial_axes = Vec::with_capacity(self.elements.len());
        for (k, e) in self.elements.iter().enumerate() {
            let [a, b] = e.nodes;
            if a >= n || b >= n || a == b {
                return Err(Error::InvalidModel {
                    reason: format!("element {k} joins nodes {a} and {b} (the model has {n} nodes)"),
                });
            }
            e.section.validate()?;
            let d = self.nodes[b] - self.nodes[a];
            let length = d.norm();
            if length <= 0.0 || length.is_nan() {
                return Err(Error::InvalidModel {
                    reason: format!("element {k}: nodes {a} and {b} coincide"),
                });
            }
            let e1 = d * (1.0 / length);
            let across = e.orientation - e1 * e.orientation.dot(e1);
            if across.norm() <= 1e-6 * e.orientation.norm() || across.norm().is_nan() {
                return Err(Error::InvalidModel {
                    reason: format!("element {k}: the orientation vector lies along the element"),
                });
            }
            let e2 = across * (1.0 / across.norm());
            let e3 = e1.cross(e2);
            let axes = from_columns(e1, e2, e3);
            let half = 0.5 * length;
            let j = axes * Mat3::from_diagonal(e.section.rotary_inertia * half) * axes.transpose();
            for node in [a, b] {
                mass[node] += e.section.mass_per_length * half;
                rotary[node] = rotary[node] + j;
            }
            initial_axes.push((axes, length));
        }
        let mut nodes = Vec::with_capacity(n);
        let mut bodies = Bodies::new();
        let mut body_node = Vec::new();
        let mut body_axes = Vec::new();
        let mut node_axes = vec![Mat3::IDENTITY; n];
        let (mut fixed_position, mut fixed_rotation) = (Vec::new(), Vec::new());
        for node in 0..n {
            if mass[node] == 0.0 {
                return Err(Error::InvalidModel {
                    reason: format!(
                        "node {node} at ({}, {}, {}) belongs to no element",
                        self.nodes[node].x, self.nodes[node].y, self.nodes[node].z
                    ),
                });
            }
            if self.supports[node] == Support::Clamped {
                nodes.push(NodeRef::Fixed(fixed_position.len()));
                fixed_position.push(self.nodes[node]);
                fixed_rotation.push(Mat3::IDENTITY);
                continue;
            }
            let (values, axes) = symmetric_eigen(&rotary[node])?;
            // A lumped rotary inertia is a sum of planar ones: the triangle inequality may
            // hold with equality and fail by rounding only.
            let mut m = values;
            for i in 0..3 {
                let others = m[(i + 1) % 3] + m[(i + 2) % 3];
                m[i] = m[i].min(others);
            }
            node_axes[node] = axes;
            nodes.push(NodeRef::Body(bodies.len()));
            body_node.push(node);
            body_axes.push(axes);
            bodies.push(
                mass[node],
                Vec3::from_array(m),
                self.supports[node] == Support::Free,
                self.nodes[node],
                Vec3::ZERO,
                axes,
                Vec3::ZERO,
            )?;
        }
        let elements: Vec<ElementData> = self
            .elements
            .iter()
            .zip(&initial_axes)
            .map(|(e, &(axes, length))| {
                let s = &e.section;
                ElementData {
                    ends: [nodes[e.nodes[0]], nodes[e.nodes[1]]],
                    stiffness: ElementStiffness {
                        length,
                        axial: s.axial_stiffness / length,
                        torsion: s.torsional_stiffness / length,
                        bending2: s.bending_stiffness_2 / length,
                        bending3: s.bending_stiffness_3 / length,
                    },
                    axes: [
                        node_axes[e.nodes[0]].transpose() * axes,
                        node_axes[e.nodes[1]].transpose() * axes,
                    ],
                }
            })
            .collect();
        let nb = bodies.len();
        let mut count = vec![0usize; nb + 1];
        for e in &elements {
            for end in e.ends {
                if let NodeRef::Body(i) = end {
                    count[i + 1] += 1;
                }
            }
        }
        for i in 0..nb {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut incidence = vec![0u32; count[nb]];
        for (k, e) in elements.iter().enumerate() {
            for (end, node) in e.ends.iter().enumerate() {
                if let NodeRef::Body(i) = *node {
                    incidence[fill[i]] = u32::try_from(2 * k + end).map_err(|_| Error::InvalidModel {
                        reason: "more than 2^31 elements".into(),
                    })?;
                    fill[i] += 1;
                }
            }
        }
        let mut loads = Vec::new();
        for load in &self.loads {
            if let NodeRef::Body(i) = nodes[load.node] {
                loads.push(BodyLoad {
                    body: i,
                    free: self.supports[load.node] == Support::Free,
                    force: load.force,
                    moment: load.moment,
                    follower: load.follower,
                    history: load.history.clone(),
                    reference: self.nodes[load.node],
                });
            }
        }
        let structure = Structure {
            scratch: Mutex::new(vec![EndForces::default(); elements.len()]),
            elements,
            fixed_position,
            fixed_rotation,
            incidence_start: count,
            incidence,
            loads,
            gravity: self.gravity,
            body_axes: body_axes.clone(),
        };
        let impulse = impulse::Scratch::new(bodies.len());
        let mut system = BeamSystem {
            impulse,
            mass_scaling: mass_scaling::Scratch::default(),
            bodies,
            structure,
            nodes,
            frame: self.clone(),
            body_node,
            body_axes,
        };
        system.bodies.evaluate(&system.structure);
        system.impulse.omega_axial = system.stability(0).omega_axial_bound;
        system.mass_scaling = mass_scaling::Scratch::new(&system, 0.0);
        system.mass_scaling.beta = system.default_axial_mass();
        Ok(system)
    }
}

impl BeamSystem {
    /// Number of elements.
    #[must_use]
    pub fn elements(&self) -> usize {
        self.structure.elements()
    }

    /// Time.
    #[must_use]
    pub fn t(&self) -> f64 {
        self.bodies.t
    }

    /// The current position of node `node`.
    #[must_use]
    pub fn position(&self, node: usize) -> Vec3 {
        self.structure
            .pose(&self.bodies.position, &self.bodies.rotation, self.nodes[node])
            .0
    }

    /// The displacement of node `node` from its initial position.
    #[must_use]
    pub fn displacement(&self, node: usize) -> Vec3 {
        self.position(node) - self.frame.nodes[node]
    }

    /// The rotation of node `node` from its initial attitude (spatial: `R Bᵀ`).
    #[must_use]
    pub fn rotation(&self, node: usize) -> Mat3 {
        match self.nodes[node] {
            NodeRef::Body(i) => self.bodies.rotation[i] * self.body_axes[i].transpose(),
            NodeRef::Fixed(_) => Mat3::IDENTITY,
        }
    }

    /// Put node `node` at `position`, turned by `rotation` from its initial attitude (for
    /// a clamped node nothing changes); forces are evaluated again.
    pub fn set_pose(&mut self, node: usize, position: Vec3, rotation: Mat3) {
        if let NodeRef::Body(i) = self.nodes[node] {
            if self.bodies.free[i] {
                self.bodies.position[i] = position;
            }
            self.bodies.rotation[i] = rotation * self.body_axes[i];
            self.bodies.evaluate(&self.structure);
            self.impulse.valid = false;
        }
    }

    /// Choose the node rotations' drift of the explicit methods (`liemid`, `liemid4`,
    /// `liemid-mts`, `liemid-sms`): two half steps of the midpoint equation (M) (EA's, the
    /// default) or of the variational equation (V) (EAV's, Lie–Poisson). Both are
    /// second order and symmetric; the methods' orders, reversibility and momenta are the
    /// same with either (docs/theory/rigid.md §9). Newmark does not use it.
    pub fn set_drift(&mut self, drift: Drift) {
        self.bodies.set_drift(drift);
        self.impulse.valid = false;
    }

    /// The node rotations' drift; `None` when the nodes turn by their exact free flow
    /// (set on [`BeamSystem::bodies`] by hand, the structure tests' control).
    #[must_use]
    pub fn drift(&self) -> Option<Drift> {
        self.bodies.free_rotation().drift()
    }

    /// One explicit step (see the module documentation).
    ///
    /// # Errors
    /// A bad step or a failing midpoint solve (the system is then left mid-step).
    pub fn step(&mut self, h: f64) -> Result<()> {
        self.impulse.valid = false;
        self.bodies.step(&self.structure, h)
    }

    /// One step of a symmetric composition of the splitting.
    ///
    /// # Errors
    /// As [`BeamSystem::step`].
    pub fn step_composed(&mut self, h: f64, scheme: &Scheme) -> Result<()> {
        self.impulse.valid = false;
        self.bodies.step_composed(&self.structure, h, scheme)
    }

    /// One step of `method`.
    ///
    /// # Errors
    /// As [`BeamSystem::step`].
    pub fn step_with(&mut self, method: BeamMethod, h: f64) -> Result<()> {
        match (method, method.scheme()) {
            (BeamMethod::Impulse, _) => self.step_impulse(h),
            (BeamMethod::MassScaled, _) => self.step_mass_scaled(h),
            (_, None) => self.step(h),
            (_, Some(s)) => self.step_composed(h, s),
        }
    }

    /// Energy (kinetic plus [`Structure`]'s potential) and total momenta.
    #[must_use]
    pub fn totals(&self) -> Totals {
        self.bodies.totals(&self.structure)
    }

    /// [`BeamSystem::totals`] of the system `method` steps: for
    /// [`BeamMethod::MassScaled`] the kinetic energy of the scaled mass
    /// ([`mass_scaling`]; the momenta are unchanged).
    #[must_use]
    pub fn totals_for(&self, method: BeamMethod) -> Totals {
        let mut t = self.totals();
        if method == BeamMethod::MassScaled {
            t.energy += self.mass_scaling_kinetic_correction();
        }
        t
    }

    /// The strain energy.
    #[must_use]
    pub fn strain_energy(&self) -> f64 {
        self.structure
            .strain_energy(&self.bodies.position, &self.bodies.rotation)
    }

    /// The last time at which a load changes.
    #[must_use]
    pub fn loads_end(&self) -> f64 {
        self.frame.loads.iter().map(|l| l.history.end()).fold(0.0, f64::max)
    }
}
