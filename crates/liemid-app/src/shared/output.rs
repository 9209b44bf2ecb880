//! Everything `liemid` writes: the checks every output path passes before the first step,
//! and trajectory files streamed row by row to `PATH.partial`, renamed to `PATH` only when
//! the run completes.
//!
//! Rules (README, "Errors and limits"):
//! - outputs are regular files: an existing directory, device, FIFO or socket is refused,
//!   and so is a symbolic link (liemid never writes through a link or replaces it);
//! - no output is an input of the same run (compared by device and inode, so hard links
//!   count), nor another output of it;
//! - the directory must exist and be writable, checked before anything is computed;
//! - a `.partial` file is valid at every buffer flush: CSV holds whole rows only, and the
//!   `.npy` header holds the number of rows that follow it. After a failure (numerical,
//!   SIGINT/SIGTERM, a full disk) it is cut at the last whole row and its count reported.

use std::fs::{File, OpenOptions};
use std::io::{self, Seek, SeekFrom, Write};
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::{Path, PathBuf};

/// Trajectory file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Format {
    /// Comma-separated values with a header line.
    Csv,
    /// NumPy `.npy`, a little-endian f64 matrix.
    Npy,
}

/// Column names of a trajectory row.
pub const COLUMNS: [&str; 17] = [
    "t", "pi1", "pi2", "pi3", "r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33", "energy", "pix", "piy",
    "piz",
];

/// Bytes reserved for the `.npy` header (magic, version, length and the padded dict).
const NPY_HEADER: usize = 128;

/// Bytes buffered before a write to the file.
const BUFFER: usize = 1 << 16;

/// The `.partial` name a file is written under until it is complete.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".partial");
    PathBuf::from(name)
}

/// What kind of thing stands at `path` that is not a regular file, if any.
fn not_regular(path: &Path) -> Option<&'static str> {
    let meta = std::fs::symlink_metadata(path).ok()?;
    let t = meta.file_type();
    if t.is_file() {
        None
    } else if t.is_symlink() {
        Some("a symbolic link")
    } else if t.is_dir() {
        Some("a directory")
    } else if t.is_block_device() || t.is_char_device() {
        Some("a device")
    } else if t.is_fifo() {
        Some("a FIFO")
    } else {
        Some("a special file")
    }
}

/// `path` made absolute lexically, with its directory resolved when it exists.
fn normalized(path: &Path) -> PathBuf {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path.file_name().map(PathBuf::from).unwrap_or_default();
    std::fs::canonicalize(&parent).unwrap_or(parent).join(name)
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => normalized(a) == normalized(b),
    }
}

/// The outputs of one command, checked against each other and against its inputs before
/// the first step.
pub struct OutputPlan {
    inputs: Vec<PathBuf>,
    outputs: Vec<(String, PathBuf)>,
}

impl OutputPlan {
    /// A plan for a command that reads `inputs`.
    pub fn new(inputs: &[&Path]) -> Self {
        OutputPlan {
            inputs: inputs.iter().map(|p| p.to_path_buf()).collect(),
            outputs: Vec::new(),
        }
    }

    /// Check that `path` (given as `what`, e.g. `--out`) can be written: a regular file or
    /// nothing, not an input, not another output, in a writable directory. The check
    /// creates and removes `PATH.partial` when no such file exists.
    pub fn add(&mut self, what: &str, path: &Path) -> Result<(), String> {
        let shown = path.display();
        if path.as_os_str().is_empty() {
            return Err(format!("{what}: the path is empty"));
        }
        for (label, candidate) in [("", path.to_path_buf()), (" (its .partial file)", partial_path(path))] {
            if let Some(kind) = not_regular(&candidate) {
                return Err(format!(
                    "{what} {}{label} is {kind}; liemid writes regular files only and never replaces \
                     anything else (give another path{})",
                    candidate.display(),
                    if what == "--out" { ", or --no-output" } else { "" }
                ));
            }
            for input in &self.inputs {
                if same_file(&candidate, input) {
                    return Err(format!(
                        "{what} {}{label} is the input {} of this run; writing it would destroy it",
                        candidate.display(),
                        input.display()
                    ));
                }
            }
            for (other, p) in &self.outputs {
                if same_file(&candidate, p) || same_file(&candidate, &partial_path(p)) {
                    return Err(format!(
                        "{what} {}{label} is also the {other} output of this run",
                        candidate.display()
                    ));
                }
            }
        }
        // `--json` takes an optional value: `--json scenario.toml` would read the scenario as
        // the JSON target and replace it.
        let model_like = ["toml", "xml", "urdf", "npy"];
        if what == "--json"
            && path
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| model_like.contains(&e.to_ascii_lowercase().as_str()))
        {
            return Err(format!(
                "--json {shown}: that looks like a scenario or model file, not a JSON target; give the \
                 scenario first (`liemid ... {shown} --json [FILE.json|-]`)"
            ));
        }
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if !dir.is_dir() {
            return Err(format!(
                "{what} {shown}: cannot write there, the directory {} does not exist",
                dir.display()
            ));
        }
        let partial = partial_path(path);
        let existed = partial.exists();
        let probe = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(&partial);
        if let Err(e) = probe {
            return Err(format!("{what} {shown}: cannot write in {}: {e}", dir.display()));
        }
        if !existed {
            let _ = std::fs::remove_file(&partial);
        }
        self.outputs.push((what.to_string(), path.to_path_buf()));
        Ok(())
    }
}

