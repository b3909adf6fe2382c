//! The film: per-pixel linear radiance, tone mapping, and atomic PNG and OpenEXR output.

use std::path::Path;

use glam::Vec3;
use image::{ImageBuffer, Rgb};

use super::RenderError;

/// Linear RGB radiance per pixel, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

/// ACES filmic tone curve (Narkowicz's fit), input and output linear.
fn aces(x: Vec3) -> Vec3 {
    let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
    ((x * (a * x + b)) / (x * (c * x + d) + e)).clamp(Vec3::ZERO, Vec3::ONE)
}

fn srgb_encode(c: f32) -> u8 {
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5).clamp(0.0, 255.0) as u8
}

impl Film {
    pub(crate) fn new(width: u32, height: u32) -> Self {
        Self { width, height, pixels: vec![Vec3::ZERO; width as usize * height as usize] }
    }

    /// Tone-mapped, sRGB-encoded 8-bit pixels. Non-finite radiance maps to black.
    fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|&p| {
                let p = if p.is_finite() { p } else { Vec3::ZERO };
                let m = aces(p * exposure);
                [srgb_encode(m.x), srgb_encode(m.y), srgb_encode(m.z)]
            })
            .collect()
    }
}

/// Encodes the film as an 8-bit sRGB PNG and writes it atomically.
pub fn write_png_atomic(film: &Film, exposure: f32, path: &Path) -> Result<(), RenderError> {
    write_rgb8_png_atomic(film.width, film.height, film.to_srgb8(exposure), path)
}

/// Writes an AOV pass as an 8-bit PNG, atomically, without tone mapping: albedo sRGB-encoded,
/// normals as `0.5 * n + 0.5`, depth as grey from 0 (at the camera) to 1 (the farthest hit;
/// rays that hit nothing are white too), sample counts as grey from 0 to the frame's most.
pub fn write_aov_png_atomic(film: &Film, aov: super::Aov, path: &Path) -> Result<(), RenderError> {
    let far = film.pixels.iter().map(|p| p.x).filter(|d| d.is_finite()).fold(0.0f32, f32::max).max(1e-6);
    let byte = |c: f32| (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    let bytes = film
        .pixels
        .iter()
        .flat_map(|&p| {
            let p = if p.is_finite() { p } else { Vec3::ZERO };
            match aov {
                super::Aov::Albedo | super::Aov::Baked => {
                    p.to_array().map(|c| srgb_encode(c.clamp(0.0, 1.0)))
                }
                super::Aov::Normal => (p * 0.5 + Vec3::splat(0.5)).to_array().map(byte),
                super::Aov::Depth if p.x <= 0.0 => [255; 3],
                super::Aov::Depth => [byte(p.x / far); 3],
                super::Aov::Spp => [byte(p.x / far); 3],
            }
        })
        .collect();
    write_rgb8_png_atomic(film.width, film.height, bytes, path)
}

fn write_rgb8_png_atomic(width: u32, height: u32, bytes: Vec<u8>, path: &Path) -> Result<(), RenderError> {
    let img: ImageBuffer<Rgb<u8>, Vec<u8>> =
        ImageBuffer::from_raw(width, height, bytes).expect("film holds width * height pixels");
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|source| RenderError::Encode { path: path.to_path_buf(), source })?;
    crate::atomic_file::write_atomic(path, &bytes)
        .map_err(|source| RenderError::Io { path: path.to_path_buf(), source })
}

/// Writes the film's linear radiance as a 32-bit float OpenEXR file, atomically.
pub fn write_exr_atomic(film: &Film, path: &Path) -> Result<(), RenderError> {
    let data: Vec<f32> = film.pixels.iter().flat_map(|p| p.to_array()).collect();
    let img: image::Rgb32FImage =
        ImageBuffer::from_raw(film.width, film.height, data).expect("film holds width * height pixels");
    let mut bytes = Vec::new();
    image::DynamicImage::ImageRgb32F(img)
        .write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::OpenExr)
        .map_err(|source| RenderError::Encode { path: path.to_path_buf(), source })?;
    crate::atomic_file::write_atomic(path, &bytes)
        .map_err(|source| RenderError::Io { path: path.to_path_buf(), source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trips_linear_radiance() {
        let mut film = Film::new(3, 2);
        film.pixels[4] = Vec3::new(12.5, 0.25, 1e-3);
        let path = std::env::temp_dir().join(format!("dormant-film-{}.exr", std::process::id()));
        write_exr_atomic(&film, &path).unwrap();
        let back = image::open(&path).unwrap().to_rgb32f();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(back.get_pixel(1, 1).0, [12.5, 0.25, 1e-3]);
    }

    #[test]
    fn tone_curve_is_monotonic_and_bounded() {
        let mut last = 0u8;
        for i in 0..100 {
            let v = srgb_encode(aces(Vec3::splat(i as f32 * 0.1)).x);
            assert!(v >= last);
            last = v;
        }
        assert_eq!(srgb_encode(aces(Vec3::splat(1e9)).x), 255);
        assert_eq!(srgb_encode(aces(Vec3::ZERO).x), 0);
    }
}
