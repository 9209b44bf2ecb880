//! `liemid multibody`: integrate jointed rigid bodies from a model file (MJCF, URDF), a
//! scenario file or a built-in problem; stream the bodies' poses, plot the run, and print a
//! summary of what the method keeps (energy, constraints, momenta).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use liemid::error::Num;
use liemid::multibody::{MultibodyState, MultibodySystem, Prepared, Rattle, Simulation};
use serde_json::json;

use super::scenario::{self, Method, MultibodyScenario};
use super::sink::{after_step, Halt, Poses, Record, Sink};
use crate::shared::command::{check_positive, emit_json, CmdResult, Failure};
use crate::shared::interrupt::{progress, Interrupt};
use crate::shared::output::OutputPlan;
use crate::shared::plot;
use crate::shared::view;

/// Arguments of `liemid multibody`.
#[derive(Args, Debug)]
pub struct MultibodyArgs {
    /// Model file (MJCF `.xml`, URDF `.urdf`) or scenario file (`.toml`); without it,
    /// `--problem`.
    pub model: Option<PathBuf>,
    /// Built-in problem: double-pendulum (default), chain-10, spacecraft, closed-loop,
    /// chain-1000, test-chain.
    #[arg(long, conflicts_with = "model")]
    pub problem: Option<String>,
    /// liemid (RATTLE with EA's rotation, order 2), liemid4, liemid6, liemid8 (its symmetric
    /// compositions), rk4 (classical RK4 in joint coordinates) or dop853 (Dormand-Prince
    /// 8(5,3) with step control in joint coordinates, `--rtol`: the reference)
    /// [default: liemid].
    #[arg(long)]
    pub method: Option<String>,
    /// The torque-free rotation in the liemid methods' drift: midpoint (EA's pair of
    /// midpoint half steps) or variational (the pair of liemid-eav, a Lie-Poisson drift: the
    /// step is then symplectic on a free body) [default: midpoint].
    #[arg(long)]
    pub drift: Option<String>,
    /// Step (s) [default: the file's `timestep`, else 1e-3].
    #[arg(long, allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// End time (s) [default: the problem's, else 1].
    #[arg(long, allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Interval of the trajectory, in steps [default: 10].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub every: Option<u64>,
    /// Write t, the energy and each body's frame origin (x, y, z) and attitude quaternion
    /// (w, x, y, z) every `--every` steps (CSV, or .npy by extension; `-` for standard
    /// output).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the summary as JSON to FILE, or to standard output with `-` or no value.
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<String>,
    /// Plot the joint coordinates and the relative energy error against time (PNG or SVG;
    /// NAME alone writes both).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Write a self-contained 3-D animation page (HTML): a box per body, a line per joint,
    /// and the energy error; frames every `--every` steps, subsampled to a byte budget.
    #[arg(long)]
    pub view: Option<PathBuf>,
    /// Refuse runs of more than N steps (exit 2) before the first step [default: 10⁹].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_steps: Option<u64>,
    /// dop853's relative tolerance (absolute: rtol / 1000) [default: 1e-12].
    #[arg(long)]
    pub rtol: Option<f64>,
    /// A constant control, one value per actuator in the model's order, comma-separated
    /// (replaces the keyframe's ctrl).
    #[arg(
        long,
        allow_hyphen_values = true,
        value_name = "U1,U2,...",
        conflicts_with = "ctrl_file"
    )]
    pub ctrl: Option<String>,
    /// Controls over time: CSV with a header `t,<actuator>,...` naming every actuator, then
    /// rows of increasing t; each row is held from its time until the next (piecewise
    /// constant, sampled at each step's start; before the first row, the first row).
    #[arg(long, value_name = "CSV")]
    pub ctrl_file: Option<PathBuf>,
}

/// The most bytes of a `--ctrl-file` table.
const MAX_CTRL_FILE_BYTES: u64 = 256 << 20;

/// `--ctrl`'s values.
fn parse_ctrl(text: &str) -> Result<Vec<f64>, Failure> {
    text.split(',')
        .enumerate()
        .map(|(k, x)| {
            x.trim().parse::<f64>().map_err(|_| {
                Failure::Input(format!(
                    "--ctrl: value {k} `{}` is not a number (one value per actuator, comma-separated)",
                    x.trim().chars().take(40).collect::<String>()
                ))
            })
        })
        .collect()
}

