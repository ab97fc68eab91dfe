//! The materials check: `shaders/include/materials.glsl` run by a compute pass at given points,
//! results in full f32. It exists so that a test can hold the CPU reference's twin of the
//! shader functions (`reference::materials`) to float rounding; nothing renders with it.

use std::sync::Arc;

use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;

use super::gpu::{CheckPush, MaterialSample};
use super::Renderer;
use crate::scene::state::SceneState;
use crate::vk::commands::host_read_barrier;
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::Device;
use crate::vk::memory::{Buffer, BufferDesc};
use crate::vk::pipeline::{Pipeline, PipelineLayout};
use crate::vk::GpuError;

/// Invocations per workgroup (`local_size_x` in materials_check.comp).
const GROUP: u32 = 64;

impl Renderer {
    /// `shade(material_albedo(...))` exactly as `scene.frag` computes it, for material
    /// `points[i].0` at the fragment inputs `points[i].1`, with the scene's light. Returns
    /// linear RGB in input order. Each material index must be below the scene's count.
    pub fn evaluate_materials(
        &mut self,
        points: &[(usize, MaterialSample)],
    ) -> Result<Vec<Vec3>, GpuError> {
        if points.is_empty() {
            return Ok(Vec::new()); // (and Vulkan buffers may not be empty)
        }
        let count = self.scene.materials.len();
        if let Some((m, _)) = points.iter().find(|(m, _)| *m >= count) {
            return Err(GpuError::Unsupported(format!(
                "material {m} does not exist (the scene has {count})"
            )));
        }
        // The frame block carries the light; time 0 is as good as any (lights do not move). It
        // reaches the device through a frame slot's uploads, recorded before the dispatches.
        self.acquire_slot()?;
        self.write_frame_buffers(&SceneState::at(&self.scene, 0.0))?;
        // One dispatch per material, so the texture index is dynamically uniform.
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_by_key(|&i| points[i].0);
        let sorted: Vec<MaterialSample> = order.iter().map(|&i| points[i].1).collect();
        let device = &Arc::clone(&self.device);
        let pass = CheckPass::create(device, self.resources.scene_set_layout.raw, &sorted)?;
        // The frame graph orders the uploads (what the dispatches read, the frame block, rests
        // as read by any command once copied); the check's own results place their barrier.
        let cmd = self.begin_frame(&mut super::graph::FrameGraph::default())?;
        pass.record(cmd, self.resources.scene_set, points, &order);
        self.submit_slot_and_wait()?;
        pass.results(&order)
    }
}

/// The check's compute pass: the samples in material order, the results, the pipeline and
/// its sets. Field order is drop order: the pipeline before its layout, the pool before the
/// set layout.
struct CheckPass {
    pipeline: Pipeline,
    layout: PipelineLayout,
    set: vk::DescriptorSet,
    _pool: DescriptorPool,
    _set_layout: DescriptorSetLayout,
    results: Buffer,
    _samples: Buffer,
    device: Arc<Device>,
}

impl CheckPass {
    fn create(
        device: &Arc<Device>,
        scene_set_layout: vk::DescriptorSetLayout,
        sorted: &[MaterialSample],
    ) -> Result<Self, GpuError> {
        let sample_bytes = std::mem::size_of_val(sorted) as u64;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let mut samples = Buffer::create(
            device,
            &BufferDesc::new_cpu_to_gpu(sample_bytes, storage),
            "material samples",
        )?;
        samples.write(sorted)?;
        let results_desc = BufferDesc {
            size: 16 * sorted.len() as u64,
            usage: storage,
            location: MemoryLocation::GpuToCpu,
        };
        let results = Buffer::create(device, &results_desc, "material results")?;
        let storage_binding = |b| {
            let kind = vk::DescriptorType::STORAGE_BUFFER;
            descriptors::binding(b, kind, 1, vk::ShaderStageFlags::COMPUTE)
        };
        let set_layout = DescriptorSetLayout::create(
            device,
            &[storage_binding(0), storage_binding(1)],
            "check set layout",
        )?;
        let sizes = [vk::DescriptorPoolSize {
            ty: vk::DescriptorType::STORAGE_BUFFER,
            descriptor_count: 2,
        }];
        let pool = DescriptorPool::create(device, 1, &sizes, "check descriptors")?;
        let set = pool.allocate(&set_layout, "check set")?;
        for (binding, buffer) in [(0, &samples), (1, &results)] {
            let kind = vk::DescriptorType::STORAGE_BUFFER;
            descriptors::write_buffer(device, set, binding, kind, buffer.raw);
        }
        let layout = PipelineLayout::create_compute(
            device,
            &[scene_set_layout, set_layout.raw],
            std::mem::size_of::<CheckPush>() as u32,
            "check layout",
        )?;
        let pipeline = Pipeline::create_compute(
            device,
            &layout,
            crate::shaders::MATERIALS_CHECK_COMP,
            "materials check",
        )?;
        Ok(Self {
            pipeline,
            layout,
            set,
            _pool: pool,
            _set_layout: set_layout,
            results,
            _samples: samples,
            device: Arc::clone(device),
        })
    }

    /// One dispatch per run of samples of one material (in `order`), the results then made
    /// visible to the host.
    fn record(
        &self,
        cmd: vk::CommandBuffer,
        scene_set: vk::DescriptorSet,
        points: &[(usize, MaterialSample)],
        order: &[usize],
    ) {
        let d = &self.device.raw;
        // SAFETY (whole block): cmd is recording; the pipeline, sets and buffers are live
        // until after the slot is waited for; the push range matches the layout.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout.raw,
                0,
                &[scene_set, self.set],
                &[],
            );
            let mut first = 0;
            while first < order.len() {
                let material = points[order[first]].0;
                let n = order[first..]
                    .iter()
                    .take_while(|&&i| points[i].0 == material)
                    .count();
                let push = CheckPush {
                    first: first as u32,
                    count: n as u32,
                    material: material as u32,
                    pad: 0,
                };
                d.cmd_push_constants(
                    cmd,
                    self.layout.raw,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    bytemuck::bytes_of(&push),
                );
                d.cmd_dispatch(cmd, (n as u32).div_ceil(GROUP), 1, 1);
                first += n;
            }
        }
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        host_read_barrier(
            &self.device,
            cmd,
            stage,
            vk::AccessFlags2::SHADER_STORAGE_WRITE,
        );
    }

    /// The results (after the frame's fence), back in input order.
    fn results(&self, order: &[usize]) -> Result<Vec<Vec3>, GpuError> {
        let bytes = self.results.mapped()?;
        let mut out = vec![Vec3::ZERO; order.len()];
        for (k, &i) in order.iter().enumerate() {
            let texel = &bytes[16 * k..16 * k + 12];
            let c: [f32; 3] = std::array::from_fn(|j| {
                f32::from_le_bytes(texel[4 * j..4 * j + 4].try_into().expect("4 bytes"))
            });
            out[i] = Vec3::from(c);
        }
        Ok(out)
    }
}
