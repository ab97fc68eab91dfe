//! What comes back from the GPU after a frame: the readback buffer's layout (cube faces, then
//! the view images in slot order), the copies into it, the decoding of its texels, and the
//! timestamp and statistics queries.

use ash::vk;

use super::draw::{barrier, COPY_READ, SAMPLED};
use super::passes::{copy_offset, texel_bytes, Copies, Slot};
use super::*;
use crate::vk::commands::host_read_barrier;

impl Renderer {
    pub(super) fn cube_readback_bytes(&self, readback: Readback) -> u64 {
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
        for (slot, t) in self.views.slots(readback) {
            bytes =
                copy_offset(bytes) + u64::from(t.width) * u64::from(t.height) * texel_bytes(slot);
        }
        bytes
    }

    /// Makes the current slot's readback buffer large enough for `readback` (replacing it is
    /// safe: the slot's previous frame has finished).
    pub(super) fn grow_readback(&mut self, readback: Readback) -> Result<(), GpuError> {
        let bytes = self.readback_size(readback);
        let slot = self.frames.current();
        if bytes == 0 || slot.readback.as_ref().is_some_and(|b| b.size >= bytes) {
            return Ok(());
        }
        budget::check_buffer(&self.device, "this frame's readback", bytes)?;
        let buffer = Buffer::create(&self.device, &BufferDesc::new_readback(bytes), "readback")?;
        self.frames.current_mut().readback = Some(buffer);
        Ok(())
    }

    /// Copies mip 0 of the cube faces and the view images into the readback buffer.
    pub(super) fn record_readback(
        &self,
        cmd: vk::CommandBuffer,
        readback: Readback,
        copies: &Copies,
    ) {
        let Some(buffer) = &self.frames.current().readback else {
            return;
        };
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
        for ((_, t), &(_, at)) in self.views.slots(readback).into_iter().zip(&copies.items) {
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

    /// Decodes a finished frame's pixels from its slot's readback `buffer`.
    pub(super) fn read_images(
        &self,
        buffer: Option<&Buffer>,
        readback: Readback,
        copies: &Copies,
    ) -> Result<FrameImages, GpuError> {
        let mut images = FrameImages::default();
        let Some(buffer) = buffer else {
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
        for ((slot, t), &(_, at)) in self.views.slots(readback).into_iter().zip(&copies.items) {
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

    /// The statistics queries a frame reads: after a cube update, the faces six-pass
    /// rendered (a query each) or the one-pass fill's query 0; the views' when asked.
    pub(super) fn stats_read(&self, update: bool, face_mask: u32, views: bool) -> StatsRead {
        let fill = match (update, self.cube_fill.per_face_marks()) {
            (false, _) => 0,
            (true, true) => face_mask & 0x3F,
            (true, false) => 1,
        };
        StatsRead { fill, views }
    }

    /// A finished frame's timestamps and the statistics in `stats`, from the copies its
    /// commands ended with.
    pub(super) fn read_queries(
        &self,
        queries: &FrameQueries,
        report: &mut FrameReport,
        stats: StatsRead,
    ) -> Result<(), GpuError> {
        if let Some(q) = &queries.timestamps {
            let t = q.timestamps_ns(TS_COUNT)?;
            let ms = |a: u32, b: u32| (t[b as usize] - t[a as usize]) / 1e6;
            if self.cube_fill.per_face_marks() {
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
        if let Some(q) = &queries.statistics {
            if stats.fill != 0 && self.cube_fill.per_face_marks() {
                let mut faces = [PipelineStats::default(); 6];
                let mut total = PipelineStats::default();
                for f in 0..6u32 {
                    if stats.fill & (1 << f) != 0 {
                        faces[f as usize] = q.statistics(f, 1)?[0];
                        total += faces[f as usize];
                    }
                }
                report.face_stats = Some(faces);
                report.fill_stats = Some(total);
            } else if stats.fill != 0 {
                report.fill_stats = Some(q.statistics(0, 1)?[0]);
            }
            if stats.views {
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
