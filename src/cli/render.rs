use std::path::PathBuf;

use clap::Args;

use super::CliError;
use crate::accel::{self, Backend};
use crate::render::{
    self, AmbientOcclusion, DirectLighting, Integrator, PathTracer, RenderScene, RenderSettings,
};

/// Image size as `WIDTHxHEIGHT`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

impl std::str::FromStr for Size {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parse = |v: &str| v.trim().parse::<u32>().ok().filter(|&n| (1..=16384).contains(&n));
        match s.split_once(['x', 'X']) {
            Some((w, h)) => match (parse(w), parse(h)) {
                (Some(width), Some(height)) => Ok(Size { width, height }),
                _ => Err(format!("'{s}': width and height must be whole numbers from 1 to 16384")),
            },
            None => Err(format!("'{s}': expected WIDTHxHEIGHT, e.g. 1280x720")),
        }
    }
}

/// What a render computes per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RenderMode {
    /// Path tracing: sun, sky and indirect light, MIS, GGX metallic-roughness.
    Path,
    /// Direct light only (sun and sky with shadows): the quick preview.
    Shaded,
    /// Ambient occlusion within one scene unit.
    Ao,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: super::SceneSource,
    /// Output directory; frames are written as frame_NNNN.png.
    #[arg(long, value_name = "DIR", default_value = "out/render")]
    pub out: PathBuf,
    /// Image size.
    #[arg(long, value_name = "WxH", default_value = "960x540")]
    pub size: Size,
    /// Samples per pixel.
    #[arg(long, value_name = "N", default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub spp: u32,
    /// Rendering mode: path tracing, direct light only, or ambient occlusion.
    #[arg(long, value_enum, default_value_t = RenderMode::Path)]
    pub mode: RenderMode,
    /// Longest path (bounces) in `path` mode.
    #[arg(long, value_name = "N", default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub max_depth: u32,
    /// Ray tracing backend (default: the first compiled in, Embree preferred).
    #[arg(long)]
    pub backend: Option<Backend>,
    /// Also write linear HDR radiance as frame_NNNN.exr.
    #[arg(long)]
    pub exr: bool,
    #[command(flatten)]
    pub json: super::JsonOutput,
    /// Exposure multiplier applied before tone mapping.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
}

pub(super) fn run(args: &RenderArgs, threads: Option<usize>, quiet: bool) -> Result<(), CliError> {
    let backend = match args.backend {
        Some(b) if !b.is_compiled() => {
            return Err(CliError::Input(format!("backend '{b}' is not compiled into this build")));
        }
        Some(b) => b,
        None => *Backend::compiled().first().ok_or_else(|| {
            CliError::Input(
                "no ray tracing backend is compiled in: Embree is not compiled in (build with the default \
                 feature `embree`)"
                    .into(),
            )
        })?,
    };
    if !args.exposure.is_finite() || args.exposure <= 0.0 {
        return Err(CliError::Input(format!("--exposure {}: must be a positive number", args.exposure)));
    }
    std::fs::create_dir_all(&args.out).map_err(|e| {
        CliError::Runtime(format!("cannot create output directory {}: {e}", args.out.display()))
    })?;

    let description = args.scene.load()?;
    let mut accel = accel::create(backend, threads).map_err(|e| CliError::Runtime(e.to_string()))?;
    let render_scene =
        RenderScene::build(&description, accel.as_mut()).map_err(|e| CliError::Runtime(e.to_string()))?;
    let query = accel.query().map_err(|e| CliError::Runtime(e.to_string()))?;
    let settings =
        RenderSettings { width: args.size.width, height: args.size.height, spp: args.spp, frame: 0 };
    let path_tracer = PathTracer { max_depth: args.max_depth, ..PathTracer::default() };
    let integrator: &dyn Integrator = match args.mode {
        RenderMode::Path => &path_tracer,
        RenderMode::Shaded => &DirectLighting,
        RenderMode::Ao => &AmbientOcclusion { radius: 1.0 },
    };
    let (film, stats) = render::render_frame(&render_scene, query, integrator, &settings)
        .map_err(|e| CliError::Runtime(e.to_string()))?;
    let path = args.out.join("frame_0000.png");
    render::write_png_atomic(&film, args.exposure, &path).map_err(|e| CliError::Runtime(e.to_string()))?;
    if args.exr {
        render::write_exr_atomic(&film, &path.with_extension("exr"))
            .map_err(|e| CliError::Runtime(e.to_string()))?;
    }

    if args.json.is_requested() {
        let report = serde_json::json!({
            "scene": render_scene.name,
            "backend": backend,
            "width": settings.width,
            "height": settings.height,
            "spp": settings.spp,
            "mode": args.mode,
            "frames": [{ "path": path, "rays": stats.rays, "seconds": stats.seconds,
                         "mrays_per_second": stats.mrays_per_second() }],
        });
        args.json.emit(&report)?;
    } else if !quiet {
        println!(
            "rendered {} ({}x{}, {} spp, {:?} mode, {backend}): {:.2} s, {} rays, {:.1} Mrays/s",
            path.display(),
            settings.width,
            settings.height,
            settings.spp,
            args.mode,
            stats.seconds,
            stats.rays,
            stats.mrays_per_second()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::Size;

    #[test]
    fn size_parses_and_rejects() {
        assert_eq!("640x360".parse::<Size>(), Ok(Size { width: 640, height: 360 }));
        assert!("640".parse::<Size>().is_err());
        assert!("0x10".parse::<Size>().is_err());
        assert!("axb".parse::<Size>().is_err());
        assert!("20000x10".parse::<Size>().is_err());
    }
}
