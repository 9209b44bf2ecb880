//! Log-log plots of the convergence study: momentum and attitude error against the step,
//! one line and marker per method, with reference slopes 1 and 2.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::converge::Study;
use crate::work_precision::Study as WorkStudy;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Register the embedded DejaVu Sans as "sans-serif" (the bitmap backend has no system fonts).
fn register_font() {
    REGISTER.call_once(|| {
        // The font is compiled in and known to parse.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

fn e<E: std::fmt::Display>(err: E) -> String {
    format!("plot: {err}")
}

/// Tableau-10 colours: distinguishable on white, in print and for most colour-blind readers.
const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Log-axis tick label: only 1, 2 and 5 times a power of ten, so labels never crowd.
fn nice_label(v: &f64) -> String {
    let s = format!("{v:.0e}");
    if s.starts_with('1') || s.starts_with('2') || s.starts_with('5') {
        s
    } else {
        String::new()
    }
}

/// The series of one panel: label, points.
type Series = (String, Vec<(f64, f64)>);

/// Axis names and options of one panel.
struct Axes<'a> {
    title: &'a str,
    x_desc: &'a str,
    y_desc: &'a str,
    /// Draw reference slopes 1 and 2.
    slopes: bool,
}

fn panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, axes: &Axes, series: &[Series]) -> Result<(), String> {
    let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.1.iter().copied()).collect();
    if all.is_empty() {
        return Ok(());
    }
    let (xmin, xmax) = all
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let ymin_data = all.iter().fold(f64::INFINITY, |a, p| a.min(p.1));
    let ymax_data = all.iter().fold(0.0f64, |a, p| a.max(p.1));
    // Reference slopes, anchored below the smallest error at the smallest step.
    let anchor = all
        .iter()
        .filter(|p| p.0 == xmin)
        .fold(f64::INFINITY, |a, p| a.min(p.1))
        / 3.0;
    let powers: &[f64] = if axes.slopes { &[1.0, 2.0] } else { &[] };
    let slopes: Vec<(f64, Vec<(f64, f64)>)> = powers
        .iter()
        .map(|&p| (p, vec![(xmin, anchor), (xmax, anchor * (xmax / xmin).powf(p))]))
        .collect();
    let ymin = ymin_data.min(anchor) / 2.0;
    let ymax = ymax_data.max(slopes.iter().map(|s| s.1[1].1).fold(0.0, f64::max)) * 2.0;

    let mut chart = ChartBuilder::on(area)
        .caption(axes.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d((xmin / 1.3..xmax * 1.3).log_scale(), (ymin..ymax).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(axes.x_desc)
        .y_desc(axes.y_desc)
        .x_labels(12)
        .x_label_formatter(&nice_label)
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .light_line_style(WHITE)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(e)?;

    for (i, (label, points)) in series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        // The paper's method stands out.
        let width = if label == "LIEMID[EA]" { 3 } else { 2 };
        let style = ShapeStyle::from(color).stroke_width(width);
        let marker = i % 4;
        let shape = move |c: (f64, f64)| -> DynElement<'static, DB, (f64, f64)> {
            match marker {
                0 => Circle::new(c, 4, style.filled()).into_dyn(),
                1 => TriangleMarker::new(c, 5, style.filled()).into_dyn(),
                2 => Cross::new(c, 5, style).into_dyn(),
                _ => Circle::new(c, 4, style).into_dyn(),
            }
        };
        chart
            .draw_series(LineSeries::new(points.clone(), style))
            .map_err(e)?
            .label(label.as_str())
            .legend(move |(x, y)| {
                let m: DynElement<'static, DB, (i32, i32)> = match marker {
                    0 => Circle::new((x + 10, y), 4, style.filled()).into_dyn(),
                    1 => TriangleMarker::new((x + 10, y), 5, style.filled()).into_dyn(),
                    2 => Cross::new((x + 10, y), 5, style).into_dyn(),
                    _ => Circle::new((x + 10, y), 4, style).into_dyn(),
                };
                EmptyElement::at((0, 0)) + PathElement::new(vec![(x, y), (x + 20, y)], style) + m
            });
        chart.draw_series(points.iter().map(|&p| shape(p))).map_err(e)?;
    }
    for (p, line) in &slopes {
        let style = ShapeStyle::from(BLACK.mix(0.6)).stroke_width(1);
        chart
            .draw_series(DashedLineSeries::new(line.clone(), 6, 4, style))
            .map_err(e)?
            .label(format!("slope {p}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(e)?;
    Ok(())
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, study: &Study) -> Result<(), String> {
    root.fill(&WHITE).map_err(e)?;
    let title = format!("{}: error at t = {} s against the step", study.problem, study.t_end);
    let root = root.titled(&title, ("sans-serif", 24)).map_err(e)?;
    let panels = root.split_evenly((1, 2));
    let collect = |f: &dyn Fn(&crate::converge::MethodErrors, usize) -> Option<f64>| -> Vec<Series> {
        study
            .methods
            .iter()
            .map(|m| {
                let pts = m
                    .steps
                    .iter()
                    .enumerate()
                    .filter_map(|(k, h)| f(m, k).filter(|v| *v > 0.0).map(|v| (*h, v)));
                (m.label.clone(), pts.collect())
            })
            .collect()
    };
    let momentum = collect(&|m, k| m.momentum_error[k]);
    let attitude = collect(&|m, k| m.attitude_error[k]);
    let axes = |title, y_desc| Axes {
        title,
        x_desc: "step h (s)",
        y_desc,
        slopes: true,
    };
    panel(
        &panels[0],
        &axes("body angular momentum", "|Pi - Pi_ref| / |Pi_ref|"),
        &momentum,
    )?;
    panel(&panels[1], &axes("attitude", "||R - R_ref||_F"), &attitude)?;
    root.present().map_err(e)?;
    Ok(())
}

fn draw_work<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, study: &WorkStudy) -> Result<(), String> {
    root.fill(&WHITE).map_err(e)?;
    let title = format!("{}: work-precision to t = {} s", study.problem, study.t_end);
    let root = root.titled(&title, ("sans-serif", 24)).map_err(e)?;
    let panels = root.split_evenly((1, 2));
    let series = |f: &dyn Fn(&crate::work_precision::Point) -> f64| -> Vec<Series> {
        study
            .methods
            .iter()
            .map(|c| {
                let pts = c
                    .points
                    .iter()
                    .map(|p| (p.seconds, f(p)))
                    .filter(|p| p.0 > 0.0 && p.1 > 0.0);
                (c.label.clone(), pts.collect())
            })
            .collect()
    };
    let axes = |title, y_desc| Axes {
        title,
        x_desc: "CPU time (s), median of repeated runs",
        y_desc,
        slopes: false,
    };
    panel(
        &panels[0],
        &axes("attitude error at t_end", "||R - R_ref||_F"),
        &series(&|p| p.attitude_error),
    )?;
    panel(
        &panels[1],
        &axes("largest energy error along the run", "max |E - E0| / |E0|"),
        &series(&|p| p.max_energy_error),
    )?;
    root.present().map_err(e)?;
    Ok(())
}

/// A figure the tool can draw.
pub enum Figure<'a> {
    /// The convergence study.
    Convergence(&'a Study),
    /// The work-precision study.
    WorkPrecision(&'a WorkStudy),
}

fn render<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, figure: &Figure) -> Result<(), String> {
    match figure {
        Figure::Convergence(s) => draw(root, s),
        Figure::WorkPrecision(s) => draw_work(root, s),
    }
}

/// Write the plot as SVG or PNG, chosen by the extension of `path`.
pub fn write(path: &Path, figure: &Figure) -> Result<(), String> {
    register_font();
    let size = (1400, 620);
    match path.extension().and_then(|x| x.to_str()) {
        Some("svg") => render(SVGBackend::new(path, size).into_drawing_area(), figure),
        Some("png") => render(BitMapBackend::new(path, size).into_drawing_area(), figure),
        _ => Err(format!("plot: {}: use a .svg or .png file name", path.display())),
    }
}
