//! Built-in [`Interaction`]s for many-body systems: independent bodies in uniform gravity,
//! and point dipoles with short-range repulsion ([`Dipoles`], in `many/dipoles`).

use crate::linalg::{Mat3, Vec3};
use crate::many::{Configuration, Interaction};

pub use super::dipoles::{
    CutoffForm, Dipoles, DomainForces, DEFAULT_SKIN, DEFAULT_SWITCH_FRACTION, HALF_LIST_MAX_BODIES,
};

/// Each body on its own: a free body feels `F = m g`; a rotor (fixed point) feels the
/// gravity torque about its pivot `T = X × (Rᵀ m g)`, with `X` the centre of mass in the
/// body frame. With `g = 0`, torque-free bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Independent {
    /// Gravity (spatial).
    pub gravity: Vec3,
    /// Centre of mass of the rotors in their body frame, from the pivot.
    pub center_of_mass: Vec3,
}

impl Independent {
    /// Torque-free bodies.
    #[must_use]
    pub fn torque_free() -> Self {
        Independent {
            gravity: Vec3::ZERO,
            center_of_mass: Vec3::ZERO,
        }
    }
}

pub(crate) fn for_chunks(
    force: &mut [Vec3],
    torque: &mut [Vec3],
    f: impl Fn(usize, &mut Vec3, &mut Vec3) + Sync + Send,
) {
    #[cfg(feature = "parallel")]
    {
        use crate::many::CHUNK;
        use rayon::prelude::*;
        force
            .par_chunks_mut(CHUNK)
            .zip(torque.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(k, (fs, ts))| {
                for (j, (fo, to)) in fs.iter_mut().zip(ts.iter_mut()).enumerate() {
                    f(k * CHUNK + j, fo, to);
                }
            });
    }
    #[cfg(not(feature = "parallel"))]
    for (i, (fo, to)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
        f(i, fo, to);
    }
}

impl Independent {
    /// Force and torque on one body of mass `mass`.
    #[inline]
    fn on_body(&self, mass: f64, free: bool, rotation: &Mat3) -> (Vec3, Vec3) {
        let w = self.gravity * mass;
        if free {
            (w, Vec3::ZERO)
        } else {
            (Vec3::ZERO, self.center_of_mass.cross(rotation.tr_mul_vec(w)))
        }
    }
}

impl Interaction for Independent {
    fn compute(&self, c: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        for_chunks(force, torque, |i, f, t| {
            (*f, *t) = self.on_body(c.mass[i], c.free[i], &c.rotation[i]);
        });
    }
    fn is_local(&self) -> bool {
        true
    }
    fn compute_local(&self, c: Configuration<'_>, force: &mut [Vec3], torque: &mut [Vec3]) {
        for (i, (f, t)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
            (*f, *t) = self.on_body(c.mass[i], c.free[i], &c.rotation[i]);
        }
    }
    fn potential_energy(&self, c: Configuration<'_>) -> f64 {
        (0..c.mass.len())
            .map(|i| {
                let w = self.gravity * c.mass[i];
                if c.free[i] {
                    -w.dot(c.position[i])
                } else {
                    -w.dot(c.rotation[i] * self.center_of_mass)
                }
            })
            .sum()
    }
}
