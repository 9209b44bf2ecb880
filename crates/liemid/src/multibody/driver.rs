//! The fixed-step driver of the multibody step, the one under every front end (the
//! `liemid multibody` command, the Python package, the tests): the model policy of a run
//! ([`Simulation::prepare`]: what is left out or projected, said as [`ModelNote`]s), the
//! time loop (the last step lands on `t_end`), the extremes of the run, and an observer
//! per step; the same loop for the joint-space reference ([`JointSpaceModel::integrate_rk4`]).
//!
//! Reference: docs/theory/multibody.md §5; `crate::rigid::driver::integrate` (the same
//! time stepping).

use crate::error::{Error, Result};

use super::joint_space::JointSpaceModel;
use super::method::{MultibodyMethod, StepReport};
use super::model::{JointKind, Model};
use super::rattle::Rattle;
use super::state::MultibodyState;
use super::system::MultibodySystem;

/// What a run did: steps and the extremes over every step.
///
/// Reference: docs/theory/multibody.md §5.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MultibodyRun {
    /// Steps taken.
    pub steps: u64,
    /// Largest relative position violation over the steps.
    pub max_position_violation: f64,
    /// Largest relative velocity violation over the steps.
    pub max_velocity_violation: f64,
    /// Largest iteration count of one step.
    pub max_iterations: u32,
    /// Total position iterations.
    pub total_iterations: u64,
    /// Largest `|E − E₀| / |E₀|` (absolute when `E₀ = 0`).
    pub max_energy_error: f64,
    /// Largest `|p − p₀|` of the total linear momentum (conserved without gravity and
    /// without joints to the world).
    pub max_linear_momentum_change: f64,
    /// Largest `|L − L₀|` of the total angular momentum about the origin.
    pub max_angular_momentum_change: f64,
    /// Most contact points of one step.
    pub max_contacts: u32,
    /// The deepest penetration found at a step's start (m).
    pub max_penetration: f64,
    /// Outer iterations of the contact position problem, and projected Gauss–Seidel
    /// sweeps of the contact problems, over the run (a solve over free bodies counts the
    /// most sweeps of its islands).
    pub contact_iterations: u64,
    /// See `contact_iterations`.
    pub contact_sweeps: u64,
    /// Contact steps redone as two half steps because their solve failed (all levels).
    pub split_steps: u64,
    /// Contact stages whose drift held no contact by friction
    /// (`StepReport::frictionless_drifts`).
    pub frictionless_drifts: u64,
    /// Contact stages taken at the looser tolerance (`StepReport::loose_steps`), and the
    /// largest violation among them (relative to the contact length).
    pub loose_steps: u64,
    /// See `loose_steps`.
    pub max_loose_violation: f64,
}

impl MultibodyRun {
    /// Fold one step's report into the run's statistics (not the energy and momenta).
    fn record(&mut self, k: u64, report: &StepReport) {
        self.steps = k;
        self.max_position_violation = self.max_position_violation.max(report.position_violation);
        self.max_velocity_violation = self.max_velocity_violation.max(report.velocity_violation);
        self.max_iterations = self.max_iterations.max(report.iterations);
        self.total_iterations += u64::from(report.iterations);
        self.max_contacts = self.max_contacts.max(report.contacts);
        self.max_penetration = self.max_penetration.max(report.penetration);
        self.contact_iterations += u64::from(report.contact_iterations);
        self.contact_sweeps += u64::from(report.contact_sweeps);
        self.split_steps += u64::from(report.split_steps);
        self.frictionless_drifts += u64::from(report.frictionless_drifts);
        self.loose_steps += u64::from(report.loose_steps);
        self.max_loose_violation = self.max_loose_violation.max(report.loose_violation);
    }
}

