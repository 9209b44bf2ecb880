//! The triangle meshes a model draws (MJCF `<mesh file>`, URDF `<mesh filename>`), read
//! from their files for viewers: never part of the dynamics (the masses come from
//! `<inertial>`; a body whose mass would come from a mesh is refused by the loaders).
//!
//! Decisions:
//! - STL, binary and ASCII, through the `stl_io` crate (identical vertices merged); a binary
//!   file whose 80-byte header happens to start with `solid ` (many CAD exporters write one)
//!   is told from ASCII by its size, `84 + 50 n` bytes for `n` triangles. OBJ through the
//!   `tobj` crate: every object and group of the file into one mesh, polygons triangulated
//!   as fans, points and lines left out, no material file read. Other formats (MuJoCo's
//!   `.msh`, `.ply`) are refused with the reason, which the front ends say in a note.
//! - The file is read through the loaders' bounded reading (a regular file only, at most
//!   [`MAX_MESH_FILE_BYTES`]), as the model file and its includes are.
//! - [`Mesh::simplified`] caps the triangles of a mesh by vertex clustering
//!   (Rossignac–Borrel): the vertices in one cell of a uniform grid over the bounding box
//!   become their mean, and the triangles that collapse are dropped; the finest grid under
//!   the cap is taken. It keeps the silhouette to within a cell, which is what a page needs.
//!
//! Reference: the STL format (3D Systems, 1989); the Wavefront OBJ format; J. Rossignac and
//! P. Borrel, *Multi-resolution 3D approximations for rendering complex scenes* (1993).

use std::collections::HashMap;
use std::path::Path;

use super::xml::read_bounded_bytes;
use crate::error::Error;

/// The largest mesh file read (bytes): a binary STL of 1.3 million triangles.
pub const MAX_MESH_FILE_BYTES: u64 = 64 << 20;

/// A triangle mesh: vertices and the triangles over them (counter-clockwise seen from
/// outside, as the file gives them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// The vertices, in the file's coordinates.
    pub vertices: Vec<[f32; 3]>,
    /// Each triangle's three vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

/// The extension of `path`, lower case (empty without one).
fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Whether [`Mesh::read`] reads files of the (lower-case) extension `ext`.
fn reads(ext: &str) -> bool {
    matches!(ext, "stl" | "obj")
}

/// Whether [`Mesh::read`] reads the format of `path` (STL or OBJ, by its extension).
pub(crate) fn format_is_read(path: &Path) -> bool {
    reads(&extension(path))
}

impl Mesh {
    /// Reads the mesh file `path` (`.stl` or `.obj`, by its extension, in any case).
    ///
    /// # Errors
    /// Why the file gives no mesh, in words (without the file's name): it cannot be read,
    /// is not a regular file, is too large, has another format, or holds no valid triangle.
    pub fn read(path: &Path) -> Result<Mesh, String> {
        let ext = extension(path);
        if !reads(&ext) {
            return Err(format!("the .{ext} format is not read (STL and OBJ meshes are)"));
        }
        let bytes = read_bounded_bytes(path, MAX_MESH_FILE_BYTES, "a mesh file").map_err(|e| match e {
            Error::ModelFile { message, .. } => message,
            other => other.to_string(),
        })?;
        if ext == "stl" {
            Mesh::from_stl(&bytes)
        } else {
            Mesh::from_obj(&bytes)
        }
    }

    /// A mesh from the bytes of an STL file, binary or ASCII.
    ///
    /// # Errors
    /// The file is not STL, or holds no valid triangle.
    pub fn from_stl(bytes: &[u8]) -> Result<Mesh, String> {
        let binary_size = bytes
            .get(80..84)
            .map(|n| 84 + 50 * u64::from(u32::from_le_bytes([n[0], n[1], n[2], n[3]])));
        let solid = bytes.starts_with(b"solid");
        let patched;
        let data: &[u8] = match binary_size {
            Some(n) if solid && n == bytes.len() as u64 => {
                // A binary file whose header reads like ASCII: the header is free text, so
                // change its first byte and let the reader take it as binary.
                let mut v = bytes.to_vec();
                v[0] = b'#';
                patched = v;
                &patched
            }
            _ if solid => bytes,
            Some(n) if n <= bytes.len() as u64 => bytes,
            Some(n) => {
                return Err(format!(
                    "not an STL file: {} bytes, fewer than the {n} of a binary STL of its triangle count",
                    bytes.len()
                ))
            }
            None => return Err("not an STL file: shorter than a binary STL header".into()),
        };
        let mut cursor = std::io::Cursor::new(data);
        let indexed = stl_io::read_stl(&mut cursor).map_err(|e| format!("not a valid STL file: {e}"))?;
        let vertices: Vec<[f32; 3]> = indexed.vertices.iter().map(|v| [v[0], v[1], v[2]]).collect();
        let triangles = indexed.faces.iter().map(|f| f.vertices.map(|i| i as u32)).collect();
        Mesh { vertices, triangles }.checked()
    }

