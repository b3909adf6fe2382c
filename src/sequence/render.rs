//! The per-frame call into the renderer: a scene manager brought to a frame, its committed
//! scene rendered with the run's integrator and AOVs, and the trace time reported back to the
//! manager's cost model.

use super::{FrameSelection, Sequence, SequenceError};
use crate::integrate::{FrameStats, SceneManager};
use crate::physics::ReplayFrame;
use crate::render::{
    render_frame, Aov, AovIntegrator, Emitters, Film, Integrator, PinholeCamera, RenderError, RenderScene,
    RenderSettings, RenderStats,
};

/// Camera rays (one per pixel of this image) of the manager's trace-penalty probes: enough
/// rays for a stable time, few enough to cost a few ms.
const PROBE_SIZE: (u32, u32) = (128, 72);

/// How every frame of a run is rendered.
#[derive(Clone, Copy)]
pub struct FrameRenderer<'a> {
    pub integrator: &'a dyn Integrator,
    /// Extra passes, rendered after the beauty image in this order.
    pub aovs: &'a [Aov],
    pub width: u32,
    pub height: u32,
    pub spp: u32,
}

impl FrameRenderer<'_> {
    fn settings(&self, frame: u32) -> RenderSettings {
        RenderSettings { width: self.width, height: self.height, spp: self.spp, frame }
    }
}

/// One rendered frame; the manager keeps its statistics ([`SceneManager::last_frame`]).
pub struct RenderedFrame {
    pub index: u32,
    pub film: Film,
    pub render: RenderStats,
    /// The requested AOV passes, in request order.
    pub aovs: Vec<(Aov, Film)>,
}

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
        let camera = self.assets.camera_at(self.time_of(frame.index));
        manager.set_probe_rays(PinholeCamera::pixel_centre_rays(&camera, PROBE_SIZE.0, PROBE_SIZE.1));
        manager.prepare(frame)?;
        // Emissive prototypes are light-sampled where their bodies are this frame.
        let bodies =
            if Emitters::prototypes_emit(&self.template) { self.bodies_at(frame) } else { Vec::new() };
        let settings = renderer.settings(frame.index);
        let (film, render, aovs) = {
            let mut scene = RenderScene::with_objects(&self.template, &*manager, &bodies)?;
            scene.camera = camera;
            let query = manager.query()?;
            let (film, render) = render_frame(&scene, query, renderer.integrator, &settings)?;
            let mut aovs = Vec::with_capacity(renderer.aovs.len());
            for &aov in renderer.aovs {
                aovs.push((aov, render_frame(&scene, query, &AovIntegrator(aov), &settings)?.0));
            }
            (film, render, aovs)
        };
        manager.record_trace(render.seconds * 1e3, render.rays);
        Ok(RenderedFrame { index: frame.index, film, render, aovs })
    }

    /// Renders the frames `selection` selects through `manager` and hands each to
    /// `on_frame` with the manager's statistics. The accelerator is brought up to date at the
    /// first selected frame, so a slice of a sequence renders the same images as a whole run,
    /// up to float noise (integrated and instanced bodies are hit alike).
    pub fn render<E: From<SequenceError>>(
        &self,
        selection: &FrameSelection,
        manager: &mut SceneManager,
        renderer: &FrameRenderer<'_>,
        on_frame: &mut dyn FnMut(&RenderedFrame, &FrameStats) -> Result<(), E>,
    ) -> Result<(), E> {
        self.replay(selection, std::slice::from_mut(manager), &mut |frame, managers| {
            let manager = &mut managers[0];
            let rendered = self.render_frame(manager, frame, renderer).map_err(SequenceError::from)?;
            on_frame(&rendered, manager.last_frame())
        })
    }
}
