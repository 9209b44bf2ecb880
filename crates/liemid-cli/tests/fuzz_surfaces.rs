//! Fuzz test of the newer surfaces of the `liemid` binary (issue 48), each case run through
//! the real binary in a directory of its own and held to the clean outcome of
//! `common/fuzz.rs` (no hang, no panic, exit 0/1/2, one readable line, inputs untouched,
//! nothing written on exit 2):
//! - `model`: the MJCF and URDF files of `examples/multibody`, mutated (attribute values,
//!   lines removed, repeated or swapped, tags renamed, cut short, random bytes, entities,
//!   `<include>`s of itself, of a missing file, a directory, a device or a FIFO), run by
//!   `liemid multibody` with random methods, drifts, steps, end times and outputs (among
//!   them the model and its included file);
//! - `adaptive`: `liemid run --adaptive` with random tolerances, end times, densities,
//!   methods, outputs and bounds;
//! - `checkpoint`: a checkpoint of `liemid run` edited (values, types, cut short, bytes),
//!   sealed again or not, and resumed;
//! - `state`: a `liemid many` state file edited byte-wise and resumed;
//! - `spins`: `liemid spins` with random options.
//!
//! Without the test harness, so that the case count and the outcome counts are printed in
//! CI's log.

#[path = "common/fuzz.rs"]
mod fuzz;

use std::path::Path;
use std::process::Command;

use fuzz::{case_dir, root, run_all, Case, Input, Rng};

const NAME: &str = "fuzz-surfaces";

/// Cases per model file, and per other surface.
const MODEL_CASES: usize = 200;
const ADAPTIVE_CASES: usize = 200;
const CHECKPOINT_CASES: usize = 200;
const STATE_CASES: usize = 100;
const SPINS_CASES: usize = 200;

/// Values a mutated attribute may get.
const ATTRIBUTE_VALUES: &[&str] = &[
    "1e300",
    "-1e300",
    "1e308 1e308 1e308",
    "1e-300",
    "nan",
    "inf",
    "-inf",
    "0",
    "-1",
    "0 0 0",
    "0 0 0 0",
    "1 2",
    "1 2 3 4 5 6 7",
    "",
    " ",
    "abc",
    "true",
    "&amp;",
    "1e18",
    "9223372036854775807",
    "-0.0",
    "2.5",
    "0 0 1",
    "1 0 0 0",
    "arm.xml",
    "model.xml",
    "world",
    "ball",
    "free",
    "hinge",
    "slide",
    "universal",
];

/// One mutation of a model file's text.
fn mutate_model(text: &str, rng: &mut Rng) -> Vec<u8> {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let n = lines.len();
    match rng.below(12) {
        0..=4 => {
            // An attribute's value (most bugs hide in values).
            let spans: Vec<(usize, usize, usize)> = lines
                .iter()
                .enumerate()
                .flat_map(|(i, l)| {
                    let mut found = Vec::new();
                    let mut from = 0;
                    while let Some(k) = l[from..].find("=\"") {
                        let start = from + k + 2;
                        let Some(len) = l[start..].find('"') else { break };
                        found.push((i, start, start + len));
                        from = start + len + 1;
                    }
                    found
                })
                .collect();
            if let Some(&(i, a, b)) = spans.get(rng.below(spans.len())) {
                let value = if rng.chance(0.05) {
                    // 20,000 numbers.
                    vec!["1.5"; 20_000].join(" ")
                } else {
                    rng.pick(ATTRIBUTE_VALUES).to_string()
                };
                lines[i].replace_range(a..b, &value);
            }
        }
        5 => {
            lines.remove(rng.below(n));
        }
        6 => {
            let i = rng.below(n);
            let l = lines[i].clone();
            lines.insert(i, l);
        }
        7 => {
            let (i, j) = (rng.below(n), rng.below(n));
            lines.swap(i, j);
        }
        8 => {
            // A tag renamed.
            let tags = [
                "<body",
                "<joint",
                "<geom",
                "<inertial",
                "<link",
                "<site",
                "<include",
                "<default",
            ];
            let (from, to) = (rng.pick(&tags), rng.pick(&tags));
            let i = rng.below(n);
            lines[i] = lines[i].replacen(from, to, 1);
        }
        9 => {
            // An include of itself, of the other file, of what is not a model.
            let file = rng.pick(&[
                "model.xml",
                "arm.xml",
                "missing.xml",
                ".",
                "fifo",
                "/dev/zero",
                "../work",
                "",
            ]);
            let at = (1 + rng.below(n.saturating_sub(1).max(1))).min(n);
            lines.insert(at, format!("<include file=\"{file}\"/>"));
        }
        10 => {
            // Entities: one that expands a lot, and its use.
            let laugh = "<!DOCTYPE m [<!ENTITY a \"aaaaaaaaaa\"><!ENTITY b \"&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;\">\
                         <!ENTITY c \"&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;\"><!ENTITY d \"&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;\">]>";
            let at = usize::from(lines.first().is_some_and(|l| l.starts_with("<?xml")));
            lines.insert(at, laugh.to_string());
            let i = rng.below(lines.len());
            lines[i] = lines[i].replacen("name=\"", "name=\"&d;", 1);
        }
        _ => {
            let mut bytes = lines.join("\n").into_bytes();
            if rng.chance(0.5) {
                let cut = rng.below(bytes.len() + 1);
                bytes.truncate(cut);
            } else {
                for _ in 0..1 + rng.below(4) {
                    let at = rng.below(bytes.len() + 1);
                    bytes.insert(at, (rng.next() & 0xff) as u8);
                }
            }
            return bytes;
        }
    }
    (lines.join("\n") + "\n").into_bytes()
}

