//! Extended XYZ trajectories of many bodies, which OVITO, ASE and MDAnalysis read: one
//! frame per snapshot,
//!
//! ```text
//! N
//! Lattice="L 0 0 0 L 0 0 0 L" Properties=species:S:1:pos:R:3:orientation:R:4:velo:R:3:angmom:R:3:body_angmom:R:3 Time=t pbc="T T T"
//! X  x y z  qw qx qy qz  vx vy vz  Lx Ly Lz  Πx Πy Πz
//! ```
//!
//! (`orientation` the unit quaternion of the attitude, `velo = p/m`, `angmom = R Π` the
//! spatial angular momentum, `body_angmom = Π`; open systems have no `Lattice` and
//! `pbc="F F F"`). Streamed like `liemid run`'s trajectories: frames go to `PATH.partial`
//! and the file is renamed to `PATH` when the run completes; the partial file ends with a
//! whole frame at every flush, and after a failed write it is cut back to the last one.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use liemid::many::Bodies;
use liemid::so3::Quaternion;

use crate::shared::output::partial_path;

/// Bytes buffered before a write.
const BUFFER: usize = 1 << 16;

/// An extended XYZ trajectory being written.
pub struct FrameWriter {
    file: File,
    path: PathBuf,
    partial: PathBuf,
    buffer: Vec<u8>,
    /// Whole frames in the file, and its length.
    frames: u64,
    bytes: u64,
    /// Frames in the buffer.
    pending: u64,
}

impl FrameWriter {
    /// Start writing `path` (as `path.partial`).
    ///
    /// # Errors
    /// The partial file cannot be created.
    pub fn create(path: &Path) -> Result<Self, String> {
        let partial = partial_path(path);
        let file = File::create(&partial).map_err(|e| format!("{}: cannot create: {e}", partial.display()))?;
        Ok(FrameWriter {
            file,
            path: path.to_path_buf(),
            partial,
            buffer: Vec::with_capacity(BUFFER + 4096),
            frames: 0,
            bytes: 0,
            pending: 0,
        })
    }

    /// Append the frame of `bodies` at their time; `box_length` for a periodic cube.
    ///
    /// # Errors
    /// A failed write (the file is then cut back to its last whole frame).
    pub fn write_frame(&mut self, bodies: &Bodies, box_length: Option<f64>) -> Result<(), String> {
        let n = bodies.len();
        let b = &mut self.buffer;
        let _ = writeln!(b, "{n}");
        if let Some(l) = box_length {
            let _ = write!(b, "Lattice=\"{l:?} 0.0 0.0 0.0 {l:?} 0.0 0.0 0.0 {l:?}\" ");
        }
        let pbc = if box_length.is_some() { "T T T" } else { "F F F" };
        let _ = writeln!(
            b,
            "Properties=species:S:1:pos:R:3:orientation:R:4:velo:R:3:angmom:R:3:body_angmom:R:3 Time={:?} pbc=\"{pbc}\"",
            bodies.t
        );
        for i in 0..n {
            let x = bodies.position[i];
            let q = Quaternion::from_matrix(&bodies.rotation[i]).normalized();
            let v = if bodies.free[i] {
                bodies.momentum[i] * (1.0 / bodies.mass[i])
            } else {
                liemid::Vec3::ZERO
            };
            let pi = bodies.pi[i];
            let l = bodies.rotation[i] * pi;
            let _ = writeln!(
                b,
                "X {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
                x.x, x.y, x.z, q.w, q.x, q.y, q.z, v.x, v.y, v.z, l.x, l.y, l.z, pi.x, pi.y, pi.z
            );
        }
        self.pending += 1;
        if self.buffer.len() >= BUFFER {
            self.flush()?;
        }
        Ok(())
    }

    fn flush(&mut self) -> Result<(), String> {
        if self.buffer.is_empty() {
            return Ok(());
        }
        if let Err(e) = self.file.write_all(&self.buffer) {
            // Back to the last whole frame.
            let _ = self.file.set_len(self.bytes);
            return Err(format!(
                "{}: write failed ({e}); it holds {} whole frames",
                self.partial.display(),
                self.frames
            ));
        }
        self.bytes += self.buffer.len() as u64;
        self.frames += self.pending;
        self.pending = 0;
        self.buffer.clear();
        Ok(())
    }

    /// Leave the partial file as it is after a failure: a message naming it and its frames.
    pub fn keep_partial(mut self) -> String {
        let _ = self.flush();
        format!("{} holds {} whole frames", self.partial.display(), self.frames)
    }

    /// Flush, sync and rename to the final path; the number of frames.
    ///
    /// # Errors
    /// A failed write, sync or rename.
    pub fn finish(mut self) -> Result<u64, String> {
        self.flush()?;
        self.file
            .sync_all()
            .map_err(|e| format!("{}: cannot sync: {e}", self.partial.display()))?;
        std::fs::rename(&self.partial, &self.path).map_err(|e| {
            format!(
                "{}: cannot rename to {}: {e}",
                self.partial.display(),
                self.path.display()
            )
        })?;
        Ok(self.frames)
    }
}
