//! The `eccentric-satellite` problem (orbit and attitude together, `liemid::rigid::satellite`):
//! its own path through `liemid run` (keyed on the problem name: the state is not a
//! `RigidState`, so it does not go through `liemid::Run` and the scenario machinery), the
//! DOP853 baseline on the full orbit + attitude ODE, the work-precision study of
//! `liemid work-precision --problem eccentric-satellite --adaptive`, and the long-run
//! drift figure (`--drift-orbits N`).

use std::path::Path;
use std::time::Instant;

use crate::shared::dop853::dop853;
use liemid::rigid::adaptive::{AdaptiveRun, AdaptiveStats};
use liemid::rigid::satellite::{
    eccentric_satellite, Satellite, SatelliteAdaptive, SatelliteDensity, SatelliteIntegrator, SatelliteProblem,
    SatelliteState,
};
use liemid::so3::Quaternion;
use liemid::{RotationMethod, Vec3};
use ode_solvers::{SVector, System};
use serde::Serialize;
use serde_json::json;

use crate::rigid::command::args::{parse_method, WorkPrecisionArgs};
use crate::shared::command::{check_positive, check_study_outputs, emit_json, write_json, CmdResult, Failure};
use crate::shared::cpu_time::thread_seconds;
use crate::shared::output::OutputPlan;
use crate::shared::plot;

/// The problem's name.
pub const PROBLEM: &str = "eccentric-satellite";

/// One line on the problem.
pub const DESCRIPTION: &str =
    "rigid satellite diag(100,200,300) kg m^2 on a Molniya orbit (e = 0.74), orbit + attitude, one orbit (11.97 h)";

/// The default fixed step of `liemid run --problem eccentric-satellite` (s).
pub const DEFAULT_STEP: f64 = 10.0;

/// What `liemid run --problem eccentric-satellite` was asked for.
pub struct RunRequest<'a> {
    /// `--method` [default: liemid-ea].
    pub method: Option<&'a str>,
    /// `--adaptive EPS`.
    pub adaptive: Option<f64>,
    /// `--rho NAME`.
    pub rho: Option<&'a str>,
    /// `--step`.
    pub step: Option<f64>,
    /// `--orbits`.
    pub orbits: f64,
    /// `--json FILE|-`.
    pub json: Option<&'a str>,
    /// `--max-steps`: the step bound, checked before the first step.
    pub max_steps: Option<u64>,
}

/// The density named by `--rho` for the satellite (default `orbit`).
pub fn density(rho: Option<&str>) -> Result<SatelliteDensity, Failure> {
    let name = rho.unwrap_or("orbit");
    SatelliteDensity::from_key(name).ok_or_else(|| {
        let known: Vec<&str> = SatelliteDensity::ALL.iter().map(|d| d.key()).collect();
        Failure::Input(format!(
            "--rho {name}: unknown step density for {PROBLEM} (known: {})",
            known.join(", ")
        ))
    })
}

/// Errors of the invariants along a run: relative energy and total angular momentum.
#[derive(Clone, Copy, Debug, Default)]
struct Tracker {
    e0: f64,
    l0: Vec3,
    max_energy: f64,
    max_momentum: f64,
}

impl Tracker {
    fn new(sat: &Satellite, s: &SatelliteState) -> Self {
        Tracker {
            e0: sat.energy(s),
            l0: sat.angular_momentum(s),
            ..Tracker::default()
        }
    }
    fn errors(&self, sat: &Satellite, s: &SatelliteState) -> (f64, f64) {
        (
            ((sat.energy(s) - self.e0) / self.e0).abs(),
            (sat.angular_momentum(s) - self.l0).norm() / self.l0.norm(),
        )
    }
    fn see(&mut self, sat: &Satellite, s: &SatelliteState) {
        let (e, l) = self.errors(sat, s);
        self.max_energy = self.max_energy.max(e);
        self.max_momentum = self.max_momentum.max(l);
    }
}