/// Write `bytes` to `path` through `PATH.partial` and a rename (a path checked by
/// [`OutputPlan::add`]).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let partial = partial_path(path);
    let mut f = File::create(&partial)?;
    f.write_all(bytes)?;
    f.sync_all()?;
    drop(f);
    std::fs::rename(&partial, path)
}

pub(crate) fn npy_header(rows: u64, columns: usize) -> Vec<u8> {
    let dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({rows}, {columns}), }}");
    let mut h = Vec::with_capacity(NPY_HEADER);
    h.extend_from_slice(b"\x93NUMPY\x01\x00");
    h.extend_from_slice(&((NPY_HEADER - 10) as u16).to_le_bytes());
    h.extend_from_slice(dict.as_bytes());
    h.resize(NPY_HEADER - 1, b' ');
    h.push(b'\n');
    h
}

/// Where a trajectory goes.
enum Sink {
    /// `PATH.partial`, renamed to `PATH` at the end.
    File {
        file: File,
        path: PathBuf,
        partial: PathBuf,
    },
    /// Standard output (`--out -`, CSV only).
    Stdout(io::Stdout),
}

/// How much of a trajectory is in its file: whole rows and their bytes (header included).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Written {
    /// Rows in the file.
    pub rows: u64,
    /// Bytes in the file.
    pub bytes: u64,
}

/// A trajectory being written.
pub struct TrajectoryWriter {
    sink: Sink,
    format: Format,
    columns: usize,
    buffer: Vec<u8>,
    buffered_rows: u64,
    written: Written,
}

impl TrajectoryWriter {
    /// Start writing `path` (as `path.partial`, or standard output for `-`) in `format`,
    /// rows of the named `columns`.
    pub fn create(path: &Path, format: Format, columns: &[&str]) -> Result<Self, String> {
        let sink = if path == Path::new("-") {
            if format == Format::Npy {
                return Err(
                    "--out -: a .npy trajectory cannot go to standard output (its header holds \
                            the row count); use csv or a file"
                        .into(),
                );
            }
            Sink::Stdout(io::stdout())
        } else {
            let partial = partial_path(path);
            let file = File::create(&partial).map_err(|e| format!("{}: cannot create: {e}", partial.display()))?;
            Sink::File {
                file,
                path: path.to_path_buf(),
                partial,
            }
        };
        let mut w = TrajectoryWriter {
            sink,
            format,
            columns: columns.len(),
            buffer: Vec::with_capacity(BUFFER + 1024),
            buffered_rows: 0,
            written: Written { rows: 0, bytes: 0 },
        };
        match format {
            Format::Csv => w.buffer.extend_from_slice((columns.join(",") + "\n").as_bytes()),
            Format::Npy => w.buffer.extend_from_slice(&npy_header(0, columns.len())),
        }
        w.flush().map_err(|e| format!("{}: {e}", w.shown()))?;
        Ok(w)
    }

    /// Continue the trajectory `path` of a checkpointed run: its `.partial` file is cut to
    /// what the checkpoint recorded (rows written after it are written again).
    pub fn resume(path: &Path, format: Format, columns: usize, written: Written) -> Result<Self, String> {
        let partial = partial_path(path);
        let shown = partial.display();
        if !partial.exists() && path.exists() {
            return Err(format!(
                "the run of this checkpoint has completed: {} is its whole trajectory",
                path.display()
            ));
        }
        let mut file = OpenOptions::new()
            .write(true)
            .open(&partial)
            .map_err(|e| format!("{shown}: cannot reopen the trajectory to continue it: {e}"))?;
        let len = file.metadata().map_err(|e| format!("{shown}: {e}"))?.len();
        if len < written.bytes {
            return Err(format!(
                "{shown} holds {len} bytes, fewer than the {} the checkpoint recorded; it is not the \
                 trajectory of this run",
                written.bytes
            ));
        }
        file.set_len(written.bytes)
            .and_then(|()| file.seek(SeekFrom::End(0)).map(|_| ()))
            .map_err(|e| format!("{shown}: {e}"))?;
        Ok(TrajectoryWriter {
            sink: Sink::File {
                file,
                path: path.to_path_buf(),
                partial,
            },
            format,
            columns,
            buffer: Vec::with_capacity(BUFFER + 1024),
            buffered_rows: 0,
            written,
        })
    }

