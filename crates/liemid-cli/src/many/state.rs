//! The state file of `liemid many` (`--state`, `--checkpoint`, `--resume`): every body's
//! state in body order and the positions at the Verlet list's last build, so that a run
//! resumed from it (in one process or on any number of MPI ranks) builds the same list and
//! continues with the bits of an uninterrupted run.
//!
//! Layout (little-endian): the 18 bytes `LIEMID-MANY-STATE\n`, then u32 version (2), u64
//! bodies `n`, u64 steps done, u64 Langevin steps, f64 time, f64 step, f64 box side (NaN
//! without a box), u8 free rotation (0 midpoint, 1 exact, 2 variational), then per body 26 f64: mass,
//! principal moments (3), free (1 or 0), position (3), linear momentum (3), attitude (9, by
//! rows), body angular momentum (3), position at the last list build (3); last, the u32
//! CRC-32 of every byte before it, so that a damaged or edited file is refused.

use std::path::Path;

use liemid::linalg::{Mat3, Vec3};
use liemid::many::{Bodies, FreeRotation};

const MAGIC: &[u8; 18] = b"LIEMID-MANY-STATE\n";
const VERSION: u32 = 2;
const HEADER: usize = 18 + 4 + 8 * 6 + 1;
const RECORD: usize = 26;

/// A state read from or written to a file.
pub struct State {
    /// The bodies (time and Langevin steps included).
    pub bodies: Bodies,
    /// The positions at the last list build (the bodies' positions without a list).
    pub reference: Vec<Vec3>,
    /// Steps done since t = 0.
    pub steps: u64,
    /// The step of the run.
    pub h: f64,
    /// The periodic box's side, if any.
    pub box_length: Option<f64>,
}

/// The bytes of a state.
#[must_use]
pub fn encode(s: &State) -> Vec<u8> {
    let b = &s.bodies;
    let mut out = Vec::with_capacity(HEADER + b.len() * RECORD * 8);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    for v in [b.len() as u64, s.steps, b.langevin_steps] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in [b.t, s.h, s.box_length.unwrap_or(f64::NAN)] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.push(match b.free_rotation() {
        FreeRotation::Midpoint => 0,
        FreeRotation::Exact => 1,
        FreeRotation::Variational => 2,
    });
    for i in 0..b.len() {
        let (g, x, p, r, pi, x0) = (
            b.inertia[i].moments,
            b.position[i],
            b.momentum[i],
            &b.rotation[i],
            b.pi[i],
            s.reference[i],
        );
        let mut record = vec![b.mass[i], g.x, g.y, g.z, f64::from(u8::from(b.free[i]))];
        record.extend_from_slice(&[x.x, x.y, x.z, p.x, p.y, p.z]);
        record.extend_from_slice(&r.m.concat());
        record.extend_from_slice(&[pi.x, pi.y, pi.z, x0.x, x0.y, x0.z]);
        for v in record {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    let sum = crc32fast::hash(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

/// Write a state atomically.
///
/// # Errors
/// The file cannot be written.
pub fn write(path: &Path, s: &State) -> Result<(), String> {
    crate::shared::output::write_atomically(path, &encode(s))
        .map_err(|e| format!("{}: cannot write the state: {e}", path.display()))
}

/// Read a state file.
///
/// # Errors
/// The file cannot be read, is not a state file of this version, is cut short, or holds a
/// body the library refuses (non-finite state, non-positive mass or moments).
pub fn read(path: &Path) -> Result<State, String> {
    let bytes = liemid_app::shared::input::read_bytes(path, liemid_app::shared::input::MAX_START_BYTES)?;
    decode(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

fn decode(bytes: &[u8]) -> Result<State, String> {
    if bytes.len() < HEADER || &bytes[..18] != MAGIC {
        return Err("not a liemid many state file".into());
    }
    let u32_at = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().expect("4 bytes"));
    let u64_at = |k: usize| u64::from_le_bytes(bytes[k..k + 8].try_into().expect("8 bytes"));
    let f64_at = |k: usize| f64::from_bits(u64_at(k));
    if u32_at(18) != VERSION {
        return Err(format!(
            "state file version {}, this liemid reads {VERSION}",
            u32_at(18)
        ));
    }
    let n = u64_at(22);
    let expected = (n as u128) * (RECORD as u128 * 8) + HEADER as u128 + 4;
    if bytes.len() as u128 != expected {
        return Err(format!(
            "{} bytes, but {n} bodies need {}: the file is cut short or not a state file",
            bytes.len(),
            liemid::error::Num(expected as f64)
        ));
    }
    let (content, sum) = bytes.split_at(bytes.len() - 4);
    if crc32fast::hash(content).to_le_bytes() != sum {
        return Err("the state file's checksum does not match its content (edited or damaged)".into());
    }
    let (steps, langevin) = (u64_at(30), u64_at(38));
    let (t, h, box_length) = (f64_at(46), f64_at(54), f64_at(62));
    let rotation = match bytes[70] {
        0 => FreeRotation::Midpoint,
        1 => FreeRotation::Exact,
        2 => FreeRotation::Variational,
        k => return Err(format!("unknown free rotation {k}")),
    };
    let mut bodies = Bodies::new();
    bodies.set_free_rotation(rotation).map_err(|e| e.to_string())?;
    let mut reference = Vec::with_capacity(n as usize);
    for i in 0..n as usize {
        let base = HEADER + i * RECORD * 8;
        let r = |k: usize| f64_at(base + 8 * k);
        let v = |k: usize| Vec3::new(r(k), r(k + 1), r(k + 2));
        let rot = Mat3 {
            m: [[r(11), r(12), r(13)], [r(14), r(15), r(16)], [r(17), r(18), r(19)]],
        };
        bodies
            .push(r(0), v(1), r(4) != 0.0, v(5), v(8), rot, v(20))
            .map_err(|e| format!("body {i}: {e}"))?;
        let x0 = v(23);
        if !x0.is_finite() {
            return Err(format!("body {i}: non-finite reference position"));
        }
        reference.push(x0);
    }
    bodies.t = t;
    bodies.langevin_steps = langevin;
    Ok(State {
        bodies,
        reference,
        steps,
        h,
        box_length: box_length.is_finite().then_some(box_length),
    })
}