/// Run `liemid multibody`.
pub fn multibody(args: &MultibodyArgs) -> CmdResult {
    let input = |e: String| Failure::Input(e);
    let mut sc = match (&args.model, &args.problem) {
        (Some(path), _) => scenario::load(path).map_err(input)?,
        (None, p) => scenario::builtin(p.as_deref().unwrap_or("double-pendulum")).map_err(input)?,
    };
    let drift = match &args.drift {
        None => liemid::multibody::Drift::Midpoint,
        Some(key) => liemid::multibody::Drift::from_key(key).ok_or_else(|| {
            input(format!(
                "--drift: unknown drift \"{key}\" (known: midpoint, variational)"
            ))
        })?,
    };
    let method = match &args.method {
        Some(m) => Method::from_key(m).map_err(|e| input(format!("--method: {e}")))?,
        None => sc
            .method
            .unwrap_or(Method::Liemid(liemid::multibody::MultibodyMethod::Liemid)),
    };
    let step = check_positive("step", args.step.or(sc.step).unwrap_or_else(|| sc.default_step()))?;
    let t_end = args.t_end.or(sc.t_end).unwrap_or_else(|| sc.default_t_end());
    if !(t_end.is_finite() && t_end > 0.0) {
        return Err(input(format!("--t-end must be a positive number, found {t_end}")));
    }
    let every = args.every.or(sc.every).unwrap_or(10);
    let out = args.out.clone().or_else(|| sc.out.take());
    let inputs: Vec<&Path> = sc
        .inputs
        .iter()
        .map(PathBuf::as_path)
        .chain(args.ctrl_file.as_deref())
        .collect();
    let mut plan = OutputPlan::new(&inputs);
    if let Some(p) = out.as_deref().filter(|p| *p != Path::new("-")) {
        plan.add("--out", p).map_err(input)?;
    }
    if let Some(j) = args.json.as_deref().filter(|j| *j != "-") {
        plan.add("--json", Path::new(j)).map_err(input)?;
    }
    if let Some(base) = &args.plot {
        for p in plot::plot_paths(base) {
            plan.add("--plot", &p).map_err(input)?;
        }
    }
    if let Some(p) = &args.view {
        plan.add("--view", p).map_err(input)?;
    }
    let rtol = args.rtol.unwrap_or(1e-12);
    if !(rtol.is_finite() && rtol > 0.0 && rtol < 1.0) {
        return Err(input(format!("--rtol must be in (0, 1), found {rtol}")));
    }
    if args.rtol.is_some() && method != Method::Dop853 {
        return Err(input(
            "--rtol sets dop853's tolerance; this run's method has a fixed step (--step)".into(),
        ));
    }
    if let Some(text) = &args.ctrl {
        sc.model.ctrl = Some(parse_ctrl(text)?);
        sc.model
            .validate_actuators()
            .map_err(|e| input(format!("--ctrl: {e}")))?;
    }
    let table = match &args.ctrl_file {
        None => None,
        Some(path) => {
            if method == Method::Dop853 {
                return Err(input(
                    "--ctrl-file: a held control jumps at the table's times, which dop853's step control does not \
                     see; take --method rk4 or a liemid method"
                        .into(),
                ));
            }
            let text = liemid_app::shared::input::read_text(path, MAX_CTRL_FILE_BYTES).map_err(input)?;
            let names: Vec<String> = sc.model.actuators.iter().map(|a| a.name.clone()).collect();
            let table =
                liemid::multibody::ControlTable::parse(&text, &format!("--ctrl-file {}", path.display()), &names)
                    .map_err(|e| input(e.to_string()))?;
            sc.model.ctrl = Some(table.at(0.0).to_vec());
            Some(table)
        }
    };
    // The model policy of the run (the library's, as Python's): what is left out, and the
    // start projected onto loop-closing joints.
    if args.drift.is_some() && !matches!(method, Method::Liemid(_)) {
        return Err(input(
            "--drift chooses the liemid methods' rotation; rk4 and dop853 run in joint coordinates".into(),
        ));
    }
    let prepared = match method {
        Method::Liemid(m) => {
            let mut prepared = Simulation::prepare(&sc.model, m)
                .map_err(|e| Failure::Input(format!("{}: the start: {e}", sc.name)))?;
            prepared.simulation.integrator.set_drift(drift);
            Some(prepared)
        }
        Method::Rk4 | Method::Dop853 => None,
    };
    let notes = match &prepared {
        Some(p) => p.notes.clone(),
        None => liemid::multibody::joint_space_notes(&sc.model),
    };
    sc.ignored
        .extend(notes.iter().filter(|n| n.is_ignored_content()).map(ToString::to_string));
    if !sc.ignored.is_empty() {
        eprintln!(
            "liemid: note: {} holds what is not simulated, ignored: {}",
            sc.name,
            sc.ignored.join(", ")
        );
    }
    for note in notes.iter().filter(|n| !n.is_ignored_content()) {
        eprintln!("liemid: note: {}: {note}", sc.name);
    }
    let n = liemid::rigid::driver::step_count(0.0, t_end, step).map_err(|e| input(e.to_string()))?;
    if method != Method::Dop853 {
        crate::shared::command::check_steps(n, args.max_steps)?;
    }
    let sink = Sink::new(&sc, out.as_deref(), args.view.is_some())?;
    let (summary, sink) = match (method, prepared) {
        (Method::Liemid(m), Some(prepared)) => {
            run_maximal(&sc, m, prepared, (step, t_end, n), every, table.as_ref(), sink)?
        }
        (Method::Rk4, _) => super::joint_run::rk4(&sc, (step, t_end, every, n), table.as_ref(), sink)?,
        (_, _) => super::joint_run::dop853(&sc, rtol, t_end, (every, args.max_steps), sink)?,
    };
    let quiet = args.json.as_deref() == Some("-") || out.as_deref() == Some(Path::new("-"));
    if let Some(base) = &args.plot {
        let step_label = match method {
            Method::Dop853 => format!("rtol {}", Num(rtol)),
            _ => format!("h = {}", Num(step)),
        };
        for p in plot_run(
            &sc,
            &sink.record,
            base,
            &format!("{}: {} at {step_label}", sc.name, method.key()),
        )? {
            if !quiet {
                crate::outln!("wrote {}", p.display());
            }
        }
    }
    if let (Some(page), Some(path)) = (&sink.page, &args.view) {
        let steps = summary["steps"].as_u64().unwrap_or(n);
        let line = view::report(path, page.write(path, steps).map_err(Failure::Run)?, steps);
        if quiet {
            eprintln!("{line}");
        } else {
            crate::outln!("{line}");
        }
    }
    match args.json.as_deref() {
        Some(j) => emit_json(Some(j), &summary)?,
        None => print_summary(&summary),
    }
    Ok(())
}