    fn shown(&self) -> String {
        match &self.sink {
            Sink::File { partial, .. } => partial.display().to_string(),
            Sink::Stdout(_) => "standard output".into(),
        }
    }

    /// Append one row (of as many values as there are columns).
    pub fn write_row(&mut self, row: &[f64]) -> Result<(), String> {
        debug_assert_eq!(row.len(), self.columns);
        match self.format {
            Format::Csv => {
                for (i, v) in row.iter().enumerate() {
                    if i > 0 {
                        self.buffer.push(b',');
                    }
                    write!(self.buffer, "{v:e}").expect("writing to a Vec");
                }
                self.buffer.push(b'\n');
            }
            Format::Npy => {
                for v in row {
                    self.buffer.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        self.buffered_rows += 1;
        if self.buffer.len() >= BUFFER {
            self.flush().map_err(|e| format!("writing {}: {e}", self.shown()))?;
        }
        Ok(())
    }

    /// Write the buffered rows. On error the file is cut back to the rows written before
    /// (with the `.npy` header fixed), so it never ends mid-row.
    pub fn flush(&mut self) -> io::Result<()> {
        let (format, columns) = (self.format, self.columns);
        let rows = self.written.rows + self.buffered_rows;
        let result = match &mut self.sink {
            Sink::Stdout(out) => out.write_all(&self.buffer).and_then(|()| out.flush()),
            Sink::File { file, .. } => file.write_all(&self.buffer).and_then(|()| {
                if format == Format::Npy {
                    let end = file.stream_position()?;
                    file.seek(SeekFrom::Start(0))?;
                    file.write_all(&npy_header(rows, columns))?;
                    file.seek(SeekFrom::Start(end))?;
                }
                Ok(())
            }),
        };
        match result {
            Ok(()) => {
                self.written = Written {
                    rows,
                    bytes: self.written.bytes + self.buffer.len() as u64,
                };
            }
            Err(e) => {
                if let Sink::File { file, .. } = &mut self.sink {
                    // Best effort: the disk may be full, but cutting a file frees space.
                    let _ = file.set_len(self.written.bytes);
                    let _ = file.seek(SeekFrom::End(0));
                    if format == Format::Npy && self.written.bytes >= NPY_HEADER as u64 {
                        let _ = file.seek(SeekFrom::Start(0));
                        let _ = file.write_all(&npy_header(self.written.rows, columns));
                        let _ = file.seek(SeekFrom::End(0));
                    }
                }
                self.buffer.clear();
                self.buffered_rows = 0;
                return Err(e);
            }
        }
        self.buffer.clear();
        self.buffered_rows = 0;
        Ok(())
    }

    /// Flush and sync, for a checkpoint: the rows and bytes returned are what a resumed run
    /// continues from.
    pub fn sync(&mut self) -> Result<Written, String> {
        self.flush().map_err(|e| format!("writing {}: {e}", self.shown()))?;
        if let Sink::File { file, .. } = &self.sink {
            file.sync_data().map_err(|e| format!("{}: {e}", self.shown()))?;
        }
        Ok(self.written)
    }

    /// Stop after a failure: write what is buffered (or cut at the last whole row) and keep
    /// the `.partial` file; returns a sentence naming it and its true row count.
    pub fn keep_partial(mut self) -> String {
        let _ = self.flush();
        let shown = self.shown();
        if let Sink::File { file, .. } = &self.sink {
            let _ = file.sync_all();
        }
        let rows = self.written.rows;
        format!("the {rows} {} written are kept in {shown}", plural(rows, "row", "rows"))
    }

    /// Flush, sync and rename to the final path; returns it and the row count.
    pub fn finish(mut self) -> Result<(String, u64), String> {
        self.flush().map_err(|e| format!("writing {}: {e}", self.shown()))?;
        let rows = self.written.rows;
        match self.sink {
            Sink::Stdout(_) => Ok(("-".into(), rows)),
            Sink::File { file, path, partial } => {
                file.sync_all().map_err(|e| format!("{}: {e}", partial.display()))?;
                drop(file);
                std::fs::rename(&partial, &path).map_err(|e| format!("renaming {}: {e}", partial.display()))?;
                Ok((path.display().to_string(), rows))
            }
        }
    }
}

/// `singular` for 1, else `plural_form`.
pub fn plural(n: u64, singular: &'static str, plural_form: &'static str) -> &'static str {
    if n == 1 {
        singular
    } else {
        plural_form
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_header_is_aligned_and_parsable() {
        let h = npy_header(123_456_789, 17);
        assert_eq!(h.len(), NPY_HEADER);
        assert_eq!(h.len() % 64, 0);
        let text = String::from_utf8_lossy(&h[10..]);
        assert!(text.contains("'shape': (123456789, 17)"), "{text}");
        assert!(text.ends_with('\n'));
    }
}
