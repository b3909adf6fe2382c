//! What every figure shares: the embedded font (DejaVu Sans Mono, so no system font library
//! is needed), the stage colours, the legend style, count axes, and drawing into a pixel
//! buffer with plotters that `image` encodes and writes atomically.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::ReportError;

/// The font family every figure draws text in (registered by [`write_png`]).
pub const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSansMono.ttf");

/// The frame stages stacked bottom to top in stage-time plots, with their colours.
pub const STAGES: [(&str, RGBColor); 5] = [
    ("update", RGBColor(31, 119, 180)),
    ("integrate", RGBColor(255, 127, 14)),
    ("reactivate", RGBColor(214, 39, 40)),
    ("commit", RGBColor(148, 103, 189)),
    ("trace", RGBColor(44, 160, 44)),
];

/// A panel of a figure.
pub type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
/// What drawing a panel returns: plotters' errors as text.
pub type PlotResult = Result<(), String>;

/// A plotters error as the text [`PlotResult`] carries.
pub fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// Draws `width` x `height` pixels with `draw` (the embedded font registered) and writes
/// them to `path` as PNG, atomically.
pub fn write_png(
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
    dormant::atomic_file::write_atomic(path, &png)
        .map_err(|source| ReportError::Write { path: path.to_path_buf(), source })
}

/// The legend of `chart`'s labelled series, in the one style every panel uses.
pub fn draw_legend<'a, CT: CoordTranslate>(
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

/// Tick labels for a count axis up to `top`: at most one per whole number, so none repeats.
pub fn count_labels(top: f64) -> usize {
    (top.floor() as usize + 1).clamp(2, 11)
}
