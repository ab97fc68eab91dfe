//! Per-frame data from the host (views, object transforms, indirect commands, meshlet draws,
//! acceleration-structure instances) through one staging buffer per frame in flight.
//!
//! With several frames in flight the host writes frame N+1's data while the GPU may still be
//! reading frame N's. A buffer the host writes in place would need one copy per frame in
//! flight, and every descriptor set, indirect draw and device address that names it would have
//! to follow the frame. Instead each frame in flight owns a staging buffer ([`FrameUploads`]):
//! the host writes there, and the frame's own commands copy it into the single device buffer
//! the shaders read, after the previous frames' reads of that buffer and before this frame's
//! (the barriers are the caller's: the renderer declares the copies to its frame graph). The
//! device buffers then live in the GPU's fastest memory, and nothing that names them changes
//! per frame. Vulkan guide: "Synchronization examples",
//! upload then read.

use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::memory::{Buffer, BufferDesc};
use super::GpuError;

/// Each upload starts at a multiple of this (any copy offset is valid; 16 keeps every
/// upload aligned for the host's typed writes and the device's wide copies).
const ALIGN: usize = 16;

/// One queued copy: `size` bytes from `at` in the staging data to offset 0 of `dst`.
struct Queued {
    dst: vk::Buffer,
    at: u64,
    size: u64,
}

/// The uploads of one frame in flight: queued by the host before the frame is recorded,
/// copied by its first commands. Reused every time its frame slot comes round (its fence
/// waited first, so its staging buffer is no longer read by the GPU).
pub struct FrameUploads {
    data: Vec<u8>,
    queued: Vec<Queued>,
    /// Host-visible; grown (replaced) when a frame needs more, which is safe only because the
    /// slot's previous frame has finished.
    staging: Option<Buffer>,
    name: String,
    device: Arc<Device>,
}

impl FrameUploads {
    pub fn new(device: &Arc<Device>, name: &str) -> Self {
        Self {
            data: Vec::new(),
            queued: Vec::new(),
            staging: None,
            name: name.to_owned(),
            device: Arc::clone(device),
        }
    }

    /// Queues `data` for the start of `dst` (which needs `TRANSFER_DST` usage). The copy runs
    /// at the start of the frame recorded next, before any of its commands read `dst`.
    pub fn write<T: bytemuck::Pod>(&mut self, dst: &Buffer, data: &[T]) -> Result<(), GpuError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() as u64 > dst.size {
            return Err(GpuError::Unsupported(format!(
                "upload of {} bytes into a {}-byte buffer",
                bytes.len(),
                dst.size
            )));
        }
        if bytes.is_empty() {
            return Ok(());
        }
        let at = self.data.len().next_multiple_of(ALIGN);
        self.data.resize(at, 0);
        self.data.extend_from_slice(bytes);
        self.queued.push(Queued {
            dst: dst.raw,
            at: at as u64,
            size: bytes.len() as u64,
        });
        Ok(())
    }

    /// Forgets what is queued (the frame it was queued for was never recorded: its
    /// recording failed before the copies), so that the slot's next frame starts empty.
    pub fn clear(&mut self) {
        self.queued.clear();
        self.data.clear();
    }

    /// The buffers the queued copies write, each once, in the order first queued.
    pub fn destinations(&self) -> Vec<vk::Buffer> {
        let mut seen = Vec::new();
        for q in &self.queued {
            if !seen.contains(&q.dst) {
                seen.push(q.dst);
            }
        }
        seen
    }

    /// Records the queued copies at the start of a frame and empties the queue. The caller
    /// orders them (the renderer's frame graph): after every earlier command's reads of
    /// [`Self::destinations`] (the frames still in flight read these buffers: a write after
    /// read, for which an execution dependency is enough), and their writes made visible to
    /// every later read, whatever stage reads them (uniforms, storage, indirect commands,
    /// acceleration-structure builds).
    pub fn record_copies(&mut self, cmd: vk::CommandBuffer) -> Result<(), GpuError> {
        if self.queued.is_empty() {
            return Ok(());
        }
        let needed = self.data.len() as u64;
        if self.staging.as_ref().is_none_or(|b| b.size < needed) {
            let desc = BufferDesc::new_cpu_to_gpu(needed, vk::BufferUsageFlags::TRANSFER_SRC);
            self.staging = Some(Buffer::create(&self.device, &desc, &self.name)?);
        }
        let staging = self.staging.as_mut().expect("made above");
        staging.write(&self.data)?;
        let d = &self.device.raw;
        for q in &self.queued {
            let region = [vk::BufferCopy {
                src_offset: q.at,
                dst_offset: 0,
                size: q.size,
            }];
            // SAFETY: cmd is recording; both buffers are live and the regions fit (checked in
            // `write`, and the staging buffer holds all of `data`).
            unsafe { d.cmd_copy_buffer(cmd, staging.raw, q.dst, &region) };
        }
        self.queued.clear();
        self.data.clear();
        Ok(())
    }
}
