//! The driver of a beam run, the one under every front end (the `liemid beam` command and
//! the Python package): the integrator by key (an explicit splitting or implicit Newmark,
//! [`BeamIntegrator`]), the step policy (the default step at 0.9 of the critical one, a
//! larger step refused unless forced, whole steps between samples: [`BeamDriver::plan`]),
//! and the stepping ([`BeamDriver::advance`]). Sampling, timing and output are the front
//! ends'.
//!
//! Reference: docs/beams.md (the stability bound and the methods).

use crate::error::{Error, Result};

use super::{BeamMethod, BeamSystem, Newmark, Stability};

/// The integrators of a beam run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BeamIntegrator {
    /// An explicit splitting.
    Explicit(BeamMethod),
    /// Implicit Newmark (average acceleration) with Newton.
    Newmark,
}

impl BeamIntegrator {
    /// Every integrator.
    pub const ALL: [BeamIntegrator; 5] = [
        BeamIntegrator::Explicit(BeamMethod::Splitting),
        BeamIntegrator::Explicit(BeamMethod::Splitting4),
        BeamIntegrator::Explicit(BeamMethod::Impulse),
        BeamIntegrator::Explicit(BeamMethod::MassScaled),
        BeamIntegrator::Newmark,
    ];

    /// The key in files, on the command line and in Python.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            BeamIntegrator::Explicit(m) => m.key(),
            BeamIntegrator::Newmark => "newmark",
        }
    }

    /// By key ([`BeamIntegrator::key`]).
    #[must_use]
    pub fn from_key(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.key() == key)
    }

    /// The explicit method, `None` for Newmark.
    #[must_use]
    pub fn explicit(self) -> Option<BeamMethod> {
        match self {
            BeamIntegrator::Explicit(m) => Some(m),
            BeamIntegrator::Newmark => None,
        }
    }
}

/// The steps of a sampled run ([`BeamDriver::plan`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepPlan {
    /// The step.
    pub step: f64,
    /// Steps between two samples.
    pub every: u64,
    /// Steps to the end.
    pub steps: u64,
    /// The critical step of the explicit method (of the splitting for Newmark).
    pub critical_step: f64,
    /// The bound of `ω_max` that sets it.
    pub omega_bound: f64,
}

/// A beam system and the integrator that steps it.
#[derive(Debug)]
pub struct BeamDriver {
    integrator: BeamIntegrator,
    stability: Stability,
    /// The explicit methods step this system; Newmark steps its own copy.
    system: BeamSystem,
    newmark: Option<Box<Newmark>>,
}

impl BeamDriver {
    /// `system` stepped by `integrator` from its current state (its stability bound is
    /// computed once, here).
    #[must_use]
    pub fn new(system: BeamSystem, integrator: BeamIntegrator) -> Self {
        let stability = system.stability(0);
        let newmark = (integrator == BeamIntegrator::Newmark).then(|| Box::new(Newmark::new(&system)));
        BeamDriver {
            integrator,
            stability,
            system,
            newmark,
        }
    }

    /// The integrator.
    #[must_use]
    pub fn integrator(&self) -> BeamIntegrator {
        self.integrator
    }

    /// The method whose bound and totals apply: the explicit method, or the splitting for
    /// Newmark.
    fn bound_method(&self) -> BeamMethod {
        self.integrator.explicit().unwrap_or(BeamMethod::Splitting)
    }

    /// The steps of a run to `t_end` sampled every `sample` (rounded to whole steps): at
    /// `step`, or by default 0.9 of the critical step for the explicit methods (shortened
    /// to divide the sample interval) and 0.05 for Newmark. An explicit step above the
    /// critical one is refused unless `force_step`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `t_end`, `sample` or `step` when not positive and
    /// finite; [`Error::UnstableStep`] for an explicit step above the critical one.
    pub fn plan(&self, t_end: f64, step: Option<f64>, sample: f64, force_step: bool) -> Result<StepPlan> {
        let positive = |name: &'static str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(Error::InvalidParameter {
                    name,
                    value,
                    reason: "must be positive and finite",
                })
            }
        };
        positive("t_end", t_end)?;
        positive("sample", sample)?;
        let explicit = self.integrator.explicit();
        let critical = self.stability.critical_step(self.bound_method());
        let (h, every) = match step {
            Some(h) => {
                positive("step", h)?;
                if let (Some(m), false) = (explicit, force_step) {
                    self.stability.check(m, h)?;
                }
                (h, ((sample / h).round() as u64).max(1))
            }
            None => {
                let default = if explicit.is_some() { 0.9 * critical } else { 0.05 };
                let k = (sample / default).ceil().max(1.0);
                (sample / k, k as u64)
            }
        };
        Ok(StepPlan {
            step: h,
            every,
            steps: (t_end / h - 1e-9).ceil() as u64,
            critical_step: critical,
            omega_bound: self.stability.omega_bound_of(self.bound_method()),
        })
    }

    /// `steps` steps of `h`.
    ///
    /// # Errors
    /// The step's errors (for Newmark, a Newton solve that does not converge).
    pub fn advance(&mut self, steps: u64, h: f64) -> Result<()> {
        for _ in 0..steps {
            match (&mut self.newmark, self.integrator) {
                (Some(nm), _) => nm.step(h).map(|_| ())?,
                (None, BeamIntegrator::Explicit(m)) => self.system.step_with(m, h)?,
                (None, BeamIntegrator::Newmark) => unreachable!("Newmark keeps its own system"),
            }
        }
        Ok(())
    }

    /// The system at the current state.
    #[must_use]
    pub fn system(&self) -> &BeamSystem {
        self.newmark.as_ref().map_or(&self.system, |nm| nm.system())
    }

    /// The conserved totals (energy, momenta) of the explicit method at the current state;
    /// `None` for Newmark (whose energy is not computed).
    #[must_use]
    pub fn totals(&self) -> Option<crate::many::Totals> {
        self.integrator.explicit().map(|m| self.system.totals_for(m))
    }

    /// Newton iterations of Newmark so far; `None` for the explicit methods.
    #[must_use]
    pub fn newton_iterations(&self) -> Option<u64> {
        self.newmark.as_ref().map(|nm| nm.iterations)
    }
}
