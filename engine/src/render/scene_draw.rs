//! Recording the scene's draws, one part of the renderer: [`SceneDraw`] opens and closes
//! rendering scopes, sets viewports, winding and culling, binds the scene (set 0, the shared
//! vertex and index buffers) and draws objects. It holds what every pass shares and nothing
//! of a frame: the view passes record through it, and so does a fill method, through the
//! cube recorder (`methods::CubeRecorder`), which is all of the renderer a method sees.

use ash::vk;

use super::draw::{Attachments, Facing, CLEAR_COLOR, CLEAR_DEPTH, CLEAR_ID};
use super::gpu::Push;
use super::resources::SceneResources;
use super::Renderer;
use crate::scene::pixel_rect::PixelRect;
use crate::vk::device::Device;
use crate::vk::pipeline::{Pipeline, PipelineLayout};

/// The scene's draws: the device, the scene's pipeline layout (set 0 and the push constants,
/// [`Push`]) and its resources.
#[derive(Clone, Copy)]
pub(super) struct SceneDraw<'a> {
    pub device: &'a Device,
    pub layout: &'a PipelineLayout,
    pub resources: &'a SceneResources,
}

impl Renderer {
    /// The part that records the scene's draws.
    pub(super) fn scene_draw(&self) -> SceneDraw<'_> {
        SceneDraw {
            device: &self.device,
            layout: &self.scene_layout,
            resources: &self.resources,
        }
    }
}

