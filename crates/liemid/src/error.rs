//! Error values of the library. Every variant carries the numbers that explain it.

use thiserror::Error;

/// Everything that can go wrong when building a system or stepping it.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum Error {
    /// The inertia tensor is not that of a body: not finite, not symmetric positive definite, or
    /// its principal moments violate the triangle inequality.
    #[error("invalid inertia tensor: {reason}")]
    InvalidInertia {
        /// What is wrong with it.
        reason: String,
    },
    /// The mass matrix of a vector-space system is not symmetric positive definite.
    #[error("mass matrix is not symmetric positive definite: {reason}")]
    InvalidMass {
        /// What is wrong with it.
        reason: String,
    },
    /// A model parameter is out of range or not finite.
    #[error("invalid parameter `{name}` = {}: {reason}", Num(*.value))]
    InvalidParameter {
        /// Name of the parameter.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// A state holds a NaN or an infinity.
    #[error("state field `{field}` is not finite at t = {}", Num(*.t))]
    NonFiniteState {
        /// The field (`pi`, `rotation`, `t`, `p`, `u`).
        field: &'static str,
        /// The state's time.
        t: f64,
    },
    /// An attitude that is not a rotation matrix: `‖RᵀR − I‖_F` above
    /// [`crate::rigid::ROTATION_TOLERANCE`] or `det R ≤ 0`.
    #[error(
        "the attitude at t = {} is not a rotation: orthogonality defect |R^T R - I| = {defect:.3e} \
         (at most {tolerance:e} is accepted), determinant {determinant:.6}"
    , Num(*.t))]
    NotARotation {
        /// The state's time.
        t: f64,
        /// `‖RᵀR − I‖_F`.
        defect: f64,
        /// `det R`.
        determinant: f64,
        /// The largest defect accepted.
        tolerance: f64,
    },
    /// The step size is zero or not finite.
    #[error("step size h = {} must be finite and non-zero", Num(*.h))]
    InvalidStep {
        /// The step size.
        h: f64,
    },
    /// The end time lies before the start time (or either is not finite).
    #[error("end time t_end = {} is before the start time t0 = {} (or not finite)", Num(*.t_end), Num(*.t0))]
    EndBeforeStart {
        /// Start time.
        t0: f64,
        /// End time.
        t_end: f64,
    },
    /// The step is too small for the interval: the run would take more steps than the
    /// driver counts exactly (`2^53`), or `t + h` rounds to `t` at the end of the interval.
    #[error("step size h = {h:e} is too small for t from {} to {}: {reason}", Num(*.t0), Num(*.t_end))]
    StepTooSmall {
        /// The step size.
        h: f64,
        /// Start time.
        t0: f64,
        /// End time.
        t_end: f64,
        /// Which of the two limits it breaks.
        reason: String,
    },
    /// A method cache put back into a method that does not carry that kind of cache.
    #[error("{method} cannot take a cache of kind `{found}` (or it holds non-finite numbers)")]
    IncompatibleCache {
        /// The method.
        method: &'static str,
        /// The kind of cache offered.
        found: &'static str,
    },
    /// The output interval of the driver is zero.
    #[error("observer interval `every` must be at least 1")]
    InvalidObserverInterval,
    /// Newton's method for an implicit step equation did not converge.
    #[error(
        "{method}: {equation} did not converge in the step from t = {} with h = {} \
         ({}); {}"
    , Num(*.t), Num(*.h), Residual(*.residual, *.iterations), Hint(equation))]
    NewtonDidNotConverge {
        /// The integrator.
        method: &'static str,
        /// The equation being solved.
        equation: &'static str,
        /// Time at the start of the failing step.
        t: f64,
        /// The step size.
        h: f64,
        /// Norm of the last residual (relative to the equation's scale).
        residual: f64,
        /// Iterations taken.
        iterations: u32,
    },
    /// The rotation increment of a step exceeds half a turn.
    #[error(
        "{method}: the step from t = {} with h = {} turns the body by {} rad, more than \
         half a turn; the midpoint equation has no unique solution there: reduce the step"
    , Num(*.t), Num(*.h), Short(*.angle))]
    StepTooLarge {
        /// The integrator.
        method: &'static str,
        /// Time at the start of the failing step.
        t: f64,
        /// The step size.
        h: f64,
        /// The rotation angle `|Ψ|` of the increment (rad).
        angle: f64,
    },
    /// The state became NaN or infinite during a step.
    #[error("{method}: the state became non-finite in the step from t = {} with h = {}", Num(*.t), Num(*.h))]
    NonFiniteResult {
        /// The integrator.
        method: &'static str,
        /// Time at the start of the failing step.
        t: f64,
        /// The step size.
        h: f64,
    },
    /// A structural model that cannot be built: a node without elements, an element of
    /// zero length, an orientation vector along the element, a load on a missing node.
    #[error("invalid structural model: {reason}")]
    InvalidModel {
        /// What is wrong, naming the node, element or field.
        reason: String,
    },
    /// An explicit step above the estimated critical step of the linearised structure.
    #[error(
        "step h = {h:.4e} exceeds the critical step {critical:.4e} of the explicit method (largest \
         eigenfrequency at most {omega:.4e} rad per time unit in the linearised structure); use a smaller step"
    )]
    UnstableStep {
        /// The step asked for.
        h: f64,
        /// The estimated critical step.
        critical: f64,
        /// The largest eigenfrequency found.
        omega: f64,
    },
    /// A method asked to take time-transformed (adaptive) steps that is not symmetric, or
    /// not one the adaptive driver supports.
    #[error("{method} cannot take reversible adaptive steps: {reason}")]
    NotReversible {
        /// The method.
        method: &'static str,
        /// Why.
        reason: &'static str,
    },
    /// The adaptive step-size control failed: the control variable `z` (the step density,
    /// `h = ε/z`) became non-positive or non-finite, or the step density was.
    #[error(
        "adaptive step control failed at t = {}: {what} = {value:e} with eps = {eps:e}; the \
         step density must stay finite and positive (reduce eps)"
    , Num(*.t))]
    StepControl {
        /// Time of the state where it failed.
        t: f64,
        /// Which quantity (`rho`, `z`, `h`).
        what: &'static str,
        /// Its value.
        value: f64,
        /// The accuracy parameter.
        eps: f64,
    },
    /// A model file (MJCF, URDF) that cannot be loaded: not well-formed XML, a value that is
    /// missing, malformed or out of range, or a structure the multibody model cannot
    /// represent. `line` is 1-based (0 when the whole file is at fault, e.g. unreadable).
    #[error("{}", model_file_message(file, *line, element, message))]
    ModelFile {
        /// The file's name (as given to the loader).
        file: String,
        /// The line of the offending element (1-based; 0 for the whole file).
        line: u32,
        /// The element, e.g. `body name="upper_arm"` (empty for the whole file).
        element: String,
        /// What is wrong.
        message: String,
    },
    /// The observer asked the driver to stop with an error of its own.
    #[error("observer stopped the run at t = {}: {reason}", Num(*.t))]
    ObserverFailed {
        /// Time of the state the observer saw.
        t: f64,
        /// The observer's message.
        reason: String,
    },
}

