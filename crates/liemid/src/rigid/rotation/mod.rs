//! One-step integrators for a rigid body with a fixed point.
//!
//! Each method is a type named after the literature, implementing [`RotationIntegrator`].
//! [`RotationMethod`] names them all for run-time selection and [`AnyRotationIntegrator`]
//! dispatches to them.

mod akw;
mod exact;
mod liemid;
mod newmark;
mod rk4;
mod simo_wong;
mod variational;

pub use akw::AustinKrishnaprasadWang;
pub use exact::LieMidpointExact;
pub use liemid::{LieMidpointAlternating, LieMidpointE1, LieMidpointE2, LieMidpointImplicit};
pub use newmark::KryslEndresNewmark;
pub use rk4::{RungeKutta4Quaternion, RungeKuttaMuntheKaas4};
pub use simo_wong::SimoWong;
pub use variational::LieVariationalAlternating;

use crate::composition::{Composition, Scheme};
pub(crate) use crate::error::check_step;
use crate::error::{Error, Result};
use crate::linalg::{Mat3, Vec3};
pub(crate) use crate::midpoint::newton_error;
use crate::rigid::{RigidBodySystem, RigidState};

/// A one-step method for [`RigidBodySystem`]s.
pub trait RotationIntegrator {
    /// The method's name as in the literature, e.g. `LIEMID[EA]`.
    fn name(&self) -> &'static str;

    /// The classical order of accuracy.
    fn order(&self) -> u32;

    /// Advance `state` by one step `h` (which may be negative). On error the state is left
    /// unchanged.
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()>;

    /// Forget anything cached from earlier steps (the end torque, a quaternion).
    /// Caches are keyed on the system, time and attitude, so this is needed only when a
    /// system's torque model is mutated between steps.
    fn reset(&mut self) {}
}

/// Reject a step whose result is not finite, leaving the state unchanged.
#[inline]
pub(crate) fn commit(method: &'static str, state: &mut RigidState, h: f64, next: RigidState) -> Result<()> {
    if next.pi.is_finite() && next.rotation.is_finite() {
        *state = next;
        Ok(())
    } else {
        Err(Error::NonFiniteResult { method, t: state.t, h })
    }
}

/// The torque at the end of the previous step, reused as the start torque of the next
/// (so that explicit methods pay one torque evaluation per step).
///
/// The key is the system's address, the time (to a relative 1e-12, since drivers may
/// reset the time to `t0 + k h`) and the attitude, bit for bit.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TorqueCache {
    entry: Option<(usize, f64, Mat3, Vec3)>,
}

impl TorqueCache {
    #[inline]
    fn address<S: ?Sized>(system: &S) -> usize {
        system as *const S as *const u8 as usize
    }

    /// The torque at `(R, t)`, from the cache when it holds that configuration.
    #[inline]
    pub(crate) fn torque<S: RigidBodySystem + ?Sized>(&self, system: &S, rotation: &Mat3, t: f64) -> Vec3 {
        if let Some((addr, tc, rc, torque)) = &self.entry {
            if *addr == Self::address(system)
                && (t == *tc || (t - tc).abs() <= 1e-12 * t.abs().max(tc.abs()))
                && rc.bitwise_eq(rotation)
            {
                return Vec3::load_split(torque);
            }
        }
        system.torque(rotation, t)
    }

    /// Remember the torque at `(R, t)`.
    #[inline]
    pub(crate) fn store<S: RigidBodySystem + ?Sized>(&mut self, system: &S, rotation: &Mat3, t: f64, torque: Vec3) {
        self.entry = Some((Self::address(system), t, *rotation, torque));
    }

    pub(crate) fn clear(&mut self) {
        self.entry = None;
    }

    /// The cached `(t, R, T)`, if any.
    pub(crate) fn snapshot(&self) -> Option<(f64, Mat3, Vec3)> {
        self.entry.map(|(_, t, r, torque)| (t, r, torque))
    }
}

