//! The multibody system: what a [`Model`] says, in the form the step reads it (mass
//! properties, joint geometry, force parameters), immutable while stepping. The working
//! memory of a method lives apart, in the `Workspace` (`workspace.rs`) inside
//! [`super::Rattle`]; one system can be stepped by several integrators (as Pinocchio's
//! `Model` by several `Data`, MuJoCo's `mjModel` by several `mjData`).
//!
//! Reference: docs/theory/multibody.md §1 (state and model), §2 (joints).

use crate::error::{Error, Result};
use crate::inertia::Inertia;
use crate::linalg::{Mat3, Vec3};

use super::armature::Armature;
use super::constraints::{JointGeometry, JointParams};
use super::contact::ContactGeometry;
use super::model::{JointKind, Model};

/// A force law added to gravity, springs and constant loads: given the time and the
/// configuration (centres of mass `c`, attitudes `R`), add to each body's force (space,
/// at the centre of mass) and torque (body frame). Forces that depend on the positions
/// only keep the step symmetric and the energy bounded when they are the gradient of a potential. A hook is part
/// of the system, which steps read only: it takes `&self` (keep counters in atomics).
///
/// Reference: docs/theory/multibody.md §3 (`F(q)`, `T(q)`).
pub trait ForceHook: Send + Sync {
    /// Add the forces and body torques at `(t, c, rotation)`.
    fn add(&self, t: f64, c: &[Vec3], rotation: &[Mat3], force: &mut [Vec3], torque: &mut [Vec3]);
}

impl<F> ForceHook for F
where
    F: Fn(f64, &[Vec3], &[Mat3], &mut [Vec3], &mut [Vec3]) + Send + Sync,
{
    fn add(&self, t: f64, c: &[Vec3], rotation: &[Mat3], force: &mut [Vec3], torque: &mut [Vec3]) {
        self(t, c, rotation, force, torque);
    }
}

/// A multibody system built from a validated [`Model`]: structure, mass properties and
/// forces. Stepped by [`super::Rattle`], which holds every scratch array.
///
/// Reference: docs/theory/multibody.md §1-§2.
pub struct MultibodySystem {
    pub(super) name: String,
    /// The bodies' and the joints' names, for messages.
    pub(super) body_names: Vec<String>,
    pub(super) joint_names: Vec<String>,
    pub(super) mass: Vec<f64>,
    pub(super) inertia: Vec<Inertia>,
    pub(super) inertia_matrix: Vec<Mat3>,
    /// The rotational mass matrix `𝕁` with hinge armature (`None`: no armature, `𝕁` block
    /// diagonal, the per-body path).
    pub(super) armature: Option<Armature>,
    pub(super) com: Vec<Vec3>,
    pub(super) joints: Vec<JointGeometry>,
    pub(super) pairs: Vec<(Option<usize>, usize)>,
    pub(super) params: Vec<JointParams>,
    pub(super) gravity: Vec3,
    pub(super) length: f64,
    pub(super) has_damping: bool,
    /// Whether a joint has dry friction (`frictionloss`).
    pub(super) has_friction: bool,
    pub(super) const_force: Vec<Vec3>,
    pub(super) const_torque: Vec<Vec3>,
    pub(super) hook: Option<Box<dyn ForceHook>>,
    /// The actuators, grouped by joint (`actuated`: the joint and the range of its
    /// actuators in `actuators`, in joint order), and the current control (one value per
    /// actuator, in the model's order; `actuator_order` maps a group position to it).
    pub(super) actuators: Vec<super::model::Actuator>,
    pub(super) actuator_order: Vec<usize>,
    pub(super) actuated: Vec<(usize, core::ops::Range<usize>)>,
    pub(super) actuator_names: Vec<String>,
    pub(super) ctrl: Vec<f64>,
    /// The summed actuator force clamp per joint (`actuatorfrcrange`).
    pub(super) joint_force_range: Vec<Option<(f64, f64)>>,
    /// The contact geometry (`None`: nothing can touch, or contacts switched off).
    pub(super) contact: Option<ContactGeometry>,
    /// Counts the edits of the forces ([`Self::set_body_load`], [`Self::set_force_hook`]),
    /// so that an integrator's cached start forces are known to be stale.
    pub(super) revision: u64,
}

impl core::fmt::Debug for MultibodySystem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("MultibodySystem")
            .field("name", &self.name)
            .field("bodies", &self.mass.len())
            .field("joints", &self.joints.len())
            .finish_non_exhaustive()
    }
}

impl MultibodySystem {
    /// Whether the system has contacts: shapes that can touch, contacts switched on.
    #[must_use]
    pub fn has_contacts(&self) -> bool {
        self.contact.is_some()
    }

    /// The contact length scale `L` the contact solves' tolerances are relative to (m;
    /// `None` without contacts; docs/theory/multibody.md §6).
    pub fn contact_length(&self) -> Option<f64> {
        self.contact.as_ref().map(|g| g.length)
    }