impl SceneDraw<'_> {
    /// Binds `pipeline` with the scene's descriptor set, vertex and index buffers.
    pub fn bind_scene(&self, cmd: vk::CommandBuffer, pipeline: &Pipeline) {
        let d = &self.device.raw;
        // SAFETY (whole block): cmd is recording inside a rendering scope whose attachment
        // formats match the pipeline; buffers and sets are live and not being written.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout.raw,
                0,
                &[self.resources.scene_set],
                &[],
            );
            d.cmd_bind_vertex_buffers(cmd, 0, &[self.resources.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, self.resources.indices.raw, 0, vk::IndexType::UINT32);
        }
    }

    pub fn push(&self, cmd: vk::CommandBuffer, layout: vk::PipelineLayout, push: Push) {
        // SAFETY: the push range covers the device's graphics stages and this many bytes.
        unsafe {
            self.device.raw.cmd_push_constants(
                cmd,
                layout,
                self.device.graphics_stages(),
                0,
                bytemuck::bytes_of(&push),
            )
        };
    }

    /// Binds `pipeline` and draws `objects` in order, one indexed draw each, with push
    /// constants `base` whose object index is replaced per draw, back faces culled where
    /// `facing` allows (closed meshes clear of the eye) and drawn otherwise.
    pub fn draw_objects(
        &self,
        cmd: vk::CommandBuffer,
        pipeline: &Pipeline,
        base: Push,
        objects: &[u32],
        facing: &Facing,
    ) {
        self.bind_scene(cmd, pipeline);
        self.set_front_face(cmd, facing.front);
        let mut culling = None;
        for &i in objects {
            let draw = &self.resources.drawables[i as usize];
            let cull = facing.cull[i as usize];
            if culling != Some(cull) {
                self.set_cull_back(cmd, cull);
                culling = Some(cull);
            }
            self.push(
                cmd,
                self.layout.raw,
                Push {
                    object_index: i,
                    ..base
                },
            );
            // SAFETY: the scene is bound; the ranges lie inside the shared buffers.
            unsafe {
                self.device.raw.cmd_draw_indexed(
                    cmd,
                    draw.index_count,
                    1,
                    draw.first_index,
                    draw.vertex_offset,
                    0,
                )
            };
        }
    }

    /// Front-face winding for the draws that follow (pipelines with dynamic culling).
    pub fn set_front_face(&self, cmd: vk::CommandBuffer, front: vk::FrontFace) {
        // SAFETY: recording; the bound pipeline has FRONT_FACE as dynamic state.
        unsafe { self.device.raw.cmd_set_front_face(cmd, front) };
    }

    /// Back faces culled or not for the draws that follow (pipelines with dynamic culling).
    pub fn set_cull_back(&self, cmd: vk::CommandBuffer, cull: bool) {
        let mode = if cull {
            vk::CullModeFlags::BACK
        } else {
            vk::CullModeFlags::NONE
        };
        // SAFETY: recording; the bound pipeline has CULL_MODE as dynamic state.
        unsafe { self.device.raw.cmd_set_cull_mode(cmd, mode) };
    }

    pub fn begin_rendering(&self, cmd: vk::CommandBuffer, a: &Attachments) {
        let load = if a.clear {
            vk::AttachmentLoadOp::CLEAR
        } else {
            vk::AttachmentLoadOp::LOAD
        };
        let colour = |view, clear| {
            vk::RenderingAttachmentInfo::default()
                .image_view(view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(load)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(clear)
        };
        let color_att: Vec<vk::RenderingAttachmentInfo> = [(a.color, CLEAR_COLOR)]
            .into_iter()
            .chain(a.ids.map(|ids| (ids, CLEAR_ID)))
            .chain(a.more_colors.iter().map(|&view| (view, CLEAR_COLOR)))
            .map(|(view, clear)| colour(view, clear))
            .collect();
        let depth_att = vk::RenderingAttachmentInfo::default()
            .image_view(a.depth)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(if a.store_depth {
                vk::AttachmentStoreOp::STORE
            } else {
                vk::AttachmentStoreOp::DONT_CARE
            })
            .clear_value(CLEAR_DEPTH);
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D {
                width: a.size[0],
                height: a.size[1],
            },
        };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(a.layers)
            .view_mask(a.view_mask)
            .color_attachments(&color_att)
            .depth_attachment(&depth_att);
        // SAFETY: the attachments are in the layouts named above.
        unsafe { self.device.raw.cmd_begin_rendering(cmd, &info) };
    }

    pub fn end_rendering(&self, cmd: vk::CommandBuffer) {
        // SAFETY: closes the scope opened by begin_rendering on this command buffer.
        unsafe { self.device.raw.cmd_end_rendering(cmd) };
    }

    /// Inside a rendering scope: clears colour and depth of each (layer, rectangle), and with
    /// `ids` the id cube (attachment 1) too.
    pub fn clear_rects(&self, cmd: vk::CommandBuffer, rects: &[(u32, PixelRect)], ids: bool) {
        let all = [
            vk::ClearAttachment {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                color_attachment: 0,
                clear_value: CLEAR_COLOR,
            },
            vk::ClearAttachment {
                aspect_mask: vk::ImageAspectFlags::DEPTH,
                color_attachment: 0,
                clear_value: CLEAR_DEPTH,
            },
            vk::ClearAttachment {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                color_attachment: 1,
                clear_value: CLEAR_ID,
            },
        ];
        let attachments = &all[..if ids { 3 } else { 2 }];
        let rects: Vec<vk::ClearRect> = (rects.iter())
            .map(|&(layer, r)| vk::ClearRect {
                rect: rect2d(&r),
                base_array_layer: layer,
                layer_count: 1,
            })
            .collect();
        // SAFETY: inside a rendering scope holding the layers; the rects lie within it.
        unsafe {
            self.device
                .raw
                .cmd_clear_attachments(cmd, attachments, &rects)
        };
    }

    /// Draws that follow touch only the pixels of `r`.
    pub fn set_scissor(&self, cmd: vk::CommandBuffer, r: &PixelRect) {
        // SAFETY: recording; the scissor is dynamic in every pipeline.
        unsafe { self.device.raw.cmd_set_scissor(cmd, 0, &[rect2d(r)]) };
    }

    pub fn set_viewport(&self, cmd: vk::CommandBuffer, x: f32, y: f32, w: f32, h: f32) {
        let vp = vk::Viewport {
            x,
            y,
            width: w,
            height: h,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let scissor = vk::Rect2D {
            offset: vk::Offset2D {
                x: x as i32,
                y: y as i32,
            },
            extent: vk::Extent2D {
                width: w as u32,
                height: h as u32,
            },
        };
        // SAFETY: recording; viewport and scissor are dynamic in every pipeline.
        unsafe {
            self.device.raw.cmd_set_viewport(cmd, 0, &[vp]);
            self.device.raw.cmd_set_scissor(cmd, 0, &[scissor]);
        }
    }
}

/// `r` as Vulkan's rectangle.
fn rect2d(r: &PixelRect) -> vk::Rect2D {
    vk::Rect2D {
        offset: vk::Offset2D {
            x: r.x0 as i32,
            y: r.y0 as i32,
        },
        extent: vk::Extent2D {
            width: r.width(),
            height: r.height(),
        },
    }
}
