//! The report's charts (docs/design.md §8), drawn with plotters into SVG strings that `report.html`
//! inlines: grouped bars (build and render times, with min–max whiskers), stacked bars (memory by
//! component), log–log scaling plots with the fitted exponent in the legend, per scene the
//! trade-off a user chooses on, Mrays/s against memory, and per volume source each structure's
//! speed-up over the dense marcher against the share of voxels left visible. Legends sit beside the plot, never over
//! it; log axes tick at 1, 2, 5 × 10ⁿ (or powers of two for voxel resolutions). Text is left to
//! the browser (no font files), so the SVG holds no external reference. The SVG is meant to be
//! inlined in HTML, so it carries no `xmlns` either.

use plotters::coord::Shift;
use plotters::coord::combinators::{LogCoord, WithKeyPoints};
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

/// Tableau 20 (its ten hues, each with its light twin after it in the second half): distinct for
/// the up to twenty memory components or structures of a chart.
const PALETTE: [RGBColor; 20] = [
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
    RGBColor(160, 203, 232),
    RGBColor(255, 190, 125),
    RGBColor(255, 157, 154),
    RGBColor(134, 188, 182),
    RGBColor(140, 209, 125),
    RGBColor(241, 206, 99),
    RGBColor(212, 166, 200),
    RGBColor(250, 191, 210),
    RGBColor(215, 181, 166),
    RGBColor(121, 112, 110),
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

/// A legend entry: its label, colour and marker.
#[derive(Clone, Debug)]
struct Entry {
    label: String,
    color: RGBColor,
    marker: Marker,
}

#[derive(Clone, Copy, Debug)]
enum Marker {
    Square,
    Dot,
    Line,
    /// A published figure, drawn as a cross beside our dots.
    Cross,
}

/// The first legend row's centre, level with the plot's top, and the rows' pitch, in pixels.
const LEGEND_TOP: i32 = 44;
const LEGEND_ROW: i32 = 18;

/// Pixels a legend needs for its longest label (13 px sans-serif, about 7 px a character).
fn legend_width(entries: &[Entry]) -> u32 {
    if entries.is_empty() {
        return 0;
    }
    let longest = entries.iter().map(|e| e.label.chars().count()).max().unwrap_or(0) as u32;
    (longest * 7 + 34).clamp(80, 320)
}

/// Draws into an SVG string: the chart `size` wide and high, its legend (if any) in a strip of its
/// own to the right; plotters' errors become a [`PlotError`] naming the chart.
fn svg(
    title: &str,
    size: (u32, u32),
    legend: &[Entry],
    draw: impl FnOnce(&DrawingArea<SVGBackend, Shift>) -> Result<(), String>,
) -> Result<String, PlotError> {
    let mut out = String::new();
    let extra = legend_width(legend);
    // Taller than asked where the legend needs it: every entry stays readable.
    let height = size.1.max(LEGEND_TOP as u32 + LEGEND_ROW as u32 * legend.len() as u32 + 10);
    {
        let root = SVGBackend::with_string(&mut out, (size.0 + extra, height)).into_drawing_area();
        let err = |message: String| PlotError { title: title.into(), message };
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let (plot, side) = root.split_horizontally(size.0);
        draw(&plot).map_err(err)?;
        draw_legend(&side, legend).map_err(err)?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    // Inline SVG in HTML needs no namespace, and without it the page holds no URL at all.
    Ok(out.replacen(" xmlns=\"http://www.w3.org/2000/svg\"", "", 1))
}

/// The legend strip: one entry a row from the top of the plot area down.
fn draw_legend(area: &DrawingArea<SVGBackend, Shift>, entries: &[Entry]) -> Result<(), String> {
    let style = LABEL_FONT.into_font().color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
    for (i, entry) in entries.iter().enumerate() {
        let y = LEGEND_TOP + LEGEND_ROW * i as i32;
        let c = entry.color;
        match entry.marker {
            Marker::Square => area.draw(&Rectangle::new([(6, y - 5), (16, y + 5)], c.filled())),
            Marker::Dot => area.draw(&Circle::new((11, y), 4, c.filled())),
            Marker::Line => area.draw(&PathElement::new(vec![(4, y), (18, y)], c.stroke_width(2))),
            Marker::Cross => area.draw(&Cross::new((11, y), 5, c.stroke_width(2))),
        }
        .map_err(e)?;
        area.draw(&Text::new(entry.label.clone(), (24, y), style.clone())).map_err(e)?;
    }
    Ok(())
}

/// Tick positions for a log axis over `lo..hi`: 1, 2, 5 × 10ⁿ, or only the powers of ten when
/// the range spans many decades (at most about eight ticks).
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && lo.is_finite() && hi.is_finite()) {
        return Vec::new();
    }
    let decades = (hi / lo).log10();
    let mantissas: &[f64] = if decades > 4.0 {
        &[1.0]
    } else if decades > 1.5 {
        &[1.0, 3.0]
    } else {
        &[1.0, 2.0, 5.0]
    };
    let mut ticks = Vec::new();
    let mut p = 10f64.powi(lo.log10().floor() as i32);
    while p <= hi {
        for m in mantissas {
            let t = m * p;
            if t >= lo && t <= hi {
                ticks.push(t);
            }
        }
        p *= 10.0;
    }
    ticks
}

