//! Runs of a beam scenario (explicit splitting or implicit Newmark) sampled at a fixed
//! interval, and the work-precision study of the two on the right-angle cantilever.

use liemid::beam::{BeamDriver, BeamMethod, BeamSystem, Drift, StepPlan};
use serde_json::{json, Value};

use crate::beam::scenario::{BeamIntegrator, BeamScenario};
use std::time::Instant;

use crate::shared::cpu_time::thread_seconds;
use crate::shared::view::{self, Scene, ViewPage};

/// Why a run failed: bad input (a step above the critical one, a bad step) or a failure
/// of the integration itself.
#[derive(Clone, Debug, PartialEq)]
pub enum RunFailure {
    /// Exit 2.
    Input(String),
    /// Exit 1.
    Numerical(String),
}

/// A sampled run.
#[derive(Clone, Debug)]
pub struct BeamRun {
    /// Method.
    pub method: BeamIntegrator,
    /// The node rotations' drift (`None` for Newmark, which has none).
    pub drift: Option<Drift>,
    /// Sample times.
    pub t: Vec<f64>,
    /// Tracked nodes: name, displacement at every sample.
    pub tracked: Vec<(String, Vec<[f64; 3]>)>,
    /// Energy at every sample (explicit methods; Newmark's is not computed).
    pub energy: Vec<f64>,
    /// Steps taken.
    pub steps: u64,
    /// Step.
    pub step: f64,
    /// Wall time of the stepping (s).
    pub wall_seconds: f64,
    /// CPU time of the stepping on the calling thread (s): all of it on one thread, and
    /// not stretched by the load of other processes (what the work-precision study
    /// compares).
    pub cpu_seconds: f64,
    /// Elements.
    pub elements: usize,
    /// The bound of the largest eigenfrequency.
    pub omega_bound: f64,
    /// The explicit method's critical step (for Newmark: the splitting's, for comparison).
    pub critical_step: f64,
    /// The added stretch inertia `β` (liemid-sms).
    pub axial_mass: Option<f64>,
    /// Newton iterations per step of the stretch equations (liemid-sms).
    pub stretch_iterations: Option<f64>,
    /// Newton iterations (Newmark).
    pub newton_iterations: Option<u64>,
    /// Total linear and angular momentum at the start and the end (explicit).
    pub momenta: Option<[[f64; 3]; 4]>,
}

impl BeamRun {
    /// Element-steps per second (internal-force evaluations count once per stage).
    #[must_use]
    pub fn element_steps_per_second(&self) -> f64 {
        self.elements as f64 * self.steps as f64 / self.wall_seconds.max(1e-12)
    }

    /// The summary JSON of `liemid beam`.
    #[must_use]
    pub fn json(&self, scenario: &str) -> Value {
        let tracked: serde_json::Map<String, Value> = self
            .tracked
            .iter()
            .map(|(n, u)| (n.clone(), json!({"t": self.t, "u": u})))
            .collect();
        json!({
            "problem": scenario,
            "method": self.method.key(),
            "drift": self.drift.map(Drift::key),
            "tracked": tracked,
            "energy": if self.energy.is_empty() { Value::Null } else { json!(self.energy) },
            "steps": self.steps,
            "step": self.step,
            "critical_step": self.critical_step,
            "omega_max_bound": self.omega_bound,
            "elements": self.elements,
            "wall_seconds": self.wall_seconds,
            "cpu_seconds": self.cpu_seconds,
            "element_steps_per_second": self.element_steps_per_second(),
            "newton_iterations": self.newton_iterations,
            "axial_mass": self.axial_mass,
            "stretch_iterations_per_step": self.stretch_iterations,
            "momenta": self.momenta.map(|m| json!({"linear_start": m[0], "linear_end": m[1], "angular_start": m[2], "angular_end": m[3]})),
        })
    }
}

/// How a beam run steps: `step` (default: 0.9 of the critical step for the explicit
/// methods, 0.05 for Newmark), a sample every `sample` (rounded to whole steps), a step above
/// the critical one refused unless `force_step`, and at most `max_steps` steps
/// ([`DEFAULT_MAX_STEPS`](crate::shared::bounds::DEFAULT_MAX_STEPS) when `None`).
#[derive(Clone, Copy, Debug)]
pub struct Stepping {
    /// The step, or the default.
    pub step: Option<f64>,
    /// The interval of the samples.
    pub sample: f64,
    /// Run an explicit step above the critical one anyway.
    pub force_step: bool,
    /// The step bound.
    pub max_steps: Option<u64>,
}

