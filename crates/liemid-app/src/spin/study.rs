//! The spin work-precision study of `liemid spins work-precision`: for every method a
//! sequence of halved steps, each run timed without observation and repeated with the
//! energy sampled every 10 steps; the largest relative energy error along the run, the
//! spins' error at `t_end` against a reference (the eighth-order splitting at a small step,
//! its own error estimated from the step twice as large), and the CPU time to reach energy
//! errors 1e-6 and 1e-8 and spin errors 1e-3 and 1e-6.

use liemid::spin::{SpinIntegrator, SpinMethod};
use liemid::Vec3;
use serde::Serialize;

use crate::shared::cpu_time::process_seconds;
use crate::shared::figure::{work_series, Axes, Figure};
use crate::spin::scenario::SpinScenario;

/// One run.
#[derive(Clone, Debug, Serialize)]
pub struct SpinPoint {
    /// Step (ps).
    pub step: f64,
    /// CPU time of the unobserved run (all the process's threads, median of up to three),
    /// seconds.
    pub seconds: f64,
    /// Largest `|E − E₀|/|E₀|`, sampled every 10 steps.
    pub max_relative_energy_error: f64,
    /// `max_i |S_i − S_i,ref|` at `t_end` (Euclidean norm per site).
    pub spin_error: f64,
    /// Largest `| |S_i| − 1 |` at `t_end`.
    pub norm_error: f64,
    /// `|Σ S_z(t_end) − Σ S_z(0)|`.
    pub sz_change: f64,
}

/// A method's sequence.
#[derive(Clone, Debug, Serialize)]
pub struct SpinCurve {
    /// Method key.
    pub name: String,
    /// Order.
    pub order: u32,
    /// Runs, largest step first.
    pub points: Vec<SpinPoint>,
}

/// CPU time of each method to reach an error level (log-log interpolation).
#[derive(Clone, Debug, Serialize)]
pub struct SpinTarget {
    /// `"energy"` or `"spins"`.
    pub measure: &'static str,
    /// The error level.
    pub error: f64,
    /// `(method, seconds)`, `None` where not reached.
    pub seconds: Vec<(String, Option<f64>)>,
}

/// The study.
#[derive(Clone, Debug, Serialize)]
pub struct SpinStudy {
    /// Problem or file.
    pub problem: String,
    /// Number of spins.
    pub spins: usize,
    /// End time (ps).
    pub t_end: f64,
    /// Threads.
    pub threads: usize,
    /// The reference's method and step.
    pub reference: String,
    /// Its estimated error (difference from the step twice as large).
    pub reference_error: f64,
    /// Per method.
    pub methods: Vec<SpinCurve>,
    /// CPU time to energy errors 1e-6, 1e-8 and spin errors 1e-3, 1e-6.
    pub targets: Vec<SpinTarget>,
}

fn run_to(
    sc: &SpinScenario,
    method: SpinMethod,
    h: f64,
    steps: u64,
    observe: bool,
) -> Result<(Vec<Vec3>, f64), String> {
    let mut s = sc.spins.clone();
    let mut integ = SpinIntegrator::new(method);
    let e0 = sc.system.energy(&s);
    let scale = if e0 != 0.0 { e0.abs() } else { 1.0 };
    let mut max_de = 0.0f64;
    let chunk = if observe { 10 } else { steps.max(1) };
    let mut done = 0;
    while done < steps {
        let k = chunk.min(steps - done);
        integ
            .advance(&sc.system, &mut s, done as f64 * h, h, k)
            .map_err(|e| format!("{} at h = {h}: {e}", method.key()))?;
        done += k;
        if observe {
            max_de = max_de.max(((sc.system.energy(&s) - e0) / scale).abs());
        }
    }
    Ok((s, max_de))
}

/// The trajectory error: `max_i |a_i − b_i|`, the Euclidean distance of the worst site (the
/// definition `benchmarks/vs_spirit.py` uses).
fn max_difference(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (*x - *y).norm()).fold(0.0, f64::max)
}

/// Time to reach `level` along points sorted by time (log-log interpolation).
fn time_to(points: &[SpinPoint], level: f64, error: impl Fn(&SpinPoint) -> f64) -> Option<f64> {
    let mut pts: Vec<&SpinPoint> = points.iter().collect();
    pts.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
    let mut prev: Option<&SpinPoint> = None;
    for p in pts {
        if error(p) <= level {
            return Some(match prev {
                Some(q) if error(q) > level && error(p) > 0.0 => {
                    let (a, b) = (error(q).ln(), error(p).ln());
                    let f = (level.ln() - a) / (b - a);
                    (q.seconds.ln() + f * (p.seconds.ln() - q.seconds.ln())).exp()
                }
                _ => p.seconds,
            });
        }
        prev = Some(p);
    }
    None
}

