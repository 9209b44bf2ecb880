//! Log-log plots of the convergence study (momentum and attitude error against the step,
//! with reference slopes 1 and 2) and of the work-precision study (errors against CPU
//! time). Each family of methods has a colour, each order a marker, the baselines are
//! black and grey, and the legend has a strip of its own beside the panels.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

pub use liemid_app::shared::figure::{work_series, Axes, Figure, Histories, Series};

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
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

/// Tableau-10 colours, one per family (distinguishable on white, in print and for most
/// colour-blind readers); the baselines are black and greys.
mod palette {
    use plotters::style::RGBColor;
    pub const BLUE: RGBColor = RGBColor(31, 119, 180);
    pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
    pub const GREEN: RGBColor = RGBColor(44, 160, 44);
    pub const RED: RGBColor = RGBColor(214, 39, 40);
    pub const PURPLE: RGBColor = RGBColor(148, 103, 189);
    pub const BROWN: RGBColor = RGBColor(140, 86, 75);
    pub const PINK: RGBColor = RGBColor(227, 119, 194);
    pub const OLIVE: RGBColor = RGBColor(188, 189, 34);
    pub const CYAN: RGBColor = RGBColor(23, 190, 207);
    pub const BLACK: RGBColor = RGBColor(0, 0, 0);
    pub const GREY: RGBColor = RGBColor(140, 140, 140);
    pub const DARK_GREY: RGBColor = RGBColor(80, 80, 80);
}

/// The marker of a series: one per order of accuracy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Marker {
    /// First order.
    Cross,
    /// Second order.
    Circle,
    /// Fourth order (hollow for a second scheme of the same order).
    Triangle { hollow: bool },
    /// Sixth order.
    Square,
    /// Eighth order.
    Diamond,
}

/// How a series is drawn: colour by family, marker by order, dashes for a second baseline.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Look {
    color: RGBColor,
    marker: Marker,
    width: u32,
    dashed: bool,
}

/// The look of a series from its label: `LIEMID[EA]6` is the EA family (blue) at order 6
/// (square); the FS family is dashed; DOP853 is black, RK4 grey and dashed, RKMK4 dark
/// grey.
fn look(label: &str) -> Look {
    use palette::*;
    let (family, suffix) = match label.find(']') {
        Some(i) => label.split_at(i + 1),
        None => (label, ""),
    };
    let marker_of = |order: u32, hollow: bool| match order {
        1 => Marker::Cross,
        2 => Marker::Circle,
        4 => Marker::Triangle { hollow },
        6 => Marker::Square,
        _ => Marker::Diamond,
    };
    let base = |color, first_order: bool| {
        let digits: String = suffix.chars().take_while(char::is_ascii_digit).collect();
        let order = digits.parse().unwrap_or(if first_order { 1 } else { 2 });
        let hollow = suffix.len() > digits.len();
        Look {
            color,
            marker: marker_of(order, hollow),
            width: if label == "LIEMID[EA]" { 3 } else { 2 },
            dashed: false,
        }
    };
    let baseline = |color, marker, dashed| Look {
        color,
        marker,
        width: 2,
        dashed,
    };
    match family {
        "LIEMID[EA]" => base(BLUE, false),
        // Dashed blue: the variational drift beside EA's midpoint one.
        "LIEMID[EAV]" => Look {
            dashed: true,
            ..base(BLUE, false)
        },
        "LIEMID[EX]" => base(RED, false),
        // Dashed: on a symmetric body FS is EX, and the red shows between the dashes.
        "LIEMID[FS]" => Look {
            dashed: true,
            ..base(PURPLE, false)
        },
        "LIEMID[E1]" => base(ORANGE, true),
        "LIEMID[E2]" => base(OLIVE, true),
        "LIEMID[I]" => base(GREEN, false),
        "AKW" => base(BROWN, false),
        "SW" => base(PINK, false),
        "NMB" => base(CYAN, false),
        "DOP853" => baseline(BLACK, Marker::Diamond, false),
        // The spin methods: the splitting family blue by order, the midpoint rule green,
        // the field's baselines (Heun, Depondt-Mertens, RK4) in orange, olive and grey.
        "split" | "split4" | "split6" | "split8" => {
            let order = family.trim_start_matches("split").parse().unwrap_or(2);
            Look {
                marker: marker_of(order, false),
                ..base(BLUE, false)
            }
        }
        "midpoint" => base(GREEN, false),
        "heun" => base(ORANGE, false),
        "depondt" => base(OLIVE, false),
        "rk4" => baseline(GREY, Marker::Triangle { hollow: false }, true),
        "RK4" => baseline(GREY, Marker::Triangle { hollow: false }, true),
        "RKMK4" => baseline(DARK_GREY, Marker::Triangle { hollow: true }, false),
        _ => baseline(DARK_GREY, Marker::Circle, true),
    }
}

