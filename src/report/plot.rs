//! The report's plots, drawn as SVG by `plotters`: lines (a figure against
//! a key or time, one line per series) and heatmaps (a figure over two
//! keys). Each returns the SVG's text, to be put in the page as it is.
//!
//! Axes start where the data does (with a twentieth of the range on each
//! side), never at zero for its own sake; tick labels carry up to four
//! significant digits, in scientific notation only outside 10⁻³…10⁵.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// A plot's size in pixels.
const SIZE: (u32, u32) = (560, 340);

/// Series colours (Tableau 10), in order.
const PALETTE: [RGBColor; 10] = [
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

/// The colour of the `k`-th series.
pub fn colour(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

/// Viridis at `h` in `[0, 1]`: dark blue through green to yellow, even in
/// lightness, legible to colour-blind readers (nine stops, linear between).
fn viridis(h: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 9] = [
        (68.0, 1.0, 84.0),
        (71.0, 44.0, 122.0),
        (59.0, 81.0, 139.0),
        (44.0, 113.0, 142.0),
        (33.0, 144.0, 141.0),
        (39.0, 173.0, 129.0),
        (92.0, 200.0, 99.0),
        (170.0, 220.0, 50.0),
        (253.0, 231.0, 37.0),
    ];
    let t = h.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let k = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - k as f64;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    let mix = |x: f64, y: f64| (x + (y - x) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Why a plot could not be drawn (plotters' error, as text).
#[derive(Debug, thiserror::Error)]
#[error("drawing the plot `{title}`: {why}")]
pub struct PlotError {
    /// The plot's title.
    pub title: String,
    /// What plotters said.
    pub why: String,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A line through the points.
    Line,
    /// A dot at each point.
    Dots,
    /// A line and a dot at each point.
    LineDots,
    /// A line drawn in steps (the value holds until the next point).
    Steps,
}

/// One named series of `(x, y)` points; non-finite points are left out.
#[derive(Clone, Debug)]
pub struct Series {
    /// Its name in the legend.
    pub name: String,
    /// Its points.
    pub points: Vec<(f64, f64)>,
    /// How it is drawn.
    pub mark: Mark,
    /// Its place in the palette (default: its place in the plot), so that
    /// a run keeps its colour in a plot that leaves another run out.
    pub colour: Option<usize>,
}

/// A plot's title and its axes' labels (each with its unit).
#[derive(Clone, Copy, Debug)]
pub struct Labels<'a> {
    /// The title above the plot.
    pub title: &'a str,
    /// The horizontal axis.
    pub x: &'a str,
    /// The vertical axis.
    pub y: &'a str,
}

/// A number for a tick or a cell: up to four significant digits.
pub fn number(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.2e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        return format!("{}e{e}", trim(m));
    }
    let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
    trim(&format!("{v:.decimals$}")).to_string()
}

/// A tick's label on an axis spanning `span`: rounding noise around zero
/// (`1.7e-21` on an axis from 0 to `3e-5`) reads 0.
fn tick(v: f64, span: f64) -> String {
    if v.abs() < span * 1e-6 {
        "0".into()
    } else {
        number(v)
    }
}

fn trim(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

/// The range an axis shows for values from `lo` to `hi`: a twentieth of
/// the span beyond each end, or a small span around a single value.
fn span(lo: f64, hi: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else if lo != 0.0 {
        0.05 * lo.abs()
    } else {
        1.0
    };
    (lo - pad, hi + pad)
}

fn failed(title: &str) -> impl Fn(String) -> PlotError + '_ {
    move |why| PlotError {
        title: title.into(),
        why,
    }
}

/// The key to a plot's series, as HTML for its caption (a swatch of each
/// series' colour and its name), empty for a single series: kept out of the
/// plot, so that it never hides a line.
pub fn legend(series: &[Series]) -> String {
    if series.len() < 2 {
        return String::new();
    }
    let keys: Vec<String> = series
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let RGBColor(r, g, b) = colour(s.colour.unwrap_or(k));
            format!(
                "<span class=\"key\"><i style=\"background:#{r:02x}{g:02x}{b:02x}\"></i>{}</span>",
                super::page::esc(&s.name)
            )
        })
        .collect();
    format!("<span class=\"legend\">{}</span>", keys.join(" "))
}

/// A line plot with its caption as the page shows them: the SVG, and the
/// [`legend`] followed by `caption` (HTML).
pub fn captioned(
    labels: Labels<'_>,
    series: &[Series],
    caption: &str,
) -> Result<(String, String), PlotError> {
    Ok((
        lines(labels, series)?,
        format!("{}{caption}", legend(series)),
    ))
}

