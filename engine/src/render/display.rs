//! Frames for a window (the live viewer): one view drawn, and copied out for the host.
//!
//! The viewer asks for one of the renderer's own view targets (the 1200x450 pair, the
//! observer or the sensor), drawn exactly as for `specchio render`, and gets its texels back
//! as they are ([`DisplayPixels`]), neither decoded nor copied. The window is drawn by a device of its own
//! (`viewer/src/shown.rs`): a slow frame here, however long it runs on this device's queue,
//! never holds the window's frames (the menu, a resize) behind it. The renderer does not wait
//! for its frame (it keeps its frames in flight, `in_flight.rs`); the copy out is the frame's
//! last command, the same copy `specchio render` reads its views with (`readback.rs`).

use std::sync::Arc;

use ash::vk;

use super::{lookups, Readback, Renderer};
use crate::scene::state::SceneState;
use crate::vk::memory::Buffer;
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
///
/// The texels stay in the frame slot's host-visible readback buffer, not copied out: while
/// this is kept, the renderer gives the slot a new buffer rather than write into this one.
#[derive(Clone)]
pub struct DisplayPixels {
    pub width: u32,
    pub height: u32,
    buffer: Arc<Buffer>,
    bytes: usize,
}

impl DisplayPixels {
    /// The format of the texels, for the image they are uploaded into.
    pub const FORMAT: vk::Format = super::targets::VIEW_FORMAT;

    pub(super) fn new([width, height]: [u32; 2], buffer: Arc<Buffer>, bytes: usize) -> Self {
        Self {
            width,
            height,
            buffer,
            bytes,
        }
    }

    /// The texels, read where the frame's copy left them (its fence has signalled).
    pub fn rgba16f(&self) -> Result<&[u8], GpuError> {
        Ok(&self.buffer.mapped()?[..self.bytes])
    }
}

impl std::fmt::Debug for DisplayPixels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (w, h) = (self.width, self.height);
        write!(f, "DisplayPixels({w}x{h}, {} bytes)", self.bytes)
    }
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
        self.submit(super::FrameAsk {
            display: Some(view),
            ..super::FrameAsk::new(frame, t_s, Readback::default())
        })
    }

    /// Whether the cube map, once the frames submitted so far have run, shows the scene as it
    /// is at `t_s` (a viewer that draws on demand goes on drawing until it does: an `every-n`
    /// policy updates the cube only every n frames). True for a lookup that reads no cube.
    pub fn cube_shows_scene_at(&self, t_s: f64) -> bool {
        !lookups::plugin(self.mirror.lookup()).uses_cube()
            || self.refresh.shows_state(&SceneState::at(&self.scene, t_s))
    }
}
