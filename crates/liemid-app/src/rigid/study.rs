//! Work-precision: for every method, the attitude error at `t_end` against the CPU time it
//! took (median of repeated runs in this process, after a warm-up), with the torque
//! evaluations and the largest energy error along the run.

use std::time::Instant;

use liemid::{advance, CountingTorque, RigidBodySystem, RigidState, RotationMethod, RunSummary};
use serde::Serialize;

use crate::rigid::baseline;
use crate::rigid::converge::Reference;
use crate::rigid::scenario::Scenario;
use crate::shared::figure::{work_series, Axes, Figure};
use crate::shared::progress::Progress;

/// A method in the study: fixed-step liemid method or the adaptive baseline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Entry {
    /// A fixed-step method.
    Fixed(RotationMethod),
    /// Dormand-Prince 8(5,3), adaptive.
    Dop853,
    /// A symmetric method with reversible adaptive steps (density |Ω|).
    Adaptive(RotationMethod),
}

impl Entry {
    /// The entry named `key`.
    pub fn from_key(key: &str) -> Option<Self> {
        if key == "dop853" {
            Some(Entry::Dop853)
        } else {
            RotationMethod::from_key(key).map(Entry::Fixed)
        }
    }
    /// The adaptive family: EA, EX and their compositions, with reversible adaptive steps.
    pub fn adaptive() -> Vec<Entry> {
        use RotationMethod as M;
        [
            M::LieMidpointAlternating,
            M::LieMidpointAlternating4,
            M::LieMidpointAlternating6,
            M::LieMidpointAlternating8,
            M::LieMidpointExact,
            M::LieMidpointExact4,
            M::LieMidpointExact8,
        ]
        .into_iter()
        .map(Entry::Adaptive)
        .collect()
    }
    /// Every entry.
    pub fn all() -> Vec<Entry> {
        let mut v: Vec<Entry> = RotationMethod::ALL.iter().map(|m| Entry::Fixed(*m)).collect();
        v.push(Entry::Dop853);
        v
    }
}

/// One run of one method.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// The fixed step (fixed-step methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// The relative tolerance (adaptive baseline).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// The accuracy parameter of a reversible adaptive run (`h = eps / z`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eps: Option<f64>,
    /// `‖R − R_ref‖_F` at `t_end`.
    pub attitude_error: f64,
    /// `|Π − Π_ref| / |Π_ref|` at `t_end`.
    pub momentum_error: f64,
    /// Median CPU (wall) time of the repetitions, in seconds.
    pub seconds: f64,
    /// Torque evaluations of one run.
    pub torque_evaluations: u64,
    /// Largest relative energy error along the run.
    pub max_energy_error: f64,
    /// Largest relative energy error over the first tenth of the run.
    pub energy_error_first_tenth: f64,
    /// Largest relative energy error over the last tenth of the run.
    pub energy_error_last_tenth: f64,
}