/// What a method carries from one step to the next, taken out of it
/// ([`AnyRotationIntegrator::cache`]) and put back ([`AnyRotationIntegrator::restore_cache`])
/// so that a run stopped and continued (a checkpoint) takes the same steps bit for bit.
///
/// Every cached value is a function of the state, so a fresh method gives the same result
/// to round-off; only with the cache is it the same to the bit (RK4's quaternion is not
/// recomputed from the matrix; the end torque was computed at `t + h`, which may differ by
/// an ulp from the reset time `t0 + k h`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MethodCache {
    /// Nothing is carried.
    Empty,
    /// The end torque of the last step: `torque = T(rotation, t)` (EA, E2, AKW, NMB and
    /// the EA compositions).
    Torque {
        /// The time it was computed at.
        t: f64,
        /// The attitude it was computed at.
        rotation: Mat3,
        /// The body torque.
        torque: Vec3,
    },
    /// RK4's unit quaternion of the attitude it produced.
    Quaternion {
        /// The attitude.
        rotation: Mat3,
        /// Its quaternion, as RK4 integrated it.
        quaternion: crate::so3::Quaternion,
    },
}

impl MethodCache {
    fn kind(&self) -> &'static str {
        match self {
            MethodCache::Empty => "empty",
            MethodCache::Torque { .. } => "torque",
            MethodCache::Quaternion { .. } => "quaternion",
        }
    }

    fn from_torque(entry: Option<(f64, Mat3, Vec3)>) -> Self {
        entry.map_or(MethodCache::Empty, |(t, rotation, torque)| MethodCache::Torque {
            t,
            rotation,
            torque,
        })
    }
}

/// Every rotation method of the crate, for selection by name at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RotationMethod {
    /// [`LieMidpointE1`]: explicit midpoint Lie, impulse at the end.
    LieMidpointE1,
    /// [`LieMidpointE2`]: explicit midpoint Lie, impulse at the start.
    LieMidpointE2,
    /// [`LieMidpointAlternating`]: `E1_{h/2} ∘ E2_{h/2}`.
    LieMidpointAlternating,
    /// [`LieMidpointImplicit`]: implicit midpoint Lie.
    LieMidpointImplicit,
    /// [`AustinKrishnaprasadWang`].
    AustinKrishnaprasadWang,
    /// [`SimoWong`].
    SimoWong,
    /// [`KryslEndresNewmark`].
    KryslEndresNewmark,
    /// [`RungeKutta4Quaternion`].
    RungeKutta4,
    /// EA composed by Suzuki's 5-stage scheme: fourth order.
    LieMidpointAlternating4,
    /// EA composed by Yoshida's triple jump: fourth order.
    LieMidpointAlternating4Yoshida,
    /// EA composed by Kahan and Li's 9-stage scheme: sixth order.
    LieMidpointAlternating6,
    /// EA composed by Kahan and Li's 17-stage scheme: eighth order.
    LieMidpointAlternating8,
    /// [`LieMidpointExact`]: impulses around the exact torque-free flow.
    LieMidpointExact,
    /// EX composed by Suzuki's 5-stage scheme: fourth order.
    LieMidpointExact4,
    /// EX composed by Kahan and Li's 9-stage scheme: sixth order.
    LieMidpointExact6,
    /// EX composed by Kahan and Li's 17-stage scheme: eighth order.
    LieMidpointExact8,
    /// [`LieMidpointExact::fasso`]: impulses around Fassò's symmetric + asymmetric
    /// splitting of the free motion.
    LieMidpointFasso,
    /// FS composed by Suzuki's 5-stage scheme: fourth order.
    LieMidpointFasso4,
    /// FS composed by Kahan and Li's 9-stage scheme: sixth order.
    LieMidpointFasso6,
    /// FS composed by Kahan and Li's 17-stage scheme: eighth order.
    LieMidpointFasso8,
    /// [`RungeKuttaMuntheKaas4`]: the Lie-group RK4 baseline.
    RungeKuttaMuntheKaas4,
    /// [`LieVariationalAlternating`]: EA's impulses around the variational torque-free step.
    LieVariationalAlternating,
    /// EAV composed by Suzuki's 5-stage scheme: fourth order.
    LieVariationalAlternating4,
    /// EAV composed by Kahan and Li's 9-stage scheme: sixth order.
    LieVariationalAlternating6,
    /// EAV composed by Kahan and Li's 17-stage scheme: eighth order.
    LieVariationalAlternating8,
}

