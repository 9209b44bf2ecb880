//! The structural model: nodes, members cut into elements, cross sections, supports and
//! loads. [`Frame::build`] turns it into a [`super::BeamSystem`]: every node a rigid body
//! with the lumped mass and rotary inertia of its half elements.

use crate::error::{Error, Result};
use crate::linalg::Vec3;

/// A cross section by its stiffness and mass coefficients (per unit length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    /// Axial stiffness `EA`.
    pub axial_stiffness: f64,
    /// Torsional stiffness `GJ`.
    pub torsional_stiffness: f64,
    /// Bending stiffness about the section's second axis, `EI₂`.
    pub bending_stiffness_2: f64,
    /// Bending stiffness about the section's third axis, `EI₃`.
    pub bending_stiffness_3: f64,
    /// Mass per unit length `ρA`.
    pub mass_per_length: f64,
    /// Rotary inertia per unit length about the element axis and the two section axes:
    /// `(ρ(I₂ + I₃), ρI₂, ρI₃)`.
    pub rotary_inertia: Vec3,
}

impl Section {
    /// From the material and the section's geometry: Young's modulus `e`, shear modulus
    /// `g`, area, second moments `i2` (about the second axis), `i3`, torsion constant `j`,
    /// density `rho`.
    ///
    /// # Errors
    /// A coefficient that is not finite and positive.
    #[allow(clippy::too_many_arguments)]
    pub fn from_material(e: f64, g: f64, area: f64, i2: f64, i3: f64, j: f64, rho: f64) -> Result<Self> {
        let s = Section {
            axial_stiffness: e * area,
            torsional_stiffness: g * j,
            bending_stiffness_2: e * i2,
            bending_stiffness_3: e * i3,
            mass_per_length: rho * area,
            rotary_inertia: Vec3::new(rho * (i2 + i3), rho * i2, rho * i3),
        };
        for (name, v) in [
            ("E", e),
            ("G", g),
            ("A", area),
            ("I2", i2),
            ("I3", i3),
            ("J", j),
            ("rho", rho),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidParameter {
                    name,
                    value: v,
                    reason: "a section property must be finite and positive",
                });
            }
        }
        Ok(s)
    }

    /// A solid rectangle `b` wide along the second axis and `h` high along the third, of
    /// an isotropic material (`G = E/(2(1 + ν))`); the torsion constant is Saint-Venant's
    /// `J = c d³ (1/3 − 0.21 (d/c)(1 − d⁴/(12 c⁴)))` with `c ≥ d` the longer and shorter
    /// side (Roark's formula, within 0.5 %).
    ///
    /// # Errors
    /// A property that is not finite and positive, or `ν` outside `(−1, 0.5]`.
    pub fn rectangle(e: f64, nu: f64, rho: f64, b: f64, h: f64) -> Result<Self> {
        if !(nu > -1.0 && nu <= 0.5) {
            return Err(Error::InvalidParameter {
                name: "nu",
                value: nu,
                reason: "Poisson's ratio must lie in (-1, 0.5]",
            });
        }
        let (c, d) = if b >= h { (b, h) } else { (h, b) };
        let j = c * d.powi(3) * (1.0 / 3.0 - 0.21 * (d / c) * (1.0 - d.powi(4) / (12.0 * c.powi(4))));
        let g = e / (2.0 * (1.0 + nu));
        Section::from_material(e, g, b * h, b * h.powi(3) / 12.0, h * b.powi(3) / 12.0, j, rho)
    }

    /// Check that every coefficient is finite and positive, naming the first that is not.
    ///
    /// # Errors
    /// The offending coefficient.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("EA", self.axial_stiffness),
            ("GJ", self.torsional_stiffness),
            ("EI2", self.bending_stiffness_2),
            ("EI3", self.bending_stiffness_3),
            ("rhoA", self.mass_per_length),
            ("rho_J (rotary inertia about the axis)", self.rotary_inertia.x),
            ("rho_I2 (rotary inertia)", self.rotary_inertia.y),
            ("rho_I3 (rotary inertia)", self.rotary_inertia.z),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidParameter {
                    name,
                    value: v,
                    reason: "a section coefficient must be finite and positive",
                });
            }
        }
        Ok(())
    }
}

