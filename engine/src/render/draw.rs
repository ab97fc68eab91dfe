//! Recording helpers shared by every pass: barriers' stage/access pairs, culling, draws,
//! rendering scopes and viewports.

use ash::vk;
use glam::Vec3;

use super::gpu::Push;
use super::sensor_rays::MirrorOutput;
use super::Renderer;
use crate::scene::camera::Frustum;
use crate::vk::commands::ImageBarrier;
use crate::vk::pipeline::Pipeline;

/// A stage and access pair, one side of a barrier.
pub(super) type Sync = (vk::PipelineStageFlags2, vk::AccessFlags2);

pub(super) const COLOR_OUT: Sync = (
    vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw()
            | vk::AccessFlags2::COLOR_ATTACHMENT_READ.as_raw(),
    ),
);
pub(super) const DEPTH_RW: Sync = (
    vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS.as_raw()
            | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw(),
    ),
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ.as_raw()
            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw(),
    ),
);
pub(super) const SAMPLED: Sync = (
    vk::PipelineStageFlags2::FRAGMENT_SHADER,
    vk::AccessFlags2::SHADER_SAMPLED_READ,
);
pub(super) const COPY_READ: Sync = (
    vk::PipelineStageFlags2::COPY,
    vk::AccessFlags2::TRANSFER_READ,
);
pub(super) const COPY_WRITE: Sync = (
    vk::PipelineStageFlags2::COPY,
    vk::AccessFlags2::TRANSFER_WRITE,
);
pub(super) const NOTHING: Sync = (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);

pub(super) fn barrier(
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    from: (vk::ImageLayout, Sync),
    to: (vk::ImageLayout, Sync),
) -> ImageBarrier {
    ImageBarrier {
        image,
        range,
        from: (from.0, from.1 .0, from.1 .1),
        to: (to.0, to.1 .0, to.1 .1),
    }
}

/// The attachments of one rendering scope.
pub(super) struct Attachments {
    pub color: vk::ImageView,
    /// The id cube's view, attachment 1 of a cube fill that writes ids.
    pub ids: Option<vk::ImageView>,
    pub depth: vk::ImageView,
    pub size: [u32; 2],
    /// Layers rendered (layered cube fills: 6); ignored when `view_mask` is set.
    pub layers: u32,
    /// Multiview view mask (0: not multiview).
    pub view_mask: u32,
    /// Clear on load (the whole attachment); otherwise keep the contents and let the method
    /// clear the layers it re-renders.
    pub clear: bool,
    /// Keep the depth after the scope: the cube's depth is the `distance` lookup's distance
    /// map, and a face not re-rendered keeps it; a view's depth is needed only within.
    pub store_depth: bool,
}

/// How a front face (counter-clockwise seen from the front, as every mesh is wound) turns on
/// screen: a view keeps it; a cube face sees the world mirrored (its u axis runs the other
/// way, docs/conventions.md), which turns it clockwise.
pub(super) const VIEW_FRONT: vk::FrontFace = vk::FrontFace::COUNTER_CLOCKWISE;
pub(super) const CUBE_FRONT: vk::FrontFace = vk::FrontFace::CLOCKWISE;

/// How one pass's draws face the viewer: the winding of a front face on its screen, and per
/// drawable whether its back faces may be culled. They may when the mesh is closed and stays
/// out of the ball around the eye that reaches the corners of the near plane: an eye inside a
/// closed mesh, or a near plane cutting into one, would see its inside, which culling would
/// remove (the reference, which does not cull, shows it).
pub(super) struct Facing {
    pub front: vk::FrontFace,
    pub cull: Vec<bool>,
}

/// Clear values: transparent black colour (a direction image is then zero, alpha included,
/// wherever the mirror is not; the room covers every other target), and the far plane for
/// reverse-Z depth.
pub(super) const CLEAR_COLOR: vk::ClearValue = vk::ClearValue {
    color: vk::ClearColorValue {
        float32: [0.0, 0.0, 0.0, 0.0],
    },
};
/// The id cube's clear value: no drawable (`OBJECT_NONE`).
pub(super) const CLEAR_ID: vk::ClearValue = vk::ClearValue {
    color: vk::ClearColorValue {
        uint32: [crate::shaders::shared::OBJECT_NONE; 4],
    },
};
pub(super) const CLEAR_DEPTH: vk::ClearValue = vk::ClearValue {
    depth_stencil: vk::ClearDepthStencilValue {
        depth: 0.0,
        stencil: 0,
    },
};

