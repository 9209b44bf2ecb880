//! `--view FILE.html` on every domain's command: a self-contained page that states its
//! frames, written without changing any other output; a wrong path is refused before the
//! run (exit 2, one line).

use crate::common;
#[allow(unused_imports)]
use common::{examples, run_in, scratch, stderr, stdout};
use std::path::Path;

/// Check a page: self-contained (no http(s) src/href in its markup), the frames stated.
fn check_page(page: &Path, frames_of_steps: &str) {
    let html = std::fs::read_to_string(page).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert!(html.contains(frames_of_steps), "{frames_of_steps} not in the page");
    for bad in ["src=\"http", "href=\"http", "src='http", "href='http", "<script src"] {
        assert!(!html.contains(bad), "the page holds {bad}");
    }
    assert!(html.contains("id=\"data-frames\""));
    assert!(html.len() < 5_000_000, "{} bytes", html.len());
    assert!(!Path::new(&format!("{}.partial", page.display())).exists());
}

fn refusals(dir: &Path, command: &[&str], input: Option<&str>) {
    std::fs::create_dir_all(dir.join("a-dir")).unwrap();
    let mut wrong = vec!["a-dir", "/dev/null"];
    wrong.extend(input);
    for path in wrong {
        let o = run_in(dir, &[command, &["--view", path]].concat());
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "--view {path}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains("--view"), "{err}");
    }
}

