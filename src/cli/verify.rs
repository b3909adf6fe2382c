use std::path::PathBuf;

use clap::Args;

use super::{CliError, JsonOutput, SceneSource};
use dormant::accel::LoadedObjectMap;
use dormant::accel::{self, AccelError, Accelerator, Backend};
use dormant::geometry::InstanceMotion;
use dormant::physics::SimulateOptions;
use dormant::scene::file::SceneFile;
use dormant::scene::SceneDescription;
use dormant::sequence::{FrameRange, SequenceError, SequenceSource};
use dormant_lab::crosscheck::{self, MappedQuery, VerifyReport, BOUND};

#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// Scene file to simulate; several of its frames are checked (default: the built-in
    /// scene, or --env/--object).
    #[arg(value_name = "SCENE", conflicts_with_all = ["env", "object"])]
    pub scene_file: Option<PathBuf>,
    /// With SCENE: frames to simulate (default: the scene's own count).
    #[arg(long, value_name = "N")]
    pub frame_count: Option<u32>,
    /// With SCENE: how many frames, evenly spaced and ending with the last, to check.
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub check_frames: u32,
    /// With a glTF file as SCENE: frames per second to sample its animation at (files from
    /// dormant's export record it; Blender's do not).
    #[arg(long, value_name = "FPS", requires = "scene_file")]
    pub fps: Option<f64>,
    /// With SCENE: directory that relative asset paths in the scene file resolve against
    /// (default: the scene file's own directory).
    #[arg(long, value_name = "DIR", requires = "scene_file")]
    pub assets: Option<PathBuf>,
    #[command(flatten)]
    pub scene: SceneSource,
    /// Camera rays: one per pixel of an image of this size.
    #[arg(long, value_name = "WxH", default_value = "320x180")]
    pub size: dormant::render::ImageSize,
    /// Random rays leaving random points on the scene's surfaces.
    #[arg(long, value_name = "N", default_value_t = 100_000)]
    pub surface_rays: usize,
    /// Shadow-ray segments between two random surface points, ending short of the second:
    /// occlusion queries over a finite interval.
    #[arg(long, value_name = "N", default_value_t = 20_000)]
    pub shadow_rays: usize,
    /// With SCENE: motion blur. Bodies moving within a shutter of this fraction of the frame
    /// interval (0 to 1, centred on each checked frame) become motion instances on both
    /// backends, and every ray gets a random time in the shutter (default: the scene's
    /// render.shutter, else 0).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub shutter: Option<f32>,
    /// Seeds the random surface and shadow rays (and their times): checks with different
    /// offsets trace different rays.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed_offset: u64,
}

pub(super) fn run(
    args: &VerifyArgs,
    threads: Option<usize>,
    quiet: bool,
    json_out: &JsonOutput,
) -> Result<(), CliError> {
    check_input(args)?;
    let (descs, frames, shutter) = match &args.scene_file {
        Some(path) => simulated_frames(path, args, quiet)?,
        None => (vec![(args.scene.load()?, Vec::new())], Vec::new(), 0.0),
    };
    let mut report = VerifyReport::default();
    let mut counts = [0; 3];
    for (i, frame) in descs.iter().enumerate() {
        let (r, n) = check_frame(frame, args, shutter, args.seed_offset.wrapping_add(i as u64), threads)?;
        report.merge(r);
        counts = [counts[0] + n[0], counts[1] + n[1], counts[2] + n[2]];
    }
    let desc = &descs[0].0;
    let json = report_json(&desc.name, &frames, shutter, counts, &report);
    json_out.emit(&json)?;
    if !quiet && !json_out.is_requested() {
        println!("{}", summary(&desc.name, counts, &report));
    }
    if report.mismatches > 0 {
        return Err(CliError::Runtime(format!(
            "{} of {} rays differ between Embree and the BVH (see the JSON report's examples)",
            report.mismatches, report.rays
        )));
    }
    Ok(())
}

/// The `--json` report: the rays checked by kind and the verdicts.
fn report_json(
    scene: &str,
    frames: &[u32],
    shutter: f32,
    counts: [usize; 3],
    report: &VerifyReport,
) -> serde_json::Value {
    let [camera_rays, surface_rays, shadow_rays] = counts;
    serde_json::json!({
        "scene": scene,
        "reference": Backend::Embree,
        "candidate": Backend::Bvh,
        "frames": frames,
        "shutter": shutter,
        "camera_rays": camera_rays,
        "surface_rays": surface_rays,
        "shadow_rays": shadow_rays,
        "bound": BOUND,
        "rays": report.rays,
        "hits": report.hits,
        "misses": report.misses,
        "mismatches": report.mismatches,
        "ties": report.ties,
        "closest": report.closest,
        "occlusion": report.occlusion,
        "max_t_err_over_bound": report.max_t_err_over_bound,
        "max_t_rel_err": report.max_t_rel_err,
        "examples": report.examples,
    })
}

