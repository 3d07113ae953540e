//! The report's charts (DESIGN.md §8), drawn with plotters into SVG strings that `report.html`
//! inlines: grouped bars (build and render times, with min–max whiskers), stacked bars (memory by
//! component), and log–log scaling plots with the fitted exponent in the legend. Text is left to
//! the browser (no font files), so the SVG holds no external reference. The SVG is meant to be
//! inlined in HTML, so it carries no `xmlns` either.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::scaling::{Axis, Study};

/// Bar chart size in SVG pixels: three side by side on a wide screen.
const BAR_SIZE: (u32, u32) = (420, 320);
/// Scaling plot size: wider, for the legend with its exponents.
const SCALING_SIZE: (u32, u32) = (660, 400);
const LABEL_FONT: (&str, u32) = ("sans-serif", 13);
const TITLE_FONT: (&str, u32) = ("sans-serif", 17);

/// Tableau 10: distinguishable, and readable by most colour-blind readers.
const PALETTE: [RGBColor; 10] = [
    RGBColor(78, 121, 167),
    RGBColor(242, 142, 43),
    RGBColor(225, 87, 89),
    RGBColor(118, 183, 178),
    RGBColor(89, 161, 79),
    RGBColor(237, 201, 72),
    RGBColor(176, 122, 161),
    RGBColor(255, 157, 167),
    RGBColor(156, 117, 95),
    RGBColor(186, 176, 172),
];

pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

#[derive(Debug, thiserror::Error)]
#[error("plot '{title}': {message}")]
pub struct PlotError {
    title: String,
    message: String,
}

/// One series of a bar chart: a value per category, optionally with a (min, max) whisker.
#[derive(Clone, Debug, PartialEq)]
pub struct Bars {
    pub name: String,
    pub values: Vec<f64>,
    pub ranges: Vec<Option<(f64, f64)>>,
}

/// Draws into an SVG string; plotters' errors become a [`PlotError`] naming the chart.
fn svg(
    title: &str,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<SVGBackend, Shift>) -> Result<(), String>,
) -> Result<String, PlotError> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        let err = |message: String| PlotError { title: title.into(), message };
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        draw(&root).map_err(err)?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    // Inline SVG in HTML needs no namespace, and without it the page holds no URL at all.
    Ok(out.replacen(" xmlns=\"http://www.w3.org/2000/svg\"", "", 1))
}

fn e<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Grouped bars: one group per category, one bar per series, whiskers from min to max.
pub fn grouped_bars(title: &str, y_label: &str, categories: &[String], series: &[Bars]) -> Result<String, PlotError> {
    let top = series
        .iter()
        .flat_map(|s| s.values.iter().copied().chain(s.ranges.iter().flatten().map(|r| r.1)))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let k = series.len();
    svg(title, BAR_SIZE, |root| {
        let mut chart = bar_frame(root, title, y_label, categories, nice_top(top, if k > 1 { k } else { 0 }))?;
        let width = 0.8 / k.max(1) as f64;
        for (si, s) in series.iter().enumerate() {
            let fill = color(si);
            let x0 = |ci: usize| ci as f64 + 0.1 + si as f64 * width;
            let bars = s
                .values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite())
                .map(|(ci, &v)| Rectangle::new([(x0(ci), 0.0), (x0(ci) + width * 0.9, v)], fill.filled()));
            let drawn = chart.draw_series(bars).map_err(e)?;
            if k > 1 {
                drawn
                    .label(s.name.clone())
                    .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], fill.filled()));
            }
            let whiskers = s.ranges.iter().enumerate().filter_map(|(ci, r)| {
                let (lo, hi) = (*r)?;
                let x = x0(ci) + width * 0.45;
                Some(PathElement::new(vec![(x, lo), (x, hi)], BLACK.stroke_width(1)))
            });
            chart.draw_series(whiskers).map_err(e)?;
        }
        if k > 1 {
            chart
                .configure_series_labels()
                .label_font(LABEL_FONT)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(e)?;
        }
        Ok(())
    })
}

