//! The model of a rigid body with a fixed point: state, the system trait (inertia and
//! torque model), the built-in models and the diagnostics.
//!
//! Equations of motion in the body (convected) frame:
//! `Π' = Π × Ω + T(R, t)`, `Ω = I⁻¹ Π`, `R' = R hat(Ω)`, where `R` maps body to space,
//! `Π` is the body angular momentum and `T` the body torque. The spatial angular momentum
//! `π = R Π` obeys `π' = R T`.

use crate::error::{Error, Result};
use crate::inertia::Inertia;
use crate::linalg::{Mat3, Vec3};
use crate::so3;

/// The state of a rotating rigid body: time, body angular momentum and attitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidState {
    /// Time (s).
    pub t: f64,
    /// Body angular momentum `Π` (kg m²/s).
    pub pi: Vec3,
    /// Attitude `R`, mapping body vectors to space.
    pub rotation: Mat3,
}

impl RigidState {
    /// A state from its parts.
    #[must_use]
    pub fn new(t: f64, pi: Vec3, rotation: Mat3) -> Self {
        RigidState { t, pi, rotation }
    }

    /// A state from the body angular velocity `Ω`: `Π = I Ω`.
    #[must_use]
    pub fn from_angular_velocity(t: f64, inertia: &Inertia, omega: Vec3, rotation: Mat3) -> Self {
        RigidState::new(t, inertia.apply(omega), rotation)
    }

    /// The spatial angular momentum `π = R Π`.
    #[must_use]
    pub fn spatial_momentum(&self) -> Vec3 {
        self.rotation * self.pi
    }

    /// An error naming the first field that holds a NaN or an infinity.
    pub fn check_finite(&self) -> Result<()> {
        if !self.t.is_finite() {
            return Err(Error::NonFiniteState { field: "t", t: self.t });
        }
        if !self.pi.is_finite() {
            return Err(Error::NonFiniteState { field: "pi", t: self.t });
        }
        if !self.rotation.is_finite() {
            return Err(Error::NonFiniteState {
                field: "rotation",
                t: self.t,
            });
        }
        Ok(())
    }
}

/// The largest orthogonality defect `‖RᵀR − I‖_F` the drivers accept in an initial
/// attitude: far above what any integrator's round-off reaches (2e-13 after 10⁶ EA steps),
/// far below any attitude that is meant to be something else.
pub const ROTATION_TOLERANCE: f64 = 1e-6;

impl RigidState {
    /// An error unless the state is finite and its attitude a rotation to within
    /// [`ROTATION_TOLERANCE`] (`det R > 0`).
    pub fn check_valid(&self) -> Result<()> {
        self.check_finite()?;
        let defect = so3::orthogonality_defect(&self.rotation);
        let determinant = self.rotation.determinant();
        if defect.is_nan() || defect > ROTATION_TOLERANCE || determinant <= 0.0 {
            return Err(Error::NotARotation {
                t: self.t,
                defect,
                determinant,
                tolerance: ROTATION_TOLERANCE,
            });
        }
        Ok(())
    }
}

/// A rigid body with a fixed point: its inertia and its torque model.
///
/// Implementations must be deterministic functions of `(R, t)`; integrators may cache a
/// torque for the configuration it was computed in.
pub trait RigidBodySystem {
    /// The body inertia tensor.
    fn inertia(&self) -> &Inertia;

    /// The torque in the body frame, `T(R, t)`.
    fn torque(&self, rotation: &Mat3, t: f64) -> Vec3;

    /// The potential energy `V(R, t)` whose torque this is, for the energy diagnostic.
    /// Zero by default (torque-free bodies, or non-conservative torques, whose energy
    /// diagnostic is then the kinetic energy alone).
    fn potential_energy(&self, _rotation: &Mat3, _t: f64) -> f64 {
        0.0
    }
}

impl<S: RigidBodySystem + ?Sized> RigidBodySystem for &S {
    fn inertia(&self) -> &Inertia {
        (**self).inertia()
    }
    fn torque(&self, rotation: &Mat3, t: f64) -> Vec3 {
        (**self).torque(rotation, t)
    }
    fn potential_energy(&self, rotation: &Mat3, t: f64) -> f64 {
        (**self).potential_energy(rotation, t)
    }
}

impl<S: RigidBodySystem + ?Sized> RigidBodySystem for Box<S> {
    fn inertia(&self) -> &Inertia {
        (**self).inertia()
    }
    fn torque(&self, rotation: &Mat3, t: f64) -> Vec3 {
        (**self).torque(rotation, t)
    }
    fn potential_energy(&self, rotation: &Mat3, t: f64) -> f64 {
        (**self).potential_energy(rotation, t)
    }
}