/// `liemid run --problem eccentric-satellite`: a fixed or an adaptive run, and its summary.
pub fn run(req: &RunRequest) -> CmdResult {
    let method = req
        .method
        .map_or(Ok(RotationMethod::LieMidpointAlternating), parse_method)?;
    if let Some(eps) = req.adaptive {
        check_positive("adaptive", eps)?;
    }
    if let Some(path) = req.json.filter(|p| *p != "-") {
        OutputPlan::new(&[])
            .add("--json", Path::new(path))
            .map_err(Failure::Input)?;
    }
    let p = eccentric_satellite();
    let sat = &p.satellite;
    if !(req.orbits.is_finite() && req.orbits > 0.0) {
        return Err(Failure::Input(format!(
            "--orbits must be a positive number, found {}",
            liemid::error::Num(req.orbits)
        )));
    }
    let t_end = req.orbits * p.period;
    let mut tracker = Tracker::new(sat, &p.initial);
    let started = Instant::now();
    let (state, steps, step_info, adaptive) = match req.adaptive {
        Some(eps) => {
            let d = density(req.rho)?;
            let stepper = SatelliteAdaptive::new(sat, method, d).map_err(|e| Failure::Input(e.to_string()))?;
            let mut run = AdaptiveRun::new(stepper, p.initial, t_end, eps)
                .map_err(|e| Failure::Input(format!("{PROBLEM}: {e}")))?;
            let bound = crate::shared::command::check_adaptive_steps(run.span(), run.control(), eps, req.max_steps)?;
            while !run.is_done() {
                if run.stats().steps >= bound {
                    return Err(Failure::Run(format!(
                        "{PROBLEM}: the adaptive run reached {bound} steps (--max-steps) before the end"
                    )));
                }
                run.step().map_err(|e| Failure::Run(format!("{PROBLEM}: {e}")))?;
                tracker.see(sat, run.state());
            }
            let s = run.stats();
            (*run.state(), s.steps, None, Some((s, d)))
        }
        None => {
            let h = req.step.unwrap_or(DEFAULT_STEP);
            let steps = liemid::step_count(0.0, t_end, h).map_err(|e| Failure::Input(format!("--step: {e}")))?;
            crate::shared::command::check_steps(steps, req.max_steps)?;
            let mut integrator = SatelliteIntegrator::new(method, sat).map_err(|e| Failure::Input(e.to_string()))?;
            let mut s = p.initial;
            for k in 1..=steps {
                let target = if k == steps { t_end } else { k as f64 * h };
                let dt = target - s.t;
                integrator
                    .step(sat, &mut s, dt)
                    .map_err(|e| Failure::Run(format!("{PROBLEM}: {e}")))?;
                s.t = target;
                tracker.see(sat, &s);
            }
            (s, steps, Some(h), None)
        }
    };
    let wall = started.elapsed().as_secs_f64();
    let e1 = sat.energy(&state);
    if let Some(target) = req.json {
        let out = json!({
            "problem": PROBLEM,
            "method": method.key(),
            "step": step_info,
            "steps": steps,
            "adaptive": adaptive.map(|(s, d)| json!({
                "eps": s.eps, "rho": d.key(), "min_step": s.min_step, "max_step": s.max_step,
                "last_step": s.last_step,
            })),
            "t": state.t,
            "orbits": req.orbits,
            "pi": state.pi.to_array(),
            "rotation": state.rotation.to_row_major(),
            "position": state.position.to_array(),
            "velocity": state.velocity.to_array(),
            "energy": [tracker.e0, e1],
            "max_energy_error": tracker.max_energy,
            "max_angular_momentum_error": tracker.max_momentum,
            "wall_time_seconds": wall,
        });
        emit_json(Some(target), &out)?;
        if target == "-" {
            return Ok(());
        }
    }
    let how = match (adaptive, step_info) {
        (Some((s, d)), _) => format!(
            "adaptive eps = {} (rho = {}), steps from {:.4e} to {:.4e} s, the last {:.4e} s",
            s.eps,
            d.key(),
            s.min_step,
            s.max_step,
            s.last_step
        ),
        (None, Some(h)) => format!("h = {h} s"),
        _ => String::new(),
    };
    crate::outln!(
        "{PROBLEM}: {} with {how} to t = {:.6e} s ({} orbits)",
        method.name(),
        state.t,
        req.orbits
    );
    crate::outln!("steps                          {steps}");
    let r = state.rotation.m;
    for (i, row) in r.iter().enumerate() {
        let label = if i == 0 { "final rotation" } else { "" };
        crate::outln!(
            "{label:<30} [{:>19.12e}, {:>19.12e}, {:>19.12e}]",
            row[0],
            row[1],
            row[2]
        );
    }
    let (x, v) = (state.position, state.velocity);
    crate::outln!(
        "final Pi (kg m^2/s)            [{:.12e}, {:.12e}, {:.12e}]",
        state.pi.x,
        state.pi.y,
        state.pi.z
    );
    crate::outln!(
        "final position (m)             [{:.12e}, {:.12e}, {:.12e}]",
        x.x,
        x.y,
        x.z
    );
    crate::outln!(
        "final velocity (m/s)           [{:.12e}, {:.12e}, {:.12e}]",
        v.x,
        v.y,
        v.z
    );
    crate::outln!("max relative energy error      {:.3e}", tracker.max_energy);
    crate::outln!(
        "max rel. angular momentum error {:.3e} (m r x v + R Pi)",
        tracker.max_momentum
    );
    crate::outln!("wall time                      {wall:.3} s");
    Ok(())
}