#[test]
fn rigid_page_and_refusals() {
    let dir = scratch("view-rigid");
    let file = examples().join("tennis_racket_flip.toml");
    let file = file.to_str().unwrap();
    let o = run_in(
        &dir,
        &["run", file, "--no-output", "--step", "1e-2", "--view", "r.html"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("view: r.html (1001 frames of 1000 steps)"));
    check_page(&dir.join("r.html"), "1001 frames of 1000 steps");
    // Without --view the trajectory is the same bytes.
    let a = run_in(&dir, &["run", file, "--step", "1e-2", "--out", "a.csv"]);
    let b = run_in(
        &dir,
        &["run", file, "--step", "1e-2", "--out", "b.csv", "--view", "b.html"],
    );
    assert!(a.status.success() && b.status.success());
    assert_eq!(
        std::fs::read(dir.join("a.csv")).unwrap(),
        std::fs::read(dir.join("b.csv")).unwrap()
    );
    refusals(&dir, &["run", file, "--no-output"], Some(file));
    let o = run_in(&dir, &["run", file, "--out", "same.csv", "--view", "same.csv"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// `--adaptive EPS --view`: one frame a step at the adaptive steps' times (the page states
/// steps + 1 frames), the trajectory unchanged by the page; the eccentric satellite, whose
/// run keeps no frames, refuses `--view` in one line.
#[test]
fn adaptive_rigid_page_and_satellite_refusal() {
    let dir = scratch("view-adaptive");
    let file = examples().join("tennis_racket_flip.toml");
    let file = file.to_str().unwrap();
    let args = ["run", file, "--adaptive", "1e-2"];
    let o = run_in(
        &dir,
        &[&args[..], &["--no-output", "--json", "--view", "a.html"]].concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let steps: u64 = out
        .split("\"steps\":")
        .nth(1)
        .and_then(|r| r.split([',', '}']).next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no steps in {out}"));
    assert!(out.contains("\"adaptive\":{"), "{out}");
    let stated = format!("{} frames of {steps} steps", steps + 1);
    assert!(
        stderr(&o).contains(&format!("view: a.html ({stated})")),
        "{}",
        stderr(&o)
    );
    check_page(&dir.join("a.html"), &stated);
    let a = run_in(&dir, &[&args[..], &["--out", "a.csv"]].concat());
    let b = run_in(&dir, &[&args[..], &["--out", "b.csv", "--view", "b.html"]].concat());
    assert!(a.status.success() && b.status.success(), "{}", stderr(&b));
    assert_eq!(
        std::fs::read(dir.join("a.csv")).unwrap(),
        std::fs::read(dir.join("b.csv")).unwrap()
    );
    refusals(&dir, &[&args[..], &["--no-output"]].concat(), Some(file));
    let o = run_in(
        &dir,
        &[
            "run",
            "--problem",
            "eccentric-satellite",
            "--adaptive",
            "0.05",
            "--view",
            "s.html",
        ],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("--view is not available for --problem eccentric-satellite"),
        "{err}"
    );
    assert!(!dir.join("s.html").exists());
}

#[test]
fn many_page_and_refusals() {
    let dir = scratch("view-many");
    let file = examples().join("dipolar_fluid.toml");
    let file = file.to_str().unwrap();
    let args = ["many", "--scenario", file, "--bodies", "64", "--out", "t.csv"];
    let o = run_in(&dir, &[&args[..], &["--view", "m.html"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    check_page(&dir.join("m.html"), "11 frames of 100 steps");
    refusals(&dir, &args, Some(file));
}

#[test]
fn spins_page_and_refusals() {
    let dir = scratch("view-spins");
    let file = examples().join("spins_square.toml");
    let file = file.to_str().unwrap();
    // The time series goes to the scratch folder, not next to the example.
    let o = run_in(
        &dir,
        &["spins", file, "--every", "100", "--out", "s.csv", "--view", "s.html"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    check_page(&dir.join("s.html"), "11 frames of 1000 steps");
    refusals(&dir, &["spins", file], Some(file));
}

#[test]
fn beam_page_and_refusals() {
    let dir = scratch("view-beam");
    let o = run_in(&dir, &["beam", "--t-end", "3", "--view", "b.html"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let html = std::fs::read_to_string(dir.join("b.html")).unwrap();
    assert!(html.contains("\"kind\":\"beam\""));
    check_page(&dir.join("b.html"), " frames of ");
    refusals(&dir, &["beam", "--t-end", "1"], None);
}

/// The numbers of the page's `<script id="ID">` block (base64 of little-endian `f32`).
fn page_floats(html: &str, id: &str) -> Vec<f32> {
    let start = html.find(&format!("id=\"{id}\">")).unwrap() + id.len() + 6;
    let text = &html[start..start + html[start..].find("</script>").unwrap()];
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let mut bytes = Vec::new();
    for q in text.as_bytes().chunks(4) {
        let n = q
            .iter()
            .fold(0u32, |n, &c| (n << 6) | u32::from(if c == b'=' { 0 } else { value(c) }));
        let pad = q.iter().filter(|&&c| c == b'=').count();
        bytes.extend_from_slice(&n.to_be_bytes()[1..4 - pad]);
    }
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// A model with mesh geoms (`compiler meshdir`, a binary STL the test writes): the page
/// holds the mesh's vertices and triangles and draws it at the asset's scale; a geom whose
/// file is missing is drawn as the box of its `size` with a note naming the geom and the
/// file; `--view` onto the mesh file is refused as an input of the run, as for includes.
#[test]
fn multibody_page_draws_a_mesh_from_its_file_and_notes_a_missing_one() {
    let dir = scratch("view-mesh");
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    let v: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]];
    let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&4u32.to_le_bytes());
    for f in faces {
        stl.extend_from_slice(&[0u8; 12]);
        for k in f {
            for c in v[k] {
                stl.extend_from_slice(&c.to_le_bytes());
            }
        }
        stl.extend_from_slice(&[0, 0]);
    }
    std::fs::write(dir.join("meshes/tet.stl"), &stl).unwrap();
    let model = r#"<mujoco model="meshes"><compiler meshdir="meshes"/>
  <asset><mesh name="tet" file="tet.stl" scale="2 2 2"/><mesh file="gone.stl"/></asset>
  <worldbody><body name="b" pos="0 0 1"><joint type="hinge" axis="1 0 0"/>
    <inertial pos="0 0 -0.2" mass="1" diaginertia="0.01 0.01 0.01"/>
    <geom type="mesh" mesh="tet" rgba="0.2 0.6 0.9 1"/>
    <geom name="lost" type="mesh" mesh="gone" size="0.1 0.2 0.3"/>
  </body></worldbody></mujoco>"#;
    std::fs::write(dir.join("model.xml"), model).unwrap();
    let o = run_in(
        &dir,
        &["multibody", "model.xml", "--t-end", "0.01", "--view", "page.html"],
    );
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("the mesh of `lost` on body `b` is not drawn from `gone.stl`: cannot read the file")
            && err.contains("the box of the geom's size stands in for it"),
        "{err}"
    );
    check_page(&dir.join("page.html"), "frames of 10 steps");
    let html = std::fs::read_to_string(dir.join("page.html")).unwrap();
    assert!(html.contains("\"meshes\":[[4,4]]"), "the mesh's counts");
    assert!(html.contains("\"kind\":\"mesh\",\"mesh\":0"));
    assert!(html.contains("\"size\":[2.0,2.0,2.0]"), "the asset's scale");
    assert!(
        html.contains("\"kind\":\"box\"")
            && html.contains("\"size\":[0.10000000149011612,0.20000000298023224,0.30000001192092896]")
    );
    // The file's four vertices (merged from the twelve triangle corners), then its four
    // triangles over them.
    let numbers = page_floats(&html, "data-meshes");
    assert_eq!(numbers.len(), 24);
    let vertices: Vec<[f32; 3]> = numbers[..12].chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    for p in v {
        assert!(vertices.contains(&p), "{p:?} not in {vertices:?}");
    }
    for (t, f) in numbers[12..].chunks(3).zip(faces) {
        let corners: Vec<[f32; 3]> = t.iter().map(|&i| vertices[i as usize]).collect();
        assert_eq!(corners, f.map(|k| v[k]).to_vec());
    }
    // The mesh file is an input: --view onto it is refused and it is left as it was.
    for target in ["meshes/tet.stl", "model.xml"] {
        let before = std::fs::read(dir.join(target)).unwrap();
        let o = run_in(&dir, &["multibody", "model.xml", "--t-end", "0.01", "--view", target]);
        assert_eq!(o.status.code(), Some(2), "{target}: {}", stderr(&o));
        assert!(stderr(&o).contains("is the input"), "{target}: {}", stderr(&o));
        assert_eq!(std::fs::read(dir.join(target)).unwrap(), before);
    }
}

/// A model with contacts: each frame holds, after the bodies, 64 contact slots (point and
/// force, NaN when unused). A 1 kg box resting flat on a floor shows its four corners on
/// the floor, and their forces on the box add up to its weight, upward.
#[test]
fn multibody_page_holds_the_touching_contacts_and_their_forces() {
    let dir = scratch("view-contacts");
    std::fs::write(
        dir.join("box.xml"),
        r#"<mujoco><worldbody><geom name="floor" type="plane" size="0 0 1"/>
        <body name="box" pos="0 0 0.1"><freejoint/><geom type="box" size="0.1 0.1 0.1" mass="1"/></body>
        </worldbody></mujoco>"#,
    )
    .unwrap();
    let o = run_in(
        &dir,
        &["multibody", "box.xml", "--t-end", "0.05", "--view", "page.html"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let html = std::fs::read_to_string(dir.join("page.html")).unwrap();
    assert!(
        html.contains("\"contact_slots\":64"),
        "the scene does not say its contact slots"
    );
    let frames = page_floats(&html, "data-frames");
    let per_frame = 7 + 6 * 64;
    assert_eq!(frames.len() % per_frame, 0);
    let last = &frames[frames.len() - per_frame..];
    let slots: Vec<&[f32]> = last[7..].chunks_exact(6).collect();
    let touching: Vec<&&[f32]> = slots.iter().filter(|c| !c[0].is_nan()).collect();
    assert_eq!(touching.len(), 4, "{} contacts drawn", touching.len());
    assert!(slots[4..].iter().all(|c| c.iter().all(|v| v.is_nan())));
    let mut total = [0.0f64; 3];
    for c in &touching {
        assert!(
            c[2].abs() < 1e-6 && (c[0].abs() - 0.1).abs() < 1e-6 && (c[1].abs() - 0.1).abs() < 1e-6,
            "{c:?}"
        );
        for (t, f) in total.iter_mut().zip(&c[3..6]) {
            *t += f64::from(*f);
        }
    }
    // The closing half-kick's forces hold the box against gravity (9.81 N, f32 in the page).
    assert!(
        (total[2] - 9.81).abs() < 1e-4 && total[0].abs() < 1e-4 && total[1].abs() < 1e-4,
        "{total:?}"
    );
}