/// `flag value` with probability `p`, the value picked from `values`.
fn maybe(args: &mut Vec<String>, rng: &mut Rng, p: f64, flag: &str, values: &[&str]) {
    if rng.chance(p) {
        args.push(flag.to_string());
        args.push(rng.pick(values).to_string());
    }
}

fn strings(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

fn model_cases(examples: &Path, rng: &mut Rng, cases: &mut Vec<Case>) {
    let dir = examples.join("multibody");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml" || x == "urdf"))
        .collect();
    files.sort();
    assert!(files.len() >= 6, "{} model files", files.len());
    let arm = std::fs::read(dir.join("arm.xml")).unwrap();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let urdf = f.extension().is_some_and(|x| x == "urdf");
        let model = if urdf { "model.urdf" } else { "model.xml" };
        for _ in 0..MODEL_CASES {
            let mutated = mutate_model(&text, rng);
            // The scene includes arm.xml: every case has it, an input when the model names it
            // (an include may), else a file an output may replace; and a FIFO to include.
            let names_arm = !urdf && String::from_utf8_lossy(&mutated).contains("arm.xml");
            let mut inputs = vec![Input::File(model.into(), mutated)];
            inputs.push(if names_arm {
                Input::File("arm.xml".into(), arm.clone())
            } else {
                Input::Other("arm.xml".into(), arm.clone())
            });
            inputs.push(Input::Fifo("fifo".into()));
            let mut args = strings(&["multibody", model, "--max-steps", "3000"]);
            let t_end = if rng.chance(0.85) {
                "0.01"
            } else {
                rng.pick(&["0", "-1", "nan", "1e9", "1e300", "0.2"])
            };
            args.extend(strings(&["--t-end", t_end]));
            maybe(
                &mut args,
                rng,
                0.4,
                "--method",
                &["liemid", "liemid4", "liemid8", "rk4", "dop853", "euler"],
            );
            maybe(&mut args, rng, 0.3, "--drift", &["midpoint", "variational", "exact"]);
            maybe(
                &mut args,
                rng,
                0.3,
                "--step",
                &["1e-3", "1e-4", "0.1", "1e-300", "-1", "nan", "0"],
            );
            maybe(&mut args, rng, 0.2, "--every", &["1", "0", "7"]);
            maybe(&mut args, rng, 0.1, "--rtol", &["1e-6", "0", "-1", "nan", "1e-30"]);
            let outputs = ["out.csv", "out.npy", model, "arm.xml", "fifo", ".", "missing/out.csv"];
            maybe(&mut args, rng, 0.3, "--out", &outputs);
            maybe(&mut args, rng, 0.1, "--view", &["v.html", model, "arm.xml"]);
            maybe(&mut args, rng, 0.1, "--json", &["j.json", model]);
            cases.push(Case {
                label: format!("model:{}", f.file_name().unwrap().to_string_lossy()),
                inputs,
                args,
                to_stdout: false,
            });
        }
    }
}