/// Tick positions for a log axis of bytes over `lo..hi`: powers of two a power of 4, 16, … apart
/// (1 KiB, 4 KiB, 16 KiB, …), at most about seven, as binary units read round.
fn byte_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let (first, last) = (lo.log2().ceil() as i32, hi.log2().floor() as i32);
    let step = ((last - first) / 6 + 1).max(2);
    // Aligned to whole KiB, MiB, GiB where the step allows.
    let start = first + (10 - first % 10).rem_euclid(10) % step;
    (start..=last).step_by(step as usize).map(|e| 2f64.powi(e)).collect()
}

/// Tick positions at powers of two over `lo..hi` (voxel resolutions 2^L).
fn pow2_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut ticks = Vec::new();
    let mut t = 2f64.powi(lo.max(1.0).log2().ceil() as i32);
    while t <= hi {
        ticks.push(t);
        t *= 2.0;
    }
    ticks
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
    let legend: Vec<Entry> = match k > 1 {
        true => series
            .iter()
            .enumerate()
            .map(|(i, s)| Entry { label: s.name.clone(), color: color(i), marker: Marker::Square })
            .collect(),
        false => Vec::new(),
    };
    svg(title, BAR_SIZE, &legend, |root| {
        let mut chart = bar_frame(root, title, y_label, categories, nice_top(top))?;
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
            chart.draw_series(bars).map_err(e)?;
            let whiskers = s.ranges.iter().enumerate().filter_map(|(ci, r)| {
                let (lo, hi) = (*r)?;
                let x = x0(ci) + width * 0.45;
                Some(PathElement::new(vec![(x, lo), (x, hi)], BLACK.stroke_width(1)))
            });
            chart.draw_series(whiskers).map_err(e)?;
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
    // Top of the stack first, as the bars read.
    let legend: Vec<Entry> = components
        .iter()
        .enumerate()
        .rev()
        .map(|(i, (name, _))| Entry { label: name.clone(), color: color(i), marker: Marker::Square })
        .collect();
    svg(title, BAR_SIZE, &legend, |root| {
        let mut chart = bar_frame(root, title, y_label, categories, nice_top(top))?;
        let mut base = vec![0.0; n];
        for (i, (_, values)) in components.iter().enumerate() {
            let fill = color(i);
            let bars: Vec<_> = (0..n)
                .filter_map(|ci| {
                    let v = values.get(ci).copied().unwrap_or(0.0);
                    let lo = base[ci];
                    base[ci] += v;
                    (v > 0.0).then(|| Rectangle::new([(ci as f64 + 0.2, lo), (ci as f64 + 0.8, lo + v)], fill.filled()))
                })
                .collect();
            chart.draw_series(bars).map_err(e)?;
        }
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
    let legend: Vec<Entry> = study
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| Entry { label: s.legend(study.x), color: color(i), marker: Marker::Dot })
        .collect();
    let (xr, yr) = ((x0 / 1.25, x1 * 1.25), (y0 / 1.5, y1 * 1.5));
    let x_ticks = match study.x {
        Axis::Triangles => log_ticks(xr.0, xr.1),
        Axis::Resolution => pow2_ticks(xr.0, xr.1),
    };
    svg(&study.title, SCALING_SIZE, &legend, |root| {
        let x_label = |x: &f64| match study.x {
            Axis::Triangles => si(*x),
            Axis::Resolution => format!("{:.0}", x),
        };
        let y_label = |y: &f64| if y_is_bytes { bytes(*y) } else { si(*y) };
        let y_ticks = if y_is_bytes { byte_ticks(yr.0, yr.1) } else { log_ticks(yr.0, yr.1) };
        let mut chart = log_log_frame(
            root,
            &study.title,
            70,
            LogAxis { range: xr, ticks: x_ticks, desc: x_desc, label: &x_label },
            LogAxis { range: yr, ticks: y_ticks, desc: study.y_label, label: &y_label },
        )?;
        for (i, s) in study.series.iter().enumerate() {
            let c = color(i);
            chart.draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2))).map_err(e)?;
            chart.draw_series(s.points.iter().map(|&p| Circle::new(p, 4, c.filled()))).map_err(e)?;
        }
        Ok(())
    })
}