impl Stepping {
    /// The step `h`, a sample every `sample`, the critical step and the step bound enforced.
    #[must_use]
    pub fn fixed(h: f64, sample: f64) -> Self {
        Stepping {
            step: Some(h),
            sample,
            force_step: false,
            max_steps: None,
        }
    }
}

/// Run `scenario` to `t_end` as `stepping` says. The step bound and the memory of the
/// samples are checked before the first step. `stop` is asked between samples, and within
/// a sample interval every [`STOP_WORK`] element steps;
/// `Some(reason)` ends the run with that message.
pub fn run(
    scenario: &BeamScenario,
    t_end: f64,
    stepping: Stepping,
    stop: &mut dyn FnMut(f64) -> Option<String>,
) -> Result<BeamRun, RunFailure> {
    run_viewed(scenario, t_end, stepping, stop, None).map(|(run, _)| run)
}

/// Element steps between two questions to `stop` within a sample interval (a few
/// milliseconds of stepping), so that a long interval can be stopped too.
pub const STOP_WORK: u64 = 1 << 16;

/// [`run`], and with `view = Some(title)` the 3-D page of the run: the deformed centre
/// line and the nodes' section frames at every sample, and the energy (explicit methods).
pub fn run_viewed(
    scenario: &BeamScenario,
    t_end: f64,
    stepping: Stepping,
    stop: &mut dyn FnMut(f64) -> Option<String>,
    view: Option<&str>,
) -> Result<(BeamRun, Option<ViewPage>), RunFailure> {
    run_checked(scenario, t_end, stepping, &mut |_| Ok(()), stop, view)
}