fn adaptive_cases(scenario: &[u8], rng: &mut Rng, cases: &mut Vec<Case>) {
    for _ in 0..ADAPTIVE_CASES {
        let mut args = strings(&["run", "scenario.toml", "--max-steps", "20000"]);
        let eps = rng.pick(&["0.3", "0.1", "1e-3", "1e-300", "0", "-1", "nan", "inf", "1e300", "abc"]);
        args.extend(strings(&["--adaptive", eps]));
        let t_end = if rng.chance(0.7) {
            "0.05"
        } else {
            rng.pick(&["0", "-1", "nan", "1e300", "1e9", "0.5"])
        };
        args.extend(strings(&["--t-end", t_end]));
        maybe(&mut args, rng, 0.3, "--rho", &["omega", "torque", "orbit", ""]);
        maybe(
            &mut args,
            rng,
            0.3,
            "--method",
            &["liemid-ea", "liemid-eav", "liemid-ex4", "liemid-e1", "rk4", "x"],
        );
        maybe(
            &mut args,
            rng,
            0.3,
            "--out",
            &["out.csv", "out.npy", "scenario.toml", "fifo"],
        );
        maybe(&mut args, rng, 0.2, "--every", &["1", "0", "3", "18446744073709551615"]);
        maybe(&mut args, rng, 0.1, "--checkpoint", &["c.json", "scenario.toml"]);
        maybe(&mut args, rng, 0.1, "--view", &["v.html", "scenario.toml"]);
        if rng.chance(0.1) {
            args.push("--allow-large-output".into());
        }
        cases.push(Case {
            label: "adaptive:fast_top.toml".into(),
            inputs: vec![
                Input::File("scenario.toml".into(), scenario.to_vec()),
                Input::Fifo("fifo".into()),
            ],
            args,
            to_stdout: false,
        });
    }
}

/// Values an edited checkpoint's number, string or array may get.
const JSON_VALUES: &[&str] = &[
    "0",
    "-1",
    "1e300",
    "-1e300",
    "1e-300",
    "18446744073709551615",
    "1.5",
    "null",
    "true",
    "\"x\"",
    "[]",
    "[1, 2]",
    "{}",
];

/// Every path to a leaf of `v`.
fn leaves(v: &serde_json::Value, at: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                at.push(k.clone());
                leaves(x, at, out);
                at.pop();
            }
        }
        serde_json::Value::Array(a) => {
            for (k, x) in a.iter().enumerate() {
                at.push(k.to_string());
                leaves(x, at, out);
                at.pop();
            }
        }
        _ => out.push(at.clone()),
    }
}

