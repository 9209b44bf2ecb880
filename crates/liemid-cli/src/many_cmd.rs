//! `liemid many`: step an ensemble of rigid bodies in parallel and report throughput and
//! conservation.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use liemid::many::{Bodies, Interaction, Totals, BYTES_PER_BODY};
use liemid::problems;
use serde_json::json;

/// Which built-in many-body model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Model {
    /// Fast Lagrangian tops in uniform gravity, each about its own pivot.
    Independent,
    /// Torque-free asymmetric rotors.
    TorqueFree,
    /// A dipolar fluid: point dipoles with WCA repulsion in a periodic box.
    Dipoles,
}

/// Arguments of `liemid many`.
#[derive(clap::Args, Debug)]
pub struct ManyArgs {
    /// Scenario file (TOML) with `[system] model, bodies, seed, density, cutoff,
    /// switch_start`,
    /// `[integrator] step, t_end` and `[output] path, every`; command-line options win.
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// The interaction model [default: independent].
    #[arg(long, value_enum)]
    pub model: Option<Model>,
    /// Number of bodies [default: 1000].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub bodies: Option<u64>,
    /// End time [default: 0.01 for tops, 0.1 torque-free, 1 for dipoles].
    #[arg(long, allow_negative_numbers = true)]
    pub t_end: Option<f64>,
    /// Step [default: 1e-4 for tops, 1e-3 otherwise].
    #[arg(long, allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// Threads [default: all cores]; results are identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub threads: Option<u64>,
    /// Seed of the initial conditions [default: 1].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Number density of the dipolar fluid [default: 0.3].
    #[arg(long, allow_negative_numbers = true)]
    pub density: Option<f64>,
    /// Cutoff of the dipolar fluid's pair sum [default: 3]; without a box of at least twice
    /// the cutoff, all pairs in open space.
    #[arg(long, allow_negative_numbers = true)]
    pub cutoff: Option<f64>,
    /// Where the dipole energy starts to be switched off [default: 0.8 × cutoff]; equal to
    /// the cutoff, a plain truncation.
    #[arg(long, allow_negative_numbers = true)]
    pub switch_start: Option<f64>,
    /// Write the summary as JSON to FILE, or to standard output with `-`.
    #[arg(long)]
    pub json: Option<String>,
    /// Write the totals (t, energy, P, L) every `--every` steps to this CSV file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Interval of the totals file, in steps [default: 10].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub every: Option<u64>,
}

/// The settings of a run, from the scenario file and the command line.
struct Settings {
    model: Model,
    bodies: usize,
    seed: u64,
    density: f64,
    cutoff: Option<f64>,
    switch_start: Option<f64>,
    step: Option<f64>,
    t_end: Option<f64>,
    out: Option<PathBuf>,
    every: u64,
}

