//! The window's copy of the last view the renderer finished, on the window's own device.
//!
//! Why a copy, and why on another device: a queue runs its submissions in order, and a CPU
//! driver (lavapipe, SwiftShader) has one. A window frame queued behind a slow frame (a
//! 2048² cube filled by a distance search: 757 ms measured) would wait for all of it, so a
//! menu opened with F1 or a resized window would show only after it. The renderer therefore
//! runs on one logical device and the window on another, each with its own queue: the
//! renderer copies each finished view out for the host (`DisplayPixels`), and the window's
//! device uploads it here and blits it into the window's composed view (`backdrop.rs`), which
//! every window frame (the menu, a resize, an exposed window) then shows, whatever the
//! renderer's queue is doing.
//! The cost is one copy of the view through host memory per renderer frame (the 1200x450
//! pair is 4.3 MB of RGBA16F).
//!
//! Synchronisation of the image, all on the window's queue: between frames it is in
//! `TRANSFER_SRC_OPTIMAL`, last read by a blit (`BLIT`) or written by an upload made visible
//! to the blit. An upload waits for every earlier blit (its barrier's first scope is `BLIT`;
//! read-after-read between blits needs none). Each frame slot has its staging buffer, reused
//! once the slot's frame before has finished; an image replaced by one of another size is
//! retired through the frame ring's deletion queue.

use std::sync::Arc;

use anyhow::{ensure, Result};
use ash::vk;
use specchio::render::display::DisplayPixels;
use specchio::vk::commands::{image_barriers, ImageBarrier};
use specchio::vk::device::Device;
use specchio::vk::frames::{FrameRing, FRAMES_IN_FLIGHT};
use specchio::vk::image::{color_copy_region, Image, ImageDesc};
use specchio::vk::memory::{Buffer, BufferDesc};
use vk::AccessFlags2 as A;
use vk::ImageLayout as L;
use vk::PipelineStageFlags2 as S;

/// The image the window's view is composed from: in `TRANSFER_SRC_OPTIMAL`, ready for
/// `BLIT` reads.
#[derive(Debug, Clone, Copy)]
pub struct ShownImage {
    pub image: vk::Image,
    pub width: u32,
    pub height: u32,
    /// Which upload it holds (1 for the first): a new one asks for a new composition.
    pub generation: u64,
}

/// The view the window shows: the newest pixels not yet uploaded, and the image holding the
/// last ones that were.
pub struct ShownView {
    pending: Option<DisplayPixels>,
    image: Option<Image>,
    /// One staging buffer per frame slot of the window's ring, reused: the slot's frame
    /// before has finished once `FrameRing::begin` returned (a new 4.3 MB buffer a frame
    /// cost its page faults every frame).
    staging: Vec<Option<Buffer>>,
    /// Uploads recorded so far.
    generation: u64,
    device: Arc<Device>,
}

impl ShownView {
    pub fn new(device: &Arc<Device>) -> Self {
        Self {
            pending: None,
            image: None,
            staging: (0..FRAMES_IN_FLIGHT).map(|_| None).collect(),
            generation: 0,
            device: Arc::clone(device),
        }
    }

    /// A finished frame's view: shown from the next window frame on (a newer one replaces
    /// one not shown yet).
    pub fn set(&mut self, pixels: DisplayPixels) {
        self.pending = Some(pixels);
    }

    /// Records the upload of the newest pixels, if any came since the last frame, into `cmd`
    /// (the ring's current frame); the image to blit from, `None` before the first view.
    pub fn record(
        &mut self,
        ring: &mut FrameRing,
        cmd: vk::CommandBuffer,
    ) -> Result<Option<ShownImage>> {
        if let Some(pixels) = self.pending.take() {
            self.upload(ring, cmd, &pixels)?;
            self.generation += 1;
        }
        Ok(self.image.as_ref().map(|image| ShownImage {
            image: image.raw,
            width: image.desc.width,
            height: image.desc.height,
            generation: self.generation,
        }))
    }

    fn upload(
        &mut self,
        ring: &mut FrameRing,
        cmd: vk::CommandBuffer,
        pixels: &DisplayPixels,
    ) -> Result<()> {
        let (w, h) = (pixels.width, pixels.height);
        let bytes = u64::from(w) * u64::from(h) * 8;
        let texels = pixels.rgba16f()?;
        ensure!(
            texels.len() as u64 == bytes,
            "a {w}x{h} view came with {} bytes, not {bytes}",
            texels.len()
        );
        // The image before this upload: its contents are replaced whole, so a new one
        // starts from UNDEFINED.
        let mut before = L::TRANSFER_SRC_OPTIMAL;
        let same_size = |i: &Image| [i.desc.width, i.desc.height] == [w, h];
        if self.image.as_ref().is_none_or(|i| !same_size(i)) {
            let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC;
            let desc = ImageDesc::new_2d(DisplayPixels::FORMAT, w, h, usage);
            let new = Image::create(&self.device, &desc, "the window's view")?;
            if let Some(old) = self.image.replace(new) {
                ring.defer(old);
            }
            before = L::UNDEFINED;
        }
        let staging = self.staging_for(ring.current_index(), bytes)?;
        staging.write(texels)?;
        let staging = staging.raw;
        let image = self.image.as_ref().expect("made above");
        let (range, image) = (image.full_range(), image.raw);
        let barrier = |from, to| ImageBarrier {
            image,
            range,
            from,
            to,
        };
        let write = (L::TRANSFER_DST_OPTIMAL, S::COPY, A::TRANSFER_WRITE);
        // After every earlier blit from it (write-after-read: an execution dependency).
        let after_blits = barrier((before, S::BLIT, A::NONE), write);
        image_barriers(&self.device, cmd, &[after_blits]);
        copy(&self.device, cmd, staging, image, [w, h]);
        let for_blits = (L::TRANSFER_SRC_OPTIMAL, S::BLIT, A::TRANSFER_READ);
        image_barriers(&self.device, cmd, &[barrier(write, for_blits)]);
        Ok(())
    }

    /// Slot `slot`'s staging buffer, at least `bytes` large (one too small is replaced: the
    /// slot's last frame, the only one that used it, has finished).
    fn staging_for(&mut self, slot: usize, bytes: u64) -> Result<&mut Buffer> {
        let kept = &mut self.staging[slot];
        if kept.as_ref().is_none_or(|b| b.size < bytes) {
            let desc = BufferDesc::new_cpu_to_gpu(bytes, vk::BufferUsageFlags::TRANSFER_SRC);
            *kept = Some(Buffer::create(
                &self.device,
                &desc,
                "the window's view upload",
            )?);
        }
        Ok(kept.as_mut().expect("made above"))
    }
}

/// Records the copy of the whole of `staging` into `image` (in `TRANSFER_DST_OPTIMAL`).
fn copy(
    device: &Device,
    cmd: vk::CommandBuffer,
    staging: vk::Buffer,
    image: vk::Image,
    [width, height]: [u32; 2],
) {
    let region = color_copy_region(0, 1, [width, height]);
    // SAFETY: the image is in TRANSFER_DST layout and as large as the region; the buffer
    // holds width x height texels (checked by `upload`).
    unsafe {
        device
            .raw
            .cmd_copy_buffer_to_image(cmd, staging, image, L::TRANSFER_DST_OPTIMAL, &[region])
    };
}