/// One method's curve.
#[derive(Clone, Debug, Serialize)]
pub struct Curve {
    /// Short name.
    pub name: String,
    /// Display name.
    pub label: String,
    /// The runs, from cheapest to most expensive.
    pub points: Vec<Point>,
    /// Why the sequence stopped early, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// CPU time each contender needs for one target error.
#[derive(Clone, Debug, Serialize)]
pub struct Target {
    /// The attitude error to reach.
    pub attitude_error: f64,
    /// The fastest liemid method and its time (log-log interpolation between runs).
    pub fastest_liemid: Option<(String, f64)>,
    /// DOP853's time.
    pub dop853_seconds: Option<f64>,
    /// RK4's time.
    pub rk4_seconds: Option<f64>,
}

/// The study, as written by `--json`.
#[derive(Clone, Debug, Serialize)]
pub struct Study {
    /// Problem name.
    pub problem: String,
    /// End time.
    pub t_end: f64,
    /// Timed repetitions per point (the median is reported).
    pub repetitions: usize,
    /// The reference solution.
    pub reference: Reference,
    /// Per-method curves.
    pub methods: Vec<Curve>,
    /// Time to reach 1e-3, 1e-6 and 1e-9.
    pub targets: Vec<Target>,
}

/// Settings of a study.
#[derive(Clone, Debug)]
pub struct Options {
    /// Methods.
    pub entries: Vec<Entry>,
    /// Timed repetitions (at least 5).
    pub repetitions: usize,
    /// Stop a method's sequence once one run takes longer than this (seconds).
    pub budget: f64,
    /// Stop once the attitude error is below this.
    pub min_error: f64,
    /// At most this many points per method.
    pub max_points: usize,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Warm-up before each timed point: at least one run and at least this long, so that the
/// first points of a process are not timed on a cold processor (measured: with a single
/// warm-up run, the first method of `--methods liemid-ea4,…` came out 15% to 25% slower
/// than the same point measured later in the process).
const WARM_UP_SECONDS: f64 = 0.02;

/// Median time of `reps` runs of `f` after warming up (see [`WARM_UP_SECONDS`]).
fn timed<T>(reps: usize, mut f: impl FnMut() -> Result<T, String>) -> Result<(T, f64), String> {
    let warm_up = Instant::now();
    let first = f()?;
    while warm_up.elapsed().as_secs_f64() < WARM_UP_SECONDS {
        std::hint::black_box(f()?);
    }
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        let start = Instant::now();
        std::hint::black_box(f()?);
        times.push(start.elapsed().as_secs_f64());
    }
    Ok((first, median(times)))
}

/// Energy errors over the first and last tenth of a fixed-step run, with the torque count.
fn diagnostics_run(
    scenario: &Scenario,
    method: RotationMethod,
    t_end: f64,
    h: f64,
) -> Result<(RunSummary, u64, f64, f64), String> {
    let counting = CountingTorque::new(&scenario.system);
    let t0 = scenario.initial.t;
    let span = t_end - t0;
    let e0 = liemid::Diagnostics::of(&scenario.system, &scenario.initial).energy;
    let (mut first, mut last) = (0.0f64, 0.0f64);
    let summary = liemid::integrate(
        &mut method.integrator(),
        &counting,
        scenario.initial,
        t_end,
        h,
        1,
        |_, s, d| {
            let e = if e0 != 0.0 {
                ((d.energy - e0) / e0).abs()
            } else {
                (d.energy - e0).abs()
            };
            if s.t <= t0 + 0.1 * span {
                first = first.max(e);
            }
            if s.t >= t_end - 0.1 * span {
                last = last.max(e);
            }
            Ok(())
        },
    )
    .map_err(|e| e.to_string())?;
    Ok((summary, counting.count(), first, last))
}

fn errors(state: &RigidState, reference: &RigidState) -> (f64, f64) {
    (
        (state.pi - reference.pi).norm() / reference.pi.norm(),
        (state.rotation - reference.rotation).norm_frobenius(),
    )
}

/// The first step of a method's sequence on a problem whose fastest rate is `rate`:
/// `Ω h ≈ 2` for the basic methods, eight times that for the compositions (their stages are
/// shorter), and `Ω h ≈ 1` for RK4. The exact-flow family has no limit from the spin (its
/// free motion is exact at any step), nor has Fassò's splitting (exact for a symmetric body,
/// its error set by the asymmetry): they start at `Ω h ≈ 64`.
fn first_step(method: RotationMethod, rate: f64) -> f64 {
    let exact = matches!(
        method,
        RotationMethod::LieMidpointExact
            | RotationMethod::LieMidpointExact4
            | RotationMethod::LieMidpointExact6
            | RotationMethod::LieMidpointExact8
            | RotationMethod::LieMidpointFasso
            | RotationMethod::LieMidpointFasso4
            | RotationMethod::LieMidpointFasso6
            | RotationMethod::LieMidpointFasso8
    );
    match method.order() {
        _ if exact => 64.0 / rate,
        _ if matches!(
            method,
            RotationMethod::RungeKutta4 | RotationMethod::RungeKuttaMuntheKaas4
        ) =>
        {
            1.0 / rate
        }
        1 | 2 => 2.0 / rate,
        _ => 16.0 / rate,
    }
}

/// The steps of the study's coarsest run to `t_end`, a lower bound of every run's: the
/// largest first step (`first_step`, `Ω h ≈ 64`) over the span. A front end refuses a
/// study beyond its step bound with it before the reference is computed.
#[must_use]
pub fn coarsest_steps(scenario: &Scenario, t_end: f64) -> f64 {
    let span = t_end - scenario.initial.t;
    let rate = scenario
        .system
        .inertia()
        .apply_inverse(scenario.initial.pi)
        .norm()
        .max(1.0 / span);
    span * rate / 64.0
}

fn curve_fixed(
    scenario: &Scenario,
    method: RotationMethod,
    t_end: f64,
    reference: &RigidState,
    options: &Options,
    progress: &dyn Progress,
) -> Curve {
    let rate = scenario
        .system
        .inertia()
        .apply_inverse(scenario.initial.pi)
        .norm()
        .max(1.0 / (t_end - scenario.initial.t));
    let mut h = first_step(method, rate);
    let mut points = Vec::new();
    let mut note = None;
    while points.len() < options.max_points && !progress.stopped() {
        let run = timed(options.repetitions, || {
            let mut state = scenario.initial;
            advance(&mut method.integrator(), &scenario.system, &mut state, t_end, h).map_err(|e| e.to_string())?;
            Ok(state)
        });
        let (end, seconds) = match run {
            Ok(r) => r,
            Err(e) => {
                // Too large a step for this method: try the next one.
                if points.is_empty() && h > 1e-9 {
                    h *= std::f64::consts::FRAC_1_SQRT_2;
                    continue;
                }
                note = Some(e);
                break;
            }
        };
        let (dp, dr) = errors(&end, reference);
        let (summary, evaluations, first, last) = match diagnostics_run(scenario, method, t_end, h) {
            Ok(d) => d,
            Err(e) => {
                note = Some(e);
                break;
            }
        };
        points.push(Point {
            step: Some(h),
            tolerance: None,
            eps: None,
            attitude_error: dr,
            momentum_error: dp,
            seconds,
            torque_evaluations: evaluations,
            max_energy_error: summary.max_energy_error,
            energy_error_first_tenth: first,
            energy_error_last_tenth: last,
        });
        if dr < options.min_error || seconds > options.budget {
            break;
        }
        h *= 0.5;
    }
    Curve {
        name: method.key().into(),
        label: method.name().into(),
        points,
        note,
    }
}

fn curve_dop853(
    scenario: &Scenario,
    t_end: f64,
    reference: &RigidState,
    options: &Options,
    progress: &dyn Progress,
) -> Curve {
    let mut points = Vec::new();
    let mut note = None;
    let mut tol = 1e-3;
    while points.len() < options.max_points && tol >= 1e-14 && !progress.stopped() {
        let run = timed(options.repetitions, || {
            baseline::dop853_until(&scenario.system, scenario.initial, t_end, tol, &|| progress.stopped())
        });
        let (run, seconds) = match run {
            Ok(r) => r,
            Err(e) => {
                note = Some(e);
                break;
            }
        };
        let tracked = match baseline::dop853_tenths(&scenario.system, scenario.initial, t_end, tol) {
            Ok(t) => t,
            Err(e) => {
                note = Some(e);
                break;
            }
        };
        let (dp, dr) = errors(&run.state, reference);
        points.push(Point {
            step: None,
            tolerance: Some(tol),
            eps: None,
            attitude_error: dr,
            momentum_error: dp,
            seconds,
            torque_evaluations: run.evaluations,
            max_energy_error: tracked.0,
            energy_error_first_tenth: tracked.1,
            energy_error_last_tenth: tracked.2,
        });
        if dr < options.min_error || seconds > options.budget {
            break;
        }
        tol *= 0.1;
    }
    Curve {
        name: "dop853".into(),
        label: "DOP853".into(),
        points,
        note,
    }
}

/// A reversible adaptive method (density |Ω|): `eps` from 1 (EA, EX) or 2 (compositions)
/// halved until the error or the time budget is reached.
fn curve_adaptive(
    scenario: &Scenario,
    method: RotationMethod,
    t_end: f64,
    reference: &RigidState,
    options: &Options,
    progress: &dyn Progress,
) -> Curve {
    use liemid::rigid::adaptive::{AdaptiveRun, AngularSpeed, RigidAdaptive};
    let mut eps = if method.order() > 2 { 2.0 } else { 1.0 };
    let mut points = Vec::new();
    let mut note = None;
    while points.len() < options.max_points && !progress.stopped() {
        let counting = CountingTorque::new(&scenario.system);
        let go = |system: &dyn Fn() -> Result<(RigidState, u64), String>| system();
        let run = timed(options.repetitions, || {
            go(&|| {
                let st = RigidAdaptive::new(&scenario.system, method, AngularSpeed).map_err(|e| e.to_string())?;
                let mut run = AdaptiveRun::new(st, scenario.initial, t_end, eps).map_err(|e| e.to_string())?;
                let s = run.run_to_end().map_err(|e| e.to_string())?;
                Ok((*run.state(), s.steps))
            })
        });
        let ((end, _), seconds) = match run {
            Ok(r) => r,
            Err(e) => {
                if points.is_empty() && eps > 1e-6 {
                    eps *= 0.5;
                    continue;
                }
                note = Some(e);
                break;
            }
        };
        // The diagnostics along the run and the torque count (not timed).
        let e0 = liemid::Diagnostics::of(&scenario.system, &scenario.initial).energy;
        let span = t_end - scenario.initial.t;
        let (mut max, mut first, mut last) = (0.0f64, 0.0f64, 0.0f64);
        if let Ok(st) = RigidAdaptive::new(&counting, method, AngularSpeed) {
            if let Ok(mut run) = AdaptiveRun::new(st, scenario.initial, t_end, eps) {
                while !run.is_done() && run.step().is_ok() {
                    let s = run.state();
                    let d = liemid::Diagnostics::of(&scenario.system, s);
                    let e = if e0 != 0.0 {
                        ((d.energy - e0) / e0).abs()
                    } else {
                        (d.energy - e0).abs()
                    };
                    max = max.max(e);
                    if s.t <= scenario.initial.t + 0.1 * span {
                        first = first.max(e);
                    }
                    if s.t >= t_end - 0.1 * span {
                        last = last.max(e);
                    }
                }
            }
        }
        let (dp, dr) = errors(&end, reference);
        points.push(Point {
            step: None,
            tolerance: None,
            eps: Some(eps),
            attitude_error: dr,
            momentum_error: dp,
            seconds,
            torque_evaluations: counting.count(),
            max_energy_error: max,
            energy_error_first_tenth: first,
            energy_error_last_tenth: last,
        });
        if dr < options.min_error || seconds > options.budget {
            break;
        }
        eps *= 0.5;
    }
    Curve {
        name: format!("{}-adaptive", method.key()),
        label: format!("{} adaptive", method.name()),
        points,
        note,
    }
}

/// The CPU time at which a curve reaches `target`, interpolating `log t` against
/// `log error` between the runs that bracket it; `None` if it never does.
pub fn time_to_reach(curve: &Curve, target: f64) -> Option<f64> {
    let pts = &curve.points;
    if let Some(p) = pts.first() {
        if p.attitude_error <= target {
            return Some(p.seconds);
        }
    }
    for w in pts.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if a.attitude_error > target && b.attitude_error <= target {
            let (la, lb, lt) = (a.attitude_error.ln(), b.attitude_error.ln(), target.ln());
            let f = (lt - la) / (lb - la);
            return Some((a.seconds.ln() + f * (b.seconds.ln() - a.seconds.ln())).exp());
        }
    }
    None
}

