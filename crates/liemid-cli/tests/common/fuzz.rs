//! What the fuzz harnesses share: a seeded generator, one case run through the real binary
//! in a directory of its own, the clean outcome every case must have, and the report.
//!
//! A case is clean when the binary does not hang or panic, exits with 0, 1 or 2, says what
//! went wrong in one line on standard error (notes and warnings aside; no Rust debug text, no number of
//! twenty digits or more, no line beyond 1000 characters), leaves every input file as it
//! was, and writes nothing when it exits with 2 (bad input).

// Each harness uses a part of it.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Seconds a case may take before it counts as hanging.
pub const TIMEOUT: Duration = Duration::from_secs(30);

/// SplitMix64: reproducible cases from the seed.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    pub fn pick<'a>(&mut self, items: &[&'a str]) -> &'a str {
        items[self.below(items.len())]
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        ((self.next() >> 11) as f64 / (1u64 << 53) as f64) < p
    }
}

/// A file a case starts with.
pub enum Input {
    /// A regular file and its bytes.
    File(String, Vec<u8>),
    /// A FIFO (a named pipe nobody writes to: opening it for reading blocks).
    Fifo(String),
    /// A file that lies in the directory but that the run does not read (an output may
    /// replace it).
    Other(String, Vec<u8>),
}

/// One case: the files of its directory, the arguments, and whether its output goes to
/// standard output (the summary then goes to standard error by design).
pub struct Case {
    /// Which surface and which example the case came from.
    pub label: String,
    /// The files of the case's directory before the run.
    pub inputs: Vec<Input>,
    /// The command's arguments.
    pub args: Vec<String>,
    /// The trajectory goes to standard output.
    pub to_stdout: bool,
}

/// What one case did.
pub struct Outcome {
    pub code: Option<i32>,
    pub problem: Option<String>,
}

/// The longest run of digits in `text`.
fn longest_digits(text: &str) -> usize {
    text.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

#[cfg(unix)]
fn make_fifo(path: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo reads it and returns.
    let rc = unsafe { libc::mkfifo(c.as_ptr(), 0o644) };
    assert_eq!(rc, 0, "mkfifo {}", path.display());
}

#[cfg(not(unix))]
fn make_fifo(_: &Path) {}

/// The names in `dir`.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Run `case` in `dir` (made afresh) and judge its outcome.
pub fn run_case(bin: &Path, dir: &Path, case: &Case) -> Outcome {
    std::fs::create_dir_all(dir).unwrap();
    for input in &case.inputs {
        match input {
            Input::File(name, bytes) | Input::Other(name, bytes) => std::fs::write(dir.join(name), bytes).unwrap(),
            Input::Fifo(name) => make_fifo(&dir.join(name)),
        }
    }
    let before = names(dir);
    let mut child = Command::new(bin)
        .current_dir(dir)
        .args(&case.args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read standard error while waiting, so that a long message cannot fill the pipe.
    let mut stderr_pipe = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        use std::io::Read;
        let mut err = Vec::new();
        let _ = stderr_pipe.read_to_end(&mut err);
        String::from_utf8_lossy(&err).into_owned()
    });
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
    let err = reader.join().unwrap();
    let Some(status) = status else {
        return Outcome {
            code: None,
            problem: Some(format!("no exit after {TIMEOUT:?}")),
        };
    };
    let code = status.code();
    let said: Vec<&str> = err
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with("liemid: note:") && !l.starts_with("liemid: warning:"))
        .collect();
    let mut problem = None;
    if err.contains("panicked") || code == Some(101) {
        problem = Some(format!("panic: {err}"));
    } else if !matches!(code, Some(0..=2)) {
        problem = Some(format!("exit code {code:?}: {err}"));
    } else if code != Some(0) && said.len() != 1 {
        problem = Some(format!("{} lines on stderr: {err}", said.len()));
    } else if code == Some(0) && !said.is_empty() && !case.to_stdout {
        problem = Some(format!("{} lines on stderr after success: {err}", said.len()));
    } else if err.contains("residual 0.000e0") {
        problem = Some(format!("a failure to converge with a residual of 0: {err}"));
    } else if code != Some(0) && (err.contains("Some(") || err.contains("None /")) {
        problem = Some(format!("Rust debug text: {err}"));
    } else if code != Some(0) && (longest_digits(&err) > 20 || err.len() > 1000) {
        problem = Some(format!(
            "a number of {} digits or a long line: {err}",
            longest_digits(&err)
        ));
    }
    if problem.is_none() {
        for input in &case.inputs {
            // Inputs stay as they were; on exit 2, every file does.
            let (Input::File(name, bytes) | Input::Other(name, bytes)) = input else {
                continue;
            };
            if (matches!(input, Input::File(..)) || code == Some(2))
                && std::fs::read(dir.join(name)).ok().as_ref() != Some(bytes)
            {
                problem = Some(format!("{name} was changed or removed: {err}"));
            }
        }
    }
    if problem.is_none() && code == Some(2) && names(dir) != before {
        problem = Some(format!(
            "exit 2 but the files went from {before:?} to {:?}: {err}",
            names(dir)
        ));
    }
    Outcome { code, problem }
}

