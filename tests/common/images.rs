//! Rendered images read back and compared.

use std::path::Path;

/// An image's pixels as RGB triples (an EXR's radiance as written).
pub fn pixels(path: &Path) -> Vec<[f32; 3]> {
    image::open(path).unwrap().to_rgb32f().pixels().map(|p| p.0).collect()
}

/// Relative MSE of `image` against `reference`: the mean over pixels and channels of
/// (x - ref)^2 / (ref^2 + 0.01), as in docs/performance.md.
pub fn relative_mse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    let sum: f64 = image
        .iter()
        .zip(reference)
        .flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]), f64::from(q[c]))))
        .map(|(x, r)| (x - r).powi(2) / (r * r + 0.01))
        .sum();
    sum / (3 * image.len()) as f64
}

/// [`relative_mse`] of the image file `image` against the image file `reference`, which must
/// have the same size.
pub fn relative_mse_of_files(image: &Path, reference: &Path) -> f64 {
    let (x, r) = (image::open(image).unwrap().to_rgb32f(), image::open(reference).unwrap().to_rgb32f());
    assert_eq!(x.dimensions(), r.dimensions());
    let pixels = |img: &image::Rgb32FImage| img.pixels().map(|p| p.0).collect::<Vec<_>>();
    relative_mse(&pixels(&x), &pixels(&r))
}