/// Plot the record's joint coordinates and energy error to `base` (PNG, SVG or both);
/// returns the files written.
fn plot_run(sc: &MultibodyScenario, record: &Record, base: &Path, title: &str) -> Result<Vec<PathBuf>, Failure> {
    let names = sc
        .model
        .joints
        .iter()
        .filter(|j| j.kind.axis().is_some())
        .map(|j| j.name.clone());
    let series = |values: &[f64]| -> Vec<(f64, f64)> { record.t.iter().copied().zip(values.iter().copied()).collect() };
    let coordinates: Vec<(String, Vec<(f64, f64)>)> =
        names.zip(&record.joints).map(|(name, q)| (name, series(q))).collect();
    let energy = vec![("(E - E0) / |E0|".to_string(), series(&record.energy_error))];
    let panels = [
        plot::Histories {
            title,
            x_desc: "t (s)",
            y_desc: "joint coordinate (rad or m)",
            lines: &coordinates,
            points: &[],
        },
        plot::Histories {
            title: "relative energy error",
            x_desc: "t (s)",
            y_desc: "(E - E0) / |E0|",
            lines: &energy,
            points: &[],
        },
    ];
    let paths = plot::plot_paths(base);
    for p in &paths {
        plot::stacked_histories(p, &panels).map_err(Failure::Run)?;
    }
    Ok(paths)
}

struct Maximal<'a> {
    system: &'a MultibodySystem,
    state: &'a MultibodyState,
    joints: usize,
    integrator: &'a Rattle,
}

impl Poses for Maximal<'_> {
    fn time(&self) -> f64 {
        self.state.t
    }
    fn energy(&mut self) -> f64 {
        self.system.energy(self.state)
    }
    fn pose(&mut self, i: usize) -> ([f64; 3], [f64; 4]) {
        let x = self.system.frame_origin(self.state, i);
        ([x.x, x.y, x.z], self.system.quaternion(self.state, i))
    }
    fn contacts(&mut self, out: &mut Vec<[f64; 6]>) {
        self.integrator.contact_forces(self.state, out);
    }
    fn hinge_and_slide(&mut self, out: &mut Vec<f64>) {
        for k in 0..self.joints {
            if let Some(q) = self.system.joint_coordinate(self.state, k) {
                out.push(q);
            }
        }
    }
}