/// Stacked bars: one bar per category, stacked by named component (a category lacking a
/// component stacks nothing for it).
pub fn stacked_bars(
    title: &str,
    y_label: &str,
    categories: &[String],
    components: &[(String, Vec<f64>)],
) -> Result<String, PlotError> {
    let n = categories.len();
    let top = (0..n).map(|ci| components.iter().map(|(_, v)| v.get(ci).copied().unwrap_or(0.0)).sum::<f64>());
    let top = top.fold(0.0f64, f64::max);
    svg(title, BAR_SIZE, |root| {
        let mut chart = bar_frame(root, title, y_label, categories, nice_top(top, components.len()))?;
        let mut base = vec![0.0; n];
        for (i, (name, values)) in components.iter().enumerate() {
            let fill = color(i);
            let bars: Vec<_> = (0..n)
                .filter_map(|ci| {
                    let v = values.get(ci).copied().unwrap_or(0.0);
                    let lo = base[ci];
                    base[ci] += v;
                    (v > 0.0).then(|| Rectangle::new([(ci as f64 + 0.2, lo), (ci as f64 + 0.8, lo + v)], fill.filled()))
                })
                .collect();
            chart
                .draw_series(bars)
                .map_err(e)?
                .label(name.clone())
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], fill.filled()));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(LABEL_FONT)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(e)?;
        Ok(())
    })
}

/// A log–log scaling plot: each series as points joined by lines, its fitted exponent in the
/// legend.
pub fn scaling(study: &Study) -> Result<String, PlotError> {
    let points = study.series.iter().flat_map(|s| s.points.iter().copied());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for (x, y) in points.filter(|&(x, y)| x > 0.0 && y > 0.0) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x1 <= 0.0 || y1 <= 0.0 {
        return Err(PlotError { title: study.title.clone(), message: "no positive points".into() });
    }
    let x_desc = match study.x {
        Axis::Triangles => "triangles",
        Axis::Resolution => "voxel resolution 2^L",
    };
    let y_is_bytes = study.y_label == "bytes";
    svg(&study.title, SCALING_SIZE, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(&study.title, TITLE_FONT)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d((x0 / 1.25..x1 * 1.25).log_scale(), (y0 / 1.5..y1 * 1.5).log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(study.y_label)
            .label_style(LABEL_FONT)
            .axis_desc_style(LABEL_FONT)
            .x_label_formatter(&|x| match study.x {
                Axis::Triangles => si(*x),
                Axis::Resolution => format!("{:.0}", x),
            })
            .y_label_formatter(&|y| if y_is_bytes { bytes(*y) } else { si(*y) })
            .draw()
            .map_err(e)?;
        for (i, s) in study.series.iter().enumerate() {
            let c = color(i);
            chart.draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2))).map_err(e)?;
            chart
                .draw_series(s.points.iter().map(|&p| Circle::new(p, 4, c.filled())))
                .map_err(e)?
                .label(s.legend(study.x))
                .legend(move |(x, y)| Circle::new((x + 5, y), 4, c.filled()));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(LABEL_FONT)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(e)?;
        Ok(())
    })
}

type BarChart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The frame every bar chart shares: caption, one slot per category on x (labelled beneath),
/// `0..y_top` on y with its mesh and description.
fn bar_frame<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, Shift>,
    title: &str,
    y_label: &str,
    categories: &[String],
    y_top: f64,
) -> Result<BarChart<'a, 'b>, String> {
    let mut chart = ChartBuilder::on(root)
        .caption(title, TITLE_FONT)
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..categories.len() as f64, 0.0..y_top)
        .map_err(e)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_label_formatter(&|y| significant(*y))
        .y_desc(y_label)
        .label_style(LABEL_FONT)
        .axis_desc_style(LABEL_FONT)
        .draw()
        .map_err(e)?;
    category_labels(root, &chart, categories)?;
    Ok(chart)
}

