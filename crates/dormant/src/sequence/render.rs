//! The sequence's rendering methods: the per-frame call into the renderer (a scene manager
//! brought to a frame, its committed scene rendered with the run's integrator and AOVs, the
//! trace time reported back to the manager's cost model), the render loop over a run's frames
//! with static-frame reuse, and frames kept from an earlier run brought through the manager.
//! Exact temporal reuse is `crate::render::reuse`'s; this file asks it whether it applies,
//! hands it the run's facts ([`RunMotion`]) and calls it once per frame.

use super::{FrameRenderer, FrameSelection, KeptFrame, ReuseMode, Sequence, SequenceError};
use crate::physics::trajectory::ReplayFrame;
use crate::render::reuse::{ExactFrame, ExactReuse, FullFrame, RunMotion};
use crate::render::{
    render_with_aovs, Aov, Emitters, Film, FrameTracer, PinholeCamera, RenderError, RenderScene, RenderStats,
};
use crate::residency::{FrameStats, IntegrationForm, SceneManager, TraceKind};

/// Camera rays (one per pixel of this image) of the manager's trace-penalty probes: enough
/// rays for a stable time, few enough to cost a few ms.
const PROBE_SIZE: (u32, u32) = (128, 72);

/// One frame of a sequence: rendered, or (static-frame reuse) the same image as an earlier
/// one; the manager keeps the statistics of the last frame it prepared.
pub struct RenderedFrame {
    pub index: u32,
    /// The image; empty (0x0, no AOVs) when it is the image of a frame kept from an earlier
    /// run (`reused_from` names it; its files hold the image).
    pub film: Film,
    pub render: RenderStats,
    /// The requested AOV passes, in request order.
    pub aovs: Vec<(Aov, Film)>,
    /// `Some(f)`: nothing visible changed since frame `f`, whose image (and AOVs) this is; no
    /// ray was traced.
    pub reused_from: Option<u32>,
    /// With exact temporal reuse: what was traced and reused, and why the frame was traced in
    /// full when it was.
    pub reuse: Option<ExactFrame>,
}

impl RenderedFrame {
    /// Frame `index`, kept from an earlier run: no image in memory.
    fn kept(index: u32) -> Self {
        Self {
            index,
            film: Film::new(0, 0),
            render: RenderStats::default(),
            aovs: Vec::new(),
            reused_from: None,
            reuse: None,
        }
    }

    /// This frame's image handed on as frame `index`'s (static-frame reuse).
    fn reuse_as(&mut self, index: u32) {
        self.reused_from = Some(self.reused_from.unwrap_or(self.index));
        self.index = index;
        self.render = RenderStats::default();
        self.reuse = None;
    }
}

/// What [`Sequence::render`] calls with each frame it renders or reuses: the frame, its
/// statistics and the manager (for its cache and cost model so far).
pub(crate) type FrameHandler<'h, E> =
    dyn FnMut(&RenderedFrame, &FrameStats, &SceneManager) -> Result<(), E> + 'h;

impl Sequence {
    /// Renders `frame` through `manager`, whose island events up to this frame must have been
    /// observed ([`Sequence::replay`] does): prepares the accelerator, renders the image and
    /// the AOVs, and reports the trace time back to the manager.
    pub fn render_frame(
        &self,
        manager: &mut SceneManager,
        frame: &ReplayFrame<'_>,
        renderer: &FrameRenderer<'_>,
    ) -> Result<RenderedFrame, RenderError> {
        self.render_frame_with(manager, frame, renderer, None)
    }