/// One structure of a scene on the speed–memory chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    pub label: String,
    pub bytes: f64,
    pub mrays_per_s: f64,
}

/// Mrays/s against memory, log–log, one point per structure (labelled beside it and in the
/// legend), the Pareto front — the structures no other beats on both — joined by a line: the
/// trade-off a user chooses on.
pub fn speed_memory(title: &str, choices: &[Choice]) -> Result<String, PlotError> {
    let points: Vec<&Choice> = choices.iter().filter(|c| c.bytes > 0.0 && c.mrays_per_s > 0.0).collect();
    if points.len() < 2 {
        return Err(PlotError {
            title: title.into(),
            message: "fewer than two structures with speed and memory".into(),
        });
    }
    let (x0, x1) = points.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), c| (lo.min(c.bytes), hi.max(c.bytes)));
    let (y0, y1) =
        points.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), c| (lo.min(c.mrays_per_s), hi.max(c.mrays_per_s)));
    let (xr, yr) = ((x0 / 1.6, x1 * 1.6), (y0 / 1.4, y1 * 1.4));
    let front = pareto_front(&points);
    let mut legend: Vec<Entry> = points
        .iter()
        .enumerate()
        .map(|(i, c)| Entry {
            label: format!("{}: {}, {:.2} Mrays/s", c.label, bytes(c.bytes), c.mrays_per_s),
            color: color(i),
            marker: Marker::Dot,
        })
        .collect();
    legend.push(Entry { label: "Pareto front".into(), color: RGBColor(60, 60, 60), marker: Marker::Line });
    svg(title, SCALING_SIZE, &legend, |root| {
        let mut chart = log_log_frame(
            root,
            title,
            60,
            LogAxis { range: xr, ticks: byte_ticks(xr.0, xr.1), desc: "memory", label: &|x| bytes(*x) },
            LogAxis { range: yr, ticks: log_ticks(yr.0, yr.1), desc: "Mrays/s", label: &|y| significant(*y) },
        )?;
        let line: Vec<(f64, f64)> = front.iter().map(|c| (c.bytes, c.mrays_per_s)).collect();
        chart.draw_series(LineSeries::new(line, RGBColor(60, 60, 60).stroke_width(1))).map_err(e)?;
        let style = ("sans-serif", 11).into_font().color(&BLACK).pos(Pos::new(HPos::Left, VPos::Bottom));
        for (i, c) in points.iter().enumerate() {
            let p = (c.bytes, c.mrays_per_s);
            chart.draw_series(std::iter::once(Circle::new(p, 5, color(i).filled()))).map_err(e)?;
            let (px, py) = chart.backend_coord(&p);
            root.draw(&Text::new(c.label.clone(), (px + 6, py - 3), style.clone())).map_err(e)?;
        }
        Ok(())
    })
}

