//! The regime map of `dormant bench regimes`: `regimes.json`, `regimes.md` (one table row per
//! body count and budget), `regimes.png` (settled speed-up of `auto` against its ceiling over
//! the body count, one panel per budget) and `regimes-reuse.png` (exact reuse, integration and
//! both over every frame in full, the same panels).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

use super::{Budget, RegimeCell, RegimesReport};
use crate::report::figure::{draw_legend, err, write_png, Area, PlotResult, FONT};
use crate::report::ReportError;
use dormant::accel::Backend;

const WIDTH: u32 = 1500;
const HEIGHT: u32 = 520;

/// Writes `regimes.json`, `regimes.md` and `regimes.png` into `dir`; returns their paths.
pub fn write_regimes(report: &RegimesReport, dir: &Path) -> Result<Vec<PathBuf>, ReportError> {
    std::fs::create_dir_all(dir).map_err(|source| ReportError::Write { path: dir.to_path_buf(), source })?;
    let png = dir.join("regimes.png");
    write_png(&png, WIDTH, HEIGHT, |buffer| draw(report, buffer))?;
    let reuse_png = dir.join("regimes-reuse.png");
    write_png(&reuse_png, WIDTH, HEIGHT, |buffer| draw_reuse(report, buffer))?;
    let value = crate::bench::bench_json(report);
    let json = serde_json::to_string_pretty(&value).expect("JSON values serialise");
    let mut written = vec![png, reuse_png];
    for (name, text) in [("regimes.json", json), ("regimes.md", regimes_markdown(report))] {
        let path = dir.join(name);
        dormant::atomic_file::write_atomic(&path, text.as_bytes())
            .map_err(|source| ReportError::Write { path: path.clone(), source })?;
        written.push(path);
    }
    Ok(written)
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        "n/a".into()
    }
}

fn budget_name(b: Budget) -> String {
    let (w, h, spp) = b.image();
    image_name(b, w, h, spp)
}

fn image_name(b: Budget, w: u32, h: u32, spp: u32) -> String {
    let mode = if b == Budget::Production { "path traced" } else { "shaded" };
    format!("{mode} {w}x{h} {spp} spp")
}

/// The table: one row per body count, budget and backend.
pub fn regimes_markdown(report: &RegimesReport) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Scene `{}`, integration form `{}`, {} threads, {:.0} min. Speed-ups are `never` over \
         `auto` (lookahead on); the ceiling is `never`'s settled frame over its trace plus its \
         commit times the awake share; the trace penalty is `always`'s settled trace over \
         `never`'s. Reuse, integration and both: over every frame in full under `never`, on \
         the cell's preview frames or {} consecutive production frames from the start of the \
         last quarter; the traced share is exact reuse's share of camera samples traced, its \
         bound 1 over it.\n",
        report.scene,
        report.form,
        report.threads,
        report.wall_s / 60.0,
        report.sizes.reuse_frames
    );
    let _ = writeln!(
        md,
        "| bodies | budget | backend | frames (settled) | settled speed-up | ceiling | of ceiling | \
         run speed-up | auto over best | trace penalty | never ms | auto ms | reuse | integration | \
         both | traced share (bound) |"
    );
    let _ = writeln!(md, "| ---: | --- | --- | ---: |{}", " ---: |".repeat(12));
    for c in &report.cells {
        let r = &c.ratios;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} ({}) | {} | {} | {} | {} | {} | {} | {:.1} | {:.1} | {} | {} | {} | {:.2}% ({:.0}) |",
            c.bodies,
            image_name(c.budget, c.width, c.height, c.spp),
            c.backend,
            c.frames_rendered,
            c.settled_frames,
            num(r.settled_speedup),
            num(r.ceiling),
            num(r.of_ceiling),
            num(r.run_speedup),
            num(r.auto_over_best),
            num(r.trace_penalty),
            c.never_frame_ms,
            c.auto_frame_ms,
            num(c.reuse.reuse_speedup),
            num(c.reuse.integration_speedup),
            num(c.reuse.both_speedup),
            100.0 * c.reuse.traced_share,
            c.reuse.bound
        );
    }
    md
}

fn draw(report: &RegimesReport, buffer: &mut [u8]) -> PlotResult {
    let title = format!("Where integration pays: {} (settled speed-up of auto over never)", report.scene);
    draw_panels(report, buffer, &title, panel)
}

fn draw_reuse(report: &RegimesReport, buffer: &mut [u8]) -> PlotResult {
    let title = format!("Reuse and integration: {} (speed-up over every frame in full)", report.scene);
    draw_panels(report, buffer, &title, reuse_panel)
}

