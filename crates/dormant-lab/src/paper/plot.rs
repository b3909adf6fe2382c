//! The figure of one `bench paper` workload: frame time over the run under `never`, `always`
//! and `auto` with the share of bodies asleep (the paper's Figure 2), one panel per backend;
//! the settled frame's cost by stage per configuration; and the histogram of the fraction of
//! requested islands the cache held.

use std::path::Path;

use plotters::prelude::*;

use super::WorkloadReport;
use crate::bench::integration::IntegrationBenchReport;
use crate::report::figure::{count_labels, draw_legend, err, write_png, Area, PlotResult, FONT, STAGES};
use crate::report::ReportError;
use dormant::residency::{CacheStats, IntegrationForm, IntegrationPolicy, StageTimes};

const WIDTH: u32 = 1400;
const ROW_HEIGHT: u32 = 480;

/// Colours of the policies' lines.
const POLICIES: [(IntegrationPolicy, &str, RGBColor); 3] = [
    (IntegrationPolicy::Never, "never", RGBColor(214, 39, 40)),
    (IntegrationPolicy::Always, "always", RGBColor(255, 127, 14)),
    (IntegrationPolicy::Auto, "auto", RGBColor(31, 119, 180)),
];

/// Writes the workload's figure to `path`.
pub fn write_workload_png(workload: &WorkloadReport, path: &Path) -> Result<(), ReportError> {
    let rows = workload.runs.len() as u32 + 1;
    write_png(path, WIDTH, ROW_HEIGHT * rows, |buffer| draw(workload, buffer, rows))
}

fn draw(w: &WorkloadReport, buffer: &mut [u8], rows: u32) -> PlotResult {
    let root = BitMapBackend::with_buffer(buffer, (WIDTH, ROW_HEIGHT * rows)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let title = format!(
        "{}: {} objects, {} frames, every {} rendered at {}x{} (shaded, 1 spp)",
        w.name, w.size.count, w.size.frames, w.size.frame_step, w.size.width, w.size.height
    );
    let root = root.titled(&title, (FONT, 24)).map_err(err)?;
    let panels = root.split_evenly((rows as usize, 1));
    for (run, area) in w.runs.iter().zip(&panels) {
        frame_times(&run.integration, area)?;
    }
    let bottom = panels.last().expect("one row more than runs").split_evenly((1, 2));
    stage_bars(w, &bottom[0])?;
    fraction_histogram(w, &bottom[1])?;
    root.present().map_err(err)
}

/// Frame time per policy (cache on) over the run, with the asleep share on the right axis.
fn frame_times(report: &IntegrationBenchReport, area: &Area<'_>) -> PlotResult {
    let first = report.frames.first().copied().unwrap_or(0) as f64;
    let last = (report.frames.last().copied().unwrap_or(0) as f64).max(first + 1.0);
    // Scaled to the 98th percentile: one island of 500 bodies integrated in one frame takes
    // seconds and would flatten every other frame; clipped peaks are labelled in the caption.
    let mut all: Vec<f64> = report.runs.iter().flat_map(|r| r.frame_ms.iter().copied()).collect();
    all.sort_by(f64::total_cmp);
    let p98 = all.get(all.len() * 98 / 100).copied().unwrap_or(0.0);
    let peak = all.last().copied().unwrap_or(0.0);
    let top = (p98 * 1.6).max(1e-3).min(peak * 1.1);
    let clipped = if peak > top { format!(" (clipped; peak {peak:.0} ms)") } else { String::new() };
    let caption = format!(
        "{} backend: frame time (all stages) per policy, cache on{clipped}; grey: bodies asleep",
        report.backend
    );
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .right_y_label_area_size(60)
        .build_cartesian_2d(first..last, 0.0..top)
        .map_err(err)?
        .set_secondary_coord(first..last, 0.0..105.0);
    chart
        .configure_mesh()
        .x_desc("simulated frame")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_desc("frame time (ms)")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(err)?;
    chart
        .configure_secondary_axes()
        .y_desc("bodies asleep (%)")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(err)?;
    let grey = RGBColor(150, 150, 150);
    chart
        .draw_secondary_series(LineSeries::new(
            report.frames.iter().zip(&report.asleep_fraction).map(|(&f, &a)| (f as f64, 100.0 * a)),
            grey.stroke_width(2),
        ))
        .map_err(err)?
        .label("bodies asleep (%, right axis)")
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], grey.stroke_width(2)));
    for (policy, name, colour) in POLICIES {
        let Some(run) = report.cache_on(policy) else { continue };
        let mean = run.total_ms / run.frame_ms.len().max(1) as f64;
        chart
            .draw_series(LineSeries::new(
                report.frames.iter().zip(&run.frame_ms).map(|(&f, &ms)| (f as f64, ms.min(top))),
                colour.stroke_width(2),
            ))
            .map_err(err)?
            .label(format!("{name} (mean {mean:.1} ms)"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(3)));
    }
    // Upper left: the asleep share is near zero there, and near 100% at the right.
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

