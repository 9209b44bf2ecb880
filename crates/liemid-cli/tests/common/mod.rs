//! Helpers of the end-to-end tests of the `liemid` binary.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn liemid() -> Command {
    Command::new(env!("CARGO_BIN_EXE_liemid"))
}

/// A fresh, empty directory for one test, removed when the test passes (a failing test
/// keeps it, for a look at what it wrote).
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

pub fn scratch(name: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("liemid-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    liemid().current_dir(dir).args(args).output().unwrap()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("not JSON ({e}): {text}"))
}

/// Parse a CSV trajectory: header and rows of 17 numbers.
pub fn read_csv(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    assert_eq!(
        header,
        "t,pi1,pi2,pi3,r11,r12,r13,r21,r22,r23,r31,r32,r33,energy,pix,piy,piz"
    );
    lines
        .map(|l| {
            let row: Vec<f64> = l.split(',').map(|v| v.parse::<f64>().unwrap()).collect();
            assert_eq!(row.len(), 17, "{l}");
            row
        })
        .collect()
}

/// Read a `.npy` trajectory of f64 with 17 columns.
pub fn read_npy(path: &Path) -> Vec<Vec<f64>> {
    read_npy_columns(path, 17)
}

/// Read a `.npy` matrix of f64 with `columns` columns; the header's row count must match the data.
pub fn read_npy_columns(path: &Path, columns: usize) -> Vec<Vec<f64>> {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + hlen]).unwrap();
    assert!(
        header.contains("'descr': '<f8'") && header.contains("'fortran_order': False"),
        "{header}"
    );
    let shape = &header[header.find("'shape': (").unwrap() + 10..];
    let rows: usize = shape[..shape.find(',').unwrap()].trim().parse().unwrap();
    let data = &bytes[10 + hlen..];
    assert_eq!(data.len(), rows * columns * 8, "npy data size");
    data.chunks(columns * 8)
        .map(|r| r.chunks(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect())
        .collect()
}

/// Write `text` to `dir/name`.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}