/// Run the study; each method's sequence stops once a run takes longer than `budget`
/// seconds, its spins' error is below 1e-10, or after 10 points.
///
/// # Errors
/// A failed run (a method's message with its step).
pub fn run(sc: &SpinScenario, methods: &[SpinMethod], budget: f64) -> Result<SpinStudy, String> {
    let t_end = sc.t_end;
    let reference_step = 2.5e-3;
    let steps_of = |h: f64| (t_end / h).round().max(1.0) as u64;
    let (reference, _) = run_to(
        sc,
        SpinMethod::Splitting8,
        t_end / steps_of(reference_step) as f64,
        steps_of(reference_step),
        false,
    )?;
    let (coarse, _) = run_to(
        sc,
        SpinMethod::Splitting8,
        t_end / steps_of(2.0 * reference_step) as f64,
        steps_of(2.0 * reference_step),
        false,
    )?;
    let reference_error = max_difference(&reference, &coarse);
    let sz0 = sc.system.total_spin(&sc.spins).z;
    let mut curves = Vec::new();
    for &method in methods {
        let mut points = Vec::new();
        // Each method from the step where its error is about 1e-3 to 1e-2: the compositions
        // are cheapest at much larger steps than Strang's.
        let mut h = match method {
            SpinMethod::Splitting4 => 0.125,
            SpinMethod::Splitting6 => 0.2,
            SpinMethod::Splitting8 => 0.3125,
            _ => 0.04,
        };
        for _ in 0..10 {
            let steps = steps_of(h);
            let step = t_end / steps as f64;
            // Warm up once, then time up to three runs (one when a run is long).
            let _ = run_to(sc, method, step, steps.min(50), false)?;
            let mut times = Vec::new();
            for _ in 0..3 {
                let start = process_seconds();
                run_to(sc, method, step, steps, false)?;
                let s = process_seconds() - start;
                times.push(s);
                if s > 0.3 {
                    break;
                }
            }
            times.sort_by(f64::total_cmp);
            let seconds = times[times.len() / 2];
            let (end, max_de) = run_to(sc, method, step, steps, true)?;
            points.push(SpinPoint {
                step,
                seconds,
                max_relative_energy_error: max_de,
                spin_error: max_difference(&end, &reference),
                norm_error: end.iter().map(|v| (v.norm() - 1.0).abs()).fold(0.0, f64::max),
                sz_change: (sc.system.total_spin(&end).z - sz0).abs(),
            });
            // The midpoint rule keeps the energy at every step, so its sequence ends on the
            // spins' error, like every other's.
            if seconds > budget || points.last().is_some_and(|p: &SpinPoint| p.spin_error < 1e-10) {
                break;
            }
            h /= 2.0;
        }
        curves.push(SpinCurve {
            name: method.key().to_string(),
            order: method.order(),
            points,
        });
    }
    let mut targets = Vec::new();
    for (measure, level) in [("energy", 1e-6), ("energy", 1e-8), ("spins", 1e-3), ("spins", 1e-6)] {
        let seconds = curves
            .iter()
            .map(|c| {
                let t = if measure == "energy" {
                    time_to(&c.points, level, |p| p.max_relative_energy_error)
                } else {
                    time_to(&c.points, level, |p| p.spin_error)
                };
                (c.name.clone(), t)
            })
            .collect();
        targets.push(SpinTarget {
            measure,
            error: level,
            seconds,
        });
    }
    Ok(SpinStudy {
        problem: sc.name.clone(),
        spins: sc.spins.len(),
        t_end,
        threads: rayon::current_num_threads(),
        reference: format!("split8 at h = {reference_step} ps"),
        reference_error,
        methods: curves,
        targets,
    })
}

/// The study as a table.
#[must_use]
pub fn table(study: &SpinStudy) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: {} spins to t = {} ps on {} thread(s); reference {} (estimated error {:.1e})",
        study.problem, study.spins, study.t_end, study.threads, study.reference, study.reference_error
    );
    let _ = writeln!(
        s,
        "{:<9} {:>9} {:>10} {:>12} {:>11} {:>10} {:>10}",
        "method", "step", "seconds", "max dE/E", "spin error", "||S|-1|", "dSz"
    );
    for c in &study.methods {
        for p in &c.points {
            let _ = writeln!(
                s,
                "{:<9} {:>9.3e} {:>10.3e} {:>12.3e} {:>11.3e} {:>10.1e} {:>10.1e}",
                c.name, p.step, p.seconds, p.max_relative_energy_error, p.spin_error, p.norm_error, p.sz_change
            );
        }
    }
    for t in &study.targets {
        let _ = write!(s, "CPU time to {} error {:.0e}:", t.measure, t.error);
        for (name, secs) in &t.seconds {
            match secs {
                Some(x) => {
                    let _ = write!(s, " {name} {x:.3e} s;");
                }
                None => {
                    let _ = write!(s, " {name} -;");
                }
            }
        }
        s.push('\n');
    }
    s
}

impl SpinStudy {
    /// The figure: the largest energy error and the spin error at `t_end` against CPU time.
    pub fn figure(&self) -> Figure<'static> {
        let curves = || self.methods.iter().map(|c| (c.name.as_str(), c.points.as_slice()));
        let axes = |title, y_desc| Axes {
            title,
            x_desc: "CPU time (s)",
            y_desc,
            slopes: false,
        };
        Figure {
            title: format!(
                "{}: {} spins, work-precision to t = {} ps",
                self.problem, self.spins, self.t_end
            ),
            labels: self.methods.iter().map(|m| m.name.clone()).collect(),
            panels: [
                (
                    axes("largest energy error along the run", "max |E - E0| / |E0|"),
                    work_series(curves(), |p| p.seconds, |p| p.max_relative_energy_error),
                ),
                (
                    axes("spins at t_end", "max |S_i - S_i,ref|"),
                    work_series(curves(), |p| p.seconds, |p| p.spin_error),
                ),
            ],
        }
    }
}
