//! `liemid many --cutoff-form`: LAMMPS's shifted-force dipole potential from the command
//! line and from a scenario, and its input errors; `--rotation variational` from the
//! command and a scenario, checkpointed and resumed.

use crate::common;
use common::{json, run_in, scratch, stderr, stdout};

#[test]
fn the_shifted_force_form_runs_and_is_reported() {
    let dir = scratch("many-sf");
    let args = [
        "many", "--model", "dipoles", "--bodies", "216", "--t-end", "0.02", "--json", "-",
    ];
    let sf = run_in(&dir, &[&args[..], &["--cutoff-form", "shifted-force"]].concat());
    assert!(sf.status.success(), "{}", stderr(&sf));
    let sf = json(&stdout(&sf));
    assert_eq!(sf["cutoff_form"], "shifted-force");
    let sw = json(&stdout(&run_in(&dir, &args)));
    assert_eq!(sw["cutoff_form"], "switched");
    // Another potential, another energy (the same start).
    assert_ne!(sf["energy"][0], sw["energy"][0]);
    std::fs::write(
        dir.join("sf.toml"),
        "[system]\nmodel = \"dipoles\"\nbodies = 216\ncutoff_form = \"shifted-force\"\n[integrator]\nt_end = 0.02\n",
    )
    .unwrap();
    let file = json(&stdout(&run_in(
        &dir,
        &["many", "--scenario", "sf.toml", "--json", "-"],
    )));
    assert_eq!(file["energy"][0], sf["energy"][0]);
}

#[test]
fn cutoff_form_errors_exit_2_naming_the_choices() {
    let dir = scratch("many-sf-errors");
    let o = run_in(
        &dir,
        &[
            "many",
            "--model",
            "dipoles",
            "--bodies",
            "216",
            "--cutoff-form",
            "smooth",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("switched, shifted-force"), "{}", stderr(&o));
    let o = run_in(
        &dir,
        &[
            "many",
            "--model",
            "dipoles",
            "--bodies",
            "216",
            "--cutoff-form",
            "shifted-force",
            "--switch-start",
            "2",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("switch_start"), "{}", stderr(&o));
}

/// A state file carries a CRC-32 of its content: one flipped bit anywhere is refused with
/// exit 2 before the first step (it used to resume from the edited state), and the file as
/// written resumes.
#[test]
fn a_damaged_state_file_is_refused_by_its_checksum() {
    let dir = scratch("many-state-checksum");
    let args = ["many", "--model", "dipoles", "--bodies", "27", "--t-end", "0.01"];
    let o = run_in(&dir, &[&args[..], &["--state", "s.bin"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let good = std::fs::read(dir.join("s.bin")).unwrap();
    let resume = [&args[..], &["--resume", "d.bin"]].concat();
    // A body's position, its reference position, and the time in the header.
    for at in [71 + 8 * 5 + 2, good.len() - 10, 46] {
        let mut bad = good.clone();
        bad[at] ^= 0x10;
        std::fs::write(dir.join("d.bin"), &bad).unwrap();
        let o = run_in(&dir, &resume);
        assert_eq!(o.status.code(), Some(2), "byte {at}: {}", stderr(&o));
        assert!(stderr(&o).contains("checksum does not match"), "{}", stderr(&o));
    }
    std::fs::write(dir.join("d.bin"), &good).unwrap();
    let o = run_in(&dir, &resume);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn the_variational_rotation_runs_from_the_command_and_the_scenario_and_resumes_bit_for_bit() {
    let dir = scratch("many-variational");
    let args = [
        "many", "--model", "dipoles", "--bodies", "216", "--t-end", "0.02", "--step", "1e-3", "--json", "-",
    ];
    let o = run_in(
        &dir,
        &[&args[..], &["--rotation", "variational", "--state", "whole.bin"]].concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let variational = json(&stdout(&o));
    assert_eq!(variational["rotation"], "variational");
    // The fluid's dipoles are spheres, for which (M) and (V) have the same root `h I⁻¹ Π`;
    // asymmetric torque-free rotors tell the drifts apart: both keep their energy only to
    // the drift's order, with different errors.
    let rotors = |rotation: &str| {
        let o = run_in(
            &dir,
            &[
                "many",
                "--model",
                "torque-free",
                "--bodies",
                "64",
                "--t-end",
                "0.2",
                "--step",
                "0.01",
                "--rotation",
                rotation,
                "--json",
                "-",
            ],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        json(&stdout(&o))["max_relative_energy_error"].as_f64().unwrap()
    };
    let (midpoint, variational_rotors) = (rotors("midpoint"), rotors("variational"));
    assert!(
        midpoint > 1e-12 && variational_rotors > 1e-12 && midpoint != variational_rotors,
        "energy errors: midpoint {midpoint:e}, variational {variational_rotors:e}"
    );
    std::fs::write(
        dir.join("v.toml"),
        "[system]\nmodel = \"dipoles\"\nbodies = 216\n[integrator]\nstep = 1e-3\nt_end = 0.02\nrotation = \"variational\"\n",
    )
    .unwrap();
    let file = json(&stdout(&run_in(&dir, &["many", "--scenario", "v.toml", "--json", "-"])));
    assert_eq!(file["energy"], variational["energy"]);
    // Checkpointed after 7 steps and resumed: the state file of the whole run, byte for byte.
    let o = run_in(
        &dir,
        &[
            &args[..],
            &[
                "--rotation",
                "variational",
                "--checkpoint",
                "c.bin",
                "--checkpoint-at",
                "7",
            ],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run_in(
        &dir,
        &[
            &args[..],
            &[
                "--rotation",
                "variational",
                "--resume",
                "c.bin",
                "--state",
                "resumed.bin",
            ],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(dir.join("whole.bin")).unwrap(),
        std::fs::read(dir.join("resumed.bin")).unwrap(),
        "the resumed run's state differs"
    );
    // Resuming it with another rotation is refused, naming both.
    let o = run_in(&dir, &[&args[..], &["--resume", "c.bin"]].concat());
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("variational rotation, this run asks for midpoint"),
        "{}",
        stderr(&o)
    );
    // An unknown rotation in a scenario names the three.
    std::fs::write(
        dir.join("bad.toml"),
        "[system]\nmodel = \"dipoles\"\n[integrator]\nrotation = \"cayley\"\n",
    )
    .unwrap();
    let o = run_in(&dir, &["many", "--scenario", "bad.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("(midpoint, exact, variational)"), "{}", stderr(&o));
}