/// What a run of a model leaves out or changes, said once before it runs (the command
/// prints it, Python returns it).
#[derive(Clone, Debug, PartialEq)]
pub enum ModelNote {
    /// Armature on the joints named (slide, ball and free joints, loop-closing hinges: a
    /// rotor inertia that is configuration-dependent in maximal coordinates); the
    /// maximal-coordinate methods run without it there. Tree hinges keep theirs exactly.
    ArmatureDropped(String),
    /// The joint-space reference integrates the joints free of their ranges.
    LimitsIgnored,
    /// Actuators with a viscous part (`kv`, a velocity bias) and a force clamp
    /// (`forcerange`, the joint's `actuatorfrcrange`): the maximal-coordinate methods
    /// hold the viscous part implicitly as a joint damper outside the clamp, so the
    /// force is MuJoCo's while the clamp is not reached.
    ActuatorDampingUnclamped {
        /// How many actuators.
        actuators: usize,
    },
    /// The start violated the loop-closing joints (relative violations before the
    /// projection) and was projected onto them.
    StartProjected {
        /// Relative position violation.
        position: f64,
        /// Relative velocity violation.
        velocity: f64,
    },
    /// The model's shapes touch, but this method runs without contacts (only `liemid`
    /// has them: a composition's negative sub-steps cannot run a dissipative contact, and
    /// the joint-space reference has none).
    ContactsIgnored(&'static str),
    /// A mesh a page cannot draw from its file (a viewer's note: drawing is not physics).
    MeshNotDrawn {
        /// The geom (MJCF) or visual (URDF) and its body, in words.
        geom: String,
        /// The file as the model names it.
        file: String,
        /// Why: the file is missing, unreadable, of another format, not a mesh.
        reason: String,
        /// Whether the box of the geom's `size` is drawn in its place (else nothing is).
        boxed: bool,
    },
    /// A mesh a page draws with fewer triangles than its file has, to keep the page within
    /// its size budget.
    MeshSimplified {
        /// The file as the model names it.
        file: String,
        /// The file's triangles.
        triangles: usize,
        /// The triangles drawn.
        kept: usize,
    },
}

impl ModelNote {
    /// Whether the note names content of the model that is not simulated (as opposed to a
    /// change of the start).
    #[must_use]
    pub fn is_ignored_content(&self) -> bool {
        matches!(
            self,
            ModelNote::ArmatureDropped(_) | ModelNote::LimitsIgnored | ModelNote::ContactsIgnored(_)
        )
    }
}

impl core::fmt::Display for ModelNote {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ModelNote::ArmatureDropped(joints) => write!(
                f,
                "joint armature on {joints} (exact in maximal coordinates on tree hinges only; --method rk4 keeps it)"
            ),
            ModelNote::LimitsIgnored => {
                f.write_str("joint limits (the joint-space reference has none; the liemid methods keep them)")
            }
            ModelNote::ActuatorDampingUnclamped { actuators } => write!(
                f,
                "the force clamp of {actuators} actuator(s) with a viscous part (kv): the liemid methods hold kv \
                 as an implicit joint damper outside the clamp (exact while the clamp is not reached; --method rk4 \
                 clamps the whole force)"
            ),
            ModelNote::StartProjected { position, velocity } => write!(
                f,
                "the start violated the loop-closing joints (relative position {position:.1e}, velocity \
                 {velocity:.1e}); projected onto them"
            ),
            ModelNote::ContactsIgnored(method) => write!(
                f,
                "contacts between the model's shapes ({method} runs without them; --method liemid has them)"
            ),
            ModelNote::MeshNotDrawn {
                geom,
                file,
                reason,
                boxed,
            } => write!(
                f,
                "the mesh of {geom} is not drawn from `{file}`: {reason}; {}",
                if *boxed {
                    "the box of the geom's size stands in for it"
                } else {
                    "nothing is drawn in its place"
                }
            ),
            ModelNote::MeshSimplified { file, triangles, kept } => write!(
                f,
                "the mesh `{file}` is drawn simplified, {kept} of its {triangles} triangles (the page's size \
                 budget)"
            ),
        }
    }
}

/// A simulation ready to run, its start, and what the model policy changed.
#[derive(Debug)]
pub struct Prepared {
    /// The system and its integrator.
    pub simulation: Simulation,
    /// The start (on the loop-closing joints).
    pub state: MultibodyState,
    /// What was left out or projected, in that order.
    pub notes: Vec<ModelNote>,
}

/// The notes of a run of `model` in joint coordinates ([`JointSpaceModel`]).
#[must_use]
pub fn joint_space_notes(model: &Model) -> Vec<ModelNote> {
    let mut notes = Vec::new();
    if model.joints.iter().any(|j| j.range.is_some()) {
        notes.push(ModelNote::LimitsIgnored);
    }
    if model.collision.any() {
        notes.push(ModelNote::ContactsIgnored("the joint-space reference"));
    }
    notes
}