/// A figure of one panel per budget, each drawn by `panel` from that budget's cells.
fn draw_panels(
    report: &RegimesReport,
    buffer: &mut [u8],
    title: &str,
    panel: fn(&[&RegimeCell], Budget, &Area<'_>) -> PlotResult,
) -> PlotResult {
    let root = BitMapBackend::with_buffer(buffer, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(title, (FONT, 22)).map_err(err)?;
    let budgets: Vec<Budget> =
        Budget::ALL.into_iter().filter(|b| report.cells.iter().any(|c| c.budget == *b)).collect();
    let panels = root.split_evenly((1, budgets.len().max(1)));
    for (budget, area) in budgets.iter().zip(&panels) {
        let cells: Vec<&RegimeCell> = report.cells.iter().filter(|c| c.budget == *budget).collect();
        panel(&cells, *budget, area)?;
    }
    root.present().map_err(err)
}

/// One budget: per backend, the settled speed-up (solid) and the ceiling (dashed) over bodies.
fn panel(cells: &[&RegimeCell], budget: Budget, area: &Area<'_>) -> PlotResult {
    let (lo, hi) = body_range(cells);
    let top = cells
        .iter()
        .flat_map(|c| [c.ratios.settled_speedup, c.ratios.ceiling])
        .filter(|v| v.is_finite())
        .fold(1.2f64, f64::max)
        * 1.15;
    let mut chart = speedup_chart(area, budget, (lo, hi), 0.0..top)?;
    let colours = [RGBColor(31, 119, 180), RGBColor(214, 39, 40)];
    for (backend, colour) in backends_of(cells).into_iter().zip(colours.iter().cycle()) {
        let series = |get: fn(&RegimeCell) -> f64| -> Vec<(f64, f64)> {
            cells
                .iter()
                .filter(|c| c.backend == backend)
                .map(|c| (c.bodies.max(1) as f64, get(c)))
                .filter(|(_, y)| y.is_finite())
                .collect()
        };
        let colour = *colour;
        chart
            .draw_series(LineSeries::new(series(|c| c.ratios.settled_speedup), colour.stroke_width(3)))
            .map_err(err)?
            .label(format!("{backend}: auto"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(3)));
        chart
            .draw_series(DashedLineSeries::new(series(|c| c.ratios.ceiling), 8, 5, colour.stroke_width(2)))
            .map_err(err)?
            .label(format!("{backend}: ceiling"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(1)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

/// One of a cell's speed-ups.
type Speedup = fn(&RegimeCell) -> f64;

/// One budget: per backend (solid, then dashed), reuse, integration and both over bodies, on
/// a log scale.
fn reuse_panel(cells: &[&RegimeCell], budget: Budget, area: &Area<'_>) -> PlotResult {
    let (lo, hi) = body_range(cells);
    let top = cells
        .iter()
        .flat_map(|c| [c.reuse.reuse_speedup, c.reuse.integration_speedup, c.reuse.both_speedup])
        .filter(|v| v.is_finite())
        .fold(2.0f64, f64::max)
        * 1.5;
    let mut chart = speedup_chart(area, budget, (lo, hi), (0.5..top).log_scale())?;
    let kinds: [(&str, RGBColor, Speedup); 3] = [
        ("reuse", RGBColor(31, 119, 180), |c| c.reuse.reuse_speedup),
        ("integration", RGBColor(255, 127, 14), |c| c.reuse.integration_speedup),
        ("both", RGBColor(44, 160, 44), |c| c.reuse.both_speedup),
    ];
    for (b, backend) in backends_of(cells).into_iter().enumerate() {
        for (name, colour, get) in kinds {
            let points: Vec<(f64, f64)> = cells
                .iter()
                .filter(|c| c.backend == backend)
                .map(|c| (c.bodies.max(1) as f64, get(c)))
                .filter(|(_, y)| y.is_finite() && *y > 0.0)
                .collect();
            let style = colour.stroke_width(if b == 0 { 3 } else { 2 });
            let label = format!("{backend}: {name}");
            if b == 0 {
                chart.draw_series(LineSeries::new(points, style)).map_err(err)?.label(label)
            } else {
                chart.draw_series(DashedLineSeries::new(points, 8, 5, style)).map_err(err)?.label(label)
            }
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style));
        }
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

/// A chart of speed-ups (on `Y`) over body counts (log).
type SpeedupChart<'c, 'b, Y> = ChartContext<'c, BitMapBackend<'b>, Cartesian2d<LogCoord<f64>, Y>>;

/// A panel's chart: body counts `bodies` (least, most) on a log scale against speed-ups on
/// `y`, its mesh drawn and a line at 1.
fn speedup_chart<'c, 'b, Y>(
    area: &Area<'b>,
    budget: Budget,
    (lo, hi): (f64, f64),
    y: Y,
) -> Result<SpeedupChart<'c, 'b, Y::CoordDescType>, String>
where
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(budget_name(budget), (FONT, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d((lo * 0.8..hi * 1.25).log_scale(), y)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("bodies")
        .y_desc("speed-up")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v:.1}"))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()
        .map_err(err)?;
    let one = vec![(lo * 0.8, 1.0), (hi * 1.25, 1.0)];
    chart.draw_series(LineSeries::new(one, BLACK.mix(0.4))).map_err(err)?;
    Ok(chart)
}

/// The least and most body counts of `cells`.
fn body_range(cells: &[&RegimeCell]) -> (f64, f64) {
    cells.iter().map(|c| c.bodies.max(1) as f64).fold((f64::MAX, 1.0f64), |(a, b), x| (a.min(x), b.max(x)))
}

/// The backends of `cells` in the order they first come (cells come count by count, each
/// with every backend): one series each.
fn backends_of(cells: &[&RegimeCell]) -> Vec<Backend> {
    let mut backends = Vec::new();
    for c in cells {
        if !backends.contains(&c.backend) {
            backends.push(c.backend);
        }
    }
    backends
}