/// Wraps a system and counts its torque evaluations (for cost accounting and tests).
#[derive(Debug)]
pub struct CountingTorque<S> {
    /// The wrapped system.
    pub inner: S,
    count: std::cell::Cell<u64>,
}

impl<S> CountingTorque<S> {
    /// Wrap `inner`, with the count at zero.
    pub fn new(inner: S) -> Self {
        CountingTorque {
            inner,
            count: std::cell::Cell::new(0),
        }
    }

    /// Torque evaluations so far.
    #[must_use]
    pub fn count(&self) -> u64 {
        self.count.get()
    }
}

impl<S: RigidBodySystem> RigidBodySystem for CountingTorque<S> {
    fn inertia(&self) -> &Inertia {
        self.inner.inertia()
    }
    fn torque(&self, rotation: &Mat3, t: f64) -> Vec3 {
        self.count.set(self.count.get() + 1);
        self.inner.torque(rotation, t)
    }
    fn potential_energy(&self, rotation: &Mat3, t: f64) -> f64 {
        self.inner.potential_energy(rotation, t)
    }
}

/// A torque-free rigid body (Euler's equations). Keeps `|Π|`, the kinetic energy and the
/// spatial momentum `π` exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeBody {
    /// The body inertia tensor.
    pub inertia: Inertia,
}

impl FreeBody {
    /// A free body with the given inertia.
    #[must_use]
    pub fn new(inertia: Inertia) -> Self {
        FreeBody { inertia }
    }
}

impl RigidBodySystem for FreeBody {
    fn inertia(&self) -> &Inertia {
        &self.inertia
    }
    #[inline]
    fn torque(&self, _rotation: &Mat3, _t: f64) -> Vec3 {
        Vec3::ZERO
    }
}

fn check_vector(name: &'static str, v: Vec3) -> Result<()> {
    for c in v.to_array() {
        if !c.is_finite() {
            return Err(Error::InvalidParameter {
                name,
                value: c,
                reason: "must be finite",
            });
        }
    }
    Ok(())
}

/// A heavy top: a rigid body in a uniform gravity field, pivoting about a fixed point at
/// the body origin.
///
/// Body torque `T(R) = X × (Rᵀ m g)`, potential `V(R) = −m g · (R X)`, where `X` is the centre
/// of mass in the body frame and `g` the spatial gravity vector. Exact invariants: the
/// energy `½ Π·I⁻¹Π + V(R)` and the spatial momentum component along `g`; for a symmetric
/// top with `X` on the symmetry axis also the spin about that axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeavyTop {
    /// The body inertia tensor about the pivot (kg m²).
    pub inertia: Inertia,
    /// The mass `m` (kg).
    pub mass: f64,
    /// The centre of mass `X` in the body frame, from the pivot (m).
    pub center_of_mass: Vec3,
    /// The gravity vector `g` in the spatial frame (m/s²).
    pub gravity: Vec3,
    /// `m g`, precomputed.
    weight: Vec3,
}

impl HeavyTop {
    /// A heavy top; the mass must be finite and non-negative, the vectors finite.
    pub fn new(inertia: Inertia, mass: f64, center_of_mass: Vec3, gravity: Vec3) -> Result<Self> {
        if !mass.is_finite() || mass < 0.0 {
            return Err(Error::InvalidParameter {
                name: "mass",
                value: mass,
                reason: "must be finite and non-negative",
            });
        }
        check_vector("center_of_mass", center_of_mass)?;
        check_vector("gravity", gravity)?;
        Ok(HeavyTop {
            inertia,
            mass,
            center_of_mass,
            gravity,
            weight: gravity * mass,
        })
    }

    /// The fast Lagrangian top of the reference test case (docs/theory/rigid.md §8): an aluminium
    /// block 0.06 x 0.06 x 0.24 m (density 2700 kg/m³) pivoting at one end, under
    /// `g = (0, 0, −9.81)`.
    #[must_use]
    pub fn lagrangian_block() -> Self {
        let (w, h, l, rho) = (0.06, 0.06, 0.24, 2700.0);
        let mass = rho * w * h * l;
        let i1 = mass * (l * l + h * h) / 12.0 + mass * (l / 2.0) * (l / 2.0);
        let i3 = mass * (w * w + h * h) / 12.0;
        let inertia = Inertia::principal([i1, i1, i3]).expect("positive moments");
        HeavyTop::new(inertia, mass, Vec3::new(0.0, 0.0, l / 2.0), Vec3::new(0.0, 0.0, -9.81))
            .expect("finite parameters")
    }
}