impl Rattle {
    /// Integrate from `state.t` to `t_end` with step `h` (the last step lands on `t_end`),
    /// calling `observer(k, state, report, integrator)` after every step (the integrator
    /// for what the step left, as [`Rattle::contact_forces`]); returns the extremes.
    ///
    /// # Errors
    /// The step's errors, [`crate::rigid::driver::step_count`]'s,
    /// [`Error::NonFiniteResult`] when a step leaves a non-finite energy, and
    /// [`Error::ObserverFailed`] when the observer returns an error.
    ///
    /// Reference: `crate::rigid::driver::integrate` (the same time stepping).
    pub fn integrate<O>(
        &mut self,
        system: &MultibodySystem,
        state: &mut MultibodyState,
        t_end: f64,
        h: f64,
        mut observer: O,
    ) -> Result<MultibodyRun>
    where
        O: FnMut(u64, &MultibodyState, &StepReport, &Rattle) -> core::result::Result<(), String>,
    {
        let t0 = state.t;
        let n = crate::rigid::driver::step_count(t0, t_end, h)?;
        let e0 = system.energy(state);
        let (p0, l0) = (system.linear_momentum(state), system.angular_momentum(state));
        let mut run = MultibodyRun::default();
        for k in 1..=n {
            let t_next = if k == n { t_end } else { t0 + k as f64 * h };
            let report = self.step(system, state, t_next - state.t)?;
            self.work.set_time(state, t_next);
            run.record(k, &report);
            let energy = system.energy(state);
            if !energy.is_finite() {
                return Err(Error::NonFiniteResult {
                    method: self.work.method_name,
                    t: state.t,
                    h,
                });
            }
            let de = (energy - e0).abs();
            run.max_energy_error = run.max_energy_error.max(if e0 != 0.0 { de / e0.abs() } else { de });
            let dp = (system.linear_momentum(state) - p0).norm();
            run.max_linear_momentum_change = run.max_linear_momentum_change.max(dp);
            let dl = (system.angular_momentum(state) - l0).norm();
            run.max_angular_momentum_change = run.max_angular_momentum_change.max(dl);
            observer(k, state, &report, self).map_err(|reason| Error::ObserverFailed { t: state.t, reason })?;
        }
        Ok(run)
    }
}

/// A system and its integrator together: what the front ends (the `liemid multibody`
/// command, the Python package) and most tests step. The model stays apart from the
/// working memory ([`MultibodySystem`], [`Rattle`]); this only pairs them so that a call
/// cannot hand an integrator the wrong system.
///
/// Reference: docs/theory/multibody.md §3.
#[derive(Debug)]
pub struct Simulation {
    /// The model data, read by every step.
    pub system: MultibodySystem,
    /// The method and its working memory.
    pub integrator: Rattle,
}

