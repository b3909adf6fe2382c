//! Texture lookup for shading: wrap modes, bilinear filtering and sRGB decoding of the
//! scene's plain RGBA8 textures.

use std::sync::OnceLock;

use glam::{Vec2, Vec4};

use crate::scene::texture::{Texture, Wrap};

/// sRGB-encoded byte -> linear value.
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f32 / 255.0;
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        })
    })
}

/// Texel index along one axis of `size` texels for integer coordinate `i`.
fn wrap(i: i64, size: u32, mode: Wrap) -> usize {
    let n = size as i64;
    if (0..n).contains(&i) {
        // Inside the image, every mode agrees; skips `rem_euclid`'s 64-bit division, which
        // most look-ups would otherwise pay twice per texel (same texels).
        return i as usize;
    }
    let i = match mode {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    };
    i as usize
}

/// The texture at `uv` (glTF convention: origin at the image's top-left), bilinearly
/// filtered, as linear RGBA; the RGB channels are decoded from sRGB when `srgb`. Alpha is
/// always linear.
pub(crate) fn sample(texture: &Texture, uv: Vec2, srgb: bool) -> Vec4 {
    if !texture.is_consistent() {
        debug_assert!(false, "inconsistent texture {}", texture.name);
        return Vec4::new(1.0, 0.0, 1.0, 1.0);
    }
    let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
    // Texel centres sit at half-integers. Keep the coordinate small enough for i64 and
    // precise enough for the fraction: wrapping is periodic, and clamping saturates anyway.
    let x = (uv.x as f64 * texture.width as f64 - 0.5).clamp(-1e12, 1e12);
    let y = (uv.y as f64 * texture.height as f64 - 0.5).clamp(-1e12, 1e12);
    // floor() as an integer conversion (x86-64's baseline has no rounding instruction, so
    // f64::floor is a libm call); exact, since |x| <= 1e12.
    let floor = |v: f64| {
        let i = v as i64;
        i - ((i as f64) > v) as i64
    };
    let (x0, y0) = (floor(x), floor(y));
    let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
    let table = srgb_table();
    let texel = |xi: i64, yi: i64| {
        let tx = wrap(xi, texture.width, texture.wrap_s);
        let ty = wrap(yi, texture.height, texture.wrap_t);
        let [r, g, b, a] = texture.texels[ty * texture.width as usize + tx];
        if srgb {
            Vec4::new(table[r as usize], table[g as usize], table[b as usize], a as f32 / 255.0)
        } else {
            Vec4::new(r as f32, g as f32, b as f32, a as f32) / 255.0
        }
    };
    let top = texel(x0, y0).lerp(texel(x0 + 1, y0), fx);
    let bottom = texel(x0, y0 + 1).lerp(texel(x0 + 1, y0 + 1), fx);
    top.lerp(bottom, fy)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(wrap: Wrap) -> Texture {
        Texture {
            name: "checker".into(),
            width: 2,
            height: 2,
            texels: vec![[255, 255, 255, 255], [0, 0, 0, 255], [0, 0, 0, 255], [255, 255, 255, 255]],
            wrap_s: wrap,
            wrap_t: wrap,
        }
    }

    #[test]
    fn texel_centres_return_their_texel() {
        let t = checker(Wrap::Repeat);
        assert_eq!(sample(&t, Vec2::new(0.25, 0.25), false).x, 1.0);
        assert_eq!(sample(&t, Vec2::new(0.75, 0.25), false).x, 0.0);
        assert_eq!(sample(&t, Vec2::new(0.25, 0.75), false).x, 0.0);
    }

    #[test]
    fn wrap_modes_outside_the_unit_square() {
        let repeat = checker(Wrap::Repeat);
        assert_eq!(sample(&repeat, Vec2::new(1.25, 0.25), false).x, 1.0);
        assert_eq!(sample(&repeat, Vec2::new(-0.25, 0.25), false).x, 0.0);
        let clamp = checker(Wrap::ClampToEdge);
        assert_eq!(sample(&clamp, Vec2::new(3.0, 0.25), false).x, 0.0);
        assert_eq!(sample(&clamp, Vec2::new(-3.0, 0.25), false).x, 1.0);
        let mirror = checker(Wrap::MirroredRepeat);
        // [1, 2) mirrors [0, 1): u = 1.25 reads the texel at u = 0.75.
        assert_eq!(sample(&mirror, Vec2::new(1.25, 0.25), false).x, 0.0);
        assert_eq!(sample(&mirror, Vec2::new(1.75, 0.25), false).x, 1.0);
    }

    #[test]
    fn bilinear_between_texels_and_srgb_decoding() {
        let t = checker(Wrap::Repeat);
        let mid = sample(&t, Vec2::new(0.5, 0.25), false).x;
        assert!((mid - 0.5).abs() < 1e-6, "{mid}");
        let grey = Texture { texels: vec![[188, 188, 188, 255]], width: 1, height: 1, ..t };
        let linear = sample(&grey, Vec2::ZERO, true).x;
        assert!((linear - 0.5).abs() < 0.01, "{linear}");
    }

    #[test]
    fn non_finite_uv_does_not_panic() {
        let t = checker(Wrap::MirroredRepeat);
        let v = sample(&t, Vec2::new(f32::NAN, f32::INFINITY), true);
        assert!(v.is_finite());
    }
}