impl RotationMethod {
    /// Every method: the paper's line-up, the RK4 baseline, the EA compositions, the
    /// exact-flow family and the variational family.
    pub const ALL: [RotationMethod; 25] = [
        RotationMethod::LieMidpointE1,
        RotationMethod::LieMidpointE2,
        RotationMethod::LieMidpointAlternating,
        RotationMethod::LieMidpointImplicit,
        RotationMethod::AustinKrishnaprasadWang,
        RotationMethod::SimoWong,
        RotationMethod::KryslEndresNewmark,
        RotationMethod::RungeKutta4,
        RotationMethod::LieMidpointAlternating4,
        RotationMethod::LieMidpointAlternating4Yoshida,
        RotationMethod::LieMidpointAlternating6,
        RotationMethod::LieMidpointAlternating8,
        RotationMethod::LieMidpointExact,
        RotationMethod::LieMidpointExact4,
        RotationMethod::LieMidpointExact6,
        RotationMethod::LieMidpointExact8,
        RotationMethod::LieMidpointFasso,
        RotationMethod::LieMidpointFasso4,
        RotationMethod::LieMidpointFasso6,
        RotationMethod::LieMidpointFasso8,
        RotationMethod::RungeKuttaMuntheKaas4,
        RotationMethod::LieVariationalAlternating,
        RotationMethod::LieVariationalAlternating4,
        RotationMethod::LieVariationalAlternating6,
        RotationMethod::LieVariationalAlternating8,
    ];

    /// The paper's Figure 1 line-up plus the RK4 baseline.
    pub const PAPER: [RotationMethod; 8] = [
        RotationMethod::LieMidpointE1,
        RotationMethod::LieMidpointE2,
        RotationMethod::LieMidpointAlternating,
        RotationMethod::LieMidpointImplicit,
        RotationMethod::AustinKrishnaprasadWang,
        RotationMethod::SimoWong,
        RotationMethod::KryslEndresNewmark,
        RotationMethod::RungeKutta4,
    ];