fn model_file_message(file: &str, line: u32, element: &str, message: &str) -> String {
    let message = abbreviate_quoted(message);
    if line == 0 {
        format!("{file}: {message}")
    } else {
        format!("{file}:{line}: <{element}>: {message}")
    }
}

/// `text` for a message: whole up to 60 characters, else its first 40 and how long it is (an
/// attribute of 200,000 numbers used to be echoed whole, a 400 KB error line).
pub(crate) fn abbreviate(text: &str) -> String {
    if text.chars().count() <= 60 {
        return text.to_string();
    }
    let head: String = text.chars().take(40).collect();
    format!("{head}… ({} characters)", text.chars().count())
}

/// `message` with every value quoted in backticks abbreviated ([`abbreviate`]): whatever a
/// model file's message quotes from the file stays short.
fn abbreviate_quoted(message: &str) -> String {
    let mut out = String::with_capacity(message.len().min(1024));
    for (k, part) in message.split('`').enumerate() {
        if k > 0 {
            out.push('`');
        }
        // Odd parts lie between a pair of backticks.
        if k % 2 == 1 {
            out.push_str(&abbreviate(part));
        } else {
            out.push_str(&shorten_numbers(part));
        }
    }
    out
}

/// `text` with every number written with more than 24 characters (a value of 1e300 printed
/// digit by digit) written as [`Num`] writes it.
fn shorten_numbers(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len().min(1024));
    let mut i = 0;
    while i < bytes.len() {
        let starts =
            bytes[i].is_ascii_digit() || (bytes[i] == b'-' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit));
        if starts {
            let mut j = i + 1;
            while j < bytes.len() && (bytes[j].is_ascii_digit() || matches!(bytes[j], b'.' | b'e' | b'E' | b'+' | b'-'))
            {
                j += 1;
            }
            let token = &text[i..j];
            match token.parse::<f64>() {
                Ok(v) if token.len() > 24 => out.push_str(&Num(v).to_string()),
                _ => out.push_str(token),
            }
            i = j;
        } else {
            let c = text[i..].chars().next().unwrap_or(' ');
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// The end of a failed solve in words: "residual 2.044e-12 after 60 iterations", "the
/// residual became non-finite after 3 iterations", or, when no residual was measured (a
/// failure before the first iteration's residual), "after 0 iterations" alone: never a
/// residual of 0 for a solve that failed.
struct Residual(f64, u32);

impl core::fmt::Display for Residual {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let Residual(r, n) = *self;
        let iterations = if n == 1 { "iteration" } else { "iterations" };
        if !r.is_finite() {
            write!(f, "the residual became non-finite after {n} {iterations}")
        } else if r == 0.0 {
            write!(f, "after {n} {iterations}")
        } else {
            write!(f, "residual {r:.3e} after {n} {iterations}")
        }
    }
}