/// The line printed after a check.
fn summary(scene: &str, counts: [usize; 3], report: &VerifyReport) -> String {
    let [camera_rays, surface_rays, shadow_rays] = counts;
    format!(
        "verify {}: {} rays ({} camera, {} surface, {} shadow): {} hits, {} misses, {} ties, {} mismatches, max t error {:.2} of the bound",
        scene,
        report.rays,
        camera_rays,
        surface_rays,
        shadow_rays,
        report.hits,
        report.misses,
        report.ties,
        report.mismatches,
        report.max_t_err_over_bound
    )
}

/// Loads a checked frame into Embree and the BVH (its moving bodies as motion instances) and
/// compares them on its camera, surface and shadow rays, each with a random time in the
/// shutter when there is one; returns the report and the three ray counts.
fn check_frame(
    (desc, motions): &CheckedFrame,
    args: &VerifyArgs,
    shutter: f32,
    seed: u64,
    threads: Option<usize>,
) -> Result<(VerifyReport, [usize; 3]), CliError> {
    let runtime = |e: &dyn std::fmt::Display| CliError::Runtime(e.to_string());
    let (reference, reference_map) =
        load_frame(Backend::Embree, threads, desc, motions).map_err(|e| runtime(&e))?;
    let (candidate, candidate_map) =
        load_frame(Backend::Bvh, threads, desc, motions).map_err(|e| runtime(&e))?;
    let a = MappedQuery { query: reference.query().map_err(|e| runtime(&e))?, objects: &reference_map };
    let b = MappedQuery { query: candidate.query().map_err(|e| runtime(&e))?, objects: &candidate_map };
    let timed = |rays, seed| if shutter > 0.0 { crosscheck::with_random_times(rays, seed) } else { rays };
    let rays = [
        timed(crosscheck::camera_rays(desc, args.size.width, args.size.height), seed.rotate_left(29)),
        timed(crosscheck::surface_rays(desc, args.surface_rays, seed), seed.rotate_left(17)),
        timed(crosscheck::shadow_rays(desc, args.shadow_rays, !seed), seed.rotate_left(41)),
    ];
    let mut report = VerifyReport::default();
    for r in &rays {
        report.merge(crosscheck::compare(desc, a, b, r));
    }
    Ok((report, rays.map(|r| r.len())))
}

/// A shutter from 0 to 1 (checked first: a bad flag is reported in every build), and both
/// backends compiled in.
fn check_input(args: &VerifyArgs) -> Result<(), CliError> {
    super::render::check_shutter(args.shutter)?;
    for b in [Backend::Embree, Backend::Bvh] {
        if !b.is_compiled() {
            return Err(CliError::Input(format!(
                "verify compares Embree with the BVH, but {b} is not compiled in"
            )));
        }
    }
    Ok(())
}

/// A checked frame: its description, and the motion over the shutter of the bodies (by
/// position in `bodies`) that move within it.
type CheckedFrame = (SceneDescription, Vec<(usize, InstanceMotion)>);

/// `desc` in a new accelerator of `backend`, its moving bodies motion instances, committed,
/// with the map from its hit ids to the scene's objects.
fn load_frame(
    backend: Backend,
    threads: Option<usize>,
    desc: &SceneDescription,
    motions: &[(usize, InstanceMotion)],
) -> Result<(Box<dyn Accelerator>, LoadedObjectMap), AccelError> {
    let mut accel = accel::create(backend, threads)?;
    let loaded = accel::load_scene(desc, accel.as_mut())?;
    for &(body, motion) in motions {
        accel.set_instance_motion(loaded.instances[body], Some(motion))?;
    }
    accel.commit()?;
    let mut map = LoadedObjectMap::new(desc, &loaded);
    for &(body, motion) in motions {
        map.set_motion(loaded.instances[body], Some(motion));
    }
    Ok((accel, map))
}

/// Simulates the scene file and describes `check_frames` frames of it, evenly spaced and
/// ending with the last, with their motion over the shutter; returns them with their frame
/// numbers and the shutter.
fn simulated_frames(
    path: &std::path::Path,
    args: &VerifyArgs,
    quiet: bool,
) -> Result<(Vec<CheckedFrame>, Vec<u32>, f32), CliError> {
    let file = SceneFile::load_with_fps(path, args.assets.as_deref(), args.fps)
        .map_err(|e| CliError::Input(e.to_string()))?;
    let options = SimulateOptions { count: args.scene.count, frames: args.frame_count };
    let sequence = super::render::load_sequence(SequenceSource::scene(file, options, None), quiet)?;
    let shutter = args.shutter.or(sequence.render.shutter).unwrap_or(0.0);
    let whole = FrameRange { start: 0, end: sequence.frame_count() };
    let selection = sequence.evenly_spaced_in(whole, args.check_frames);
    let mut descs = Vec::new();
    sequence.replay(&selection, &mut [], &mut |frame, _| {
        // `describe_frame` lists the present bodies in ascending order.
        let present: Vec<usize> = frame.present_bodies().map(|b| b.0 as usize).collect();
        let motions = frame
            .shutter_motions(shutter)
            .into_iter()
            .filter_map(|(b, m)| Some((present.binary_search(&b).ok()?, m)))
            .collect();
        descs.push((sequence.describe_frame(frame), motions));
        Ok::<(), SequenceError>(())
    })?;
    Ok((descs, selection.frames(), shutter))
}
