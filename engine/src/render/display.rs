//! Frames for a window (the live viewer): one view drawn, and copied out for the host.
//!
//! The viewer asks for one of the renderer's own view targets (the 1200x450 pair, the
//! observer or the sensor), drawn exactly as for `specchio render`, and gets its texels back
//! as they are ([`DisplayPixels`]), not decoded. The window is drawn by a device of its own
//! (`viewer/src/shown.rs`): a slow frame here, however long it runs on this device's queue,
//! never holds the window's frames (the menu, a resize) behind it. The renderer does not wait
//! for its frame (it keeps its frames in flight, `in_flight.rs`); the copy out is the frame's
//! last command, the same copy `specchio render` reads its views with (`readback.rs`).

use ash::vk;

use super::{lookups, Readback, Renderer};
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

/// A window's view as the renderer drew it: `width` x `height` texels of
/// `targets::VIEW_FORMAT` (linear RGBA16F, 8 bytes each), rows top to bottom, exactly the
/// target's contents (nothing converted: the window's own device uploads and blits them).
#[derive(Debug, Clone, Default)]
pub struct DisplayPixels {
    pub width: u32,
    pub height: u32,
    pub rgba16f: Vec<u8>,
}

impl DisplayPixels {
    /// The format of the texels, for the image they are uploaded into.
    pub const FORMAT: vk::Format = super::targets::VIEW_FORMAT;
}

impl Renderer {
    /// Submits frame `frame` at scene time `t_s` with only `view` drawn and copied out for
    /// the host (no cube, direction or other view copies). It does not wait: the frame's
    /// report and [`DisplayPixels`] (`FrameImages::display`) come from
    /// [`Renderer::finished_frames`] once it has run.
    pub fn render_display_frame(
        &mut self,
        frame: u64,
        t_s: f64,
        view: DisplayView,
    ) -> Result<(), GpuError> {
        self.submit_frame_views(frame, t_s, Readback::default(), Some(view))
    }

    /// Whether the cube map, once the frames submitted so far have run, shows the scene as it
    /// is at `t_s` (a viewer that draws on demand goes on drawing until it does: an `every-n`
    /// policy updates the cube only every n frames). True for a lookup that reads no cube.
    pub fn cube_shows_scene_at(&self, t_s: f64) -> bool {
        !lookups::plugin(self.mirror.lookup()).uses_cube()
            || self.refresh.shows_state(&SceneState::at(&self.scene, t_s))
    }
}
