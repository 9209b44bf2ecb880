//! Time to read a model file (MJCF or URDF) into a `Model`, and to build its system: the
//! loader is linear in the file (a line is located by binary search over the line starts),
//! so a file of 10⁵ bodies loads well under a second.
//!
//! Run with `cargo run --release --example load_model FILE`.

use std::time::Instant;

use liemid::multibody::{mjcf, urdf, MultibodySystem};

fn main() -> Result<(), liemid::Error> {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: load_model FILE.xml|FILE.urdf");
        std::process::exit(2);
    };
    let path = std::path::Path::new(&path);
    let started = Instant::now();
    let loaded = if path.extension().is_some_and(|e| e == "urdf") {
        urdf::load(path)?
    } else {
        mjcf::load(path)?
    };
    let read = started.elapsed().as_secs_f64();
    let system = MultibodySystem::new(&loaded.model)?;
    let built = started.elapsed().as_secs_f64() - read;
    println!(
        "{}: {} bodies, {} joints; read in {read:.3} s, system built in {built:.3} s",
        path.display(),
        system.body_count(),
        system.joint_count()
    );
    Ok(())
}
