//! `report.png`, the plot of a rendered sequence's statistics: frame time by stage over the
//! run, the share of camera samples each frame traced, the bodies in the per-frame top level,
//! resting and baked over the run, and, when the geometry cache served requests, its hits over the
//! run and the histogram of the fraction of requested islands it already held. Drawn with
//! the lab's figure helpers.

use std::path::Path;

use dormant::residency::{CacheStats, StageTimes};
use dormant::sequence::stats::{FrameRecord, RunStats};
use dormant_lab::report::figure::{
    count_labels, draw_legend, err, write_png, Area, PlotResult, FONT, STAGES,
};
use dormant_lab::report::ReportError;
use plotters::prelude::*;

const PLOT_WIDTH: u32 = 1200;
/// Height of one panel.
const PANEL_HEIGHT: u32 = 450;

/// A per-frame count of a record.
type Count = fn(&FrameRecord) -> u64;

/// A line of a plot: its legend, colour and (frame, value) points.
type Line = (String, RGBColor, Vec<(f64, f64)>);

fn stage_ms(f: &FrameRecord, stage: usize) -> f64 {
    (StageTimes::STAGES[stage].1)(&f.stages)
}

/// Draws the report of `stats` and writes it to `path` as PNG.
pub fn write_report_png(stats: &RunStats, path: &Path) -> Result<(), ReportError> {
    let height = PANEL_HEIGHT * panel_count(stats);
    write_png(path, PLOT_WIDTH, height, |buffer| draw(stats, buffer, height))
}

/// Whether the geometry cache served any request: without, its panels would say nothing.
fn cache_used(stats: &RunStats) -> bool {
    stats.summary.cache.stats.requests > 0
}

fn panel_count(stats: &RunStats) -> u32 {
    3 + if cache_used(stats) { 2 } else { 0 }
}

fn draw(stats: &RunStats, buffer: &mut [u8], height: u32) -> PlotResult {
    let root = BitMapBackend::with_buffer(buffer, (PLOT_WIDTH, height)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let run = &stats.run;
    let title = format!(
        "{}: {} frames, {}x{} {} spp, {} backend, integration {}",
        run.scene, stats.summary.frames, run.width, run.height, run.spp, run.backend, run.integration
    );
    let root = root.titled(&title, (FONT, 22)).map_err(err)?;
    let panels = root.split_evenly((panel_count(stats) as usize, 1));
    stage_times(stats, &panels[0])?;
    traced_share(stats, &panels[1])?;
    bodies(stats, &panels[2])?;
    if cache_used(stats) {
        cache_hits(stats, &panels[3])?;
        fraction_histogram(stats, &panels[4])?;
    }
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

/// The share of each frame's camera samples it traced (the rest were reused), in percent.
fn traced_share(stats: &RunStats, area: &Area<'_>) -> PlotResult {
    let points: Vec<(f64, f64)> =
        stats.frames.iter().map(|f| (f.frame as f64, 100.0 * f.reuse.traced_share())).collect();
    let caption = format!("Camera samples traced, % of the frame's (--reuse {})", stats.run.reuse_mode);
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(frame_range(stats), (0.001f64..110.0).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_desc("traced (%, log)")
        .y_label_formatter(&|v| format!("{v}"))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(err)?;
    let colour = RGBColor(31, 119, 180);
    let clamped = points.into_iter().map(|(x, y)| (x, y.max(0.001)));
    chart.draw_series(LineSeries::new(clamped, colour.stroke_width(2))).map_err(err)?;
    Ok(())
}

/// Bodies in the per-frame top level (awake, and asleep but not integrated), resting and baked.
fn bodies(stats: &RunStats, area: &Area<'_>) -> PlotResult {
    let series: [(&str, RGBColor, Count); 3] = [
        ("in the per-frame top level", RGBColor(31, 119, 180), |f| f.instances as u64),
        ("resting", RGBColor(44, 160, 44), |f| f.resting_bodies as u64),
        ("baked", RGBColor(255, 127, 14), |f| f.baked_bodies as u64),
    ];
    let lines = series.map(|(name, colour, get)| {
        let points = stats.frames.iter().map(|f| (f.frame as f64, get(f) as f64)).collect();
        (name.to_string(), colour, points)
    });
    count_lines(stats, area, "Bodies in the per-frame top level, resting and baked", "bodies (count)", lines)
}

/// Lines of counts over the run's frames, each with its name in the legend.
fn count_lines(
    stats: &RunStats,
    area: &Area<'_>,
    caption: &str,
    y_desc: &str,
    lines: [Line; 3],
) -> PlotResult {
    let top = lines.iter().flat_map(|l| l.2.iter().map(|p| p.1)).fold(0.0, f64::max).max(1.0) * 1.15;
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
        .y_desc(y_desc)
        .y_labels(count_labels(top))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(err)?;
    for (name, colour, points) in lines {
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(3)))
            .map_err(err)?
            .label(name)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(3)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
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
    let lines = series.map(|(name, colour, get)| {
        let mut sum = 0u64;
        let points: Vec<(f64, f64)> = stats
            .frames
            .iter()
            .map(|f| {
                sum += get(f);
                (f.frame as f64, sum as f64)
            })
            .collect();
        (format!("{name} ({sum})"), colour, points)
    });
    let caption = if stats.run.cache_enabled {
        "Geometry cache lookups on reactivation, cumulative"
    } else {
        "Geometry cache: off (--cache off)"
    };
    count_lines(stats, area, caption, "cache requests (count)", lines)
}

fn fraction_histogram(stats: &RunStats, area: &Area<'_>) -> PlotResult {
    let cache = &stats.summary.cache.stats;
    let counts = cache.fraction_histogram;
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f64 * 1.15;
    let caption = format!(
        "Fraction of requested islands already integrated in the served cache entry ({} requests)",
        cache.requests
    );
    let buckets = CacheStats::FRACTION_BUCKETS.len() as u32;
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
        .x_labels(CacheStats::FRACTION_BUCKETS.len())
        .x_label_formatter(&|v| match v {
            SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => {
                CacheStats::FRACTION_BUCKETS.get(*i as usize).copied().unwrap_or("").to_string()
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