/// One structure's speed-ups over the dense marcher on a volume source: `(visible voxels in %,
/// × dense)` at each transfer function.
#[derive(Clone, Debug, PartialEq)]
pub struct SpeedUps {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// A published speed-up shown beside ours: what it is, at what share of visible voxels (%).
#[derive(Clone, Debug, PartialEq)]
pub struct Published {
    pub label: String,
    pub visible_percent: f64,
    pub speed_up: f64,
}

/// Speed-up over the dense marcher against the share of voxels a transfer function leaves
/// visible, log–log: one line per structure (its transfer functions in order of visibility), the
/// published figures as crosses, and a dashed line at 1× (as fast as the dense marcher: below it
/// skipping costs more than it saves).
pub fn speed_up_occupancy(title: &str, series: &[SpeedUps], published: &[Published]) -> Result<String, PlotError> {
    let ours = series.iter().flat_map(|s| s.points.iter().copied());
    let theirs = published.iter().map(|p| (p.visible_percent, p.speed_up));
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, 1.0f64, 1.0f64);
    for (x, y) in ours.chain(theirs).filter(|&(x, y)| x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite()) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if series.iter().all(|s| s.points.is_empty()) || x1 <= 0.0 {
        return Err(PlotError { title: title.into(), message: "no speed-up to plot".into() });
    }
    let (xr, yr) = ((x0 / 1.6, x1 * 1.6), (y0 / 1.4, y1 * 1.4));
    let gray = RGBColor(60, 60, 60);
    let mut legend: Vec<Entry> = series
        .iter()
        .enumerate()
        .map(|(i, s)| Entry { label: s.label.clone(), color: color(i), marker: Marker::Dot })
        .collect();
    legend.extend(published.iter().map(|p| Entry {
        label: format!("{} {}×", p.label, significant(p.speed_up)),
        color: gray,
        marker: Marker::Cross,
    }));
    svg(title, SCALING_SIZE, &legend, |root| {
        let label = |v: &f64| significant(*v);
        let mut chart = log_log_frame(
            root,
            title,
            60,
            LogAxis { range: xr, ticks: log_ticks(xr.0, xr.1), desc: "visible voxels (%)", label: &label },
            LogAxis { range: yr, ticks: log_ticks(yr.0, yr.1), desc: "× dense marcher", label: &label },
        )?;
        chart.draw_series(DashedLineSeries::new([(xr.0, 1.0), (xr.1, 1.0)], 6, 4, gray.stroke_width(1))).map_err(e)?;
        draw_lines(&mut chart, series)?;
        for p in published {
            let at = (p.visible_percent, p.speed_up);
            chart.draw_series(std::iter::once(Cross::new(at, 5, gray.stroke_width(2)))).map_err(e)?;
        }
        Ok(())
    })
}

/// Time per frame against the brick cache's size, log–log (issue 42): one line per page table
/// (`(cache bytes, ms a frame)` points, in order of size).
pub fn frame_time_cache(title: &str, series: &[SpeedUps]) -> Result<String, PlotError> {
    let points = series.iter().flat_map(|s| s.points.iter().copied());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for (x, y) in points.filter(|&(x, y)| x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite()) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x1 <= 0.0 || y1 <= 0.0 {
        return Err(PlotError { title: title.into(), message: "no frame times to plot".into() });
    }
    let (xr, yr) = ((x0 / 1.6, x1 * 1.6), (y0 / 1.5, y1 * 1.5));
    let legend: Vec<Entry> = series
        .iter()
        .enumerate()
        .map(|(i, s)| Entry { label: s.label.clone(), color: color(i), marker: Marker::Dot })
        .collect();
    svg(title, SCALING_SIZE, &legend, |root| {
        let x_label = |v: &f64| bytes(*v);
        let y_label = |v: &f64| significant(*v);
        let mut chart = log_log_frame(
            root,
            title,
            60,
            LogAxis { range: xr, ticks: byte_ticks(xr.0, xr.1), desc: "brick cache", label: &x_label },
            LogAxis { range: yr, ticks: log_ticks(yr.0, yr.1), desc: "ms a frame (after the first)", label: &y_label },
        )?;
        draw_lines(&mut chart, series)?;
        Ok(())
    })
}

/// Each series as a line through its points in order of x, a dot at each, in its colour.
fn draw_lines(chart: &mut LogLogChart<'_, '_>, series: &[SpeedUps]) -> Result<(), String> {
    for (i, s) in series.iter().enumerate() {
        let c = color(i);
        let mut points = s.points.clone();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart.draw_series(LineSeries::new(points.iter().copied(), c.stroke_width(2))).map_err(e)?;
        chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, c.filled()))).map_err(e)?;
    }
    Ok(())
}

/// The choices no other is both smaller and faster than, by memory.
fn pareto_front<'a>(points: &[&'a Choice]) -> Vec<&'a Choice> {
    let mut sorted = points.to_vec();
    sorted.sort_by(|a, b| a.bytes.total_cmp(&b.bytes).then(b.mrays_per_s.total_cmp(&a.mrays_per_s)));
    let mut front: Vec<&Choice> = Vec::new();
    for c in sorted {
        if front.last().is_none_or(|best| c.mrays_per_s > best.mrays_per_s) {
            front.push(c);
        }
    }
    front
}

/// One log axis of a chart: its range, its ticks, what it measures and how a tick reads.
struct LogAxis<'f> {
    range: (f64, f64),
    ticks: Vec<f64>,
    desc: &'f str,
    label: &'f dyn Fn(&f64) -> String,
}