    /// Build the system of a model: validate it, precompute the joint geometry and the
    /// force parameters.
    ///
    /// # Errors
    /// [`Model::validate`]'s errors; [`Error::InvalidModel`] for armature on a joint other
    /// than a tree hinge (slide, ball and free armature are configuration-dependent in
    /// maximal coordinates, docs/theory/multibody.md §7).
    pub fn new(model: &Model) -> Result<Self> {
        model.validate()?;
        for (a, act) in model.actuators.iter().enumerate() {
            if act.gain[2] != 0.0 {
                return Err(Error::InvalidModel {
                    reason: format!(
                        "actuator `{}` ({a}): a gain that depends on the velocity (gainprm[2] = {}) is not simulated \
                         by the maximal-coordinate methods (--method rk4 has it)",
                        act.name, act.gain[2]
                    ),
                });
            }
        }
        let nb = model.bodies.len();
        let nj = model.joints.len();
        for (k, j) in model.joints.iter().enumerate() {
            let hinge = matches!(j.kind, JointKind::Hinge { .. });
            if j.armature != 0.0
                && (!hinge || k >= nb || j.armature.is_nan() || j.armature <= 0.0 || !j.armature.is_finite())
            {
                return Err(Error::InvalidModel {
                    reason: format!(
                        "joint `{}` ({k}): armature = {} is supported on tree hinges only (positive): a rotor inertia \
                         on a {} joint is configuration-dependent in maximal coordinates (remove it or model the rotor \
                         as a body)",
                        j.name,
                        j.armature,
                        if hinge { "loop-closing" } else { j.kind.name() }
                    ),
                });
            }
        }
        let inertia = (0..nb).map(|i| model.inertia(i)).collect::<Result<Vec<_>>>()?;
        let joints: Vec<JointGeometry> = (0..nj).map(|k| JointGeometry::new(model, k)).collect();
        let pairs: Vec<_> = joints.iter().map(|g| (g.parent, g.child)).collect();
        let inertia_matrix: Vec<Mat3> = inertia.iter().map(|i| *i.matrix()).collect();
        let hinges: Vec<_> = (0..nb)
            .filter(|&k| model.joints[k].armature > 0.0)
            .map(|k| {
                let g = &joints[k];
                (g.child, model.joints[k].armature, g.u_child, g.u_parent, g.parent)
            })
            .collect();
        let armature = if hinges.is_empty() {
            None
        } else {
            Some(
                Armature::new(&inertia_matrix, &hinges).ok_or_else(|| Error::InvalidModel {
                    reason: "the rotational mass matrix with armature is singular".to_string(),
                })?,
            )
        };
        let params: Vec<_> = model
            .joints
            .iter()
            .map(|j| {
                let one_dof = matches!(j.kind, JointKind::Hinge { .. } | JointKind::Slide { .. });
                JointParams {
                    stiffness: if one_dof || j.kind == JointKind::Ball {
                        j.stiffness
                    } else {
                        0.0
                    },
                    spring_ref: j.spring_ref,
                    damping: if one_dof || j.kind == JointKind::Ball {
                        j.damping
                    } else {
                        0.0
                    },
                    frictionloss: if one_dof { j.frictionloss } else { 0.0 },
                    range: if one_dof { j.range } else { None },
                }
            })
            .collect();
        let mut params: Vec<JointParams> = params;
        // An actuator's viscous bias `b₂ V` is a damper `−gear² b₂ q̇` on its joint, held
        // implicitly with the joint's own (docs/theory/multibody.md §8).
        for act in &model.actuators {
            params[act.joint].damping += act.damping();
        }
        let mut actuator_order: Vec<usize> = (0..model.actuators.len()).collect();
        actuator_order.sort_by_key(|&a| model.actuators[a].joint);
        let actuators: Vec<_> = actuator_order.iter().map(|&a| model.actuators[a].clone()).collect();
        let mut actuated: Vec<(usize, core::ops::Range<usize>)> = Vec::new();
        for (k, act) in actuators.iter().enumerate() {
            match actuated.last_mut() {
                Some((j, r)) if *j == act.joint => r.end = k + 1,
                _ => actuated.push((act.joint, k..k + 1)),
            }
        }
        let z3 = vec![Vec3::ZERO; nb];
        let com: Vec<Vec3> = model.bodies.iter().map(|b| b.com).collect();
        let body_names: Vec<String> = model.bodies.iter().map(|b| b.name.clone()).collect();
        // The tree's parent of each body (its first joint's parent).
        let mut parents = vec![None; nb];
        for g in joints.iter().take(nb) {
            parents[g.child] = g.parent;
        }
        let contact = ContactGeometry::new(&model.collision, &com, &parents, &body_names)
            .map_err(|reason| Error::InvalidModel { reason })?;
        Ok(MultibodySystem {
            name: model.name.clone(),
            body_names,
            joint_names: model.joints.iter().map(|j| j.name.clone()).collect(),
            mass: model.bodies.iter().map(|b| b.mass).collect(),
            inertia_matrix,
            armature,
            inertia,
            com,
            contact,
            has_damping: params.iter().any(|p| p.damping > 0.0),
            has_friction: params.iter().any(|p| p.frictionloss > 0.0),
            params,
            pairs,
            joints,
            gravity: model.gravity,
            length: model.length_scale(),
            const_force: z3.clone(),
            const_torque: z3,
            hook: None,
            actuator_names: model.actuators.iter().map(|a| a.name.clone()).collect(),
            ctrl: model.ctrl.clone().unwrap_or_else(|| vec![0.0; model.actuators.len()]),
            actuators,
            actuator_order,
            actuated,
            joint_force_range: model.joints.iter().map(|j| j.actuator_force_range).collect(),
            revision: 0,
        })
    }