/// This frame's drawables in render space: their bounds (walls first) and the order they are
/// drawn in. One part, remade each frame by `write_frame_buffers`; culling, the draw order and
/// the back-face guard read it.
#[derive(Default)]
pub(super) struct DrawOrder {
    /// Render-space bounds of every drawable, walls first.
    pub bounds: Vec<(Vec3, Vec3)>,
    /// Objects front to back from the cube's centre, walls last ([`DrawOrder::of`]).
    pub order: Vec<u32>,
}

impl DrawOrder {
    /// The order for `bounds`: objects by the distance of their bounds from the cube's centre
    /// (`centre`, render space), nearest first, then the six walls. Every cube face looks out from
    /// that one point, so this one order is front to back for all six faces at once: the
    /// depth test then rejects hidden fragments before they are shaded (early depth), instead
    /// of shading every wall texel and painting objects over it. Ties go by index, so the order
    /// is deterministic and every method uses the same one (equal depths resolve alike).
    pub fn of(bounds: Vec<(Vec3, Vec3)>, centre: Vec3) -> Self {
        let walls = 6;
        let mut objects: Vec<(f32, u32)> = (walls..bounds.len())
            .map(|i| {
                let (lo, hi) = bounds[i];
                // Distance from the centre to the nearest point of the box (0 inside it).
                let nearest = centre.clamp(lo, hi);
                (nearest.distance_squared(centre), i as u32)
            })
            .collect();
        objects.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let order = (objects.into_iter().map(|(_, i)| i))
            .chain(0..walls as u32)
            .collect();
        Self { bounds, order }
    }

    /// Indices of the drawables whose render-space bounds meet `frustum`, in draw order.
    pub fn visible(&self, frustum: &Frustum) -> Vec<u32> {
        (self.order.iter().copied())
            .filter(|&i| {
                let (lo, hi) = self.bounds[i as usize];
                frustum.intersects_aabb(lo, hi)
            })
            .collect()
    }
}

impl Renderer {
    /// Indices of the drawables whose render-space bounds meet `frustum`, in draw order.
    pub(super) fn visible(&self, frustum: &Frustum) -> Vec<u32> {
        self.drawn.visible(frustum)
    }