/// The marker of `look` at `c` (data or pixel coordinates), drawn in pixels about it.
fn marker<'a, C: Clone + 'a, DB: DrawingBackend + 'a>(look: Look, c: C) -> DynElement<'a, DB, C> {
    let style = ShapeStyle::from(look.color).stroke_width(look.width);
    let at = EmptyElement::at(c);
    match look.marker {
        Marker::Cross => (at + Cross::new((0, 0), 5, style)).into_dyn(),
        Marker::Circle => (at + Circle::new((0, 0), 4, style.filled())).into_dyn(),
        Marker::Triangle { hollow: false } => (at + TriangleMarker::new((0, 0), 5, style.filled())).into_dyn(),
        Marker::Triangle { hollow: true } => (at + TriangleMarker::new((0, 0), 5, style)).into_dyn(),
        Marker::Square => (at + Rectangle::new([(-4, -4), (4, 4)], style.filled())).into_dyn(),
        Marker::Diamond => (at + Polygon::new(vec![(0, -6), (5, 0), (0, 6), (-5, 0)], style.filled())).into_dyn(),
    }
}

/// The legend of every series (and the reference slopes) in its own strip beside the
/// panels, so that it never covers data.
fn legend<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, labels: &[String], slopes: bool) -> Result<(), String> {
    let row = 22;
    let top = 60;
    let font = ("sans-serif", 14).into_font();
    for (k, label) in labels.iter().enumerate() {
        let l = look(label);
        let y = top + row * k as i32;
        let style = ShapeStyle::from(l.color).stroke_width(l.width);
        if l.dashed {
            area.draw(&PathElement::new(vec![(10, y), (18, y)], style)).map_err(e)?;
            area.draw(&PathElement::new(vec![(26, y), (34, y)], style)).map_err(e)?;
        } else {
            area.draw(&PathElement::new(vec![(10, y), (34, y)], style)).map_err(e)?;
        }
        area.draw(&marker(l, (22, y))).map_err(e)?;
        area.draw(&Text::new(label.clone(), (42, y - 8), font.clone()))
            .map_err(e)?;
    }
    if slopes {
        let style = ShapeStyle::from(BLACK.mix(0.6)).stroke_width(1);
        for (k, p) in [1, 2].iter().enumerate() {
            let y = top + row * (labels.len() + k) as i32;
            area.draw(&PathElement::new(vec![(10, y), (16, y)], style)).map_err(e)?;
            area.draw(&PathElement::new(vec![(22, y), (28, y)], style)).map_err(e)?;
            area.draw(&Text::new(format!("slope {p}"), (42, y - 8), font.clone()))
                .map_err(e)?;
        }
    }
    Ok(())
}

/// Width of the legend strip right of the panels (pixels).
const LEGEND_WIDTH: u32 = 190;

