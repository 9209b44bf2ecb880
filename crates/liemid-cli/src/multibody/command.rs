//! `liemid multibody`: integrate jointed rigid bodies from a model file (MJCF, URDF), a
//! scenario file or a built-in problem; stream the bodies' poses, plot the run, and print a
//! summary of what the method keeps (energy, constraints, momenta).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use liemid::error::Num;
use liemid::multibody::{JointSpaceModel, MultibodyState, MultibodySystem};
use serde_json::json;

use super::scenario::{self, Method, MultibodyScenario};
use crate::shared::command::{check_positive, emit_json, CmdResult, Failure};
use crate::shared::interrupt::{progress, Interrupt};
use crate::shared::output::{Format, OutputPlan, TrajectoryWriter};
use crate::shared::plot;

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
    /// compositions) or rk4 (classical RK4 in joint coordinates) [default: liemid].
    #[arg(long)]
    pub method: Option<String>,
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
    /// Write the summary as JSON to FILE, or to standard output with `-`.
    #[arg(long)]
    pub json: Option<String>,
    /// Plot the joint coordinates and the relative energy error against time (PNG or SVG;
    /// NAME alone writes both).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// Bodies whose poses the trajectory file holds at most (its rows stay below 7,000 numbers).
const MAX_TRAJECTORY_BODIES: usize = 1000;

/// What the run records for its plot.
#[derive(Default)]
struct Record {
    t: Vec<f64>,
    energy_error: Vec<f64>,
    joints: Vec<Vec<f64>>,
}