/// A number in messages: as Rust prints it between 1e-4 and 1e6 (`0.8`, `1000`), in
/// exponent form outside (`1e300`, not three hundred digits).
#[derive(Clone, Copy, Debug)]
pub struct Num(pub f64);

impl core::fmt::Display for Num {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || !a.is_finite() || (1e-4..1e6).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// What to try when `equation` does not converge.
struct Hint<'a>(&'a str);

impl core::fmt::Display for Hint<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.0.contains("contact") {
            f.write_str(
                "the step was split down to h/16, tried there with friction in the closing kick only, \
                 and its law still missed the acceptance (1e-8 of the contact length): redundant contacts of bodies resting on several others, or contacts \
                 sliding together near their friction limit, stall this solver: a known limit \
                 (docs/theory/multibody.md §6)",
            )
        } else {
            f.write_str("the step is probably too large for the rotation rate")
        }
    }
}

/// A number with three decimals where that is short (`7.291`), else in scientific notation
/// with three (`1.021e43`).
pub struct Short(pub f64);

impl core::fmt::Display for Short {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || !a.is_finite() || (1e-3..1e6).contains(&a) {
            write!(f, "{:.3}", self.0)
        } else {
            write!(f, "{:.3e}", self.0)
        }
    }
}

/// Result type of the library.
pub type Result<T, E = Error> = core::result::Result<T, E>;

/// Reject a step size that is zero or not finite.
#[inline]
pub(crate) fn check_step(h: f64) -> Result<()> {
    if h.is_finite() && h != 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidStep { h })
    }
}

#[cfg(test)]
mod message_tests {
    use super::*;

    /// A failed solve never reports a residual of 0 (issue 48: "residual 0.000e0").
    #[test]
    fn a_failed_solve_says_what_its_residual_was() {
        let e = |residual| Error::NewtonDidNotConverge {
            method: "m",
            equation: "e",
            t: 1e300,
            h: 0.5,
            residual,
            iterations: 3,
        };
        let text = e(2.5e-12).to_string();
        assert!(
            text.contains("residual 2.500e-12 after 3 iterations") && text.contains("t = 1e300"),
            "{text}"
        );
        assert!(e(f64::NAN)
            .to_string()
            .contains("(the residual became non-finite after 3 iterations)"));
        let zero = e(0.0).to_string();
        assert!(
            zero.contains("(after 3 iterations)") && !zero.contains("0.000e0"),
            "{zero}"
        );
    }

    /// Whatever a model file's message quotes is abbreviated.
    #[test]
    fn quoted_values_are_abbreviated() {
        let long = "1.5 ".repeat(10_000);
        let text = Error::ModelFile {
            file: "m.xml".into(),
            line: 3,
            element: "geom".into(),
            message: format!("unknown geom type `{long}`, known `sphere`"),
        }
        .to_string();
        assert!(text.len() < 200, "{text}");
        assert!(text.contains("(40000 characters)`, known `sphere`"), "{text}");
    }
}