impl Simulation {
    /// What every front end runs: `model` by `method` under the model policy of the
    /// maximal-coordinate methods. Hinge armature is kept, exactly (docs/theory/multibody.md
    /// §7); armature on other joints is dropped ([`ModelNote::ArmatureDropped`] names them:
    /// configuration-dependent in maximal coordinates), and a
    /// start off the loop-closing joints (a keyframe written for MuJoCo's soft equalities)
    /// is projected onto them ([`ModelNote::StartProjected`] when the violation exceeded
    /// `1e-12`).
    ///
    /// # Errors
    /// [`MultibodySystem::new`]'s and [`Rattle::initial_state_on_loops`]'s errors;
    /// [`Error::InvalidModel`] when the start's energy is not finite.
    ///
    /// Reference: docs/theory/multibody.md §3 (the model), §6 (the projection).
    pub fn prepare(model: &Model, method: MultibodyMethod) -> Result<Prepared> {
        let mut notes = Vec::new();
        let stripped;
        let nb = model.bodies.len();
        let inexact =
            |k: usize, j: &super::Joint| j.armature != 0.0 && (k >= nb || !matches!(j.kind, JointKind::Hinge { .. }));
        let model = if model.joints.iter().enumerate().any(|(k, j)| inexact(k, j)) {
            let mut m = model.clone();
            let mut named = Vec::new();
            for (k, j) in m.joints.iter_mut().enumerate() {
                if inexact(k, j) {
                    let kind = if k >= nb { "loop-closing hinge" } else { j.kind.name() };
                    named.push(format!("`{}` ({kind})", crate::error::abbreviate(&j.name)));
                    j.armature = 0.0;
                }
            }
            notes.push(ModelNote::ArmatureDropped(named.join(", ")));
            stripped = m;
            &stripped
        } else {
            model
        };
        let without_contacts;
        let model = if method != MultibodyMethod::Liemid && model.collision.any() {
            let mut m = model.clone();
            m.collision.disabled = true;
            notes.push(ModelNote::ContactsIgnored(method.name()));
            without_contacts = m;
            &without_contacts
        } else {
            model
        };
        let unclamped = model
            .actuators
            .iter()
            .filter(|a| {
                a.bias[2] != 0.0 && (a.force_range.is_some() || model.joints[a.joint].actuator_force_range.is_some())
            })
            .count();
        if unclamped > 0 {
            notes.push(ModelNote::ActuatorDampingUnclamped { actuators: unclamped });
        }
        let mut simulation = Simulation::new(model, method)?;
        let (state, position, velocity) = simulation.initial_state_on_loops(model)?;
        let energy = simulation.system.energy(&state);
        if !energy.is_finite() {
            return Err(Error::InvalidModel {
                reason: format!(
                    "the start's energy is {} (a velocity or position too large for f64; rescale the units)",
                    crate::error::Num(energy)
                ),
            });
        }
        if let Err(s) = simulation.integrator.check_start_rows(&simulation.system, &state) {
            return Err(Error::InvalidModel {
                reason: format!(
                    "the constraint rows are dependent at the start, at {} (relative pivot {:.1e}): a body of \
                     (nearly) zero mass or inertia beside much heavier ones, or joints whose rows repeat each other",
                    simulation.system.describe_block(&s),
                    s.ratio
                ),
            });
        }
        if position > 1e-12 || velocity > 1e-12 {
            notes.push(ModelNote::StartProjected { position, velocity });
        }
        Ok(Prepared {
            simulation,
            state,
            notes,
        })
    }

    /// The system of `model` and its integrator by `method`.
    ///
    /// # Errors
    /// [`MultibodySystem::new`]'s errors.
    pub fn new(model: &super::Model, method: super::MultibodyMethod) -> Result<Self> {
        let system = MultibodySystem::new(model)?;
        let integrator = Rattle::new(&system, method);
        Ok(Simulation { system, integrator })
    }

    /// Set the control held over the next steps ([`MultibodySystem::set_ctrl`]).
    ///
    /// # Errors
    /// [`MultibodySystem::set_ctrl`]'s errors.
    pub fn set_ctrl(&mut self, ctrl: &[f64]) -> Result<()> {
        self.system.set_ctrl(ctrl)
    }

    /// One step ([`Rattle::step`]).
    ///
    /// # Errors
    /// [`Rattle::step`]'s errors.
    pub fn step(&mut self, state: &mut MultibodyState, h: f64) -> Result<StepReport> {
        self.integrator.step(&self.system, state, h)
    }

    /// Integrate to `t_end` ([`Rattle::integrate`]).
    ///
    /// # Errors
    /// [`Rattle::integrate`]'s errors.
    pub fn integrate<O>(&mut self, state: &mut MultibodyState, t_end: f64, h: f64, observer: O) -> Result<MultibodyRun>
    where
        O: FnMut(u64, &MultibodyState, &StepReport, &Rattle) -> core::result::Result<(), String>,
    {
        self.check_step(state, h)?;
        self.integrator.integrate(&self.system, state, t_end, h, observer)
    }

    /// Refuse a step `h` at which the method cannot hold a damper or actuator row, naming
    /// the joint and the largest step that holds it ([`Rattle::check_step`]); the
    /// integrator is not touched.
    ///
    /// # Errors
    /// [`Rattle::check_step`]'s.
    pub fn check_step(&self, state: &MultibodyState, h: f64) -> Result<()> {
        self.integrator.check_step(&self.system, state, h)
    }