    /// A mesh from the bytes of an OBJ file (its `v` and `f` lines).
    ///
    /// # Errors
    /// The text is not OBJ, or holds no valid triangle.
    pub fn from_obj(bytes: &[u8]) -> Result<Mesh, String> {
        let options = tobj::LoadOptions {
            triangulate: true,
            ignore_points: true,
            ignore_lines: true,
            ..Default::default()
        };
        let mut reader = std::io::BufReader::new(bytes);
        // No material file is read (the page colours a mesh by its geom).
        let (models, _) = tobj::load_obj_buf(&mut reader, &options, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| format!("not a valid OBJ file: {e}"))?;
        let mut mesh = Mesh::default();
        for m in &models {
            let base = mesh.vertices.len() as u32;
            mesh.vertices
                .extend(m.mesh.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
            mesh.triangles.extend(
                m.mesh
                    .indices
                    .chunks_exact(3)
                    .map(|t| [base + t[0], base + t[1], base + t[2]]),
            );
        }
        mesh.checked()
    }

    /// The mesh with its triangles checked: indices in range, finite vertices, at least one
    /// triangle.
    fn checked(self) -> Result<Mesh, String> {
        let n = self.vertices.len();
        if let Some(t) = self.triangles.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
            return Err(format!("a triangle {t:?} names a vertex beyond the {n} vertices"));
        }
        if self.vertices.iter().flatten().any(|c| !c.is_finite()) {
            return Err("a vertex is not finite".into());
        }
        if self.triangles.is_empty() {
            return Err("no triangle".into());
        }
        Ok(self)
    }