    /// [`Self::render_frame`], with exact temporal reuse when `reuse` is given.
    pub(crate) fn render_frame_with(
        &self,
        manager: &mut SceneManager,
        frame: &ReplayFrame<'_>,
        renderer: &FrameRenderer<'_>,
        reuse: Option<&mut ExactReuse>,
    ) -> Result<RenderedFrame, RenderError> {
        self.aim_probes(manager, frame, renderer);
        manager.prepare(frame)?;
        debug_assert_eq!(manager.options().shutter, renderer.shutter, "one shutter for instances and camera");
        let (camera, camera_close) = self.shutter_cameras(frame.index, renderer.shutter);
        // Emissive prototypes are light-sampled where their bodies are this frame.
        let bodies =
            if Emitters::prototypes_emit(&self.template) { self.bodies_at(frame) } else { Vec::new() };
        let settings = renderer.settings(frame.index);
        let (film, render, aovs, exact) = {
            let mut scene = RenderScene::with_objects(&self.template, &*manager, &bodies)?;
            scene.camera = camera;
            scene.camera_close = camera_close;
            let query = manager.query()?;
            match reuse {
                None => {
                    let (film, render, aovs) =
                        render_with_aovs(&scene, query, renderer.integrator, &settings, renderer.aovs)?;
                    (film, render, aovs, None)
                }
                Some(reuse) => {
                    let tracer = FrameTracer {
                        scene: &scene,
                        query,
                        integrator: renderer.integrator,
                        settings: &settings,
                    };
                    let (film, render, aovs, exact) =
                        reuse.render(&tracer, renderer.aovs, frame.index, islands_baked(manager))?;
                    (film, render, aovs, Some(exact))
                }
            }
        };
        let full = exact.as_ref().and_then(|e| e.full);
        manager.record_trace(render.seconds * 1e3, render.rays, trace_kind(full));
        Ok(RenderedFrame { index: frame.index, film, render, aovs, reused_from: None, reuse: exact })
    }

    /// Points the manager's trace-penalty probes along `frame`'s camera, with the samples of
    /// one of `renderer`'s frames.
    pub(super) fn aim_probes(
        &self,
        manager: &mut SceneManager,
        frame: &ReplayFrame<'_>,
        renderer: &FrameRenderer<'_>,
    ) {
        let camera = self.assets.camera_at(self.time_of(frame.index));
        let samples = u64::from(renderer.width) * u64::from(renderer.height) * u64::from(renderer.spp);
        manager
            .set_probe_rays(PinholeCamera::pixel_centre_rays(&camera, PROBE_SIZE.0, PROBE_SIZE.1), samples);
    }

    /// Renders the frames `selection` selects through `manager` and hands each to
    /// `on_frame` with its statistics and the manager. The accelerator is brought up to date at the first
    /// selected frame, so a slice of a sequence renders the same images as a whole run, up to
    /// float noise (integrated and instanced bodies are hit alike).
    ///
    /// With a fixed seed, a frame that shows the same scene as the previous rendered frame
    /// ([`Sequence::unchanged_between`]) is that frame's image again: it is handed on with
    /// `reused_from` set and statistics marked `reused`, and the manager is not touched.
    ///
    /// `kept`: the first selected frames, in order, that an earlier run of the same
    /// configuration finished (`render --resume`; empty otherwise). They are neither rendered
    /// nor handed on: the manager is brought through them as that run did
    /// ([`KeptFrame`]), so the frames after them render as in an uninterrupted run.
    pub fn render<E: From<SequenceError>>(
        &self,
        selection: &FrameSelection,
        manager: &mut SceneManager,
        renderer: &FrameRenderer<'_>,
        kept: &[KeptFrame],
        on_frame: &mut FrameHandler<'_, E>,
    ) -> Result<(), E> {
        let mut last: Option<RenderedFrame> = None;
        let mut kept = kept.iter().peekable();
        let reuse = renderer.decide_reuse().map_err(SequenceError::from)?;
        let reusable = reuse != ReuseMode::Off;
        let mut exact = (reuse == ReuseMode::Exact)
            .then(|| ExactReuse::new(self.run_motion(selection, renderer.shutter), renderer.reuse_budget));
        // With motion blur a frame's image also shows the motion from the frame before it to
        // the frame after it.
        let last_frame = self.frame_count().saturating_sub(1);
        let unchanged = |a: u32, b: u32| match renderer.shutter > 0.0 {
            false => self.unchanged_between(a, b),
            true => self.unchanged_between(a.saturating_sub(1), (b + 1).min(last_frame).max(b)),
        };
        self.replay(selection, std::slice::from_mut(manager), &mut |frame, managers| {
            let manager = &mut managers[0];
            let previous = last.as_mut().filter(|p| reusable && unchanged(p.index, frame.index));
            if let Some(k) = kept.next_if(|k| k.index == frame.index) {
                self.replay_kept(manager, frame, renderer, k, previous.is_some())?;
                match previous {
                    Some(prev) => prev.reuse_as(frame.index),
                    None => last = Some(RenderedFrame::kept(frame.index)),
                }
                return Ok(());
            }
            if let Some(prev) = previous {
                prev.reuse_as(frame.index);
                let stats = manager.last_frame().reused_as(frame.index);
                return on_frame(prev, &stats, manager);
            }
            let rendered = self
                .render_frame_with(manager, frame, renderer, exact.as_mut())
                .map_err(SequenceError::from)?;
            on_frame(&rendered, manager.last_frame(), manager)?;
            last = Some(rendered);
            Ok(())
        })?;
        debug_assert!(kept.next().is_none(), "kept frames are the first selected ones");
        Ok(())
    }

