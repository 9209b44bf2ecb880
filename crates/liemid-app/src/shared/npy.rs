//! NumPy `.npy` matrices of `f64` (version 1.0, little-endian, C order): the spins of
//! `liemid spins` in and out, shape `(N, 3)`.

use std::path::Path;

use crate::shared::output::npy_header;

/// The bytes of a `.npy` file holding `data` as `rows × columns`.
#[must_use]
pub fn matrix_bytes(rows: usize, columns: usize, data: &[f64]) -> Vec<u8> {
    assert_eq!(data.len(), rows * columns);
    let mut bytes = npy_header(rows as u64, columns);
    for x in data {
        bytes.extend_from_slice(&x.to_le_bytes());
    }
    bytes
}

/// Read a `.npy` file of `f64` with shape `(N, columns)` in C order: its rows.
///
/// # Errors
/// A file that cannot be read, is not `.npy`, holds another type, order or shape, or is
/// cut short; the message names the file.
pub fn read_matrix(path: &Path, columns: usize) -> Result<Vec<Vec<f64>>, String> {
    let file = path.display();
    let bytes = crate::shared::input::read_bytes(path, crate::shared::input::MAX_START_BYTES)?;
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(format!("{file}: not a .npy file"));
    }
    let (header_len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("{file}: .npy version {v} is not supported")),
    };
    let header = bytes
        .get(start..start + header_len)
        .and_then(|h| std::str::from_utf8(h).ok())
        .ok_or(format!("{file}: the .npy header is cut short or not text"))?;
    let compact: String = header.chars().filter(|c| !c.is_whitespace()).collect();
    if !compact.contains("'descr':'<f8'") {
        return Err(format!(
            "{file}: expected float64 ('<f8') data, header {}",
            header.trim()
        ));
    }
    if compact.contains("'fortran_order':True") {
        return Err(format!(
            "{file}: Fortran-ordered arrays are not supported (save with C order)"
        ));
    }
    let shape = compact
        .split("'shape':(")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .ok_or(format!("{file}: no shape in the .npy header"))?;
    let dims: Vec<usize> = shape
        .split(',')
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{file}: bad shape ({shape}) in the .npy header"))?;
    if dims.len() != 2 || dims[1] != columns {
        return Err(format!("{file}: expected shape (N, {columns}), found ({shape})"));
    }
    let rows = dims[0];
    let data = &bytes[start + header_len..];
    if data.len() != rows * columns * 8 {
        return Err(format!(
            "{file}: shape ({rows}, {columns}) needs {} data bytes, found {}",
            rows * columns * 8,
            data.len()
        ));
    }
    Ok(data
        .chunks_exact(8 * columns)
        .map(|row| {
            row.chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
                .collect()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_matrix_written_is_read_back() {
        let dir = std::env::temp_dir().join(format!("liemid-npy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.npy");
        let data: Vec<f64> = (0..12).map(|k| k as f64 * 0.5 - 1.0).collect();
        std::fs::write(&path, matrix_bytes(4, 3, &data)).unwrap();
        let rows = read_matrix(&path, 3).unwrap();
        assert_eq!(rows.concat(), data);
        assert!(read_matrix(&path, 2).unwrap_err().contains("expected shape (N, 2)"));
        std::fs::write(&path, b"not numpy").unwrap();
        assert!(read_matrix(&path, 3).unwrap_err().contains("not a .npy file"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
