//! The one DOP853 configuration of every baseline run (rigid body, satellite, multibody
//! joint coordinates): `ode_solvers`' Dormand-Prince 8(5,3) with Hairer's step control.

/// `Dop853::from_param` with liemid's baseline settings: absolute tolerance `rtol · 1e-3`,
/// Hairer's safety factor 0.9, no PI stabilisation (`β = 0`), step ratio within
/// `[0.333, 6]`, the largest step the whole span `dx`, the first step chosen by the
/// solver, no limit on the step count (or the optional seventh argument, a `u32`), the
/// stiffness test every 1000 steps, and output at the `dx` grid only
/// (`OutputType::Sparse`). Arguments: the system, `t0`, `t_end`, `dx`, `y0`, `rtol`
/// [, `max_steps`].
///
/// Reference: E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential
/// Equations I*, 2nd ed., Springer (1993), section II.10 (DOP853).
#[macro_export]
macro_rules! dop853 {
    ($system:expr, $t0:expr, $t_end:expr, $dx:expr, $y0:expr, $rtol:expr $(,)?) => {
        $crate::dop853!($system, $t0, $t_end, $dx, $y0, $rtol, u32::MAX)
    };
    ($system:expr, $t0:expr, $t_end:expr, $dx:expr, $y0:expr, $rtol:expr, $max_steps:expr $(,)?) => {{
        let (dx, rtol) = ($dx, $rtol);
        $crate::shared::dop853::ode_solvers::Dop853::from_param(
            $system,
            $t0,
            $t_end,
            dx,
            $y0,
            rtol,
            rtol * 1e-3,
            0.9,
            0.0,
            0.333,
            6.0,
            dx,
            0.0,
            $max_steps,
            1000,
            $crate::shared::dop853::ode_solvers::OutputType::Sparse,
        )
    }};
}
pub use crate::dop853;
/// The solver the macro configures, for callers that name its types.
pub use ode_solvers;
