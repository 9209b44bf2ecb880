//! `liemid spins`: run a spin-dynamics scenario (built-in or TOML), write the energy and
//! magnetisation time series, the final spins and a snapshot; `liemid spins
//! work-precision`: CPU time against energy and trajectory error for every spin method.

use std::path::{Path, PathBuf};
use std::time::Instant;

use liemid::error::Num;
use liemid::spin::{SpinIntegrator, SpinMethod};
use liemid::Vec3;
use serde_json::json;

use crate::shared::command::{CmdResult, Failure};
use crate::shared::interrupt::{progress, Interrupt};
use crate::shared::output::Format;
use crate::shared::output::{plural, write_atomically, OutputPlan, TrajectoryWriter};
use crate::shared::view::{self, Scene, ViewPage};
use crate::spin::scenario::{self, SpinScenario};
use crate::spin::study;

/// Columns of the time series.
const COLUMNS: [&str; 5] = ["t", "energy", "mx", "my", "mz"];

/// Arguments of `liemid spins`.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true)]
pub struct SpinsArgs {
    #[command(subcommand)]
    pub command: Option<SpinsCommand>,
    /// Scenario file (TOML); without it, `--problem`.
    pub file: Option<PathBuf>,
    #[command(flatten)]
    pub common: CommonArgs,
    /// Spin method [default: the file's, else split; midpoint with damping].
    #[arg(long)]
    pub method: Option<String>,
    /// Step (ps) [default: the scenario's].
    #[arg(long, allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// Write t, energy and the mean spin every `--every` steps (CSV or .npy by extension,
    /// `-` for standard output).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Interval of the time series and of the energy check, in steps [default: 10].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub every: Option<u64>,
    /// Write the final spins, shape (N, 3) in site order, to this .npy file.
    #[arg(long = "final")]
    pub final_spins: Option<PathBuf>,
    /// Write a PNG of the final in-plane angle of a 2-D lattice.
    #[arg(long)]
    pub snapshot: Option<PathBuf>,
    /// Write the summary as JSON to FILE, or to standard output with `-` or no value.
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<String>,
    /// Refuse runs of more than N spin-steps (spins × steps; exit 2) before the first step.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_spin_steps: Option<u64>,
    /// Refuse runs of more than N steps (exit 2) before the first step [default: 10⁹].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_steps: Option<u64>,
    /// Write a self-contained 3-D animation of the run (HTML) to FILE, sampled every
    /// `--every` steps (frames subsampled to the page's byte budget).
    #[arg(long)]
    pub view: Option<PathBuf>,
}

/// Options shared by the run and the study.
#[derive(clap::Args, Debug)]
pub struct CommonArgs {
    /// Built-in problem (`square-64`, `chain-64`, `skyrmion`) when no file is given.
    #[arg(long)]
    pub problem: Option<String>,
    /// End time (ps) [default: the scenario's].
    #[arg(long, allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Threads [default: all cores]; results are identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub threads: Option<u64>,
}

/// Subcommands of `liemid spins`.
#[derive(clap::Subcommand, Debug)]
pub enum SpinsCommand {
    /// CPU time against energy error and trajectory error for every spin method.
    WorkPrecision(WorkPrecisionArgs),
}

/// Arguments of `liemid spins work-precision`.
#[derive(clap::Args, Debug)]
pub struct WorkPrecisionArgs {
    /// Scenario file (TOML); without it, `--problem` [default: square-64].
    pub file: Option<PathBuf>,
    #[command(flatten)]
    pub common: CommonArgs,
    /// Comma-separated spin methods [default: all].
    #[arg(long, value_delimiter = ',')]
    pub methods: Option<Vec<String>>,
    /// Stop a method's sequence once one run takes longer than this many seconds.
    #[arg(long, allow_negative_numbers = true, default_value_t = 3.0)]
    pub budget: f64,
    /// Plot file: NAME writes NAME.svg and NAME.png; NAME.svg or NAME.png writes one.
    #[arg(long, default_value = "spin-work-precision")]
    pub plot: PathBuf,
    /// Write no plot.
    #[arg(long)]
    pub no_plot: bool,
    /// Write the study as JSON to FILE, or to standard output with `-` or no value.
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<String>,
}

fn load(file: Option<&Path>, common: &CommonArgs) -> Result<SpinScenario, Failure> {
    let mut sc = match (file, &common.problem) {
        (Some(_), Some(_)) => return Err(Failure::Input("give a scenario file or --problem, not both".into())),
        (Some(f), None) => scenario::load(f),
        (None, p) => scenario::builtin(p.as_deref().unwrap_or("square-64")),
    }
    .map_err(Failure::Input)?;
    if let Some(t) = common.t_end {
        sc.t_end = t;
    }
    if !(sc.t_end.is_finite() && sc.t_end > 0.0) {
        return Err(Failure::Input(format!(
            "t_end must be a positive number of ps, found {}",
            sc.t_end
        )));
    }
    Ok(sc)
}

