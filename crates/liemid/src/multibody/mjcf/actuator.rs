//! MJCF `<actuator>`: `motor`, `position` (`kp`, `kv`, `inheritrange`), `velocity` (`kv`)
//! and `general` (`gaintype` fixed or affine, `biastype` none or affine, `dyntype` none)
//! on a joint transmission (`joint`, or `jointinparent`, the same for a hinge or slide),
//! with `gear` (its first component), `ctrlrange`/`ctrllimited`,
//! `forcerange`/`forcelimited` (`auto` under `compiler autolimits`, as joint ranges) and
//! default classes (every shortcut of a `<default>` sets the class's one actuator
//! default, as in MuJoCo). The first keyframe's `ctrl` is the start's control (as
//! `mj_resetDataKeyframe`). Anything else (tendon, site or body transmissions, activation
//! dynamics, muscles, cylinders, dampers, adhesion, plugins, and actuators on hinges merged
//! into a universal or ball joint) is listed as not simulated and left out, together with
//! its keyframe control.
//!
//! Reference: docs/theory/multibody.md §8; MuJoCo documentation, XML reference,
//! "actuator".

use roxmltree::Node;

use super::{Elem, State};
use crate::error::Result;
use crate::multibody::model::{Actuator, Model};

impl<'a, 'i> State<'a, 'i> {
    /// The actuators of the `<actuator>` sections into `model.actuators`; returns, per
    /// actuator of the file, whether it was kept (for the keyframe's `ctrl`).
    pub(super) fn read_actuators(&mut self, sections: &[Node<'a, 'i>], model: &mut Model) -> Result<Vec<bool>> {
        let cx = self.cx;
        let mut kept = Vec::new();
        let mut damp_ratios = Vec::new();
        for section in sections {
            for node in section.children().filter(Node::is_element) {
                let tag = node.tag_name().name();
                let index = kept.len();
                let class = self.class_of(node, "main")?;
                let e = Elem {
                    node,
                    defaults: self.classes[class].actuator.clone(),
                };
                let skip = match tag {
                    "motor" | "position" | "velocity" | "general" => None,
                    other => Some(format!("actuator {other} (not simulated)")),
                };
                let skip = skip.or_else(|| {
                    ["tendon", "site", "body", "cranksite"]
                        .iter()
                        .find(|t| e.get(t).is_some())
                        .map(|t| format!("actuator with a {t} transmission (not simulated)"))
                });
                let skip = skip.or_else(|| {
                    if tag != "general" {
                        return None;
                    }
                    match (e.get("dyntype"), e.get("gaintype"), e.get("biastype")) {
                        (Some(d), _, _) if d != "none" => Some(format!("actuator dyntype {d} (not simulated)")),
                        (_, Some(g), _) if g != "fixed" && g != "affine" => {
                            Some(format!("actuator gaintype {g} (not simulated)"))
                        }
                        (_, _, Some(b)) if b != "none" && b != "affine" => {
                            Some(format!("actuator biastype {b} (not simulated)"))
                        }
                        _ => None,
                    }
                });
                if let Some(what) = skip {
                    self.ignored.note(&what);
                    kept.push(false);
                    continue;
                }
                let name = node
                    .attribute("name")
                    .map_or_else(|| format!("actuator{index}"), str::to_string);
                let Some(target) = e.get("joint").or_else(|| e.get("jointinparent")) else {
                    return Err(cx.err(
                        node,
                        format!("actuator `{name}` names no joint (or other transmission)"),
                    ));
                };
                let Some(joint) = model.joints.iter().position(|j| j.name == target) else {
                    let merged = model
                        .joints
                        .iter()
                        .any(|j| j.name.contains('+') && j.name.split('+').any(|h| h == target));
                    if merged {
                        // One hinge of a universal or ball joint has no coordinate of its own.
                        self.ignored.note("actuators on merged hinges (not simulated)");
                        kept.push(false);
                        continue;
                    }
                    return Err(cx.err(
                        node,
                        format!("actuator `{name}` names joint `{target}`, which the model does not have"),
                    ));
                };
                let num = |attr: &str, default: f64| -> Result<f64> {
                    e.get(attr)
                        .map_or(Ok(default), |v| cx.array_of::<1>(node, attr, v).map(|a| a[0]))
                };
                let prm = |attr: &str, default: [f64; 3]| -> Result<[f64; 3]> {
                    match e.get(attr) {
                        None => Ok(default),
                        Some(v) => {
                            let x = cx.floats(node, attr, v, 1, 10)?;
                            let mut out = [0.0; 3];
                            for (o, v) in out.iter_mut().zip(&x) {
                                *o = *v;
                            }
                            Ok(out)
                        }
                    }
                };
                let gear = match e.get("gear") {
                    Some(v) => cx.floats(node, "gear", v, 1, 6)?[0],
                    None => 1.0,
                };
                let (gain, bias) = match tag {
                    "motor" => ([1.0, 0.0, 0.0], [0.0; 3]),
                    "position" => {
                        let kp = num("kp", 1.0)?;
                        let kv = num("kv", 0.0)?;
                        if kp < 0.0 {
                            return Err(cx.err(node, format!("actuator `{name}`: negative kp {kp}")));
                        }
                        if kv < 0.0 {
                            return Err(cx.err(node, format!("actuator `{name}`: negative kv {kv}")));
                        }
                        let ratio = num("dampratio", 0.0)?;
                        if ratio < 0.0 || (ratio > 0.0 && e.node.attribute("kv").is_some()) {
                            return Err(cx.err(
                                node,
                                format!("actuator `{name}`: dampratio {ratio} must be >= 0 and not given with kv"),
                            ));
                        }
                        if ratio > 0.0 {
                            damp_ratios.push((model.actuators.len(), ratio));
                        }
                        ([kp, 0.0, 0.0], [0.0, -kp, -kv])
                    }
                    "velocity" => {
                        let kv = num("kv", 1.0)?;
                        if kv < 0.0 {
                            return Err(cx.err(node, format!("actuator `{name}`: negative kv {kv}")));
                        }
                        ([kv, 0.0, 0.0], [0.0, 0.0, -kv])
                    }
                    _ => {
                        let g = prm("gainprm", [1.0, 0.0, 0.0])?;
                        let b = prm("biasprm", [0.0; 3])?;
                        let gain = if e.get("gaintype").unwrap_or("fixed") == "affine" {
                            g
                        } else {
                            [g[0], 0.0, 0.0]
                        };
                        let bias = if e.get("biastype").unwrap_or("none") == "affine" {
                            b
                        } else {
                            [0.0; 3]
                        };
                        (gain, bias)
                    }
                };
                let mut ranges = [None, None];
                for (slot, (range, limited)) in [("ctrlrange", "ctrllimited"), ("forcerange", "forcelimited")]
                    .into_iter()
                    .enumerate()
                {
                    let r = e.get(range).map(|v| cx.array_of::<2>(node, range, v)).transpose()?;
                    if self.limited(node, e.get(limited), r.is_some(), range)? {
                        let [lo, hi] = r.ok_or_else(|| cx.err(node, format!("{limited} without {range}")))?;
                        if lo.is_nan() || hi.is_nan() || lo > hi {
                            return Err(cx.err(
                                node,
                                format!("actuator `{name}`: {range} ({lo}, {hi}) is upside down (lower <= upper)"),
                            ));
                        }
                        ranges[slot] = Some((lo, hi));
                    }
                }
                let offset = self.joint_refs.get(target).copied().unwrap_or(0.0);
                if tag == "position" {
                    let inherit = num("inheritrange", 0.0)?;
                    if inherit > 0.0 {
                        let (lo, hi) = model.joints[joint].range.ok_or_else(|| {
                            cx.err(
                                node,
                                format!("actuator `{name}`: inheritrange on joint `{target}` without a range"),
                            )
                        })?;
                        let (mid, half) = (0.5 * (lo + hi) + offset, 0.5 * (hi - lo) * inherit);
                        ranges[0] = Some((mid - half, mid + half));
                    }
                }
                let known = [
                    "name",
                    "class",
                    "joint",
                    "jointinparent",
                    "gear",
                    "ctrlrange",
                    "ctrllimited",
                    "forcerange",
                    "forcelimited",
                    "kp",
                    "kv",
                    "dampratio",
                    "inheritrange",
                    "gainprm",
                    "biasprm",
                    "gaintype",
                    "biastype",
                    "dyntype",
                    "group",
                ];
                let extra = node.attributes().map(|a| a.name()).chain(e.defaults.keys().copied());
                for a in extra.filter(|a| !known.contains(a)).collect::<Vec<_>>() {
                    self.ignored.note(&format!("actuator {a}"));
                }
                model.actuators.push(Actuator {
                    name,
                    joint,
                    gear,
                    gain,
                    bias,
                    ctrl_range: ranges[0],
                    force_range: ranges[1],
                    length_offset: offset,
                });
                kept.push(true);
            }
        }
        if !damp_ratios.is_empty() {
            set_damp_ratios(model, &damp_ratios).map_err(|e| cx.err(sections[0], e.to_string()))?;
        }
        Ok(kept)
    }