/// For a composition (its negative sub-steps anti-damp) whose step `h` is beyond the
/// model's damper bound ([`liemid::multibody::model::Model::damper_step_bound`]): which
/// joint's damper is too stiff at `h` and the step that holds it.
fn stiff_damper(
    model: &liemid::multibody::model::Model,
    method: liemid::multibody::MultibodyMethod,
    h: f64,
) -> Option<String> {
    if method == liemid::multibody::MultibodyMethod::Liemid {
        return None;
    }
    let (k, bound) = model.damper_step_bound().filter(|&(_, bound)| h > bound)?;
    let j = &model.joints[k];
    Some(format!(
        "joint `{}` has damping {} against the child's inertia about its axis: a composition's negative \
         sub-step cannot hold it above h = 2 I / d = {:.3e}; take --method liemid, a smaller --step or --method rk4",
        j.name,
        Num(j.damping),
        bound
    ))
}

fn run_maximal(
    sc: &MultibodyScenario,
    method: liemid::multibody::MultibodyMethod,
    prepared: Prepared,
    (h, t_end, n): (f64, f64, u64),
    every: u64,
    table: Option<&liemid::multibody::ControlTable>,
    mut sink: Sink,
) -> Result<(serde_json::Value, Sink), Failure> {
    let Prepared {
        simulation: mut sim,
        mut state,
        ..
    } = prepared;
    // The rows the method cannot hold at this step are refused before the first step.
    sim.check_step(&state, h)
        .map_err(|e| Failure::Input(format!("{}: {e}", sc.name)))?;
    let bodies = state.len();
    let joints = sc.model.joints.len();
    sink.observe(&mut Maximal {
        system: &sim.system,
        state: &state,
        joints,
        integrator: &sim.integrator,
    })?;
    let interrupt = Interrupt::install();
    let bar = progress(n, "steps", n >= 200_000);
    let started = Instant::now();
    // The observer's own outcome: a failed write or a signal ends the run through it.
    let mut stop: Option<Halt> = None;
    let observer =
        |k: u64, system: &MultibodySystem, state: &MultibodyState, integrator: &Rattle| -> Result<(), String> {
            if k % every == 0 || k == n {
                let observed = sink.observe(&mut Maximal {
                    system,
                    state,
                    joints,
                    integrator,
                });
                if let Err(failure) = observed {
                    stop = Some(Halt::Output(failure));
                    return Err("the output failed".into());
                }
            }
            after_step(k, n, &bar, &interrupt, &mut stop)
        };
    let outcome = match table {
        None => {
            let mut observer = observer;
            let system = &sim.system;
            sim.integrator
                .integrate(system, &mut state, t_end, h, |k, state, _, integrator| {
                    observer(k, system, state, integrator)
                })
        }
        // A table's control, held over each step from its start (docs/theory/multibody.md §8).
        Some(table) => {
            let mut observer = observer;
            sim.integrate_controlled(
                &mut state,
                t_end,
                h,
                |_, state, u| {
                    u.copy_from_slice(table.at(state.t));
                    Ok(())
                },
                |k, system, state, _, integrator| observer(k, system, state, integrator),
            )
        }
    };
    bar.finish_and_clear();
    let system = &sim.system;
    let run = match (outcome, stop) {
        (Ok(run), _) => run,
        (Err(_), Some(Halt::Output(failure))) => return Err(failure),
        (Err(_), Some(Halt::Signal(signal, done))) => return Err(sink.stopped(signal, state.t, done, n)),
        (Err(e), None) => {
            let hint = stiff_damper(&sc.model, method, h)
                .map(|w| format!(" ({w})"))
                .unwrap_or_default();
            return Err(sink.failed(format!("{}: at t = {}: {e}{hint}", sc.name, Num(state.t))));
        }
    };
    let seconds = started.elapsed().as_secs_f64();
    let written = sink.finish()?;
    let free = sc
        .model
        .joints
        .iter()
        .all(|j| j.parent != liemid::multibody::Link::World || j.kind == liemid::multibody::JointKind::Free)
        && sc.model.gravity.norm() == 0.0;
    let finals: Vec<_> = (0..bodies)
        .map(|i| {
            let x = system.frame_origin(&state, i);
            json!({"name": sc.model.bodies[i].name, "xpos": [x.x, x.y, x.z], "xquat": system.quaternion(&state, i)})
        })
        .collect();
    let joint_values: Vec<_> = (0..joints)
        .filter_map(|k| {
            system
                .joint_coordinate(&state, k)
                .map(|q| json!({"name": sc.model.joints[k].name, "value": q}))
        })
        .collect();
    let momentum = json!({"linear": run.max_linear_momentum_change, "angular": run.max_angular_momentum_change});
    let summary = json!({
        "model": sc.name,
        "method": method.name(),
        "drift": sim.integrator.drift().key(),
        "step": h,
        "t_end": t_end,
        "steps": n,
        "bodies": bodies,
        "max_relative_energy_error": run.max_energy_error,
        "max_position_constraint_violation": run.max_position_violation,
        "max_velocity_constraint_violation": run.max_velocity_violation,
        "max_momentum_change": if free { momentum } else { json!(null) },
        "contacts": if sim.system.has_contacts() {
            json!({
                "most_points": run.max_contacts,
                "deepest_penetration": run.max_penetration,
                "position_iterations": run.contact_iterations,
                "solver_sweeps": run.contact_sweeps,
                "split_steps": run.split_steps,
                "frictionless_drifts": run.frictionless_drifts,
                "loose_steps": run.loose_steps,
                "max_loose_violation": run.max_loose_violation,
            })
        } else {
            json!(null)
        },
        "final": finals,
        "joints": joint_values,
        "ignored": sc.ignored,
        "stepping_seconds": seconds,
        "body_steps_per_second": (bodies as f64 * n as f64) / seconds.max(1e-12),
        "trajectory": written.map(|(path, rows)| json!({"path": path, "rows": rows})),
    });
    Ok((summary, sink))
}