    /// The short name used on the command line and in files, e.g. `liemid-ea`.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            RotationMethod::LieMidpointE1 => "liemid-e1",
            RotationMethod::LieMidpointE2 => "liemid-e2",
            RotationMethod::LieMidpointAlternating => "liemid-ea",
            RotationMethod::LieMidpointImplicit => "liemid-i",
            RotationMethod::AustinKrishnaprasadWang => "akw",
            RotationMethod::SimoWong => "simo-wong",
            RotationMethod::KryslEndresNewmark => "nmb",
            RotationMethod::RungeKutta4 => "rk4",
            RotationMethod::LieMidpointAlternating4 => "liemid-ea4",
            RotationMethod::LieMidpointAlternating4Yoshida => "liemid-ea4y",
            RotationMethod::LieMidpointAlternating6 => "liemid-ea6",
            RotationMethod::LieMidpointAlternating8 => "liemid-ea8",
            RotationMethod::LieMidpointExact => "liemid-ex",
            RotationMethod::LieMidpointExact4 => "liemid-ex4",
            RotationMethod::LieMidpointExact6 => "liemid-ex6",
            RotationMethod::LieMidpointExact8 => "liemid-ex8",
            RotationMethod::LieMidpointFasso => "liemid-fs",
            RotationMethod::LieMidpointFasso4 => "liemid-fs4",
            RotationMethod::LieMidpointFasso6 => "liemid-fs6",
            RotationMethod::LieMidpointFasso8 => "liemid-fs8",
            RotationMethod::RungeKuttaMuntheKaas4 => "rkmk4",
            RotationMethod::LieVariationalAlternating => "liemid-eav",
            RotationMethod::LieVariationalAlternating4 => "liemid-eav4",
            RotationMethod::LieVariationalAlternating6 => "liemid-eav6",
            RotationMethod::LieVariationalAlternating8 => "liemid-eav8",
        }
    }

    /// The method with the short name `key`.
    #[must_use]
    pub fn from_key(key: &str) -> Option<Self> {
        RotationMethod::ALL.into_iter().find(|m| m.key() == key)
    }

    /// The name in the literature, e.g. `LIEMID[EA]`.
    #[must_use]
    pub fn name(self) -> &'static str {
        self.integrator().name()
    }

    /// The classical order.
    #[must_use]
    pub fn order(self) -> u32 {
        self.integrator().order()
    }

    /// Whether the method can take reversible adaptive steps
    /// ([`crate::rigid::adaptive`]): `Ok` for the symmetric explicit families (EA, EX, FS
    /// and their compositions), otherwise why not.
    ///
    /// # Errors
    /// [`Error::NotReversible`] naming the method and the reason.
    pub fn check_reversible(self) -> Result<()> {
        use RotationMethod as M;
        let reason = match self {
            M::LieMidpointAlternating
            | M::LieMidpointAlternating4
            | M::LieMidpointAlternating4Yoshida
            | M::LieMidpointAlternating6
            | M::LieMidpointAlternating8
            | M::LieMidpointExact
            | M::LieMidpointExact4
            | M::LieMidpointExact6
            | M::LieMidpointExact8
            | M::LieMidpointFasso
            | M::LieMidpointFasso4
            | M::LieMidpointFasso6
            | M::LieMidpointFasso8
            | M::LieVariationalAlternating
            | M::LieVariationalAlternating4
            | M::LieVariationalAlternating6
            | M::LieVariationalAlternating8 => return Ok(()),
            M::LieMidpointE1 | M::LieMidpointE2 => {
                "it is not symmetric (E1 and E2 are each other's adjoint, first order); use liemid-ea, their symmetric composition"
            }
            M::RungeKutta4 | M::RungeKuttaMuntheKaas4 => {
                "it is not symmetric (an explicit Runge-Kutta method is not its own adjoint), so the time-transformed step would be neither reversible nor of its order in eps"
            }
            M::LieMidpointImplicit | M::AustinKrishnaprasadWang | M::SimoWong | M::KryslEndresNewmark => {
                "only the explicit symmetric families (liemid-ea, liemid-ex, liemid-fs and their compositions) are wired to the adaptive driver"
            }
        };
        Err(Error::NotReversible {
            method: self.name(),
            reason,
        })
    }

    /// Torque evaluations per step in a long run.
    #[must_use]
    pub fn torque_evaluations_per_step(self) -> &'static str {
        match self {
            RotationMethod::LieMidpointE1
            | RotationMethod::LieMidpointE2
            | RotationMethod::LieMidpointAlternating
            | RotationMethod::KryslEndresNewmark
            | RotationMethod::LieMidpointExact
            | RotationMethod::LieMidpointFasso
            | RotationMethod::LieVariationalAlternating => "1",
            RotationMethod::LieMidpointImplicit
            | RotationMethod::AustinKrishnaprasadWang
            | RotationMethod::SimoWong => "1 per Newton iteration",
            RotationMethod::RungeKutta4 | RotationMethod::RungeKuttaMuntheKaas4 => "4",
            RotationMethod::LieMidpointAlternating4
            | RotationMethod::LieMidpointExact4
            | RotationMethod::LieMidpointFasso4
            | RotationMethod::LieVariationalAlternating4 => "5",
            RotationMethod::LieMidpointAlternating4Yoshida => "3",
            RotationMethod::LieMidpointAlternating6
            | RotationMethod::LieMidpointExact6
            | RotationMethod::LieMidpointFasso6
            | RotationMethod::LieVariationalAlternating6 => "9",
            RotationMethod::LieMidpointAlternating8
            | RotationMethod::LieMidpointExact8
            | RotationMethod::LieMidpointFasso8
            | RotationMethod::LieVariationalAlternating8 => "17",
        }
    }

    /// One line on what the method is and what it conserves.
    #[must_use]
    pub fn description(self) -> &'static str {
        match self {
            RotationMethod::LieMidpointE1 => {
                "explicit midpoint Lie, impulse at end; adjoint of E2; keeps |Pi| and pi torque-free, pi.g with gravity"
            }
            RotationMethod::LieMidpointE2 => {
                "explicit midpoint Lie, impulse at start; keeps |Pi| and pi torque-free, pi.g with gravity"
            }
            RotationMethod::LieMidpointAlternating => {
                "E1(h/2) o E2(h/2); time-reversible, Lie-Poisson defect O(h^3) per step (not symplectic); keeps |Pi| and pi torque-free, pi.g with gravity; energy bounded"
            }
            RotationMethod::LieMidpointImplicit => {
                "implicit midpoint Lie, torque at the midpoint; symmetric; keeps |Pi| and pi torque-free, pi.g with gravity"
            }
            RotationMethod::AustinKrishnaprasadWang => {
                "implicit midpoint Lie-Poisson with Cayley update; keeps energy and |Pi| torque-free"
            }
            RotationMethod::SimoWong => "Simo-Wong energy-momentum; keeps energy and pi torque-free",
            RotationMethod::KryslEndresNewmark => {
                "explicit Newmark (gamma = 1/2, beta = 0) for rotations; symmetric; pi drifts slowly"
            }
            RotationMethod::RungeKutta4 => {
                "classical RK4 on (Pi, unit quaternion), renormalised each step; conserves nothing exactly"
            }
            RotationMethod::LieMidpointAlternating4 => "EA composed by Suzuki's 5-stage scheme; keeps what EA keeps",
            RotationMethod::LieMidpointAlternating4Yoshida => "EA composed by Yoshida's triple jump; keeps what EA keeps",
            RotationMethod::LieMidpointAlternating6 => "EA composed by Kahan-Li's 9-stage scheme; keeps what EA keeps",
            RotationMethod::LieMidpointAlternating8 => "EA composed by Kahan-Li's 17-stage scheme; keeps what EA keeps",
            RotationMethod::LieMidpointExact => {
                "half impulses around the exact torque-free flow; Lie-Poisson, symmetric; keeps what EA keeps; exact torque-free"
            }
            RotationMethod::LieMidpointExact4 => "EX composed by Suzuki's 5-stage scheme; keeps what EX keeps",
            RotationMethod::LieMidpointExact6 => "EX composed by Kahan-Li's 9-stage scheme; keeps what EX keeps",
            RotationMethod::LieMidpointExact8 => "EX composed by Kahan-Li's 17-stage scheme; keeps what EX keeps",
            RotationMethod::LieMidpointFasso => {
                "half impulses around Fasso's symmetric + asymmetric split of the free motion; Lie-Poisson, symmetric; keeps what EA keeps"
            }
            RotationMethod::LieMidpointFasso4 => "FS composed by Suzuki's 5-stage scheme; keeps what FS keeps",
            RotationMethod::LieMidpointFasso6 => "FS composed by Kahan-Li's 9-stage scheme; keeps what FS keeps",
            RotationMethod::LieMidpointFasso8 => "FS composed by Kahan-Li's 17-stage scheme; keeps what FS keeps",
            RotationMethod::RungeKuttaMuntheKaas4 => {
                "Runge-Kutta-Munthe-Kaas 4: RK4 in exponential coordinates on SO(3); conserves nothing exactly"
            }
            RotationMethod::LieVariationalAlternating => {
                "EA's half impulses around the variational torque-free step (V); Lie-Poisson, symmetric; keeps what EA keeps"
            }
            RotationMethod::LieVariationalAlternating4 => "EAV composed by Suzuki's 5-stage scheme; keeps what EAV keeps",
            RotationMethod::LieVariationalAlternating6 => "EAV composed by Kahan-Li's 9-stage scheme; keeps what EAV keeps",
            RotationMethod::LieVariationalAlternating8 => "EAV composed by Kahan-Li's 17-stage scheme; keeps what EAV keeps",
        }
    }

    /// A fresh integrator of this method.
    #[must_use]
    pub fn integrator(self) -> AnyRotationIntegrator {
        match self {
            RotationMethod::LieMidpointE1 => AnyRotationIntegrator::E1(LieMidpointE1::new()),
            RotationMethod::LieMidpointE2 => AnyRotationIntegrator::E2(LieMidpointE2::new()),
            RotationMethod::LieMidpointAlternating => AnyRotationIntegrator::Ea(LieMidpointAlternating::new()),
            RotationMethod::LieMidpointImplicit => AnyRotationIntegrator::I(LieMidpointImplicit::new()),
            RotationMethod::AustinKrishnaprasadWang => AnyRotationIntegrator::Akw(AustinKrishnaprasadWang::new()),
            RotationMethod::SimoWong => AnyRotationIntegrator::Sw(SimoWong::new()),
            RotationMethod::KryslEndresNewmark => AnyRotationIntegrator::Nmb(KryslEndresNewmark::new()),
            RotationMethod::RungeKutta4 => AnyRotationIntegrator::Rk4(RungeKutta4Quaternion::new()),
            RotationMethod::LieMidpointAlternating4 => ea_composition(Scheme::SUZUKI4, "LIEMID[EA]4"),
            RotationMethod::LieMidpointAlternating4Yoshida => ea_composition(Scheme::YOSHIDA4, "LIEMID[EA]4Y"),
            RotationMethod::LieMidpointAlternating6 => ea_composition(Scheme::KAHAN_LI6, "LIEMID[EA]6"),
            RotationMethod::LieMidpointAlternating8 => ea_composition(Scheme::KAHAN_LI8, "LIEMID[EA]8"),
            RotationMethod::LieMidpointExact => AnyRotationIntegrator::Ex(LieMidpointExact::new()),
            RotationMethod::LieMidpointExact4 => ex_composition(Scheme::SUZUKI4, "LIEMID[EX]4"),
            RotationMethod::LieMidpointExact6 => ex_composition(Scheme::KAHAN_LI6, "LIEMID[EX]6"),
            RotationMethod::LieMidpointExact8 => ex_composition(Scheme::KAHAN_LI8, "LIEMID[EX]8"),
            RotationMethod::LieMidpointFasso => AnyRotationIntegrator::Ex(LieMidpointExact::fasso()),
            RotationMethod::LieMidpointFasso4 => fs_composition(Scheme::SUZUKI4, "LIEMID[FS]4"),
            RotationMethod::LieMidpointFasso6 => fs_composition(Scheme::KAHAN_LI6, "LIEMID[FS]6"),
            RotationMethod::LieMidpointFasso8 => fs_composition(Scheme::KAHAN_LI8, "LIEMID[FS]8"),
            RotationMethod::RungeKuttaMuntheKaas4 => AnyRotationIntegrator::Rkmk4(RungeKuttaMuntheKaas4::new()),
            RotationMethod::LieVariationalAlternating => AnyRotationIntegrator::Eav(LieVariationalAlternating::new()),
            RotationMethod::LieVariationalAlternating4 => eav_composition(Scheme::SUZUKI4, "LIEMID[EAV]4"),
            RotationMethod::LieVariationalAlternating6 => eav_composition(Scheme::KAHAN_LI6, "LIEMID[EAV]6"),
            RotationMethod::LieVariationalAlternating8 => eav_composition(Scheme::KAHAN_LI8, "LIEMID[EAV]8"),
        }
    }
}