type State13 = SVector<f64, 13>;

/// The full orbit + attitude ODE on `(r, v, Π, q)` for DOP853; the quaternion is
/// normalised where the attitude is used and renormalised only at output.
struct FullOde<'a> {
    sat: &'a Satellite,
}

fn unpack(t: f64, y: &State13) -> SatelliteState {
    let q = Quaternion::new(y[9], y[10], y[11], y[12]).normalized();
    SatelliteState {
        t,
        position: Vec3::new(y[0], y[1], y[2]),
        velocity: Vec3::new(y[3], y[4], y[5]),
        pi: Vec3::new(y[6], y[7], y[8]),
        rotation: q.to_matrix(),
    }
}

impl System<f64, State13> for FullOde<'_> {
    fn system(&self, _t: f64, y: &State13, dy: &mut State13) {
        let q = Quaternion::new(y[9], y[10], y[11], y[12]);
        let (r, v, pi) = (
            Vec3::new(y[0], y[1], y[2]),
            Vec3::new(y[3], y[4], y[5]),
            Vec3::new(y[6], y[7], y[8]),
        );
        let (f, t) = self.sat.force_and_torque(r, &q.normalized().to_matrix());
        let w = self.sat.inertia.apply_inverse(pi);
        let a = f * (1.0 / self.sat.mass);
        let dpi = pi.cross(w) + t;
        let dq = q.mul(&Quaternion::new(0.0, 0.5 * w.x, 0.5 * w.y, 0.5 * w.z));
        *dy = State13::from([
            v.x, v.y, v.z, a.x, a.y, a.z, dpi.x, dpi.y, dpi.z, dq.w, dq.x, dq.y, dq.z,
        ]);
    }
}

/// DOP853 at relative tolerance `rtol` (absolute `rtol/1000`) from the problem's start to
/// `t_end`; every accepted step is kept when `keep` (for the drift figure).
fn dop853(
    p: &SatelliteProblem,
    t_end: f64,
    rtol: f64,
    keep: bool,
) -> Result<(Vec<(f64, SatelliteState)>, u64), String> {
    let s = p.initial;
    let q = Quaternion::from_matrix(&s.rotation);
    let y0 = State13::from([
        s.position.x,
        s.position.y,
        s.position.z,
        s.velocity.x,
        s.velocity.y,
        s.velocity.z,
        s.pi.x,
        s.pi.y,
        s.pi.z,
        q.w,
        q.x,
        q.y,
        q.z,
    ]);
    let mut solver = dop853!(FullOde { sat: &p.satellite }, 0.0, t_end, t_end, y0, rtol,);
    let stats = solver
        .integrate()
        .map_err(|e| format!("Dop853 at rtol {rtol:e}: {e}"))?;
    let out: Vec<(f64, SatelliteState)> = if keep {
        solver
            .x_out()
            .iter()
            .zip(solver.y_out())
            .map(|(t, y)| (*t, unpack(*t, y)))
            .collect()
    } else {
        let y = solver.y_out().last().ok_or("Dop853 produced no output")?;
        vec![(t_end, unpack(t_end, y))]
    };
    Ok((out, u64::from(stats.num_eval)))
}