type LogLogChart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<WithKeyPoints<LogCoord<f64>>, WithKeyPoints<LogCoord<f64>>>>;

/// The frame every log–log chart shares: caption, both axes log-scaled with ticks at `x.ticks` and
/// `y.ticks`, the mesh with the axes' descriptions; `y_area` pixels for the y labels.
fn log_log_frame<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, Shift>,
    title: &str,
    y_area: u32,
    x: LogAxis,
    y: LogAxis,
) -> Result<LogLogChart<'a, 'b>, String> {
    let mut chart = ChartBuilder::on(root)
        .caption(title, TITLE_FONT)
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(y_area)
        .build_cartesian_2d(
            (x.range.0..x.range.1).log_scale().with_key_points(x.ticks),
            (y.range.0..y.range.1).log_scale().with_key_points(y.ticks),
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(x.desc)
        .y_desc(y.desc)
        .label_style(LABEL_FONT)
        .axis_desc_style(LABEL_FONT)
        .x_label_formatter(x.label)
        .y_label_formatter(y.label)
        .draw()
        .map_err(e)?;
    Ok(chart)
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

/// The y-axis top: a tenth above the tallest bar; never zero.
fn nice_top(top: f64) -> f64 {
    if top > 0.0 && top.is_finite() { top * 1.1 } else { 1.0 }
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
        // The legend sits right of the plot: the SVG is wider than the plot by its strip.
        assert!(
            svg.contains(&format!(
                "width=\"{}\"",
                SCALING_SIZE.0
                    + legend_width(&[Entry { label: "org (k = 1.00)".into(), color: color(0), marker: Marker::Dot }])
            )),
            "{}",
            &svg[..200]
        );
        let choices = [
            Choice { label: "bvh".into(), bytes: 1e6, mrays_per_s: 5.0 },
            Choice { label: "org".into(), bytes: 4e5, mrays_per_s: 3.0 },
            Choice { label: "svo".into(), bytes: 2e6, mrays_per_s: 1.0 },
        ];
        let svg = speed_memory("bunny: Mrays/s against memory", &choices).unwrap();
        assert!(svg.contains("bvh: 977 KiB, 5.00 Mrays/s") && svg.contains("Pareto front"), "{svg}");
        let refs: Vec<&Choice> = choices.iter().collect();
        let front: Vec<&str> = pareto_front(&refs).iter().map(|c| c.label.as_str()).collect();
        assert_eq!(front, ["org", "bvh"], "svo is both larger and slower than bvh");
    }

    #[test]
    fn speed_ups_are_drawn_beside_the_published_figures() {
        let series = [SpeedUps { label: "bricks".into(), points: vec![(30.0, 1.5), (1.0, 4.5), (100.0, 0.95)] }];
        let published = [Published { label: "grid".into(), visible_percent: 0.15, speed_up: 3.5 }];
        let svg = speed_up_occupancy("field", &series, &published).unwrap();
        assert!(svg.contains("bricks") && svg.contains("grid 3.5×") && svg.contains("visible voxels"));
        // Nothing of ours to draw is an error naming the chart, not an empty frame.
        let none = [SpeedUps { label: "bricks".into(), points: Vec::new() }];
        let err = speed_up_occupancy("field", &none, &published).unwrap_err();
        assert!(err.to_string().contains("field"), "{err}");
    }

    #[test]
    fn log_ticks_are_round() {
        assert_eq!(log_ticks(0.8, 60.0), [1.0, 3.0, 10.0, 30.0]);
        assert_eq!(log_ticks(3.0, 40.0), [5.0, 10.0, 20.0]);
        assert_eq!(log_ticks(1.0, 1e7), [1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6, 1e7]);
        assert_eq!(pow2_ticks(100.0, 2500.0), [128.0, 256.0, 512.0, 1024.0, 2048.0]);
        let kib = 1024.0;
        assert_eq!(byte_ticks(40.0 * kib, 9.0 * kib * kib), [64.0 * kib, 256.0 * kib, kib * kib, 4.0 * kib * kib]);
        let wide = byte_ticks(100.0, 1e10);
        assert!(wide.len() <= 7 && wide.contains(&(kib * kib)), "{wide:?}");
        assert!(wide.iter().all(|&t| bytes(t).split(' ').next().is_some_and(|n| !n.contains('.'))), "{wide:?}");
        assert!(log_ticks(0.0, 1.0).is_empty());
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