fn ea_composition(scheme: Scheme, name: &'static str) -> AnyRotationIntegrator {
    AnyRotationIntegrator::Composed(Composition::new(LieMidpointAlternating::new(), scheme, name))
}

fn eav_composition(scheme: Scheme, name: &'static str) -> AnyRotationIntegrator {
    AnyRotationIntegrator::ComposedV(Composition::new(LieVariationalAlternating::new(), scheme, name))
}

fn ex_composition(scheme: Scheme, name: &'static str) -> AnyRotationIntegrator {
    AnyRotationIntegrator::ComposedEx(Composition::new(LieMidpointExact::new(), scheme, name))
}

fn fs_composition(scheme: Scheme, name: &'static str) -> AnyRotationIntegrator {
    AnyRotationIntegrator::ComposedEx(Composition::new(LieMidpointExact::fasso(), scheme, name))
}

/// Any of the crate's rotation integrators, chosen at run time.
#[derive(Clone, Debug)]
pub enum AnyRotationIntegrator {
    /// LIEMID\[E1\].
    E1(LieMidpointE1),
    /// LIEMID\[E2\].
    E2(LieMidpointE2),
    /// LIEMID\[EA\].
    Ea(LieMidpointAlternating),
    /// LIEMID\[I\].
    I(LieMidpointImplicit),
    /// AKW.
    Akw(AustinKrishnaprasadWang),
    /// SW.
    Sw(SimoWong),
    /// NMB.
    Nmb(KryslEndresNewmark),
    /// RK4 on quaternions.
    Rk4(RungeKutta4Quaternion),
    /// A symmetric composition of EA.
    Composed(Composition<LieMidpointAlternating>),
    /// LIEMID\[EX\].
    Ex(LieMidpointExact),
    /// A symmetric composition of EX.
    ComposedEx(Composition<LieMidpointExact>),
    /// RKMK4.
    Rkmk4(RungeKuttaMuntheKaas4),
    /// LIEMID\[EAV\].
    Eav(LieVariationalAlternating),
    /// A symmetric composition of EAV.
    ComposedV(Composition<LieVariationalAlternating>),
}