/// [`run_viewed`] with a pre-flight: `check` sees the plan (the step, the steps, the steps
/// between samples) before the first step, for a front end's step bound or the memory its
/// samples will take; its error is bad input ([`RunFailure::Input`]).
pub fn run_checked(
    scenario: &BeamScenario,
    t_end: f64,
    stepping: Stepping,
    check: &mut dyn FnMut(&StepPlan) -> Result<(), String>,
    stop: &mut dyn FnMut(f64) -> Option<String>,
    view: Option<&str>,
) -> Result<(BeamRun, Option<ViewPage>), RunFailure> {
    let input = RunFailure::Input;
    let explicit = scenario.method.explicit();
    if explicit.is_none() && scenario.drift != Drift::Midpoint {
        return Err(input(format!(
            "drift {}: the drift chooses the liemid methods' node rotation; newmark has none",
            scenario.drift.key()
        )));
    }
    let mut system: BeamSystem = scenario.problem.system().map_err(|e| input(e.to_string()))?;
    system.set_drift(scenario.drift);
    let mut driver = BeamDriver::new(system, scenario.method);
    let Stepping {
        step,
        sample,
        force_step,
        max_steps,
    } = stepping;
    let plan = driver.plan(t_end, step, sample, force_step).map_err(|e| match e {
        liemid::Error::UnstableStep { .. } => input(format!("{e} (or --force-step)")),
        e => input(e.to_string()),
    })?;
    check(&plan).map_err(input)?;
    let (h, every, steps) = (plan.step, plan.every, plan.steps);
    // Before the first step: the step bound, and the samples kept (t, the energy and three
    // displacements per tracked node) against the memory.
    crate::shared::bounds::check_steps(steps, max_steps, "--max-steps").map_err(input)?;
    let samples = (steps / every + 2) as f64;
    let tracked = scenario.problem.frame.names.len() as f64;
    crate::shared::memory::check_fits(
        &format!(
            "{samples:.3e} samples (sample every {} s)",
            liemid::error::Num(h * every as f64)
        ),
        samples * (16.0 + 24.0 * tracked),
    )
    .map_err(input)?;
    let system = driver.system();
    let names: Vec<(String, usize)> = scenario.problem.frame.names.clone();
    let mut out = BeamRun {
        method: scenario.method,
        drift: explicit.map(|_| scenario.drift),
        t: Vec::new(),
        tracked: names.iter().map(|(n, _)| (n.clone(), Vec::new())).collect(),
        energy: Vec::new(),
        steps,
        step: h,
        wall_seconds: 0.0,
        cpu_seconds: 0.0,
        elements: system.elements(),
        omega_bound: plan.omega_bound,
        axial_mass: (explicit == Some(BeamMethod::MassScaled)).then(|| system.axial_mass()),
        stretch_iterations: None,
        critical_step: plan.critical_step,
        newton_iterations: None,
        momenta: None,
    };
    let mut page = view.map(|title| {
        let scene = Scene::Beam {
            nodes: system.frame.nodes.len(),
            elements: system
                .frame
                .elements
                .iter()
                .map(|e| e.nodes.map(|i| i as u32))
                .collect(),
        };
        let mut page = ViewPage::new(scene, title);
        page.set_energy_label("total energy (it changes while the loads act)");
        page
    });
    let mut record = |out: &mut BeamRun, s: &BeamSystem, t: f64, energy: Option<f64>| {
        if let Some(p) = page.as_mut() {
            let frame: Vec<f32> = (0..s.frame.nodes.len())
                .flat_map(|i| {
                    let (x, q) = (s.position(i), view::quaternion(&s.rotation(i).m));
                    [x.x as f32, x.y as f32, x.z as f32, q[0], q[1], q[2], q[3]]
                })
                .collect();
            p.push_frame(t, &frame);
            if let Some(e) = energy {
                p.energy_error(t, e);
            }
        }
        out.t.push(t);
        for (k, (_, node)) in names.iter().enumerate() {
            out.tracked[k].1.push(s.displacement(*node).to_array());
        }
        if let Some(e) = energy {
            out.energy.push(e);
        }
    };
    let start_totals = driver.totals();
    record(&mut out, driver.system(), 0.0, start_totals.map(|t| t.energy));
    let mut done = 0u64;
    let (mut seconds, mut cpu_seconds) = (0.0, 0.0);
    let piece = (STOP_WORK / driver.system().elements().max(1) as u64).max(1);
    while done < steps {
        if let Some(reason) = stop(done as f64 * h) {
            return Err(RunFailure::Numerical(reason));
        }
        let k = every.min(steps - done);
        let mut left = k;
        while left > 0 {
            if left < k {
                if let Some(reason) = stop((done + k - left) as f64 * h) {
                    return Err(RunFailure::Numerical(reason));
                }
            }
            let piece = left.min(piece);
            let (clock, cpu) = (Instant::now(), thread_seconds());
            driver
                .advance(piece, h)
                .map_err(|e| RunFailure::Numerical(e.to_string()))?;
            seconds += clock.elapsed().as_secs_f64();
            cpu_seconds += thread_seconds() - cpu;
            left -= piece;
        }
        done += k;
        let t = done as f64 * h;
        let energy = driver.totals().map(|totals| totals.energy);
        if energy.is_some_and(|e| !e.is_finite()) {
            return Err(RunFailure::Numerical(format!(
                "the energy became non-finite by t = {t}: the step {h:e} is unstable for this structure"
            )));
        }
        record(&mut out, driver.system(), t, energy);
    }
    out.wall_seconds = seconds;
    out.cpu_seconds = cpu_seconds;
    out.newton_iterations = driver.newton_iterations();
    if let (Some(start), Some(end)) = (start_totals, driver.totals()) {
        if explicit == Some(BeamMethod::MassScaled) {
            out.stretch_iterations = Some(driver.system().stretch_iterations() as f64 / steps.max(1) as f64);
        }
        out.momenta = Some([
            start.linear_momentum.to_array(),
            end.linear_momentum.to_array(),
            start.angular_momentum.to_array(),
            end.angular_momentum.to_array(),
        ]);
    }
    Ok((out, page))
}

/// One point of the work-precision study.
#[derive(Clone, Debug)]
pub struct WorkPoint {
    /// Method.
    pub method: &'static str,
    /// Step.
    pub step: f64,
    /// Least CPU time of the stepping over the repetitions (s).
    pub seconds: f64,
    /// `max_t |u(t) − u_ref(t)| / max_t |u_ref(t)|` of the tracked node.
    pub error: f64,
}

/// The error of `run`'s history of node `node` against `reference`'s (sampled every
/// `sample`), at `run`'s samples that fall on the reference's (all of them when the step
/// divides `sample`; every other one for Newmark's 0.075).
fn history_error(run: &BeamRun, reference: &BeamRun, node: usize, sample: f64) -> f64 {
    let r = &reference.tracked[node].1;
    let scale = r
        .iter()
        .map(|u| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt())
        .fold(0.0, f64::max);
    let mut worst: f64 = 0.0;
    for (t, u) in run.t.iter().zip(&run.tracked[node].1) {
        let k = (t / sample).round() as usize;
        if (t / sample - k as f64).abs() > 1e-6 {
            continue;
        }
        if let Some(v) = r.get(k) {
            let d = ((u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2) + (u[2] - v[2]).powi(2)).sqrt();
            worst = worst.max(d);
        }
    }
    worst / scale
}