/// Settled-phase mean ms per stage, stacked, for each backend and policy (cache on).
fn stage_bars(w: &WorkloadReport, area: &Area<'_>) -> PlotResult {
    let mut bars: Vec<(String, [f64; 5])> = Vec::new();
    for run in &w.runs {
        for (policy, name, _) in POLICIES {
            if let Some(p) = run.integration.cache_on(policy) {
                let s = &p.settled;
                bars.push((
                    format!("{}:{name}", run.backend),
                    StageTimes::STAGES.map(|(_, get)| get(&s.stages)),
                ));
            }
        }
    }
    let top = bars.iter().map(|(_, v)| v.iter().sum::<f64>()).fold(0.0, f64::max).max(1e-3) * 1.35;
    let n = bars.len().max(1);
    let mut chart = ChartBuilder::on(area)
        .caption("Settled frames (>= 90% asleep): mean cost by stage", (FONT, 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((0..n).into_segmented(), 0.0..top)
        .map_err(err)?;
    let labels: Vec<String> = bars.iter().map(|b| b.0.clone()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n)
        .x_label_formatter(&|v| match v {
            SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => labels.get(*i).cloned().unwrap_or_default(),
            SegmentValue::Last => String::new(),
        })
        .y_desc("time per frame (ms)")
        .label_style((FONT, 11))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(err)?;
    for (stage, (name, colour)) in STAGES.iter().enumerate() {
        let rects = bars.iter().enumerate().map(|(i, (_, v))| {
            let below: f64 = v[..stage].iter().sum();
            Rectangle::new(
                [(SegmentValue::Exact(i), below), (SegmentValue::Exact(i + 1), below + v[stage])],
                colour.mix(0.85).filled(),
            )
        });
        let colour = *colour;
        chart
            .draw_series(rects)
            .map_err(err)?
            .label(*name)
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], colour.filled()));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
}

/// Cache requests of `auto` (cache on) by the fraction of requested islands held, per
/// backend.
fn fraction_histogram(w: &WorkloadReport, area: &Area<'_>) -> PlotResult {
    let series: Vec<(String, [u64; 12])> = w
        .runs
        .iter()
        .filter_map(|run| {
            let auto = run.integration.run_of(IntegrationPolicy::Auto, IntegrationForm::Baked)?;
            let s = &auto.cache_stats;
            Some((format!("{} ({} requests)", run.backend, s.requests), s.fraction_histogram))
        })
        .collect();
    let top = series.iter().flat_map(|s| s.1.iter().copied()).max().unwrap_or(0).max(1) as f64 * 1.3;
    let buckets = CacheStats::FRACTION_BUCKETS.len();
    let mut chart = ChartBuilder::on(area)
        .caption("auto, cache on: fraction of requested islands held", (FONT, 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5..buckets as f64 - 0.5, 0.0..top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(buckets)
        // Bucket i is centred on x = i; ticks fall on whole numbers.
        .x_label_formatter(&|v| {
            match v.round() {
                i if (v - i).abs() < 1e-6 && i >= 0.0 => {
                    CacheStats::FRACTION_BUCKETS.get(i as usize).copied().unwrap_or("")
                }
                _ => "",
            }
            .to_string()
        })
        .x_desc("fraction of requested islands held (bucket)")
        .y_desc("requests (count)")
        .y_labels(count_labels(top))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(err)?;
    let colours = [RGBColor(31, 119, 180), RGBColor(44, 160, 44)];
    let width = 0.8 / series.len().max(1) as f64;
    for (k, (name, counts)) in series.iter().enumerate() {
        let colour = colours[k % colours.len()];
        let rects = counts.iter().enumerate().map(|(i, &c)| {
            let x0 = i as f64 - 0.4 + k as f64 * width;
            Rectangle::new([(x0, 0.0), (x0 + width, c as f64)], colour.filled())
        });
        chart
            .draw_series(rects)
            .map_err(err)?
            .label(name.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], colour.filled()));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}
