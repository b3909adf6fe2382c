//! The spawn schedule: when and where each dynamic object enters the world. Structures'
//! bodies come first, asleep before the first frame; then spawners' waves and projectiles'
//! launches by frame. The whole schedule is computed up front from the scene and its seeds,
//! so it is identical on every run.

use glam::{Quat, Vec3};

use super::body::BodyPose;
use super::colliders::PrototypeShape;
use crate::rng::SplitMix64;
use crate::scene::file::{SceneFile, SpawnPattern, SpawnerDef, StructureDef};

/// One object to create at the start of `frame`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SpawnOrder {
    pub frame: u32,
    pub prototype: u32,
    pub pose: BodyPose,
    pub(crate) velocity: Vec3,
    /// The structure copy (numbered over all structures) the body belongs to: it enters the
    /// world asleep.
    pub structure: Option<u32>,
}

/// Every object's order, sorted by frame (stable: structures copy by copy, then spawners in
/// order, wave by wave, then projectiles in order, launch by launch).
pub(crate) fn spawn_schedule(file: &SceneFile, shapes: &[PrototypeShape]) -> Vec<SpawnOrder> {
    let d = file.spec();
    let mut orders = structure_orders(&d.structures);
    for s in &d.spawners {
        let seed = d.scene.seed ^ s.seed.wrapping_mul(0xA076_1D64_78BD_642F);
        let mut rng = SplitMix64::new(seed);
        spawner_orders(s, shapes, d.physics.timestep, &mut rng, &mut orders);
    }
    for p in &d.projectiles {
        orders.extend(p.launches(&d.structures, d.scene.frames).into_iter().map(|launch| SpawnOrder {
            frame: launch.frame,
            prototype: p.prototype as u32,
            pose: BodyPose { translation: launch.translation, rotation: launch.rotation },
            velocity: launch.velocity,
            structure: None,
        }));
    }
    orders.sort_by_key(|o| o.frame);
    orders
}

/// Every structure's blocks at frame 0, asleep; copies are numbered over all structures.
fn structure_orders(structures: &[StructureDef]) -> Vec<SpawnOrder> {
    let mut orders = Vec::new();
    let mut first_copy = 0;
    for s in structures {
        orders.extend(s.blocks().into_iter().map(|block| SpawnOrder {
            frame: 0,
            prototype: s.prototype as u32,
            pose: BodyPose { translation: block.translation, rotation: block.rotation },
            velocity: Vec3::ZERO,
            structure: Some(first_copy + block.copy),
        }));
        first_copy += s.copies();
    }
    orders
}

fn spawner_orders(
    s: &SpawnerDef,
    shapes: &[PrototypeShape],
    timestep: f32,
    rng: &mut SplitMix64,
    out: &mut Vec<SpawnOrder>,
) {
    let protos = &s.prototypes;
    let radius = protos.iter().map(|&p| shapes[p].bounding_radius).fold(0.0f32, f32::max);
    // Grid cells hold any of the spawner's prototypes in any orientation with a small gap.
    let cell = 2.0 * radius * 1.05 + s.position_jitter * 2.0;
    let (lo, hi) = (Vec3::from_array(s.region.min), Vec3::from_array(s.region.max));
    let size = hi - lo;
    let nx = ((size.x / cell).floor() as u32).max(1);
    let nz = ((size.z / cell).floor() as u32).max(1);
    let per_wave_base = s.count / s.waves;
    let extra = s.count % s.waves;
    for wave in 0..s.waves {
        let n = per_wave_base + u32::from(wave < extra);
        let time = s.start_time + wave as f32 * s.wave_interval;
        let frame = (time / timestep).round() as u32;
        for k in 0..n {
            let position = match s.pattern {
                SpawnPattern::Grid => {
                    let (layer, rest) = (k / (nx * nz), k % (nx * nz));
                    let (ix, iz) = (rest % nx, rest / nx);
                    let centre = |lo: f32, size: f32, count: u32, i: u32| {
                        lo + 0.5 * (size - (count - 1) as f32 * cell) + i as f32 * cell
                    };
                    let mut p = Vec3::new(
                        centre(lo.x, size.x, nx, ix),
                        lo.y + radius + layer as f32 * cell,
                        centre(lo.z, size.z, nz, iz),
                    );
                    if s.position_jitter > 0.0 {
                        p += Vec3::new(rng.signed(), rng.signed(), rng.signed()) * s.position_jitter;
                    }
                    p
                }
                SpawnPattern::Random => lo + Vec3::new(rng.unit(), rng.unit(), rng.unit()) * size,
            };
            let prototype = protos[rng.below(protos.len())] as u32;
            let rotation = if s.random_rotation { rng.rotation() } else { Quat::IDENTITY };
            let velocity = Vec3::from_array(s.initial_velocity)
                + Vec3::new(rng.signed(), rng.signed(), rng.signed()) * s.velocity_jitter;
            out.push(SpawnOrder {
                frame,
                prototype,
                pose: BodyPose { translation: position, rotation },
                velocity,
                structure: None,
            });
        }
    }
}
