//! Command recording for one frame: cube faces, mips, views, readback.

use ash::vk;

use super::camera::{transform_aabb, Frustum, ViewBasis};
use super::gpu::Push;
use super::resources::{VIEW_OBSERVER, VIEW_PAIR_LEFT, VIEW_PAIR_RIGHT, VIEW_SENSOR};
use super::targets::{ViewTarget, DEPTH_FORMAT, VIEW_FORMAT};
use super::*;

/// Where each read-back image sits in the readback buffer.
#[derive(Debug, Default, Clone)]
pub(super) struct Copies {
    observer: Option<u64>,
    sensor: Option<u64>,
    pair: Option<u64>,
}

const COLOR_OUT: (vk::PipelineStageFlags2, vk::AccessFlags2) = (
    vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
    vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
);
const DEPTH_RW: (vk::PipelineStageFlags2, vk::AccessFlags2) = (
    vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS.as_raw()
            | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw(),
    ),
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ.as_raw()
            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw(),
    ),
);
const SAMPLED: (vk::PipelineStageFlags2, vk::AccessFlags2) = (
    vk::PipelineStageFlags2::FRAGMENT_SHADER,
    vk::AccessFlags2::SHADER_SAMPLED_READ,
);
const COPY_READ: (vk::PipelineStageFlags2, vk::AccessFlags2) = (
    vk::PipelineStageFlags2::COPY,
    vk::AccessFlags2::TRANSFER_READ,
);

fn barrier(
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    from: (vk::ImageLayout, (vk::PipelineStageFlags2, vk::AccessFlags2)),
    to: (vk::ImageLayout, (vk::PipelineStageFlags2, vk::AccessFlags2)),
) -> ImageBarrier {
    ImageBarrier {
        image,
        range,
        from: (from.0, from.1 .0, from.1 .1),
        to: (to.0, to.1 .0, to.1 .1),
    }
}

const NOTHING: (vk::PipelineStageFlags2, vk::AccessFlags2) =
    (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);

impl Renderer {
    /// Indices of the drawables whose render-space bounds meet `frustum`.
    fn visible(&self, frustum: &Frustum) -> Vec<u32> {
        self.resources
            .drawables
            .iter()
            .zip(&self.object_matrices)
            .enumerate()
            .filter(|(_, (d, m))| {
                let (lo, hi) = transform_aabb(m, d.bounds_min, d.bounds_max);
                frustum.intersects_aabb(lo, hi)
            })
            .map(|(i, _)| i as u32)
            .collect()
    }