macro_rules! dispatch {
    ($self:ident, $m:ident => $e:expr) => {
        match $self {
            AnyRotationIntegrator::E1($m) => $e,
            AnyRotationIntegrator::E2($m) => $e,
            AnyRotationIntegrator::Ea($m) => $e,
            AnyRotationIntegrator::I($m) => $e,
            AnyRotationIntegrator::Akw($m) => $e,
            AnyRotationIntegrator::Sw($m) => $e,
            AnyRotationIntegrator::Nmb($m) => $e,
            AnyRotationIntegrator::Rk4($m) => $e,
            AnyRotationIntegrator::Composed($m) => $e,
            AnyRotationIntegrator::Ex($m) => $e,
            AnyRotationIntegrator::ComposedEx($m) => $e,
            AnyRotationIntegrator::Rkmk4($m) => $e,
            AnyRotationIntegrator::Eav($m) => $e,
            AnyRotationIntegrator::ComposedV($m) => $e,
        }
    };
}

impl RotationIntegrator for AnyRotationIntegrator {
    fn name(&self) -> &'static str {
        dispatch!(self, m => m.name())
    }
    fn order(&self) -> u32 {
        dispatch!(self, m => m.order())
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        dispatch!(self, m => m.step(system, state, h))
    }
    fn reset(&mut self) {
        dispatch!(self, m => m.reset())
    }
}

