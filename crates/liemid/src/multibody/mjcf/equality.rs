//! MJCF `<equality>`: `connect` and `weld` as exact loop-closing joints.
//!
//! MuJoCo enforces equality constraints softly (`solref`, `solimp`); maximal coordinates
//! hold them as holonomic rows like any joint, exactly (a loop closure,
//! docs/theory/multibody.md §4). As in MuJoCo the constraint is satisfied in the model's reference pose
//! (`qpos0`):
//! - `connect body1 body2 anchor`: a ball joint at `anchor` (body1's frame); the point on
//!   body2 (or the world when `body2` is omitted) is where that anchor is in the reference
//!   pose.
//! - `weld body1 body2 relpose anchor`: a weld joint holding body2's point `anchor` on
//!   body1's point `relpose[0..3]`, body2 turned by `relpose[3..7]` in body1's frame, when
//!   that quaternion is not zero; else the reference pose's relative pose (body1's point is
//!   then where body2's anchor is).
//! - Either body may be the world (omitted, or `world`), not both.
//!
//! `active="false"` equalities are skipped; `joint`, `tendon`, `distance` and `flex`
//! equalities, site-based ones and the softness parameters are listed as ignored. A body
//! merged into another (massless, without a joint) cannot carry an equality and is
//! refused, as is an unknown body.
//!
//! Reference: MuJoCo documentation, *XML Reference*, `equality`
//! (<https://mujoco.readthedocs.io/en/stable/XMLreference.html#equality>).

use roxmltree::Node;

use super::super::model::{Joint, JointKind, Link, Model};
use super::super::xml::{quat_matrix, Ctx, Ignored};
use crate::error::Result;
use crate::linalg::{Mat3, Vec3};

/// The loop joints of the `<equality>` elements `nodes` on the built `model` (bodies at
/// their reference poses); `merged` lists the bodies merged away.
pub(super) fn loop_joints(
    cx: &Ctx,
    nodes: &[Node],
    model: &Model,
    merged: &[(String, String)],
    ignored: &mut Ignored,
) -> Result<Vec<Joint>> {
    let mut joints = Vec::new();
    for &equality in nodes {
        for node in equality.children().filter(Node::is_element) {
            let tag = node.tag_name().name();
            if !matches!(tag, "connect" | "weld") {
                ignored.note(&format!("equality {tag}"));
                continue;
            }
            if node.attribute("active") == Some("false") {
                ignored.note("inactive equality");
                continue;
            }
            if node.attribute("site1").is_some() || node.attribute("site2").is_some() {
                return Err(cx.err(node, "a site-based equality is not supported: give body1 (and body2)"));
            }
            for soft in ["solref", "solimp", "torquescale"] {
                if node.attribute(soft).is_some() {
                    ignored.note("equality solref/solimp/torquescale (the loop is exact here)");
                }
            }
            let body = |attr: &str| -> Result<Option<usize>> {
                let Some(name) = node.attribute(attr) else {
                    return Ok(None);
                };
                if name == "world" {
                    return Ok(None);
                }
                if let Some((_, into)) = merged.iter().find(|(m, _)| m == name) {
                    return Err(cx.err(
                        node,
                        format!("{attr} `{name}` is merged into `{into}` (it has no mass and no joint), so it cannot close a loop"),
                    ));
                }
                model
                    .bodies
                    .iter()
                    .position(|b| b.name == name)
                    .map(Some)
                    .ok_or_else(|| cx.err(node, format!("{attr} `{name}` is not a body of the model")))
            };
            let b1 = body("body1")?;
            let b2 = body("body2")?;
            if b1 == b2 {
                return Err(match b1 {
                    Some(i) => cx.err(node, format!("<{tag}> joins body `{}` to itself", model.bodies[i].name)),
                    None => cx.err(
                        node,
                        format!("<{tag}> needs body1 or body2 to be a body, not the world"),
                    ),
                });
            }
            let anchor = Vec3::from_array(cx.array::<3>(node, "anchor")?.unwrap_or([0.0; 3]));
            let pose = |b: Option<usize>| {
                b.map_or((Vec3::ZERO, Mat3::IDENTITY), |i| {
                    (model.bodies[i].position, model.bodies[i].rotation)
                })
            };
            let (p1, r1) = pose(b1);
            let (p2, r2) = pose(b2);
            let label = |b: Option<usize>| b.map_or("world", |i| model.bodies[i].name.as_str());
            let name = node
                .attribute("name")
                .map_or_else(|| format!("{tag} {}-{}", label(b1), label(b2)), str::to_string);
            let joint = if tag == "connect" {
                if node.attribute("anchor").is_none() {
                    return Err(cx.err(node, "<connect> needs an anchor (a point in body1's frame)"));
                }
                // The anchor in the world at the reference pose, and that point on body2.
                let x = p1 + r1 * anchor;
                let on_body2 = r2.transpose() * (x - p2);
                match (b1, b2) {
                    (Some(i), _) => loop_joint(name, JointKind::Ball, b2, i, on_body2, anchor, r2.transpose() * r1),
                    (None, Some(j)) => loop_joint(name, JointKind::Ball, None, j, x, on_body2, r2),
                    (None, None) => unreachable!("refused above"),
                }
            } else {
                // MuJoCo's weld: body1's point `anchor1` on body2's point `anchor`, body2 turned
                // by `rel` in body1's frame; `relpose` (position = anchor1, quaternion = rel)
                // when its quaternion is not zero, else the reference pose's.
                let relpose = cx.array::<7>(node, "relpose")?;
                let (anchor1, rel) = match relpose {
                    Some(v) if v[3..].iter().any(|&q| q != 0.0) => {
                        let rot = quat_matrix([v[3], v[4], v[5], v[6]])
                            .ok_or_else(|| cx.err(node, "relpose has a zero or non-finite quaternion"))?;
                        (Vec3::new(v[0], v[1], v[2]), rot)
                    }
                    _ => (r1.transpose() * (p2 + r2 * anchor - p1), r1.transpose() * r2),
                };
                match (b1, b2) {
                    (_, Some(j)) => loop_joint(name, JointKind::Weld, b1, j, anchor1, anchor, rel),
                    // Welded to the world: body1 is the child, its attitude in the world rel⁻¹.
                    (Some(i), None) => loop_joint(name, JointKind::Weld, None, i, anchor, anchor1, rel.transpose()),
                    (None, None) => unreachable!("refused above"),
                }
            };
            joints.push(joint);
        }
    }
    Ok(joints)
}

/// A loop-closing joint from `parent` (world when `None`) to `child`.
fn loop_joint(
    name: String,
    kind: JointKind,
    parent: Option<usize>,
    child: usize,
    anchor_parent: Vec3,
    anchor_child: Vec3,
    reference_rotation: Mat3,
) -> Joint {
    Joint {
        name,
        kind,
        parent: parent.map_or(Link::World, Link::Body),
        child,
        anchor_parent,
        anchor_child,
        reference_rotation,
        range: None,
        stiffness: 0.0,
        spring_ref: 0.0,
        damping: 0.0,
        armature: 0.0,
        frictionloss: 0.0,
        actuator_force_range: None,
    }
}
