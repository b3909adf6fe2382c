//! What `[[structures]]` and `[[projectiles]]` put into the world, as plain geometry from the
//! checked spec: the blocks of one copy in its own frame, where each copy stands, every
//! block in world space, and when and where each projectile is launched. Physics spawns
//! bodies from these; validation uses a copy's footprint to keep copies apart.

use std::f32::consts::FRAC_PI_2;

use glam::{Affine3A, Quat, Vec3};

use super::spec::{ProjectileAim, ProjectileDef, StructureDef, StructureLayout};
use crate::geometry::Aabb;

/// One body of a structure in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StructureBlock {
    /// Which copy of the structure it belongs to (array order: X fastest, then Z).
    pub copy: u32,
    pub translation: Vec3,
    pub rotation: Quat,
}

/// One projectile body: the frame it enters the world, its pose and its velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Launch {
    pub frame: u32,
    pub translation: Vec3,
    pub rotation: Quat,
    pub(crate) velocity: Vec3,
}

/// The extent of one copy in its own frame, over X and Z (for spacing copies apart).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footprint {
    pub min: [f32; 2],
    pub max: [f32; 2],
}

impl Footprint {
    /// Width along X and depth along Z.
    pub fn size(&self) -> [f32; 2] {
        [self.max[0] - self.min[0], self.max[1] - self.min[1]]
    }
}

impl StructureLayout {
    /// Blocks in one copy.
    pub fn blocks_per_copy(&self) -> u64 {
        match *self {
            StructureLayout::Tower { layers, per_layer } | StructureLayout::Wall { layers, per_layer } => {
                layers as u64 * per_layer as u64
            }
            StructureLayout::Dominoes { count, .. } => count as u64,
            StructureLayout::Grid { counts } => counts.iter().map(|&c| c as u64).product(),
        }
    }
}

impl StructureDef {
    /// Copies in the array.
    pub fn copies(&self) -> u32 {
        self.array.counts[0] * self.array.counts[1]
    }

    /// Every body of every copy.
    pub fn body_count(&self) -> u64 {
        self.copies() as u64 * self.layout.blocks_per_copy()
    }

    /// One copy's blocks in its own frame: centre and heading (radians about +Y), bottom
    /// layer first.
    pub fn local_blocks(&self) -> Vec<(Vec3, f32)> {
        let h = Vec3::from_array(self.half_extents);
        let g = self.gap;
        // Centres of `n` blocks of size `size` in a row centred on 0, `g` apart.
        let row = |n: u32, size: f32, j: u32| (j as f32 - (n as f32 - 1.0) * 0.5) * (size + g);
        let height = |k: u32| h.y + k as f32 * (2.0 * h.y + g);
        let mut blocks = Vec::with_capacity(self.layout.blocks_per_copy() as usize);
        match self.layout {
            StructureLayout::Tower { layers, per_layer } => {
                for k in 0..layers {
                    for j in 0..per_layer {
                        let across = row(per_layer, 2.0 * h.z, j);
                        blocks.push(if k % 2 == 0 {
                            (Vec3::new(0.0, height(k), across), 0.0)
                        } else {
                            (Vec3::new(across, height(k), 0.0), FRAC_PI_2)
                        });
                    }
                }
            }
            StructureLayout::Wall { layers, per_layer } => {
                for k in 0..layers {
                    // Running bond: courses shifted a quarter block either way.
                    let shift = if k % 2 == 0 { -0.25 } else { 0.25 } * (2.0 * h.x + g);
                    for j in 0..per_layer {
                        blocks.push((Vec3::new(row(per_layer, 2.0 * h.x, j) + shift, height(k), 0.0), 0.0));
                    }
                }
            }
            StructureLayout::Dominoes { count, spacing } => {
                blocks.extend((0..count).map(|j| (Vec3::new(0.0, h.y, j as f32 * spacing), 0.0)));
            }
            StructureLayout::Grid { counts: [nx, ny, nz] } => {
                for y in 0..ny {
                    for z in 0..nz {
                        for x in 0..nx {
                            let centre = Vec3::new(row(nx, 2.0 * h.x, x), height(y), row(nz, 2.0 * h.z, z));
                            blocks.push((centre, 0.0));
                        }
                    }
                }
            }
        }
        blocks
    }

