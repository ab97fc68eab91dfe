//! Buffers and their memory (through `gpu-allocator`).

use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::commands::Submitter;
use super::device::Device;
use super::{GpuError, VkContext};

/// What a buffer is for and where it lives.
#[derive(Debug, Clone)]
pub struct BufferDesc {
    pub size: u64,
    pub usage: vk::BufferUsageFlags,
    pub location: MemoryLocation,
}

impl BufferDesc {
    /// Written by the CPU every frame or once, read by the GPU (mapped, host-coherent).
    pub fn new_cpu_to_gpu(size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self {
            size,
            usage,
            location: MemoryLocation::CpuToGpu,
        }
    }

    /// Read by the GPU only, in its fastest memory (filled through [`Upload`]).
    pub fn new_device_local(size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self {
            size,
            usage: usage | vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuOnly,
        }
    }

    /// Written by the GPU, read back by the CPU (mapped).
    pub fn new_readback(size: u64) -> Self {
        Self {
            size,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuToCpu,
        }
    }
}

/// A buffer and its memory; both freed on drop.
pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    /// `Option` only so that `Drop` can hand it back to the allocator.
    allocation: Option<Allocation>,
    device: Arc<Device>,
}

impl Buffer {
    pub fn create(device: &Arc<Device>, desc: &BufferDesc, name: &str) -> Result<Self, GpuError> {
        // Zero-sized buffers are invalid in Vulkan; callers with nothing to store get 16 bytes.
        let size = desc.size.max(16);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: raw was just created on this device.
        let requirements = unsafe { device.raw.get_buffer_memory_requirements(raw) };
        let allocation = device
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: desc.location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| {
                // SAFETY: the buffer is unused and bound to nothing.
                unsafe { device.raw.destroy_buffer(raw, None) };
                GpuError::Alloc {
                    name: name.into(),
                    source,
                }
            })?;
        let buffer = Self {
            raw,
            size,
            allocation: Some(allocation),
            device: Arc::clone(device),
        };
        let a = buffer.allocation();
        // SAFETY: memory and offset come from an allocation sized for this buffer.
        unsafe { device.raw.bind_buffer_memory(raw, a.memory(), a.offset()) }
            .vk("vkBindBufferMemory")?;
        device.set_name(raw, name);
        Ok(buffer)
    }

    fn allocation(&self) -> &Allocation {
        self.allocation
            .as_ref()
            .expect("a buffer's allocation lives until drop")
    }

    /// The mapped bytes of a CPU-visible buffer.
    pub fn mapped(&self) -> Result<&[u8], GpuError> {
        let a = self.allocation();
        let ptr = a
            .mapped_ptr()
            .ok_or_else(|| GpuError::Unsupported("buffer is not host-visible".into()))?;
        // SAFETY: the mapping covers `a.size()` bytes and lives as long as the allocation;
        // the caller waited for the GPU writes (fence) before reading.
        Ok(unsafe { std::slice::from_raw_parts(ptr.as_ptr().cast::<u8>(), a.size() as usize) })
    }

    /// Copies `data` to the start of a CPU-visible buffer.
    pub fn write<T: bytemuck::Pod>(&mut self, data: &[T]) -> Result<(), GpuError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let a = self
            .allocation
            .as_mut()
            .expect("a buffer's allocation lives until drop");
        let slice = a
            .mapped_slice_mut()
            .ok_or_else(|| GpuError::Unsupported("buffer is not host-visible".into()))?;
        if bytes.len() > slice.len() {
            return Err(GpuError::Unsupported(format!(
                "write of {} bytes into a {}-byte buffer",
                bytes.len(),
                slice.len()
            )));
        }
        slice[..bytes.len()].copy_from_slice(bytes);
        Ok(())
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: the renderer waited on the last fence that used this buffer.
        unsafe { self.device.raw.destroy_buffer(self.raw, None) };
        if let Some(a) = self.allocation.take() {
            let _ = self.device.allocator().free(a);
        }
    }
}

/// Fills device-local buffers with data that does not change (scene geometry, say) through
/// host-visible staging buffers, all in one submission. On a discrete GPU the passes then
/// read video memory rather than system memory over the bus; on a CPU driver both are the
/// same memory and nothing changes but one copy at load.
pub struct Upload<'a> {
    device: &'a Arc<Device>,
    submitter: &'a Submitter,
    cmd: vk::CommandBuffer,
    /// Kept until the copies have run.
    staging: Vec<Buffer>,
}

impl<'a> Upload<'a> {
    /// Starts recording the copies on `submitter`'s command buffer.
    pub fn begin(device: &'a Arc<Device>, submitter: &'a Submitter) -> Result<Self, GpuError> {
        Ok(Self {
            device,
            submitter,
            cmd: submitter.begin()?,
            staging: Vec::new(),
        })
    }

    /// A device-local buffer with `usage` that will hold `data` once [`Self::finish`] returns.
    pub fn buffer<T: bytemuck::Pod>(
        &mut self,
        data: &[T],
        usage: vk::BufferUsageFlags,
        name: &str,
    ) -> Result<Buffer, GpuError> {
        let bytes = std::mem::size_of_val(data) as u64;
        let mut staging = Buffer::create(
            self.device,
            &BufferDesc::new_cpu_to_gpu(bytes, vk::BufferUsageFlags::TRANSFER_SRC),
            &format!("{name} (staging)"),
        )?;
        staging.write(data)?;
        let buffer = Buffer::create(
            self.device,
            &BufferDesc::new_device_local(bytes, usage),
            name,
        )?;
        if bytes > 0 {
            let region = [vk::BufferCopy::default().size(bytes)];
            // SAFETY: both buffers are live and hold at least `bytes` bytes; cmd is recording.
            unsafe {
                self.device
                    .raw
                    .cmd_copy_buffer(self.cmd, staging.raw, buffer.raw, &region)
            };
        }
        self.staging.push(staging);
        Ok(buffer)
    }

    /// Runs the copies and waits for them; the copies are made visible to every later read on
    /// the device (vertex and index fetch, shaders), so the buffers are ready for any pass.
    pub fn finish(self) -> Result<(), GpuError> {
        let visible = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ)];
        // SAFETY: cmd is recording.
        unsafe {
            self.device.raw.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().memory_barriers(&visible),
            )
        };
        self.submitter.submit_and_wait()
        // The staging buffers are dropped here, after the wait.
    }
}