/// The reference at `t_end`: RK4 at a tiny step for short runs, DOP853 at rtol 1e-14 for
/// long ones (with an error estimate from the run at 1e-13); ended early once `progress`
/// is [`Progress::stopped`].
fn reference(scenario: &Scenario, t_end: f64, progress: &dyn Progress) -> Result<(RigidState, Reference), String> {
    if t_end - scenario.initial.t <= 2.0 {
        return crate::rigid::converge::reference_until(scenario, t_end, 6.25e-5, progress).map_err(|e| e.to_string());
    }
    let stop = || progress.stopped();
    let fine = baseline::dop853_until(&scenario.system, scenario.initial, t_end, 1e-14, &stop)?;
    let coarse = baseline::dop853_until(&scenario.system, scenario.initial, t_end, 1e-13, &stop)?;
    let (dp, dr) = errors(&coarse.state, &fine.state);
    Ok((
        fine.state,
        Reference {
            pi: fine.state.pi.to_array(),
            rotation: fine.state.rotation.to_row_major(),
            method: "DOP853 at rtol 1e-14 (error estimated against rtol 1e-13)".into(),
            step: 0.0,
            estimated_error: dp.max(dr),
        },
    ))
}

/// Run the study, each method reported to `progress` as it ends (and the runs left
/// skipped once it is [`Progress::stopped`]).
pub fn study(scenario: &Scenario, t_end: f64, options: &Options, progress: &dyn Progress) -> Result<Study, String> {
    let (ref_state, reference) = reference(scenario, t_end, progress)?;
    let mut methods = Vec::new();
    progress.start(options.entries.len() as u64, "methods");
    for entry in &options.entries {
        if progress.stopped() {
            break;
        }
        let curve = match entry {
            Entry::Fixed(m) => curve_fixed(scenario, *m, t_end, &ref_state, options, progress),
            Entry::Dop853 => curve_dop853(scenario, t_end, &ref_state, options, progress),
            Entry::Adaptive(m) => curve_adaptive(scenario, *m, t_end, &ref_state, options, progress),
        };
        methods.push(curve);
        progress.advance();
    }
    progress.finish();
    let targets = [1e-3, 1e-6, 1e-9]
        .iter()
        .map(|&target| {
            let fastest = methods
                .iter()
                .filter(|c| c.name.starts_with("liemid"))
                .filter_map(|c| time_to_reach(c, target).map(|t| (c.name.clone(), t)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let find = |name: &str| {
                methods
                    .iter()
                    .find(|c| c.name == name)
                    .and_then(|c| time_to_reach(c, target))
            };
            Target {
                attitude_error: target,
                fastest_liemid: fastest,
                dop853_seconds: find("dop853"),
                rk4_seconds: find("rk4"),
            }
        })
        .collect();
    Ok(Study {
        problem: scenario.name.clone(),
        t_end,
        repetitions: options.repetitions,
        reference,
        methods,
        targets,
    })
}

/// The study as a text table.
pub fn table(study: &Study) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} to t = {}; reference: {} (estimated error {:.1e}); times are medians of {} runs",
        study.problem, study.t_end, study.reference.method, study.reference.estimated_error, study.repetitions
    );
    let _ = writeln!(
        s,
        "{:<13} {:>10} {:>11} {:>11} {:>10} {:>12} {:>11} {:>11}",
        "method", "step/tol", "attitude", "momentum", "seconds", "torque evals", "max dE/E", "last/first"
    );
    for c in &study.methods {
        for p in &c.points {
            let knob = p.step.or(p.tolerance).unwrap_or(f64::NAN);
            let drift = if p.energy_error_first_tenth > 0.0 {
                p.energy_error_last_tenth / p.energy_error_first_tenth
            } else {
                f64::NAN
            };
            let _ = writeln!(
                s,
                "{:<13} {knob:>10.3e} {:>11.3e} {:>11.3e} {:>10.3e} {:>12} {:>11.3e} {drift:>11.2}",
                c.label, p.attitude_error, p.momentum_error, p.seconds, p.torque_evaluations, p.max_energy_error
            );
        }
        if let Some(n) = &c.note {
            let _ = writeln!(s, "{:<13} stopped: {n}", c.label);
        }
    }
    let _ = writeln!(s, "CPU time to reach an attitude error:");
    for t in &study.targets {
        let f = |x: Option<f64>| x.map_or_else(|| "not reached".to_string(), |x| format!("{x:.3e} s"));
        let best = t
            .fastest_liemid
            .as_ref()
            .map_or_else(|| "not reached".to_string(), |(n, x)| format!("{x:.3e} s ({n})"));
        let _ = writeln!(
            s,
            "  {:.0e}: fastest liemid {best}; DOP853 {}; RK4 {}",
            t.attitude_error,
            f(t.dop853_seconds),
            f(t.rk4_seconds)
        );
    }
    s
}

impl Study {
    /// The figure: attitude error at `t_end` and the largest energy error against CPU time.
    pub fn figure(&self) -> Figure<'static> {
        let curves = || self.methods.iter().map(|c| (c.label.as_str(), c.points.as_slice()));
        let axes = |title, y_desc| Axes {
            title,
            x_desc: "CPU time (s), median of repeated runs",
            y_desc,
            slopes: false,
        };
        Figure {
            title: format!("{}: work-precision to t = {} s", self.problem, self.t_end),
            labels: self.methods.iter().map(|m| m.label.clone()).collect(),
            panels: [
                (
                    axes("attitude error at t_end", "||R - R_ref||_F"),
                    work_series(curves(), |p| p.seconds, |p| p.attitude_error),
                ),
                (
                    axes("largest energy error along the run", "max |E - E0| / |E0|"),
                    work_series(curves(), |p| p.seconds, |p| p.max_energy_error),
                ),
            ],
        }
    }
}