    /// The box one copy fills in its own frame.
    pub(crate) fn local_bounds(&self) -> Aabb {
        let h = Vec3::from_array(self.half_extents);
        self.local_blocks().into_iter().fold(Aabb::EMPTY, |bounds, (centre, yaw)| {
            let (s, c) = (yaw.sin().abs(), yaw.cos().abs());
            let half = Vec3::new(c * h.x + s * h.z, h.y, s * h.x + c * h.z);
            bounds.union(Aabb { min: centre - half, max: centre + half })
        })
    }

    /// The extent of one copy over X and Z in its own frame.
    pub fn footprint(&self) -> Footprint {
        let b = self.local_bounds();
        Footprint { min: [b.min.x, b.min.z], max: [b.max.x, b.max.z] }
    }

    /// The world-space box around copy `copy`.
    pub(crate) fn copy_bounds(&self, copy: u32) -> Aabb {
        let (anchor, rotation) = self.copy_placement(copy);
        self.local_bounds().transformed(&Affine3A::from_rotation_translation(rotation, anchor))
    }

    /// Where copy `copy` stands: its anchor in world space and its heading.
    pub fn copy_placement(&self, copy: u32) -> (Vec3, Quat) {
        let [nx, _] = self.array.counts;
        let (ix, iz) = (copy % nx, copy / nx);
        let rotation = Quat::from_rotation_y(self.yaw_degrees.to_radians());
        let offset = Vec3::new(ix as f32 * self.array.spacing[0], 0.0, iz as f32 * self.array.spacing[1]);
        (Vec3::from_array(self.origin) + rotation * offset, rotation)
    }

    /// Every block of every copy in world space, copy by copy.
    pub(crate) fn blocks(&self) -> Vec<StructureBlock> {
        let local = self.local_blocks();
        let mut blocks = Vec::with_capacity(local.len() * self.copies() as usize);
        for copy in 0..self.copies() {
            let (anchor, heading) = self.copy_placement(copy);
            blocks.extend(local.iter().map(|&(centre, yaw)| StructureBlock {
                copy,
                translation: anchor + heading * centre,
                rotation: heading * Quat::from_rotation_y(yaw),
            }));
        }
        blocks
    }
}

impl ProjectileDef {
    /// Every launch before frame `frames` (the run's length), in launch order.
    pub fn launches(&self, structures: &[StructureDef], frames: u32) -> Vec<Launch> {
        let position = Vec3::from_array(self.position);
        let velocity = Vec3::from_array(self.velocity);
        // Each launch's frame: world space moved on by the step, or an aimed-at copy's frame.
        let placements: Vec<(Vec3, Quat)> = match self.aim {
            ProjectileAim::World { count, step } => {
                (0..count).map(|i| (i as f32 * Vec3::from_array(step), Quat::IDENTITY)).collect()
            }
            ProjectileAim::Structure { structure, every, count } => {
                let s = &structures[structure];
                (0..s.copies())
                    .step_by(every as usize)
                    .take(count.map_or(usize::MAX, |c| c as usize))
                    .map(|copy| s.copy_placement(copy))
                    .collect()
            }
        };
        placements
            .into_iter()
            .enumerate()
            .map(|(i, (anchor, rotation))| Launch {
                frame: self.frame.saturating_add((i as u32).saturating_mul(self.interval_frames)),
                translation: anchor + rotation * position,
                rotation,
                velocity: rotation * velocity,
            })
            .take_while(|launch| launch.frame < frames)
            .collect()
    }
}