/// Lines (or dots) of every series against one axis, each in its
/// [`colour`]: the SVG's text.
pub fn lines(labels: Labels<'_>, series: &[Series]) -> Result<String, PlotError> {
    svg(labels.title, |root| draw_lines(root, labels, series))
}

/// The SVG text of what `draw` draws on a plot-sized area.
fn svg(
    title: &str,
    draw: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), String>,
) -> Result<String, PlotError> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw(&root).map_err(failed(title))?;
        root.present()
            .map_err(|e| e.to_string())
            .map_err(failed(title))?;
    }
    Ok(svg)
}

fn draw_lines(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    labels: Labels<'_>,
    series: &[Series],
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<std::io::Error>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let finite = |s: &Series| {
        s.points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect::<Vec<_>>()
    };
    let all: Vec<(f64, f64)> = series.iter().flat_map(finite).collect();
    let bounds = |f: fn(&(f64, f64)) -> f64| {
        all.iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
    };
    let (x0, x1) = span(bounds(|p| p.0).0, bounds(|p| p.0).1);
    let (y0, y1) = span(bounds(|p| p.1).0, bounds(|p| p.1).1);
    let mut chart = ChartBuilder::on(root)
        .caption(labels.title, ("sans-serif", 17))
        .margin(12)
        .x_label_area_size(42)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e)?;
    // Whole numbers along x (runs, generations, iterations) get no
    // ticks between them.
    let whole = all.iter().all(|(x, _)| x.fract() == 0.0);
    let x_tick = |v: &f64| {
        if whole && v.fract() != 0.0 {
            String::new()
        } else {
            tick(*v, x1 - x0)
        }
    };
    let y_tick = |v: &f64| tick(*v, y1 - y0);
    chart
        .configure_mesh()
        .x_desc(labels.x)
        .y_desc(labels.y)
        .x_labels(7)
        .y_labels(6)
        .x_label_formatter(&x_tick)
        .y_label_formatter(&y_tick)
        .light_line_style(RGBColor(235, 235, 235))
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(e)?;
    for (k, s) in series.iter().enumerate() {
        let c = colour(s.colour.unwrap_or(k));
        let points = finite(s);
        let mut line = points.clone();
        if s.mark == Mark::Steps {
            line = points
                .windows(2)
                .flat_map(|w| [w[0], (w[1].0, w[0].1)])
                .chain(points.last().copied())
                .collect();
        }
        if s.mark != Mark::Dots {
            chart
                .draw_series(LineSeries::new(line, c.stroke_width(2)))
                .map_err(e)?;
        }
        if matches!(s.mark, Mark::Dots | Mark::LineDots) {
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(e)?;
        }
    }
    Ok(())
}

/// A grid of values over two keys: `cells[j][i]` is the value at the
/// `i`-th of `columns` and the `j`-th of `rows` (`None`: no point there).
pub struct Grid<'a> {
    /// The horizontal key's values, as labels.
    pub columns: &'a [String],
    /// The vertical key's values, as labels.
    pub rows: &'a [String],
    /// The values, a row at a time.
    pub cells: &'a [Vec<Option<f64>>],
}

/// A heatmap of `grid`, with a colour bar from its lowest to its highest
/// value (viridis) and each cell's value written in it while they fit.
pub fn heatmap(labels: Labels<'_>, grid: &Grid<'_>) -> Result<String, PlotError> {
    svg(labels.title, |root| draw_heatmap(root, labels, grid))
}

