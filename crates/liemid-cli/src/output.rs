//! Trajectory files, streamed row by row to `PATH.partial` and renamed to `PATH` only when
//! the run completes, so a failed run never leaves a file that looks complete.

use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::scenario::Format;

/// Column names of a trajectory row.
pub const COLUMNS: [&str; 17] = [
    "t", "pi1", "pi2", "pi3", "r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33", "energy", "pix", "piy",
    "piz",
];

/// Bytes reserved for the `.npy` header (magic, version, length and the padded dict).
const NPY_HEADER: usize = 128;

/// A trajectory being written.
pub struct TrajectoryWriter {
    path: PathBuf,
    partial: PathBuf,
    out: BufWriter<File>,
    format: Format,
    rows: u64,
}

/// The `.partial` name a trajectory is written under until it is complete.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".partial");
    PathBuf::from(name)
}

fn npy_header(rows: u64) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({rows}, {}), }}",
        COLUMNS.len()
    );
    let mut h = Vec::with_capacity(NPY_HEADER);
    h.extend_from_slice(b"\x93NUMPY\x01\x00");
    h.extend_from_slice(&((NPY_HEADER - 10) as u16).to_le_bytes());
    h.extend_from_slice(dict.as_bytes());
    h.resize(NPY_HEADER - 1, b' ');
    h.push(b'\n');
    h
}

impl TrajectoryWriter {
    /// Start writing `path` (as `path.partial`) in `format`.
    pub fn create(path: &Path, format: Format) -> io::Result<Self> {
        let partial = partial_path(path);
        let mut out = BufWriter::with_capacity(1 << 16, File::create(&partial)?);
        match format {
            Format::Csv => writeln!(out, "{}", COLUMNS.join(","))?,
            Format::Npy => out.write_all(&npy_header(0))?,
        }
        Ok(TrajectoryWriter {
            path: path.to_path_buf(),
            partial,
            out,
            format,
            rows: 0,
        })
    }

    /// Append one row.
    pub fn write_row(&mut self, row: &[f64; 17]) -> io::Result<()> {
        match self.format {
            Format::Csv => {
                let mut first = true;
                for v in row {
                    if !first {
                        self.out.write_all(b",")?;
                    }
                    first = false;
                    write!(self.out, "{v:e}")?;
                }
                self.out.write_all(b"\n")?;
            }
            Format::Npy => {
                for v in row {
                    self.out.write_all(&v.to_le_bytes())?;
                }
            }
        }
        self.rows += 1;
        Ok(())
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// The `.partial` path being written.
    pub fn partial(&self) -> &Path {
        &self.partial
    }

    /// Flush, fix the `.npy` row count, and rename to the final path.
    pub fn finish(mut self) -> io::Result<(PathBuf, u64)> {
        self.out.flush()?;
        let mut file = self.out.into_inner().map_err(|e| e.into_error())?;
        if self.format == Format::Npy {
            file.seek(SeekFrom::Start(0))?;
            file.write_all(&npy_header(self.rows))?;
        }
        file.sync_all()?;
        drop(file);
        std::fs::rename(&self.partial, &self.path)?;
        Ok((self.path, self.rows))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_header_is_aligned_and_parsable() {
        let h = npy_header(123_456_789);
        assert_eq!(h.len(), NPY_HEADER);
        assert_eq!(h.len() % 64, 0);
        let text = String::from_utf8_lossy(&h[10..]);
        assert!(text.contains("'shape': (123456789, 17)"), "{text}");
        assert!(text.ends_with('\n'));
    }
}