/// How a node is held.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Support {
    /// Free (6 degrees of freedom).
    #[default]
    Free,
    /// Translations held, rotations free.
    Pinned,
    /// All six held.
    Clamped,
}

/// A piecewise-linear multiplier `s(t)` through points `(t_k, s_k)` with increasing `t_k`,
/// constant before the first and after the last.
#[derive(Clone, Debug, PartialEq)]
pub struct History {
    points: Vec<(f64, f64)>,
}

impl History {
    /// `s(t) = 1` at all times.
    #[must_use]
    pub fn constant() -> Self {
        History {
            points: vec![(0.0, 1.0)],
        }
    }

    /// Through the given points.
    ///
    /// # Errors
    /// No points, a non-finite value, or times that do not increase.
    pub fn new(points: Vec<(f64, f64)>) -> Result<Self> {
        if points.is_empty() {
            return Err(Error::InvalidModel {
                reason: "a load history needs at least one point (t, value)".into(),
            });
        }
        for (k, &(t, s)) in points.iter().enumerate() {
            if !(t.is_finite() && s.is_finite()) {
                return Err(Error::InvalidModel {
                    reason: format!("load history point {k} = ({t}, {s}) is not finite"),
                });
            }
            if k > 0 && t <= points[k - 1].0 {
                return Err(Error::InvalidModel {
                    reason: format!(
                        "load history times must increase: point {k} has t = {t} after t = {}",
                        points[k - 1].0
                    ),
                });
            }
        }
        Ok(History { points })
    }

    /// The points.
    #[must_use]
    pub fn points(&self) -> &[(f64, f64)] {
        &self.points
    }

    /// `s(t)`.
    #[must_use]
    pub fn value(&self, t: f64) -> f64 {
        let p = &self.points;
        if t <= p[0].0 {
            return p[0].1;
        }
        let k = p.partition_point(|&(tk, _)| tk <= t);
        if k == p.len() {
            return p[k - 1].1;
        }
        let ((t0, s0), (t1, s1)) = (p[k - 1], p[k]);
        s0 + (s1 - s0) * (t - t0) / (t1 - t0)
    }

    /// The last time at which `s` changes (the first point's time for a constant).
    #[must_use]
    pub fn end(&self) -> f64 {
        self.points[self.points.len() - 1].0
    }
}

/// A force and a moment on one node, scaled by a history.
#[derive(Clone, Debug, PartialEq)]
pub struct NodalLoad {
    /// The node.
    pub node: usize,
    /// Force at `s = 1`.
    pub force: Vec3,
    /// Moment at `s = 1`.
    pub moment: Vec3,
    /// `false`: fixed spatial directions; `true`: the load turns with the node (given in
    /// the node's initial axes).
    pub follower: bool,
    /// The multiplier `s(t)`.
    pub history: History,
}

/// One element of the model: its nodes, section and orientation vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementSpec {
    /// End nodes `a`, `b`.
    pub nodes: [usize; 2],
    /// The cross section.
    pub section: Section,
    /// A vector in the plane of the element axis and the section's second axis.
    pub orientation: Vec3,
}

/// A beam structure: nodes, elements, supports, loads and gravity.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Node positions in the undeformed configuration.
    pub nodes: Vec<Vec3>,
    /// Elements.
    pub elements: Vec<ElementSpec>,
    /// Support of each node (free unless set).
    pub supports: Vec<Support>,
    /// Nodal loads.
    pub loads: Vec<NodalLoad>,
    /// Gravitational acceleration.
    pub gravity: Vec3,
    /// Named nodes, in the order they were named.
    pub names: Vec<(String, usize)>,
}

impl Frame {
    /// An empty model.
    #[must_use]
    pub fn new() -> Self {
        Frame::default()
    }

    /// Add a node (always a new one).
    ///
    /// # Errors
    /// A non-finite position.
    pub fn add_node(&mut self, x: Vec3) -> Result<usize> {
        if !x.is_finite() {
            return Err(Error::InvalidModel {
                reason: format!("node position ({}, {}, {}) is not finite", x.x, x.y, x.z),
            });
        }
        self.nodes.push(x);
        self.supports.push(Support::Free);
        Ok(self.nodes.len() - 1)
    }