    /// Brings `manager` through `kept` (the frame `frame`) as the earlier run did, without
    /// tracing; `reused`: whether this run reuses the previous image here. Fails when the
    /// replay does not reach the state that run recorded.
    pub(super) fn replay_kept(
        &self,
        manager: &mut SceneManager,
        frame: &ReplayFrame<'_>,
        renderer: &FrameRenderer<'_>,
        kept: &KeptFrame,
        reused: bool,
    ) -> Result<(), SequenceError> {
        let mismatch = |what: &'static str, recorded: String, replayed: String| SequenceError::KeptMismatch {
            frame: frame.index,
            what,
            recorded,
            replayed,
        };
        if kept.reused != reused {
            return Err(mismatch("reused", kept.reused.to_string(), reused.to_string()));
        }
        if reused {
            return Ok(());
        }
        self.aim_probes(manager, frame, renderer);
        manager.prepare_decided(frame, &kept.decisions)?;
        let stats: &FrameStats = manager.record_trace(kept.trace_ms, kept.rays, kept.trace_kind);
        for (what, recorded, replayed) in [
            ("instances", kept.instances, stats.instances),
            ("integrated_islands", kept.integrated_islands, stats.integrated_islands),
            ("sleeping_islands", kept.sleeping_islands, stats.sleeping_islands),
        ] {
            if recorded != replayed {
                return Err(mismatch(what, recorded.to_string(), replayed.to_string()));
            }
        }
        Ok(())
    }

    /// What exact reuse needs to know of rendering `selection` with shutter `shutter`: the
    /// trajectory, the template, the frames and the camera at each.
    fn run_motion(&self, selection: &FrameSelection, shutter: f32) -> RunMotion<'_> {
        let frames = selection.frames();
        let cameras = frames.iter().map(|&f| self.shutter_cameras(f, shutter)).collect();
        RunMotion::new(&self.trajectory, &self.template, frames, cameras, shutter)
    }
}

/// Whether the frame `manager` just prepared baked islands into its static scene or took
/// them out (the baked form): their triangles are then hit through another structure, and
/// exact reuse traces the frame in full.
fn islands_baked(manager: &SceneManager) -> bool {
    let stats = manager.last_frame();
    manager.options().form == IntegrationForm::Baked
        && stats.islands_integrated + stats.islands_reactivated > 0
}

/// What the trace of a frame traced in full for `full` under exact reuse (`None`: it reused
/// samples, or reuse was off) says of the frames after it.
pub(crate) fn trace_kind(full: Option<FullFrame>) -> TraceKind {
    match full {
        Some(_) => TraceKind::FullBeforeReuse,
        None => TraceKind::Typical,
    }
}
