//! Getting a drawn view onto the window: the swapchain, the frames in flight, and the blit.
//!
//! Each frame: wait for the frame slot's previous use (its fence), acquire a swapchain image,
//! record a blit from the renderer's view image (linear HDR) into it (an sRGB image: the blit
//! encodes), transition it for presentation, submit waiting on "image available" and
//! signalling the image's "drawn" semaphore, present. Swapchain recreation (resize, out of
//! date) waits for the idle queue before destroying the old swapchain: a present has no
//! fence. A menu renderer replaced meanwhile goes through the ring's deletion queue.

use std::sync::Arc;

use anyhow::{bail, Result};
use ash::vk;
use specchio::render::display::DisplayImage;
use specchio::vk::commands::{image_barriers, ImageBarrier};
use specchio::vk::device::Device;
use specchio::vk::frames::{FrameRing, FRAMES_IN_FLIGHT};
use specchio::vk::memory::{Buffer, BufferDesc};
use specchio::vk::surface::Surface;
use specchio::vk::swapchain::{Acquired, PresentPreference, Swapchain, SwapchainDesc};

use super::overlay::{Overlay, Paint, Textures};
use super::present_thread::PresentThread;

/// What became of one frame.
pub enum Shown {
    Presented,
    /// Nothing shown: the window has no area (minimised) or the swapchain was out of date;
    /// the caller tries again with the next frame.
    Skipped,
}

/// A screenshot: the presented image's pixels as 8-bit sRGB RGB, rows top to bottom.
pub struct Screenshot {
    pub width: u32,
    pub height: u32,
    pub rgb8: Vec<u8>,
}

/// Teardown: the drop waits for the idle queue (a present has no fence); then, in field
/// order, the ring (releasing what it deferred), the swapchain, the surface, the device.
pub struct Presenter {
    pub ring: FrameRing,
    /// The menu's egui renderer, for the swapchain's format; `None` while there is no
    /// swapchain or its images cannot be drawn into (the menu is then not shown).
    overlay: Option<Overlay>,
    /// Every texture egui holds, for a menu renderer made later.
    textures: Textures,
    /// Shared with the present thread while a present of it runs.
    swapchain: Option<Arc<Swapchain>>,
    /// The presents, made on a thread of their own (`present_thread`).
    presents: PresentThread,
    /// The swapchain no longer matches the window: recreate before the next frame.
    stale: bool,
    pub surface: Arc<Surface>,
    present: PresentPreference,
    /// Test hook (`--renew-menu-renderer`): a new menu renderer every frame, as a swapchain
    /// format change makes one, to show that it is given egui's textures.
    pub renew_overlay: bool,
    device: Arc<Device>,
}

impl Presenter {
    pub fn create(
        device: &Arc<Device>,
        surface: Surface,
        present: PresentPreference,
    ) -> Result<Self> {
        surface.check_present(device)?;
        Ok(Self {
            ring: FrameRing::create(device, FRAMES_IN_FLIGHT)?,
            overlay: None,
            textures: Textures::default(),
            swapchain: None,
            presents: PresentThread::start(),
            stale: true,
            surface: Arc::new(surface),
            present,
            renew_overlay: false,
            device: Arc::clone(device),
        })
    }

    /// Whether the last frame's present has returned: until it has, the loop draws nothing
    /// (the present thread uses the queue and the swapchain), and never waits for it.
    pub fn present_returned(&mut self) -> bool {
        self.presents.returned()
    }

    /// The last present's outcome once it has returned (never waits): a swapchain to
    /// recreate is noted, a failure (the surface or the device lost) is returned now rather
    /// than at the next frame, which an idle window may never draw.
    pub fn poll_present(&mut self) -> Result<()> {
        if self.presents.returned() {
            self.stale |= self.presents.take()?;
        }
        Ok(())
    }

    /// The window changed size: the swapchain is recreated before the next frame.
    pub fn resized(&mut self) {
        self.stale = true;
    }

