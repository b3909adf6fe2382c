//! A camera-ray block: its pixels ([`Cells`], each a [`Cell`] with its sampler and sample
//! budget) and the packet of their camera rays at one sample index ([`CameraPacket`]).

use glam::Vec3;

use super::BLOCK_PIXELS;
use crate::accel::Hit;
use crate::geometry::Ray;
use crate::render::PixelSampler;

/// The pixels of one camera-ray block (at most [`BLOCK_PIXELS`]).
pub(super) struct Cells {
    pub cells: [Cell; BLOCK_PIXELS],
    pub len: usize,
}

/// A pixel of a camera-ray block: its coordinates, sampler, the most samples it may get, and
/// whether its paths are traced (a pixel reused from earlier frames only takes its place in
/// the camera packets, for each of its samples up to its stored count).
#[derive(Clone, Copy)]
pub(super) struct Cell {
    pub x: u32,
    pub y: u32,
    /// Row-major index of the pixel in the image.
    pub pixel: u32,
    pub sampler: PixelSampler,
    pub budget: u32,
    pub traced: bool,
}

/// One camera packet of a block: which cells sample at the current index (`slots`, the first
/// `len`), their rays and hits.
pub(super) struct CameraPacket {
    pub slots: [usize; BLOCK_PIXELS],
    pub len: usize,
    pub rays: [Ray; BLOCK_PIXELS],
    pub hits: [Option<Hit>; BLOCK_PIXELS],
}

impl CameraPacket {
    pub(super) fn new() -> Self {
        Self {
            slots: [0; BLOCK_PIXELS],
            len: 0,
            rays: [Ray::new(Vec3::ZERO, Vec3::Z); BLOCK_PIXELS],
            hits: [None; BLOCK_PIXELS],
        }
    }

    /// Takes the cells of `block` that still sample at index `i` (within their budget, not
    /// converged); whether there is any.
    pub(super) fn select(&mut self, block: &[Cell], i: u32, done: &[bool; BLOCK_PIXELS]) -> bool {
        self.len = 0;
        for (c, cell) in block.iter().enumerate() {
            if i < cell.budget && !done[c] {
                self.slots[self.len] = c;
                self.len += 1;
            }
        }
        self.len > 0
    }

    pub(super) fn slots(&self) -> &[usize] {
        &self.slots[..self.len]
    }
}
