//! Runs of a beam frame shared by the beam tests.

use liemid::beam::{BeamMethod, BeamSystem};

/// Nodal positions and attitudes after `t` from `start`, in steps of `h` of `method`.
pub fn advance(start: &BeamSystem, method: BeamMethod, h: f64, t: f64) -> Vec<f64> {
    let mut s = start.clone();
    let steps = (t / h).round() as usize;
    for _ in 0..steps {
        s.step_with(method, h).unwrap();
    }
    let mut out = Vec::new();
    for node in 0..s.frame.nodes.len() {
        out.extend(s.position(node).to_array());
        out.extend(s.rotation(node).to_row_major());
    }
    out
}