fn settings(args: &ManyArgs) -> Result<Settings, String> {
    let mut s = Settings {
        model: Model::Independent,
        bodies: 1000,
        seed: 1,
        density: 0.3,
        cutoff: None,
        switch_start: None,
        step: None,
        t_end: None,
        out: None,
        every: 10,
    };
    if let Some(path) = &args.scenario {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| format!("{file}: cannot read: {e}"))?;
        let mut parse = || -> Result<(), String> {
            let root = crate::scenario::parse_table(&text)?;
            for key in root.keys() {
                if !["system", "integrator", "output"].contains(&key.as_str()) {
                    return Err(format!(
                        "unknown section or key `{key}` (sections: system, integrator, output)"
                    ));
                }
            }
            use crate::scenario::Section;
            if let Some(sys) = Section::new(
                &root,
                "system",
                &["model", "bodies", "seed", "density", "cutoff", "switch_start"],
                true,
            )? {
                if let Some(m) = sys.string("model")? {
                    s.model = match m {
                        "independent" => Model::Independent,
                        "torque-free" => Model::TorqueFree,
                        "dipoles" => Model::Dipoles,
                        other => {
                            return Err(sys.err(
                                "model",
                                format!("unknown model \"{other}\" (independent, torque-free, dipoles)"),
                            ))
                        }
                    };
                }
                if let Some(n) = sys.count("bodies")? {
                    s.bodies = n as usize;
                }
                if let Some(n) = sys.count("seed")? {
                    s.seed = n;
                }
                if let Some(d) = sys.number("density")? {
                    s.density = d;
                }
                s.cutoff = sys.number("cutoff")?;
                s.switch_start = sys.number("switch_start")?;
            }
            if let Some(integ) = Section::new(&root, "integrator", &["step", "t_end"], false)? {
                s.step = integ.number("step")?;
                s.t_end = integ.number("t_end")?;
            }
            if let Some(out) = Section::new(&root, "output", &["path", "every"], false)? {
                s.out = out.string("path")?.map(PathBuf::from);
                if let Some(e) = out.count("every")? {
                    s.every = e;
                }
            }
            Ok(())
        };
        parse().map_err(|e| format!("{file}: {e}"))?;
    }
    if let Some(m) = args.model {
        s.model = m;
    }
    if let Some(n) = args.bodies {
        s.bodies = n as usize;
    }
    if let Some(v) = args.seed {
        s.seed = v;
    }
    if let Some(v) = args.density {
        s.density = v;
    }
    if args.cutoff.is_some() {
        s.cutoff = args.cutoff;
    }
    if args.switch_start.is_some() {
        s.switch_start = args.switch_start;
    }
    if s.model != Model::Dipoles && (s.cutoff.is_some() || s.switch_start.is_some()) {
        return Err("cutoff and switch_start apply to the dipoles model only".into());
    }
    if args.step.is_some() {
        s.step = args.step;
    }
    if args.t_end.is_some() {
        s.t_end = args.t_end;
    }
    if args.out.is_some() {
        s.out = args.out.clone();
    }
    if let Some(e) = args.every {
        s.every = e;
    }
    Ok(s)
}

fn run_model<I: Interaction>(
    args: &Settings,
    mut bodies: Bodies,
    model: &I,
    h: f64,
    steps: u64,
) -> Result<(Bodies, Totals, Totals, f64, f64), String> {
    bodies.evaluate(model);
    let first = bodies.totals(model);
    let mut out = match &args.out {
        Some(p) => {
            let partial = crate::output::partial_path(p);
            let mut f = std::io::BufWriter::new(
                std::fs::File::create(&partial).map_err(|e| format!("{}: cannot create: {e}", partial.display()))?,
            );
            writeln!(f, "t,energy,px,py,pz,lx,ly,lz").map_err(|e| e.to_string())?;
            Some((f, partial, p.clone()))
        }
        None => None,
    };
    let mut max_de = 0.0f64;
    let mut write =
        |b: &Bodies, out: &mut Option<(std::io::BufWriter<std::fs::File>, PathBuf, PathBuf)>| -> Result<(), String> {
            let tot = b.totals(model);
            let de = ((tot.energy - first.energy) / first.energy).abs();
            max_de = max_de.max(de);
            if let Some((f, _, _)) = out.as_mut() {
                let (p, l) = (tot.linear_momentum, tot.angular_momentum);
                writeln!(
                    f,
                    "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
                    b.t, tot.energy, p.x, p.y, p.z, l.x, l.y, l.z
                )
                .map_err(|e| e.to_string())?;
            }
            Ok(())
        };
    write(&bodies, &mut out)?;
    let mut stepping = 0.0;
    for k in 1..=steps {
        let start = Instant::now();
        bodies.step(model, h).map_err(|e| format!("step {k}: {e}"))?;
        stepping += start.elapsed().as_secs_f64();
        if k % args.every == 0 || k == steps {
            write(&bodies, &mut out)?;
        }
    }
    if let Some((mut f, partial, path)) = out {
        f.flush().map_err(|e| e.to_string())?;
        drop(f);
        std::fs::rename(&partial, &path).map_err(|e| e.to_string())?;
    }
    let last = bodies.totals(model);
    Ok((bodies, first, last, stepping, max_de))
}

