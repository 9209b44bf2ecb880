//! Steps the fast top with LIEMID[EA] many times, for profilers.
use liemid::{rigid::problems, LieMidpointAlternating, RotationIntegrator};
fn main() {
    let top = problems::fast_top();
    let mut s = top.initial;
    let mut ea = LieMidpointAlternating::new();
    for _ in 0..5_000_000 {
        ea.step(&top.system, &mut s, 1e-4).unwrap();
    }
    println!("{:?}", s.pi);
}
