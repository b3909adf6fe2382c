//! `dormant bench instances`: Embree's top level of N instances of a few prototypes laid out as
//! one instance geometry per instance (what [`dormant::accel::embree::EmbreeAccel`] does)
//! against one instance array, each still (one time step), translating over the shutter or
//! translating and rotating (two time steps, quaternion decompositions). Per layout and motion:
//! the update (new transforms for every instance), the top-level commit and a trace of the
//! same rays at random shutter times: what the blurred top level's commit costs, and why.

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use super::timed;
use dormant::accel::embree::{lerps_as_matrices, shutter_poses};
use dormant::geometry::{primitives, InstanceMotion, RigidTransform, TriangleMesh};
use dormant::rng::SplitMix64;
use dormant::sequence::stats::median;
use dormant_embree::{
    BuildQuality, Device, EmbreeError, FrozenScene, InstanceArrayGeometry, InstanceGeometry, Scene,
    SceneFlags, ShutterPoses, TriangleGeometry,
};

pub struct InstancesBenchOptions {
    pub count: usize,
    pub rays: usize,
    /// Updates and commits per row (the median is reported); traces (the best is reported).
    pub runs: u32,
    pub threads: Option<usize>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InstanceLayout {
    /// One RTC_GEOMETRY_TYPE_INSTANCE per instance.
    Geometries,
    /// One RTC_GEOMETRY_TYPE_INSTANCE_ARRAY holding every instance.
    Array,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Motion {
    Still,
    Translating,
    Rotating,
}

#[derive(Clone, Debug, Serialize)]
pub struct InstancesRow {
    pub layout: InstanceLayout,
    pub motion: Motion,
    pub update_ms: f64,
    pub commit_ms: f64,
    pub trace_ms: f64,
    /// Rays that hit something (equal across layouts of one motion).
    pub hits: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct InstancesReport {
    pub instances: usize,
    pub prototypes: usize,
    pub rays: usize,
    pub runs: u32,
    pub rows: Vec<InstancesRow>,
}

/// Side of the cube the instances fill, in units.
const EXTENT: f32 = 30.0;

fn prototype_meshes() -> Vec<TriangleMesh> {
    vec![
        primitives::cuboid(Vec3::splat(0.4)),
        primitives::uv_sphere(0.4, 16, 8),
        primitives::cuboid(Vec3::new(0.15, 0.6, 0.25)),
        primitives::uv_sphere(0.25, 8, 4),
    ]
}

/// Instance `i`'s prototype and motion over the shutter at update `run` (every run moves
/// everything a little, so each commit has changes).
fn placement(i: usize, run: u32, motion: Motion, prototypes: usize) -> (u32, InstanceMotion) {
    let mut rng = SplitMix64::new(i as u64 * 7919 + 17);
    let p = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * EXTENT - Vec3::splat(EXTENT / 2.0);
    let open = RigidTransform { rotation: rng.rotation(), translation: p + Vec3::Y * (run as f32 * 0.01) };
    let spin = Quat::from_axis_angle(Vec3::new(rng.signed(), rng.signed(), 1.0).normalize(), 0.3);
    let close = match motion {
        Motion::Still => open,
        Motion::Translating => RigidTransform { translation: open.translation - Vec3::Y * 0.2, ..open },
        Motion::Rotating => RigidTransform {
            rotation: (spin * open.rotation).normalize(),
            translation: open.translation - Vec3::Y * 0.2,
        },
    };
    ((i % prototypes) as u32, InstanceMotion { open, close })
}

/// The top level in one layout: the scene and a way to give every instance new transforms.
struct TopLevel {
    scene: Scene,
    layout: InstanceLayout,
    motion: Motion,
    prototypes: Vec<Arc<FrozenScene>>,
    count: usize,
}

impl TopLevel {
    fn new(
        device: &Device,
        prototypes: &[Arc<FrozenScene>],
        layout: InstanceLayout,
        motion: Motion,
        count: usize,
    ) -> Result<Self, EmbreeError> {
        let flags = SceneFlags { dynamic: true, ..SceneFlags::default() };
        let mut scene = Scene::new(device, flags, BuildQuality::High)?;
        match layout {
            InstanceLayout::Geometries => {
                for i in 0..count {
                    let (p, _) = placement(i, 0, Motion::Still, prototypes.len());
                    let g = InstanceGeometry::new(device, &prototypes[p as usize], &Affine3A::IDENTITY)?;
                    scene.attach_by_id(g, i as u32)?;
                }
            }
            InstanceLayout::Array => {
                let array = InstanceArrayGeometry::new(device, prototypes, motion != Motion::Still)?;
                scene.attach_by_id(array, 0)?;
            }
        }
        Ok(Self { scene, layout, motion, prototypes: prototypes.to_vec(), count })
    }

    /// An array's motions as Embree takes them: matrices when every entry barely turns for
    /// its prototype's size ([`lerps_as_matrices`]), else rigid poses for all (an array holds
    /// one format).
    fn array_poses(&self, entries: &[(Option<u32>, InstanceMotion)]) -> Vec<(Option<u32>, ShutterPoses)> {
        let radius =
            |p: Option<u32>| p.and_then(|p| self.prototypes.get(p as usize)).map_or(0.0, |s| s.radius());
        let matrices = entries.iter().all(|&(p, ref m)| lerps_as_matrices(m, radius(p)));
        let poses = |m: &InstanceMotion| match matrices {
            true => ShutterPoses::Matrices([m.open.to_affine(), m.close.to_affine()]),
            false => ShutterPoses::Rigid([m.open, m.close].map(|t| (t.rotation, t.translation))),
        };
        entries.iter().map(|(p, m)| (*p, poses(m))).collect()
    }

    /// New transforms for every instance (update `run`).
    fn update(&mut self, run: u32) -> Result<(), EmbreeError> {
        let n = self.prototypes.len();
        let placements = (0..self.count).map(|i| placement(i, run, self.motion, n));
        match (self.layout, self.motion) {
            (InstanceLayout::Geometries, motion) => {
                for (i, (_, m)) in placements.enumerate() {
                    let g = self.scene.instance_mut(i as u32)?;
                    match motion {
                        Motion::Still => g.set_transform(&m.open.to_affine())?,
                        _ => {
                            let poses = shutter_poses(&m, g.child_radius());
                            g.set_motion(&poses)?
                        }
                    }
                }
            }
            (InstanceLayout::Array, Motion::Still) => {
                let entries: Vec<_> = placements.map(|(p, m)| (Some(p), m.open.to_affine())).collect();
                self.scene.instance_array_mut(0)?.set_still(&entries)?;
            }
            (InstanceLayout::Array, _) => {
                let entries: Vec<_> = placements.map(|(p, m)| (Some(p), m)).collect();
                let poses = self.array_poses(&entries);
                self.scene.instance_array_mut(0)?.set_moving(&poses)?;
            }
        }
        Ok(())
    }
}

/// Rays from a sphere around the cube towards points inside it, each at a random shutter time.
fn rays(count: usize) -> Vec<([f32; 3], [f32; 3], f32)> {
    let mut rng = SplitMix64::new(0x1257);
    (0..count)
        .map(|_| {
            let from = Vec3::new(rng.signed(), rng.signed(), rng.signed()).try_normalize().unwrap_or(Vec3::Z)
                * EXTENT
                * 1.5;
            let to = Vec3::new(rng.signed(), rng.signed(), rng.signed()) * (EXTENT / 2.0);
            (from.to_array(), (to - from).normalize().to_array(), rng.unit())
        })
        .collect()
}

fn measure(
    top: &mut TopLevel,
    rays: &[([f32; 3], [f32; 3], f32)],
    runs: u32,
) -> Result<InstancesRow, EmbreeError> {
    let (mut updates, mut commits, mut traces, mut hits) = (Vec::new(), Vec::new(), Vec::new(), 0);
    for run in 0..runs.max(1) {
        let (r, update_ms) = timed(|| top.update(run + 1));
        r?;
        let (r, commit_ms) = timed(|| top.scene.commit());
        r?;
        let view = top.scene.view().expect("committed");
        let (h, trace_ms) = timed(|| {
            rays.par_iter()
                .filter(|(o, d, time)| view.intersect1_at(*o, *d, 0.0, f32::INFINITY, *time).is_some())
                .count()
        });
        hits = h;
        updates.push(update_ms);
        commits.push(commit_ms);
        traces.push(trace_ms);
    }
    Ok(InstancesRow {
        layout: top.layout,
        motion: top.motion,
        update_ms: median(updates),
        commit_ms: median(commits),
        trace_ms: traces.into_iter().fold(f64::INFINITY, f64::min),
        hits,
    })
}

pub fn bench_instances(options: &InstancesBenchOptions) -> Result<InstancesReport, EmbreeError> {
    let device = Device::new(options.threads)?;
    let mut prototypes = Vec::new();
    for mesh in prototype_meshes() {
        let mut scene = Scene::new(&device, SceneFlags::default(), BuildQuality::High)?;
        scene.attach(TriangleGeometry::with_quality(
            &device,
            &mesh.positions,
            &mesh.indices,
            BuildQuality::High,
        )?)?;
        prototypes.push(scene.freeze()?);
    }
    let rays = rays(options.rays);
    let mut rows = Vec::new();
    for motion in [Motion::Still, Motion::Translating, Motion::Rotating] {
        for layout in [InstanceLayout::Geometries, InstanceLayout::Array] {
            let mut top = TopLevel::new(&device, &prototypes, layout, motion, options.count)?;
            rows.push(measure(&mut top, &rays, options.runs)?);
        }
    }
    Ok(InstancesReport {
        instances: options.count,
        prototypes: prototypes.len(),
        rays: rays.len(),
        runs: options.runs,
        rows,
    })
}