    fn draw_objects(
        &self,
        cmd: vk::CommandBuffer,
        pipeline: &Pipeline,
        view: u32,
        objects: &[u32],
    ) {
        let d = &self.device.raw;
        let p = &self.pipelines;
        // SAFETY (whole block): cmd is recording inside a rendering scope whose attachment
        // formats match the pipeline; buffers and sets are live and not being written.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                p.scene_layout.raw,
                0,
                &[self.resources.scene_set],
                &[],
            );
            d.cmd_bind_vertex_buffers(cmd, 0, &[self.resources.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, self.resources.indices.raw, 0, vk::IndexType::UINT32);
        }
        for &i in objects {
            let draw = &self.resources.drawables[i as usize];
            let push = Push {
                view_index: view,
                object_index: i,
            };
            // SAFETY: as above; the push range covers all graphics stages.
            unsafe {
                d.cmd_push_constants(
                    cmd,
                    p.scene_layout.raw,
                    vk::ShaderStageFlags::ALL_GRAPHICS,
                    0,
                    bytemuck::bytes_of(&push),
                );
                d.cmd_draw_indexed(
                    cmd,
                    draw.index_count,
                    1,
                    draw.first_index,
                    draw.vertex_offset,
                    0,
                );
            }
        }
    }

    fn draw_mirror(&self, cmd: vk::CommandBuffer, view: u32) {
        let d = &self.device.raw;
        let p = &self.pipelines;
        let push = Push {
            view_index: view,
            object_index: 0,
        };
        // SAFETY: recording inside a view pass; the cube is in SHADER_READ_ONLY layout.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, p.mirror.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                p.mirror_layout.raw,
                0,
                &[self.resources.scene_set, self.resources.environment_set],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                p.mirror_layout.raw,
                vk::ShaderStageFlags::ALL_GRAPHICS,
                0,
                bytemuck::bytes_of(&push),
            );
            d.cmd_draw(cmd, 36, 1, 0, 0);
        }
    }

    fn begin_rendering(
        &self,
        cmd: vk::CommandBuffer,
        color: vk::ImageView,
        depth: vk::ImageView,
        w: u32,
        h: u32,
    ) {
        let color_att = [vk::RenderingAttachmentInfo::default()
            .image_view(color)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [0.0, 0.0, 0.0, 1.0],
                },
            })];
        let depth_att = vk::RenderingAttachmentInfo::default()
            .image_view(depth)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            // Depth is only needed within the pass.
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .clear_value(vk::ClearValue {
                // Reverse-Z: 0 is the far plane.
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 0.0,
                    stencil: 0,
                },
            });
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D {
                width: w,
                height: h,
            },
        };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&color_att)
            .depth_attachment(&depth_att);
        // SAFETY: the attachments are in the layouts named above.
        unsafe { self.device.raw.cmd_begin_rendering(cmd, &info) };
    }

    fn set_viewport(&self, cmd: vk::CommandBuffer, x: f32, y: f32, w: f32, h: f32) {
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

    /// Six passes, one per face, each drawing only what its frustum holds; then the mips.
    pub(super) fn record_cube(
        &self,
        cmd: vk::CommandBuffer,
        views: &[ViewBasis],
        report: &mut FrameReport,
    ) {
        let dev = &self.device;
        let cube = &self.cube;
        let mip0 = vk::ImageSubresourceRange {
            level_count: 1,
            ..cube.color.full_range()
        };
        dev.begin_label(cmd, "cube six-pass");
        // Every face is re-rendered in full, so the old contents can be discarded (UNDEFINED).
        image_barriers(
            dev,
            cmd,
            &[
                barrier(
                    cube.color.raw,
                    mip0,
                    (vk::ImageLayout::UNDEFINED, SAMPLED),
                    (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
                ),
                barrier(
                    cube.depth.raw,
                    cube.depth.full_range(),
                    (vk::ImageLayout::UNDEFINED, DEPTH_RW),
                    (vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, DEPTH_RW),
                ),
            ],
        );
        let size = cube.size;
        for face in 0..6u32 {
            dev.begin_label(cmd, &format!("face {}", camera::FACE_NAMES[face as usize]));
            let frustum = Frustum::new(
                &views[face as usize],
                self.scene.cube.near_m,
                self.scene.cube.far_m,
            );
            let visible = self.visible(&frustum);
            report.draws_per_face[face as usize] = visible.len() as u32;
            if let Some(q) = &self.statistics {
                q.begin(cmd, face);
            }
            self.begin_rendering(
                cmd,
                cube.face_views[face as usize].raw,
                cube.depth_views[face as usize].raw,
                size,
                size,
            );
            self.set_viewport(cmd, 0.0, 0.0, size as f32, size as f32);
            self.draw_objects(cmd, &self.pipelines.cube_scene, face, &visible);
            // SAFETY: closes the rendering scope begun above.
            unsafe { dev.raw.cmd_end_rendering(cmd) };
            if let Some(q) = &self.statistics {
                q.end(cmd, face);
            }
            if let Some(q) = &self.timestamps {
                q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_GRAPHICS, 1 + face);
            }
            dev.end_label(cmd);
        }
        report.faces_rendered = 6;
        self.record_mips(cmd);
        if let Some(q) = &self.timestamps {
            q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, TS_MIPS);
        }
        dev.end_label(cmd);
    }

    /// Builds mips 1.. by halving blits (all six layers at once); leaves every level ready
    /// for sampling.
    fn record_mips(&self, cmd: vk::CommandBuffer) {
        let dev = &self.device;
        let cube = &self.cube;
        let levels = cube.mip_levels();
        let level = |m: u32| vk::ImageSubresourceRange {
            base_mip_level: m,
            level_count: 1,
            ..cube.color.full_range()
        };
        if levels == 1 {
            image_barriers(
                dev,
                cmd,
                &[barrier(
                    cube.color.raw,
                    level(0),
                    (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
                    (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED),
                )],
            );
            return;
        }
        dev.begin_label(cmd, "cube mips");
        let blit_write = (
            vk::PipelineStageFlags2::BLIT,
            vk::AccessFlags2::TRANSFER_WRITE,
        );
        let blit_read = (
            vk::PipelineStageFlags2::BLIT,
            vk::AccessFlags2::TRANSFER_READ,
        );
        image_barriers(
            dev,
            cmd,
            &[barrier(
                cube.color.raw,
                level(0),
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
                (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, blit_read),
            )],
        );
        for m in 1..levels {
            image_barriers(
                dev,
                cmd,
                &[barrier(
                    cube.color.raw,
                    level(m),
                    (vk::ImageLayout::UNDEFINED, NOTHING),
                    (vk::ImageLayout::TRANSFER_DST_OPTIMAL, blit_write),
                )],
            );
            let src = (cube.size >> (m - 1)).max(1) as i32;
            let dst = (cube.size >> m).max(1) as i32;
            let layers = |mip| vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: mip,
                base_array_layer: 0,
                layer_count: 6,
            };
            let blit = vk::ImageBlit::default()
                .src_subresource(layers(m - 1))
                .src_offsets([
                    vk::Offset3D::default(),
                    vk::Offset3D {
                        x: src,
                        y: src,
                        z: 1,
                    },
                ])
                .dst_subresource(layers(m))
                .dst_offsets([
                    vk::Offset3D::default(),
                    vk::Offset3D {
                        x: dst,
                        y: dst,
                        z: 1,
                    },
                ]);
            // SAFETY: level m-1 is TRANSFER_SRC, level m is TRANSFER_DST; format supports linear blits.
            unsafe {
                dev.raw.cmd_blit_image(
                    cmd,
                    cube.color.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    cube.color.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[blit],
                    vk::Filter::LINEAR,
                )
            };
            image_barriers(
                dev,
                cmd,
                &[barrier(
                    cube.color.raw,
                    level(m),
                    (vk::ImageLayout::TRANSFER_DST_OPTIMAL, blit_write),
                    (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, blit_read),
                )],
            );
        }
        image_barriers(
            dev,
            cmd,
            &[barrier(
                cube.color.raw,
                cube.color.full_range(),
                (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, blit_read),
                (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED),
            )],
        );
        dev.end_label(cmd);
    }

    /// Observer, sensor and the side-by-side pair, each: culled scene draws, then the mirror.
    pub(super) fn record_views(
        &self,
        cmd: vk::CommandBuffer,
        views: &[ViewBasis],
        readback: Readback,
    ) -> Copies {
        let mut copies = Copies::default();
        if !readback.views {
            // Views are skipped; their timestamps are still written so every query has a result.
            if let Some(q) = &self.timestamps {
                for ts in [TS_OBSERVER, TS_SENSOR, TS_PAIR] {
                    q.write_timestamp(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, ts);
                }
            }
            return copies;
        }
        let targets: [(&ViewTarget, &[u32], u32, &str); 3] = [
            (
                &self.observer_target,
                &[VIEW_OBSERVER],
                TS_OBSERVER,
                "observer",
            ),
            (&self.sensor_target, &[VIEW_SENSOR], TS_SENSOR, "sensor"),
            (
                &self.pair_target,
                &[VIEW_PAIR_LEFT, VIEW_PAIR_RIGHT],
                TS_PAIR,
                "views",
            ),
        ];
        for (slot, (target, view_ids, ts, name)) in targets.iter().enumerate() {
            self.record_view(cmd, target, view_ids, views, 6 + slot as u32, name);
            if let Some(q) = &self.timestamps {
                q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_GRAPHICS, *ts);
            }
        }
        let mut offset = self.cube_readback_bytes(readback);
        for (i, t) in [
            &self.observer_target,
            &self.sensor_target,
            &self.pair_target,
        ]
        .into_iter()
        .enumerate()
        {
            let at = offset;
            offset += u64::from(t.width) * u64::from(t.height) * 8;
            match i {
                0 => copies.observer = Some(at),
                1 => copies.sensor = Some(at),
                _ => copies.pair = Some(at),
            }
        }
        copies
    }

    fn record_view(
        &self,
        cmd: vk::CommandBuffer,
        target: &ViewTarget,
        view_ids: &[u32],
        views: &[ViewBasis],
        stats_slot: u32,
        name: &str,
    ) {
        let dev = &self.device;
        dev.begin_label(cmd, name);
        image_barriers(
            dev,
            cmd,
            &[
                barrier(
                    target.color.raw,
                    target.color.full_range(),
                    (vk::ImageLayout::UNDEFINED, COPY_READ),
                    (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
                ),
                barrier(
                    target.depth.raw,
                    target.depth.full_range(),
                    (vk::ImageLayout::UNDEFINED, DEPTH_RW),
                    (vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, DEPTH_RW),
                ),
            ],
        );
        if let Some(q) = &self.statistics {
            q.begin(cmd, stats_slot);
        }
        self.begin_rendering(
            cmd,
            target.color_view.raw,
            target.depth_view.raw,
            target.width,
            target.height,
        );
        for &v in view_ids {
            let vp = match v {
                VIEW_PAIR_LEFT => [0.0, 0.0, (PAIR_SIZE[0] / 2) as f32, PAIR_SIZE[1] as f32],
                VIEW_PAIR_RIGHT => [
                    (PAIR_SIZE[0] / 2) as f32,
                    0.0,
                    (PAIR_SIZE[0] / 2) as f32,
                    PAIR_SIZE[1] as f32,
                ],
                _ => [0.0, 0.0, target.width as f32, target.height as f32],
            };
            self.set_viewport(cmd, vp[0], vp[1], vp[2], vp[3]);
            let frustum = Frustum::new(&views[v as usize], CAMERA_NEAR_M, f32::INFINITY);
            let visible = self.visible(&frustum);
            self.draw_objects(cmd, &self.pipelines.view_scene, v, &visible);
            self.draw_mirror(cmd, v);
        }
        // SAFETY: closes the rendering scope begun above.
        unsafe { dev.raw.cmd_end_rendering(cmd) };
        if let Some(q) = &self.statistics {
            q.end(cmd, stats_slot);
        }
        image_barriers(
            dev,
            cmd,
            &[barrier(
                target.color.raw,
                target.color.full_range(),
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
                (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, COPY_READ),
            )],
        );
        dev.end_label(cmd);
    }

    fn cube_readback_bytes(&self, readback: Readback) -> u64 {
        if !readback.cube {
            return 0;
        }
        let texel = if self.cube.format == vk::Format::R8G8B8A8_UNORM {
            4
        } else {
            8
        };
        6 * u64::from(self.cube.size) * u64::from(self.cube.size) * texel
    }

    pub(super) fn readback_size(&self, readback: Readback) -> u64 {
        let mut bytes = self.cube_readback_bytes(readback);
        if readback.views {
            for t in [
                &self.observer_target,
                &self.sensor_target,
                &self.pair_target,
            ] {
                bytes += u64::from(t.width) * u64::from(t.height) * 8;
            }
        }
        bytes
    }

    /// Copies mip 0 of the cube faces and the view images into the readback buffer.
    pub(super) fn record_readback(
        &self,
        cmd: vk::CommandBuffer,
        readback: Readback,
        copies: &Copies,
    ) {
        let Some(buffer) = &self.readback else { return };
        let dev = &self.device;
        let copy = |image: vk::Image, layers: u32, w: u32, h: u32, offset: u64| {
            let region = vk::BufferImageCopy::default()
                .buffer_offset(offset)
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: layers,
                })
                .image_extent(vk::Extent3D {
                    width: w,
                    height: h,
                    depth: 1,
                });
            // SAFETY: the image is in TRANSFER_SRC layout and the buffer has room (readback_size).
            unsafe {
                dev.raw.cmd_copy_image_to_buffer(
                    cmd,
                    image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    buffer.raw,
                    &[region],
                )
            };
        };
        if readback.cube {
            let cube = &self.cube;
            let mip0 = vk::ImageSubresourceRange {
                level_count: 1,
                ..cube.color.full_range()
            };
            image_barriers(
                dev,
                cmd,
                &[barrier(
                    cube.color.raw,
                    mip0,
                    (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED),
                    (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, COPY_READ),
                )],
            );
            copy(cube.color.raw, 6, cube.size, cube.size, 0);
            image_barriers(
                dev,
                cmd,
                &[barrier(
                    cube.color.raw,
                    mip0,
                    (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, COPY_READ),
                    (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED),
                )],
            );
        }
        for (t, at) in [
            (&self.observer_target, copies.observer),
            (&self.sensor_target, copies.sensor),
            (&self.pair_target, copies.pair),
        ] {
            if let Some(at) = at {
                copy(t.color.raw, 1, t.width, t.height, at);
            }
        }
    }

    pub(super) fn read_images(
        &self,
        readback: Readback,
        copies: &Copies,
    ) -> Result<FrameImages, GpuError> {
        let mut images = FrameImages::default();
        let Some(buffer) = &self.readback else {
            return Ok(images);
        };
        let bytes = buffer.mapped()?;
        if readback.cube {
            let s = self.cube.size;
            let unorm = self.cube.format == vk::Format::R8G8B8A8_UNORM;
            let face_bytes = (s * s) as usize * if unorm { 4 } else { 8 };
            images.cube = Some(
                (0..6)
                    .map(|f| {
                        let b = &bytes[f * face_bytes..(f + 1) * face_bytes];
                        if unorm {
                            decode_unorm8(b, s, s)
                        } else {
                            decode_f16(b, s, s)
                        }
                    })
                    .collect(),
            );
        }
        let decode = |t: &ViewTarget, at: Option<u64>| {
            at.map(|at| {
                let n = u64::from(t.width) * u64::from(t.height) * 8;
                decode_f16(&bytes[at as usize..(at + n) as usize], t.width, t.height)
            })
        };
        images.observer = decode(&self.observer_target, copies.observer);
        images.sensor = decode(&self.sensor_target, copies.sensor);
        images.pair = decode(&self.pair_target, copies.pair);
        Ok(images)
    }

    pub(super) fn read_queries(
        &self,
        report: &mut FrameReport,
        update: bool,
        views: bool,
    ) -> Result<(), GpuError> {
        if let Some(q) = &self.timestamps {
            let t = q.timestamps_ns(TS_COUNT)?;
            let ms = |a: u32, b: u32| (t[b as usize] - t[a as usize]) / 1e6;
            report.gpu_face_ms = Some(std::array::from_fn(|f| ms(f as u32, f as u32 + 1)));
            report.gpu_cube_ms = Some(ms(TS_START, TS_MIPS));
            report.gpu_mips_ms = Some(ms(6, TS_MIPS));
            report.gpu_observer_ms = Some(ms(TS_MIPS, TS_OBSERVER));
            report.gpu_sensor_ms = Some(ms(TS_OBSERVER, TS_SENSOR));
            report.gpu_pair_ms = Some(ms(TS_SENSOR, TS_PAIR));
        }
        if let Some(q) = &self.statistics {
            // Queries that were not begun this frame have no results: read only those used.
            // Only queries begun this frame have results.
            if update {
                let s = q.statistics(0, 6)?;
                report.face_stats = Some(std::array::from_fn(|f| s[f]));
            }
            if views {
                let s = q.statistics(6, 3)?;
                report.view_stats = Some(std::array::from_fn(|v| s[v]));
            }
        }
        Ok(())
    }
}

