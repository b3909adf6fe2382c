use std::fs;
use std::io::Write;
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
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, pixels: vec![Vec3::ZERO; width as usize * height as usize] }
    }

    /// Tone-mapped, sRGB-encoded 8-bit pixels. Non-finite radiance maps to black.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
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

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename, so
/// readers never see a partial file and a failure leaves nothing behind.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), RenderError> {
    let io = |source| RenderError::Io { path: path.to_path_buf(), source };
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .ok_or_else(|| io(std::io::Error::new(std::io::ErrorKind::InvalidInput, "path has no file name")))?;
    let tmp = dir.join(format!(".{}.{}.tmp", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// Encodes the film as an 8-bit sRGB PNG and writes it atomically.
pub fn write_png_atomic(film: &Film, exposure: f32, path: &Path) -> Result<(), RenderError> {
    let img: ImageBuffer<Rgb<u8>, Vec<u8>> =
        ImageBuffer::from_raw(film.width, film.height, film.to_srgb8(exposure))
            .expect("film holds width * height pixels");
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|source| RenderError::Encode { path: path.to_path_buf(), source })?;
    write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn failed_write_leaves_no_file() {
        let dir = std::env::temp_dir().join(format!("dormant-film-{}", std::process::id()));
        let missing = dir.join("no/such/dir/frame.png");
        assert!(write_atomic(&missing, b"x").is_err());
        assert!(!missing.exists());
    }
}