impl AnyRotationIntegrator {
    /// What the method carries to its next step (see [`MethodCache`]).
    #[must_use]
    pub fn cache(&self) -> MethodCache {
        match self {
            AnyRotationIntegrator::E2(m) => MethodCache::from_torque(m.cache.snapshot()),
            AnyRotationIntegrator::Ea(m) => MethodCache::from_torque(m.cache.snapshot()),
            AnyRotationIntegrator::Akw(m) => MethodCache::from_torque(m.cache.snapshot()),
            AnyRotationIntegrator::Nmb(m) => MethodCache::from_torque(m.cache.snapshot()),
            AnyRotationIntegrator::Composed(m) => MethodCache::from_torque(m.base().cache.snapshot()),
            AnyRotationIntegrator::Ex(m) => MethodCache::from_torque(m.cache.snapshot()),
            AnyRotationIntegrator::ComposedEx(m) => MethodCache::from_torque(m.base().cache.snapshot()),
            AnyRotationIntegrator::Eav(m) => MethodCache::from_torque(m.cache.snapshot()),
            AnyRotationIntegrator::ComposedV(m) => MethodCache::from_torque(m.base().cache.snapshot()),
            AnyRotationIntegrator::Rk4(m) => {
                m.last
                    .map_or(MethodCache::Empty, |(rotation, quaternion)| MethodCache::Quaternion {
                        rotation,
                        quaternion,
                    })
            }
            AnyRotationIntegrator::E1(_)
            | AnyRotationIntegrator::I(_)
            | AnyRotationIntegrator::Sw(_)
            | AnyRotationIntegrator::Rkmk4(_) => MethodCache::Empty,
        }
    }