    /// The node at `x` within `tolerance`, if any (the first one).
    #[must_use]
    pub fn node_at(&self, x: Vec3, tolerance: f64) -> Option<usize> {
        self.nodes.iter().position(|&y| (y - x).norm() <= tolerance)
    }

    /// The node named `name`.
    #[must_use]
    pub fn named(&self, name: &str) -> Option<usize> {
        self.names.iter().find(|(n, _)| n == name).map(|&(_, k)| k)
    }

    /// A straight member from `from` to `to` cut into `elements` equal elements; its end
    /// nodes are merged with existing nodes within `1e-9` of the member length. Returns the
    /// member's nodes in order.
    ///
    /// # Errors
    /// Zero elements, a zero-length member, or an orientation vector along the member.
    pub fn add_member(
        &mut self,
        from: Vec3,
        to: Vec3,
        elements: usize,
        section: Section,
        orientation: Vec3,
    ) -> Result<Vec<usize>> {
        section.validate()?;
        let length = (to - from).norm();
        if elements == 0 {
            return Err(Error::InvalidModel {
                reason: "a member needs at least one element".into(),
            });
        }
        if !(length.is_finite() && length > 0.0) {
            return Err(Error::InvalidModel {
                reason: format!(
                    "member from ({}, {}, {}) to ({}, {}, {}) has zero length",
                    from.x, from.y, from.z, to.x, to.y, to.z
                ),
            });
        }
        let axis = (to - from) * (1.0 / length);
        let across = orientation - axis * orientation.dot(axis);
        if !(orientation.is_finite() && across.norm() > 1e-6 * orientation.norm()) {
            return Err(Error::InvalidModel {
                reason: format!(
                    "orientation vector ({}, {}, {}) lies along the member from ({}, {}, {}) to ({}, {}, {}): it must \
                     give the section's second axis, across the member",
                    orientation.x, orientation.y, orientation.z, from.x, from.y, from.z, to.x, to.y, to.z
                ),
            });
        }
        let tolerance = 1e-9 * length;
        let mut ids = Vec::with_capacity(elements + 1);
        for k in 0..=elements {
            let x = from + (to - from) * (k as f64 / elements as f64);
            let existing = if k == 0 || k == elements {
                self.node_at(x, tolerance)
            } else {
                None
            };
            ids.push(match existing {
                Some(id) => id,
                None => self.add_node(x)?,
            });
        }
        for w in ids.windows(2) {
            self.elements.push(ElementSpec {
                nodes: [w[0], w[1]],
                section,
                orientation,
            });
        }
        Ok(ids)
    }

    /// Hold node `node` by `support`.
    ///
    /// # Errors
    /// A node that does not exist.
    pub fn support(&mut self, node: usize, support: Support) -> Result<()> {
        let n = self.nodes.len();
        let s = self.supports.get_mut(node).ok_or_else(|| Error::InvalidModel {
            reason: format!("support on node {node}, but the model has {n} nodes"),
        })?;
        *s = support;
        Ok(())
    }

    /// Add a nodal load.
    ///
    /// # Errors
    /// A node that does not exist, or a non-finite force or moment.
    pub fn load(&mut self, load: NodalLoad) -> Result<()> {
        if load.node >= self.nodes.len() {
            return Err(Error::InvalidModel {
                reason: format!(
                    "load on node {}, but the model has {} nodes",
                    load.node,
                    self.nodes.len()
                ),
            });
        }
        if !(load.force.is_finite() && load.moment.is_finite()) {
            return Err(Error::InvalidModel {
                reason: format!("load on node {} is not finite", load.node),
            });
        }
        self.loads.push(load);
        Ok(())
    }

    /// Give node `node` a name (for tracking).
    ///
    /// # Errors
    /// A node that does not exist or a name already used.
    pub fn name(&mut self, name: &str, node: usize) -> Result<()> {
        if node >= self.nodes.len() {
            return Err(Error::InvalidModel {
                reason: format!(
                    "name `{name}` for node {node}, but the model has {} nodes",
                    self.nodes.len()
                ),
            });
        }
        if self.named(name).is_some() {
            return Err(Error::InvalidModel {
                reason: format!("node name `{name}` is used twice"),
            });
        }
        self.names.push((name.to_string(), node));
        Ok(())
    }
}