    /// Shows `source` in the window (scaled to fit, aspect kept, centred on black when the
    /// sizes differ; copied 1:1 when they match). With `screenshot`, the presented image is
    /// also read back (the call then waits for the frame).
    pub fn show(
        &mut self,
        window_size: [u32; 2],
        source: &DisplayImage,
        mut paint: Option<&mut Paint>,
        screenshot: bool,
    ) -> Result<(Shown, Option<Screenshot>)> {
        // The last present's outcome (the caller waited for it to return: no wait here).
        self.stale |= self.presents.take()?;
        if self.stale && !self.recreate(window_size)? {
            return Ok((Shown::Skipped, None));
        }
        if self.renew_overlay {
            if let Some(old) = self.overlay.take() {
                self.ring.defer(old);
            }
            self.replace_overlay(overlay_format(self.swapchain.as_deref()))?;
        }
        let Some(swapchain) = &self.swapchain else {
            return Ok((Shown::Skipped, None));
        };
        // A swapchain whose images cannot be read back gives no screenshot (the caller says so).
        let screenshot = screenshot && swapchain.readable;
        // Textures first: an upload waits for the queue, so it goes before this frame's
        // submission rather than inside its recording.
        if let (Some(p), Some(overlay)) = (paint.as_deref_mut(), &mut self.overlay) {
            overlay.update_textures(&mut self.ring, &mut p.textures, &mut self.textures)?;
        }
        let (extent, format) = (swapchain.extent, swapchain.format.format);
        let slot_semaphore = self.ring.begin()?.image_available;
        let index = match swapchain.acquire(slot_semaphore)? {
            Acquired::Image { index, suboptimal } => {
                self.stale |= suboptimal;
                index
            }
            Acquired::OutOfDate => {
                self.ring.abandon()?;
                self.stale = true;
                return Ok((Shown::Skipped, None));
            }
        };
        let target = swapchain.images[index as usize];
        let cmd = self.ring.slot().cmd;
        let readback = screenshot
            .then(|| {
                let bytes = u64::from(extent.width) * u64::from(extent.height) * 4;
                Buffer::create(&self.device, &BufferDesc::new_readback(bytes), "screenshot")
            })
            .transpose()?;
        record_blit(&self.device, cmd, source, target, extent);
        let mut last = (
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::PipelineStageFlags2::BLIT,
            vk::AccessFlags2::TRANSFER_WRITE,
        );
        let paint = paint.filter(|p| !p.primitives.is_empty());
        if let (Some(paint), Some(overlay)) = (paint, &self.overlay) {
            let view = swapchain.views[index as usize];
            overlay.record(cmd, target, view, extent, paint)?;
            last = (
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
            );
        }
        record_finish(&self.device, cmd, target, extent, last, readback.as_ref());
        let drawn = swapchain.render_done[index as usize];
        // The blit (and the clear before it) write the image first: they wait for its
        // acquisition; the menu pass after them is ordered by barriers.
        let wait_stage = vk::PipelineStageFlags2::BLIT | vk::PipelineStageFlags2::CLEAR;
        self.ring.submit((slot_semaphore, wait_stage), drawn)?;
        self.presents.present(swapchain, index)?;
        let shot = match readback {
            Some(buffer) => {
                self.ring.wait_all()?;
                Some(read_screenshot(&buffer, extent, format)?)
            }
            None => None,
        };
        Ok((Shown::Presented, shot))
    }

    /// Replaces the swapchain for the window's current size; `false` when the window has no
    /// area (nothing to present to until it is resized).
    fn recreate(&mut self, window_size: [u32; 2]) -> Result<bool> {
        let desc = SwapchainDesc {
            window_size,
            present: self.present,
        };
        let old = self.swapchain.as_deref();
        let new = Swapchain::create(&self.device, &self.surface, &desc, old)?.map(Arc::new);
        if let Some(old) = self.swapchain.take() {
            // A frame's fence says its drawing finished, not that its present did, and the
            // old swapchain's "drawn" semaphores may still be waited on by one. Only an idle
            // queue says so (VK_EXT_swapchain_maintenance1's present fences would, but not
            // every driver has them); a resize is rare enough to wait for it.
            self.device.wait_idle()?;
            drop(old);
        }
        if let Some(s) = &new {
            // One line per (re)creation: what the window presents with.
            specchio::say!(
                "swapchain: {}x{} {:?} {:?}",
                s.extent.width,
                s.extent.height,
                s.format.format,
                s.present_mode
            );
        }
        self.replace_overlay(overlay_format(new.as_deref()))?;
        self.swapchain = new;
        self.stale = self.swapchain.is_none();
        Ok(self.swapchain.is_some())
    }
}

impl Drop for Presenter {
    fn drop(&mut self) {
        // The last frame's present may still run on its thread, and then still wait on its
        // image's "drawn" semaphore, which the swapchain destroys, and no fence covers a
        // present: wait for it to return, then for the idle queue (the ring's own drop then
        // finds its fences signalled).
        let _ = self.presents.take();
        let _ = self.device.wait_idle();
    }
}

