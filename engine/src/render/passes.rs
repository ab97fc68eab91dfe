//! Command recording for one frame: cube faces, mips, views, readback.

use ash::vk;

use super::draw::{barrier, Attachments, COLOR_OUT, COPY_READ, DEPTH_RW, SAMPLED};
use super::gpu::Push;
use super::resources::{VIEW_OBSERVER, VIEW_PAIR_LEFT, VIEW_PAIR_RIGHT, VIEW_SENSOR};
use super::sensor_rays::MirrorOutput;
use super::targets::{ViewTarget, DEPTH_FORMAT, DIRECTION_FORMAT, VIEW_FORMAT};
use super::*;
use crate::scene::camera::{Frustum, ViewBasis};
use crate::vk::commands::host_read_barrier;

/// The view images a frame can read back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    Observer,
    Sensor,
    Pair,
    ObserverDirection,
    SensorDirection,
    SensorRayOrigin,
    SensorRayDirection,
}

/// Where each read-back view image sits in the readback buffer (after the cube faces).
#[derive(Debug, Default, Clone)]
pub(super) struct Copies {
    items: Vec<(Slot, u64)>,
}

/// Bytes per texel of a view target's colour format.
fn texel_bytes(slot: Slot) -> u64 {
    match slot {
        Slot::ObserverDirection
        | Slot::SensorDirection
        | Slot::SensorRayOrigin
        | Slot::SensorRayDirection => 16,
        _ => 8,
    }
}

impl Renderer {
    /// Observer, sensor and the side-by-side pair, each: culled scene draws, then the mirror.
    /// The view targets `readback` asks for, in readback order.
    fn view_slots(&self, readback: Readback) -> Vec<(Slot, &ViewTarget)> {
        let mut slots = Vec::new();
        if readback.views {
            slots.push((Slot::Observer, &self.observer_target));
            slots.push((Slot::Sensor, &self.sensor_target));
            slots.push((Slot::Pair, &self.pair_target));
        }
        if readback.directions {
            slots.push((Slot::ObserverDirection, &self.observer_direction_target));
            slots.push((Slot::SensorDirection, &self.sensor_direction_target));
        }
        if let (true, Some([origin, direction])) = (readback.rays, &self.sensor_ray_targets) {
            slots.push((Slot::SensorRayOrigin, origin));
            slots.push((Slot::SensorRayDirection, direction));
        }
        slots
    }

