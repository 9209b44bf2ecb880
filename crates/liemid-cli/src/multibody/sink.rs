//! Where a multibody run's observations go, whichever coordinates it steps (maximal by
//! `command.rs`, joint coordinates by `joint_run.rs`): the trajectory file, the record
//! its plot draws and the `--view` page.

use std::path::Path;

use liemid::error::Num;

use super::scenario::MultibodyScenario;
use crate::shared::command::Failure;
use crate::shared::interrupt::Interrupt;
use crate::shared::output::{Format, TrajectoryWriter};
use crate::shared::view::ViewPage;

/// Bodies whose poses the trajectory file holds at most (its rows stay below 7,000 numbers).
pub(super) const MAX_TRAJECTORY_BODIES: usize = 1000;

/// What the run records for its plot.
#[derive(Default)]
pub(super) struct Record {
    pub(super) t: Vec<f64>,
    pub(super) energy_error: Vec<f64>,
    pub(super) joints: Vec<Vec<f64>>,
}

/// The trajectory's columns: t, energy, then x, y, z, qw, qx, qy, qz per body.
pub(super) fn columns(sc: &MultibodyScenario) -> Vec<String> {
    let mut c = vec!["t".to_string(), "energy".to_string()];
    for b in sc.model.bodies.iter().take(MAX_TRAJECTORY_BODIES) {
        for s in ["x", "y", "z", "qw", "qx", "qy", "qz"] {
            c.push(format!("{}.{s}", b.name));
        }
    }
    c
}

pub(super) fn writer(sc: &MultibodyScenario, out: Option<&Path>) -> Result<Option<TrajectoryWriter>, Failure> {
    let Some(path) = out else { return Ok(None) };
    let format = match path.extension().and_then(|x| x.to_str()) {
        Some("npy") => Format::Npy,
        _ => Format::Csv,
    };
    let cols = columns(sc);
    let refs: Vec<&str> = cols.iter().map(String::as_str).collect();
    TrajectoryWriter::create(path, format, &refs)
        .map(Some)
        .map_err(Failure::Input)
}

/// The rows and record of a run, whichever coordinates it steps.
pub(super) trait Poses {
    fn time(&self) -> f64;
    fn energy(&mut self) -> f64;
    /// Body `i`'s frame origin and attitude quaternion `w, x, y, z`.
    fn pose(&mut self, i: usize) -> ([f64; 3], [f64; 4]);
    fn hinge_and_slide(&mut self, out: &mut Vec<f64>);
    /// The contacts touching at this state and their forces, `[x, y, z, f_x, f_y, f_z]`
    /// (none by default).
    fn contacts(&mut self, _out: &mut Vec<[f64; 6]>) {}
}

/// Where a run's observations go: the trajectory file, the plot's record and the view page.
pub(super) struct Sink {
    writer: Option<TrajectoryWriter>,
    pub(super) record: Record,
    pub(super) page: Option<ViewPage>,
    centres: Vec<liemid::Vec3>,
    row: Vec<f64>,
    frame: Vec<f32>,
    contacts: Vec<[f64; 6]>,
    e0: f64,
}

impl Sink {
    /// A sink for `sc`'s run writing to `out` and, with `view`, filling a page.
    pub(super) fn new(sc: &MultibodyScenario, out: Option<&Path>, view: bool) -> Result<Sink, Failure> {
        Ok(Sink {
            writer: writer(sc, out)?,
            record: Record::default(),
            page: view.then(|| {
                // What the page cannot draw as the file says (missing or simplified meshes).
                let (page, notes) = super::view::page(sc);
                for note in notes {
                    eprintln!("liemid: note: {}: {note}", sc.name);
                }
                page
            }),
            centres: sc.model.bodies.iter().map(|b| b.com).collect(),
            row: Vec::new(),
            frame: Vec::new(),
            contacts: Vec::new(),
            e0: f64::NAN,
        })
    }