/// Run every case on a few threads, print the counts, and exit 1 after printing the first
/// failures when a case was not clean.
pub fn run_all(name: &str, cases: &[Case]) {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_liemid"));
    let root = root(name);
    // `LIEMID_FUZZ_CASE=N`: write case N's files to a directory and say how to run it.
    if let Some(i) = std::env::var("LIEMID_FUZZ_CASE")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        let dir = std::env::temp_dir().join(format!("liemid-{name}-case-{i}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for input in &cases[i].inputs {
            match input {
                Input::File(n, b) | Input::Other(n, b) => std::fs::write(dir.join(n), b).unwrap(),
                Input::Fifo(n) => make_fifo(&dir.join(n)),
            }
        }
        println!("cd {} && {} {}", dir.display(), bin.display(), cases[i].args.join(" "));
        return;
    }
    let started = Instant::now();
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get()).min(4);
    let outcomes: Vec<(usize, Outcome)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                let (bin, root) = (&bin, &root);
                scope.spawn(move || {
                    let mut out = Vec::new();
                    for i in (w..cases.len()).step_by(workers) {
                        let dir = case_dir(root, i);
                        out.push((i, run_case(bin, &dir, &cases[i])));
                        let _ = std::fs::remove_dir_all(dir.parent().unwrap());
                    }
                    out
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    let _ = std::fs::remove_dir_all(&root);
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    let mut by_surface: BTreeMap<String, usize> = BTreeMap::new();
    let mut failures = Vec::new();
    for (i, o) in &outcomes {
        let key = o.code.map_or("hung".to_string(), |c| format!("exit {c}"));
        *counts.entry(key).or_default() += 1;
        let surface = cases[*i].label.split(':').next().unwrap_or("").to_string();
        *by_surface.entry(surface).or_default() += 1;
        if let Some(p) = &o.problem {
            let c = &cases[*i];
            let files: Vec<String> = c
                .inputs
                .iter()
                .map(|f| match f {
                    Input::File(n, b) | Input::Other(n, b) => {
                        let text = String::from_utf8_lossy(b);
                        let shown: String = text.chars().take(4000).collect();
                        format!("--- {n} ---\n{shown}")
                    }
                    Input::Fifo(n) => format!("--- {n}: a FIFO ---"),
                })
                .collect();
            failures.push(format!(
                "case {i} ({}): liemid {}\n{p}\n{}",
                c.label,
                c.args.join(" "),
                files.join("\n")
            ));
        }
    }
    let summary: Vec<String> = counts.iter().map(|(k, v)| format!("{k}: {v}")).collect();
    let surfaces: Vec<String> = by_surface.iter().map(|(k, v)| format!("{k} {v}")).collect();
    println!(
        "{name}: {} cases ({}) in {:.1} s ({})",
        outcomes.len(),
        surfaces.join(", "),
        started.elapsed().as_secs_f64(),
        summary.join(", ")
    );
    if failures.is_empty() {
        println!("{name}: {} passed, 0 failed", outcomes.len());
    } else {
        // Hangs and panics first.
        failures.sort_by_key(|f| !(f.contains("no exit after") || f.contains("panic")));
        for f in failures.iter().take(10) {
            eprintln!("{f}\n");
        }
        eprintln!(
            "{name}: {} passed, {} failed",
            outcomes.len() - failures.len(),
            failures.len()
        );
        std::process::exit(1);
    }
}

/// The directory the cases of harness `name` run under.
pub fn root(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("liemid-{name}-{}", std::process::id()))
}

/// The directory case `i` runs in (known when the case is made, for files that name it).
pub fn case_dir(root: &Path, i: usize) -> PathBuf {
    root.join("cases").join(i.to_string()).join("work")
}
