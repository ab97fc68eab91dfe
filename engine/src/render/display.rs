//! Frames for a window (the live viewer): one view drawn, nothing read back.
//!
//! The viewer does not read pixels back to the CPU. It asks for one of the renderer's own
//! view targets (the 1200x450 pair, the observer or the sensor), drawn exactly as for
//! `specchio render`, and copies that image into its swapchain image in its own submission
//! (`viewer/src/`). The renderer does not wait for its frame (it keeps its frames in flight,
//! `in_flight.rs`): the copy is submitted to the same queue after the frame and before the
//! next one, whose first barrier on the target chains after the copy's closing barrier (see
//! [`DisplayImage`]), so the target is never overwritten while the copy may read it.

use ash::vk;

use super::{lookups, FrameReport, Readback, Renderer};
use crate::scene::state::SceneState;
use crate::vk::GpuError;

/// Which of the renderer's views a window shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DisplayView {
    /// Observer left, sensor right, at [`super::PAIR_SIZE`] (the thesis's window).
    #[default]
    Pair,
    /// The observer alone, at the scene's `observer.resolution`.
    Observer,
    /// The sensor alone, at the scene's `sensor.resolution`.
    Sensor,
}

/// A drawn view image, ready to be copied by the caller.
///
/// State after [`Renderer::render_display_frame`] returned: layout `TRANSFER_SRC_OPTIMAL`,
/// its colour writes available and visible to `COPY`-stage transfer reads. A caller that
/// reads it at another stage (a blit: `BLIT`) first records a barrier from `COPY` to its
/// stage, and after reading, a barrier from its stage to `COPY`: the renderer's next frame
/// starts with a layout transition whose first scope is `COPY` (the readback copies'
/// stage), so that chain orders the caller's read before the next overwrite.
#[derive(Debug, Clone, Copy)]
pub struct DisplayImage {
    pub image: vk::Image,
    pub range: vk::ImageSubresourceRange,
    pub width: u32,
    pub height: u32,
    /// Linear HDR (`targets::VIEW_FORMAT`): a blit into an sRGB image encodes it.
    pub format: vk::Format,
}

impl Renderer {
    /// Submits frame `frame` at scene time `t_s` with only `view` drawn (no readback, no cube
    /// or direction copies) and returns its image, which the caller copies in a submission
    /// of its own after this one; and the reports of the frames finished by now, oldest first
    /// (the frame just submitted is usually not among them: it is still running).
    pub fn render_display_frame(
        &mut self,
        frame: u64,
        t_s: f64,
        view: DisplayView,
    ) -> Result<(Vec<FrameReport>, DisplayImage), GpuError> {
        self.submit_frame_views(frame, t_s, Readback::default(), Some(view))?;
        let finished = self.finished_frames()?;
        let reports = finished.into_iter().map(|(report, _)| report).collect();
        Ok((reports, self.display_image(view)))
    }

    /// Whether the cube map, once the frames submitted so far have run, shows the scene as it
    /// is at `t_s` (a viewer that draws on demand goes on drawing until it does: an `every-n`
    /// policy updates the cube only every n frames). True for a lookup that reads no cube.
    pub fn cube_shows_scene_at(&self, t_s: f64) -> bool {
        !lookups::plugin(self.mirror.lookup()).uses_cube()
            || self.refresh.shows_state(&SceneState::at(&self.scene, t_s))
    }

    /// The image `view` is drawn into (valid as described at [`DisplayImage`] only after a
    /// `render_display_frame` of that view).
    pub fn display_image(&self, view: DisplayView) -> DisplayImage {
        let target = match view {
            DisplayView::Pair => &self.views.targets.pair,
            DisplayView::Observer => &self.views.targets.observer,
            DisplayView::Sensor => &self.views.targets.sensor,
        };
        DisplayImage {
            image: target.color.raw,
            range: target.color.full_range(),
            width: target.width,
            height: target.height,
            format: super::targets::VIEW_FORMAT,
        }
    }
}
