//! Integrates the fast top to t = 0.8 with an EA composition at its work-precision step
//! nearest a target attitude error, many times, for profilers and quick timings:
//!
//! `cargo run --release -p liemid --example profile_composition -- [4|6|8] [step]`
//!
//! EA4 (Suzuki) at `h = 8.136e-3` is the point nearest 1e-3, EA6 (Kahan-Li) at `5.753e-3`
//! the point nearest 1e-6 and EA8 (Kahan-Li) at `4.068e-3` a point below 1e-9.
use liemid::{integrate_to, rigid::problems, Composition, LieMidpointAlternating, Scheme};
fn main() {
    let mut args = std::env::args().skip(1);
    let (scheme, default_step) = match args.next().as_deref() {
        Some("4") => (Scheme::SUZUKI4, 8.1357e-3),
        Some("8") => (Scheme::KAHAN_LI8, 4.0679e-3),
        None | Some("6") => (Scheme::KAHAN_LI6, 5.753e-3),
        Some(other) => panic!("order {other}: expected 4, 6 or 8"),
    };
    let h: f64 = args.next().map_or(default_step, |s| s.parse().expect("a step"));
    let top = problems::fast_top();
    let runs = 2000;
    let mut last = 0.0;
    let t = std::time::Instant::now();
    for _ in 0..runs {
        let mut m = Composition::new(LieMidpointAlternating::new(), scheme, "EA composition");
        let run = integrate_to(&mut m, &top.system, top.initial, 0.8, h).expect("runs");
        last = run.state.pi.x;
    }
    let ms = t.elapsed().as_secs_f64() / f64::from(runs) * 1e3;
    println!("{} at h = {h:e}: {ms:.4} ms per run (Π₁ = {last})", scheme.name);
}
