//! Getting a drawn view onto the window: the swapchain, the frames in flight, the copy.
//!
//! Each frame: wait for the frame slot's previous use (its fence), acquire a swapchain image,
//! record the upload of a view the renderer finished since the last frame (`shown.rs`); when
//! the view, the size or the format changed, the blit from the window's copy of the view
//! (linear HDR) into the composed view (`backdrop.rs`, an sRGB image: the blit encodes); the
//! copy of the composed view into the swapchain image, the menu over it; the transition for
//! presentation; the submit, waiting on "image available" and signalling the image's "drawn"
//! semaphore; the present (on its thread). Swapchain recreation (resize, out of
//! date) waits for the idle queue before destroying the old swapchain: a present has no
//! fence. A menu renderer replaced meanwhile goes through the ring's deletion queue.

use std::sync::Arc;

use anyhow::{bail, Result};
use ash::vk;
use specchio::render::display::DisplayPixels;

use specchio::vk::device::Device;
use specchio::vk::frames::{FrameRing, FRAMES_IN_FLIGHT};
use specchio::vk::memory::{Buffer, BufferDesc};
use specchio::vk::surface::Surface;
use specchio::vk::swapchain::{Acquired, PresentPreference, Swapchain, SwapchainDesc};

use super::backdrop::Backdrop;
use super::blit::{record_copy, record_finish};
use super::overlay::{Overlay, Paint, Textures};
use super::present_thread::PresentThread;
use super::shown::ShownView;

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
    /// The view shown: the renderer's last finished one, copied onto this device.
    shown: ShownView,
    /// The view as the window shows it, composed when it changes, copied every frame.
    backdrop: Backdrop,
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
            shown: ShownView::new(device),
            backdrop: Backdrop::new(device),
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

    /// Whether the last present's outcome has yet to be taken (it is running, or it returned
    /// and [`Self::poll_present`] has not read it): the loop must not sleep until then.
    pub fn present_outstanding(&self) -> bool {
        self.presents.outstanding()
    }

    /// When the last present was handed over, and when the last one returned (`None`
    /// before the first).
    pub fn present_handed_at(&self) -> Option<std::time::Instant> {
        self.presents.handed_at()
    }

    pub fn present_returned_at(&self) -> Option<std::time::Instant> {
        self.presents.returned_at()
    }

    /// Waits for the last present to return (the loop is over; what it answered is counted).
    pub fn finish_present(&mut self) {
        let _ = self.presents.take();
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

    /// A view the renderer finished: the window shows it from its next frame on.
    pub fn set_view(&mut self, pixels: DisplayPixels) {
        self.shown.set(pixels);
    }

    /// The window changed size: the swapchain is recreated before the next frame.
    pub fn resized(&mut self) {
        self.stale = true;
    }

    /// Whether the swapchain's images are `window_size` (or there is none). On X11 the
    /// swapchain takes the size the surface reports when it is made, which during a window
    /// manager's resize (leaving fullscreen) can still be the old one: the window then shows
    /// a crop of a larger image until something draws again.
    pub fn fits(&self, window_size: [u32; 2]) -> bool {
        self.swapchain
            .as_deref()
            .is_none_or(|s| [s.extent.width, s.extent.height] == window_size)
    }

    /// Shows the last view the renderer finished in the window (scaled to fit, aspect kept,
    /// centred on black when the sizes differ; copied 1:1 when they match; black before the
    /// first), the menu's `paint` over it. With `screenshot`, the presented image is also
    /// read back (the call then waits for this device's frame, never the renderer's).
    pub fn show(
        &mut self,
        window_size: [u32; 2],
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
        let readback = screenshot
            .then(|| {
                let bytes = u64::from(extent.width) * u64::from(extent.height) * 4;
                Buffer::create(&self.device, &BufferDesc::new_readback(bytes), "screenshot")
            })
            .transpose()?;
        let cmd = self.ring.slot().cmd;
        let source = self.shown.record(&mut self.ring, cmd)?;
        let composed =
            (self.backdrop).record(&mut self.ring, cmd, source.as_ref(), format, extent)?;
        let swapchain = self.swapchain.as_deref().expect("acquired from it above");
        self.record_image(cmd, swapchain, index, (composed, paint), readback.as_ref())?;
        let drawn = swapchain.render_done[index as usize];
        // The copy writes the image first: it waits for its acquisition; the menu pass after
        // it is ordered by barriers. The view's upload is a COPY as well and so waits too; a
        // batch of its own would let it overlap a FIFO wait on a GPU (not done: measured
        // only on CPU drivers here).
        let wait_stage = vk::PipelineStageFlags2::COPY;
        self.ring.submit((slot_semaphore, wait_stage), drawn)?;
        let swapchain = self.swapchain.as_ref().expect("acquired from it above");
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

    /// Records swapchain image `index`'s frame: the composed view copied in, the menu drawn
    /// over it (when it paints anything), then the image made ready to present (and copied
    /// into `readback` for a screenshot).
    fn record_image(
        &self,
        cmd: vk::CommandBuffer,
        swapchain: &Swapchain,
        index: u32,
        (composed, paint): (vk::Image, Option<&mut Paint>),
        readback: Option<&Buffer>,
    ) -> Result<()> {
        let (target, extent) = (swapchain.images[index as usize], swapchain.extent);
        record_copy(&self.device, cmd, composed, target, extent);
        let mut last = (
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::PipelineStageFlags2::COPY,
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
        record_finish(&self.device, cmd, target, extent, last, readback);
        Ok(())
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
