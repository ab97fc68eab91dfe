//! Multiview fill: one pass with view mask 0x3F over the six-layer cube; each object visible
//! in some face is drawn once and the driver replays it per view, `gl_ViewIndex` picking the
//! face. A pipeline's view mask is fixed, and a clear in the scope reaches every view, so a
//! partial update re-renders all six faces in the same rectangles, every dirty face's
//! together (`Dirty::in_every_face`). Still exact: a clean face re-rendered where nothing
//! changed gives the pixels it holds.
//!
//! **lavapipe keeps the view mask after the pass** (Mesa 25.0.7, and unchanged in Mesa's
//! later sources): `vkCmdEndRendering` does not reset its recorded view mask, so every later
//! `vkCmdWriteTimestamp2` / `vkCmdBeginQuery` in the same command buffer is replicated over
//! `popcount(viewMask)` consecutive query slots, as the spec asks only inside a multiview
//! pass. With the cube's mask that writes past the end of a query pool and crashes the
//! driver. The usage is valid, so the validation layer sees nothing. The workaround: an empty
//! rendering scope (no attachments, one layer, no view mask) right after the pass, which
//! resets the driver's state; it costs nothing on any driver, so it is always recorded.
//! [`view_mask_leak`] measures the bug in isolation (`specchio probe view-mask-leak`), and
//! the test `lavapipe_view_mask_leak_is_still_there` fails the day a Mesa release fixes it.

use std::sync::Arc;

use ash::vk;

use super::{CubeLayout, CubePlan, CubeRecorder, FillMethod, FillPass, MethodContext, Needs};
use crate::render::gpu::Push;
use crate::vk::commands::{image_barriers, ImageBarrier, Submitter};
use crate::vk::device::{Device, Limit, OptionalFeatures};
use crate::vk::image::{Image, ImageDesc, ImageView};
use crate::vk::pipeline::Pipeline;
use crate::vk::queries::QueryPool;
use crate::vk::GpuError;

pub struct Multiview;

impl FillMethod for Multiview {
    fn name(&self) -> &'static str {
        "multiview"
    }

    fn summary(&self) -> &'static str {
        "one pass, view mask 0x3F; the driver replays each draw per face (gl_ViewIndex)"
    }

    fn needs(&self) -> Needs {
        Needs {
            features: OptionalFeatures {
                multiview: true,
                ..Default::default()
            },
            limits: &[(Limit::MultiviewViewCount, 6)],
            probe: true,
        }
    }

    fn layout(&self) -> CubeLayout {
        CubeLayout::Multiview
    }

    fn create(&self, ctx: &MethodContext<'_>) -> Result<Box<dyn FillPass>, GpuError> {
        let vertex = (
            vk::ShaderStageFlags::VERTEX,
            crate::shaders::CUBE_MULTIVIEW_VERT,
        );
        let pipeline = ctx.pipeline(&[vertex], "cube pipeline (multiview)")?;
        Ok(Box::new(MultiviewFill { pipeline }))
    }
}

struct MultiviewFill {
    pipeline: Pipeline,
}

impl FillPass for MultiviewFill {
    fn record(&self, rec: &CubeRecorder<'_>, plan: &CubePlan) {
        rec.begin_cube(plan);
        rec.draw_objects(&self.pipeline, Push::default(), &plan.union());
        rec.end_cube();
        reset_view_mask(rec.device(), rec.cmd());
    }
}

/// Records an empty rendering scope without a view mask: lavapipe then forgets the view mask
/// of the multiview pass before it (see the module's comment).
fn reset_view_mask(device: &Device, cmd: vk::CommandBuffer) {
    let info = vk::RenderingInfo::default()
        .render_area(vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D {
                width: 1,
                height: 1,
            },
        })
        .layer_count(1)
        .view_mask(0);
    // SAFETY: a rendering scope with no attachments is valid (dynamicRendering); nothing is
    // drawn in it.
    unsafe {
        device.raw.cmd_begin_rendering(cmd, &info);
        device.raw.cmd_end_rendering(cmd);
    }
}