    /// The rotational body blocks of the constraint solves: `I_i`, or `𝕁_ii` with hinge
    /// armature (docs/theory/multibody.md §7).
    pub(super) fn rotational_blocks(&self) -> &[Mat3] {
        self.armature.as_ref().map_or(&self.inertia_matrix, |a| &a.block)
    }

    /// Whether some hinge has armature: the rotations then drift as one coupled system
    /// (docs/theory/multibody.md §7).
    #[must_use]
    pub fn has_armature(&self) -> bool {
        self.armature.is_some()
    }

    /// The model's name.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Where a singular tree block lies, in words: "joint `j`" or "body `b`".
    pub(super) fn describe_block(&self, s: &super::blocks::SingularPivot) -> String {
        match (s.joint, s.body) {
            (Some(j), _) => format!("joint `{}`", self.joint_names[j]),
            (None, Some(b)) => format!("body `{}`", self.body_names[b]),
            (None, None) => "a tree block".to_string(),
        }
    }

    /// The model's length scale `L` (see [`Model::length_scale`]).
    #[must_use]
    pub fn length_scale(&self) -> f64 {
        self.length
    }

    /// The floor `√(|g| L)` of the velocity scale of the relative velocity violation, so
    /// that a body at rest (against a limit, at the bottom of a swing) does not divide a
    /// round-off rate by a round-off speed.
    #[must_use]
    pub fn velocity_floor(&self) -> f64 {
        (self.gravity.norm() * self.length).sqrt()
    }

    /// Number of bodies.
    #[must_use]
    pub fn body_count(&self) -> usize {
        self.mass.len()
    }

    /// Number of joints (tree joints first, then loop-closing ones).
    #[must_use]
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// A constant force (space, at the centre of mass) and body-frame torque on body `i`;
    /// the force has the potential `−F·c` (included in the energy), the body torque none.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for an index out of range or a non-finite vector.
    pub fn set_body_load(&mut self, i: usize, force: Vec3, torque: Vec3) -> Result<()> {
        if i >= self.mass.len() || !force.is_finite() || !torque.is_finite() {
            return Err(Error::InvalidParameter {
                name: "body load",
                value: i as f64,
                reason: "body index out of range or load not finite",
            });
        }
        self.const_force[i] = force;
        self.const_torque[i] = torque;
        self.revision += 1;
        Ok(())
    }

    /// Number of actuators.
    #[must_use]
    pub fn actuator_count(&self) -> usize {
        self.ctrl.len()
    }

    /// The actuators' names, in the model's order (the order of `ctrl`).
    #[must_use]
    pub fn actuator_names(&self) -> &[String] {
        &self.actuator_names
    }

    /// The current control, one value per actuator in the model's order.
    #[must_use]
    pub fn ctrl(&self) -> &[f64] {
        &self.ctrl
    }

    /// Set the control (held over the following steps until set again; MuJoCo's
    /// `d.ctrl`). Each value is clamped to its actuator's `ctrlrange` when the forces are
    /// evaluated. An unchanged control keeps the integrator's cached start forces.
    ///
    /// # Errors
    /// [`Error::InvalidModel`] naming the actuator for a length other than
    /// [`Self::actuator_count`] or a value that is not finite (MuJoCo zeroes every control
    /// on a NaN; here it is refused).
    pub fn set_ctrl(&mut self, ctrl: &[f64]) -> Result<()> {
        check_ctrl(&self.actuator_names, ctrl)?;
        if ctrl != self.ctrl.as_slice() {
            self.ctrl.copy_from_slice(ctrl);
            self.revision += 1;
        }
        Ok(())
    }

    /// Install a force hook (replacing any earlier one).
    pub fn set_force_hook(&mut self, hook: Box<dyn ForceHook>) {
        self.hook = Some(hook);
        self.revision += 1;
    }
}

/// Check a control vector against the actuators' names: the length, every value finite.
///
/// # Errors
/// [`Error::InvalidModel`] naming the actuator.
pub fn check_ctrl(names: &[String], ctrl: &[f64]) -> Result<()> {
    if ctrl.len() != names.len() {
        return Err(Error::InvalidModel {
            reason: format!(
                "ctrl has {} values, the model has {} actuators",
                ctrl.len(),
                names.len()
            ),
        });
    }
    if let Some(k) = ctrl.iter().position(|x| !x.is_finite()) {
        return Err(Error::InvalidModel {
            reason: format!("ctrl[{k}] (actuator `{}`) = {} is not finite", names[k], ctrl[k]),
        });
    }
    Ok(())
}
