//! The convergence study of the paper's Figure 1: every method's momentum and attitude
//! errors at `t_end` against a reference computed here, for a sequence of steps.

use liemid::{integrate, integrate_to, RigidState, RotationIntegrator, RotationMethod, RungeKutta4Quaternion};
use serde::Serialize;

use crate::rigid::scenario::Scenario;
use crate::shared::figure::{Axes, Figure, Series};
use crate::shared::progress::Progress;

/// One method's errors.
#[derive(Clone, Debug, Serialize)]
pub struct MethodErrors {
    /// The short name, e.g. `liemid-ea`.
    pub name: String,
    /// The name in the literature, e.g. `LIEMID[EA]`.
    pub label: String,
    /// The classical order.
    pub order: u32,
    /// Step sizes.
    pub steps: Vec<f64>,
    /// `|Π − Π_ref| / |Π_ref|` per step (null where the run failed).
    pub momentum_error: Vec<Option<f64>>,
    /// `‖R − R_ref‖_F` per step (null where the run failed).
    pub attitude_error: Vec<Option<f64>>,
    /// Why a run failed, per step (null where it succeeded).
    pub failure: Vec<Option<String>>,
    /// Least-squares slope of the momentum error over the three smallest steps.
    pub observed_order_momentum: Option<f64>,
    /// Least-squares slope of the attitude error over the three smallest steps.
    pub observed_order_attitude: Option<f64>,
}

/// The reference solution.
#[derive(Clone, Debug, Serialize)]
pub struct Reference {
    /// `Π(t_end)`.
    pub pi: [f64; 3],
    /// `R(t_end)`, row-major.
    pub rotation: [f64; 9],
    /// How it was computed.
    pub method: String,
    /// Its step.
    pub step: f64,
    /// Estimated error (Richardson: difference to the run at twice the step, divided by 15).
    pub estimated_error: f64,
}

/// The whole study, as written by `--json`.
#[derive(Clone, Debug, Serialize)]
pub struct Study {
    /// Problem or scenario name.
    pub problem: String,
    /// End time.
    pub t_end: f64,
    /// The reference solution.
    pub reference: Reference,
    /// Per-method errors.
    pub methods: Vec<MethodErrors>,
}

/// Order over the three smallest steps that all succeeded.
fn order_of(steps: &[f64], errors: &[Option<f64>]) -> Option<f64> {
    let mut pairs: Vec<(f64, f64)> = steps
        .iter()
        .zip(errors)
        .filter_map(|(h, e)| e.filter(|e| *e > 0.0).map(|e| (*h, e)))
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    pairs.truncate(3);
    if pairs.len() < 3 {
        return None;
    }
    let (x, y): (Vec<f64>, Vec<f64>) = pairs.into_iter().unzip();
    liemid::observed_order(&x, &y)
}

fn errors(state: &RigidState, reference: &RigidState) -> (f64, f64) {
    (
        (state.pi - reference.pi).norm() / reference.pi.norm(),
        (state.rotation - reference.rotation).norm_frobenius(),
    )
}

/// The reference: RK4 on quaternions at `h_min / 64`, and at most `0.01 / |Ω₀|` (so that a
/// study of large steps still gets an accurate reference: RK4's error per step is about
/// `(|Ω| h)⁵ / 120`), in at most 4·10⁷ steps, with a Richardson estimate of its own error.
pub fn reference(scenario: &Scenario, t_end: f64, h_min: f64) -> Result<(RigidState, Reference), liemid::Error> {
    reference_until(scenario, t_end, h_min, &crate::shared::progress::Silent)
}

/// [`reference()`], ended with [`liemid::Error::ObserverFailed`] once `progress` is
/// [`Progress::stopped`] (read every 1024 steps).
pub fn reference_until(
    scenario: &Scenario,
    t_end: f64,
    h_min: f64,
    progress: &dyn Progress,
) -> Result<(RigidState, Reference), liemid::Error> {
    use liemid::RigidBodySystem;
    let span = t_end - scenario.initial.t;
    let mut h = h_min / 64.0;
    let rate = scenario.system.inertia().apply_inverse(scenario.initial.pi).norm();
    if rate > 0.0 {
        h = h.min(0.01 / rate);
    }
    if span / h > 4e7 {
        h = span / 4e7;
    }
    let run = |h: f64| {
        integrate(
            &mut RungeKutta4Quaternion::new(),
            &scenario.system,
            scenario.initial,
            t_end,
            h,
            1024,
            |_, _, _| {
                if progress.stopped() {
                    Err("stopped".to_string())
                } else {
                    Ok(())
                }
            },
        )
    };
    let fine = run(h)?.state;
    let coarse = run(2.0 * h)?.state;
    let (dp, dr) = errors(&coarse, &fine);
    let reference = Reference {
        pi: fine.pi.to_array(),
        rotation: fine.rotation.to_row_major(),
        method: "classical RK4 on (Pi, unit quaternion)".into(),
        step: h,
        estimated_error: dp.max(dr) / 15.0,
    };
    Ok((fine, reference))
}

