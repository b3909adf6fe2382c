//! The largest counts, sizes and resolutions dormant accepts, from a scene file or the command
//! line: what a 24 GiB machine can hold, so that a typo such as `count = 4000000000` is an
//! error naming the field instead of an allocation that grows until the machine gives up.
//! Scene-file validation and the CLI's parsers both check against these constants.
//!
//! The budgets come from the memory a simulated body and a rendered pixel were measured to
//! take: docs/errors.md#the-bounds-and-why.

/// Dynamic bodies in one scene: spawned objects, structure blocks, projectiles and
/// key-framed bodies together.
pub(crate) const MAX_BODIES: u64 = 2_000_000;

/// Frames in one scene (4.6 hours at 60 frames a second).
pub(crate) const MAX_FRAMES: u32 = 1_000_000;

/// Width or height of an image, in pixels.
pub(crate) const MAX_IMAGE_SIDE: u32 = 16_384;

/// Pixels in one image (8192 x 8192).
pub(crate) const MAX_PIXELS: u64 = 1 << 26;

/// Samples per pixel.
pub const MAX_SAMPLES_PER_PIXEL: u32 = 65_536;

/// Why a shutter (motion blur, a fraction of the frame interval) is out of bounds, or `None`
/// when it is from 0 (off) to 1.
pub fn shutter_problem(shutter: f32) -> Option<String> {
    (!(0.0..=1.0).contains(&shutter))
        .then(|| format!("{shutter}: must be a fraction of the frame interval from 0 (no motion blur) to 1"))
}

/// Why an image size is out of bounds, or `None` when `width` x `height` is allowed.
pub(crate) fn image_size_problem(width: u32, height: u32) -> Option<String> {
    if !(1..=MAX_IMAGE_SIDE).contains(&width) || !(1..=MAX_IMAGE_SIDE).contains(&height) {
        return Some(format!("{width}x{height}: width and height must be from 1 to {MAX_IMAGE_SIDE}"));
    }
    let pixels = width as u64 * height as u64;
    if pixels > MAX_PIXELS {
        return Some(format!(
            "{width}x{height} is {pixels} pixels, more than the {MAX_PIXELS} (8192x8192) allowed"
        ));
    }
    None
}