fn draw_heatmap(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    labels: Labels<'_>,
    grid: &Grid<'_>,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<std::io::Error>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let (nx, ny) = (grid.columns.len(), grid.rows.len());
    let values = grid.cells.iter().flatten().flatten().copied();
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    // No value at all (every run failed): an empty, grey grid.
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (0.0, 0.0) };
    let shade = |v: f64| {
        let h = if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
        viridis(h)
    };
    let root = root.titled(labels.title, ("sans-serif", 17)).map_err(e)?;
    let (area, bar) = root.split_horizontally(SIZE.0 - 96);
    let mut chart = ChartBuilder::on(&area)
        .margin(8)
        .x_label_area_size(42)
        .y_label_area_size(64)
        // `0..n - 1` is `n` segments, one a cell (the keys plotted have at
        // least two values).
        .build_cartesian_2d(
            (0..(nx as i32 - 1).max(1)).into_segmented(),
            (0..(ny as i32 - 1).max(1)).into_segmented(),
        )
        .map_err(e)?;
    // A label at each cell's centre: a key's value (at most 12 of them,
    // then plotters spaces them out).
    let cell_tick = |labels: &[String], v: &SegmentValue<i32>| match v {
        SegmentValue::CenterOf(i) => labels.get(*i as usize).cloned().unwrap_or_default(),
        _ => String::new(),
    };
    let x_tick = |v: &SegmentValue<i32>| cell_tick(grid.columns, v);
    let y_tick = |v: &SegmentValue<i32>| cell_tick(grid.rows, v);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(labels.x)
        .y_desc(labels.y)
        .x_labels(nx.min(12))
        .y_labels(ny.min(12))
        .x_label_formatter(&x_tick)
        .y_label_formatter(&y_tick)
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(e)?;
    let written = nx <= 8 && ny <= 12;
    let at = |i: usize| SegmentValue::Exact(i as i32);
    for (j, row) in grid.cells.iter().enumerate() {
        for (i, v) in row.iter().enumerate() {
            let rect =
                |style: ShapeStyle| Rectangle::new([(at(i), at(j)), (at(i + 1), at(j + 1))], style);
            match v {
                Some(v) if v.is_finite() => {
                    chart.draw_series([rect(shade(*v).filled())]).map_err(e)?;
                    if written {
                        let h = if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
                        let ink = if h > 0.6 { &BLACK } else { &WHITE };
                        let style = ("sans-serif", 12)
                            .into_font()
                            .color(ink)
                            .pos(Pos::new(HPos::Center, VPos::Center));
                        let centre = (
                            SegmentValue::CenterOf(i as i32),
                            SegmentValue::CenterOf(j as i32),
                        );
                        chart
                            .draw_series([Text::new(number(*v), centre, style)])
                            .map_err(e)?;
                    }
                }
                _ => {
                    chart
                        .draw_series([rect(RGBColor(225, 225, 225).filled())])
                        .map_err(e)?;
                }
            }
        }
    }
    // The colour bar: the value range, bottom to top.
    let (b0, b1) = span(lo, hi);
    let mut scale = ChartBuilder::on(&bar)
        .margin_top(8)
        .margin_bottom(50)
        .margin_right(8)
        .y_label_area_size(58)
        .build_cartesian_2d(0.0..1.0, b0..b1)
        .map_err(e)?;
    scale
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(5)
        .y_label_formatter(&|v| tick(*v, b1 - b0))
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(e)?;
    let steps = 48;
    for k in 0..steps {
        let a = b0 + (b1 - b0) * k as f64 / steps as f64;
        let b = b0 + (b1 - b0) * (k + 1) as f64 / steps as f64;
        let mid = 0.5 * (a + b);
        scale
            .draw_series([Rectangle::new(
                [(0.0, a), (1.0, b)],
                shade(mid.clamp(lo, hi)).filled(),
            )])
            .map_err(e)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_carry_four_significant_digits_at_most() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(0.05), "0.05");
        assert_eq!(number(1.23456), "1.235");
        assert_eq!(number(1234.5), "1234");
        assert_eq!(number(3e-8), "3e-8");
        assert_eq!(number(2.5e6), "2.5e6");
        assert_eq!(number(f64::NAN), "–");
    }

    #[test]
    fn a_plot_is_an_svg_with_its_title_and_labels() {
        let svg = lines(
            Labels {
                title: "max strain by curvature",
                x: "solver.weights.curvature",
                y: "max strain (relative)",
            },
            &[Series {
                name: "iterations=5".into(),
                points: vec![(0.05, 0.04), (0.1, 0.05), (0.2, f64::NAN)],
                mark: Mark::LineDots,
                colour: None,
            }],
        )
        .unwrap();
        assert!(svg.starts_with("<svg"));
        for text in ["max strain by curvature", "solver.weights.curvature"] {
            assert!(svg.contains(text), "{text}");
        }
    }

    #[test]
    fn a_heatmap_labels_every_cell_and_leaves_holes_grey() {
        let (columns, rows) = (
            ["0.1".to_string(), "0.2".into()],
            ["5".to_string(), "10".into()],
        );
        let cells = [vec![Some(1.0), None], vec![Some(2.0), Some(3.5)]];
        let svg = heatmap(
            Labels {
                title: "t",
                x: "a",
                y: "b",
            },
            &Grid {
                columns: &columns,
                rows: &rows,
                cells: &cells,
            },
        )
        .unwrap();
        // plotters writes a text element's content on a line of its own.
        for text in [
            "\n0.1\n", "\n0.2\n", "\n5\n", "\n10\n", "\n3.5\n", "#E1E1E1",
        ] {
            assert!(svg.contains(text), "{text} in {svg}");
        }
    }
}
