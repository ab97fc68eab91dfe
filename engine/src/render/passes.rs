//! Command recording for one frame: cube faces, mips, views, readback.

use ash::vk;

use super::camera::{Frustum, ViewBasis};
use super::draw::{barrier, Attachments, COLOR_OUT, COPY_READ, DEPTH_RW, SAMPLED};
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

impl Renderer {
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
            &Attachments {
                color: target.color_view.raw,
                depth: target.depth_view.raw,
                size: [target.width, target.height],
                layers: 1,
                view_mask: 0,
                clear: true,
            },
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
            self.draw_objects(
                cmd,
                &self.pipelines.view_scene,
                Push {
                    view_index: v,
                    ..Push::default()
                },
                &visible,
            );
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
            if self.method == methods::Method::SixPass {
                report.gpu_face_ms = Some(std::array::from_fn(|f| {
                    ms(TS_FACE0 + f as u32 - 1, TS_FACE0 + f as u32)
                }));
            }
            report.gpu_fill_ms = Some(ms(TS_START, TS_FILL));
            report.gpu_cube_ms = Some(ms(TS_START, TS_MIPS));
            report.gpu_mips_ms = Some(ms(TS_FILL, TS_MIPS));
            report.gpu_observer_ms = Some(ms(TS_MIPS, TS_OBSERVER));
            report.gpu_sensor_ms = Some(ms(TS_OBSERVER, TS_SENSOR));
            report.gpu_pair_ms = Some(ms(TS_SENSOR, TS_PAIR));
        }
        if let Some(q) = &self.statistics {
            // Only queries begun this frame have results. Six-pass uses slots 0..6 (one per
            // dirty face), the one-pass methods slot 0.
            if update && self.method == methods::Method::SixPass {
                let mut faces = [PipelineStats::default(); 6];
                let mut total = PipelineStats::default();
                for f in 0..6u32 {
                    if report.face_mask & (1 << f) != 0 {
                        faces[f as usize] = q.statistics(f, 1)?[0];
                        total += faces[f as usize];
                    }
                }
                report.face_stats = Some(faces);
                report.fill_stats = Some(total);
            } else if update {
                report.fill_stats = Some(q.statistics(0, 1)?[0]);
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
    method: methods::Method,
    gs_invocations: bool,
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
    let scene_pipeline = |color_format, method: methods::Method, name| {
        let stages: Vec<ShaderStage> = methods::stages(method, gs_invocations)
            .into_iter()
            .map(|(stage, spirv)| ShaderStage { stage, spirv })
            .collect();
        Pipeline::create_graphics(
            device,
            &scene_layout,
            &GraphicsPipelineDesc {
                stages: &stages,
                vertex_bindings: &bindings,
                vertex_attributes: &attributes,
                color_format,
                depth_format: DEPTH_FORMAT,
                // Room walls are seen from inside and meshes may be open: draw both sides.
                cull_mode: vk::CullModeFlags::NONE,
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
                view_mask: method.layers_and_view_mask().1,
            },
            name,
        )
    };
    // The views always use the plain vertex shader and RGBA16F; the cube uses its method's
    // shaders and the cube's format.
    let cube_name = format!("cube pipeline ({method})");
    let cube = scene_pipeline(cube_format, method, &cube_name)?;
    let view_scene = scene_pipeline(
        VIEW_FORMAT,
        methods::Method::SixPass,
        "scene pipeline (views)",
    )?;
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
        cube,
        view_scene,
        mirror,
        scene_layout,
        mirror_layout,
    })
}
