//! `mpirun -n R liemid many` (the `mpi` feature): the final state is the same bytes on any
//! number of ranks as in one process with `--pair-list full`, a checkpoint written on 2
//! ranks resumes on 1 (and back) bit for bit, and bad use gets one line and exit 2 on every
//! rank. Needs `mpirun` (Open MPI or MPICH) on the path; run with
//! `cargo test -p liemid-cli --features mpi --test mpi`.
#![cfg(feature = "mpi")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_liemid")
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("liemid-mpi-test-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temporary folder");
    d
}

/// `mpirun -n ranks liemid many ARGS` with a time limit (a hang fails the test).
fn mpirun(ranks: usize, args: &[&str]) -> Output {
    let mut c = Command::new("timeout");
    c.args(["300", "mpirun", "--oversubscribe"]);
    if is_root() {
        c.arg("--allow-run-as-root");
    }
    c.args(["-n", &ranks.to_string(), bin(), "many"]).args(args);
    c.output().expect("mpirun runs (install Open MPI: openmpi-bin)")
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

fn serial(args: &[&str]) -> Output {
    Command::new(bin())
        .arg("many")
        .args(args)
        .output()
        .expect("liemid runs")
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "failed: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn bytes(p: &Path) -> Vec<u8> {
    std::fs::read(p).expect("state written")
}

const FLUID: [&str; 10] = [
    "--model",
    "dipoles",
    "--bodies",
    "2000",
    "--step",
    "1e-3",
    "--t-end",
    "0.12",
    "--threads",
    "1",
];

#[test]
fn same_bytes_on_1_2_3_ranks_as_one_process_and_checkpoints_cross_resume() {
    let d = dir("bits");
    let path = |n: &str| d.join(n);
    let s = |p: &Path| p.to_str().expect("utf-8").to_owned();
    let one = path("one.bin");
    ok(&serial(
        &[&FLUID[..], &["--pair-list", "full", "--state", &s(&one)]].concat(),
    ));
    let reference = bytes(&one);
    for r in [1, 2, 3] {
        let f = path(&format!("r{r}.bin"));
        ok(&mpirun(r, &[&FLUID[..], &["--state", &s(&f)]].concat()));
        assert!(
            bytes(&f) == reference,
            "{r} ranks: the final state differs from one process's"
        );
    }
    // A checkpoint at step 60 on 2 ranks, resumed on 1 rank and in one process; one on 1
    // rank resumed on 2.
    let (ck2, ck1) = (path("ck2.bin"), path("ck1.bin"));
    ok(&mpirun(
        2,
        &[&FLUID[..], &["--checkpoint", &s(&ck2), "--checkpoint-at", "60"]].concat(),
    ));
    ok(&mpirun(
        1,
        &[&FLUID[..], &["--checkpoint", &s(&ck1), "--checkpoint-at", "60"]].concat(),
    ));
    assert!(bytes(&ck1) == bytes(&ck2), "the checkpoints of 1 and 2 ranks differ");
    let (a, b, c) = (path("a.bin"), path("b.bin"), path("c.bin"));
    ok(&mpirun(
        1,
        &[&FLUID[..], &["--resume", &s(&ck2), "--state", &s(&a)]].concat(),
    ));
    ok(&mpirun(
        2,
        &[&FLUID[..], &["--resume", &s(&ck1), "--state", &s(&b)]].concat(),
    ));
    ok(&serial(
        &[
            &FLUID[..],
            &["--pair-list", "full", "--resume", &s(&ck2), "--state", &s(&c)],
        ]
        .concat(),
    ));
    for (name, f) in [
        ("2 -> 1 rank", &a),
        ("1 -> 2 ranks", &b),
        ("2 ranks -> one process", &c),
    ] {
        assert!(bytes(f) == reference, "resumed {name}: the final state differs");
    }
    // The totals file and the XYZ trajectory, written by rank 0 from the gathered bodies.
    let (sc, sx, mc, mx) = (path("s.csv"), path("s.xyz"), path("m.csv"), path("m.xyz"));
    let files = |c: &Path, x: &Path| ["--out".to_owned(), s(c), "--trajectory".to_owned(), s(x)];
    ok(&serial(
        &[
            &FLUID[..],
            &["--pair-list", "full"],
            &files(&sc, &sx).each_ref().map(String::as_str),
        ]
        .concat(),
    ));
    ok(&mpirun(
        2,
        &[&FLUID[..], &files(&mc, &mx).each_ref().map(String::as_str)].concat(),
    ));
    assert!(bytes(&sc) == bytes(&mc), "the totals files differ");
    assert!(bytes(&sx) == bytes(&mx), "the trajectories differ");
    // The Langevin thermostat: noise keyed on (seed, body, step), whatever the rank.
    let (ls, lm) = (path("ls.bin"), path("lm.bin"));
    let thermostat = ["--temperature", "1", "--friction", "1"];
    ok(&serial(
        &[&FLUID[..], &thermostat, &["--pair-list", "full", "--state", &s(&ls)]].concat(),
    ));
    ok(&mpirun(3, &[&FLUID[..], &thermostat, &["--state", &s(&lm)]].concat()));
    assert!(bytes(&ls) == bytes(&lm), "Langevin: the final states differ");
    let _ = std::fs::remove_dir_all(&d);
}

/// Every rank exits 2 with one line naming the cause.
fn refused(ranks: usize, o: &Output, cause: &str) {
    assert_eq!(
        o.status.code(),
        Some(2),
        "exit code: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let err = String::from_utf8_lossy(&o.stderr);
    let lines = err.lines().filter(|l| l.contains(cause)).count();
    assert_eq!(lines, ranks, "one line per rank naming '{cause}':\n{err}");
}

#[test]
fn bad_use_is_refused_on_every_rank() {
    let n = |b: &'static str| ["--model", "dipoles", "--bodies", b, "--t-end", "0.01"];
    // 2000 bodies at density 0.3: a box of 18.8, 5 slabs of the reach 3.3 at most.
    refused(6, &mpirun(6, &n("2000")), "more than the 5 slabs");
    // 200 bodies: a box of 8.7 (more than twice the cutoff 3, less than 3 reaches).
    refused(2, &mpirun(2, &n("200")), "too small for the decomposition");
    // 50 bodies: a box of 5.5, shorter than twice the cutoff: not periodic.
    refused(2, &mpirun(2, &n("50")), "not periodic");
    refused(
        2,
        &mpirun(2, &["--model", "torque-free"]),
        "MPI runs the periodic dipolar fluid",
    );
    // Ranks given different input (a hash of the arguments).
    let mut c = Command::new("timeout");
    c.args(["300", "mpirun", "--oversubscribe"]);
    if is_root() {
        c.arg("--allow-run-as-root");
    }
    let o = c
        .args(["-n", "1", bin(), "many", "--model", "dipoles", "--seed", "1", ":"])
        .args(["-n", "1", bin(), "many", "--model", "dipoles", "--seed", "2"])
        .output()
        .expect("mpirun runs");
    refused(2, &o, "disagree on the input");
}
