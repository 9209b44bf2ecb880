//! Integrates the fast top to t = 0.8 with LIEMID[EA]6 at a large step, many times, for
//! profilers (the work-precision point nearest an attitude error of 1e-6).
use liemid::{integrate_to, problems, Composition, LieMidpointAlternating, Scheme};
fn main() {
    let top = problems::fast_top();
    let h: f64 = std::env::args().nth(1).map_or(5.753e-3, |s| s.parse().expect("a step"));
    let mut last = 0.0;
    let t = std::time::Instant::now();
    for _ in 0..2000 {
        let mut m = Composition::new(LieMidpointAlternating::new(), Scheme::KAHAN_LI6, "EA6");
        let run = integrate_to(&mut m, &top.system, top.initial, 0.8, h).expect("runs");
        last = run.state.pi.x;
    }
    println!("{last} {:.3} ms per run", t.elapsed().as_secs_f64() / 2000.0 * 1e3);
}
