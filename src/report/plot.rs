//! `report.png`: frame time by stage over the run, the geometry cache's hits over the run,
//! and the histogram of the fraction of requested islands the cache already held. Drawn with
//! plotters into a pixel buffer using an embedded font (DejaVu Sans Mono), then encoded with
//! `image` and written atomically.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::stats::{FrameRecord, RunStats};
use super::ReportError;
use crate::integrate::{StageTimes, FRACTION_BUCKETS};

pub const PLOT_WIDTH: u32 = 1200;
pub const PLOT_HEIGHT: u32 = 1350;

pub(super) const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSansMono.ttf");

/// Stages stacked bottom to top, with their colours.
pub(super) const STAGES: [(&str, RGBColor); 5] = [
    ("update", RGBColor(31, 119, 180)),
    ("integrate", RGBColor(255, 127, 14)),
    ("reactivate", RGBColor(214, 39, 40)),
    ("commit", RGBColor(148, 103, 189)),
    ("trace", RGBColor(44, 160, 44)),
];

fn stage_ms(f: &FrameRecord, stage: usize) -> f64 {
    (StageTimes::STAGES[stage].1)(&f.stages)
}

pub(super) type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
pub(super) type PlotResult = Result<(), String>;
/// A per-frame count of a record.
type Count = fn(&FrameRecord) -> u64;

pub(super) fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// Draws the report of `stats` and writes it to `path` as PNG.
pub fn write_report_png(stats: &RunStats, path: &Path) -> Result<(), ReportError> {
    write_png(path, PLOT_WIDTH, PLOT_HEIGHT, |buffer| draw(stats, buffer))
}

/// Draws `width` x `height` pixels with `draw` (the embedded font registered) and writes
/// them to `path` as PNG, atomically.
pub(super) fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    draw: impl FnOnce(&mut [u8]) -> PlotResult,
) -> Result<(), ReportError> {
    let plot_error = |message: String| ReportError::Plot { path: path.to_path_buf(), message };
    plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES)
        .map_err(|_| plot_error("the embedded font does not load".into()))?;
    let mut buffer = vec![0u8; (width * height * 3) as usize];
    draw(&mut buffer).map_err(plot_error)?;
    let image = image::RgbImage::from_raw(width, height, buffer)
        .ok_or_else(|| plot_error("pixel buffer has the wrong size".into()))?;
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| plot_error(e.to_string()))?;
    crate::atomic_file::write_atomic(path, &png)
        .map_err(|source| ReportError::Write { path: path.to_path_buf(), source })
}

fn draw(stats: &RunStats, buffer: &mut [u8]) -> PlotResult {
    let root = BitMapBackend::with_buffer(buffer, (PLOT_WIDTH, PLOT_HEIGHT)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let run = &stats.run;
    let title = format!(
        "{}: {} frames, {}x{} {} spp, {} backend, integration {}",
        run.scene, stats.summary.frames, run.width, run.height, run.spp, run.backend, run.integration
    );
    let root = root.titled(&title, (FONT, 22)).map_err(err)?;
    let panels = root.split_evenly((3, 1));
    stage_times(stats, &panels[0])?;
    cache_hits(stats, &panels[1])?;
    fraction_histogram(stats, &panels[2])?;
    root.present().map_err(err)
}

fn frame_range(stats: &RunStats) -> std::ops::Range<f64> {
    let first = stats.summary.first_frame.unwrap_or(0) as f64;
    let last = stats.summary.last_frame.unwrap_or(0) as f64;
    first..last.max(first + 1.0)
}

fn stage_times(stats: &RunStats, area: &Area<'_>) -> PlotResult {
    let frames = &stats.frames;
    let top = frames.iter().map(|f| f.frame_ms).fold(0.0, f64::max).max(1e-3) * 1.1;
    let mut chart = ChartBuilder::on(area)
        .caption("Frame time by stage (stacked)", (FONT, 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(frame_range(stats), 0.0..top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_desc("time (ms)")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(err)?;
    // Top of each stage's band; drawn from the top band down so each covers the ones below.
    for stage in (0..STAGES.len()).rev() {
        let (name, colour) = STAGES[stage];
        let points: Vec<(f64, f64)> =
            frames.iter().map(|f| (f.frame as f64, (0..=stage).map(|s| stage_ms(f, s)).sum())).collect();
        chart
            .draw_series(AreaSeries::new(points, 0.0, colour.mix(0.85)).border_style(colour))
            .map_err(err)?
            .label(format!("{name} (median {:.2} ms)", median_of(stats, stage)))
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], colour.filled()));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
}

/// The legend of `chart`'s labelled series, in the one style every panel uses.
pub(super) fn draw_legend<'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, BitMapBackend<'a>, CT>,
    position: SeriesLabelPosition,
) -> PlotResult {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)
}

