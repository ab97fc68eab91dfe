//! The footprint's marking pass (`shaders/footprint_mark.comp.glsl`): each camera view's
//! mirror pixels run the mirror's lookup and footprint filter, marking the cube's tiles each
//! sample may read, and the marks come back to the host. Its own frame and views buffers,
//! written by the host, and its own submission, waited for: the cube fill that follows is
//! planned on the host from the marks, before the frame's command buffer is recorded (the
//! frame's own uploads reach the GPU only when that command buffer runs).

use std::sync::Arc;

use ash::vk;

use super::tiles::Tiles;
use crate::render::gpu::{FootprintPush, FrameData, ViewData};
use crate::shaders::shared::FOOTPRINT_GROUP_SIDE;
use crate::vk::commands::{host_read_barrier, memory_barrier, Submitter};
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::Device;
use crate::vk::memory::{Buffer, BufferDesc};
use crate::vk::pipeline::{Pipeline, PipelineLayout};
use crate::vk::GpuError;

/// The pass and its buffers. Field order is drop order: the pipeline before its layout, the
/// set's pool before its layout.
pub struct MarkPass {
    pipeline: Pipeline,
    layout: PipelineLayout,
    set: vk::DescriptorSet,
    _pool: DescriptorPool,
    _set_layout: DescriptorSetLayout,
    frame: Buffer,
    views: Buffer,
    /// One bit a tile (`Tiles`), zeroed by the pass's first command.
    marks: Buffer,
    face_size: u32,
    device: Arc<Device>,
}

impl MarkPass {
    /// The pass for a cube of `face_size` texels a side and `view_count` views.
    pub fn create(
        device: &Arc<Device>,
        face_size: u32,
        view_count: usize,
    ) -> Result<Self, GpuError> {
        let compute = vk::ShaderStageFlags::COMPUTE;
        let (uniform, storage) = (
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::DescriptorType::STORAGE_BUFFER,
        );
        let set_layout = DescriptorSetLayout::create(
            device,
            &[
                descriptors::binding(0, uniform, 1, compute),
                descriptors::binding(1, storage, 1, compute),
                descriptors::binding(2, storage, 1, compute),
            ],
            "footprint set layout",
        )?;
        let sizes = [
            vk::DescriptorPoolSize {
                ty: uniform,
                descriptor_count: 1,
            },
            vk::DescriptorPoolSize {
                ty: storage,
                descriptor_count: 2,
            },
        ];
        let pool = DescriptorPool::create(device, 1, &sizes, "footprint descriptors")?;
        let set = pool.allocate(&set_layout, "footprint")?;
        let bytes = |n: usize| n as u64;
        let frame = Buffer::create(
            device,
            &BufferDesc::new_cpu_to_gpu(
                bytes(size_of::<FrameData>()),
                vk::BufferUsageFlags::UNIFORM_BUFFER,
            ),
            "footprint frame",
        )?;
        let views = Buffer::create(
            device,
            &BufferDesc::new_cpu_to_gpu(
                bytes(view_count * size_of::<ViewData>()),
                vk::BufferUsageFlags::STORAGE_BUFFER,
            ),
            "footprint views",
        )?;
        let mut marks_desc = BufferDesc::new_readback(bytes(4 * Tiles::words(face_size)));
        marks_desc.usage |= vk::BufferUsageFlags::STORAGE_BUFFER;
        let marks = Buffer::create(device, &marks_desc, "footprint marks")?;
        descriptors::write_buffer(device, set, 0, uniform, frame.raw);
        descriptors::write_buffer(device, set, 1, storage, views.raw);
        descriptors::write_buffer(device, set, 2, storage, marks.raw);
        let push = size_of::<FootprintPush>() as u32;
        let layout =
            PipelineLayout::create_compute(device, &[set_layout.raw], push, "footprint layout")?;
        let spirv = crate::shaders::FOOTPRINT_MARK_COMP;
        let pipeline = Pipeline::create_compute(device, &layout, spirv, "footprint marks")?;
        Ok(Self {
            pipeline,
            layout,
            set,
            _pool: pool,
            _set_layout: set_layout,
            frame,
            views,
            marks,
            face_size,
            device: Arc::clone(device),
        })
    }

    /// The tiles the camera views `marked` (indices into `views`, each with its viewport) read
    /// of a cube of `levels` mip levels, for the frame `frame`: recorded, submitted through
    /// `submitter` and waited for.
    pub fn mark(
        &mut self,
        submitter: &Submitter,
        (frame, views): (&FrameData, &[ViewData]),
        marked: &[u32],
        levels: u32,
    ) -> Result<Tiles, GpuError> {
        self.frame.write(std::slice::from_ref(frame))?;
        self.views.write(views)?;
        let dev = &self.device;
        let cmd = submitter.begin()?;
        dev.begin_label(cmd, "footprint");
        // SAFETY: the buffer is ours alone, and no earlier submission of it is pending (each
        // is waited for).
        unsafe {
            dev.raw
                .cmd_fill_buffer(cmd, self.marks.raw, 0, vk::WHOLE_SIZE, 0)
        };
        let storage = vk::AccessFlags2::from_raw(
            vk::AccessFlags2::SHADER_STORAGE_READ.as_raw()
                | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw(),
        );
        memory_barrier(
            dev,
            cmd,
            (
                vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::TRANSFER_WRITE,
            ),
            (vk::PipelineStageFlags2::COMPUTE_SHADER, storage),
        );
        let (tile, per_side) = Tiles::none(self.face_size).layout();
        // SAFETY: the pipeline and set are live; the set names our three buffers.
        unsafe {
            let bind = vk::PipelineBindPoint::COMPUTE;
            dev.raw.cmd_bind_pipeline(cmd, bind, self.pipeline.raw);
            dev.raw
                .cmd_bind_descriptor_sets(cmd, bind, self.layout.raw, 0, &[self.set], &[]);
        }
        for &v in marked {
            let push = FootprintPush {
                view_index: v,
                face_size: self.face_size,
                levels,
                tile_side: tile,
                tiles_per_side: per_side,
                ..Default::default()
            };
            let size = views[v as usize].viewport;
            let groups = |n: f32| (n as u32).div_ceil(FOOTPRINT_GROUP_SIDE);
            // SAFETY: the push range is the layout's; the shader returns past the viewport.
            unsafe {
                dev.raw.cmd_push_constants(
                    cmd,
                    self.layout.raw,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    bytemuck::bytes_of(&push),
                );
                dev.raw.cmd_dispatch(cmd, groups(size.z), groups(size.w), 1);
            }
        }
        let written = vk::AccessFlags2::SHADER_STORAGE_WRITE;
        host_read_barrier(dev, cmd, vk::PipelineStageFlags2::COMPUTE_SHADER, written);
        dev.end_label(cmd);
        submitter.submit_and_wait()?;
        let bytes = self.marks.mapped()?;
        let words: Vec<u32> = (bytes.chunks_exact(4))
            .map(|w| u32::from_ne_bytes([w[0], w[1], w[2], w[3]]))
            .collect();
        Ok(Tiles::from_words(self.face_size, &words))
    }
}
