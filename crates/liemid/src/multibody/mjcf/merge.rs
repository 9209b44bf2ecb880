//! Several joints in one MJCF body, merged into one joint (two hinges through one point: a
//! universal joint; three: a ball), and the keyframe's conversion from MuJoCo's per-hinge
//! `qpos`/`qvel` to the model's layout. See the module documentation of [`super`].
//!
//! Reference: MuJoCo documentation, "Computation" (kinematics of several joints in a body).

use roxmltree::Node;

use super::super::model::AXIS_INDEPENDENCE;
use super::super::xml::{RawBody, RawKind};
use super::{Elem, KeyState, State};
use crate::error::Result;
use crate::linalg::{Mat3, Vec3};
use crate::so3::{self, Quaternion};

/// How one body's joints map MuJoCo's `qpos`/`qvel` (a keyframe) to the model's.
#[derive(Clone, Debug)]
pub(super) enum KeyMap {
    /// One joint (or none: a weld) and its `ref` (model coordinate = MuJoCo's − ref).
    One(RawKind, f64),
    /// Two or three hinges merged into a universal or ball joint: their axes (body frame)
    /// and `ref`s.
    Merged(Vec<(Vec3, f64)>),
}

impl KeyMap {
    /// Entries in MuJoCo's `qpos` and `qvel`.
    pub(super) fn mujoco_dims(&self) -> (usize, usize) {
        match self {
            KeyMap::One(k, _) => match k {
                RawKind::Weld => (0, 0),
                RawKind::Free => (7, 6),
                RawKind::Ball => (4, 3),
                RawKind::Hinge(_) | RawKind::Slide(_) => (1, 1),
                RawKind::Universal(..) => (2, 2),
            },
            KeyMap::Merged(h) => (h.len(), h.len()),
        }
    }
}

/// The merged joint's `qpos` and `qvel` (model layout) from the hinges' MuJoCo values
/// (angles `q`, before subtracting `ref`; rates `v`): a universal keeps the two angles,
/// a ball gets `quat(exp(θ₁a) exp(θ₂b) exp(θ₃c))` and the relative angular velocity in the
/// child frame `exp(−θ₃c) exp(−θ₂b) a θ̇₁ + exp(−θ₃c) b θ̇₂ + c θ̇₃`.
fn merged_state(hinges: &[(Vec3, f64)], q: Option<&[f64]>, v: Option<&[f64]>) -> (Vec<f64>, Vec<f64>) {
    let theta: Vec<f64> = hinges
        .iter()
        .enumerate()
        .map(|(k, &(_, r))| q.map_or(0.0, |q| q[k] - r))
        .collect();
    if hinges.len() == 2 {
        return (theta, v.map(<[f64]>::to_vec).unwrap_or_default());
    }
    let mut m = Mat3::IDENTITY;
    for (&(axis, _), &th) in hinges.iter().zip(&theta) {
        m = m * so3::exp(axis * th);
    }
    let quat = Quaternion::from_matrix(&m);
    let mut w = Vec3::ZERO;
    if let Some(v) = v {
        // Accumulate from the last hinge back: w = c θ̇₃ + exp(−θ₃c)(b θ̇₂ + exp(−θ₂b) a θ̇₁).
        for k in 0..hinges.len() {
            let axis = hinges[k].0;
            let mut x = axis * v[k];
            for (&(later, _), &th) in hinges.iter().zip(&theta).skip(k + 1) {
                x = so3::exp(later * th).tr_mul_vec(x);
            }
            w += x;
        }
    }
    (vec![quat.w, quat.x, quat.y, quat.z], vec![w.x, w.y, w.z])
}

