//! The mass properties of MJCF geoms (sphere, capsule, cylinder, box, ellipsoid; `size`,
//! `fromto`, `mass` or `density`) for bodies without an `<inertial>`.
//!
//! Reference: MuJoCo documentation, XML reference, `geom`.

use super::super::xml::{rotation_to_z, MassProps};
use super::{Elem, State};
use crate::error::Result;
use crate::linalg::{Mat3, Vec3};

impl<'a, 'i> State<'a, 'i> {
    /// The mass properties of a geom in its body's frame (zero for a massless geom).
    pub(super) fn geom_mass(&mut self, g: Elem<'a, 'i>) -> Result<MassProps> {
        let cx = self.cx;
        let node = g.node;
        self.ignored.note("geom contacts");
        let ty = g.get("type").unwrap_or("sphere");
        let mass_attr = g.get("mass").map(|v| cx.array_of::<1>(node, "mass", v)).transpose()?;
        let density = g
            .get("density")
            .map(|v| cx.array_of::<1>(node, "density", v))
            .transpose()?;
        if let Some([m]) = mass_attr {
            if m < 0.0 {
                return Err(cx.err(node, format!("mass {m} is negative")));
            }
        }
        if let Some([d]) = density {
            if d < 0.0 {
                return Err(cx.err(node, format!("density {d} is negative")));
            }
        }
        if mass_attr == Some([0.0]) || (mass_attr.is_none() && density == Some([0.0])) {
            return Ok(MassProps::ZERO);
        }
        match ty {
            "sphere" | "capsule" | "cylinder" | "box" | "ellipsoid" => {}
            "mesh" | "hfield" | "sdf" => {
                let what = g.get("mesh").or(g.get("hfield")).unwrap_or("(unnamed)");
                return Err(cx.err(
                    node,
                    format!(
                        "the body has no <inertial>, so its mass would come from this {ty} geom `{what}`, whose \
                         file is not read: give the body an <inertial>"
                    ),
                ));
            }
            "plane" => return Err(cx.err(node, "a plane has no finite mass: planes belong in <worldbody>")),
            other => return Err(cx.err(node, format!("unknown geom type `{other}`"))),
        }
        let size = match g.get("size") {
            Some(v) => cx.floats(node, "size", v, 1, 3)?,
            None => Vec::new(),
        };
        let (mut pos, mut rot) = self.frame(node, &|a| g.get(a))?;
        let mut half_length = None;
        if let Some(v) = g.get("fromto") {
            let f = cx.array_of::<6>(node, "fromto", v)?;
            let (a, b) = (Vec3::new(f[0], f[1], f[2]), Vec3::new(f[3], f[4], f[5]));
            let d = b - a;
            rot = rotation_to_z(cx.unit(node, "fromto", d.to_array())?);
            pos = (a + b) * 0.5;
            half_length = Some(0.5 * d.norm());
        }
        let needed = match (ty, half_length) {
            ("sphere", _) => 1,
            ("capsule" | "cylinder", None) => 2,
            ("capsule" | "cylinder", Some(_)) => 1,
            (_, None) => 3,
            (_, Some(_)) => 2,
        };
        if size.len() < needed || size[..needed].iter().any(|&s| s <= 0.0) {
            return Err(cx.err(node, format!("a {ty} geom needs {needed} positive size values")));
        }
        let s = |k: usize| {
            if k == needed && half_length.is_some() {
                half_length.unwrap_or(0.0)
            } else {
                size[k]
            }
        };
        use std::f64::consts::PI;
        let (volume, unit_inertia): (f64, Box<dyn Fn(f64) -> Vec3>) = match ty {
            "sphere" => {
                let r = s(0);
                (
                    4.0 / 3.0 * PI * r.powi(3),
                    Box::new(move |m| Vec3::new(1.0, 1.0, 1.0) * (0.4 * m * r * r)),
                )
            }
            "box" | "ellipsoid" => {
                let (a, b, c) = (s(0), s(1), s(2));
                let (v, k) = if ty == "box" {
                    (8.0 * a * b * c, 1.0 / 3.0)
                } else {
                    (4.0 / 3.0 * PI * a * b * c, 0.2)
                };
                (
                    v,
                    Box::new(move |m| Vec3::new(b * b + c * c, a * a + c * c, a * a + b * b) * (k * m)),
                )
            }
            "cylinder" => {
                let (r, h) = (s(0), 2.0 * s(1));
                (
                    PI * r * r * h,
                    Box::new(move |m| {
                        let t = m * (3.0 * r * r + h * h) / 12.0;
                        Vec3::new(t, t, 0.5 * m * r * r)
                    }),
                )
            }
            _ => {
                let (r, h) = (s(0), 2.0 * s(1));
                let (v_cyl, v_sph) = (PI * r * r * h, 4.0 / 3.0 * PI * r.powi(3));
                (
                    v_cyl + v_sph,
                    Box::new(move |m| {
                        let (mc, ms) = (m * v_cyl / (v_cyl + v_sph), m * v_sph / (v_cyl + v_sph));
                        let t = mc * (3.0 * r * r + h * h) / 12.0 + ms * (0.4 * r * r + 0.25 * h * h + 0.375 * h * r);
                        Vec3::new(t, t, 0.5 * mc * r * r + 0.4 * ms * r * r)
                    }),
                )
            }
        };
        let m = match mass_attr {
            Some([m]) => m,
            None => density.map_or(1000.0, |d| d[0]) * volume,
        };
        let local = MassProps {
            mass: m,
            com: Vec3::ZERO,
            inertia: Mat3::from_diagonal(unit_inertia(m)),
        };
        Ok(local.transformed(pos, &rot))
    }
}
