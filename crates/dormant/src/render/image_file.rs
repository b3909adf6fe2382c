//! Images on disk: a film as a tone-mapped 8-bit sRGB PNG or linear 32-bit float OpenEXR, and
//! an AOV pass as a PNG in the encoding that shows it; every file written atomically.

use std::path::Path;

use glam::Vec3;
use image::{ImageBuffer, Rgb};

use super::aov::Aov;
use super::film::srgb_encode;
use super::{Film, RenderError};

/// Encodes the film as an 8-bit sRGB PNG and writes it atomically.
pub(crate) fn write_png_atomic(film: &Film, exposure: f32, path: &Path) -> Result<(), RenderError> {
    write_rgb8_png_atomic(film.width, film.height, film.to_srgb8(exposure), path)
}

/// Writes an AOV pass as an 8-bit PNG, atomically, without tone mapping: albedo sRGB-encoded,
/// normals as `0.5 * n + 0.5`, depth as grey from 0 (at the camera) to 1 (the farthest hit;
/// rays that hit nothing are white too), sample counts as grey from 0 to the frame's most.
pub(crate) fn write_aov_png_atomic(film: &Film, aov: Aov, path: &Path) -> Result<(), RenderError> {
    let far = film.pixels.iter().map(|p| p.x).filter(|d| d.is_finite()).fold(0.0f32, f32::max).max(1e-6);
    let byte = |c: f32| (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    let bytes = film
        .pixels
        .iter()
        .flat_map(|&p| {
            let p = if p.is_finite() { p } else { Vec3::ZERO };
            match aov {
                Aov::Albedo | Aov::Baked => p.to_array().map(|c| srgb_encode(c.clamp(0.0, 1.0))),
                Aov::Normal => (p * 0.5 + Vec3::splat(0.5)).to_array().map(byte),
                Aov::Depth if p.x <= 0.0 => [255; 3],
                Aov::Depth => [byte(p.x / far); 3],
                Aov::Spp | Aov::Traced => [byte(p.x / far); 3],
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
}