impl Presenter {
    /// Keeps the menu renderer when the new swapchain has the same format; otherwise makes
    /// one for the new format and retires the old one through the deletion queue (a frame
    /// in flight may still draw with its pipeline and buffers).
    fn replace_overlay(&mut self, wanted: Option<(vk::Format, bool)>) -> Result<()> {
        if self.overlay.as_ref().map(Overlay::format) == wanted.map(|w| w.0) {
            return Ok(());
        }
        let new = match wanted {
            Some((format, srgb)) => {
                let mut overlay = Overlay::create(&self.device, format, srgb)?;
                overlay.restore(&self.textures)?;
                Some(overlay)
            }
            None => None,
        };
        if let Some(old) = std::mem::replace(&mut self.overlay, new) {
            self.ring.defer(old);
        }
        Ok(())
    }
}

/// The format (and whether it encodes sRGB) a menu renderer for `swapchain` draws into;
/// `None` without a swapchain or with images that cannot be drawn into.
fn overlay_format(swapchain: Option<&Swapchain>) -> Option<(vk::Format, bool)> {
    swapchain
        .filter(|s| !s.views.is_empty())
        .map(|s| (s.format.format, s.is_srgb()))
}

/// Records: source COPY -> BLIT; target UNDEFINED -> TRANSFER_DST; a clear where the blit
/// leaves bars; the blit; source BLIT -> COPY (for the renderer's next frame, see
/// `DisplayImage`). The target is left in TRANSFER_DST, written at BLIT (and CLEAR).
fn record_blit(
    device: &Device,
    cmd: vk::CommandBuffer,
    source: &DisplayImage,
    target: vk::Image,
    extent: vk::Extent2D,
) {
    use vk::AccessFlags2 as A;
    use vk::ImageLayout as L;
    use vk::PipelineStageFlags2 as S;
    let whole = COLOR_RANGE;
    let src_layout = L::TRANSFER_SRC_OPTIMAL;
    let dst = |from: (L, S, A), to: (L, S, A)| ImageBarrier {
        image: target,
        range: whole,
        from,
        to,
    };
    let write_stages = S::BLIT | S::CLEAR;
    image_barriers(
        device,
        cmd,
        &[
            // The renderer made its writes visible to COPY; chain on to the blit's reads.
            ImageBarrier {
                image: source.image,
                range: source.range,
                from: (src_layout, S::COPY, A::NONE),
                to: (src_layout, S::BLIT, A::TRANSFER_READ),
            },
            // First scope = the stages that waited on the acquire semaphore (chaining).
            dst(
                (L::UNDEFINED, write_stages, A::NONE),
                (L::TRANSFER_DST_OPTIMAL, write_stages, A::TRANSFER_WRITE),
            ),
        ],
    );
    let (rect, covers) = fit(source.width, source.height, extent);
    let d = &device.raw;
    if !covers {
        let black = vk::ClearColorValue {
            float32: [0.0, 0.0, 0.0, 1.0],
        };
        // SAFETY: the image is in TRANSFER_DST layout; the range is its only subresource.
        unsafe { d.cmd_clear_color_image(cmd, target, L::TRANSFER_DST_OPTIMAL, &black, &[whole]) };
        image_barriers(
            device,
            cmd,
            &[dst(
                (L::TRANSFER_DST_OPTIMAL, S::CLEAR, A::TRANSFER_WRITE),
                (L::TRANSFER_DST_OPTIMAL, S::BLIT, A::TRANSFER_WRITE),
            )],
        );
    }
    let layers = COLOR_LAYER;
    let corner = |x: u32, y: u32| vk::Offset3D {
        x: x as i32,
        y: y as i32,
        z: 1,
    };
    let region = vk::ImageBlit {
        src_subresource: layers,
        src_offsets: [vk::Offset3D::default(), corner(source.width, source.height)],
        dst_subresource: layers,
        dst_offsets: [
            vk::Offset3D {
                x: rect[0] as i32,
                y: rect[1] as i32,
                z: 0,
            },
            corner(rect[0] + rect[2], rect[1] + rect[3]),
        ],
    };
    // 1:1 copies every texel exactly; a scaled view is filtered.
    let filter = if [rect[2], rect[3]] == [source.width, source.height] {
        vk::Filter::NEAREST
    } else {
        vk::Filter::LINEAR
    };
    // SAFETY: both images are in the layouts named, the regions lie inside them.
    unsafe {
        d.cmd_blit_image(
            cmd,
            source.image,
            src_layout,
            target,
            L::TRANSFER_DST_OPTIMAL,
            &[region],
            filter,
        )
    };
    // The view image is free for the renderer's next frame (see `DisplayImage`).
    let source_done = ImageBarrier {
        image: source.image,
        range: source.range,
        from: (src_layout, S::BLIT, A::NONE),
        to: (src_layout, S::COPY, A::NONE),
    };
    image_barriers(device, cmd, &[source_done]);
}