/// Log-axis tick label: only 1, 2 and 5 times a power of ten, so labels never crowd.
fn nice_label(v: &f64) -> String {
    let s = format!("{v:.0e}");
    if s.starts_with('1') || s.starts_with('2') || s.starts_with('5') {
        s
    } else {
        String::new()
    }
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

    for (label, points) in series {
        let l = look(label);
        let style = ShapeStyle::from(l.color).stroke_width(l.width);
        if l.dashed {
            chart
                .draw_series(DashedLineSeries::new(points.clone(), 8, 5, style))
                .map_err(e)?;
        } else {
            chart.draw_series(LineSeries::new(points.clone(), style)).map_err(e)?;
        }
        let area = chart.plotting_area();
        for &p in points {
            area.draw(&marker(l, p)).map_err(e)?;
        }
    }
    for (_, line) in &slopes {
        let style = ShapeStyle::from(BLACK.mix(0.6)).stroke_width(1);
        chart
            .draw_series(DashedLineSeries::new(line.clone(), 6, 4, style))
            .map_err(e)?;
    }
    Ok(())
}

/// A figure of two side-by-side log-log panels under `title`, with the legend of
/// `labels` (and the reference slopes, when the panels draw them) in its own strip.
fn two_panels<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    labels: &[String],
    panels: &[(Axes<'_>, Vec<Series>); 2],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e)?;
    let root = root.titled(title, ("sans-serif", 24)).map_err(e)?;
    let (plots, strip) = root.split_horizontally(root.dim_in_pixel().0 - LEGEND_WIDTH);
    legend(&strip, labels, panels[0].0.slopes)?;
    let areas = plots.split_evenly((1, 2));
    for (area, (axes, series)) in areas.iter().zip(panels) {
        panel(area, axes, series)?;
    }
    root.present().map_err(e)?;
    Ok(())
}

/// The files a plot option names: `NAME` writes `NAME.svg` and `NAME.png`; a name ending
/// in `.svg` or `.png` writes that one.
pub fn plot_paths(base: &Path) -> Vec<std::path::PathBuf> {
    match base.extension().and_then(|x| x.to_str()) {
        Some("svg") | Some("png") => vec![base.to_path_buf()],
        _ => {
            let with = |ext: &str| {
                let mut s = base.as_os_str().to_owned();
                s.push(".");
                s.push(ext);
                std::path::PathBuf::from(s)
            };
            vec![with("svg"), with("png")]
        }
    }
}

/// A PNG of one curve `y(x)` on linear axes (the radial distribution function).
///
/// # Errors
/// A drawing or file error.
pub fn curve(path: &Path, title: &str, x_desc: &str, y_desc: &str, points: &[(f64, f64)]) -> Result<(), String> {
    register_font();
    let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let xmax = points.iter().fold(0.0f64, |a, p| a.max(p.0)).max(1e-300);
    let ymax = points.iter().fold(0.0f64, |a, p| a.max(p.1)).max(1.0) * 1.1;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..xmax * 1.02, 0.0..ymax)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .light_line_style(WHITE)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(e)?;
    let style = ShapeStyle::from(palette::BLUE).stroke_width(2);
    chart.draw_series(LineSeries::new(points.to_vec(), style)).map_err(e)?;
    let grey = ShapeStyle::from(palette::GREY).stroke_width(1);
    chart
        .draw_series(DashedLineSeries::new(vec![(0.0, 1.0), (xmax * 1.02, 1.0)], 6, 4, grey))
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// A PNG of a 2-D lattice's spins: the in-plane angle `atan2(S_y, S_x)` as hue, darker
/// where the spin points out of the plane (`|S_z|` near 1).
///
/// # Errors
/// A drawing or file error.
pub fn spin_snapshot(path: &Path, size: &[usize; 3], spins: &[liemid::Vec3], title: &str) -> Result<(), String> {
    register_font();
    let (nx, ny) = (size[0], size[1]);
    let cell = (640 / nx.max(ny)).clamp(1, 16) as u32;
    let (w, h) = (nx as u32 * cell, ny as u32 * cell);
    let root = BitMapBackend::new(path, (w + 40, h + 70)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    root.draw(&Text::new(title.to_string(), (20, 10), ("sans-serif", 16).into_font()))
        .map_err(e)?;
    for y in 0..ny {
        for x in 0..nx {
            let s = spins[x + nx * y];
            let hue = (s.y.atan2(s.x) / (2.0 * std::f64::consts::PI)).rem_euclid(1.0);
            let in_plane = (s.x * s.x + s.y * s.y).sqrt().min(1.0);
            let color = HSLColor(hue, 0.9, 0.15 + 0.45 * in_plane);
            // Row y = 0 at the bottom, as in a plot.
            let (px, py) = (20 + x as i32 * cell as i32, 40 + (ny - 1 - y) as i32 * cell as i32);
            root.draw(&Rectangle::new(
                [(px, py), (px + cell as i32, py + cell as i32)],
                color.filled(),
            ))
            .map_err(e)?;
        }
    }
    root.draw(&Text::new(
        "hue: in-plane angle of S; dark: S out of plane".to_string(),
        (20, 48 + h as i32),
        ("sans-serif", 13).into_font(),
    ))
    .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

fn render<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, figure: &Figure) -> Result<(), String> {
    two_panels(root, &figure.title, &figure.labels, &figure.panels)
}

/// Write the plot as SVG or PNG, chosen by the extension of `path`.
pub fn write(path: &Path, figure: &Figure) -> Result<(), String> {
    register_font();
    let size = (1400 + LEGEND_WIDTH, 640);
    match path.extension().and_then(|x| x.to_str()) {
        Some("svg") => render(SVGBackend::new(path, size).into_drawing_area(), figure),
        Some("png") => render(BitMapBackend::new(path, size).into_drawing_area(), figure),
        _ => Err(format!("plot: {}: use a .svg or .png file name", path.display())),
    }
}

fn draw_histories<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, h: &Histories<'_>) -> Result<(), String> {
    root.fill(&WHITE).map_err(e)?;
    let all = h.lines.iter().chain(h.points).flat_map(|(_, v)| v.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in all {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 >= x1 {
        (x0, x1) = (0.0, 1.0);
    }
    if y0 >= y1 {
        (y0, y1) = (y0 - 1.0, y0 + 1.0);
    }
    let pad = 0.06 * (y1 - y0);
    let mut chart = ChartBuilder::on(&root)
        .caption(h.title, ("sans-serif", 20))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
        .map_err(e)?;
    // Small or large values in scientific notation (the default prints 1e-5 as "0.0").
    let magnitude = y0.abs().max(y1.abs());
    let scientific = !(1e-2..1e5).contains(&magnitude);
    let y_label = move |v: &f64| {
        if v.abs() < 1e-9 * magnitude {
            "0".to_string()
        } else if scientific {
            format!("{v:.1e}")
        } else {
            format!("{v}")
        }
    };
    chart
        .configure_mesh()
        .x_desc(h.x_desc)
        .y_desc(h.y_desc)
        .y_label_formatter(&y_label)
        .light_line_style(WHITE)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(e)?;
    let colours = [
        palette::BLUE,
        palette::ORANGE,
        palette::GREEN,
        palette::RED,
        palette::PURPLE,
        palette::BROWN,
        palette::PINK,
        palette::OLIVE,
        palette::CYAN,
    ];
    for (k, (label, v)) in h.lines.iter().enumerate() {
        let c = colours[k % colours.len()];
        // A thick polyline through a dense, jagged series draws miter spikes far past its
        // points (plotters joins wide segments with miters): dense series get a thin line.
        let width = if v.len() > 400 { 1 } else { 2 };
        chart
            .draw_series(LineSeries::new(v.clone(), ShapeStyle::from(c).stroke_width(width)))
            .map_err(e)?
            .label(label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], ShapeStyle::from(c).stroke_width(2)));
    }
    for (k, (label, v)) in h.points.iter().enumerate() {
        let c = colours[k % colours.len()];
        chart
            .draw_series(
                v.iter()
                    .map(move |&p| Circle::new(p, 3, ShapeStyle::from(c).stroke_width(1))),
            )
            .map_err(e)?
            .label(label.as_str())
            .legend(move |(x, y)| Circle::new((x + 10, y), 3, ShapeStyle::from(c).filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.9))
        .border_style(palette::GREY)
        .label_font(("sans-serif", 14))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// Write [`Histories`] as SVG or PNG, by the extension of `path`.
///
/// # Errors
/// Another extension, or a drawing or file error.
pub fn histories(path: &Path, h: &Histories<'_>) -> Result<(), String> {
    register_font();
    let size = (1100, 600);
    match path.extension().and_then(|x| x.to_str()) {
        Some("svg") => draw_histories(SVGBackend::new(path, size).into_drawing_area(), h),
        Some("png") => draw_histories(BitMapBackend::new(path, size).into_drawing_area(), h),
        _ => Err(format!("plot: {}: use a .svg or .png file name", path.display())),
    }
}

/// [`Histories`] stacked in one figure sharing the time axis, each panel with its own
/// title and legend (the joint coordinates and the energy error of `liemid multibody`).
///
/// # Errors
/// An extension other than `.svg` or `.png`, or a drawing or file error.
pub fn stacked_histories(path: &Path, panels: &[Histories<'_>]) -> Result<(), String> {
    register_font();
    let size = (1100, 420 * panels.len().max(1) as u32);
    match path.extension().and_then(|x| x.to_str()) {
        Some("svg") => draw_stacked(SVGBackend::new(path, size).into_drawing_area(), panels),
        Some("png") => draw_stacked(BitMapBackend::new(path, size).into_drawing_area(), panels),
        _ => Err(format!("plot: {}: use a .svg or .png file name", path.display())),
    }
}

fn draw_stacked<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, panels: &[Histories<'_>]) -> Result<(), String> {
    for (area, h) in root.split_evenly((panels.len().max(1), 1)).into_iter().zip(panels) {
        draw_histories(area, h)?;
    }
    root.present().map_err(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use liemid::RotationMethod;

    #[test]
    fn every_method_has_its_own_look_colour_by_family_marker_by_order() {
        let mut labels: Vec<&str> = RotationMethod::ALL.iter().map(|m| m.name()).collect();
        labels.push("DOP853");
        let looks: Vec<Look> = labels.iter().map(|l| look(l)).collect();
        for (i, a) in looks.iter().enumerate() {
            for (j, b) in looks.iter().enumerate().skip(i + 1) {
                assert!(
                    (a.color, a.marker, a.dashed) != (b.color, b.marker, b.dashed),
                    "{} and {} look the same",
                    labels[i],
                    labels[j]
                );
            }
        }
        let of = |l: &str| look(l);
        // One colour per family, one marker per order.
        assert_eq!(of("LIEMID[EA]").color, of("LIEMID[EA]8").color);
        assert_ne!(of("LIEMID[EA]").color, of("LIEMID[EX]").color);
        assert_eq!(of("LIEMID[EA]6").marker, of("LIEMID[EX]6").marker);
        assert_ne!(of("LIEMID[EA]4").marker, of("LIEMID[EA]6").marker);
        assert_eq!(of("LIEMID[E1]").marker, Marker::Cross);
        // Baselines black and grey.
        assert_eq!(of("DOP853").color, palette::BLACK);
        for b in ["RK4", "RKMK4"] {
            let c = of(b).color;
            assert!(c.0 == c.1 && c.1 == c.2 && c.0 > 0, "{b} is not grey");
        }
        // No method falls back to the unknown look.
        for l in &labels {
            assert_ne!(of(l), look("?"), "{l} has no look of its own");
        }
    }
}
