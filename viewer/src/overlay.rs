//! Drawing egui's output (the menu, the help) into the swapchain image, over the view copied in.
//!
//! egui hands over triangles (`ClippedPrimitive`s) and texture changes (`TexturesDelta`);
//! `egui-ash-renderer` turns them into one graphics pipeline's draws. This module owns that
//! renderer and records its pass: the swapchain image goes from the copy's TRANSFER_DST to
//! COLOR_ATTACHMENT_OPTIMAL, a dynamic-rendering pass LOADs what the copy wrote (the views
//! stay under the menu) and egui's triangles are blended over it.
//!
//! Lifetimes: egui frees a texture (a glyph atlas page that was replaced) in the delta of a
//! frame while an earlier frame in flight may still sample it, so the free is handed to the
//! frame ring's deletion queue (`FrameRing::defer`) and runs once those frames finished. A
//! renderer made for another swapchain format is retired the same way.
//!
//! egui sends a texture once and then only patches (new glyphs go into the font atlas as
//! partial updates). A renderer made later (a swapchain format change) would lack what was
//! sent before, so `Textures` keeps every texture's whole current image on the CPU, and a
//! new renderer is given all of them before its first draw.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard};

use anyhow::{Context, Result};
use ash::vk;
use egui::epaint::{ColorImage, ImageData, ImageDelta};
use egui::{ClippedPrimitive, TextureId, TexturesDelta};
use egui_ash_renderer::{allocator::DefaultAllocator, DynamicRendering, Options, RenderMode};
use specchio::vk::commands::{image_barriers, ImageBarrier};
use specchio::vk::device::Device;
use specchio::vk::frames::{FrameRing, FRAMES_IN_FLIGHT};

type EguiRenderer = egui_ash_renderer::Renderer<DefaultAllocator>;

/// What egui asked to draw this frame. `textures` is emptied as it is applied; what is
/// left (a frame that was skipped) goes back to the menu for the next frame.
pub struct Paint {
    pub primitives: Vec<ClippedPrimitive>,
    pub textures: TexturesDelta,
    pub pixels_per_point: f32,
}

impl Drop for Paint {
    fn drop(&mut self) {
        // Only reached with changes left on an error path, where the program is ending;
        // egui asserts that a delta is never dropped unapplied by mistake.
        self.textures.clear();
    }
}

/// The egui renderer for one swapchain format, and the command pool its texture uploads use.
pub struct Overlay {
    /// Shared with the deferred texture frees, which need it when they run.
    renderer: Arc<Mutex<EguiRenderer>>,
    format: vk::Format,
    upload_pool: UploadPool,
    device: Arc<Device>,
}

/// Textures egui freed, released when the frames that might sample them have finished.
struct DeferredFree {
    renderer: Arc<Mutex<EguiRenderer>>,
    ids: Vec<TextureId>,
}

impl Drop for DeferredFree {
    fn drop(&mut self) {
        let mut renderer = lock(&self.renderer);
        for &id in &self.ids {
            // An error here means a Vulkan call failed while destroying; nothing to undo.
            let _ = renderer.free_texture(id);
        }
    }
}

fn lock(renderer: &Mutex<EguiRenderer>) -> MutexGuard<'_, EguiRenderer> {
    renderer.lock().unwrap_or_else(|p| p.into_inner())
}

/// A transient command pool for `set_texture`'s uploads (it submits and waits itself).
struct UploadPool {
    raw: vk::CommandPool,
    device: Arc<Device>,
}

impl Drop for UploadPool {
    fn drop(&mut self) {
        // SAFETY: the uploads submitted from this pool were waited for by `set_texture`.
        unsafe { self.device.raw.destroy_command_pool(self.raw, None) };
    }
}