fn checkpoint_cases(scenario: &[u8], rng: &mut Rng, cases: &mut Vec<Case>) {
    // A run interrupted after a periodic checkpoint: the checkpoint at step 140 of 200 and
    // the trajectory's `.partial` file.
    let setup = std::env::temp_dir().join(format!("{NAME}-setup-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&setup);
    std::fs::create_dir_all(&setup).unwrap();
    std::fs::write(setup.join("scenario.toml"), scenario).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_liemid"))
        .current_dir(&setup)
        .args([
            "run",
            "scenario.toml",
            "--t-end",
            "0.2",
            "--out",
            "cut.csv",
            "--checkpoint",
            "c.json",
            "--checkpoint-every",
            "70",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let good: serde_json::Value = serde_json::from_slice(&std::fs::read(setup.join("c.json")).unwrap()).unwrap();
    let partial = std::fs::read(setup.join("cut.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&setup);
    let mut paths = Vec::new();
    leaves(&good, &mut Vec::new(), &mut paths);
    let first = cases.len();
    for i in 0..CHECKPOINT_CASES {
        // The case's own directory in the checkpoint's (absolute) paths.
        let dir = case_dir(&root(NAME), first + i);
        let mut c = good.clone();
        c["settings"]["output"][0] = dir.join("cut.csv").display().to_string().into();
        c["settings"]["checkpoint"][0] = dir.join("c.json").display().to_string().into();
        let bytes = match rng.below(4) {
            0 => {
                // A value edited, the checksum made right: the content is validated.
                let p = &paths[rng.below(paths.len())];
                let mut v = &mut c;
                for k in p {
                    v = if let Ok(i) = k.parse::<usize>() {
                        &mut v[i]
                    } else {
                        &mut v[k.as_str()]
                    };
                }
                *v = serde_json::from_str(rng.pick(JSON_VALUES)).unwrap();
                let text = c.to_string();
                liemid_app::shared::checkpoint::reseal(&text).map_or(text.into_bytes(), String::into_bytes)
            }
            1 => {
                // A value edited by hand: the checksum no longer matches.
                let p = &paths[rng.below(paths.len())];
                let mut v = &mut c;
                for k in p {
                    v = if let Ok(i) = k.parse::<usize>() {
                        &mut v[i]
                    } else {
                        &mut v[k.as_str()]
                    };
                }
                *v = serde_json::from_str(rng.pick(JSON_VALUES)).unwrap();
                c.to_string().into_bytes()
            }
            2 => {
                // Cut short, or bytes inserted.
                let mut b = liemid_app::shared::checkpoint::reseal(&c.to_string())
                    .unwrap()
                    .into_bytes();
                if rng.chance(0.5) {
                    let cut = rng.below(b.len());
                    b.truncate(cut);
                } else {
                    let at = rng.below(b.len());
                    b.insert(at, (rng.next() & 0xff) as u8);
                }
                b
            }
            _ => liemid_app::shared::checkpoint::reseal(&c.to_string())
                .unwrap()
                .into_bytes(),
        };
        let mut args = strings(&["run", "--resume", "c.json"]);
        maybe(&mut args, rng, 0.1, "--max-steps", &["10", "1000"]);
        cases.push(Case {
            label: "checkpoint:fast_top.toml".into(),
            inputs: vec![
                Input::File("c.json".into(), bytes),
                Input::Other("cut.csv.partial".into(), partial.clone()),
            ],
            args,
            to_stdout: false,
        });
    }
}

fn state_cases(rng: &mut Rng, cases: &mut Vec<Case>) {
    let setup = std::env::temp_dir().join(format!("{NAME}-state-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&setup);
    std::fs::create_dir_all(&setup).unwrap();
    let fluid = ["many", "--model", "dipoles", "--bodies", "27", "--threads", "1"];
    let o = Command::new(env!("CARGO_BIN_EXE_liemid"))
        .current_dir(&setup)
        .args(fluid)
        .args(["--t-end", "0.01", "--state", "s.bin"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let good = std::fs::read(setup.join("s.bin")).unwrap();
    let _ = std::fs::remove_dir_all(&setup);
    for _ in 0..STATE_CASES {
        let mut b = good.clone();
        match rng.below(4) {
            0 => {
                let at = rng.below(b.len());
                b[at] ^= 1 << rng.below(8);
            }
            1 => {
                let cut = rng.below(b.len());
                b.truncate(cut);
            }
            2 => b.extend_from_slice(&[0u8; 208]),
            _ => {
                // The body count of the header.
                let n = [0u64, 1, 26, 28, u64::MAX, 1 << 40][rng.below(6)];
                b[22..30].copy_from_slice(&n.to_le_bytes());
            }
        }
        let mut args = strings(&fluid);
        args.extend(strings(&["--t-end", "0.02", "--resume", "s.bin"]));
        cases.push(Case {
            label: "state:dipoles".into(),
            inputs: vec![Input::File("s.bin".into(), b)],
            args,
            to_stdout: false,
        });
    }
}

fn spins_cases(scenario: &[u8], rng: &mut Rng, cases: &mut Vec<Case>) {
    for _ in 0..SPINS_CASES {
        let mut args = strings(&[
            "spins",
            "scenario.toml",
            "--max-spin-steps",
            "2000000",
            "--threads",
            "1",
        ]);
        maybe(
            &mut args,
            rng,
            0.4,
            "--method",
            &["split", "split4", "midpoint", "heun", "depondt", "rk4", "x"],
        );
        maybe(
            &mut args,
            rng,
            0.4,
            "--step",
            &["0.01", "1e-300", "-1", "nan", "1e300", "0", "0.5"],
        );
        maybe(
            &mut args,
            rng,
            0.4,
            "--t-end",
            &["0.1", "1e12", "-1", "nan", "0", "1e300"],
        );
        maybe(&mut args, rng, 0.2, "--every", &["1", "0", "5"]);
        maybe(
            &mut args,
            rng,
            0.2,
            "--out",
            &["o.csv", "o.npy", "scenario.toml", "fifo", "-"],
        );
        maybe(&mut args, rng, 0.2, "--final", &["f.npy", "scenario.toml", "f.txt"]);
        maybe(&mut args, rng, 0.1, "--snapshot", &["s.png", "s.txt", "scenario.toml"]);
        maybe(&mut args, rng, 0.1, "--view", &["v.html", "scenario.toml"]);
        maybe(&mut args, rng, 0.2, "--max-steps", &["1", "10", "0"]);
        let to_stdout = args.windows(2).any(|w| w[0] == "--out" && w[1] == "-");
        cases.push(Case {
            label: "spins:spins_square.toml".into(),
            inputs: vec![
                Input::File("scenario.toml".into(), scenario.to_vec()),
                Input::Fifo("fifo".into()),
            ],
            args,
            to_stdout,
        });
    }
}

fn main() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let top = std::fs::read(examples.join("fast_top.toml")).unwrap();
    let spins = std::fs::read_to_string(examples.join("spins_square.toml"))
        .unwrap()
        .replace("[64, 64]", "[8, 8]")
        .replace("[128, 128]", "[8, 8]");
    let mut rng = Rng(0x5EED_0048);
    let mut cases = Vec::new();
    model_cases(&examples, &mut rng, &mut cases);
    adaptive_cases(&top, &mut rng, &mut cases);
    checkpoint_cases(&top, &mut rng, &mut cases);
    state_cases(&mut rng, &mut cases);
    spins_cases(spins.as_bytes(), &mut rng, &mut cases);
    run_all(NAME, &cases);
}