/// CPU time against the error of the elbow's history on the right-angle cantilever with
/// `per_leg` elements per leg, for the explicit splittings (0.9 and 0.45 of their
/// critical steps) and Newmark (`dt` 0.2 down to 0.0125, with 0.15 and 0.075 between the
/// octaves near 1 %; a step whose Newton iteration
/// fails gives no point); the reference is `liemid4` at 0.2 of its critical step. Returns
/// the points and the reference's own error estimate (against `liemid4` at 0.1).
pub fn work_precision(per_leg: usize, repetitions: usize) -> Result<(Vec<WorkPoint>, f64), RunFailure> {
    let scenario = |method: BeamIntegrator| -> Result<BeamScenario, RunFailure> {
        let mut s =
            crate::beam::scenario::builtin("right-angle-cantilever", Some(per_leg)).map_err(RunFailure::Input)?;
        s.method = method;
        Ok(s)
    };
    let sample = 0.05;
    let t_end = scenario(BeamIntegrator::Newmark)?.problem.t_end;
    let elbow = 0;
    let explicit4 = BeamIntegrator::Explicit(BeamMethod::Splitting4);
    let critical4 = scenario(explicit4)?
        .problem
        .system()
        .map_err(|e| RunFailure::Input(e.to_string()))?
        .stability(0)
        .critical_step(BeamMethod::Splitting4);
    let fine = |fraction: f64| -> Result<BeamRun, RunFailure> {
        let h = sample / (sample / (fraction * critical4)).ceil();
        run(&scenario(explicit4)?, t_end, Stepping::fixed(h, sample), &mut |_| None)
    };
    let reference = fine(0.2)?;
    let check = fine(0.1)?;
    let reference_error = history_error(&reference, &check, elbow, sample);
    let mut points = Vec::new();
    let time = |method: BeamIntegrator, h: f64| -> Result<Option<WorkPoint>, RunFailure> {
        let sc = scenario(method)?;
        let mut best = f64::INFINITY;
        let mut last = None;
        for _ in 0..repetitions.max(1) {
            let r = match run(&sc, t_end, Stepping::fixed(h, sample), &mut |_| None) {
                Ok(r) => r,
                // Newmark's Newton iteration can fail at a large step: a point it does not reach.
                Err(RunFailure::Numerical(_)) if method == BeamIntegrator::Newmark => return Ok(None),
                Err(e) => return Err(e),
            };
            best = best.min(r.cpu_seconds);
            let long = r.cpu_seconds > 1.0;
            last = Some(r);
            if long {
                break;
            }
        }
        let r = last.expect("at least one repetition");
        Ok(Some(WorkPoint {
            method: method.key(),
            step: h,
            seconds: best,
            error: history_error(&r, &reference, elbow, sample),
        }))
    };
    for m in BeamMethod::ALL {
        let critical = scenario(BeamIntegrator::Explicit(m))?
            .problem
            .system()
            .map_err(|e| RunFailure::Input(e.to_string()))?
            .stability(0)
            .critical_step(m);
        for fraction in [0.9, 0.45] {
            let h = sample / (sample / (fraction * critical)).ceil();
            points.extend(time(BeamIntegrator::Explicit(m), h)?);
        }
    }
    for dt in [0.2, 0.15, 0.1, 0.075, 0.05, 0.025, 0.0125] {
        points.extend(time(BeamIntegrator::Newmark, dt)?);
    }
    Ok((points, reference_error))
}

/// The CPU time at which `method`'s points reach `target` (log-log interpolation between
/// the neighbouring points; the cheapest point's time when even it is below the target;
/// `None` when no point reaches it).
#[must_use]
pub fn time_to_error(points: &[WorkPoint], method: &str, target: f64) -> Option<(f64, bool)> {
    let mut p: Vec<&WorkPoint> = points.iter().filter(|p| p.method == method).collect();
    p.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
    let first = p.first()?;
    if first.error <= target {
        return Some((first.seconds, false));
    }
    for w in p.windows(2) {
        let (a, b) = (w[0], w[1]);
        if a.error > target && b.error <= target {
            let f = (target.ln() - a.error.ln()) / (b.error.ln() - a.error.ln());
            return Some(((a.seconds.ln() + f * (b.seconds.ln() - a.seconds.ln())).exp(), true));
        }
    }
    None
}