/// What [`view_mask_leak`] measured: the query slots a single timestamp written after a
/// multiview pass made available.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct ViewMaskLeak {
    /// Whether the empty rendering scope was recorded after the pass.
    pub reset: bool,
    /// The slot the timestamp was written to.
    pub written: u32,
    /// Every slot that holds a result afterwards (only `written` on a correct driver).
    pub available: Vec<u32>,
}

/// Measures the lavapipe bug in isolation: a multiview rendering scope (view mask 0x3F, no
/// draws) on a 6-layer image, then one timestamp at slot 2 of a 16-slot pool, in one command
/// buffer; reports which slots became available. With `reset`, the workaround's empty scope
/// is recorded between the two. Slots stay in range, so even the buggy driver does not crash.
pub fn view_mask_leak(device: &Arc<Device>, reset: bool) -> Result<ViewMaskLeak, GpuError> {
    const SLOTS: u32 = 16;
    const WRITTEN: u32 = 2;
    let image = Image::create(device, &probe_desc(), "view mask probe")?;
    let view = image.view(
        vk::ImageViewType::TYPE_2D_ARRAY,
        0,
        6,
        0,
        1,
        "view mask probe layers",
    )?;
    let queries = QueryPool::timestamps(device, SLOTS, "view mask probe")?;
    let submitter = Submitter::create(device, "view mask probe")?;
    let cmd = submitter.begin()?;
    queries.reset(cmd);
    image_barriers(device, cmd, &[to_attachment(&image)]);
    record_empty_multiview_scope(device, cmd, &view);
    if reset {
        reset_view_mask(device, cmd);
    }
    queries.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, WRITTEN);
    submitter.submit_and_wait()?;
    let available = available_slots(&queries, SLOTS)?;
    Ok(ViewMaskLeak {
        reset,
        written: WRITTEN,
        available,
    })
}

/// The probe's image: 4 x 4 texels, six layers, one per view of the mask.
fn probe_desc() -> ImageDesc {
    ImageDesc {
        layers: 6,
        ..ImageDesc::new_2d(
            vk::Format::R8G8B8A8_UNORM,
            4,
            4,
            vk::ImageUsageFlags::COLOR_ATTACHMENT,
        )
    }
}

/// The probe image, from undefined to colour attachment.
fn to_attachment(image: &Image) -> ImageBarrier {
    ImageBarrier {
        image: image.raw,
        range: image.full_range(),
        from: (
            vk::ImageLayout::UNDEFINED,
            vk::PipelineStageFlags2::NONE,
            vk::AccessFlags2::NONE,
        ),
        to: (
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        ),
    }
}

/// Records a rendering scope with view mask 0x3F over the probe's six layers, and no draws.
fn record_empty_multiview_scope(device: &Device, cmd: vk::CommandBuffer, view: &ImageView) {
    let color = [vk::RenderingAttachmentInfo::default()
        .image_view(view.raw)
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)];
    let info = vk::RenderingInfo::default()
        .render_area(vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D {
                width: 4,
                height: 4,
            },
        })
        .view_mask(0x3F)
        .color_attachments(&color);
    // SAFETY: the image is a colour attachment with 6 layers, as the view mask needs; the
    // device was created with the multiview feature (the caller's duty).
    unsafe {
        device.raw.cmd_begin_rendering(cmd, &info);
        device.raw.cmd_end_rendering(cmd);
    }
}

/// The slots of the first `slots` of `queries` that hold a result.
fn available_slots(queries: &QueryPool, slots: u32) -> Result<Vec<u32>, GpuError> {
    Ok(queries
        .availability(slots)?
        .into_iter()
        .enumerate()
        .filter_map(|(i, a)| a.then_some(i as u32))
        .collect())
}
