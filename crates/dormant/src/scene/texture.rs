//! Textures as plain data: decoded 8-bit RGBA texels plus the glTF sampler's wrap modes.
//! Sampling (filtering, colour space) belongs to the renderer.

use glam::Vec3;

/// How texture coordinates outside [0, 1] map back into the image (glTF sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    #[default]
    Repeat,
    ClampToEdge,
    MirroredRepeat,
}

/// A decoded image: `width * height` RGBA texels, rows from the top (glTF's UV origin is the
/// image's top-left corner). Texels are stored as authored; whether they are sRGB-encoded is
/// decided by the material slot that uses them.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where the image came from, for messages (e.g. `duck.glb: images[0]`).
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[u8; 4]>,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
}

impl Texture {
    /// The stand-in for an image that could not be loaded: one opaque magenta texel.
    pub(crate) fn magenta(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            width: 1,
            height: 1,
            texels: vec![[255, 0, 255, 255]],
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
        }
    }

    /// Whether the texel array matches the size (and the size is not zero).
    pub(crate) fn is_consistent(&self) -> bool {
        self.width > 0 && self.height > 0 && self.texels.len() == self.width as usize * self.height as usize
    }

    /// The mean of the texels' RGB as stored (0..1, not linearised): a summary for tests and
    /// logs.
    pub fn mean_rgb(&self) -> Vec3 {
        let n = self.texels.len().max(1) as f32;
        self.texels
            .iter()
            .fold(Vec3::ZERO, |acc, t| acc + Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32) / 255.0)
            / n
    }
}
