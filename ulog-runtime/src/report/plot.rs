//! The report's plots, drawn with plotters into SVG text: time plots with the flight modes
//! behind them, x-y plots (linear or logarithmic), the GPS track with equal scales, and
//! the flight-mode timeline.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::series::Series;

/// Plot size, pixels.
const WIDTH: u32 = 1100;
const HEIGHT: u32 = 340;

/// Line colors, in series order.
const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// A flight mode's time, drawn behind the time plots.
#[derive(Debug, Clone)]
pub(super) struct Band {
    pub(super) start_s: f64,
    pub(super) end_s: f64,
    pub(super) label: String,
}

/// The background color of a mode, the same in every plot.
fn band_color(label: &str) -> RGBAColor {
    const SOFT: [RGBColor; 8] = [
        RGBColor(174, 199, 232),
        RGBColor(255, 187, 120),
        RGBColor(152, 223, 138),
        RGBColor(255, 152, 150),
        RGBColor(197, 176, 213),
        RGBColor(196, 156, 148),
        RGBColor(247, 182, 210),
        RGBColor(219, 219, 141),
    ];
    let h = label
        .bytes()
        .fold(7u32, |h, b| h.wrapping_mul(31).wrapping_add(u32::from(b)));
    SOFT[h as usize % SOFT.len()].mix(0.35)
}

type Error = String;

fn err(e: impl std::fmt::Display) -> Error {
    e.to_string()
}

/// Values beyond this magnitude are drawn at a plot's edge: an axis ends within it (and a
/// twentieth of its span of padding, so within ±1.1e300), so that its span, its padding and
/// the ticks plotters steps along it stay finite numbers.
const LIMIT: f64 = 1e300;

/// The range of an axis for values from `lo` to `hi` (either infinite or NaN, or `lo`
/// above `hi` when there are none): finite, widened by a twentieth of its span each side,
/// and at least a millionth of a millionth of its magnitude wide, so that plotters' ticks
/// step along it (plotters loops for ever on an infinite range, panics on a NaN one, and a
/// range of a few units in the last place has no ticks to show).
fn axis(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = (lo.clamp(-LIMIT, LIMIT), hi.clamp(-LIMIT, LIMIT));
    // NaN, or no value at all.
    if lo.is_nan() || hi.is_nan() || lo > hi {
        return (0.0, 1.0);
    }
    let magnitude = lo.abs().max(hi.abs()).max(1.0);
    let span = hi - lo;
    if span < magnitude * 1e-12 {
        let d = magnitude * 0.05;
        return (lo - d, hi + d);
    }
    (lo - span * 0.05, hi + span * 0.05)
}

/// The range of an axis as [`axis`] makes it, but exactly `lo..hi` when that is already a
/// range plotters can draw (a frequency axis from 0 to its highest, say).
fn exact_axis(lo: f64, hi: f64) -> (f64, f64) {
    let magnitude = lo.abs().max(hi.abs()).max(1.0);
    if lo >= -LIMIT && hi <= LIMIT && hi - lo >= magnitude * 1e-12 {
        (lo, hi)
    } else {
        axis(lo, hi)
    }
}

/// The range of a logarithmic axis for positive values from `lo` to `hi`: within
/// `1/LIMIT..LIMIT`, widened a little, never empty.
fn log_axis(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = (lo.clamp(1.0 / LIMIT, LIMIT), hi.clamp(1.0 / LIMIT, LIMIT));
    if lo.is_nan() || hi.is_nan() || lo > hi {
        return (1e-6, 1.0);
    }
    (lo * 0.8, hi * 1.25)
}

fn bounds(series: &[Series], axis: impl Fn(&(f64, f64)) -> f64) -> (f64, f64) {
    series
        .iter()
        .flat_map(|s| s.points.iter().map(&axis))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

/// A plot of `series` over time (s), modes behind, dashed lines at `levels`.
pub(super) fn time_plot(
    title: &str,
    y_label: &str,
    series: &[Series],
    bands: &[Band],
    levels: &[(f64, &str)],
) -> Result<String, Error> {
    let (x0, x1) = bounds(series, |p| p.0);
    let (y0, y1) = bounds(series, |p| p.1);
    let (y0, y1) = levels
        .iter()
        .fold((y0, y1), |(lo, hi), (v, _)| (lo.min(*v), hi.max(*v)));
    let (y0, y1) = axis(y0, y1);
    let (x0, x1) = axis(x0, x1);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(32)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("time since boot (s)")
            .y_desc(y_label)
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(
                bands
                    .iter()
                    .filter(|b| b.end_s > x0 && b.start_s < x1)
                    .map(|b| {
                        Rectangle::new(
                            [(b.start_s.max(x0), y0), (b.end_s.min(x1), y1)],
                            band_color(&b.label).filled(),
                        )
                    }),
            )
            .map_err(err)?;
        for (v, name) in levels {
            chart
                .draw_series(DashedLineSeries::new(
                    [(x0, *v), (x1, *v)],
                    6,
                    4,
                    BLACK.mix(0.5).stroke_width(1),
                ))
                .map_err(err)?
                .label(*name)
                .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLACK.mix(0.5)));
        }
        draw_lines(&mut chart, series)?;
        legend(&mut chart, series.len() + levels.len())?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

