//! The view as the window shows it (scaled to fit, black bars, in the swapchain's format),
//! composed once per view rather than once per window frame.
//!
//! Why: the blit from the window's copy of the view (linear RGBA16F) into the swapchain's
//! format (8-bit sRGB where offered) scales, filters and encodes every pixel. On a CPU driver that is the window frame's largest
//! cost (lavapipe, 1200x450: its blit's JIT code took about two thirds of the window's
//! rasteriser samples in a profile of F1 presses), and a frame that changes only the menu
//! (F1, `h`, the frame-time graph, an exposed window) would pay it for the same pixels. So
//! the blit writes this image, at the swapchain's size and in its format, when the view, the
//! size or the format changed; every window frame copies it into the swapchain image (texels
//! of one format copied as they are: a memcpy on a CPU driver, a plain transfer on a GPU)
//! and draws the menu over that. The price: one more window-sized image, and while the scene
//! moves (a new view for nearly every window frame) a copy on top of the blit each frame
//! (on lavapipe 0.2 to 0.4 ms at 1200x450; thesis-room's frame rate moved within its noise,
//! docs/viewer.md).
//!
//! Synchronisation, all on the window's queue: between frames the image is in
//! `TRANSFER_SRC_OPTIMAL`, last read by a copy (`COPY`). A recompose waits for every earlier
//! copy from it (write-after-read: an execution dependency), clears and blits, and makes its
//! writes visible to the copies after it. An image replaced by one of another size or format
//! is retired through the frame ring's deletion queue: a frame in flight may still copy from
//! it.
//!
//! What the image holds is noted when its composition is recorded, not when it is submitted:
//! the caller submits every frame it records, and a failure in between ends the viewer (a
//! frame recorded and then dropped would leave the note claiming pixels never drawn).

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use specchio::vk::commands::{image_barriers, ImageBarrier};
use specchio::vk::device::Device;
use specchio::vk::frames::FrameRing;
use specchio::vk::image::{Image, ImageDesc};
use vk::AccessFlags2 as A;
use vk::ImageLayout as L;
use vk::PipelineStageFlags2 as S;

use super::blit::compose;
use super::shown::ShownImage;

/// The composed view, and which view it holds.
pub struct Backdrop {
    image: Option<Image>,
    /// The generation of the view `image` holds; `None` while it holds nothing yet.
    generation: Option<u64>,
    device: Arc<Device>,
}

/// What a composed view holds: which upload of the view (0: none yet, black), at which
/// size, in which format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Held {
    generation: u64,
    extent: [u32; 2],
    format: vk::Format,
}

/// What a frame records for its composed view.
#[derive(Debug, PartialEq, Eq)]
enum Plan {
    /// It already holds the view: the copy only.
    Keep,
    /// A new view came: composed again into the same image.
    Compose,
    /// The size or the format changed (or there is no image yet): a new image, composed.
    Replace,
}

fn plan(held: Option<Held>, wanted: Held) -> Plan {
    match held {
        Some(h) if h == wanted => Plan::Keep,
        Some(h) if (h.extent, h.format) == (wanted.extent, wanted.format) => Plan::Compose,
        _ => Plan::Replace,
    }
}

impl Backdrop {
    pub fn new(device: &Arc<Device>) -> Self {
        Self {
            image: None,
            generation: None,
            device: Arc::clone(device),
        }
    }

    /// Records into `cmd` (the ring's current frame) whatever makes the image hold `source`
    /// at `extent` in `format`: nothing when it already does. Returns the image, in
    /// `TRANSFER_SRC_OPTIMAL` and visible to `COPY` reads.
    pub fn record(
        &mut self,
        ring: &mut FrameRing,
        cmd: vk::CommandBuffer,
        source: Option<&ShownImage>,
        format: vk::Format,
        extent: vk::Extent2D,
    ) -> Result<vk::Image> {
        let wanted = Held {
            generation: source.map_or(0, |s| s.generation),
            extent: [extent.width, extent.height],
            format,
        };
        let plan = plan(self.held(), wanted);
        let before = match plan {
            Plan::Keep | Plan::Compose => L::TRANSFER_SRC_OPTIMAL,
            Plan::Replace => {
                let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC;
                let desc = ImageDesc::new_2d(format, extent.width, extent.height, usage);
                let new = Image::create(&self.device, &desc, "the window's composed view")?;
                if let Some(old) = self.image.replace(new) {
                    ring.defer(old);
                }
                // Its contents are written whole: a new image starts from UNDEFINED.
                L::UNDEFINED
            }
        };
        let image = self.image.as_ref().expect("made above when missing");
        let (raw, range) = (image.raw, image.full_range());
        if plan != Plan::Keep {
            let barrier = |from, to| ImageBarrier {
                image: raw,
                range,
                from,
                to,
            };
            let writes = (
                L::TRANSFER_DST_OPTIMAL,
                S::BLIT | S::CLEAR,
                A::TRANSFER_WRITE,
            );
            let for_copies = (L::TRANSFER_SRC_OPTIMAL, S::COPY, A::TRANSFER_READ);
            // After every earlier copy from it; a new image has none to wait for.
            let first = match before {
                L::UNDEFINED => S::NONE,
                _ => S::COPY,
            };
            image_barriers(
                &self.device,
                cmd,
                &[barrier((before, first, A::NONE), writes)],
            );
            compose(&self.device, cmd, source, raw, extent);
            image_barriers(&self.device, cmd, &[barrier(writes, for_copies)]);
            self.generation = Some(wanted.generation);
        }
        Ok(raw)
    }

    /// What the image holds: its size and format are its own, the view is noted.
    fn held(&self) -> Option<Held> {
        let (image, generation) = self.image.as_ref().zip(self.generation)?;
        Some(Held {
            generation,
            extent: [image.desc.width, image.desc.height],
            format: image.desc.format,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_view_is_composed_again_only_when_it_or_the_size_or_the_format_changed() {
        let held = Held {
            generation: 3,
            extent: [1200, 450],
            format: vk::Format::B8G8R8A8_SRGB,
        };
        assert_eq!(plan(None, held), Plan::Replace);
        // A frame that changes only the menu: the copy alone.
        assert_eq!(plan(Some(held), held), Plan::Keep);
        let newer = Held {
            generation: 4,
            ..held
        };
        assert_eq!(plan(Some(held), newer), Plan::Compose);
        let resized = Held {
            extent: [800, 600],
            ..held
        };
        assert_eq!(plan(Some(held), resized), Plan::Replace);
        let unorm = Held {
            format: vk::Format::B8G8R8A8_UNORM,
            ..held
        };
        assert_eq!(plan(Some(held), unorm), Plan::Replace);
    }
}