    /// Integrate to `t_end` as [`Rattle::integrate`], the control set before every step:
    /// `control(system, state, ctrl)` writes the control held over the step from
    /// `state.t` into `ctrl` (which holds the previous step's; one buffer for the run),
    /// then [`MultibodySystem::set_ctrl`] checks it (its length, finite values) — the
    /// control of a Python callback, a table ([`super::control::ControlTable`], held) or a
    /// constant. `observer(k, system, state, report, integrator)` after every step.
    ///
    /// # Errors
    /// [`Rattle::integrate`]'s; [`Error::ObserverFailed`] when `control` returns an error;
    /// [`Error::InvalidModel`] naming the actuator of a control that is not finite.
    ///
    /// Reference: docs/theory/multibody.md §8.
    pub fn integrate_controlled<C, O>(
        &mut self,
        state: &mut MultibodyState,
        t_end: f64,
        h: f64,
        mut control: C,
        mut observer: O,
    ) -> Result<MultibodyRun>
    where
        C: FnMut(&MultibodySystem, &MultibodyState, &mut [f64]) -> core::result::Result<(), String>,
        O: FnMut(u64, &MultibodySystem, &MultibodyState, &StepReport, &Rattle) -> core::result::Result<(), String>,
    {
        let t0 = state.t;
        let n = crate::rigid::driver::step_count(t0, t_end, h)?;
        let e0 = self.system.energy(state);
        let (p0, l0) = (self.system.linear_momentum(state), self.system.angular_momentum(state));
        let mut run = MultibodyRun::default();
        self.check_step(state, h)?;
        let mut ctrl = self.system.ctrl.clone();
        for k in 1..=n {
            control(&self.system, state, &mut ctrl).map_err(|reason| Error::ObserverFailed { t: state.t, reason })?;
            self.system.set_ctrl(&ctrl)?;
            let t_next = if k == n { t_end } else { t0 + k as f64 * h };
            let report = self.integrator.step(&self.system, state, t_next - state.t)?;
            self.integrator.work.set_time(state, t_next);
            run.record(k, &report);
            let energy = self.system.energy(state);
            if !energy.is_finite() {
                return Err(Error::NonFiniteResult {
                    method: self.integrator.work.method_name,
                    t: state.t,
                    h,
                });
            }
            let de = (energy - e0).abs();
            run.max_energy_error = run.max_energy_error.max(if e0 != 0.0 { de / e0.abs() } else { de });
            let dp = (self.system.linear_momentum(state) - p0).norm();
            run.max_linear_momentum_change = run.max_linear_momentum_change.max(dp);
            let dl = (self.system.angular_momentum(state) - l0).norm();
            run.max_angular_momentum_change = run.max_angular_momentum_change.max(dl);
            observer(k, &self.system, state, &report, &self.integrator)
                .map_err(|reason| Error::ObserverFailed { t: state.t, reason })?;
        }
        Ok(run)
    }

    /// The constraint violations of `state` with the integrator's active limits
    /// ([`Rattle::constraint_violation`]).
    #[must_use]
    pub fn constraint_violation(&self, state: &MultibodyState) -> (f64, f64) {
        self.integrator.constraint_violation(&self.system, state)
    }

    /// [`Rattle::project_velocities`] on this system.
    ///
    /// # Errors
    /// [`Rattle::project_velocities`]'s errors.
    pub fn project_velocities(&mut self, state: &mut MultibodyState) -> Result<f64> {
        self.integrator.project_velocities(&self.system, state)
    }

    /// [`Rattle::project_positions`] on this system.
    ///
    /// # Errors
    /// [`Rattle::project_positions`]'s errors.
    pub fn project_positions(&mut self, state: &mut MultibodyState) -> Result<f64> {
        self.integrator.project_positions(&self.system, state)
    }

    /// [`Rattle::initial_state_on_loops`] on this system (`model` the one it was built
    /// from).
    ///
    /// # Errors
    /// [`Rattle::initial_state_on_loops`]'s errors.
    pub fn initial_state_on_loops(&mut self, model: &super::Model) -> Result<(MultibodyState, f64, f64)> {
        self.integrator.initial_state_on_loops(&self.system, model)
    }
}

/// What a joint-space run did: steps and the largest energy error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointSpaceRun {
    /// Steps taken.
    pub steps: u64,
    /// Largest `|E − E₀| / |E₀|` (absolute when `E₀ = 0`).
    pub max_energy_error: f64,
}

