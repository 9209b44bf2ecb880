//! How a long study tells its caller how far it has got, without knowing how that is shown:
//! the command draws a bar on a terminal, the Python package and the tests show nothing.

/// The receiver of a study's progress: `start` once with the number of units it will run,
/// `advance` as each one ends (from any thread), `finish` at the end.
pub trait Progress: Sync {
    /// The study will run `total` units named `unit` ("runs", "methods").
    fn start(&self, total: u64, unit: &str);
    /// One unit has ended.
    fn advance(&self);
    /// The study has ended.
    fn finish(&self);
    /// Whether the caller asks the study to stop (a signal, in the Python package): read
    /// between runs; a study asked to stop skips its remaining runs and returns early, with
    /// a result the caller discards.
    fn stopped(&self) -> bool {
        false
    }
}

/// Progress that nobody watches.
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _total: u64, _unit: &str) {}
    fn advance(&self) {}
    fn finish(&self) {}
}