impl RigidBodySystem for HeavyTop {
    fn inertia(&self) -> &Inertia {
        &self.inertia
    }
    #[inline]
    fn torque(&self, rotation: &Mat3, _t: f64) -> Vec3 {
        self.center_of_mass.cross(rotation.tr_mul_vec(self.weight))
    }
    fn potential_energy(&self, rotation: &Mat3, _t: f64) -> f64 {
        -self.weight.dot(*rotation * self.center_of_mass)
    }
}

/// A constant torque: a part fixed in the body frame plus a part fixed in space,
/// `T(R) = T_body + Rᵀ T_spatial`. Not conservative in general: its energy diagnostic is
/// the kinetic energy alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstantTorque {
    /// The body inertia tensor.
    pub inertia: Inertia,
    /// Torque fixed in the body frame (N m).
    pub body: Vec3,
    /// Torque fixed in the spatial frame (N m).
    pub spatial: Vec3,
}

impl ConstantTorque {
    /// A constant torque model; both vectors must be finite.
    pub fn new(inertia: Inertia, body: Vec3, spatial: Vec3) -> Result<Self> {
        check_vector("body", body)?;
        check_vector("spatial", spatial)?;
        Ok(ConstantTorque { inertia, body, spatial })
    }
}

impl RigidBodySystem for ConstantTorque {
    fn inertia(&self) -> &Inertia {
        &self.inertia
    }
    #[inline]
    fn torque(&self, rotation: &Mat3, _t: f64) -> Vec3 {
        self.body + rotation.tr_mul_vec(self.spatial)
    }
}

/// A torque given by a closure `T(R, t)` (body frame), with an optional potential for the
/// energy diagnostic.
pub struct TorqueFn<F, V = fn(&Mat3, f64) -> f64> {
    inertia: Inertia,
    torque: F,
    potential: Option<V>,
}

impl<F: Fn(&Mat3, f64) -> Vec3> TorqueFn<F> {
    /// A body with inertia `inertia` and body torque `torque(R, t)`.
    pub fn new(inertia: Inertia, torque: F) -> Self {
        TorqueFn {
            inertia,
            torque,
            potential: None,
        }
    }
}

impl<F: Fn(&Mat3, f64) -> Vec3, V: Fn(&Mat3, f64) -> f64> TorqueFn<F, V> {
    /// A body whose torque derives from the potential `potential(R, t)`; the caller
    /// guarantees that `torque` is its (negative) gradient.
    pub fn with_potential(inertia: Inertia, torque: F, potential: V) -> Self {
        TorqueFn {
            inertia,
            torque,
            potential: Some(potential),
        }
    }
}

impl<F: Fn(&Mat3, f64) -> Vec3, V: Fn(&Mat3, f64) -> f64> RigidBodySystem for TorqueFn<F, V> {
    fn inertia(&self) -> &Inertia {
        &self.inertia
    }
    #[inline]
    fn torque(&self, rotation: &Mat3, t: f64) -> Vec3 {
        (self.torque)(rotation, t)
    }
    fn potential_energy(&self, rotation: &Mat3, t: f64) -> f64 {
        self.potential.as_ref().map_or(0.0, |v| v(rotation, t))
    }
}

/// Conserved and monitored quantities of a rigid-body state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diagnostics {
    /// Total energy `½ Π·I⁻¹Π + V(R, t)` (J).
    pub energy: f64,
    /// Kinetic energy `½ Π·I⁻¹Π` (J).
    pub kinetic_energy: f64,
    /// Spatial angular momentum `π = R Π`.
    pub spatial_momentum: Vec3,
    /// Body angular momentum `Π`.
    pub body_momentum: Vec3,
    /// `|Π|`, kept exactly by the free body.
    pub body_momentum_norm: f64,
    /// Orthogonality defect `‖RᵀR − I‖_F`.
    pub orthogonality_defect: f64,
}

impl Diagnostics {
    /// The diagnostics of `state` under `system`.
    #[must_use]
    pub fn of<S: RigidBodySystem + ?Sized>(system: &S, state: &RigidState) -> Self {
        let omega = system.inertia().apply_inverse(state.pi);
        let kinetic = 0.5 * state.pi.dot(omega);
        Diagnostics {
            energy: kinetic + system.potential_energy(&state.rotation, state.t),
            kinetic_energy: kinetic,
            spatial_momentum: state.spatial_momentum(),
            body_momentum: state.pi,
            body_momentum_norm: state.pi.norm(),
            orthogonality_defect: so3::orthogonality_defect(&state.rotation),
        }
    }
}
