use clap::Args;

use super::{CliError, JsonOutput, SceneSource};
use crate::accel::{self, Backend};
use crate::crosscheck::{self, Tolerance, VerifyReport};
use crate::render::RenderScene;

#[derive(Debug, Args)]
pub struct VerifyArgs {
    #[command(flatten)]
    pub scene: SceneSource,
    /// Camera rays: one per pixel of an image of this size.
    #[arg(long, value_name = "WxH", default_value = "320x180")]
    pub size: super::render::Size,
    /// Random rays leaving random points on the scene's surfaces.
    #[arg(long, value_name = "N", default_value_t = 100_000)]
    pub surface_rays: usize,
    /// Seed for the surface rays.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub json: JsonOutput,
}

pub(super) fn run(args: &VerifyArgs, threads: Option<usize>, quiet: bool) -> Result<(), CliError> {
    for b in [Backend::Embree, Backend::Bvh] {
        if !b.is_compiled() {
            return Err(CliError::Input(format!(
                "verify compares Embree with the BVH, but {b} is not compiled in"
            )));
        }
    }
    let desc = args.scene.load()?;
    let runtime = |e: &dyn std::fmt::Display| CliError::Runtime(e.to_string());
    let mut reference = accel::create(Backend::Embree, threads).map_err(|e| runtime(&e))?;
    let mut candidate = accel::create(Backend::Bvh, threads).map_err(|e| runtime(&e))?;
    RenderScene::build(&desc, reference.as_mut()).map_err(|e| runtime(&e))?;
    RenderScene::build(&desc, candidate.as_mut()).map_err(|e| runtime(&e))?;
    let (a, b) = (reference.query().map_err(|e| runtime(&e))?, candidate.query().map_err(|e| runtime(&e))?);

    let tolerance = Tolerance::default();
    let camera = crosscheck::camera_rays(&desc, args.size.width, args.size.height);
    let surface = crosscheck::surface_rays(&desc, args.surface_rays, args.seed);
    let mut report = VerifyReport::default();
    report.merge(crosscheck::compare(a, b, &camera, &tolerance));
    report.merge(crosscheck::compare(a, b, &surface, &tolerance));

    let json = serde_json::json!({
        "scene": desc.name,
        "reference": Backend::Embree,
        "candidate": Backend::Bvh,
        "camera_rays": camera.len(),
        "surface_rays": surface.len(),
        "tolerance": tolerance,
        "rays": report.rays,
        "hits": report.hits,
        "misses": report.misses,
        "mismatches": report.mismatches,
        "ties": report.ties,
        "precision_ties": report.precision_ties,
        "max_precision_err": report.max_precision_err,
        "max_t_rel_err": report.max_t_rel_err,
        "examples": report.examples,
    });
    args.json.emit(&json)?;
    if !quiet && !args.json.is_requested() {
        println!(
            "verify {}: {} rays ({} camera, {} surface): {} hits, {} misses, {} ties, {} precision ties, {} mismatches, max t rel err {:.2e}",
            desc.name,
            report.rays,
            camera.len(),
            surface.len(),
            report.hits,
            report.misses,
            report.ties,
            report.precision_ties,
            report.mismatches,
            report.max_t_rel_err
        );
    }
    if report.mismatches > 0 {
        return Err(CliError::Runtime(format!(
            "{} of {} rays differ between Embree and the BVH (see the JSON report's examples)",
            report.mismatches, report.rays
        )));
    }
    Ok(())
}
