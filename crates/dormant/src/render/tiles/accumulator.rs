//! A tile's running sums per pixel ([`Accumulator`]): the image's samples in index order, their
//! squares for adaptive sampling, and the AOV passes shaded at traced samples' camera hits
//! with their camera rays' horizon ([`FirstHits`]).

use glam::Vec3;

use super::packet::Cell;
use crate::render::adaptive::Stopping;

/// A tile's running sums per pixel, row by row. Per pixel, samples are summed in index order
/// whatever the blocking, so the image is the same as tracing pixel by pixel.
pub(super) struct Accumulator {
    x0: u32,
    y0: u32,
    tw: u32,
    pub sums: Vec<Vec3>,
    /// Sums of squared samples; only with adaptive sampling.
    squares: Vec<Vec3>,
    pub samples: Vec<u32>,
    pub first_hits: FirstHits,
}

/// A tile's AOV passes shaded at traced samples' camera hits: per pixel, `passes` running
/// sums in index order, the samples added, and the least horizon of their camera rays.
pub(super) struct FirstHits {
    passes: usize,
    sums: Vec<Vec3>,
    samples: Vec<u32>,
    camera_horizons: Vec<u32>,
}

impl FirstHits {
    /// Room for `passes` passes of `pixels` pixels (nothing without passes), and their camera
    /// horizons when `horizons`.
    pub(super) fn new(passes: usize, pixels: usize, horizons: bool) -> Self {
        let pixels = if passes == 0 { 0 } else { pixels };
        FirstHits {
            passes,
            sums: vec![Vec3::ZERO; passes * pixels],
            samples: vec![0; pixels],
            camera_horizons: if horizons { vec![u32::MAX; pixels] } else { Vec::new() },
        }
    }

    /// Adds one sample's pass `values` to pixel `at`, with its camera ray's horizon.
    pub(super) fn add(&mut self, at: usize, values: impl Iterator<Item = Vec3>, camera: Option<u32>) {
        for (sum, value) in self.sums[at * self.passes..(at + 1) * self.passes].iter_mut().zip(values) {
            *sum += value;
        }
        self.samples[at] += 1;
        if let (Some(camera), Some(least)) = (camera, self.camera_horizons.get_mut(at)) {
            *least = (*least).min(camera);
        }
    }

    /// The passes' pixel values (the sums over their samples, as the image's pixels are
    /// computed) and camera horizons.
    pub(super) fn finish(self) -> (Vec<Vec3>, Vec<u32>) {
        if self.passes == 0 {
            return (Vec::new(), Vec::new());
        }
        let values = self
            .sums
            .chunks_exact(self.passes)
            .zip(&self.samples)
            .flat_map(|(sums, &k)| sums.iter().map(move |&sum| sum / k.max(1) as f32))
            .collect();
        (values, self.camera_horizons)
    }
}

impl Accumulator {
    /// Empty sums for the `width` x `height` tile whose top-left pixel is `(x0, y0)`, with
    /// their squares when `squares` (adaptive sampling), and `first_hits` for its AOV passes.
    pub(super) fn new(
        x0: u32,
        y0: u32,
        (width, height): (u32, u32),
        squares: bool,
        first_hits: FirstHits,
    ) -> Self {
        let n = (width * height) as usize;
        Accumulator {
            x0,
            y0,
            tw: width,
            sums: vec![Vec3::ZERO; n],
            squares: if squares { vec![Vec3::ZERO; n] } else { Vec::new() },
            samples: vec![0; n],
            first_hits,
        }
    }

    /// The index of `cell`'s pixel in the tile.
    pub(super) fn at(&self, cell: &Cell) -> usize {
        ((cell.y - self.y0) * self.tw + (cell.x - self.x0)) as usize
    }

    /// Adds sample `li` to `cell`'s pixel; whether the pixel has converged.
    pub(super) fn add(&mut self, cell: &Cell, li: Vec3, stopping: Option<&Stopping>) -> bool {
        let at = self.at(cell);
        self.sums[at] += li;
        self.samples[at] += 1;
        let Some(stopping) = stopping else {
            return false;
        };
        self.squares[at] += li * li;
        stopping.converged(self.samples[at], self.sums[at], self.squares[at])
    }
}