    /// Put back what [`AnyRotationIntegrator::cache`] took out, for `system` (the cache is
    /// keyed on the system it is used with).
    ///
    /// # Errors
    /// [`Error::IncompatibleCache`] when `cache` is of a kind this method does not carry,
    /// or holds non-finite numbers.
    pub fn restore_cache<S: RigidBodySystem + ?Sized>(&mut self, system: &S, cache: MethodCache) -> Result<()> {
        let method = self.name();
        let mismatch = || Error::IncompatibleCache {
            method,
            found: cache.kind(),
        };
        let finite = match cache {
            MethodCache::Empty => true,
            MethodCache::Torque { t, rotation, torque } => t.is_finite() && rotation.is_finite() && torque.is_finite(),
            MethodCache::Quaternion {
                rotation,
                quaternion: q,
            } => rotation.is_finite() && [q.w, q.x, q.y, q.z].iter().all(|c| c.is_finite()),
        };
        if !finite {
            return Err(mismatch());
        }
        let torque_cache = match self {
            AnyRotationIntegrator::E2(m) => Some(&mut m.cache),
            AnyRotationIntegrator::Ea(m) => Some(&mut m.cache),
            AnyRotationIntegrator::Akw(m) => Some(&mut m.cache),
            AnyRotationIntegrator::Nmb(m) => Some(&mut m.cache),
            AnyRotationIntegrator::Composed(m) => Some(&mut m.base_mut().cache),
            AnyRotationIntegrator::Ex(m) => Some(&mut m.cache),
            AnyRotationIntegrator::ComposedEx(m) => Some(&mut m.base_mut().cache),
            AnyRotationIntegrator::Eav(m) => Some(&mut m.cache),
            AnyRotationIntegrator::ComposedV(m) => Some(&mut m.base_mut().cache),
            _ => None,
        };
        match (torque_cache, cache) {
            (Some(c), MethodCache::Empty) => c.clear(),
            (Some(c), MethodCache::Torque { t, rotation, torque }) => c.store(system, &rotation, t, torque),
            (Some(_), MethodCache::Quaternion { .. }) => return Err(mismatch()),
            (None, _) => match (self, cache) {
                (AnyRotationIntegrator::Rk4(m), MethodCache::Empty) => m.last = None,
                (AnyRotationIntegrator::Rk4(m), MethodCache::Quaternion { rotation, quaternion }) => {
                    m.last = Some((rotation, quaternion));
                }
                (_, MethodCache::Empty) => {}
                _ => return Err(mismatch()),
            },
        }
        Ok(())
    }
}

impl<M: RotationIntegrator> RotationIntegrator for Composition<M> {
    fn name(&self) -> &'static str {
        self.name
    }
    fn order(&self) -> u32 {
        self.scheme.order
    }
    fn step<S: RigidBodySystem + ?Sized>(&mut self, system: &S, state: &mut RigidState, h: f64) -> Result<()> {
        let start = *state;
        for i in 0..self.scheme.stages {
            if let Err(e) = self.base.step(system, state, self.scheme.gamma(i) * h) {
                *state = start;
                return Err(e);
            }
        }
        Ok(())
    }
    fn reset(&mut self) {
        self.base.reset();
    }
}
