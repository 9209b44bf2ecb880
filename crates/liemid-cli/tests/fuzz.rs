//! Fuzz test of the `liemid` binary: seeded mutations of every scenario in `examples/`
//! (`liemid run`, `liemid many` and `liemid spins` files), each run through the real binary
//! in a directory of its own.
//!
//! A case passes when the binary does not panic, exits with 0, 1 or 2, writes nothing when
//! it exits with 2 (bad input), and says what went wrong in one line on standard error.
//! Runs are kept small (`--max-steps`, `--max-body-steps`, `--max-spin-steps`, the dipolar
//! fluid scaled to 27 bodies and spin lattices to 8×8 before mutation) so that a few thousand cases fit in CI's budget. Without the
//! test harness, so that the case count and the outcome counts are printed in CI's log.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Cases per example file.
const CASES_PER_FILE: usize = 750;
/// Seconds a case may take before it counts as hanging.
const TIMEOUT: Duration = Duration::from_secs(30);

/// SplitMix64: reproducible cases from the seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a>(&mut self, items: &[&'a str]) -> &'a str {
        items[self.below(items.len())]
    }
}

/// Values a mutated key may get: huge, tiny, NaN, negative, zero, other types, and (for
/// paths) names relative to the case's directory, among them the scenario itself.
const VALUES: &[&str] = &[
    "1e300",
    "-1e300",
    "1e308",
    "1e-300",
    "-1",
    "0",
    "-0.0",
    "nan",
    "inf",
    "-inf",
    "1e18",
    "9223372036854775807",
    "-9223372036854775808",
    "2.5",
    "1e9",
    "3",
    "\"text\"",
    "\"\"",
    "\".\"",
    "\"..\"",
    "\"-\"",
    "\"scenario.toml\"",
    "\"out.npy\"",
    "\"out.csv\"",
    "\"missing/out.csv\"",
    "true",
    "[]",
    "[1, 2]",
    "[1.0, 2.0, 3.0]",
    "[1, 1, 3]",
    "[1e300, 0, 0]",
    "[[1, 0, 0], [0, 1, 0], [0, 0, 1]]",
    "[[2, 0, 0], [0, 1, 0], [0, 0, 1]]",
    "[0.5, 0.5, 0.5, 0.5]",
    "[2, 0, 0, 0]",
    "{ a = 1 }",
];

/// One mutation of `text`.
fn mutate(text: &str, rng: &mut Rng) -> Vec<u8> {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let n = lines.len();
    match rng.below(9) {
        0 => {
            lines.remove(rng.below(n));
        }
        1 => {
            let i = rng.below(n);
            let l = lines[i].clone();
            lines.insert(i, l);
        }
        2 => {
            let (i, j) = (rng.below(n), rng.below(n));
            lines.swap(i, j);
        }
        3..=5 => {
            // Replace the value of a key (the favourite: most bugs hide in values).
            let keyed: Vec<usize> = (0..n).filter(|&i| lines[i].contains('=')).collect();
            if let Some(&i) = keyed.get(rng.below(keyed.len())) {
                let key = lines[i].split('=').next().unwrap_or("").trim().to_string();
                lines[i] = format!("{key} = {}", rng.pick(VALUES));
            }
        }
        6 => {
            // Rename a key or a section.
            let i = rng.below(n);
            let name = rng.pick(&["x", "body", "system", "torque", "output", "path", "every", "mass"]);
            lines[i] = if lines[i].starts_with('[') {
                format!("[{name}]")
            } else {
                match lines[i].split_once('=') {
                    Some((_, v)) => format!("{name} ={v}"),
                    None => format!("{name} = 1"),
                }
            };
        }
        7 => {
            // Truncate at a random byte.
            let joined = lines.join("\n");
            let cut = rng.below(joined.len() + 1);
            return joined.as_bytes()[..cut].to_vec();
        }
        _ => {
            // Random bytes somewhere.
            let mut bytes = lines.join("\n").into_bytes();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(bytes.len() + 1);
                bytes.insert(at, (rng.next() & 0xff) as u8);
            }
            return bytes;
        }
    }
    (lines.join("\n") + "\n").into_bytes()
}

/// What one case did.
#[derive(Debug)]
struct Outcome {
    code: Option<i32>,
    problem: Option<String>,
}

/// Which command a scenario file is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// `liemid run`.
    Run,
    /// `liemid many --scenario`.
    Many,
    /// `liemid spins`.
    Spins,
}