/// Writes each category's name under the centre of its bar group; on two alternating rows when
/// the names would collide.
fn category_labels(
    root: &DrawingArea<SVGBackend, Shift>,
    chart: &BarChart,
    categories: &[String],
) -> Result<(), String> {
    let n = categories.len().max(1);
    let (left, right) = (chart.backend_coord(&(0.0, 0.0)).0, chart.backend_coord(&(n as f64, 0.0)).0);
    let longest = categories.iter().map(|c| c.chars().count()).max().unwrap_or(0) as i32;
    let crowded = longest * 7 > (right - left) / n as i32;
    let style = ("sans-serif", 13).into_font().color(&BLACK).pos(Pos::new(HPos::Center, VPos::Top));
    for (i, name) in categories.iter().enumerate() {
        let (x, y) = chart.backend_coord(&(i as f64 + 0.5, 0.0));
        let y = y + 6 + if crowded && i % 2 == 1 { 15 } else { 0 };
        root.draw(&Text::new(name.clone(), (x, y), style.clone())).map_err(e)?;
    }
    Ok(())
}

/// The y-axis top: above the tallest bar by enough to fit a legend of `legend` entries in the
/// upper part of the plot; never zero.
fn nice_top(top: f64, legend: usize) -> f64 {
    let headroom = 1.1 + if legend > 0 { 0.1 + 0.085 * legend as f64 } else { 0.0 };
    if top > 0.0 && top.is_finite() { top * headroom } else { 1.0 }
}

/// 1200 → "1.2k", 3.5e6 → "3.5M".
fn si(v: f64) -> String {
    match v.abs() {
        a if a >= 1e6 => format!("{}M", significant(v / 1e6)),
        a if a >= 1e3 => format!("{}k", significant(v / 1e3)),
        _ => significant(v),
    }
}

/// 2048 → "2 KiB", to three significant digits.
pub(crate) fn bytes(v: f64) -> String {
    let (scaled, unit) = match v {
        v if v >= (1u64 << 30) as f64 => (v / (1u64 << 30) as f64, "GiB"),
        v if v >= (1u64 << 20) as f64 => (v / (1u64 << 20) as f64, "MiB"),
        v if v >= 1024.0 => (v / 1024.0, "KiB"),
        v => (v, "B"),
    };
    format!("{} {unit}", significant(scaled))
}

/// Three significant digits, trailing zeros trimmed: 976.56 → "977", 1.5 → "1.5".
fn significant(v: f64) -> String {
    let decimals = if v >= 100.0 {
        0
    } else if v >= 10.0 {
        1
    } else {
        2
    };
    let s = format!("{v:.decimals$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scaling::Series;

    #[test]
    fn charts_are_svg_with_their_labels() {
        let cats = vec!["bvh".to_string(), "org".to_string()];
        let bars = Bars { name: "cpu/primary".into(), values: vec![1.5, 3.0], ranges: vec![Some((1.4, 1.7)), None] };
        let svg = grouped_bars("render", "ms", &cats, &[bars]).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("org") && svg.contains("render"), "{svg}");
        let svg = stacked_bars(
            "memory",
            "bytes",
            &cats,
            &[("nodes".into(), vec![10.0, 0.0]), ("cells".into(), vec![0.0, 20.0])],
        )
        .unwrap();
        assert!(svg.contains("cells") && svg.contains("nodes"));
        let study = Study {
            title: "dragon: build".into(),
            x: Axis::Triangles,
            y_label: "build ms",
            series: vec![Series { label: "org".into(), points: vec![(1e4, 1.0), (1e5, 10.0)], exponent: Some(1.0) }],
        };
        let svg = scaling(&study).unwrap();
        assert!(svg.contains("org (k = 1.00)"), "{svg}");
    }

    #[test]
    fn axis_numbers_read_short() {
        assert_eq!(si(1200.0), "1.2k");
        assert_eq!(si(3_500_000.0), "3.5M");
        assert_eq!(bytes(2048.0), "2 KiB");
        assert_eq!(bytes(1.5 * (1u64 << 20) as f64), "1.5 MiB");
        assert_eq!(bytes(976.56 * 1024.0), "977 KiB");
        assert_eq!(si(0.25), "0.25");
    }
}