fn median_of(stats: &RunStats, stage: usize) -> f64 {
    (StageTimes::STAGES[stage].1)(&stats.summary.median.stages)
}

fn cache_hits(stats: &RunStats, area: &Area<'_>) -> PlotResult {
    let series: [(&str, RGBColor, Count); 3] = [
        ("full hits", RGBColor(44, 160, 44), |f| f.cache_full),
        ("partial hits", RGBColor(255, 127, 14), |f| f.cache_partial),
        ("misses", RGBColor(214, 39, 40), |f| f.cache_miss),
    ];
    let cumulative = |get: Count| -> Vec<(f64, f64)> {
        let mut sum = 0u64;
        stats
            .frames
            .iter()
            .map(|f| {
                sum += get(f);
                (f.frame as f64, sum as f64)
            })
            .collect()
    };
    let top = series.iter().map(|s| cumulative(s.2).last().map_or(0.0, |p| p.1)).fold(0.0, f64::max).max(1.0)
        * 1.15;
    let caption = if stats.run.cache_enabled {
        "Geometry cache lookups on reactivation, cumulative"
    } else {
        "Geometry cache: off (--cache off)"
    };
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(frame_range(stats), 0.0..top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_desc("cache requests (count)")
        .y_labels(count_labels(top))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(err)?;
    for (name, colour, get) in series {
        let points = cumulative(get);
        let total = points.last().map_or(0.0, |p| p.1);
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(3)))
            .map_err(err)?
            .label(format!("{name} ({total:.0})"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(3)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

/// Tick labels for a count axis up to `top`: at most one per whole number, so none repeats.
pub(super) fn count_labels(top: f64) -> usize {
    (top.floor() as usize + 1).clamp(2, 11)
}

fn fraction_histogram(stats: &RunStats, area: &Area<'_>) -> PlotResult {
    let cache = &stats.summary.cache.stats;
    let counts = cache.fraction_histogram;
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f64 * 1.15;
    let caption = format!(
        "Fraction of requested islands already integrated in the served cache entry ({} requests)",
        cache.requests
    );
    let buckets = FRACTION_BUCKETS.len() as u32;
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((0u32..buckets).into_segmented(), 0.0..top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(FRACTION_BUCKETS.len())
        .x_label_formatter(&|v| match v {
            SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => {
                FRACTION_BUCKETS.get(*i as usize).copied().unwrap_or("").to_string()
            }
            SegmentValue::Last => String::new(),
        })
        .x_desc("fraction of requested islands held (bucket)")
        .y_desc("requests (count)")
        .y_labels(count_labels(top))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(err)?;
    let colour = RGBColor(31, 119, 180);
    chart
        .draw_series(
            Histogram::vertical(&chart)
                .style(colour.filled())
                .margin(6)
                .data(counts.iter().enumerate().map(|(i, &n)| (i as u32, n as f64))),
        )
        .map_err(err)?
        .label("requests per bucket")
        .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], colour.filled()));
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}