fn run_case(bin: &Path, dir: &Path, scenario: &[u8], kind: Kind) -> Outcome {
    std::fs::create_dir_all(dir).unwrap();
    let file = dir.join("scenario.toml");
    std::fs::write(&file, scenario).unwrap();
    let mut cmd = Command::new(bin);
    cmd.current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    match kind {
        Kind::Many => {
            cmd.args([
                "many",
                "--scenario",
                "scenario.toml",
                "--max-body-steps",
                "200000",
                "--threads",
                "1",
            ]);
        }
        Kind::Spins => {
            cmd.args([
                "spins",
                "scenario.toml",
                "--max-spin-steps",
                "2000000",
                "--threads",
                "1",
            ]);
        }
        Kind::Run => {
            cmd.args(["run", "scenario.toml", "--max-steps", "20000"]);
        }
    }
    // With the trajectory on standard output (`path = "-"`), the summary goes to standard
    // error by design.
    let to_stdout = String::from_utf8_lossy(scenario).contains("path = \"-\"");
    let mut child = cmd.spawn().unwrap();
    let started = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if started.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(1));
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        use std::io::Read;
        let _ = e.read_to_string(&mut err);
    }
    let Some(status) = status else {
        return Outcome {
            code: None,
            problem: Some(format!("no exit after {TIMEOUT:?}")),
        };
    };
    let code = status.code();
    let mut problem = None;
    let lines = err.trim_end().lines().count();
    if err.contains("panicked") || code == Some(101) {
        problem = Some(format!("panic: {err}"));
    } else if !matches!(code, Some(0..=2)) {
        problem = Some(format!("exit code {code:?}: {err}"));
    } else if code != Some(0) && lines != 1 {
        problem = Some(format!("{lines} lines on stderr: {err}"));
    } else if code == Some(0) && lines > 1 && !to_stdout {
        problem = Some(format!("{lines} lines on stderr after success: {err}"));
    } else if code == Some(2) {
        let written: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n != "scenario.toml")
            .collect();
        if !written.is_empty() || std::fs::read(&file).map(|b| b != scenario).unwrap_or(true) {
            problem = Some(format!("exit 2 but wrote {written:?} (or changed the scenario): {err}"));
        }
    }
    Outcome { code, problem }
}

fn main() {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_liemid"));
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&examples)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 4, "examples/ holds {} scenarios", files.len());
    let root = std::env::temp_dir().join(format!("liemid-fuzz-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);

    // Every case from the seed, before any runs: (file, many?, bytes).
    let mut rng = Rng(0x5EED_0014);
    let mut cases = Vec::new();
    for f in &files {
        let mut text = std::fs::read_to_string(f).unwrap();
        let kind = if text.contains("[system]") {
            Kind::Many
        } else if text.contains("[lattice]") {
            Kind::Spins
        } else {
            Kind::Run
        };
        // Small enough to run in milliseconds; the mutations then change it.
        if kind == Kind::Many {
            text = text.replace("bodies = 1000", "bodies = 27");
        }
        if kind == Kind::Spins {
            text = text.replace("[64, 64]", "[8, 8]").replace("[128, 128]", "[8, 8]");
        }
        for _ in 0..CASES_PER_FILE {
            cases.push((
                f.file_name().unwrap().to_string_lossy().into_owned(),
                kind,
                mutate(&text, &mut rng),
            ));
        }
    }

    let started = Instant::now();
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get()).min(4);
    let outcomes: Vec<(usize, Outcome)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                let (cases, bin, root) = (&cases, &bin, &root);
                scope.spawn(move || {
                    let mut out = Vec::new();
                    for i in (w..cases.len()).step_by(workers) {
                        let dir = root.join("cases").join(i.to_string()).join("work");
                        let (_, kind, bytes) = &cases[i];
                        out.push((i, run_case(bin, &dir, bytes, *kind)));
                        let _ = std::fs::remove_dir_all(root.join("cases").join(i.to_string()));
                    }
                    out
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    let _ = std::fs::remove_dir_all(&root);

    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    let mut failures = Vec::new();
    for (i, o) in &outcomes {
        let key = o.code.map_or("hung".to_string(), |c| format!("exit {c}"));
        *counts.entry(key).or_default() += 1;
        if let Some(p) = &o.problem {
            failures.push(format!(
                "case {i} ({}): {p}\n--- scenario ---\n{}",
                cases[*i].0,
                String::from_utf8_lossy(&cases[*i].2)
            ));
        }
    }
    let summary: Vec<String> = counts.iter().map(|(k, v)| format!("{k}: {v}")).collect();
    println!(
        "fuzz: {} cases from {} example files in {:.1} s ({})",
        outcomes.len(),
        files.len(),
        started.elapsed().as_secs_f64(),
        summary.join(", ")
    );
    if failures.is_empty() {
        println!("fuzz: {} passed, 0 failed", outcomes.len());
    } else {
        for f in failures.iter().take(10) {
            eprintln!("{f}\n");
        }
        eprintln!(
            "fuzz: {} passed, {} failed",
            outcomes.len() - failures.len(),
            failures.len()
        );
        std::process::exit(1);
    }
}