/// Records the end of a frame: `target` from `last` (the blit's or the menu's writes) to
/// PRESENT_SRC, or via TRANSFER_SRC and a copy into `readback` (the screenshot).
fn record_finish(
    device: &Device,
    cmd: vk::CommandBuffer,
    target: vk::Image,
    extent: vk::Extent2D,
    last: (vk::ImageLayout, vk::PipelineStageFlags2, vk::AccessFlags2),
    readback: Option<&Buffer>,
) {
    use vk::AccessFlags2 as A;
    use vk::ImageLayout as L;
    use vk::PipelineStageFlags2 as S;
    let dst = |from, to| ImageBarrier {
        image: target,
        range: COLOR_RANGE,
        from,
        to,
    };
    let present = (L::PRESENT_SRC_KHR, S::NONE, A::NONE);
    let Some(buffer) = readback else {
        image_barriers(device, cmd, &[dst(last, present)]);
        return;
    };
    let readable = (L::TRANSFER_SRC_OPTIMAL, S::COPY, A::TRANSFER_READ);
    image_barriers(device, cmd, &[dst(last, readable)]);
    let copy = vk::BufferImageCopy::default()
        .image_subresource(COLOR_LAYER)
        .image_extent(vk::Extent3D {
            width: extent.width,
            height: extent.height,
            depth: 1,
        });
    // SAFETY: the image is in TRANSFER_SRC layout; the buffer holds width x height x 4 bytes.
    unsafe {
        device.raw.cmd_copy_image_to_buffer(
            cmd,
            target,
            L::TRANSFER_SRC_OPTIMAL,
            buffer.raw,
            &[copy],
        )
    };
    specchio::vk::commands::host_read_barrier(device, cmd, S::COPY, A::TRANSFER_WRITE);
    image_barriers(device, cmd, &[dst(readable, present)]);
}

/// The one colour subresource of a swapchain image.
const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};
const COLOR_LAYER: vk::ImageSubresourceLayers = vk::ImageSubresourceLayers {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    mip_level: 0,
    base_array_layer: 0,
    layer_count: 1,
};

/// Where a `w` x `h` image goes in `extent`: [x, y, width, height], as large as fits with its
/// aspect ratio kept, centred; and whether it covers the whole extent.
pub fn fit(w: u32, h: u32, extent: vk::Extent2D) -> ([u32; 4], bool) {
    let (ew, eh) = (u64::from(extent.width), u64::from(extent.height));
    let (w64, h64) = (u64::from(w), u64::from(h));
    // Width-limited when ew / eh <= w / h (compared in integers: no rounding).
    let (fw, fh) = if ew * h64 <= eh * w64 {
        (ew, (ew * h64 / w64).max(1))
    } else {
        ((eh * w64 / h64).max(1), eh)
    };
    let (x, y) = ((ew - fw) / 2, (eh - fh) / 2);
    let rect = [x as u32, y as u32, fw as u32, fh as u32];
    (rect, fw == ew && fh == eh)
}

/// The read-back swapchain image as RGB8 (the swapchain's byte order undone).
fn read_screenshot(
    buffer: &Buffer,
    extent: vk::Extent2D,
    format: vk::Format,
) -> Result<Screenshot> {
    let bgra = match format {
        vk::Format::B8G8R8A8_SRGB | vk::Format::B8G8R8A8_UNORM => true,
        vk::Format::R8G8B8A8_SRGB | vk::Format::R8G8B8A8_UNORM => false,
        other => bail!("--screenshot: cannot read a swapchain image of format {other:?}"),
    };
    let n = extent.width as usize * extent.height as usize;
    let bytes = &buffer.mapped()?[..n * 4];
    let rgb8 = bytes
        .chunks_exact(4)
        .flat_map(|p| {
            if bgra {
                [p[2], p[1], p[0]]
            } else {
                [p[0], p[1], p[2]]
            }
        })
        .collect();
    Ok(Screenshot {
        width: extent.width,
        height: extent.height,
        rgb8,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(width: u32, height: u32) -> vk::Extent2D {
        vk::Extent2D { width, height }
    }

    #[test]
    fn an_image_fits_its_window_with_its_aspect_kept() {
        assert_eq!(fit(1200, 450, e(1200, 450)), ([0, 0, 1200, 450], true));
        // Twice as tall a window: bars above and below.
        assert_eq!(fit(1200, 450, e(1200, 900)), ([0, 225, 1200, 450], false));
        // A wider window: bars left and right.
        assert_eq!(fit(800, 600, e(1000, 600)), ([100, 0, 800, 600], false));
        assert_eq!(fit(800, 600, e(400, 300)), ([0, 0, 400, 300], true));
    }
}
