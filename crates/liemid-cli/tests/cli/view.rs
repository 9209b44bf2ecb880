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
