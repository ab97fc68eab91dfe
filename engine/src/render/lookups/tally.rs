//! How often `distance-exact` falls back to tracing: per mirror draw, the fragments it shaded
//! and, among them, the rays its distance search could not resolve and it traced
//! (`shaders/include/trace_tally.glsl`). The fraction is what that lookup costs over
//! `distance`, so the benchmark and `render.json` report it.
//!
//! One `uvec2` (fragments, traced) per view and pass (colour or directions): every mirror draw
//! of a frame adds to its own slot, so no two draws write the same bytes and they need no
//! barrier between them. Zeroed at the start of each frame, copied for the host at its end
//! (the barriers derived by the frame graph from the uses declared).
//! Helper invocations (the 2x2 quads' fill-ins) do not count: their atomics have no effect.

use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;
use serde::Serialize;

use crate::render::graph::{PassRecorder, Resource, Use};
use crate::render::resources::{VIEW_COUNT, VIEW_OBSERVER, VIEW_SENSOR};
use crate::shaders::shared::{TALLY_PASSES, TALLY_PASS_COLOUR};
use crate::vk::descriptors;
use crate::vk::device::Device;
use crate::vk::memory::{Buffer, BufferDesc};
use crate::vk::GpuError;

/// The mirror fragments of one view and the rays traced among them (colour pass).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct TracedRays {
    pub fragments: u64,
    pub traced: u64,
}

impl TracedRays {
    /// traced / fragments (None when the mirror was not drawn).
    pub fn fraction(&self) -> Option<f64> {
        (self.fragments > 0).then(|| self.traced as f64 / self.fragments as f64)
    }
}

/// One frame's tally: the observer's and the sensor's colour passes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct FrameTally {
    pub observer: TracedRays,
    pub sensor: TracedRays,
}

/// Slots per view: the colour pass and the direction pass (shared.glsl's `TALLY_PASS_*`).
const PASSES: usize = TALLY_PASSES as usize;
const SLOT_BYTES: u64 = 2 * std::mem::size_of::<u32>() as u64;

/// The tally's storage buffer, which the frame's mirror draws count into, and one host copy
/// per frame in flight (the next frame resets the device buffer while the host may not yet
/// have read the last one's counts).
pub struct TraceTally {
    device: Arc<Device>,
    buffer: Buffer,
    host: Vec<Buffer>,
}

const TALLY_BYTES: u64 = (VIEW_COUNT * PASSES) as u64 * SLOT_BYTES;

impl TraceTally {
    pub fn create(device: &Arc<Device>, frames_in_flight: usize) -> Result<Self, GpuError> {
        let desc = BufferDesc {
            size: TALLY_BYTES,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::GpuOnly,
        };
        let buffer = Buffer::create(device, &desc, "trace tally")?;
        let host = (0..frames_in_flight)
            .map(|i| {
                let desc = BufferDesc::new_readback(TALLY_BYTES);
                Buffer::create(device, &desc, &format!("trace tally, frame {i}"))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            device: device.clone(),
            buffer,
            host,
        })
    }

    /// The tally's set-layout binding.
    pub fn binding(binding: u32) -> vk::DescriptorSetLayoutBinding<'static> {
        let stage = vk::ShaderStageFlags::FRAGMENT;
        descriptors::binding(binding, vk::DescriptorType::STORAGE_BUFFER, 1, stage)
    }

    /// Points `binding` of `set` at the tally.
    pub fn write(&self, set: vk::DescriptorSet, binding: u32) {
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        descriptors::write_buffer(&self.device, set, binding, storage, self.buffer.raw);
    }

    /// The device buffer, resting as copied for the host, and slot `slot`'s host copy,
    /// resting as read by the host.
    pub fn resources(&self, slot: usize) -> Vec<(Resource, Use)> {
        vec![
            (Resource::Buffer(self.buffer.raw), Use::CopySource),
            (Resource::Buffer(self.host[slot].raw), Use::HostRead),
        ]
    }

    /// Zeroes the tally before the frame's mirror draws, which then count into it: after the
    /// last frame's copy for the host read it.
    pub fn record_reset(&self, pass: &mut PassRecorder<'_>) {
        let tally = Resource::Buffer(self.buffer.raw);
        pass.declare(&[(tally, Use::Filled)]);
        // SAFETY: cmd is recording; the buffer lives as long as the lookup pass, which the
        // renderer keeps until its frames in flight have finished.
        unsafe {
            (self.device.raw).cmd_fill_buffer(pass.cmd(), self.buffer.raw, 0, vk::WHOLE_SIZE, 0);
        }
        pass.declare(&[(tally, Use::FragmentStorage)]);
    }

    /// After the frame's mirror draws: their counts copied into slot `slot`'s host copy, for
    /// the host after the frame's fence.
    pub fn record_to_host(&self, pass: &mut PassRecorder<'_>, slot: usize) {
        let (tally, host) = (self.buffer.raw, self.host[slot].raw);
        pass.declare(&[
            (Resource::Buffer(tally), Use::CopySource),
            (Resource::Buffer(host), Use::CopyDestination),
        ]);
        let region = [vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: TALLY_BYTES,
        }];
        // SAFETY: cmd is recording; both buffers hold TALLY_BYTES; the slot's host copy is not
        // read before this frame's fence.
        unsafe { (self.device.raw).cmd_copy_buffer(pass.cmd(), tally, host, &region) };
        pass.declare(&[(Resource::Buffer(host), Use::HostRead)]);
    }

    /// The counts of slot `slot`'s frame (call after its fence).
    pub fn read(&self, slot: usize) -> Result<FrameTally, GpuError> {
        let size = TALLY_BYTES as usize;
        // The mapping is at least 4-byte aligned; the slots are (fragments, traced) u32 pairs.
        let words: &[u32] = bytemuck::cast_slice(&self.host[slot].mapped()?[..size]);
        let slot = |view: u32| {
            let at = 2 * (view as usize * PASSES + TALLY_PASS_COLOUR as usize);
            TracedRays {
                fragments: u64::from(words[at]),
                traced: u64::from(words[at + 1]),
            }
        };
        Ok(FrameTally {
            observer: slot(VIEW_OBSERVER),
            sensor: slot(VIEW_SENSOR),
        })
    }
}