/// `(attitude error, fastest adaptive method, its seconds, DOP853 seconds)`.
pub type TargetRow = (f64, Option<String>, Option<f64>, Option<f64>);

/// A DOP853 run of the drift study: `(rtol, seconds, errors per orbit, evaluations)`.
type DopRun = (f64, f64, Vec<(f64, f64)>, u64);

/// One point of the satellite study.
#[derive(Clone, Debug, Serialize)]
pub struct SatPoint {
    /// Fixed step count, adaptive eps, or DOP853 rtol.
    pub parameter: f64,
    /// Steps (DOP853: right-hand-side evaluations).
    pub steps: u64,
    /// `‖R − R_ref‖_F` after one orbit.
    pub attitude_error: f64,
    /// Median CPU time of the thread over the repetitions (s).
    pub seconds: f64,
}

/// One curve of the satellite study.
#[derive(Clone, Debug, Serialize)]
pub struct SatCurve {
    /// e.g. `liemid-ea4 adaptive`.
    pub name: String,
    /// The runs.
    pub points: Vec<SatPoint>,
    /// Force-and-torque evaluations per step (the stages; DOP853's `steps` are evaluations).
    pub evaluations_per_step: u64,
    /// Median over the runs of the CPU time per evaluation (ns).
    pub ns_per_evaluation: f64,
}

impl SatCurve {
    fn new(name: String, points: Vec<SatPoint>, evaluations_per_step: u64) -> Self {
        let mut per: Vec<f64> = points
            .iter()
            .map(|q| q.seconds * 1e9 / (q.steps * evaluations_per_step).max(1) as f64)
            .collect();
        per.sort_by(f64::total_cmp);
        SatCurve {
            name,
            ns_per_evaluation: per.get(per.len() / 2).copied().unwrap_or(f64::NAN),
            points,
            evaluations_per_step,
        }
    }
}

/// The satellite study as written by `--json`.
#[derive(Clone, Debug, Serialize)]
pub struct SatStudy {
    /// Problem.
    pub problem: &'static str,
    /// End time (one orbit).
    pub t_end: f64,
    /// `‖R_DOP853(1e-13) − R_EX8(h = T/20000)‖_F`: the reference's own check.
    pub reference_check: f64,
    /// The curves.
    pub curves: Vec<SatCurve>,
    /// At attitude errors 1e-3, 1e-6, 1e-9: `(target, fastest adaptive, its seconds,
    /// DOP853 seconds)`, log-log interpolated.
    pub targets: Vec<TargetRow>,
    /// For EA and EX: fixed steps / adaptive steps at equal attitude error 1e-3.
    pub step_ratios: Vec<(String, Option<f64>)>,
}

/// The median CPU time of the thread over `reps` runs of `f` (after one untimed run).
fn median_time(reps: usize, mut f: impl FnMut() -> Result<(), String>) -> Result<f64, String> {
    f()?;
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        let start = thread_seconds();
        f()?;
        times.push(thread_seconds() - start);
    }
    times.sort_by(f64::total_cmp);
    Ok(times[times.len() / 2])
}

