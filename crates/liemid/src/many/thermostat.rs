//! Langevin dynamics for rigid bodies: the splitting step with an Ornstein-Uhlenbeck
//! step on the momenta in its middle (BAOAB),
//!
//! ```text
//! B(h/2): p ← p + (h/2) F,  Π ← Π + (h/2) T
//! A(h/2): x ← x + (h/2) p/m;  (Π, R) ← torque-free rotation over h/2
//! O(h):   p ← c p + √((1 − c²) m k_B T) ξ,      c = e^{−γ h}
//!         Π ← c_r Π + √((1 − c_r²) k_B T) √I ξ', c_r = e^{−γ_r h}   (body frame, principal)
//! A(h/2), then forces at the new configuration, B(h/2)
//! ```
//!
//! which samples the canonical distribution at `k_B T` to second order in `h` for the
//! configurations, with the translational and rotational kinetic temperatures exact in
//! the free limit. The noise is counter-based: each normal deviate is a hash of (seed,
//! body, step, component), so runs are bitwise the same for any number of threads. With no
//! friction it is the NVE splitting with the rotation in two halves.
//!
//! References: B. Leimkuhler, C. Matthews, *Robust and efficient configurational molecular
//! sampling via Langevin dynamics*, J. Chem. Phys. 138, 174102 (2013); R. L. Davidchack,
//! T. E. Ouldridge, M. V. Tretyakov, *New Langevin and gradient thermostats for rigid body
//! dynamics*, J. Chem. Phys. 142, 144114 (2015).

use super::{for_each_chunk, free_rotation_by, keep_first_failure, kick_chunk, Bodies, Interaction};
use crate::error::{Error, Result};
use crate::linalg::Vec3;
use crate::midpoint::newton_error;
use std::sync::Mutex;

/// The Langevin thermostat's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Langevin {
    /// `k_B T` (energy units of the model).
    pub temperature: f64,
    /// Translational friction `γ` (1/time).
    pub friction: f64,
    /// Rotational friction `γ_r` (1/time).
    pub rotational_friction: f64,
    /// Seed of the noise.
    pub seed: u64,
}

impl Langevin {
    /// A thermostat at `k_B T = temperature` with the same friction for translation and
    /// rotation.
    ///
    /// # Errors
    /// A negative or non-finite temperature or friction.
    pub fn new(temperature: f64, friction: f64, seed: u64) -> Result<Self> {
        for (name, v) in [("temperature", temperature), ("friction", friction)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::InvalidParameter {
                    name,
                    value: v,
                    reason: "must be finite and non-negative",
                });
            }
        }
        Ok(Langevin {
            temperature,
            friction,
            rotational_friction: friction,
            seed,
        })
    }
}

/// SplitMix64's finaliser: a bijective 64-bit hash.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Six standard normal deviates for (seed, body, step), by Box-Muller from hashed counters.
#[inline]
pub fn noise(seed: u64, body: u64, step: u64) -> [f64; 6] {
    let key = mix(seed ^ mix(body.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ mix(step.wrapping_add(0xD1B5_4A32_D192_ED03))));
    let mut out = [0.0; 6];
    for k in 0..3 {
        let a = mix(key.wrapping_add((2 * k as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)));
        let b = mix(key.wrapping_add((2 * k as u64 + 2).wrapping_mul(0x9E37_79B9_7F4A_7C15)));
        // Uniforms in (0, 1] and [0, 1).
        let u1 = ((a >> 11) as f64 + 1.0) * (1.0 / (1u64 << 53) as f64);
        let u2 = (b >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * std::f64::consts::PI * u2).sin_cos();
        out[2 * k] = r * c;
        out[2 * k + 1] = r * s;
    }
    out
}

