//! The footprint in the renderer's frame: marked before the fill is planned, the refresh's
//! dirty faces cut to it, and the poison of a test's first fill.

use ash::vk;

use super::Footprint;
use crate::render::frame_data::{frame_data, view_bases, view_data};
use crate::render::graph::{FrameGraph, Use};
use crate::render::refresh::Dirty;
use crate::render::{lookups, FrameAsk, Renderer};
use crate::scene::state::SceneState;
use crate::scene::RefreshPolicy;
use crate::sensor::GroundTruth;
use crate::vk::GpuError;

/// What a poisoned cube holds where nothing was filled: far outside any colour a scene
/// makes (an RGBA8 cube clamps it to magenta), so that a view that reads it differs.
const POISON: [f32; 4] = [30000.0, -30000.0, 30000.0, 1.0];

impl Renderer {
    /// The footprint of the views frame `ask` draws at `state`, marked again where it moved
    /// (the host time, ms); every tile where something else reads the cube.
    pub(in crate::render) fn mark_footprint(
        &mut self,
        state: &SceneState,
        ask: &FrameAsk,
    ) -> Result<f64, GpuError> {
        let rays_read_cube = ask.readback.rays && self.sensor_ground_truth() == GroundTruth::Cube;
        let marks = lookups::plugin(self.scene.mirror.lookup).marks_footprint();
        let marked = self.views.drawn_views(ask.readback, ask.display);
        let size = self.cube.size;
        let Some(footprint) = &mut self.footprint else {
            return Ok(0.0);
        };
        // A policy that updates every n frames shows an older state between its updates: a
        // tile newly needed then could be filled only with this frame's.
        let every_n = matches!(self.scene.refresh, RefreshPolicy::EveryN(n) if n > 1);
        if ask.readback.cube || rays_read_cube || !marks || every_n {
            footprint.need_all(size);
            return Ok(0.0);
        }
        let frame = frame_data(&self.scene, state);
        let bases = view_bases(&self.scene, state);
        let views = view_data(&self.scene, &bases, size as f32);
        let levels = self.cube.mip_levels();
        let ms = footprint.mark(&self.submitter, (&frame, &views), &marked, levels)?;
        Ok(ms.unwrap_or(0.0))
    }

    /// `dirty` cut to the footprint, with the tiles newly needed (`Footprint::restrict`).
    pub(in crate::render) fn within_footprint(&mut self, dirty: Dirty) -> Dirty {
        let first = self.refresh.first_fill();
        match &mut self.footprint {
            Some(f) => f.restrict(dirty, first, self.cube.size),
            None => dirty,
        }
    }

    /// Level-0 texels the footprint holds the views may read (None without one).
    pub(in crate::render) fn footprint_texels(&self) -> Option<u64> {
        self.footprint.as_ref().map(Footprint::texels)
    }

    /// With `RenderOptions::footprint_poison`, before the cube's first fill: every level of
    /// every face cleared to [`POISON`].
    pub(in crate::render) fn record_poison(&self, graph: &mut FrameGraph, cmd: vk::CommandBuffer) {
        let poisoned = self.footprint.as_ref().is_some_and(|f| f.poison);
        if !poisoned || !self.refresh.first_fill() {
            return;
        }
        let levels = self.cube.mip_levels();
        graph.declare(
            &self.device,
            cmd,
            &[(self.cube.color_levels(0, levels, None), Use::Cleared)],
        );
        let range = self.cube.color.full_range();
        let colour = vk::ClearColorValue { float32: POISON };
        // SAFETY: the image is in TRANSFER_DST_OPTIMAL, as the graph just declared, and was
        // made with TRANSFER_DST usage.
        unsafe {
            self.device.raw.cmd_clear_color_image(
                cmd,
                self.cube.color.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &colour,
                &[range],
            )
        };
    }
}