impl<'a, 'i> State<'a, 'i> {
    /// Several joints of one body (`nodes`, in file order): two or three hinges through one
    /// point become a universal or a ball joint in `body` (see the module documentation);
    /// returns the hinges' axes and `ref`s for the keyframe. Anything else is refused,
    /// naming the body and its joints.
    pub(super) fn read_merged(
        &mut self,
        node: Node<'a, 'i>,
        nodes: &[Node<'a, 'i>],
        childclass: &'a str,
        body: &mut RawBody,
    ) -> Result<Vec<(Vec3, f64)>> {
        let cx = self.cx;
        let name = body.name.clone();
        let label = |j: &Node| {
            j.attribute("name")
                .map_or_else(|| format!("(unnamed, line {})", cx.line(*j)), |n| format!("`{n}`"))
        };
        let mut read = Vec::with_capacity(nodes.len());
        let mut kinds = Vec::with_capacity(nodes.len());
        for &j in nodes {
            if let Some(n) = j.attribute("name") {
                if let Some(first) = self.joint_names.insert(n, j) {
                    return Err(cx.err(
                        j,
                        format!("a second joint named `{n}` (first on line {})", cx.line(first)),
                    ));
                }
            }
            if j.has_tag_name("freejoint") {
                kinds.push(format!("{} (free)", label(&j)));
                read.push(None);
                continue;
            }
            let class = self.class_of(j, childclass)?;
            let defaults = self.classes[class].joint.clone();
            let mut one = body.clone();
            let reference = self.read_joint(Elem { node: j, defaults }, &mut one)?;
            kinds.push(format!(
                "{} ({})",
                label(&j),
                match one.kind {
                    RawKind::Hinge(_) => "hinge",
                    RawKind::Slide(_) => "slide",
                    RawKind::Ball => "ball",
                    _ => "free",
                }
            ));
            read.push(Some((j, one, reference)));
        }
        let list = kinds.join(", ");
        let all_hinges = read
            .iter()
            .all(|r| matches!(r, Some((_, b, _)) if matches!(b.kind, RawKind::Hinge(_))));
        if !all_hinges || nodes.len() > 3 {
            return Err(cx.err(
                node,
                format!(
                    "body `{name}` has {} joints, {list}: only two or three hinges through one point are merged \
                     (into a universal or a ball joint); other combinations (a hinge and a slide, a ball, slide \
                     or free joint with others, four or more hinges) need massless intermediate bodies, which \
                     maximal coordinates cannot integrate: give each joint its own body with mass",
                    nodes.len()
                ),
            ));
        }
        let read: Vec<(Node, RawBody, f64)> = read.into_iter().flatten().collect();
        let kind = if read.len() == 2 { "universal" } else { "ball" };
        let size = read
            .iter()
            .map(|(_, b, _)| b.anchor.norm())
            .chain([body.pos.norm()])
            .chain((body.mass.mass > 0.0).then(|| (body.mass.inertia.trace() / body.mass.mass).sqrt()))
            .fold(0.0, f64::max);
        let anchor = read[0].1.anchor;
        for (j, b, _) in &read[1..] {
            let gap = (b.anchor - anchor).norm();
            if gap > 1e-9 * size {
                return Err(cx.err(
                    *j,
                    format!(
                        "body `{name}` has joints {list} at different points (pos differ by {gap:.3e}, more than \
                         1e-9 of the body's size {size:.3e}): hinges are merged into a {kind} joint only through \
                         one point"
                    ),
                ));
            }
        }
        for (j, b, _) in &read {
            let what = [
                (b.range.is_some(), "a limit (range)"),
                (b.stiffness != 0.0, "a spring (stiffness)"),
                (b.damping != 0.0, "a damper (damping)"),
                (b.armature != 0.0, "a rotor inertia (armature)"),
                (b.frictionloss != 0.0, "dry friction (frictionloss)"),
                (
                    b.actuator_force_range.is_some(),
                    "an actuator force clamp (actuatorfrcrange)",
                ),
            ];
            if let Some((_, what)) = what.iter().find(|(bad, _)| *bad) {
                return Err(cx.err(
                    *j,
                    format!(
                        "joint {} of body `{name}` has {what}, but it is one of the hinges {list} merged into a \
                         {kind} joint, where one hinge's {what} has no exact form (not supported): remove it from \
                         these hinges (for example with a default class of their own)",
                        label(j)
                    ),
                ));
            }
        }
        let axes: Vec<Vec3> = read
            .iter()
            .map(|(_, b, _)| match b.kind {
                RawKind::Hinge(u) => u,
                _ => Vec3::ZERO,
            })
            .collect();
        let independence = if axes.len() == 2 {
            axes[0].cross(axes[1]).norm()
        } else {
            axes[0].dot(axes[1].cross(axes[2])).abs()
        };
        if independence < AXIS_INDEPENDENCE {
            return Err(cx.err(
                node,
                format!(
                    "body `{name}`: the axes of its hinges {list} are not independent ({} = {independence:.3e}, at \
                     least {AXIS_INDEPENDENCE:e}): they cannot be merged into a {kind} joint",
                    if axes.len() == 2 { "|a x b|" } else { "|det(a, b, c)|" }
                ),
            ));
        }
        body.kind = if axes.len() == 2 {
            RawKind::Universal(axes[0], axes[1])
        } else {
            RawKind::Ball
        };
        body.anchor = anchor;
        let names: Option<Vec<&str>> = read.iter().map(|(j, _, _)| j.attribute("name")).collect();
        body.joint_name = names.map(|n| n.join("+"));
        Ok(read.iter().zip(&axes).map(|((_, _, r), &u)| (u, *r)).collect())
    }

    /// The first keyframe's `qpos` and `qvel`, shifted by each hinge's and slide's `ref`,
    /// merged hinges converted to their universal or ball joint ([`merged_state`]).
    pub(super) fn read_key(&mut self, key: Node<'a, 'i>) -> Result<KeyState> {
        let cx = self.cx;
        let nq: usize = self.refs.iter().map(|m| m.mujoco_dims().0).sum();
        let nv: usize = self.refs.iter().map(|m| m.mujoco_dims().1).sum();
        let q_in = key
            .attribute("qpos")
            .map(|v| cx.floats(key, "qpos", v, nq, nq))
            .transpose()?;
        let v_in = key
            .attribute("qvel")
            .map(|v| cx.floats(key, "qvel", v, nv, nv))
            .transpose()?;
        let (mut qpos, mut qvel) = (Vec::with_capacity(nq), Vec::with_capacity(nv));
        let (mut iq, mut iv) = (0, 0);
        for map in &self.refs {
            let (dq, dv) = map.mujoco_dims();
            let q = q_in.as_deref().map(|q| &q[iq..iq + dq]);
            let v = v_in.as_deref().map(|v| &v[iv..iv + dv]);
            match map {
                KeyMap::One(kind, r) => {
                    if let Some(q) = q {
                        let shift = matches!(kind, RawKind::Hinge(_) | RawKind::Slide(_));
                        qpos.extend(q.iter().map(|x| if shift { x - r } else { *x }));
                    }
                    qvel.extend(v.unwrap_or_default());
                }
                KeyMap::Merged(hinges) => {
                    let (mq, mv) = merged_state(hinges, q, v);
                    qpos.extend(mq);
                    qvel.extend(mv);
                }
            }
            iq += dq;
            iv += dv;
        }
        self.note_other_attributes(key, &["name", "qpos", "qvel", "time", "ctrl"]);
        Ok((q_in.map(|_| qpos), v_in.map(|_| qvel)))
    }
}
