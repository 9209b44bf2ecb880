//! `liemid run --adaptive EPS` for a rigid-body scenario: the reversible adaptive run
//! (`liemid::rigid::adaptive`) with the same trajectory rows and summary as the fixed-step
//! run, which it leaves untouched, and the same `--view` page (frames at the adaptive
//! steps' times).

use std::path::{Path, PathBuf};
use std::time::Instant;

use liemid::rigid::adaptive::{AdaptiveRun, ReversibleStepper, RigidAdaptive, RigidDensity};
use liemid::{RotationMethod, Run, RunSummary, Vec3};

use super::{conserved_change, print_summary, print_view_line, row, view_frame, view_page, write_view, RunArgs};
use crate::rigid::scenario::{Format, Scenario};
use crate::shared::checkpoint::Settings;
use crate::shared::command::{CmdResult, Failure};
use crate::shared::output::{OutputPlan, TrajectoryWriter, COLUMNS};

/// The largest errors of the diagnostics, as [`liemid::Run::step`] keeps them.
fn track(p: &mut RunSummary, d: &liemid::Diagnostics) {
    let e0 = p.initial.energy;
    let de = (d.energy - e0).abs();
    p.max_energy_error = p.max_energy_error.max(if e0 != 0.0 { de / e0.abs() } else { de });
    let dm = d.spatial_momentum - p.initial.spatial_momentum;
    let m = p.max_spatial_momentum_change;
    p.max_spatial_momentum_change = Vec3::new(m.x.max(dm.x.abs()), m.y.max(dm.y.abs()), m.z.max(dm.z.abs()));
    p.max_body_momentum_norm_change = p
        .max_body_momentum_norm_change
        .max((d.body_momentum_norm - p.initial.body_momentum_norm).abs());
    p.max_orthogonality_defect = p.max_orthogonality_defect.max(d.orthogonality_defect);
    p.last = *d;
}

/// `liemid run --adaptive EPS`: the reversible adaptive run of a rigid-body scenario, with
/// the same trajectory rows (every `--every` steps, the first and the last) and summary.
pub(super) fn run_adaptive<D: RigidDensity>(
    args: &RunArgs,
    settings: &Settings,
    sc: &Scenario,
    method: RotationMethod,
    eps: f64,
    density: D,
) -> CmdResult {
    let system = &sc.system;
    let conservation = system.conservation();
    let mut plan = OutputPlan::new(&args.file.iter().map(PathBuf::as_path).collect::<Vec<_>>());
    let format = match settings.output.as_ref().map(|(_, f)| f.as_str()) {
        Some("npy") => Format::Npy,
        _ => Format::Csv,
    };
    if let Some((path, _)) = &settings.output {
        if path != "-" {
            plan.add("--out", Path::new(path)).map_err(Failure::Input)?;
        }
    }
    if let Some(path) = &args.view {
        plan.add("--view", path).map_err(Failure::Input)?;
    }
    if let Some(path) = args.json.as_deref().filter(|p| *p != "-") {
        plan.add("--json", Path::new(path)).map_err(Failure::Input)?;
    }
    let stepper = RigidAdaptive::new(system, method, density).map_err(|e| Failure::Input(e.to_string()))?;
    sc.initial
        .check_valid()
        .map_err(|e| Failure::Input(format!("{}: {e}", sc.name)))?;
    let mut run = AdaptiveRun::new(stepper, sc.initial, settings.t_end, eps)
        .map_err(|e| Failure::Input(format!("{}: {e}", sc.name)))?;
    // Pre-flight: a tiny ε or a huge t_end used to run without end.
    let bound = crate::shared::command::check_adaptive_steps(run.span(), run.control(), eps, args.max_steps)?;
    // The trajectory at the start's pace against the 4 GiB limit, as for fixed steps.
    if let Some((path, _)) = settings.output.as_ref().filter(|(p, _)| p != "-") {
        let (t0, t_end) = run.span();
        let steps = (t_end - t0) * run.control() / eps;
        super::check_trajectory_size(path, steps, settings.every, format, args.allow_large_output)?;
    }
    let first = liemid::Diagnostics::of(system, &sc.initial);
    let mut progress = RunSummary {
        state: sc.initial,
        steps: 0,
        initial: first,
        last: first,
        max_energy_error: 0.0,
        max_spatial_momentum_change: Vec3::ZERO,
        max_body_momentum_norm_change: 0.0,
        max_orthogonality_defect: first.orthogonality_defect,
    };
    let mut writer = match &settings.output {
        None => None,
        Some((path, _)) => Some(TrajectoryWriter::create(Path::new(path), format, &COLUMNS).map_err(Failure::Input)?),
    };
    let to_stdout = settings.output.as_ref().is_some_and(|(p, _)| p == "-");
    if let Some(w) = writer.as_mut() {
        w.write_row(&row(&sc.initial, &first)).map_err(Failure::Run)?;
    }
    let mut page = args.view.as_ref().map(|_| view_page(sc));
    if let Some(p) = page.as_mut() {
        view_frame(p, &sc.initial, &first, first.energy);
    }
    let mut max_conserved = 0.0f64;
    let started = Instant::now();
    let every = settings.every;
    let failure = loop {
        if run.is_done() {
            break None;
        }
        if run.stats().steps >= bound {
            break Some(format!(
                "the adaptive run reached {bound} steps (--max-steps) before t_end"
            ));
        }
        if let Err(e) = run.step() {
            break Some(format!("{}: {e}", sc.name));
        }
        let state = *run.state();
        let d = liemid::Diagnostics::of(system, &state);
        track(&mut progress, &d);
        if let Some(change) = conserved_change(conservation, first.spatial_momentum, d.spatial_momentum) {
            max_conserved = max_conserved.max(change);
        }
        let k = run.stats().steps;
        if k % every == 0 || run.is_done() {
            if let Some(p) = page.as_mut() {
                view_frame(p, &state, &d, first.energy);
            }
            if let Some(w) = writer.as_mut() {
                if let Err(e) = w.write_row(&row(&state, &d)) {
                    break Some(e);
                }
            }
        }
    };
    let wall = started.elapsed().as_secs_f64();
    if let Some(message) = failure {
        let kept = writer.map(|w| format!("; {}", w.keep_partial())).unwrap_or_default();
        return Err(Failure::Run(format!("{message}{kept}")));
    }
    let trajectory = writer.map(TrajectoryWriter::finish).transpose().map_err(Failure::Run)?;
    let stats = run.stats();
    progress.state = *run.state();
    progress.steps = stats.steps;
    let summary_run = Run {
        t0: sc.initial.t,
        t_end: settings.t_end,
        h: stats.max_step,
        total_steps: stats.steps,
        progress,
    };
    let viewed = write_view(page.as_ref(), args.view.as_deref(), stats.steps)?;
    print_summary(
        args,
        settings,
        sc,
        &summary_run,
        method,
        max_conserved,
        wall,
        trajectory,
        to_stdout,
        Some((stats, run.stepper.density_name())),
    )?;
    print_view_line(viewed, args.json.as_deref() == Some("-") || to_stdout);
    Ok(())
}