/// Run `liemid many`; errors are (exit code, message).
pub fn many(cli: &ManyArgs) -> Result<(), (u8, String)> {
    let input = |m: String| (2u8, m);
    let args = &settings(cli).map_err(input)?;
    let n = args.bodies;
    let (h_default, t_default) = match args.model {
        Model::Independent => (1e-4, 0.01),
        Model::TorqueFree => (1e-3, 0.1),
        Model::Dipoles => (1e-3, 1.0),
    };
    let h = args.step.unwrap_or(h_default);
    let t_end = args.t_end.unwrap_or(t_default);
    if !(h.is_finite() && h > 0.0) {
        return Err(input(format!("--step must be a positive number, found {h}")));
    }
    if !(t_end.is_finite() && t_end >= 0.0) {
        return Err(input(format!("--t-end must be a non-negative number, found {t_end}")));
    }
    let steps = liemid::step_count(0.0, t_end, h).map_err(|e| input(e.to_string()))?;
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(k) = cli.threads {
        builder = builder.num_threads(k as usize);
    }
    let pool = builder.build().map_err(|e| (1, format!("thread pool: {e}")))?;
    let threads = pool.current_num_threads();
    let failed = |m: String| (1u8, m);
    let result = pool.install(|| match args.model {
        Model::Independent => {
            let (b, m) = problems::top_ensemble(n, args.seed);
            run_model(args, b, &m, h, steps).map_err(failed)
        }
        Model::TorqueFree => {
            let (b, m) = problems::torque_free_ensemble(n, args.seed);
            run_model(args, b, &m, h, steps).map_err(failed)
        }
        Model::Dipoles => {
            // A bad density, cutoff or switch is bad input (exit 2), not a failed run.
            let cutoff = args.cutoff.unwrap_or(problems::DIPOLAR_FLUID_CUTOFF);
            let (b, mut m) = problems::dipolar_fluid_with_cutoff(n, args.density, args.seed, cutoff)
                .map_err(|e| input(e.to_string()))?;
            if let Some(r_s) = args.switch_start {
                if m.cutoff.is_none() {
                    return Err(input(format!(
                        "switch_start = {r_s} needs a cutoff, but the box ({:.3}) is shorter than twice the cutoff \
                         {cutoff}, so all pairs interact",
                        (n as f64 / args.density).cbrt()
                    )));
                }
                m = m.with_switch_start(r_s).map_err(|e| input(e.to_string()))?;
            }
            run_model(args, b, &m, h, steps).map_err(failed)
        }
    });
    let (bodies, first, last, seconds, max_de) = result?;
    let body_steps = steps as f64 * bodies.len() as f64;
    let throughput = if seconds > 0.0 { body_steps / seconds } else { f64::NAN };
    let dp = last.linear_momentum - first.linear_momentum;
    let dl = last.angular_momentum - first.angular_momentum;
    let summary = json!({
        "model": format!("{:?}", args.model).to_lowercase(),
        "bodies": bodies.len(),
        "steps": steps,
        "step": h,
        "t_end": t_end,
        "threads": threads,
        "stepping_seconds": seconds,
        "body_steps_per_second": throughput,
        "bytes_per_body": BYTES_PER_BODY,
        "energy": [first.energy, last.energy],
        "max_relative_energy_error": max_de,
        "linear_momentum_change": dp.to_array(),
        "angular_momentum_change": dl.to_array(),
    });
    match cli.json.as_deref() {
        Some("-") => println!("{summary}"),
        Some(path) => {
            std::fs::write(path, summary.to_string() + "\n").map_err(|e| (1, format!("{path}: {e}")))?;
            println!("wrote {path}");
        }
        None => {}
    }
    if cli.json.as_deref() != Some("-") {
        println!(
            "{:?}: {} bodies, {} steps of {h} on {threads} threads: {:.3} s stepping, {:.3e} body-steps/s",
            args.model,
            bodies.len(),
            steps,
            seconds,
            throughput
        );
        println!(
            "max relative energy error (sampled every {} steps)  {max_de:.3e}",
            args.every
        );
        println!(
            "change of total linear momentum   [{:.3e}, {:.3e}, {:.3e}]",
            dp.x, dp.y, dp.z
        );
        println!(
            "change of total angular momentum  [{:.3e}, {:.3e}, {:.3e}]",
            dl.x, dl.y, dl.z
        );
        println!("state memory                      {BYTES_PER_BODY} bytes per body");
    }
    Ok(())
}
