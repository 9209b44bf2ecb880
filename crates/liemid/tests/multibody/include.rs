//! MJCF `<include>`: a scene that includes a robot loads as the robot itself; nested
//! includes resolve against the main file's directory, else the including file's; errors
//! name the included file and its line; cycles, files included twice, missing files, deep
//! chains and a wrong root are refused.

use crate::model_files;
use model_files::refused;
use std::path::{Path, PathBuf};

use liemid::error::Error;
use liemid::multibody::mjcf;

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/multibody")
        .join(name)
}

/// A fresh directory for one test's files.
fn scratch(test: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("include").join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    dir
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// `r` is refused in file `file_ends` at `line`.
#[track_caller]
fn refused_in(r: liemid::Result<mjcf::Loaded>, file_ends: &str, line: u32, element: &str, words: &[&str]) {
    if let Err(Error::ModelFile { file, .. }) = &r {
        assert!(file.ends_with(file_ends), "error in `{file}`, expected `{file_ends}`");
    }
    refused(r, line, element, words);
}

#[test]
fn a_scene_loads_as_the_robot_it_includes() {
    let robot = mjcf::load(&example("arm.xml")).unwrap();
    let scene = mjcf::load(&example("arm_scene.xml")).unwrap();
    assert_eq!(scene.model.name, "arm scene");
    assert_eq!(scene.model.bodies, robot.model.bodies);
    assert_eq!(scene.model.joints, robot.model.joints);
    assert_eq!(scene.model.gravity, robot.model.gravity);
    assert_eq!(scene.model.timestep, robot.model.timestep);
    assert_eq!(
        (&scene.model.qpos, &scene.model.qvel),
        (&robot.model.qpos, &robot.model.qvel)
    );
    assert_eq!(scene.merged, robot.merged);
    // The scene's own content (visual, light, floor) is listed like the robot's.
    for kind in ["visual", "statistic"] {
        assert!(
            scene.ignored.iter().any(|k| k == kind),
            "{kind} not in {:?}",
            scene.ignored
        );
    }
    for kind in &robot.ignored {
        assert!(scene.ignored.contains(kind), "{kind} lost");
    }
}

#[test]
fn nested_includes_resolve_against_the_main_file() {
    let dir = scratch("nested");
    write(
        &dir,
        "parts/defaults.xml",
        "<mujoco>\n<default><joint axis=\"0 1 0\"/></default>\n</mujoco>",
    );
    write(
        &dir,
        "parts/body.xml",
        "<mujoco>\n  <include file=\"parts/defaults.xml\"/>\n  <worldbody>\n    <body name=\"b\">\n      \
         <joint name=\"j\"/>\n      <geom size=\"0.1\"/>\n    </body>\n  </worldbody>\n</mujoco>",
    );
    let main = write(
        &dir,
        "main.xml",
        "<mujoco model=\"m\">\n<include file=\"parts/body.xml\"/>\n</mujoco>",
    );
    let loaded = mjcf::load(&main).unwrap();
    assert_eq!(loaded.model.bodies.len(), 1);
    assert_eq!(loaded.model.joints[0].name, "j");
    let whole = "<mujoco model=\"m\">\n<default><joint axis=\"0 1 0\"/></default>\n<worldbody><body name=\"b\">\
                 <joint name=\"j\"/><geom size=\"0.1\"/></body></worldbody>\n</mujoco>";
    assert_eq!(loaded.model, mjcf::parse(whole, "whole.xml").unwrap().model);
    // As MuJoCo, a path not found next to the main file is looked for next to the file that
    // includes it: robot/scene.xml includes arm.xml of its own folder.
    std::fs::create_dir_all(dir.join("robot")).unwrap();
    std::fs::copy(example("arm.xml"), dir.join("robot/arm.xml")).unwrap();
    write(
        &dir,
        "robot/scene.xml",
        "<mujoco>\n<include file=\"arm.xml\"/>\n</mujoco>",
    );
    let task = write(
        &dir,
        "task.xml",
        "<mujoco model=\"task\">\n<include file=\"robot/scene.xml\"/>\n</mujoco>",
    );
    let arm = mjcf::load(&example("arm.xml")).unwrap();
    assert_eq!(mjcf::load(&task).unwrap().model.bodies, arm.model.bodies);
}

#[test]
fn errors_name_the_included_file_and_its_line() {
    let dir = scratch("located");
    write(
        &dir,
        "parts/bad.xml",
        "<mujoco>\n<worldbody>\n<body name=\"b\">\n<joint/>\n<inertial pos=\"0 0 0\" mass=\"-1\" \
         diaginertia=\"1 1 1\"/>\n</body>\n</worldbody>\n</mujoco>",
    );
    let main = write(
        &dir,
        "main.xml",
        "<mujoco>\n<!-- two lines\n of comment -->\n<include file=\"parts/bad.xml\"/>\n</mujoco>",
    );
    refused_in(mjcf::load(&main), "parts/bad.xml", 5, "inertial", &["mass"]);
    // Below the include, lines are the main file's again.
    let main = write(
        &dir,
        "main.xml",
        "<mujoco>\n<include file=\"parts/ok.xml\"/>\n<worldbody>\n<body>\n<joint axis=\"0 0 0\"/>\n\
         <geom size=\"1\"/>\n</body>\n</worldbody>\n</mujoco>",
    );
    write(
        &dir,
        "parts/ok.xml",
        "<mujoco>\n<option timestep=\"0.01\"/>\n\n\n\n\n</mujoco>",
    );
    refused_in(mjcf::load(&main), "main.xml", 5, "joint", &["axis"]);
    // XML that parses alone but not once spliced (a prefix declared on the included root)
    // is still located in the included file.
    write(&dir, "parts/ns.xml", "<mujoco xmlns:x=\"u\">\n<x:foo/>\n</mujoco>");
    let ns_main = write(
        &dir,
        "ns_main.xml",
        "<mujoco>\n\n\n<include file=\"parts/ns.xml\"/>\n</mujoco>",
    );
    refused_in(mjcf::load(&ns_main), "parts/ns.xml", 2, "xml", &["not well-formed"]);
    // Broken XML in an included file is found in that file.
    write(&dir, "parts/ok.xml", "<mujoco>\n<option>\n</mujoco>");
    refused_in(mjcf::load(&main), "parts/ok.xml", 3, "xml", &["not well-formed"]);
}

#[test]
fn refuses_cycles_missing_files_deep_chains_and_other_roots() {
    let dir = scratch("refusals");
    write(&dir, "a.xml", "<mujoco>\n<include file=\"b.xml\"/>\n</mujoco>");
    write(&dir, "b.xml", "<mujoco>\n\n<include file=\"a.xml\"/>\n</mujoco>");
    refused_in(
        mjcf::load(&dir.join("a.xml")),
        "b.xml",
        3,
        "include",
        &["includes itself", "a.xml -> "],
    );
    write(&dir, "self.xml", "<mujoco><include file=\"self.xml\"/></mujoco>");
    refused_in(
        mjcf::load(&dir.join("self.xml")),
        "self.xml",
        1,
        "include",
        &["includes itself"],
    );
    let main = write(&dir, "main.xml", "<mujoco>\n<include file=\"nowhere.xml\"/>\n</mujoco>");
    refused_in(
        mjcf::load(&main),
        "main.xml",
        2,
        "include",
        &["cannot include", "nowhere.xml"],
    );
    write(&dir, "main.xml", "<mujoco>\n<include/>\n</mujoco>");
    refused_in(mjcf::load(&main), "main.xml", 2, "include", &["`file` attribute"]);
    write(&dir, "robot.urdf", "<robot name=\"r\"/>");
    write(&dir, "main.xml", "<mujoco>\n<include file=\"robot.urdf\"/>\n</mujoco>");
    refused_in(
        mjcf::load(&main),
        "robot.urdf",
        1,
        "robot",
        &["root element must be <mujoco>"],
    );
    // A chain of 40 files, each including the next: refused at the bound, quickly.
    for k in 0..40 {
        write(
            &dir,
            &format!("c{k}.xml"),
            &format!("<mujoco><include file=\"c{}.xml\"/></mujoco>", k + 1),
        );
    }
    write(&dir, "c40.xml", "<mujoco/>");
    refused_in(
        mjcf::load(&dir.join("c0.xml")),
        "c16.xml",
        1,
        "include",
        &["nested deeper than 16"],
    );
    write(&dir, "c40.xml", "<mujoco/>");
    assert!(mjcf::load(&dir.join("c24.xml")).is_ok());
    // A file included twice (MuJoCo: "already included"): also what bounds the work of a
    // file that includes another many times over.
    write(&dir, "leaf.xml", "<mujoco/>");
    write(
        &dir,
        "main.xml",
        "<mujoco>\n<include file=\"leaf.xml\"/>\n<include file=\"leaf.xml\"/>\n</mujoco>",
    );
    refused_in(mjcf::load(&main), "main.xml", 3, "include", &["already included"]);
    // Text without a file cannot resolve an include.
    refused(
        mjcf::parse("<mujoco>\n<include file=\"a.xml\"/>\n</mujoco>", "t.xml"),
        2,
        "include",
        &["loaded from a file"],
    );
}