    /// The corners of the bounding box of the vertices the triangles use, `None` without
    /// triangles.
    #[must_use]
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for t in &self.triangles {
            for &i in t {
                let v = self.vertices[i as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
        }
        (!self.triangles.is_empty()).then_some((lo, hi))
    }

    /// The mesh with at most `max_triangles` triangles (at least 1): itself when it has no
    /// more, else the finest vertex clustering under the cap (see the module's decisions).
    #[must_use]
    pub fn simplified(&self, max_triangles: usize) -> Mesh {
        let max_triangles = max_triangles.max(1);
        if self.triangles.len() <= max_triangles {
            return self.clone();
        }
        let Some((lo, hi)) = self.bounds() else {
            return self.clone();
        };
        let extent = (0..3)
            .map(|k| hi[k] - lo[k])
            .fold(0.0f32, f32::max)
            .max(f32::MIN_POSITIVE);
        // Cells along the longest edge: bisect for the most whose clustering fits.
        let (mut fits, mut over) = (1u32, 1u32 << 12);
        let mut best = self.clustered(lo, extent, fits);
        if best.triangles.len() > max_triangles {
            // Even one cell leaves triangles (only when the box is flat in a direction and
            // points coincide): keep the first triangles.
            best.triangles.truncate(max_triangles);
            return best;
        }
        while over - fits > 1 {
            let mid = fits + (over - fits) / 2;
            let m = self.clustered(lo, extent, mid);
            if m.triangles.len() <= max_triangles {
                fits = mid;
                best = m;
            } else {
                over = mid;
            }
        }
        best
    }

    /// The vertex clustering on a grid of `cells` cells along the longest edge `extent`
    /// from the corner `lo`.
    fn clustered(&self, lo: [f32; 3], extent: f32, cells: u32) -> Mesh {
        let size = extent / cells as f32;
        let cell_of = |v: [f32; 3]| -> [u32; 3] { [0, 1, 2].map(|k| (((v[k] - lo[k]) / size) as u32).min(cells - 1)) };
        let mut cluster: HashMap<[u32; 3], u32> = HashMap::new();
        let mut sums: Vec<([f64; 3], u32)> = Vec::new();
        let mut of_vertex = vec![u32::MAX; self.vertices.len()];
        let mut triangles = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for t in &self.triangles {
            let c = t.map(|i| {
                let i = i as usize;
                if of_vertex[i] == u32::MAX {
                    let v = self.vertices[i];
                    let next = sums.len() as u32;
                    let id = *cluster.entry(cell_of(v)).or_insert(next);
                    if id == next {
                        sums.push(([0.0; 3], 0));
                    }
                    let s = &mut sums[id as usize];
                    for (sum, c) in s.0.iter_mut().zip(v) {
                        *sum += f64::from(c);
                    }
                    s.1 += 1;
                    of_vertex[i] = id;
                }
                of_vertex[i]
            });
            if c[0] != c[1] && c[1] != c[2] && c[0] != c[2] {
                // One triangle per set of three clusters and orientation.
                let r = c.iter().position(|x| x == c.iter().min().unwrap_or(&0)).unwrap_or(0);
                let key = [c[r], c[(r + 1) % 3], c[(r + 2) % 3]];
                if seen.insert(key) {
                    triangles.push(c);
                }
            }
        }
        let vertices = sums
            .iter()
            .map(|(s, n)| s.map(|x| (x / f64::from(*n)) as f32))
            .collect();
        Mesh { vertices, triangles }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 12 triangles of the box `[0, a] × [0, b] × [0, c]`, outward.
    fn box_triangles(a: f32, b: f32, c: f32) -> Vec<[[f32; 3]; 3]> {
        let p = |i: usize| [a * (i & 1) as f32, b * ((i >> 1) & 1) as f32, c * ((i >> 2) & 1) as f32];
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        quads
            .iter()
            .flat_map(|q| [[p(q[0]), p(q[1]), p(q[2])], [p(q[0]), p(q[2]), p(q[3])]])
            .collect()
    }

    fn binary_stl(triangles: &[[[f32; 3]; 3]], header: &[u8]) -> Vec<u8> {
        let mut out = vec![0u8; 80];
        out[..header.len()].copy_from_slice(header);
        out.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
        for t in triangles {
            out.extend(std::iter::repeat_n(0u8, 12));
            for v in t {
                for c in v {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
            out.extend_from_slice(&[0, 0]);
        }
        out
    }

    fn ascii_stl(triangles: &[[[f32; 3]; 3]]) -> String {
        let mut s = String::from("solid box\n");
        for t in triangles {
            s.push_str("  facet normal 0 0 0\n    outer loop\n");
            for v in t {
                s.push_str(&format!("      vertex {} {} {}\n", v[0], v[1], v[2]));
            }
            s.push_str("    endloop\n  endfacet\n");
        }
        s.push_str("endsolid box\n");
        s
    }

    fn assert_box(m: &Mesh, vertices: usize, triangles: usize, hi: [f32; 3]) {
        assert_eq!((m.vertices.len(), m.triangles.len()), (vertices, triangles));
        assert_eq!(m.bounds(), Some(([0.0; 3], hi)));
    }

    /// A binary STL (one with a header reading `solid` too), an ASCII STL and an OBJ of
    /// quads, written into a scratch directory and read back through [`Mesh::read`]: the
    /// box's 8 vertices, 12 triangles and bounds.
    #[test]
    fn binary_and_ascii_stl_and_obj_files_are_read_with_their_counts_and_bounds() {
        let dir = std::env::temp_dir().join(format!("liemid-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let tris = box_triangles(1.0, 2.0, 0.5);
        std::fs::write(dir.join("a.stl"), binary_stl(&tris, b"made by a test")).unwrap();
        std::fs::write(dir.join("b.STL"), binary_stl(&tris, b"solid but binary")).unwrap();
        std::fs::write(dir.join("c.stl"), ascii_stl(&tris)).unwrap();
        let obj =
            "# a box of quads\no box\nv 0 0 0\nv 1 0 0\nv 0 2 0\nv 1 2 0\nv 0 0 0.5\nv 1 0 0.5\nv 0 2 0.5\nv 1 2 0.5\n\
                   f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
        std::fs::write(dir.join("d.obj"), obj).unwrap();
        for name in ["a.stl", "b.STL", "c.stl", "d.obj"] {
            let m = Mesh::read(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_box(&m, 8, 12, [1.0, 2.0, 0.5]);
        }
        // What is not a mesh says why.
        std::fs::write(dir.join("e.stl"), b"neither ascii nor binary").unwrap();
        assert!(Mesh::read(&dir.join("e.stl")).unwrap_err().contains("not an STL file"));
        assert!(Mesh::read(&dir.join("f.stl")).unwrap_err().contains("cannot read"));
        assert!(Mesh::read(&dir.join("g.msh"))
            .unwrap_err()
            .contains(".msh format is not read"));
        std::fs::create_dir_all(dir.join("dir.stl")).unwrap();
        assert!(Mesh::read(&dir.join("dir.stl"))
            .unwrap_err()
            .contains("not a regular file"));
        std::fs::write(dir.join("h.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
        assert!(Mesh::read(&dir.join("h.obj")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A fine sphere capped at 500 triangles keeps its bounds to within a cell.
    #[test]
    fn a_simplified_mesh_stays_under_its_cap_and_within_its_bounds() {
        let (n, m) = (60usize, 40usize);
        let mut mesh = Mesh::default();
        for i in 0..=m {
            let th = std::f32::consts::PI * i as f32 / m as f32;
            for j in 0..n {
                let ph = 2.0 * std::f32::consts::PI * j as f32 / n as f32;
                mesh.vertices.push([th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()]);
            }
        }
        for i in 0..m {
            for j in 0..n {
                let (a, b) = ((i * n + j) as u32, (i * n + (j + 1) % n) as u32);
                let (c, d) = (a + n as u32, b + n as u32);
                mesh.triangles.push([a, c, d]);
                mesh.triangles.push([a, d, b]);
            }
        }
        assert_eq!(mesh.simplified(1 << 20), mesh);
        let s = mesh.simplified(500);
        assert!(
            s.triangles.len() <= 500 && s.triangles.len() > 100,
            "{}",
            s.triangles.len()
        );
        let (lo, hi) = s.bounds().unwrap();
        for k in 0..3 {
            assert!(
                lo[k] > -1.001 && lo[k] < -0.7 && hi[k] < 1.001 && hi[k] > 0.7,
                "{lo:?} {hi:?}"
            );
        }
    }
}