/// Run the study; methods run in parallel threads, results in the order given, each run
/// reported to `progress` as it ends (and the runs left skipped once it is
/// [`Progress::stopped`]).
pub fn study(
    scenario: &Scenario,
    methods: &[RotationMethod],
    steps: &[f64],
    t_end: f64,
    progress: &dyn Progress,
) -> Result<Study, liemid::Error> {
    let h_min = steps.iter().copied().fold(f64::INFINITY, f64::min);
    let (ref_state, reference) = reference_until(scenario, t_end, h_min, progress)?;
    progress.start((methods.len() * steps.len()) as u64, "runs");
    let results: Vec<MethodErrors> = std::thread::scope(|scope| {
        let handles: Vec<_> = methods
            .iter()
            .map(|&method| {
                let ref_state = &ref_state;
                scope.spawn(move || {
                    let mut momentum = Vec::new();
                    let mut attitude = Vec::new();
                    let mut failure = Vec::new();
                    for &h in steps {
                        if progress.stopped() {
                            momentum.push(None);
                            attitude.push(None);
                            failure.push(Some("stopped".to_string()));
                            continue;
                        }
                        let mut integrator = method.integrator();
                        match integrate_to(&mut integrator, &scenario.system, scenario.initial, t_end, h) {
                            Ok(run) => {
                                let (dp, dr) = errors(&run.state, ref_state);
                                momentum.push(Some(dp));
                                attitude.push(Some(dr));
                                failure.push(None);
                            }
                            Err(e) => {
                                momentum.push(None);
                                attitude.push(None);
                                failure.push(Some(e.to_string()));
                            }
                        }
                        progress.advance();
                    }
                    MethodErrors {
                        name: method.key().into(),
                        label: method.integrator().name().into(),
                        order: method.order(),
                        steps: steps.to_vec(),
                        observed_order_momentum: order_of(steps, &momentum),
                        observed_order_attitude: order_of(steps, &attitude),
                        momentum_error: momentum,
                        attitude_error: attitude,
                        failure,
                    }
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a convergence thread panicked"))
            .collect()
    });
    progress.finish();
    Ok(Study {
        problem: scenario.name.clone(),
        t_end,
        reference,
        methods: results,
    })
}

/// The study as a text table.
pub fn table(study: &Study) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let r = &study.reference;
    let _ = writeln!(
        s,
        "{} to t = {}; reference: {} at h = {:.3e} (estimated error {:.1e})",
        study.problem, study.t_end, r.method, r.step, r.estimated_error
    );
    let _ = writeln!(
        s,
        "{:<12} {:>10}  {:>14}  {:>14}",
        "method", "h", "momentum err", "attitude err"
    );
    let fmt = |e: Option<f64>| e.map_or_else(|| "failed".to_string(), |e| format!("{e:.3e}"));
    for m in &study.methods {
        for (k, h) in m.steps.iter().enumerate() {
            let _ = writeln!(
                s,
                "{:<12} {h:>10.3e}  {:>14}  {:>14}",
                m.label,
                fmt(m.momentum_error[k]),
                fmt(m.attitude_error[k])
            );
        }
        let o = |x: Option<f64>| x.map_or_else(|| "n/a".to_string(), |x| format!("{x:.2}"));
        let _ = writeln!(
            s,
            "{:<12} observed order (3 smallest steps): momentum {}, attitude {} (theory {})",
            m.label,
            o(m.observed_order_momentum),
            o(m.observed_order_attitude),
            m.order
        );
        for f in m.failure.iter().flatten().take(1) {
            let _ = writeln!(s, "{:<12} note: {f}", m.label);
        }
    }
    s
}

impl Study {
    /// The figure: momentum and attitude errors at `t_end` against the step, log-log, with
    /// the reference slopes.
    pub fn figure(&self) -> Figure<'static> {
        let collect = |f: &dyn Fn(&MethodErrors, usize) -> Option<f64>| -> Vec<Series> {
            self.methods
                .iter()
                .map(|m| {
                    let pts = m
                        .steps
                        .iter()
                        .enumerate()
                        .filter_map(|(k, h)| f(m, k).filter(|v| *v > 0.0).map(|v| (*h, v)));
                    (m.label.clone(), pts.collect())
                })
                .collect()
        };
        let axes = |title, y_desc| Axes {
            title,
            x_desc: "step h (s)",
            y_desc,
            slopes: true,
        };
        Figure {
            title: format!("{}: error at t = {} s against the step", self.problem, self.t_end),
            labels: self.methods.iter().map(|m| m.label.clone()).collect(),
            panels: [
                (
                    axes("body angular momentum", "|Pi - Pi_ref| / |Pi_ref|"),
                    collect(&|m, k| m.momentum_error[k]),
                ),
                (
                    axes("attitude", "||R - R_ref||_F"),
                    collect(&|m, k| m.attitude_error[k]),
                ),
            ],
        }
    }
}
