//! SIGINT/SIGTERM as a request to stop between two steps (so that files end at a whole row
//! and a checkpoint can be written), and the progress bar of long commands.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use signal_hook::consts::{SIGINT, SIGTERM, SIGXFSZ};

/// The signal that asked the command to stop, if any.
#[derive(Clone)]
pub struct Interrupt {
    signal: Arc<AtomicUsize>,
}

impl Interrupt {
    /// Catch SIGINT and SIGTERM (a second one ends the process at once, exit 130/143), and
    /// SIGXFSZ, so that a file-size limit is a write error like a full disk.
    pub fn install() -> Self {
        let signal = Arc::new(AtomicUsize::new(0));
        let armed = Arc::new(AtomicBool::new(false));
        // Registration fails only for forbidden signals; these are not. The shutdown
        // handler runs first and sees the flag only from the second signal on.
        for sig in [SIGINT, SIGTERM] {
            let _ = signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&armed));
        }
        for sig in [SIGINT, SIGTERM] {
            let _ = signal_hook::flag::register(sig, Arc::clone(&armed));
            let _ = signal_hook::flag::register_usize(sig, Arc::clone(&signal), sig as usize);
        }
        let _ = signal_hook::flag::register_usize(SIGXFSZ, Arc::new(AtomicUsize::new(0)), 1);
        Interrupt { signal }
    }

    /// The signal received (`SIGINT`, `SIGTERM`) and the exit code to end with.
    pub fn requested(&self) -> Option<(&'static str, u8)> {
        match self.signal.load(Ordering::Relaxed) {
            0 => None,
            s if s == SIGINT as usize => Some(("SIGINT", 130)),
            _ => Some(("SIGTERM", 143)),
        }
    }
}

/// A study's progress as a bar on standard error (see [`progress`]), made when the study
/// says how many units it will run.
#[derive(Default)]
pub struct Bar(std::sync::OnceLock<ProgressBar>);

impl Bar {
    /// A bar not yet started.
    pub fn new() -> Self {
        Bar::default()
    }
}

impl liemid_app::shared::progress::Progress for Bar {
    fn start(&self, total: u64, unit: &str) {
        let _ = self.0.set(progress(total, unit, true));
    }
    fn advance(&self) {
        if let Some(bar) = self.0.get() {
            bar.inc(1);
        }
    }
    fn finish(&self) {
        if let Some(bar) = self.0.get() {
            bar.finish_and_clear();
        }
    }
}

/// A progress bar with an ETA on standard error, drawn only on a terminal and only for
/// work expected to take a while (`total` units, `long` when it is worth a bar).
pub fn progress(total: u64, unit: &str, long: bool) -> ProgressBar {
    if !(long && std::io::stderr().is_terminal()) {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    let template = format!("{{wide_bar}} {{pos}}/{{len}} {unit} {{elapsed}} elapsed, ETA {{eta}}");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style);
    }
    bar
}