/// Run `liemid multibody`.
pub fn multibody(args: &MultibodyArgs) -> CmdResult {
    let input = |e: String| Failure::Input(e);
    let mut sc = match (&args.model, &args.problem) {
        (Some(path), _) => scenario::load(path).map_err(input)?,
        (None, p) => scenario::builtin(p.as_deref().unwrap_or("double-pendulum")).map_err(input)?,
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
    let inputs: Vec<&Path> = sc.inputs.iter().map(PathBuf::as_path).collect();
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
    if matches!(method, Method::Liemid(_)) && sc.model.joints.iter().any(|j| j.armature != 0.0) {
        // A rotor inertia in joint space has no exact counterpart in maximal coordinates.
        for j in &mut sc.model.joints {
            j.armature = 0.0;
        }
        sc.ignored
            .push("joint armature (no exact form in maximal coordinates; --method rk4 keeps it)".into());
    }
    if !sc.ignored.is_empty() {
        eprintln!(
            "liemid: note: {} holds what is not simulated, ignored: {}",
            sc.name,
            sc.ignored.join(", ")
        );
    }
    let n = liemid::rigid::driver::step_count(0.0, t_end, step).map_err(|e| input(e.to_string()))?;
    let report = match method {
        Method::Liemid(m) => run_maximal(&sc, m, step, t_end, every, out.as_deref(), n)?,
        Method::Rk4 => run_joint_space(&sc, step, t_end, every, out.as_deref(), n)?,
    };
    if let Some(base) = &args.plot {
        let names: Vec<String> = joint_names(&sc, &report.1);
        let title = format!("{}: {} at h = {}", sc.name, method.key(), Num(step));
        let coordinates: Vec<(String, Vec<(f64, f64)>)> = names
            .iter()
            .zip(&report.1.joints)
            .map(|(name, q)| {
                (
                    name.clone(),
                    report.1.t.iter().copied().zip(q.iter().copied()).collect(),
                )
            })
            .collect();
        let energy = vec![(
            "(E - E0) / |E0|".to_string(),
            report
                .1
                .t
                .iter()
                .copied()
                .zip(report.1.energy_error.iter().copied())
                .collect(),
        )];
        let panels = [
            plot::Histories {
                title: &title,
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
        for p in plot::plot_paths(base) {
            plot::stacked_histories(&p, &panels).map_err(Failure::Run)?;
            if args.json.as_deref() != Some("-") && out.as_deref() != Some(Path::new("-")) {
                println!("wrote {}", p.display());
            }
        }
    }
    let summary = report.0;
    match args.json.as_deref() {
        Some(j) => emit_json(Some(j), &summary)?,
        None => print_summary(&summary),
    }
    Ok(())
}

fn joint_names(sc: &MultibodyScenario, record: &Record) -> Vec<String> {
    sc.model
        .joints
        .iter()
        .filter(|j| j.kind.axis().is_some())
        .map(|j| j.name.clone())
        .take(record.joints.len())
        .collect()
}

/// The trajectory's columns: t, energy, then x, y, z, qw, qx, qy, qz per body.
fn columns(sc: &MultibodyScenario) -> Vec<String> {
    let mut c = vec!["t".to_string(), "energy".to_string()];
    for b in sc.model.bodies.iter().take(MAX_TRAJECTORY_BODIES) {
        for s in ["x", "y", "z", "qw", "qx", "qy", "qz"] {
            c.push(format!("{}.{s}", b.name));
        }
    }
    c
}

fn writer(sc: &MultibodyScenario, out: Option<&Path>) -> Result<Option<TrajectoryWriter>, Failure> {
    let Some(path) = out else { return Ok(None) };
    let format = match path.extension().and_then(|x| x.to_str()) {
        Some("npy") => Format::Npy,
        _ => Format::Csv,
    };
    let cols = columns(sc);
    let refs: Vec<&str> = cols.iter().map(String::as_str).collect();
    TrajectoryWriter::create(path, format, &refs)
        .map(Some)
        .map_err(Failure::Input)
}

/// The rows and record of a run, whichever coordinates it steps.
trait Poses {
    fn time(&self) -> f64;
    fn energy(&mut self) -> f64;
    fn pose(&mut self, i: usize) -> ([f64; 3], [f64; 4]);
    fn hinge_and_slide(&mut self, out: &mut Vec<f64>);
}

fn observe<P: Poses>(
    p: &mut P,
    bodies: usize,
    e0: f64,
    row: &mut Vec<f64>,
    writer: &mut Option<TrajectoryWriter>,
    record: &mut Record,
) -> Result<(), Failure> {
    let e = p.energy();
    if let Some(w) = writer.as_mut() {
        row.clear();
        row.push(p.time());
        row.push(e);
        for i in 0..bodies.min(MAX_TRAJECTORY_BODIES) {
            let (x, q) = p.pose(i);
            row.extend_from_slice(&x);
            row.extend_from_slice(&q);
        }
        w.write_row(row).map_err(Failure::Run)?;
    }
    record.t.push(p.time());
    record.energy_error.push((e - e0) / e0.abs().max(f64::MIN_POSITIVE));
    let mut q = Vec::new();
    p.hinge_and_slide(&mut q);
    if record.joints.is_empty() {
        record.joints = vec![Vec::new(); q.len()];
    }
    for (k, v) in q.into_iter().enumerate() {
        record.joints[k].push(v);
    }
    Ok(())
}

struct Maximal<'a> {
    system: &'a mut MultibodySystem,
    state: &'a MultibodyState,
    joints: usize,
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
    fn hinge_and_slide(&mut self, out: &mut Vec<f64>) {
        for k in 0..self.joints {
            if let Some(q) = self.system.joint_coordinate(self.state, k) {
                out.push(q);
            }
        }
    }
}

/// The failure of a run stopped by a signal after `done` of `n` steps, keeping the partial
/// trajectory.
fn stopped((signal, code): (&str, u8), t: f64, done: u64, n: u64, writer: Option<TrajectoryWriter>) -> Failure {
    let kept = writer.map(|w| format!("; {}", w.keep_partial())).unwrap_or_default();
    Failure::Signal(
        code,
        format!("{signal}: stopped at t = {} after {done} of {n} steps{kept}", Num(t)),
    )
}

fn finish_writer(writer: Option<TrajectoryWriter>) -> Result<Option<(String, u64)>, Failure> {
    writer.map(TrajectoryWriter::finish).transpose().map_err(Failure::Run)
}

fn run_maximal(
    sc: &MultibodyScenario,
    method: liemid::multibody::MultibodyMethod,
    h: f64,
    t_end: f64,
    every: u64,
    out: Option<&Path>,
    n: u64,
) -> Result<(serde_json::Value, Record), Failure> {
    let mut system =
        MultibodySystem::new(&sc.model, method).map_err(|e| Failure::Input(format!("{}: {e}", sc.name)))?;
    let mut state = sc
        .model
        .initial_state()
        .map_err(|e| Failure::Input(format!("{}: {e}", sc.name)))?;
    let bodies = state.len();
    let mut writer = writer(sc, out)?;
    let mut record = Record::default();
    let mut row = Vec::new();
    let e0 = system.energy(&state);
    let p0 = system.linear_momentum(&state);
    let l0 = system.angular_momentum(&state);
    observe(
        &mut Maximal {
            system: &mut system,
            state: &state,
            joints: sc.model.joints.len(),
        },
        bodies,
        e0,
        &mut row,
        &mut writer,
        &mut record,
    )?;
    let interrupt = Interrupt::install();
    let bar = progress(n, "steps", n >= 200_000);
    let started = Instant::now();
    let mut max_dp: f64 = 0.0;
    let mut max_dl: f64 = 0.0;
    let mut max_pos: f64 = 0.0;
    let mut max_vel: f64 = 0.0;
    let mut max_energy: f64 = 0.0;
    let mut failure = None;
    for k in 1..=n {
        if let Some(stop) = interrupt.requested() {
            bar.finish_and_clear();
            return Err(stopped(stop, state.t, k - 1, n, writer));
        }
        let t_next = if k == n { t_end } else { k as f64 * h };
        let h_k = t_next - state.t;
        match system.step(&mut state, h_k) {
            Ok(r) => {
                max_pos = max_pos.max(r.position_violation);
                max_vel = max_vel.max(r.velocity_violation);
            }
            Err(e) => {
                failure = Some(format!("at t = {}: {e}", Num(state.t)));
                break;
            }
        }
        state.t = t_next;
        let e = system.energy(&state);
        max_energy = max_energy.max(((e - e0) / e0.abs().max(f64::MIN_POSITIVE)).abs());
        max_dp = max_dp.max((system.linear_momentum(&state) - p0).norm());
        max_dl = max_dl.max((system.angular_momentum(&state) - l0).norm());
        if k % every == 0 || k == n {
            observe(
                &mut Maximal {
                    system: &mut system,
                    state: &state,
                    joints: sc.model.joints.len(),
                },
                bodies,
                e0,
                &mut row,
                &mut writer,
                &mut record,
            )?;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let seconds = started.elapsed().as_secs_f64();
    if let Some(f) = failure {
        let kept = writer.map(|w| format!("; {}", w.keep_partial())).unwrap_or_default();
        return Err(Failure::Run(format!("{}: {f}{kept}", sc.name)));
    }
    let written = finish_writer(writer)?;
    let free = sc
        .model
        .joints
        .iter()
        .all(|j| j.parent != liemid::multibody::Link::World)
        && sc.model.gravity.norm() == 0.0;
    let finals: Vec<_> = (0..bodies)
        .map(|i| {
            let x = system.frame_origin(&state, i);
            json!({"name": sc.model.bodies[i].name, "xpos": [x.x, x.y, x.z], "xquat": system.quaternion(&state, i)})
        })
        .collect();
    let joints: Vec<_> = (0..sc.model.joints.len())
        .filter_map(|k| {
            system
                .joint_coordinate(&state, k)
                .map(|q| json!({"name": sc.model.joints[k].name, "value": q}))
        })
        .collect();
    let summary = json!({
        "model": sc.name,
        "method": method.name(),
        "step": h,
        "t_end": t_end,
        "steps": n,
        "bodies": bodies,
        "max_relative_energy_error": max_energy,
        "max_position_constraint_violation": max_pos,
        "max_velocity_constraint_violation": max_vel,
        "max_momentum_change": if free { json!({"linear": max_dp, "angular": max_dl}) } else { json!(null) },
        "final": finals,
        "joints": joints,
        "ignored": sc.ignored,
        "stepping_seconds": seconds,
        "body_steps_per_second": (bodies as f64 * n as f64) / seconds.max(1e-12),
        "trajectory": written.map(|(path, rows)| json!({"path": path, "rows": rows})),
    });
    Ok((summary, record))
}

struct Joint<'a> {
    kinds: &'a [liemid::multibody::JointKind],
    model: &'a mut JointSpaceModel,
    t: f64,
    q: &'a [f64],
    v: &'a [f64],
    poses: Vec<(liemid::Vec3, liemid::Mat3)>,
}

impl Poses for Joint<'_> {
    fn time(&self) -> f64 {
        self.t
    }
    fn energy(&mut self) -> f64 {
        self.model.energy(self.q, self.v).unwrap_or(f64::NAN)
    }
    fn pose(&mut self, i: usize) -> ([f64; 3], [f64; 4]) {
        if self.poses.is_empty() {
            self.poses = self.model.forward_kinematics(self.q).unwrap_or_default();
        }
        let Some(&(x, r)) = self.poses.get(i) else {
            return ([f64::NAN; 3], [f64::NAN; 4]);
        };
        let q = liemid::so3::Quaternion::from_matrix(&r);
        ([x.x, x.y, x.z], [q.w, q.x, q.y, q.z])
    }
    fn hinge_and_slide(&mut self, out: &mut Vec<f64>) {
        hinge_and_slide(self.kinds, self.q, out);
    }
}

fn run_joint_space(
    sc: &MultibodyScenario,
    h: f64,
    t_end: f64,
    every: u64,
    out: Option<&Path>,
    n: u64,
) -> Result<(serde_json::Value, Record), Failure> {
    let mut model = JointSpaceModel::new(&sc.model).map_err(|e| Failure::Input(format!("{}: {e}", sc.name)))?;
    let (mut q, mut v) = (model.initial_q().to_vec(), model.initial_v().to_vec());
    let kinds: Vec<_> = sc.model.joints.iter().map(|j| j.kind).collect();
    let bodies = sc.model.bodies.len();
    let mut writer = writer(sc, out)?;
    let mut record = Record::default();
    let mut row = Vec::new();
    let e0 = model
        .energy(&q, &v)
        .map_err(|e| Failure::Input(format!("{}: {e}", sc.name)))?;
    let mut view = |model: &mut JointSpaceModel,
                    t: f64,
                    q: &[f64],
                    v: &[f64],
                    w: &mut Option<TrajectoryWriter>,
                    rec: &mut Record| {
        observe(
            &mut Joint {
                kinds: &kinds,
                model,
                t,
                q,
                v,
                poses: Vec::new(),
            },
            bodies,
            e0,
            &mut row,
            w,
            rec,
        )
    };
    view(&mut model, 0.0, &q, &v, &mut writer, &mut record)?;
    let interrupt = Interrupt::install();
    let bar = progress(n, "steps", n >= 200_000);
    let started = Instant::now();
    let mut max_energy: f64 = 0.0;
    let mut t = 0.0;
    for k in 1..=n {
        if let Some(stop) = interrupt.requested() {
            bar.finish_and_clear();
            return Err(stopped(stop, t, k - 1, n, writer));
        }
        let t_next = if k == n { t_end } else { k as f64 * h };
        model
            .rk4_step(&mut q, &mut v, t_next - t)
            .map_err(|e| Failure::Run(format!("{}: at t = {}: {e}", sc.name, Num(t))))?;
        t = t_next;
        if !(q.iter().chain(&v).all(|x| x.is_finite())) {
            let kept = writer.map(|w| format!("; {}", w.keep_partial())).unwrap_or_default();
            return Err(Failure::Run(format!(
                "{}: rk4 produced a non-finite state at t = {} (step too large?){kept}",
                sc.name,
                Num(t)
            )));
        }
        let e = model.energy(&q, &v).unwrap_or(f64::NAN);
        max_energy = max_energy.max(((e - e0) / e0.abs().max(f64::MIN_POSITIVE)).abs());
        if k % every == 0 || k == n {
            view(&mut model, t, &q, &v, &mut writer, &mut record)?;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let seconds = started.elapsed().as_secs_f64();
    let written = finish_writer(writer)?;
    let poses = model.forward_kinematics(&q).map_err(|e| Failure::Run(e.to_string()))?;
    let finals: Vec<_> = poses
        .iter()
        .enumerate()
        .map(|(i, (x, r))| {
            let qq = liemid::so3::Quaternion::from_matrix(r);
            json!({"name": sc.model.bodies[i].name, "xpos": [x.x, x.y, x.z], "xquat": [qq.w, qq.x, qq.y, qq.z]})
        })
        .collect();
    let mut coords = Vec::new();
    hinge_and_slide(&kinds, &q, &mut coords);
    let names = sc
        .model
        .joints
        .iter()
        .filter(|j| j.kind.axis().is_some())
        .map(|j| j.name.clone());
    let joints: Vec<_> = names
        .zip(coords)
        .map(|(name, value)| json!({"name": name, "value": value}))
        .collect();
    let summary = json!({
        "model": sc.name,
        "method": "RK4 (joint coordinates)",
        "step": h,
        "t_end": t_end,
        "steps": n,
        "bodies": bodies,
        "max_relative_energy_error": max_energy,
        "max_position_constraint_violation": 0.0,
        "max_velocity_constraint_violation": 0.0,
        "max_momentum_change": null,
        "final": finals,
        "joints": joints,
        "ignored": sc.ignored,
        "stepping_seconds": seconds,
        "body_steps_per_second": (bodies as f64 * n as f64) / seconds.max(1e-12),
        "trajectory": written.map(|(path, rows)| json!({"path": path, "rows": rows})),
    });
    Ok((summary, record))
}

fn print_summary(s: &serde_json::Value) {
    let num = |k: &str| s[k].as_f64().unwrap_or(f64::NAN);
    println!("model                          {}", s["model"].as_str().unwrap_or(""));
    println!("method                         {}", s["method"].as_str().unwrap_or(""));
    println!(
        "steps                          {} of h = {} to t = {}",
        s["steps"],
        Num(num("step")),
        Num(num("t_end"))
    );
    println!("bodies                         {}", s["bodies"]);
    println!(
        "max relative energy error      {:.3e}",
        num("max_relative_energy_error")
    );
    println!(
        "max constraint violation       position {:.3e}, velocity {:.3e} (relative)",
        num("max_position_constraint_violation"),
        num("max_velocity_constraint_violation")
    );
    if let Some(m) = s["max_momentum_change"].as_object() {
        println!(
            "max momentum change            linear {:.3e}, angular {:.3e}",
            m["linear"].as_f64().unwrap_or(f64::NAN),
            m["angular"].as_f64().unwrap_or(f64::NAN)
        );
    }
    for j in s["joints"].as_array().into_iter().flatten() {
        println!(
            "joint {:<24} {:.9}",
            j["name"].as_str().unwrap_or(""),
            j["value"].as_f64().unwrap_or(f64::NAN)
        );
    }
    if let Some(t) = s["trajectory"].as_object() {
        println!(
            "trajectory                     {} ({} rows)",
            t["path"].as_str().unwrap_or(""),
            t["rows"]
        );
    }
    println!(
        "wall time                      {:.3} s ({:.3e} body-steps/s)",
        num("stepping_seconds"),
        num("body_steps_per_second")
    );
}

/// The hinge angles and slide offsets from joint coordinates in MuJoCo's layout.
fn hinge_and_slide(kinds: &[liemid::multibody::JointKind], q: &[f64], out: &mut Vec<f64>) {
    let mut at = 0;
    for kind in kinds {
        if kind.axis().is_some() {
            out.push(q.get(at).copied().unwrap_or(f64::NAN));
        }
        at += kind.nq();
    }
}