fn draw_lines<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    series: &[Series],
) -> Result<(), Error>
where
    DB::ErrorType: 'static,
{
    // A point beyond the axes (a value past `LIMIT`) is drawn at their edge: plotters'
    // pixel arithmetic overflows on one far outside.
    let (x, y) = (chart.x_range(), chart.y_range());
    for (k, s) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        chart
            .draw_series(LineSeries::new(
                s.points
                    .iter()
                    .map(|p| (p.0.clamp(x.start, x.end), p.1.clamp(y.start, y.end))),
                color.stroke_width(1),
            ))
            .map_err(err)?
            .label(s.name.as_str())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], color.stroke_width(2)));
    }
    Ok(())
}

fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    entries: usize,
) -> Result<(), Error>
where
    DB::ErrorType: 'static,
{
    if entries > 1 {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

/// A plot of `series` against `x_label`; the y axis logarithmic if `log_y` (values not
/// above 0 left out).
pub(super) fn xy_plot(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_y: bool,
) -> Result<String, Error> {
    // Only finite points (a spectrum or a step response of extreme values may hold others:
    // plotters would draw a NaN at an edge).
    let finite: Vec<Series> = series
        .iter()
        .map(|s| Series {
            name: s.name.clone(),
            points: s
                .points
                .iter()
                .copied()
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .collect(),
        })
        .collect();
    let series = &finite[..];
    let (x0, x1) = bounds(series, |p| p.0);
    let (x0, x1) = exact_axis(x0, x1);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        if log_y {
            let positive: Vec<Series> = series
                .iter()
                .map(|s| Series {
                    name: s.name.clone(),
                    points: s.points.iter().copied().filter(|p| p.1 > 0.0).collect(),
                })
                .collect();
            let (lo, hi) = bounds(&positive, |p| p.1);
            let (lo, hi) = log_axis(lo, hi);
            let mut chart = caption_chart(&root, title)
                .build_cartesian_2d(x0..x1, (lo..hi).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(x_label)
                .y_desc(y_label)
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .draw()
                .map_err(err)?;
            for (k, s) in positive.iter().enumerate() {
                let color = COLORS[k % COLORS.len()];
                chart
                    .draw_series(LineSeries::new(
                        s.points
                            .iter()
                            .map(|p| (p.0.clamp(x0, x1), p.1.clamp(lo, hi))),
                        color.stroke_width(1),
                    ))
                    .map_err(err)?
                    .label(s.name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 16, y)], color.stroke_width(2))
                    });
            }
            legend(&mut chart, positive.len())?;
        } else {
            let (y0, y1) = bounds(series, |p| p.1);
            let (y0, y1) = axis(y0, y1);
            let mut chart = caption_chart(&root, title)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(x_label)
                .y_desc(y_label)
                .draw()
                .map_err(err)?;
            draw_lines(&mut chart, series)?;
            legend(&mut chart, series.len())?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

fn caption_chart<'a, 'b, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(root);
    b.caption(title, ("sans-serif", 18))
        .margin(8)
        .x_label_area_size(32)
        .y_label_area_size(64);
    b
}

/// The track (east, north in m from its start), the same scale on both axes, each part
/// colored by its flight mode.
pub(super) fn track_plot(title: &str, parts: &[Series]) -> Result<String, Error> {
    // Both axes as wide as the wider one needs, about the track's middle.
    let (x0, x1) = axis(bounds(parts, |p| p.0).0, bounds(parts, |p| p.0).1);
    let (y0, y1) = axis(bounds(parts, |p| p.1).0, bounds(parts, |p| p.1).1);
    let span = (x1 - x0).max(y1 - y0).max(1.0);
    let (cx, cy) = (x0 / 2.0 + x1 / 2.0, y0 / 2.0 + y1 / 2.0);
    let side = 640;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (side + 80, side)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut chart = caption_chart(&root, title)
            .build_cartesian_2d(
                cx - span / 2.0..cx + span / 2.0,
                cy - span / 2.0..cy + span / 2.0,
            )
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("east (m)")
            .y_desc("north (m)")
            .draw()
            .map_err(err)?;
        draw_lines(&mut chart, parts)?;
        if let Some(&start) = parts.first().and_then(|p| p.points.first()) {
            chart
                .draw_series([Circle::new(start, 4, GREEN.filled())])
                .map_err(err)?;
        }
        legend(&mut chart, parts.len())?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// The flight modes as one bar over time.
pub(super) fn mode_timeline(bands: &[Band], x0: f64, x1: f64) -> Result<String, Error> {
    let (x0, x1) = exact_axis(x0, x1);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 130)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Flight modes", ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, 0.0..1.0)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .disable_y_axis()
            .x_desc("time since boot (s)")
            .draw()
            .map_err(err)?;
        // A mode of no duration still shows, as a sliver.
        let least = (x1 - x0) * 0.002;
        chart
            .draw_series(bands.iter().map(|b| {
                Rectangle::new(
                    [(b.start_s, 0.0), (b.end_s.max(b.start_s + least), 1.0)],
                    band_color(&b.label).filled(),
                )
            }))
            .map_err(err)?;
        chart
            .draw_series(bands.iter().map(|b| {
                Text::new(
                    b.label.clone(),
                    (b.start_s + (x1 - x0) * 0.003, 0.6),
                    ("sans-serif", 12),
                )
            }))
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}