/// A thread pool of `threads` (at most four per core), or of all cores.
pub(crate) fn pool(threads: Option<u64>) -> Result<rayon::ThreadPool, Failure> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(k) = threads {
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        b = b.num_threads(usize::try_from(k).unwrap_or(usize::MAX).min(4 * cores));
    }
    b.build().map_err(|e| Failure::Run(format!("thread pool: {e}")))
}

/// Run `liemid spins`.
pub fn spins(args: SpinsArgs) -> CmdResult {
    if let Some(SpinsCommand::WorkPrecision(wp)) = args.command {
        return work_precision(wp);
    }
    let input = Failure::Input;
    let mut sc = load(args.file.as_deref(), &args.common)?;
    if let Some(m) = &args.method {
        sc.method = scenario::parse_method(m).map_err(input)?;
    }
    if let Some(h) = args.step {
        sc.step = h;
    }
    if !(sc.step.is_finite() && sc.step > 0.0) {
        return Err(input(format!(
            "the step must be a positive number of ps, found {}",
            sc.step
        )));
    }
    let steps = liemid::step_count(0.0, sc.t_end, sc.step)
        .map_err(|e| input(format!("step {} and t_end {}: {e}", Num(sc.step), Num(sc.t_end))))?;
    crate::shared::command::check_steps(steps, args.max_steps)?;
    if let Some(max) = args.max_spin_steps {
        let work = steps as f64 * sc.system.len() as f64;
        if work > max as f64 {
            return Err(input(format!(
                "the run would take {work:e} spin-steps ({} spins × {steps} steps), more than --max-spin-steps {max}",
                sc.system.len()
            )));
        }
    }
    let every = args.every.or(sc.every).unwrap_or(10);
    let out = args.out.clone().or(sc.out.clone());
    let inputs: Vec<&Path> = args
        .file
        .iter()
        .map(PathBuf::as_path)
        .chain(sc.inputs.iter().map(PathBuf::as_path))
        .collect();
    let mut plan = OutputPlan::new(&inputs);
    if let Some(p) = out.as_deref().filter(|p| p != &Path::new("-")) {
        plan.add("--out", p).map_err(input)?;
    }
    if let Some(p) = &args.final_spins {
        plan.add("--final", p).map_err(input)?;
    }
    if let Some(p) = &args.snapshot {
        if p.extension().and_then(|x| x.to_str()) != Some("png") {
            return Err(input(format!("--snapshot {}: use a .png file name", p.display())));
        }
        if sc.system.lattice.size()[2] != 1 || sc.system.lattice.kind() == liemid::spin::LatticeKind::Chain {
            return Err(input("--snapshot draws a 2-D (square) lattice".into()));
        }
        plan.add("--snapshot", p).map_err(input)?;
    }
    if let Some(j) = args.json.as_deref().filter(|j| *j != "-") {
        plan.add("--json", Path::new(j)).map_err(input)?;
    }
    if let Some(p) = &args.view {
        plan.add("--view", p).map_err(input)?;
    }
    let format = match out.as_deref().and_then(|p| p.extension()).and_then(|x| x.to_str()) {
        Some("npy") => Format::Npy,
        _ => Format::Csv,
    };
    let pool = pool(args.common.threads)?;
    let threads = pool.current_num_threads();
    let interrupt = Interrupt::install();
    let system = &sc.system;
    let n = system.len();
    let e0 = system.energy(&sc.spins);
    let sz0 = system.total_spin(&sc.spins).z;
    // The topological charge on square lattices (at the start and the end).
    let charge = |s: &[Vec3]| liemid::spin::topological_charge(system, s).ok();
    let q0 = charge(&sc.spins);
    let scale = if e0 != 0.0 { e0.abs() } else { 1.0 };
    let mut writer = match &out {
        Some(p) => Some(TrajectoryWriter::create(p, format, &COLUMNS).map_err(Failure::Run)?),
        None => None,
    };
    let keep = |w: Option<TrajectoryWriter>| w.map(|w| format!("; {}", w.keep_partial())).unwrap_or_default();
    let mut spins = sc.spins.clone();
    let mut integ = SpinIntegrator::new(sc.method);
    let (mut max_de, mut max_norm, mut max_sz) = (0.0f64, 0.0f64, 0.0f64);
    let mut page = args.view.as_ref().map(|_| {
        let sites = view::lattice_sites(&system.lattice);
        let mut page = ViewPage::new(Scene::Spins { sites }, &format!("{} ({n} spins)", sc.name));
        if system.damping > 0.0 {
            page.set_energy_label("relative energy change (damped: not conserved)");
        }
        page
    });
    let mut observe = |s: &[Vec3], t: f64, w: &mut Option<TrajectoryWriter>| -> Result<(), String> {
        let e = system.energy(s);
        if let Some(p) = page.as_mut() {
            p.energy_error(t, (e - e0) / scale);
            let frame: Vec<f32> = s.iter().flat_map(|v| v.to_array().map(|x| x as f32)).collect();
            p.push_frame(t, &frame);
        }
        let m = system.total_spin(s) * (1.0 / n as f64);
        max_de = max_de.max(((e - e0) / scale).abs());
        max_norm = max_norm.max(s.iter().map(|v| (v.norm() - 1.0).abs()).fold(0.0, f64::max));
        max_sz = max_sz.max((m.z * n as f64 - sz0).abs());
        if let Some(w) = w.as_mut() {
            w.write_row(&[t, e, m.x, m.y, m.z])?;
        }
        Ok(())
    };
    if let Err(e) = observe(&spins, 0.0, &mut writer) {
        return Err(Failure::Run(format!("{e}{}", keep(writer))));
    }
    let bar = progress(steps, "steps", steps as f64 * n as f64 >= 2e8);
    let start = Instant::now();
    let mut done = 0u64;
    while done < steps {
        if let Some((signal, code)) = interrupt.requested() {
            bar.finish_and_clear();
            return Err(Failure::Signal(
                code,
                format!(
                    "{signal}: stopped at t = {} ps after {done} of {steps} steps{}",
                    Num(done as f64 * sc.step),
                    keep(writer)
                ),
            ));
        }
        let k = every.min(steps - done);
        let t = done as f64 * sc.step;
        let result = pool.install(|| integ.advance(system, &mut spins, t, sc.step, k));
        if let Err(e) = result {
            bar.finish_and_clear();
            return Err(Failure::Run(format!("{e}{}", keep(writer))));
        }
        done += k;
        if let Err(e) = observe(&spins, done as f64 * sc.step, &mut writer) {
            return Err(Failure::Run(format!("{e}{}", keep(writer))));
        }
        bar.set_position(done);
    }
    let seconds = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    if let Some(w) = writer {
        w.finish().map_err(Failure::Run)?;
    }
    let viewed = match (&page, &args.view) {
        (Some(p), Some(path)) => Some(view::report(path, p.write(path, steps).map_err(Failure::Run)?, steps)),
        _ => None,
    };
    if let Some(p) = &args.final_spins {
        let flat: Vec<f64> = spins.iter().flat_map(|s| s.to_array()).collect();
        write_atomically(p, &crate::shared::npy::matrix_bytes(n, 3, &flat))
            .map_err(|e| Failure::Run(format!("{}: cannot write: {e}", p.display())))?;
    }
    if let Some(p) = &args.snapshot {
        crate::shared::plot::spin_snapshot(
            p,
            &sc.system.lattice.size(),
            &spins,
            &format!("{}: in-plane angle at t = {} ps", sc.name, Num(done as f64 * sc.step)),
        )
        .map_err(Failure::Run)?;
    }
    let e1 = system.energy(&spins);
    let q1 = charge(&spins);
    let m = system.total_spin(&spins) * (1.0 / n as f64);
    let rate = (steps as f64 * n as f64) / seconds;
    let summary = json!({
        "problem": sc.name,
        "method": sc.method.key(),
        "spins": n,
        "steps": steps,
        "step": sc.step,
        "t_end": sc.t_end,
        "threads": threads,
        "damping": system.damping,
        "seconds": seconds,
        "spin_steps_per_second": rate,
        "energy": [e0, e1],
        "max_relative_energy_error": max_de,
        "energy_error_sampled_every": every,
        "max_norm_error": max_norm,
        "sz_total_change": max_sz,
        "sz_conserved_by_the_hamiltonian": system.conserves_sz() && system.damping == 0.0,
        "magnetisation": m.to_array(),
        "dmi": system.dmi_vectors().is_some(),
        "topological_charge": q0.zip(q1).map(|(a, b)| [a, b]),
        "midpoint_iterations_per_step": if sc.method == SpinMethod::Midpoint { json!(integ.iterations as f64 / steps.max(1) as f64) } else { json!(null) },
    });
    match args.json.as_deref() {
        Some("-") => crate::outln!("{summary}"),
        Some(path) => {
            write_atomically(Path::new(path), (summary.to_string() + "\n").as_bytes())
                .map_err(|e| Failure::Run(format!("{path}: cannot write: {e}")))?;
        }
        None => {}
    }
    if args.json.as_deref() != Some("-") && out.as_deref() != Some(Path::new("-")) {
        crate::outln!(
            "{} ({}): {n} spins, {steps} {} of {} ps to t = {} ps on {threads} {}: {seconds:.3} s, {rate:.3e} spin-steps/s",
            sc.name,
            sc.method.key(),
            plural(steps, "step", "steps"),
            Num(sc.step),
            Num(done as f64 * sc.step),
            plural(threads as u64, "thread", "threads"),
        );
        crate::outln!(
            "max relative energy error (every {every} {})  {max_de:.3e}",
            plural(every, "step", "steps")
        );
        crate::outln!("max | |S_i| - 1 |                         {max_norm:.3e}");
        if system.conserves_sz() && system.damping == 0.0 {
            crate::outln!("max |sum S_z - sum S_z(0)| (conserved)    {max_sz:.3e}");
        } else {
            crate::outln!("change of sum S_z (not conserved here)    {max_sz:.3e}");
        }
        if let (Some(a), Some(b)) = (q0, q1) {
            crate::outln!("topological charge {a:.6} -> {b:.6}");
        }
        crate::outln!(
            "energy {} -> {} meV, mean spin [{:.6}, {:.6}, {:.6}]",
            Num(e0),
            Num(e1),
            m.x,
            m.y,
            m.z
        );
    }
    if let Some(line) = viewed {
        if args.json.as_deref() == Some("-") || out.as_deref() == Some(Path::new("-")) {
            eprintln!("{line}");
        } else {
            crate::outln!("{line}");
        }
    }
    Ok(())
}