impl Bodies {
    /// One BAOAB Langevin step (see [`super::thermostat`]); step `k` of the noise is
    /// [`Bodies::langevin_steps`], counted by this method.
    ///
    /// # Errors
    /// A bad step or thermostat, or a failed solve of the rotation's equation (the system is then
    /// mid-step).
    pub fn step_langevin<I: Interaction + ?Sized>(
        &mut self,
        interaction: &I,
        h: f64,
        thermostat: &Langevin,
    ) -> Result<()> {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::InvalidStep { h });
        }
        if !self.forces_valid {
            self.evaluate(interaction);
        }
        self.langevin_motion(h, thermostat, None)?;
        self.evaluate(interaction);
        self.kick(h);
        Ok(())
    }

    /// The part of [`Bodies::step_langevin`] before the new forces: the start impulse, the
    /// B-A-O-A-B motion with the noise of body `ids[i]` (of `i` without `ids`: a domain's
    /// bodies keep their identities in the whole system), `t ← t + h` and the step counter.
    /// The forces must be valid.
    ///
    /// # Errors
    /// A failed solve of the rotation's equation (the system is then mid-step).
    pub(crate) fn langevin_motion(&mut self, h: f64, thermostat: &Langevin, ids: Option<&[u64]>) -> Result<()> {
        let hh = 0.5 * h;
        let t = self.t;
        let step = self.langevin_steps;
        let (c, cr) = (
            (-thermostat.friction * h).exp(),
            (-thermostat.rotational_friction * h).exp(),
        );
        let (sp, sr) = (
            ((1.0 - c * c) * thermostat.temperature).sqrt(),
            ((1.0 - cr * cr) * thermostat.temperature).sqrt(),
        );
        let failure: Mutex<Option<(usize, Error)>> = Mutex::new(None);
        let seed = thermostat.seed;
        let (motion, all) = self.split(h);
        let (inertia, free, mass, exact, drift) = (
            motion.inertia,
            motion.free,
            motion.mass,
            motion.exact,
            motion.rotation_drift,
        );
        for_each_chunk(all, |start, ch| {
            let (p, pi, x, r) = (ch.momentum, ch.pi, ch.position, ch.rotation);
            let n = p.len();
            let (free, mass) = (&free[start..start + n], &mass[start..start + n]);
            kick_chunk(free, p, pi, ch.force, ch.torque, hh);
            for k in 0..n {
                let i = start + k;
                let half = |x: &mut Vec3, p: Vec3, r: &mut crate::linalg::Mat3, pi: &mut Vec3| -> Result<()> {
                    if free[k] {
                        *x += p * (hh / mass[k]);
                    }
                    match exact {
                        Some(flows) => {
                            let (pe, re) = flows[i].flow(*pi, r, hh);
                            (*pi, *r) = (pe, re);
                            Ok(())
                        }
                        None => free_rotation_by(drift, &inertia[i], r, pi, 0.5 * hh)
                            .map_err(|e| newton_error("Langevin splitting", drift.equation(), t, h, e)),
                    }
                };
                let mut run = || -> Result<()> {
                    half(&mut x[k], p[k], &mut r[k], &mut pi[k])?;
                    let xi = noise(seed, ids.map_or(i as u64, |ids| ids[i]), step);
                    if free[k] {
                        p[k] = p[k] * c + Vec3::new(xi[0], xi[1], xi[2]) * (sp * mass[k].sqrt());
                    }
                    let sqrt_i = Vec3::new(
                        inertia[i].moments.x.sqrt(),
                        inertia[i].moments.y.sqrt(),
                        inertia[i].moments.z.sqrt(),
                    );
                    pi[k] = pi[k] * cr + sqrt_i.component_mul(Vec3::new(xi[3], xi[4], xi[5])) * sr;
                    half(&mut x[k], p[k], &mut r[k], &mut pi[k])
                };
                if let Err(e) = run() {
                    keep_first_failure(&failure, i, e);
                    return;
                }
            }
        });
        if let Some((_, e)) = failure.into_inner().expect("not poisoned") {
            self.forces_valid = false;
            return Err(e);
        }
        self.t = t + h;
        self.langevin_steps += 1;
        Ok(())
    }
}
