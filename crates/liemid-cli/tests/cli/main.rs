//! The `liemid` command, run as a user runs it, in one test binary: `rigid` (`run`,
//! `converge`, `work-precision`, `spins`, the listings), `adaptive` (`run --adaptive`),
//! `beam`, `many`, `multibody` and `multibody_merged`, `view` (the `--view` pages), the
//! DOP853 baseline of the free flow and the structure of the joint-space DOP853
//! (`dop853_structure`), and the reliability sweep (`reliability`). The fuzz
//! run is its own binary (it prints its counts).

#[path = "../common/mod.rs"]
mod common;

mod adaptive;
mod beam;
mod dop853_structure;
mod free_flow_vs_dop853;
mod many;
mod messages;
mod multibody;
mod multibody_control;
mod multibody_merged;
mod reliability;
mod rigid;
mod view;
