//! Fuzz test of the `liemid` binary: seeded mutations of every scenario in `examples/`
//! (`liemid run`, `liemid many` and `liemid spins` files), each run through the real binary
//! in a directory of its own.
//!
//! A case passes when the binary does not panic, exits with 0, 1 or 2, writes nothing when
//! it exits with 2 (bad input), and says what went wrong in one line on standard error.
//! Runs are kept small (`--max-steps`, `--max-body-steps`, `--max-spin-steps`, the dipolar
//! fluid scaled to 27 bodies and spin lattices to 8×8 before mutation) so that a few thousand cases fit in CI's budget. Without the
//! test harness, so that the case count and the outcome counts are printed in CI's log.

#[path = "common/fuzz.rs"]
mod fuzz;

use std::path::{Path, PathBuf};

use fuzz::{run_all, Case, Input, Rng};

/// Cases per example file.
const CASES_PER_FILE: usize = 750;

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

/// The arguments of a case of `kind` (small runs: `--max-steps` and the like).
fn arguments(kind: Kind) -> Vec<String> {
    let args: &[&str] = match kind {
        Kind::Many => &[
            "many",
            "--scenario",
            "scenario.toml",
            "--max-body-steps",
            "200000",
            "--threads",
            "1",
        ],
        Kind::Spins => &[
            "spins",
            "scenario.toml",
            "--max-spin-steps",
            "2000000",
            "--threads",
            "1",
        ],
        Kind::Run => &["run", "scenario.toml", "--max-steps", "20000"],
    };
    args.iter().map(|a| a.to_string()).collect()
}

fn main() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&examples)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 4, "examples/ holds {} scenarios", files.len());

    // Every case from the seed, before any runs.
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
            let scenario = mutate(&text, &mut rng);
            // With the trajectory on standard output (`path = "-"`), the summary goes to
            // standard error by design.
            let to_stdout = String::from_utf8_lossy(&scenario).contains("path = \"-\"");
            cases.push(Case {
                label: format!("scenario:{}", f.file_name().unwrap().to_string_lossy()),
                inputs: vec![Input::File("scenario.toml".into(), scenario)],
                args: arguments(kind),
                to_stdout,
            });
        }
    }
    run_all("fuzz", &cases);
}