    /// Observer, sensor and the side-by-side pair (culled scene draws, then the mirror), and
    /// with `readback.directions` the lookup-direction passes of observer and sensor.
    /// With `display`, only that view is drawn and nothing is copied (the viewer's frame).
    pub(super) fn record_views(
        &self,
        cmd: vk::CommandBuffer,
        views: &[ViewBasis],
        readback: Readback,
        display: Option<super::display::DisplayView>,
    ) -> Copies {
        let slots = match display {
            Some(view) => vec![self.display_slot(view)],
            None => self.view_slots(readback),
        };
        // A colour view that is not drawn still gets its timestamp, so every query has a
        // result: those before the first drawn view in slot order are written first, the
        // others after the drawn views, so the drawn view's time is its own.
        let colour = [
            (Slot::Observer, TS_OBSERVER),
            (Slot::Sensor, TS_SENSOR),
            (Slot::Pair, TS_PAIR),
        ];
        let drawn = |s: Slot| slots.iter().any(|&(d, _)| d == s);
        let first = colour
            .iter()
            .position(|&(s, _)| drawn(s))
            .unwrap_or(colour.len());
        let undrawn = |range: std::ops::Range<usize>| {
            colour[range]
                .iter()
                .filter(|&&(s, _)| !drawn(s))
                .map(|&(_, ts)| ts)
                .collect::<Vec<u32>>()
        };
        let (before, after) = (undrawn(0..first), undrawn(first..colour.len()));
        let mark = |stamps: &[u32]| {
            if let Some(q) = &self.timestamps {
                for &ts in stamps {
                    q.write_timestamp(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, ts);
                }
            }
        };
        mark(&before);
        let p = &self.pipelines;
        let mut copies = Copies::default();
        let mut offset = self.cube_readback_bytes(readback);
        for (slot, target) in slots {
            use MirrorOutput::*;
            let (ids, ts, stats, output, name): (&[u32], _, _, _, _) = match slot {
                Slot::Observer => (
                    &[VIEW_OBSERVER],
                    Some(TS_OBSERVER),
                    Some(6),
                    Colour,
                    "observer",
                ),
                Slot::Sensor => (&[VIEW_SENSOR], Some(TS_SENSOR), Some(7), Colour, "sensor"),
                Slot::Pair => (
                    &[VIEW_PAIR_LEFT, VIEW_PAIR_RIGHT],
                    Some(TS_PAIR),
                    Some(8),
                    Colour,
                    "views",
                ),
                Slot::ObserverDirection => (
                    &[VIEW_OBSERVER],
                    None,
                    None,
                    LookupDirection,
                    "observer directions",
                ),
                Slot::SensorDirection => (
                    &[VIEW_SENSOR],
                    None,
                    None,
                    LookupDirection,
                    "sensor directions",
                ),
                Slot::SensorRayOrigin => (&[VIEW_SENSOR], None, None, RayOrigin, "sensor rays"),
                Slot::SensorRayDirection => (
                    &[VIEW_SENSOR],
                    None,
                    None,
                    RayDirection,
                    "sensor ray directions",
                ),
            };
            let scene = if output == Colour {
                &p.view_scene
            } else {
                &p.depth_only
            };
            self.record_view(cmd, target, ids, views, (scene, output), stats, name);
            if let (Some(q), Some(ts)) = (&self.timestamps, ts) {
                q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_GRAPHICS, ts);
            }
            if display.is_some() {
                continue;
            }
            copies.items.push((slot, offset));
            offset += u64::from(target.width) * u64::from(target.height) * texel_bytes(slot);
        }
        mark(&after);
        copies
    }

    #[allow(clippy::too_many_arguments)]
    fn record_view(
        &self,
        cmd: vk::CommandBuffer,
        target: &ViewTarget,
        view_ids: &[u32],
        views: &[ViewBasis],
        (scene_pipeline, output): (&Pipeline, MirrorOutput),
        stats_slot: Option<u32>,
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
        if let (Some(q), Some(slot)) = (&self.statistics, stats_slot) {
            q.begin(cmd, slot);
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
                store_depth: false,
            },
        );
        for &v in view_ids {
            let half = (PAIR_SIZE[0] / 2) as f32;
            let vp = match v {
                VIEW_PAIR_LEFT => [0.0, 0.0, half, PAIR_SIZE[1] as f32],
                VIEW_PAIR_RIGHT => [half, 0.0, half, PAIR_SIZE[1] as f32],
                _ => [0.0, 0.0, target.width as f32, target.height as f32],
            };
            self.set_viewport(cmd, vp[0], vp[1], vp[2], vp[3]);
            let frustum = Frustum::new(
                &views[v as usize],
                views[v as usize].near_plane_for(CAMERA_NEAR_M),
                f32::INFINITY,
            );
            let visible = self.visible(&frustum);
            let push = Push {
                view_index: v,
                ..Push::default()
            };
            let facing = self.view_facing(&views[v as usize]);
            self.draw_objects(cmd, scene_pipeline, push, &visible, &facing);
            self.draw_mirror(cmd, output, v);
        }
        self.end_rendering(cmd);
        if let (Some(q), Some(slot)) = (&self.statistics, stats_slot) {
            q.end(cmd, slot);
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

    /// The slot and target of a view drawn for a window.
    fn display_slot(&self, view: super::display::DisplayView) -> (Slot, &ViewTarget) {
        use super::display::DisplayView;
        match view {
            DisplayView::Pair => (Slot::Pair, &self.pair_target),
            DisplayView::Observer => (Slot::Observer, &self.observer_target),
            DisplayView::Sensor => (Slot::Sensor, &self.sensor_target),
        }
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
        for (slot, t) in self.view_slots(readback) {
            bytes += u64::from(t.width) * u64::from(t.height) * texel_bytes(slot);
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
            // Out of sampling for the copy and back: the cube stays valid for the next frame.
            let sampled = (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED);
            let source = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, COPY_READ);
            let transition =
                |from, to| image_barriers(dev, cmd, &[barrier(cube.color.raw, mip0, from, to)]);
            transition(sampled, source);
            copy(cube.color.raw, 6, cube.size, cube.size, 0);
            transition(source, sampled);
        }
        for ((_, t), &(_, at)) in self.view_slots(readback).into_iter().zip(&copies.items) {
            copy(t.color.raw, 1, t.width, t.height, at);
        }
        // The host reads the buffer after the fence (read_images).
        host_read_barrier(
            dev,
            cmd,
            vk::PipelineStageFlags2::COPY,
            vk::AccessFlags2::TRANSFER_WRITE,
        );
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
        for ((slot, t), &(_, at)) in self.view_slots(readback).into_iter().zip(&copies.items) {
            let n = u64::from(t.width) * u64::from(t.height) * texel_bytes(slot);
            let b = &bytes[at as usize..(at + n) as usize];
            let (w, h) = (t.width, t.height);
            match slot {
                Slot::Observer => images.observer = Some(decode_f16(b, w, h)),
                Slot::Sensor => images.sensor = Some(decode_f16(b, w, h)),
                Slot::Pair => images.pair = Some(decode_f16(b, w, h)),
                Slot::ObserverDirection => images.observer_direction = Some(decode_f32(b, w, h)),
                Slot::SensorDirection => images.sensor_direction = Some(decode_f32(b, w, h)),
                Slot::SensorRayOrigin => images.sensor_ray_origin = Some(decode_f32(b, w, h)),
                Slot::SensorRayDirection => images.sensor_ray_direction = Some(decode_f32(b, w, h)),
            }
        }
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
            if self.per_face_marks() {
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
            if update && self.per_face_marks() {
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

/// Decodes tightly packed texels of `texel_bytes` bytes each with `texel` into an image.
fn decode(
    bytes: &[u8],
    w: u32,
    h: u32,
    texel_bytes: usize,
    texel: impl Fn(&[u8]) -> [f32; 4],
) -> RgbaImage {
    let pixels = bytes.chunks_exact(texel_bytes).map(texel).collect();
    RgbaImage {
        width: w,
        height: h,
        pixels,
    }
}

/// RGBA16F texels.
fn decode_f16(bytes: &[u8], w: u32, h: u32) -> RgbaImage {
    decode(bytes, w, h, 8, |p| {
        std::array::from_fn(|c| half::f16::from_le_bytes([p[2 * c], p[2 * c + 1]]).to_f32())
    })
}

/// RGBA32F texels.
fn decode_f32(bytes: &[u8], w: u32, h: u32) -> RgbaImage {
    decode(bytes, w, h, 16, |p| {
        std::array::from_fn(|c| {
            f32::from_le_bytes([p[4 * c], p[4 * c + 1], p[4 * c + 2], p[4 * c + 3]])
        })
    })
}

/// RGBA8 unorm texels.
fn decode_unorm8(bytes: &[u8], w: u32, h: u32) -> RgbaImage {
    decode(bytes, w, h, 4, |p| {
        std::array::from_fn(|c| f32::from(p[c]) / 255.0)
    })
}

/// The scene vertex buffer's layout: `gpu::Vertex` (position, normal, uv) at binding 0.
pub(super) fn vertex_layout() -> (
    [vk::VertexInputBindingDescription; 1],
    [vk::VertexInputAttributeDescription; 3],
) {
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
    (bindings, attributes)
}

/// A scene pipeline: `stages` (vertex or mesh stages, then a fragment shader), the scene's
/// vertex layout unless the stages include a mesh shader, reverse-Z depth, culling set per
/// draw. Used by the views and, through `methods::MethodContext`, by every cube method.
pub(super) fn scene_pipeline(
    device: &Arc<Device>,
    layout: &PipelineLayout,
    stages: &[ShaderStage<'_>],
    color_format: vk::Format,
    view_mask: u32,
    name: &str,
) -> Result<Pipeline, GpuError> {
    scene_pipeline_with_writes(device, layout, stages, color_format, view_mask, true, name)
}

fn scene_pipeline_with_writes(
    device: &Arc<Device>,
    layout: &PipelineLayout,
    stages: &[ShaderStage<'_>],
    color_format: vk::Format,
    view_mask: u32,
    color_writes: bool,
    name: &str,
) -> Result<Pipeline, GpuError> {
    let (bindings, attributes) = vertex_layout();
    let mesh = stages
        .iter()
        .any(|s| s.stage.contains(vk::ShaderStageFlags::MESH_EXT));
    Pipeline::create_graphics(
        device,
        layout,
        &GraphicsPipelineDesc {
            stages,
            vertex_bindings: if mesh { &[] } else { &bindings },
            vertex_attributes: if mesh { &[] } else { &attributes },
            color_format,
            depth_format: DEPTH_FORMAT,
            // Set per draw: room walls are seen from inside and meshes may be open.
            cull_mode: vk::CullModeFlags::NONE,
            dynamic_culling: true,
            depth_compare: vk::CompareOp::GREATER,
            depth_write: true,
            color_writes,
            view_mask,
            rasterizer_discard: false,
        },
        name,
    )
}

/// A mirror pipeline: the bounding cube of `mirror.vert` and `fragment` (a lookup's shader),
/// reverse-Z depth written from the sphere's hit point. Each lookup makes its own
/// (`lookups::LookupPass`).
pub(crate) fn mirror_pipeline(
    device: &Arc<Device>,
    layout: &PipelineLayout,
    fragment: &[u32],
    color_format: vk::Format,
    name: &str,
) -> Result<Pipeline, GpuError> {
    Pipeline::create_graphics(
        device,
        layout,
        &GraphicsPipelineDesc {
            stages: &[
                ShaderStage {
                    stage: vk::ShaderStageFlags::VERTEX,
                    spirv: crate::shaders::MIRROR_VERT,
                },
                ShaderStage {
                    stage: vk::ShaderStageFlags::FRAGMENT,
                    spirv: fragment,
                },
            ],
            vertex_bindings: &[],
            vertex_attributes: &[],
            color_format,
            depth_format: DEPTH_FORMAT,
            // Back faces of the bounding cube: still on screen when the camera is inside it.
            cull_mode: vk::CullModeFlags::FRONT,
            dynamic_culling: false,
            depth_compare: vk::CompareOp::GREATER,
            depth_write: true,
            color_writes: true,
            view_mask: 0,
            rasterizer_discard: false,
        },
        name,
    )
}

/// The view and depth-only pipelines (reverse-Z depth everywhere); the cube's pipeline
/// belongs to its method, the mirror's to its lookup.
pub(super) fn create_pipelines(
    device: &Arc<Device>,
    res: &SceneResources,
) -> Result<Pipelines, GpuError> {
    let push = std::mem::size_of::<Push>() as u32;
    let scene_layout =
        PipelineLayout::create(device, &[res.scene_set_layout.raw], push, "scene layout")?;
    // The views use the plain vertex shader and RGBA16F. The direction pass lays down depth
    // only, then the lookup writes the mirror's directions in full float.
    let scene_stages = [
        ShaderStage {
            stage: vk::ShaderStageFlags::VERTEX,
            spirv: crate::shaders::SCENE_VERT,
        },
        ShaderStage {
            stage: vk::ShaderStageFlags::FRAGMENT,
            spirv: crate::shaders::SCENE_FRAG,
        },
    ];
    let view_scene = scene_pipeline(
        device,
        &scene_layout,
        &scene_stages,
        VIEW_FORMAT,
        0,
        "scene pipeline (views)",
    )?;
    let depth_only = scene_pipeline_with_writes(
        device,
        &scene_layout,
        &scene_stages,
        DIRECTION_FORMAT,
        0,
        false,
        "depth-only pipeline (directions)",
    )?;
    let [ray_origin, ray_direction] = super::sensor_rays::create_pipelines(device, &scene_layout)?;
    Ok(Pipelines {
        view_scene,
        depth_only,
        ray_origin,
        ray_direction,
        scene_layout,
    })
}