fn decode_f16(bytes: &[u8], w: u32, h: u32) -> RgbaImage {
    let pixels = bytes
        .chunks_exact(8)
        .map(|p| {
            std::array::from_fn(|c| half::f16::from_le_bytes([p[2 * c], p[2 * c + 1]]).to_f32())
        })
        .collect();
    RgbaImage {
        width: w,
        height: h,
        pixels,
    }
}

fn decode_unorm8(bytes: &[u8], w: u32, h: u32) -> RgbaImage {
    let pixels = bytes
        .chunks_exact(4)
        .map(|p| std::array::from_fn(|c| f32::from(p[c]) / 255.0))
        .collect();
    RgbaImage {
        width: w,
        height: h,
        pixels,
    }
}

/// The scene and mirror pipelines, both drawing into RGBA16F colour with reverse-Z depth.
pub(super) fn create_pipelines(
    device: &Arc<Device>,
    res: &SceneResources,
    cube_format: vk::Format,
) -> Result<Pipelines, GpuError> {
    let push = std::mem::size_of::<Push>() as u32;
    let scene_layout =
        PipelineLayout::create(device, &[res.scene_set_layout.raw], push, "scene layout")?;
    let mirror_layout = PipelineLayout::create(
        device,
        &[res.scene_set_layout.raw, res.environment_set_layout.raw],
        push,
        "mirror layout",
    )?;
    let bindings = [vk::VertexInputBindingDescription {
        binding: 0,
        stride: std::mem::size_of::<gpu::Vertex>() as u32,
        input_rate: vk::VertexInputRate::VERTEX,
    }];
    let attr = |location, format, offset| vk::VertexInputAttributeDescription {
        location,
        binding: 0,
        format,
        offset,
    };
    let attributes = [
        attr(0, vk::Format::R32G32B32_SFLOAT, 0),
        attr(1, vk::Format::R32G32B32_SFLOAT, 12),
        attr(2, vk::Format::R32G32_SFLOAT, 24),
    ];
    let scene_pipeline = |color_format, name| {
        Pipeline::create_graphics(
            device,
            &scene_layout,
            &GraphicsPipelineDesc {
                stages: &[
                    ShaderStage {
                        stage: vk::ShaderStageFlags::VERTEX,
                        spirv: crate::shaders::SCENE_VERT,
                    },
                    ShaderStage {
                        stage: vk::ShaderStageFlags::FRAGMENT,
                        spirv: crate::shaders::SCENE_FRAG,
                    },
                ],
                vertex_bindings: &bindings,
                vertex_attributes: &attributes,
                color_format,
                depth_format: DEPTH_FORMAT,
                // Room walls are seen from inside and meshes may be open: draw both sides.
                cull_mode: vk::CullModeFlags::NONE,
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
                view_mask: 0,
            },
            name,
        )
    };
    // Two pipelines because the cube may be RGBA8 while views are always RGBA16F.
    let cube_scene = scene_pipeline(cube_format, "scene pipeline (cube)")?;
    let view_scene = scene_pipeline(VIEW_FORMAT, "scene pipeline (views)")?;
    let mirror = Pipeline::create_graphics(
        device,
        &mirror_layout,
        &GraphicsPipelineDesc {
            stages: &[
                ShaderStage {
                    stage: vk::ShaderStageFlags::VERTEX,
                    spirv: crate::shaders::MIRROR_VERT,
                },
                ShaderStage {
                    stage: vk::ShaderStageFlags::FRAGMENT,
                    spirv: crate::shaders::MIRROR_FRAG,
                },
            ],
            vertex_bindings: &[],
            vertex_attributes: &[],
            color_format: VIEW_FORMAT,
            depth_format: DEPTH_FORMAT,
            // Back faces of the bounding cube: still on screen when the camera is inside it.
            cull_mode: vk::CullModeFlags::FRONT,
            depth_compare: vk::CompareOp::GREATER,
            depth_write: true,
            view_mask: 0,
        },
        "mirror pipeline",
    )?;
    Ok(Pipelines {
        cube_scene,
        view_scene,
        mirror,
        scene_layout,
        mirror_layout,
    })
}