    /// Binds `pipeline` with the scene's descriptor set, vertex and index buffers.
    pub(super) fn bind_scene(&self, cmd: vk::CommandBuffer, pipeline: &Pipeline) {
        let d = &self.device.raw;
        // SAFETY (whole block): cmd is recording inside a rendering scope whose attachment
        // formats match the pipeline; buffers and sets are live and not being written.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.pipelines.scene_layout.raw,
                0,
                &[self.resources.scene_set],
                &[],
            );
            d.cmd_bind_vertex_buffers(cmd, 0, &[self.resources.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, self.resources.indices.raw, 0, vk::IndexType::UINT32);
        }
    }

    pub(super) fn push(&self, cmd: vk::CommandBuffer, layout: vk::PipelineLayout, push: Push) {
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
    pub(super) fn draw_objects(
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
                self.pipelines.scene_layout.raw,
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

    /// Draws the mirror's bounding cube with the lookup's colour or direction pipeline, or
    /// one of the sensor ray map's (which read the cube's depth and ids).
    pub(super) fn draw_mirror(&self, cmd: vk::CommandBuffer, output: MirrorOutput, view: u32) {
        let d = &self.device.raw;
        let lookup = &self.mirror.pass;
        let (pipeline, layout, sets) = match output {
            MirrorOutput::Colour | MirrorOutput::LookupDirection => (
                lookup.pipeline(output == MirrorOutput::LookupDirection).raw,
                lookup.layout().raw,
                vec![self.resources.scene_set, lookup.set()],
            ),
            MirrorOutput::RayOrigin | MirrorOutput::RayDirection => {
                let (rays, _) = self
                    .sensor_rays
                    .as_ref()
                    .expect("the ray map's passes are made before a frame that draws them");
                let pipeline = if output == MirrorOutput::RayOrigin {
                    &rays.origin
                } else {
                    &rays.direction
                };
                (
                    pipeline.raw,
                    rays.layout.raw,
                    vec![self.resources.scene_set, rays.set],
                )
            }
        };
        // SAFETY: recording inside a view pass; what set 1 holds is ready for reading (the
        // cube's colour, depth and ids in SHADER_READ_ONLY layout, or the lookup's own data
        // after its barrier).
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
            d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, layout, 0, &sets, &[]);
        }
        self.push(
            cmd,
            layout,
            Push {
                view_index: view,
                ..Push::default()
            },
        );
        // SAFETY: as above; 36 vertices generated by mirror.vert.
        unsafe { d.cmd_draw(cmd, 36, 1, 0, 0) };
    }

    /// The facing of the cube faces: mirrored winding, eye at the cube's centre, near plane
    /// `cube.near` with corners `near * sqrt(3)` away (90-degree faces).
    pub(super) fn cube_facing(&self) -> Facing {
        let reach = self.scene.cube.near_m * 3f32.sqrt();
        self.facing(CUBE_FRONT, self.scene.cube.offset_m, reach)
    }

    /// The facing of a camera view: its near plane's corners are `camera_clearance` from the
    /// eye (`ViewBasis::near_plane_for`).
    pub(super) fn view_facing(&self, view: &crate::scene::camera::ViewBasis) -> Facing {
        let reach = super::camera_clearance(view.eye, self.scene.mirror.radius_m);
        if view.is_orthographic() {
            // The near plane spans the whole image: a drawable within reach of that plane,
            // anywhere across it, may be cut open there.
            let f = view.forward;
            let cull = (self.resources.drawables.iter().zip(&self.drawn.bounds))
                .map(|(d, &(lo, hi))| {
                    let nearest = Vec3::select(f.cmpge(Vec3::ZERO), lo, hi);
                    d.cull_back && f.dot(nearest - view.eye) > reach
                })
                .collect();
            return Facing {
                front: VIEW_FRONT,
                cull,
            };
        }
        self.facing(VIEW_FRONT, view.eye, reach)
    }

    fn facing(&self, front: vk::FrontFace, eye: Vec3, reach: f32) -> Facing {
        let cull = self
            .resources
            .drawables
            .iter()
            .zip(&self.drawn.bounds)
            .map(|(d, &(lo, hi))| {
                // Nearest point of the box to the eye; culling only when it is out of reach.
                d.cull_back && eye.clamp(lo, hi).distance(eye) > reach
            })
            .collect();
        Facing { front, cull }
    }

    /// Front-face winding for the draws that follow (pipelines with dynamic culling).
    pub(super) fn set_front_face(&self, cmd: vk::CommandBuffer, front: vk::FrontFace) {
        // SAFETY: recording; the bound pipeline has FRONT_FACE as dynamic state.
        unsafe { self.device.raw.cmd_set_front_face(cmd, front) };
    }

    /// Back faces culled or not for the draws that follow (pipelines with dynamic culling).
    pub(super) fn set_cull_back(&self, cmd: vk::CommandBuffer, cull: bool) {
        let mode = if cull {
            vk::CullModeFlags::BACK
        } else {
            vk::CullModeFlags::NONE
        };
        // SAFETY: recording; the bound pipeline has CULL_MODE as dynamic state.
        unsafe { self.device.raw.cmd_set_cull_mode(cmd, mode) };
    }

    pub(super) fn begin_rendering(&self, cmd: vk::CommandBuffer, a: &Attachments) {
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

    pub(super) fn end_rendering(&self, cmd: vk::CommandBuffer) {
        // SAFETY: closes the scope opened by begin_rendering on this command buffer.
        unsafe { self.device.raw.cmd_end_rendering(cmd) };
    }

    /// Inside a layered rendering scope: clears colour and depth of the faces in `mask`, and
    /// with `ids` the id cube (attachment 1) too.
    pub(super) fn clear_faces(&self, cmd: vk::CommandBuffer, mask: u8, size: u32, ids: bool) {
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
        let rects: Vec<vk::ClearRect> = (0..6u32)
            .filter(|f| mask & (1 << f) != 0)
            .map(|f| vk::ClearRect {
                rect: vk::Rect2D {
                    offset: vk::Offset2D::default(),
                    extent: vk::Extent2D {
                        width: size,
                        height: size,
                    },
                },
                base_array_layer: f,
                layer_count: 1,
            })
            .collect();
        // SAFETY: inside a rendering scope with 6 layers; the rects lie within it.
        unsafe {
            self.device
                .raw
                .cmd_clear_attachments(cmd, attachments, &rects)
        };
    }

    pub(super) fn set_viewport(&self, cmd: vk::CommandBuffer, x: f32, y: f32, w: f32, h: f32) {
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