impl JointSpaceModel {
    /// [`Self::integrate_rk4`] with the control set before every step:
    /// `control(t, q, v, ctrl)` writes the control held over the step from `t` into `ctrl`
    /// (one buffer for the run), checked by [`JointSpaceModel::set_ctrl`].
    ///
    /// # Errors
    /// [`Self::integrate_rk4`]'s; [`Error::ObserverFailed`] when `control` fails;
    /// [`Error::InvalidModel`] naming the actuator of a control that is not finite.
    ///
    /// Reference: docs/theory/multibody.md §8.
    pub fn integrate_rk4_controlled<C, O>(
        &mut self,
        q: &mut [f64],
        v: &mut [f64],
        (t0, t_end, h): (f64, f64, f64),
        mut control: C,
        mut observer: O,
    ) -> Result<JointSpaceRun>
    where
        C: FnMut(f64, &[f64], &[f64], &mut [f64]) -> core::result::Result<(), String>,
        O: FnMut(u64, f64, &[f64], &[f64]) -> core::result::Result<(), String>,
    {
        let n = crate::rigid::driver::step_count(t0, t_end, h)?;
        let e0 = self.energy(q, v)?;
        let mut run = JointSpaceRun::default();
        let mut t = t0;
        let mut ctrl = self.ctrl().to_vec();
        for k in 1..=n {
            control(t, q, v, &mut ctrl).map_err(|reason| Error::ObserverFailed { t, reason })?;
            self.set_ctrl(&ctrl)?;
            let t_next = if k == n { t_end } else { t0 + k as f64 * h };
            self.rk4_step(q, v, t_next - t)?;
            t = t_next;
            if !q.iter().chain(v.iter()).all(|x| x.is_finite()) {
                return Err(Error::NonFiniteResult {
                    method: "RK4 (joint coordinates)",
                    t,
                    h,
                });
            }
            run.steps = k;
            let de = (self.energy(q, v).unwrap_or(f64::NAN) - e0).abs();
            let relative = if e0 != 0.0 { de / e0.abs() } else { de };
            run.max_energy_error = run.max_energy_error.max(relative);
            observer(k, t, q, v).map_err(|reason| Error::ObserverFailed { t, reason })?;
        }
        Ok(run)
    }

    /// Integrate `(q, v)` from `t0` to `t_end` by classical RK4 ([`JointSpaceModel::rk4_step`])
    /// with step `h` (the last step lands on `t_end`), calling `observer(k, t, q, v)` after
    /// every step; returns the steps and the largest energy error. The reference the
    /// maximal-coordinate methods are measured against: fourth order, no invariant kept.
    ///
    /// # Errors
    /// [`JointSpaceModel::rk4_step`]'s errors; [`Error::NonFiniteResult`] when a step leaves
    /// a non-finite coordinate; [`Error::ObserverFailed`] when the observer returns an error.
    ///
    /// Reference: `crate::rigid::driver::integrate` (the same time stepping).
    pub fn integrate_rk4<O>(
        &mut self,
        q: &mut [f64],
        v: &mut [f64],
        (t0, t_end, h): (f64, f64, f64),
        mut observer: O,
    ) -> Result<JointSpaceRun>
    where
        O: FnMut(u64, f64, &[f64], &[f64]) -> core::result::Result<(), String>,
    {
        let n = crate::rigid::driver::step_count(t0, t_end, h)?;
        let e0 = self.energy(q, v)?;
        let mut run = JointSpaceRun::default();
        let mut t = t0;
        for k in 1..=n {
            let t_next = if k == n { t_end } else { t0 + k as f64 * h };
            self.rk4_step(q, v, t_next - t)?;
            t = t_next;
            if !q.iter().chain(v.iter()).all(|x| x.is_finite()) {
                return Err(Error::NonFiniteResult {
                    method: "RK4 (joint coordinates)",
                    t,
                    h,
                });
            }
            run.steps = k;
            let de = (self.energy(q, v).unwrap_or(f64::NAN) - e0).abs();
            let relative = if e0 != 0.0 { de / e0.abs() } else { de };
            run.max_energy_error = run.max_energy_error.max(relative);
            observer(k, t, q, v).map_err(|reason| Error::ObserverFailed { t, reason })?;
        }
        Ok(run)
    }
}