fn at_error(points: &[SatPoint], target: f64, x: impl Fn(&SatPoint) -> f64) -> Option<f64> {
    points.windows(2).find_map(|w| {
        let (a, b) = (&w[0], &w[1]);
        let (ea, eb) = (a.attitude_error, b.attitude_error);
        ((ea - target) * (eb - target) <= 0.0 && ea != eb).then(|| {
            let s = (target.ln() - ea.ln()) / (eb.ln() - ea.ln());
            (x(a).ln() + s * (x(b).ln() - x(a).ln())).exp()
        })
    })
}

fn adaptive_run(
    p: &SatelliteProblem,
    m: RotationMethod,
    eps: f64,
    t_end: f64,
) -> Result<(SatelliteState, AdaptiveStats), String> {
    let st = SatelliteAdaptive::new(&p.satellite, m, SatelliteDensity::Orbit).map_err(|e| e.to_string())?;
    let mut run = AdaptiveRun::new(st, p.initial, t_end, eps).map_err(|e| e.to_string())?;
    let s = run.run_to_end().map_err(|e| e.to_string())?;
    Ok((*run.state(), s))
}

/// The one-orbit work-precision study of the satellite: fixed and adaptive EA/EX, the
/// adaptive compositions and DOP853, against DOP853 at rtol 1e-13 (cross-checked with EX8).
pub fn study(repetitions: usize) -> Result<SatStudy, String> {
    use RotationMethod as M;
    let p = eccentric_satellite();
    let t = p.period;
    let (reference, _) = dop853(&p, t, 1e-13, false)?;
    let reference = reference[0].1;
    let mut ex8 = SatelliteIntegrator::new(M::LieMidpointExact8, &p.satellite).map_err(|e| e.to_string())?;
    let mut check = p.initial;
    ex8.advance(&p.satellite, &mut check, t, 20_000)
        .map_err(|e| e.to_string())?;
    let err = |s: &SatelliteState| (s.rotation - reference.rotation).norm_frobenius();
    let mut curves = Vec::new();
    for m in [M::LieMidpointAlternating, M::LieMidpointExact] {
        let mut points = Vec::new();
        for n in [1000u64, 2000, 4000, 8000, 16_000, 32_000] {
            let mut integrator = SatelliteIntegrator::new(m, &p.satellite).map_err(|e| e.to_string())?;
            let mut s = p.initial;
            let seconds = median_time(repetitions, || {
                s = p.initial;
                integrator
                    .advance(&p.satellite, &mut s, t, n)
                    .map_err(|e| e.to_string())
            })?;
            points.push(SatPoint {
                parameter: n as f64,
                steps: n,
                attitude_error: err(&s),
                seconds,
            });
        }
        curves.push(SatCurve::new(format!("{} fixed", m.key()), points, 1));
    }
    let families: [(M, &[f64]); 8] = [
        (M::LieMidpointAlternating, &[0.04, 0.02, 0.01, 0.005, 0.0025, 0.00125]),
        (M::LieMidpointExact, &[0.04, 0.02, 0.01, 0.005, 0.0025, 0.00125]),
        (
            M::LieMidpointAlternating4,
            &[0.1, 0.07, 0.05, 0.035, 0.025, 0.0125, 0.00625, 0.003],
        ),
        (
            M::LieMidpointExact4,
            &[0.1, 0.07, 0.05, 0.035, 0.025, 0.0125, 0.00625, 0.003],
        ),
        (
            M::LieMidpointAlternating6,
            &[0.14, 0.1, 0.07, 0.05, 0.035, 0.025, 0.0175, 0.0125],
        ),
        (
            M::LieMidpointExact6,
            &[0.14, 0.1, 0.07, 0.05, 0.035, 0.025, 0.0175, 0.0125],
        ),
        (M::LieMidpointAlternating8, &[0.14, 0.1, 0.085, 0.07, 0.06, 0.05, 0.04]),
        (M::LieMidpointExact8, &[0.14, 0.1, 0.085, 0.07, 0.06, 0.05, 0.04]),
    ];
    for (m, epss) in families {
        let mut points = Vec::new();
        for &eps in epss {
            let mut out = None;
            let seconds = median_time(repetitions, || {
                out = Some(adaptive_run(&p, m, eps, t)?);
                Ok(())
            })?;
            let (s, stats) = out.ok_or("no run")?;
            points.push(SatPoint {
                parameter: eps,
                steps: stats.steps,
                attitude_error: err(&s),
                seconds,
            });
        }
        let stages = SatelliteIntegrator::new(m, &p.satellite)
            .map_err(|e| e.to_string())?
            .stages();
        curves.push(SatCurve::new(format!("{} adaptive", m.key()), points, stages));
    }
    let mut points = Vec::new();
    for k in 3..=12 {
        let rtol = 10f64.powi(-k);
        let mut out = None;
        let seconds = median_time(repetitions, || {
            out = Some(dop853(&p, t, rtol, false)?);
            Ok(())
        })?;
        let (s, evals) = out.ok_or("no run")?;
        points.push(SatPoint {
            parameter: rtol,
            steps: evals,
            attitude_error: err(&s[0].1),
            seconds,
        });
    }
    curves.push(SatCurve::new("dop853".into(), points, 1));
    let dop = curves.last().map(|c| c.points.clone()).unwrap_or_default();
    let targets = [1e-3, 1e-6, 1e-9]
        .iter()
        .map(|&target| {
            let best = curves
                .iter()
                .filter(|c| c.name.ends_with("adaptive"))
                .filter_map(|c| at_error(&c.points, target, |q| q.seconds).map(|s| (c.name.clone(), s)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let d = at_error(&dop, target, |q| q.seconds);
            (target, best.as_ref().map(|b| b.0.clone()), best.map(|b| b.1), d)
        })
        .collect();
    let step_ratios = ["liemid-ea", "liemid-ex"]
        .iter()
        .map(|k| {
            let find = |n: String| curves.iter().find(|c| c.name == n).map(|c| c.points.clone());
            let ratio = match (find(format!("{k} fixed")), find(format!("{k} adaptive"))) {
                (Some(f), Some(a)) => at_error(&f, 1e-3, |q| q.steps as f64)
                    .zip(at_error(&a, 1e-3, |q| q.steps as f64))
                    .map(|(x, y)| x / y),
                _ => None,
            };
            ((*k).to_string(), ratio)
        })
        .collect();
    Ok(SatStudy {
        problem: PROBLEM,
        t_end: t,
        reference_check: (check.rotation - reference.rotation).norm_frobenius(),
        curves,
        targets,
        step_ratios,
    })
}

/// The study's table.
pub fn table(s: &SatStudy) -> String {
    let mut out = format!(
        "{PROBLEM}: one orbit ({:.1} s); reference DOP853 rtol 1e-13 (EX8 at T/20000 agrees to {:.2e})\n",
        s.t_end, s.reference_check
    );
    out.push_str(&format!(
        "{:<22} {:>10} {:>9} {:>12} {:>11}\n",
        "method", "parameter", "steps", "att. error", "seconds"
    ));
    for c in &s.curves {
        for q in &c.points {
            out.push_str(&format!(
                "{:<22} {:>10.3e} {:>9} {:>12.3e} {:>11.3e}\n",
                c.name, q.parameter, q.steps, q.attitude_error, q.seconds
            ));
        }
    }
    for (k, r) in &s.step_ratios {
        out.push_str(&format!(
            "{k}: fixed / adaptive steps at attitude error 1e-3: {}\n",
            r.map_or("-".into(), |r| format!("{r:.2}"))
        ));
    }
    for (target, name, secs, dop) in &s.targets {
        let f = |x: &Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.3e} s"));
        let ratio = match (secs, dop) {
            (Some(a), Some(d)) => format!(" (DOP853 / adaptive = {:.2})", d / a),
            _ => String::new(),
        };
        let evaluations = |n: Option<&str>| {
            s.curves
                .iter()
                .find(|c| Some(c.name.as_str()) == n)
                .and_then(|c| at_error(&c.points, *target, |q| (q.steps * c.evaluations_per_step) as f64))
                .map_or("-".to_string(), |e| format!("{e:.0}"))
        };
        out.push_str(&format!(
            "attitude error {target:.0e}: fastest adaptive {} {} ({} evaluations); DOP853 {} ({} evaluations){ratio}\n",
            name.as_deref().unwrap_or("-"),
            f(secs),
            evaluations(name.as_deref()),
            f(dop),
            evaluations(Some("dop853")),
        ));
    }
    out.push_str("CPU time per force-and-torque evaluation (median over the runs):");
    for c in &s.curves {
        out.push_str(&format!(" {} {:.0} ns;", c.name, c.ns_per_evaluation));
    }
    out.pop();
    out.push('\n');
    out
}

/// The long run: `orbits` orbits with the adaptive `method` at `eps`, and DOP853 at the
/// tolerance whose CPU time is closest to it; the largest relative energy and angular
/// momentum errors per orbit of both, side by side in `plot`; a JSON summary to `json`.
pub fn drift(orbits: u32, method: RotationMethod, eps: f64, plot_path: &Path, json_target: Option<&str>) -> CmdResult {
    let p = eccentric_satellite();
    let sat = &p.satellite;
    let t_end = f64::from(orbits) * p.period;
    let tracker = Tracker::new(sat, &p.initial);
    let per_orbit = |samples: &mut dyn Iterator<Item = (f64, (f64, f64))>| {
        let mut out = vec![(0.0f64, 0.0f64); orbits as usize];
        for (t, (e, l)) in samples {
            let k = ((t / p.period) as usize).min(orbits as usize - 1);
            out[k] = (out[k].0.max(e), out[k].1.max(l));
        }
        out
    };
    let started = thread_seconds();
    let stepper =
        SatelliteAdaptive::new(sat, method, SatelliteDensity::Orbit).map_err(|e| Failure::Input(e.to_string()))?;
    let mut run = AdaptiveRun::new(stepper, p.initial, t_end, eps).map_err(|e| Failure::Input(e.to_string()))?;
    let mut ours = vec![(0.0f64, 0.0f64); orbits as usize];
    while !run.is_done() {
        run.step().map_err(|e| Failure::Run(e.to_string()))?;
        let s = run.state();
        let k = ((s.t / p.period) as usize).min(orbits as usize - 1);
        let (e, l) = tracker.errors(sat, s);
        ours[k] = (ours[k].0.max(e), ours[k].1.max(l));
    }
    let our_seconds = thread_seconds() - started;
    let our_steps = run.stats().steps;
    // DOP853: the tolerance whose run takes the closest CPU time (tried from loose to tight).
    let mut best: Option<DopRun> = None;
    for k in 5..=12 {
        let rtol = 10f64.powi(-k);
        let start = thread_seconds();
        let (out, evals) = dop853(&p, t_end, rtol, true).map_err(Failure::Run)?;
        let secs = thread_seconds() - start;
        let closer = best
            .as_ref()
            .is_none_or(|b| (secs / our_seconds).ln().abs() < (b.1 / our_seconds).ln().abs());
        if closer {
            let errs = per_orbit(&mut out.iter().map(|(t, s)| (*t, tracker.errors(sat, s))));
            best = Some((rtol, secs, errs, evals));
        }
        if secs > 3.0 * our_seconds {
            break;
        }
    }
    let (rtol, dop_seconds, theirs, evals) = best.ok_or_else(|| Failure::Run("DOP853 made no run".into()))?;
    let tenth = |v: &[(f64, f64)], last: bool| {
        let n = (v.len() / 10).max(1);
        let part = if last { &v[v.len() - n..] } else { &v[..n] };
        part.iter().fold((0.0f64, 0.0f64), |a, x| (a.0.max(x.0), a.1.max(x.1)))
    };
    let (of, ol) = (tenth(&ours, false), tenth(&ours, true));
    let (df, dl) = (tenth(&theirs, false), tenth(&theirs, true));
    let summary = json!({
        "problem": PROBLEM, "orbits": orbits,
        "adaptive": {"method": method.key(), "eps": eps, "rho": "orbit", "steps": our_steps, "seconds": our_seconds,
            "energy_first_tenth": of.0, "energy_last_tenth": ol.0, "momentum_first_tenth": of.1, "momentum_last_tenth": ol.1},
        "dop853": {"rtol": rtol, "evaluations": evals, "seconds": dop_seconds,
            "energy_first_tenth": df.0, "energy_last_tenth": dl.0, "momentum_first_tenth": df.1, "momentum_last_tenth": dl.1},
    });
    crate::outln!(
        "{orbits} orbits: adaptive {} eps {eps} ({our_steps} steps, {our_seconds:.2} s): energy error first/last tenth {:.3e} / {:.3e} (ratio {:.3}), angular momentum {:.3e} / {:.3e}",
        method.key(), of.0, ol.0, ol.0 / of.0, of.1, ol.1
    );
    crate::outln!(
        "{orbits} orbits: DOP853 rtol {rtol:e} ({evals} evaluations, {dop_seconds:.2} s): energy error first/last tenth {:.3e} / {:.3e} (ratio {:.3}), angular momentum {:.3e} / {:.3e} (ratio {:.3})",
        df.0, dl.0, dl.0 / df.0, df.1, dl.1, dl.1 / df.1
    );
    let lg = |x: f64| x.max(1e-17).log10();
    let line = |v: &[(f64, f64)], which: usize| -> Vec<(f64, f64)> {
        v.iter()
            .enumerate()
            .map(|(k, x)| ((k + 1) as f64, lg(if which == 0 { x.0 } else { x.1 })))
            .collect()
    };
    let a_label = format!("{} adaptive, eps {eps} ({our_seconds:.2} s)", method.name());
    let d_label = format!("DOP853 rtol {rtol:e} ({dop_seconds:.2} s)");
    let energy = [(a_label.clone(), line(&ours, 0)), (d_label.clone(), line(&theirs, 0))];
    let momentum = [(a_label, line(&ours, 1)), (d_label, line(&theirs, 1))];
    let panels = [
        plot::Histories {
            title: "eccentric satellite: largest relative energy error per orbit",
            x_desc: "orbit",
            y_desc: "log10 |E - E0| / |E0|",
            lines: &energy,
            points: &[],
        },
        plot::Histories {
            title: "largest relative error of the total angular momentum m r x v + R Pi per orbit",
            x_desc: "orbit",
            y_desc: "log10 |L - L0| / |L0|",
            lines: &momentum,
            points: &[],
        },
    ];
    for path in plot::plot_paths(plot_path) {
        plot::stacked_histories(&path, &panels).map_err(Failure::Run)?;
        crate::outln!("wrote {}", path.display());
    }
    if let Some(target) = json_target {
        write_json(target, &summary)?;
    }
    Ok(())
}

/// `liemid work-precision --problem eccentric-satellite --adaptive [--drift-orbits N]`.
pub fn work_precision(args: &WorkPrecisionArgs) -> CmdResult {
    if !args.adaptive {
        return Err(Failure::Input(format!(
            "--problem {} has its own study: give --adaptive",
            PROBLEM
        )));
    }
    check_study_outputs(
        None,
        &args.plot,
        args.no_plot || args.drift_orbits.is_none(),
        args.json.as_deref(),
    )?;
    if let Some(orbits) = args.drift_orbits {
        let method = parse_method(&args.drift_method)?;
        method.check_reversible().map_err(|e| Failure::Input(e.to_string()))?;
        let eps = check_positive("drift-eps", args.drift_eps)?;
        if orbits == 0 {
            return Err(Failure::Input("--drift-orbits must be at least 1".into()));
        }
        return drift(orbits, method, eps, &args.plot, args.json.as_deref());
    }
    let study = study(args.repetitions as usize).map_err(Failure::Run)?;
    let table = table(&study);
    if args.json.as_deref() == Some("-") {
        eprint!("{table}");
    } else {
        crate::out!("{table}");
    }
    if let Some(target) = args.json.as_deref() {
        crate::shared::command::write_json(target, &study)?;
    }
    Ok(())
}
