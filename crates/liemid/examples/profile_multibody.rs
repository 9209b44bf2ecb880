//! Steps the built-in multibody problems and prints, per problem and method, the CPU time
//! per step, the position-solve iterations and factorizations per stage, the largest
//! constraint violations and the constraint solve's share of a step: `cargo run --release
//! -p liemid --example profile_multibody [PROBLEM [METHOD [STEP [STEPS [RUNS]]]]]` (for
//! profilers: one case when arguments are given). PROBLEM may be a model file (MJCF `.xml`,
//! URDF `.urdf`): it is prepared as the command prepares it (`Simulation::prepare`), from its
//! first keyframe. RUNS (default 1) repeats the STEPS steps from the start, each run with a
//! fresh simulation built outside the timed loop: a short trajectory (a robot's 0.5 s) made
//! long enough for the timers and a sampling profiler.
use liemid::multibody::{mjcf, problems, urdf, Model, MultibodyMethod, MultibodyState, Simulation};

fn cpu() -> f64 {
    // Process CPU time, so that a loaded machine does not inflate the figures.
    let mut ts = std::mem::MaybeUninit::<[i64; 2]>::uninit();
    // SAFETY: clock_gettime writes a timespec (two 64-bit fields on x86-64 Linux).
    unsafe {
        clock_gettime(2, ts.as_mut_ptr());
        let [s, ns] = ts.assume_init();
        s as f64 + ns as f64 * 1e-9
    }
}

extern "C" {
    fn clock_gettime(clock: i32, ts: *mut [i64; 2]) -> i32;
}

fn model(name: &str) -> Model {
    match name {
        "spacecraft" => problems::spacecraft(),
        "double-pendulum" => problems::double_pendulum(),
        "chain-10" => problems::chain(10),
        "chain-100" => problems::chain(100),
        "chain-1000" => problems::chain(1000),
        file if file.ends_with(".urdf") => urdf::load(std::path::Path::new(file)).expect("the file loads").model,
        file if file.ends_with(".xml") => mjcf::load(std::path::Path::new(file)).expect("the file loads").model,
        other => panic!("unknown problem {other}"),
    }
}

/// The simulation and its start as the command builds them (the keyframe's state; loops closed).
fn start(model: &Model, method: MultibodyMethod) -> (Simulation, MultibodyState) {
    let prepared = Simulation::prepare(model, method).expect("the model builds");
    (prepared.simulation, prepared.state)
}

fn run(name: &str, method: MultibodyMethod, h: f64, steps: u64, runs: u64) {
    let model = model(name);
    let (mut it, mut fac, mut pos, mut vel) = (0u64, 0u64, 0.0f64, 0.0f64);
    let mut c = 0.0;
    let mut state = model.initial_state().expect("the model starts");
    for _ in 0..runs {
        let (mut system, start_state) = start(&model, method);
        state = start_state;
        let c0 = cpu();
        for _ in 0..steps {
            let r = system.step(&mut state, h).expect("the step converges");
            it += u64::from(r.iterations);
            fac += u64::from(r.factorizations);
            pos = pos.max(r.position_violation);
            vel = vel.max(r.velocity_violation);
        }
        c += cpu() - c0;
    }
    let steps = steps * runs;
    let stages = steps as f64 * method.scheme().map_or(1, |s| s.stages()) as f64;
    let nb = state.len() as f64;
    let name = std::path::Path::new(name)
        .file_name()
        .map_or(name.into(), |f| f.to_string_lossy());
    println!(
        "{name:<16} {:<11} h = {h:.1e} {steps:>7} steps: {:>9.3} us/step, {:>7.3} us/stage, {:>7.4} us/body-stage; \
         iterations/stage {:.2}, factorizations/stage {:.2}; max violation pos {pos:.1e} vel {vel:.1e}; c0 {:.15e}",
        method.name(),
        c / steps as f64 * 1e6,
        c / stages * 1e6,
        c / stages / nb * 1e6,
        it as f64 / stages,
        fac as f64 / stages,
        state.c[0].x,
    );
    // The share of the constraint solves (factorizations and solves of G M⁻¹ Gᵀ) in a step,
    // from the library's own timers, in a separate run (the timers cost a little).
    let (mut solver, mut step) = (std::time::Duration::ZERO, std::time::Duration::ZERO);
    for _ in 0..runs {
        let (mut system, mut state) = start(&model, method);
        system.integrator.set_profiling(true);
        for _ in 0..steps / runs {
            system.step(&mut state, h).expect("the step converges");
        }
        let (s, t) = system.integrator.profile();
        solver += s;
        step += t;
    }
    println!(
        "{:<16} {:<11} constraint solve {:.1} % of the step (timed run)",
        "",
        "",
        100.0 * solver.as_secs_f64() / step.as_secs_f64()
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let method = |s: &str| match s {
        "liemid" => MultibodyMethod::Liemid,
        "liemid4" => MultibodyMethod::Liemid4,
        "liemid6" => MultibodyMethod::Liemid6,
        "liemid8" => MultibodyMethod::Liemid8,
        _ => panic!("unknown method {s}"),
    };
    if let Some(p) = args.first() {
        let m = method(args.get(1).map_or("liemid", String::as_str));
        let h = args.get(2).map_or(1e-4, |s| s.parse().expect("a step"));
        let n = args.get(3).map_or(100_000, |s| s.parse().expect("a step count"));
        let runs = args.get(4).map_or(1, |s| s.parse().expect("a run count"));
        run(p, m, h, n, runs);
        return;
    }
    for (p, m, h, n) in [
        ("spacecraft", "liemid", 1e-4, 100_000),
        ("spacecraft", "liemid4", 1e-3, 10_000),
        ("spacecraft", "liemid6", 2.5e-3, 4_000),
        ("double-pendulum", "liemid", 1e-4, 100_000),
        ("double-pendulum", "liemid4", 1e-2, 1_000),
        ("chain-10", "liemid", 1e-4, 20_000),
        ("chain-100", "liemid", 1e-4, 2_000),
        ("chain-1000", "liemid", 1e-4, 200),
    ] {
        run(p, method(m), h, n, 1);
    }
}