    /// The keyframe's `ctrl` (one value per actuator of the file) as the model's start
    /// control, the values of actuators left out dropped.
    pub(super) fn read_key_ctrl(&mut self, key: Node<'a, 'i>, kept: &[bool], model: &mut Model) -> Result<()> {
        let Some(v) = key.attribute("ctrl") else { return Ok(()) };
        let u = self.cx.floats(key, "ctrl", v, kept.len(), kept.len())?;
        model.ctrl = Some(u.iter().zip(kept).filter(|(_, k)| **k).map(|(x, _)| *x).collect());
        Ok(())
    }
}

/// A position actuator's `dampratio` ζ as its `kv`, as MuJoCo computes it: the critical
/// damping of the actuator's own coordinate `L = gear · q` at the reference pose (MuJoCo's
/// `qpos0`), `kv = 2 ζ √(kp · m)`, `m = 1 / (gear² (M⁻¹)ᵢᵢ)` the effective inertia of the
/// joint with the others free (`(M⁻¹)ᵢᵢ` MuJoCo's `dof_invweight0`, checked against MuJoCo
/// 4.0's `actuator_biasprm` on a six-axis arm).
///
/// Reference: docs/theory/multibody.md §8; MuJoCo documentation, XML reference,
/// "actuator/position" (dampratio).
fn set_damp_ratios(model: &mut Model, ratios: &[(usize, f64)]) -> Result<()> {
    let mut tree = model.clone();
    tree.joints.truncate(tree.bodies.len());
    tree.joints.iter_mut().for_each(|j| j.frictionloss = 0.0);
    tree.actuators.clear();
    tree.ctrl = None;
    tree.qpos = None;
    tree.qvel = None;
    let mut js = crate::multibody::JointSpaceModel::new(&tree)?;
    let nv = js.nv();
    let mut m = vec![0.0; nv * nv];
    let q0 = js.qpos0().to_vec();
    js.mass_matrix(&q0, &mut m)?;
    // M⁻¹ by Gauss–Jordan elimination (M symmetric positive definite, nv small).
    let mut inv = vec![0.0; nv * nv];
    for i in 0..nv {
        inv[i * nv + i] = 1.0;
    }
    for c in 0..nv {
        let p = m[c * nv + c];
        if p.is_nan() || p <= 0.0 {
            return Err(crate::error::Error::InvalidModel {
                reason: "dampratio: the joint-space mass matrix at the reference pose is singular".into(),
            });
        }
        for k in 0..nv {
            m[c * nv + k] /= p;
            inv[c * nv + k] /= p;
        }
        for r in 0..nv {
            let f = m[r * nv + c];
            if r != c && f != 0.0 {
                for k in 0..nv {
                    m[r * nv + k] -= f * m[c * nv + k];
                    inv[r * nv + k] -= f * inv[c * nv + k];
                }
            }
        }
    }
    for &(a, ratio) in ratios {
        let act = &model.actuators[a];
        let iv: usize = model.joints.iter().take(act.joint).map(|j| j.kind.nv()).sum();
        let inertia = 1.0 / (inv[iv * nv + iv] * act.gear * act.gear);
        let kv = 2.0 * ratio * (act.gain[0] * inertia).sqrt();
        model.actuators[a].bias[2] = -kv;
    }
    Ok(())
}