/// Run `liemid spins work-precision`.
fn work_precision(args: WorkPrecisionArgs) -> CmdResult {
    let input = Failure::Input;
    let sc = load(args.file.as_deref(), &args.common)?;
    let methods: Vec<SpinMethod> = match &args.methods {
        None => SpinMethod::ALL
            .into_iter()
            .filter(|m| sc.system.damping == 0.0 || m.handles_damping())
            .collect(),
        Some(list) => list
            .iter()
            .map(|m| scenario::parse_method(m))
            .collect::<Result<_, _>>()
            .map_err(input)?,
    };
    if !(args.budget.is_finite() && args.budget > 0.0) {
        return Err(input(format!(
            "--budget must be a positive number of seconds, found {}",
            args.budget
        )));
    }
    let mut plan = OutputPlan::new(&[]);
    let plot_paths = if args.no_plot {
        Vec::new()
    } else {
        crate::shared::plot::plot_paths(&args.plot)
    };
    for p in &plot_paths {
        plan.add("--plot", p).map_err(input)?;
    }
    if let Some(j) = args.json.as_deref().filter(|j| *j != "-") {
        plan.add("--json", Path::new(j)).map_err(input)?;
    }
    let pool = pool(args.common.threads)?;
    let study = pool
        .install(|| study::run(&sc, &methods, args.budget))
        .map_err(Failure::Run)?;
    let table = study::table(&study);
    if args.json.as_deref() == Some("-") {
        eprint!("{table}");
        crate::outln!("{}", serde_json::to_string(&study).expect("serialisable"));
    } else {
        crate::out!("{table}");
        if let Some(path) = args.json.as_deref() {
            write_atomically(
                Path::new(path),
                (serde_json::to_string_pretty(&study).expect("serialisable") + "\n").as_bytes(),
            )
            .map_err(|e| Failure::Run(format!("{path}: cannot write: {e}")))?;
            crate::outln!("wrote {path}");
        }
    }
    for p in &plot_paths {
        crate::shared::plot::write(p, &study.figure()).map_err(Failure::Run)?;
        if args.json.as_deref() != Some("-") {
            crate::outln!("wrote {}", p.display());
        }
    }
    Ok(())
}

/// `liemid methods --spins`: the spin methods, as a table or JSON.
pub fn methods(json: bool) {
    if json {
        let list: Vec<_> = SpinMethod::ALL
            .iter()
            .map(|m| {
                json!({
                    "name": m.key(),
                    "order": m.order(),
                    "field_evaluations_per_step": m.field_evaluations(),
                    "damping": m.handles_damping(),
                    "description": m.description(),
                })
            })
            .collect();
        crate::outln!("{}", serde_json::Value::Array(list));
        return;
    }
    crate::outln!(
        "{:<9} {:>5}  {:<28} {:<7} conserves",
        "name",
        "order",
        "field evaluations/step",
        "damping"
    );
    for m in SpinMethod::ALL {
        crate::outln!(
            "{:<9} {:>5}  {:<28} {:<7} {}",
            m.key(),
            m.order(),
            m.field_evaluations(),
            if m.handles_damping() { "yes" } else { "no" },
            m.description()
        );
    }
}
