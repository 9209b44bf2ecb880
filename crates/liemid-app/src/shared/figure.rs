//! What a plot shows, apart from how it is drawn: the two log-log panels of a study
//! ([`Figure`]), and lines over time with reference points ([`Histories`]). Studies build
//! these; the command draws them (the Python package returns the numbers instead).

/// The series of one panel: label, points.
pub type Series = (String, Vec<(f64, f64)>);

/// Axis names and options of one panel.
pub struct Axes<'a> {
    /// The panel's title.
    pub title: &'a str,
    /// The horizontal axis.
    pub x_desc: &'a str,
    /// The vertical axis.
    pub y_desc: &'a str,
    /// Draw reference slopes 1 and 2.
    pub slopes: bool,
}

/// The series `(label, [(seconds, error)])` of a work-precision study, positive points only.
pub fn work_series<'a, P: 'a>(
    curves: impl Iterator<Item = (&'a str, &'a [P])>,
    seconds: impl Fn(&P) -> f64,
    error: impl Fn(&P) -> f64,
) -> Vec<Series> {
    curves
        .map(|(label, points)| {
            let pts = points
                .iter()
                .map(|p| (seconds(p), error(p)))
                .filter(|p| p.0 > 0.0 && p.1 > 0.0);
            (label.to_string(), pts.collect())
        })
        .collect()
}

/// A study's figure: two side-by-side log-log panels under `title`, with the legend of
/// `labels` (and the reference slopes, when the panels draw them) in its own strip. Each
/// domain's study builds its own (`rigid::converge`, `rigid::study`, `spin::study`).
pub struct Figure<'a> {
    /// Above both panels.
    pub title: String,
    /// The legend's entries, in order.
    pub labels: Vec<String>,
    /// The two panels.
    pub panels: [(Axes<'a>, Vec<Series>); 2],
}

/// Lines `y(t)` with a legend, and optional reference points (published data), on linear
/// axes: the displacement histories of `liemid beam`.
pub struct Histories<'a> {
    /// Title.
    pub title: &'a str,
    /// Axis descriptions.
    pub x_desc: &'a str,
    /// Axis descriptions.
    pub y_desc: &'a str,
    /// Labelled lines.
    pub lines: &'a [(String, Vec<(f64, f64)>)],
    /// Labelled reference points.
    pub points: &'a [(String, Vec<(f64, f64)>)],
}
