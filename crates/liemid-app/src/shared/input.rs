//! How every front end reads an input file (a scenario, a checkpoint, a start file): only a
//! regular file (a FIFO would block the run forever in `open`, a device such as `/dev/zero`
//! would fill the memory, a directory is a mistake), and at most a stated number of bytes,
//! refused before anything is read whole. The model files and the files they include are
//! read by the library's loader under the same two rules.

use std::fs::File;
use std::io::Read;
use std::path::Path;

/// The largest scenario file read (a TOML scenario is a few kilobytes).
pub const MAX_SCENARIO_BYTES: u64 = 16 << 20;
/// The largest checkpoint read.
pub const MAX_CHECKPOINT_BYTES: u64 = 64 << 20;
/// The largest start file (`.npy`) read: 4 GiB, beyond the largest lattice accepted.
pub const MAX_START_BYTES: u64 = 4 << 30;

/// The bytes of the regular file `path`, at most `max_bytes` of them.
///
/// # Errors
/// One line naming the file: it cannot be read, is not a regular file, or is larger than
/// `max_bytes`.
pub fn read_bytes(path: &Path, max_bytes: u64) -> Result<Vec<u8>, String> {
    let shown = path.display();
    let cannot = |e: std::io::Error| format!("{shown}: cannot read: {e}");
    let meta = std::fs::metadata(path).map_err(cannot)?;
    if !meta.is_file() {
        return Err(format!(
            "{shown}: not a regular file (a directory, FIFO or device is not read as an input)"
        ));
    }
    if meta.len() > max_bytes {
        return Err(format!(
            "{shown}: {} bytes, more than the {} MiB read for this kind of file",
            meta.len(),
            max_bytes >> 20
        ));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    File::open(path)
        .and_then(|f| f.take(max_bytes + 1).read_to_end(&mut bytes))
        .map_err(cannot)?;
    if bytes.len() as u64 > max_bytes {
        return Err(format!("{shown}: grew beyond {} MiB while read", max_bytes >> 20));
    }
    Ok(bytes)
}

/// [`read_bytes`] as UTF-8 text.
///
/// # Errors
/// [`read_bytes`]'s, and text that is not UTF-8.
pub fn read_text(path: &Path, max_bytes: u64) -> Result<String, String> {
    String::from_utf8(read_bytes(path, max_bytes)?).map_err(|e| format!("{}: not UTF-8 text: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_directory_or_a_fifo_is_refused_without_blocking_and_a_large_file_by_its_size() {
        let dir = std::env::temp_dir().join(format!("liemid-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert!(read_text(&dir, 1 << 20).unwrap_err().contains("not a regular file"));
        #[cfg(unix)]
        {
            let fifo = dir.join("fifo");
            let _ = std::fs::remove_file(&fifo);
            let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
            // No writer: opening it would block forever; it is refused before the open.
            assert!(read_text(&fifo, 1 << 20).unwrap_err().contains("not a regular file"));
            assert!(read_bytes(Path::new("/dev/zero"), 1 << 20)
                .unwrap_err()
                .contains("not a regular file"));
        }
        let big = dir.join("big.toml");
        std::fs::write(&big, vec![b'#'; 2048]).unwrap();
        assert!(read_text(&big, 1024).unwrap_err().contains("more than"));
        assert_eq!(read_text(&big, 4096).unwrap().len(), 2048);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