    /// Record the state `p` shows; the first call sets the reference energy.
    pub(super) fn observe<P: Poses>(&mut self, p: &mut P) -> Result<(), Failure> {
        let e = p.energy();
        if self.e0.is_nan() {
            self.e0 = e;
        }
        let t = p.time();
        let bodies = self.centres.len();
        if let Some(w) = self.writer.as_mut() {
            self.row.clear();
            self.row.push(t);
            self.row.push(e);
            for i in 0..bodies.min(MAX_TRAJECTORY_BODIES) {
                let (x, q) = p.pose(i);
                self.row.extend_from_slice(&x);
                self.row.extend_from_slice(&q);
            }
            w.write_row(&self.row).map_err(Failure::Run)?;
        }
        let relative = (e - self.e0) / self.e0.abs().max(f64::MIN_POSITIVE);
        if let Some(page) = self.page.as_mut() {
            page.energy_error(t, relative);
            if page.wants_frame() {
                self.frame.clear();
                for (i, s) in self.centres.iter().enumerate() {
                    let (x, q) = p.pose(i);
                    let centre = super::view::centre(x, q, *s);
                    self.frame.extend(centre.iter().chain(&q).map(|&v| v as f32));
                }
                // The contact slots: the touching contacts first (as many as fit), then NaN.
                let slots = page.scene().contact_slots();
                if slots > 0 {
                    self.contacts.clear();
                    p.contacts(&mut self.contacts);
                    for k in 0..slots {
                        match self.contacts.get(k) {
                            Some(c) => self.frame.extend(c.iter().map(|&v| v as f32)),
                            None => self.frame.extend([f32::NAN; 6]),
                        }
                    }
                }
            }
            page.push_frame(t, &self.frame);
        }
        self.record.t.push(t);
        self.record.energy_error.push(relative);
        let mut q = Vec::new();
        p.hinge_and_slide(&mut q);
        if self.record.joints.is_empty() {
            self.record.joints = vec![Vec::new(); q.len()];
        }
        for (k, v) in q.into_iter().enumerate() {
            self.record.joints[k].push(v);
        }
        Ok(())
    }

    /// The failure of a run stopped by a signal after `done` of `n` steps, keeping the
    /// partial trajectory.
    pub(super) fn stopped(self, (signal, code): (&str, u8), t: f64, done: u64, n: u64) -> Failure {
        let kept = self
            .writer
            .map(|w| format!("; {}", w.keep_partial()))
            .unwrap_or_default();
        Failure::Signal(
            code,
            format!("{signal}: stopped at t = {} after {done} of {n} steps{kept}", Num(t)),
        )
    }

    /// A numerical failure `what`, keeping the partial trajectory.
    pub(super) fn failed(self, what: String) -> Failure {
        let kept = self
            .writer
            .map(|w| format!("; {}", w.keep_partial()))
            .unwrap_or_default();
        Failure::Run(format!("{what}{kept}"))
    }

    /// Close the trajectory file: its path and row count, if there is one.
    pub(super) fn finish(&mut self) -> Result<Option<(String, u64)>, Failure> {
        self.writer
            .take()
            .map(TrajectoryWriter::finish)
            .transpose()
            .map_err(Failure::Run)
    }
}

/// Why a run's observer ended the run early: the output failed, or a signal asked it to
/// stop after `steps` steps (the run is then written as far as it went).
pub(super) enum Halt {
    /// Writing an observation failed.
    Output(Failure),
    /// `SIGINT` or `SIGTERM` (its name and exit code) after `steps` steps.
    Signal((&'static str, u8), u64),
}

/// What an observer does after step `k` of `n` besides observing: the progress bar, and a
/// pending signal ends the run before the last step (kept in `stop`).
pub(super) fn after_step(
    k: u64,
    n: u64,
    bar: &indicatif::ProgressBar,
    interrupt: &Interrupt,
    stop: &mut Option<Halt>,
) -> Result<(), String> {
    bar.inc(1);
    match interrupt.requested() {
        Some(signal) if k < n => {
            *stop = Some(Halt::Signal(signal, k));
            Err("interrupted".into())
        }
        _ => Ok(()),
    }
}
