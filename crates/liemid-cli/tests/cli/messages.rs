//! Errors are one readable line that names what is wrong: no Rust debug text, no numbers of
//! hundreds of digits, the section a key was read from, the argument a usage error is about
//! (issue 48's "unclear messages", each of which these tests saw fail first).

use crate::common;
use common::{run_in, scratch, stderr, write};

/// The longest run of digits in `text`.
fn longest_digits(text: &str) -> usize {
    text.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

fn assert_input_error(o: &std::process::Output, expected: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let errors: Vec<&str> = err.lines().filter(|l| !l.starts_with("liemid: note:")).collect();
    assert_eq!(errors.len(), 1, "{err}");
    assert!(err.contains(expected), "expected `{expected}` in: {err}");
    assert!(!err.contains("Some(") && !err.contains("None"), "debug text: {err}");
    assert!(
        longest_digits(&err) < 20,
        "a number of {} digits: {err}",
        longest_digits(&err)
    );
}

/// Two bodies on a ball and a slide joint with the given `<inertial>` attributes.
fn two_bodies(inertial: &str) -> String {
    format!(
        "<mujoco><worldbody><body name=\"a\" pos=\"0 0 1\"><joint name=\"h\" type=\"ball\"/>\
         <inertial pos=\"0 0 -0.5\" {inertial}/><body name=\"b\" pos=\"0 0 -1\">\
         <joint name=\"s\" type=\"slide\" axis=\"0 0 1\"/><inertial pos=\"0 0 -0.5\" {inertial}/>\
         </body></body></worldbody></mujoco>"
    )
}

/// A body of mass 1e-30 beside... itself: the start's constraint matrix is singular. It used
/// to fail in the first step with `joint None / body Some(1)` and exit 1; it is now refused
/// before the first step, naming the body.
#[test]
fn dependent_constraint_rows_are_refused_naming_the_body() {
    let dir = scratch("messages-pivot");
    for inertial in [
        "mass=\"1e-30\" diaginertia=\"1 1 1\"",
        "mass=\"1\" diaginertia=\"1e-40 1e-40 1e-40\"",
    ] {
        write(&dir, "m.xml", &two_bodies(inertial));
        let o = run_in(&dir, &["multibody", "m.xml", "--t-end", "0.01", "--out", "o.csv"]);
        assert_input_error(&o, "dependent at the start, at body `b`");
        assert!(!dir.join("o.csv").exists() && !dir.join("o.csv.partial").exists());
    }
}

/// A moment of 1e300 was printed with its 301 digits.
#[test]
fn huge_numbers_are_printed_with_an_exponent() {
    let dir = scratch("messages-digits");
    write(&dir, "m.xml", &two_bodies("mass=\"1\" diaginertia=\"1e300 1 1\""));
    let o = run_in(&dir, &["multibody", "m.xml", "--t-end", "0.01"]);
    assert_input_error(&o, "I1 = 1e300 > I2 + I3 = 2");
    write(
        &dir,
        "s.toml",
        "[body]\ninertia = [1, 2, 3]\n[initial]\nangular_velocity = [1, 0, 0]\n[integrator]\nstep = 1e-300\nt_end = 1e300\n",
    );
    let o = run_in(&dir, &["run", "s.toml"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(longest_digits(&stderr(&o)) < 20, "{}", stderr(&o));
}

/// `liemid run --rho omega` said "the following required arguments were not provided:" and
/// stopped there; it now names `--adaptive` and the subcommand's help.
#[test]
fn a_usage_error_names_the_argument_it_is_about() {
    let dir = scratch("messages-usage");
    let o = run_in(&dir, &["run", "--rho", "omega"]);
    assert_input_error(&o, "not provided: --adaptive <EPS> (see `liemid run --help`)");
    let o = run_in(&dir, &["multibody", "--methd", "liemid"]);
    assert_input_error(&o, "a similar argument exists: '--method'");
}

/// A bad `[dynamics] damping` was reported under `[hamiltonian]`.
#[test]
fn a_spins_parameter_error_names_the_section_it_was_read_from() {
    let dir = scratch("messages-spins");
    let base = "[lattice]\nkind = \"square\"\nsize = [4, 4]\nperiodic = true\n[hamiltonian]\nexchange = 1.0\n";
    write(
        &dir,
        "d.toml",
        &format!("{base}[dynamics]\ndamping = -1\nt_end = 0.1\n"),
    );
    let o = run_in(&dir, &["spins", "d.toml"]);
    assert_input_error(&o, "[dynamics] invalid parameter `damping` = -1");
    write(
        &dir,
        "h.toml",
        &base.replace("exchange = 1.0", "exchange = 1.0\nmu_s = -2"),
    );
    let o = run_in(&dir, &["spins", "h.toml"]);
    assert_input_error(&o, "[hamiltonian] invalid parameter `mu_s`");
}
