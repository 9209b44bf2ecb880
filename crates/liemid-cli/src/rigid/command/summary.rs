//! The summary of `liemid run` (fixed or adaptive steps): text, or one JSON object with
//! `--json`, and what the scenario conserves.

use liemid::error::Num;
use liemid::rigid::adaptive::AdaptiveStats;
use liemid::{RotationMethod, Run};
use serde_json::json;

use super::RunArgs;
use crate::rigid::scenario::{Conservation, Scenario};
use crate::shared::checkpoint::Settings;
use crate::shared::command::{emit_json, CmdResult};
use crate::shared::output::plural;

/// Print the summary (text, or one JSON object with `--json -`), to standard error when the
/// trajectory goes to standard output; with `--json FILE` the JSON object goes to FILE and
/// the text is printed.
#[allow(clippy::too_many_arguments)]
pub(super) fn print_summary(
    args: &RunArgs,
    settings: &Settings,
    sc: &Scenario,
    run: &Run,
    method: RotationMethod,
    max_conserved: f64,
    wall: f64,
    trajectory: Option<(String, u64)>,
    to_stdout: bool,
    adaptive: Option<(AdaptiveStats, &str)>,
) -> CmdResult {
    let summary = run.summary();
    let s = &summary.state;
    let conservation = sc.system.conservation();
    let n = run.total_steps;
    let last_step = if let Some((a, _)) = &adaptive {
        a.last_step
    } else if n == 0 {
        0.0
    } else {
        run.t_end - (run.t0 + (n - 1) as f64 * run.h)
    };
    let energy_note = match conservation {
        Conservation::Driven => "not conserved: the constant torque does work",
        _ => "conserved by the dynamics: the error is the method's",
    };
    let momentum_note = match conservation {
        Conservation::Free => "all components conserved (torque-free)".to_string(),
        Conservation::Gravity(g) => format!(
            "only the component along gravity [{:.3}, {:.3}, {:.3}] is conserved",
            g.x, g.y, g.z
        ),
        Conservation::Driven => "not conserved: the torque changes it".to_string(),
    };
    let warn_energy =
        adaptive.is_none() && !matches!(conservation, Conservation::Driven) && summary.max_energy_error > 1e-2;
    if warn_energy {
        eprintln!(
            "liemid: warning: the relative energy error reached {:.3e}; the step h = {} is probably too \
             large for this problem",
            summary.max_energy_error,
            Num(settings.step)
        );
    }
    if let Some(target) = args.json.as_deref() {
        let mut out = json!({
            "problem": sc.name,
            "method": method.key(),
            "step": settings.step,
            "last_step": last_step,
            "t": s.t,
            "pi": s.pi.to_array(),
            "rotation": s.rotation.to_row_major(),
            "steps": summary.steps,
            "energy": [summary.initial.energy, summary.last.energy],
            "energy_conserved": !matches!(conservation, Conservation::Driven),
            "max_energy_error": summary.max_energy_error,
            "max_spatial_momentum_change": summary.max_spatial_momentum_change.to_array(),
            "conserved_momentum": momentum_note,
            "max_conserved_momentum_change": match conservation {
                Conservation::Driven => json!(null),
                _ => json!(max_conserved),
            },
            "max_orthogonality_defect": summary.max_orthogonality_defect,
            "wall_time_seconds": wall,
            "trajectory": trajectory.as_ref().map(|(p, rows)| json!({
                "path": p,
                "rows": rows,
                "format": settings.output.as_ref().map(|(_, f)| f.as_str()),
            })),
        });
        if let (Some((a, rho)), Some(map)) = (&adaptive, out.as_object_mut()) {
            map.insert("step".into(), json!(null));
            map.insert(
                "adaptive".into(),
                json!({"eps": a.eps, "rho": rho, "min_step": a.min_step, "max_step": a.max_step}),
            );
        }
        match target {
            "-" if to_stdout => eprintln!("{out}"),
            "-" => crate::outln!("{out}"),
            file => emit_json(Some(file), &out)?,
        }
        if target == "-" {
            return Ok(());
        }
    }
    let mut text = String::new();
    let mut line = |l: String| {
        text.push_str(&l);
        text.push('\n');
    };
    let r = s.rotation.m;
    let dm = summary.max_spatial_momentum_change;
    let step_text = if let Some((a, rho)) = &adaptive {
        format!(
            "adaptive steps, eps = {} (rho = {rho}), from {} to {} (the last {})",
            Num(a.eps),
            Num(a.min_step),
            Num(a.max_step),
            Num(a.last_step)
        )
    } else if n == 1 && last_step < settings.step {
        format!(
            "one step of {} (the given step {} is longer than the interval)",
            Num(last_step),
            Num(settings.step)
        )
    } else if n > 1 && (last_step - settings.step).abs() > 1e-9 * settings.step {
        format!("h = {} (the last step {})", Num(settings.step), Num(last_step))
    } else {
        format!("h = {}", Num(settings.step))
    };
    line(format!(
        "{}: {} with {step_text} to t = {}",
        sc.name,
        method.name(),
        Num(s.t)
    ));
    line(format!("steps                          {}", summary.steps));
    line(format!(
        "final Pi (kg m^2/s)            [{:.12e}, {:.12e}, {:.12e}]",
        s.pi.x, s.pi.y, s.pi.z
    ));
    for (i, row) in r.iter().enumerate() {
        let label = if i == 0 { "final R" } else { "" };
        line(format!(
            "{label:<30} [{:>19.12e}, {:>19.12e}, {:>19.12e}]",
            row[0], row[1], row[2]
        ));
    }
    line(format!(
        "energy (J)                     {:.9e} at the start; {energy_note}",
        summary.initial.energy
    ));
    let label = match conservation {
        Conservation::Driven => "max relative energy change     ",
        _ => "max relative energy error      ",
    };
    line(format!("{label}{:.3e}", summary.max_energy_error));
    line(format!("spatial momentum pi            {momentum_note}"));
    line(format!(
        "max change of pi (kg m^2/s)    [{:.3e}, {:.3e}, {:.3e}]",
        dm.x, dm.y, dm.z
    ));
    if let Conservation::Gravity(_) = conservation {
        line(format!("max change of pi along gravity {max_conserved:.3e}"));
    }
    line(format!(
        "max orthogonality defect       {:.3e}",
        summary.max_orthogonality_defect
    ));
    line(format!("wall time                      {wall:.3} s"));
    if let Some((p, rows)) = &trajectory {
        line(format!(
            "trajectory                     {p} ({rows} {})",
            plural(*rows, "row", "rows")
        ));
    }
    if to_stdout {
        eprint!("{text}");
    } else {
        crate::out!("{text}");
    }
    Ok(())
}