impl Overlay {
    /// A renderer for images of `format`. The fragment shader encodes sRGB itself unless the
    /// image format does it (egui's colours are sRGB-encoded, blended in that space).
    pub fn create(device: &Arc<Device>, format: vk::Format, srgb: bool) -> Result<Self> {
        let mode = RenderMode::DynamicRendering(DynamicRendering {
            color_attachment_format: format,
            depth_attachment_format: None,
            stencil_attachment_format: None,
        });
        let options = Options {
            in_flight_frames: FRAMES_IN_FLIGHT,
            srgb_framebuffer: srgb,
            ..Default::default()
        };
        let renderer = EguiRenderer::with_default_allocator(
            &device.instance.raw,
            device.physical,
            device.raw.clone(),
            mode,
            options,
        )
        .context("creating the menu's egui renderer")?;
        let info = vk::CommandPoolCreateInfo::default()
            .flags(vk::CommandPoolCreateFlags::TRANSIENT)
            .queue_family_index(device.queue_family);
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_command_pool(&info, None) }
            .context("creating the menu's upload command pool")?;
        Ok(Self {
            renderer: Arc::new(Mutex::new(renderer)),
            format,
            upload_pool: UploadPool {
                raw,
                device: Arc::clone(device),
            },
            device: Arc::clone(device),
        })
    }

    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// Applies egui's texture changes before recording: new and updated textures now (the
    /// upload waits for the queue), freed ones through the deletion queue. `kept` follows
    /// along, so that a later renderer can be given the same textures.
    pub fn update_textures(
        &mut self,
        ring: &mut FrameRing,
        delta: &mut TexturesDelta,
        kept: &mut Textures,
    ) -> Result<()> {
        for (id, images) in delta.set.drain() {
            for image in &images {
                self.upload(id, image)?;
                kept.set(id, image);
            }
        }
        if !delta.free.is_empty() {
            for id in &delta.free {
                kept.free(*id);
            }
            ring.defer(DeferredFree {
                renderer: Arc::clone(&self.renderer),
                ids: delta.free.drain().collect(),
            });
        }
        Ok(())
    }

    /// Uploads every texture egui holds (a new renderer's first step: egui will not send
    /// again what an earlier renderer was given).
    pub fn restore(&mut self, kept: &Textures) -> Result<()> {
        for (&id, image) in &kept.images {
            self.upload(id, image)?;
        }
        Ok(())
    }

    fn upload(&self, id: TextureId, image: &ImageDelta) -> Result<()> {
        // egui-ash submits the upload and waits for it: the queue is held meanwhile.
        let queue = self.device.queue();
        lock(&self.renderer)
            .set_texture(*queue, self.upload_pool.raw, id, image)
            .context("uploading a menu texture")
    }

    /// Records the menu pass over `target` (written by the copy, in TRANSFER_DST_OPTIMAL);
    /// leaves it in COLOR_ATTACHMENT_OPTIMAL, written at COLOR_ATTACHMENT_OUTPUT.
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        target: vk::Image,
        view: vk::ImageView,
        extent: vk::Extent2D,
        paint: &Paint,
    ) -> Result<()> {
        use vk::AccessFlags2 as A;
        use vk::ImageLayout as L;
        use vk::PipelineStageFlags2 as S;
        let range = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 1,
        };
        // The copy's writes, then the pass LOADs and blends over them.
        let attachment = A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE;
        image_barriers(
            &self.device,
            cmd,
            &[ImageBarrier {
                image: target,
                range,
                from: (L::TRANSFER_DST_OPTIMAL, S::COPY, A::TRANSFER_WRITE),
                to: (
                    L::COLOR_ATTACHMENT_OPTIMAL,
                    S::COLOR_ATTACHMENT_OUTPUT,
                    attachment,
                ),
            }],
        );
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(view)
            .image_layout(L::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            })
            .layer_count(1)
            .color_attachments(&color);
        let d = &self.device.raw;
        // SAFETY: the view is of `target`, now in COLOR_ATTACHMENT_OPTIMAL; the renderer's
        // pipeline was made for this format with dynamic rendering.
        unsafe { d.cmd_begin_rendering(cmd, &info) };
        let drawn =
            lock(&self.renderer).cmd_draw(cmd, extent, paint.pixels_per_point, &paint.primitives);
        // SAFETY: a rendering pass was begun on this command buffer above.
        unsafe { d.cmd_end_rendering(cmd) };
        drawn.context("recording the menu")?;
        Ok(())
    }
}

/// Every texture egui currently holds, whole, as egui has set and patched it.
#[derive(Default)]
pub struct Textures {
    images: HashMap<TextureId, ImageDelta>,
}

impl Textures {
    /// Applies one of egui's changes: a whole image replaces, a patch is copied in.
    pub fn set(&mut self, id: TextureId, delta: &ImageDelta) {
        let Some(pos) = delta.pos else {
            self.images.insert(id, delta.clone());
            return;
        };
        let Some(whole) = self.images.get_mut(&id) else {
            // A patch of a texture never set whole: egui does not send one; nothing to keep.
            return;
        };
        let (ImageData::Color(target), ImageData::Color(patch)) = (&mut whole.image, &delta.image);
        let target: &mut ColorImage = Arc::make_mut(target);
        let [w, _] = target.size;
        let [pw, ph] = patch.size;
        for row in 0..ph {
            let start = (pos[1] + row) * w + pos[0];
            target.pixels[start..start + pw].copy_from_slice(&patch.pixels[row * pw..][..pw]);
        }
        whole.options = delta.options;
    }

    pub fn free(&mut self, id: TextureId) {
        self.images.remove(&id);
    }

    /// The whole current image of `id`.
    #[cfg(test)]
    fn image(&self, id: TextureId) -> Option<&ColorImage> {
        self.images.get(&id).map(|d| match &d.image {
            ImageData::Color(image) => &**image,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::{Color32, TextureOptions};

    fn image(size: [usize; 2], value: u8) -> ColorImage {
        ColorImage::new(size, vec![Color32::from_gray(value); size[0] * size[1]])
    }

    #[test]
    fn kept_textures_follow_whole_images_patches_and_frees() {
        let (font, other) = (TextureId::Managed(0), TextureId::Managed(1));
        let opts = TextureOptions::LINEAR;
        let mut kept = Textures::default();
        kept.set(font, &ImageDelta::full(image([4, 3], 10), opts));
        kept.set(other, &ImageDelta::full(image([1, 1], 5), opts));
        // A 2x2 patch at (1, 1), as a new glyph goes into the atlas.
        kept.set(font, &ImageDelta::partial([1, 1], image([2, 2], 200), opts));
        let font_image = kept.image(font).unwrap();
        let gray: Vec<u8> = font_image.pixels.iter().map(|c| c.r()).collect();
        #[rustfmt::skip]
        assert_eq!(gray, [
            10, 10, 10, 10,
            10, 200, 200, 10,
            10, 200, 200, 10,
        ]);
        // A whole image replaces what was there, size included.
        kept.set(font, &ImageDelta::full(image([2, 1], 7), opts));
        assert_eq!(kept.image(font).unwrap().size, [2, 1]);
        kept.free(other);
        assert!(kept.image(other).is_none());
        assert_eq!(kept.images.len(), 1);
    }
}