fn print_summary(s: &serde_json::Value) {
    let num = |k: &str| s[k].as_f64().unwrap_or(f64::NAN);
    crate::outln!("model                          {}", s["model"].as_str().unwrap_or(""));
    crate::outln!("method                         {}", s["method"].as_str().unwrap_or(""));
    match s["rtol"].as_f64() {
        // DOP853 chooses its steps: its summary has a tolerance, not a step.
        Some(rtol) => crate::outln!(
            "steps                          {} accepted ({} rejected) at rtol {} to t = {}",
            s["steps"],
            s["rejected_steps"],
            Num(rtol),
            Num(num("t_end"))
        ),
        None => crate::outln!(
            "steps                          {} of h = {} to t = {}",
            s["steps"],
            Num(num("step")),
            Num(num("t_end"))
        ),
    }
    crate::outln!("bodies                         {}", s["bodies"]);
    crate::outln!(
        "max relative energy error      {:.3e}",
        num("max_relative_energy_error")
    );
    crate::outln!(
        "max constraint violation       position {:.3e}, velocity {:.3e} (relative)",
        num("max_position_constraint_violation"),
        num("max_velocity_constraint_violation")
    );
    if let Some(m) = s["max_momentum_change"].as_object() {
        crate::outln!(
            "max momentum change            linear {:.3e}, angular {:.3e}",
            m["linear"].as_f64().unwrap_or(f64::NAN),
            m["angular"].as_f64().unwrap_or(f64::NAN)
        );
    }
    if let Some(c) = s["contacts"].as_object() {
        crate::outln!(
            "contacts                       at most {} points, deepest penetration {:.3e} m, {} position iterations, {} solver sweeps",
            c["most_points"],
            c["deepest_penetration"].as_f64().unwrap_or(f64::NAN),
            c["position_iterations"],
            c["solver_sweeps"]
        );
    }
    for j in s["joints"].as_array().into_iter().flatten() {
        crate::outln!(
            "joint {:<24} {:.9}",
            j["name"].as_str().unwrap_or(""),
            j["value"].as_f64().unwrap_or(f64::NAN)
        );
    }
    if let Some(t) = s["trajectory"].as_object() {
        crate::outln!(
            "trajectory                     {} ({} rows)",
            t["path"].as_str().unwrap_or(""),
            t["rows"]
        );
    }
    crate::outln!(
        "wall time                      {:.3} s ({:.3e} body-steps/s)",
        num("stepping_seconds"),
        num("body_steps_per_second")
    );
}
