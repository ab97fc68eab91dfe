//! Command recording and submission: one command buffer and the fence of its submission.
//!
//! One-off work (uploads, builds) submits and waits at once. The renderer's frames in flight
//! (`render::in_flight`) each own a submitter and wait for it only when its slot comes round.

use std::cell::Cell;
use std::sync::{Arc, OnceLock};

use ash::vk;

use super::device::Device;
use super::{GpuError, VkContext};

/// A command pool with one primary command buffer and the fence of its last submission.
pub struct Submitter {
    pub cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// Submitted and not yet waited for: the fence will signal.
    in_flight: Cell<bool>,
    pool: vk::CommandPool,
    device: Arc<Device>,
}

impl Submitter {
    pub fn create(device: &Arc<Device>, name: &str) -> Result<Self, GpuError> {
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(device.queue_family)
            // Reset per frame: we re-record the same command buffer every time.
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create info on a live device.
        let pool = unsafe { device.raw.create_command_pool(&pool_info, None) }
            .vk("vkCreateCommandPool")?;
        let mut submitter = Self {
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            in_flight: Cell::new(false),
            pool,
            device: Arc::clone(device),
        };
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool is live; one buffer is requested and returned.
        submitter.cmd = unsafe { device.raw.allocate_command_buffers(&alloc) }
            .vk("vkAllocateCommandBuffers")?[0];
        // SAFETY: valid create info.
        submitter.fence = unsafe {
            device
                .raw
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }
        .vk("vkCreateFence")?;
        device.set_name(pool, name);
        device.set_name(submitter.cmd, name);
        device.set_name(submitter.fence, name);
        Ok(submitter)
    }

    /// Starts recording; the previous submission must have been waited for ([`Self::wait`]).
    pub fn begin(&self) -> Result<vk::CommandBuffer, GpuError> {
        if self.in_flight.get() {
            return Err(GpuError::Unsupported(
                "a command buffer re-recorded before its submission was waited for".into(),
            ));
        }
        let info = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the buffer is not pending (the last submit was waited for).
        unsafe {
            self.device
                .raw
                .reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())
        }
        .vk("vkResetCommandBuffer")?;
        // SAFETY: the buffer is in the initial state after the reset.
        unsafe { self.device.raw.begin_command_buffer(self.cmd, &info) }
            .vk("vkBeginCommandBuffer")?;
        Ok(self.cmd)
    }

    /// Ends recording, submits, and blocks until the GPU has finished.
    pub fn submit_and_wait(&self) -> Result<(), GpuError> {
        self.submit()?;
        self.wait()
    }

    /// Ends recording and submits; the fence signals when the GPU has finished.
    pub fn submit(&self) -> Result<(), GpuError> {
        self.submit_waiting(&[])
    }

    /// [`Self::submit`], the work waiting for `waits` first (a frame held by a test's
    /// `fault::Hold`).
    pub fn submit_waiting(&self, waits: &[vk::SemaphoreSubmitInfo<'_>]) -> Result<(), GpuError> {
        let d = &self.device.raw;
        // SAFETY: the buffer is recording (begin was called).
        unsafe { d.end_command_buffer(self.cmd) }.vk("vkEndCommandBuffer")?;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(self.cmd)];
        let submit = [vk::SubmitInfo2::default()
            .command_buffer_infos(&cmds)
            .wait_semaphore_infos(waits)];
        let queue = self.device.queue();
        // SAFETY: the fence is unsignalled (reset after every wait), the buffer is executable,
        // the queue is held.
        unsafe { d.queue_submit2(*queue, &submit, self.fence) }.vk("vkQueueSubmit2")?;
        self.in_flight.set(true);
        Ok(())
    }

    /// Blocks until the last submission has finished (at once when nothing is in flight).
    pub fn wait(&self) -> Result<(), GpuError> {
        self.wait_asking(None)
    }

    /// [`Self::wait`], asking the hook of [`set_long_wait_hook`] every [`WAIT_SLICE_NS`] while
    /// it waits: for a frame's wait, which may be seconds on a CPU driver (not for teardown's).
    pub fn wait_watched(&self) -> Result<(), GpuError> {
        self.wait_asking(LONG_WAIT_HOOK.get().copied())
    }

    fn wait_asking(&self, hook: Option<fn(std::time::Duration)>) -> Result<(), GpuError> {
        if !self.in_flight.get() {
            return Ok(());
        }
        let d = &self.device.raw;
        // A lost device returns an error rather than hanging; a CPU driver may be slow, so
        // without a hook the wait has no end.
        let slice = match hook {
            Some(_) => WAIT_SLICE_NS,
            None => u64::MAX,
        };
        let start = std::time::Instant::now();
        let waited = loop {
            // SAFETY: the fence belongs to this device.
            let waited = unsafe { d.wait_for_fences(&[self.fence], true, slice) };
            match (waited, hook) {
                (Err(vk::Result::TIMEOUT), Some(hook)) => hook(start.elapsed()),
                _ => break waited,
            }
        };
        super::fault::fence_wait(waited).vk("vkWaitForFences")?;
        // SAFETY: the fence is signalled and not in use.
        unsafe { d.reset_fences(&[self.fence]) }.vk("vkResetFences")?;
        self.in_flight.set(false);
        Ok(())
    }

    /// Whether the last submission has finished (true when nothing is in flight); no wait.
    pub fn is_finished(&self) -> Result<bool, GpuError> {
        if !self.in_flight.get() {
            return Ok(true);
        }
        // SAFETY: the fence is live.
        unsafe { self.device.raw.get_fence_status(self.fence) }.vk("vkGetFenceStatus")
    }
}

/// How long one wait for a frame's fence lasts before [`set_long_wait_hook`]'s hook is asked.
pub const WAIT_SLICE_NS: u64 = 100_000_000;

/// The hook of [`set_long_wait_hook`].
static LONG_WAIT_HOOK: OnceLock<fn(std::time::Duration)> = OnceLock::new();

/// Installs `hook`, called with the time waited so far every [`WAIT_SLICE_NS`] while a
/// frame's submission is waited for ([`Submitter::wait_watched`]); once per process. A
/// command ends the process there at a signal rather than wait out a GPU frame of seconds (no
/// GPU work can be cut short, and nothing may be destroyed under it).
pub fn set_long_wait_hook(hook: fn(std::time::Duration)) {
    let _ = LONG_WAIT_HOOK.set(hook);
}

impl Drop for Submitter {
    fn drop(&mut self) {
        // Nothing may be destroyed under a running submission; if the wait fails (device
        // lost), wait for the whole device.
        if self.wait().is_err() {
            let _ = self.device.wait_idle();
        }
        // SAFETY: the last submission has finished; the pool frees its command buffer.
        unsafe {
            self.device.raw.destroy_fence(self.fence, None);
            self.device.raw.destroy_command_pool(self.pool, None);
        }
    }
}

/// One image layout transition (synchronization2), with the stages and accesses on each side.
#[derive(Clone, Copy)]
pub struct ImageBarrier {
    pub image: vk::Image,
    pub range: vk::ImageSubresourceRange,
    pub from: (vk::ImageLayout, vk::PipelineStageFlags2, vk::AccessFlags2),
    pub to: (vk::ImageLayout, vk::PipelineStageFlags2, vk::AccessFlags2),
}

/// Records a batch of image barriers.
pub fn image_barriers(device: &Device, cmd: vk::CommandBuffer, barriers: &[ImageBarrier]) {
    let raw: Vec<vk::ImageMemoryBarrier2> = barriers
        .iter()
        .map(|b| {
            vk::ImageMemoryBarrier2::default()
                .image(b.image)
                .subresource_range(b.range)
                .old_layout(b.from.0)
                .src_stage_mask(b.from.1)
                .src_access_mask(b.from.2)
                .new_layout(b.to.0)
                .dst_stage_mask(b.to.1)
                .dst_access_mask(b.to.2)
        })
        .collect();
    let dep = vk::DependencyInfo::default().image_memory_barriers(&raw);
    // SAFETY: cmd is recording; the barriers name live images.
    unsafe { device.raw.cmd_pipeline_barrier2(cmd, &dep) };
}

/// One global memory barrier from `src` to `dst` (stage, access): everything before it in
/// `src`'s scope is ordered before (and its writes visible to) what comes after in `dst`'s.
pub fn memory_barrier(
    device: &Device,
    cmd: vk::CommandBuffer,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let barrier = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    let dep = vk::DependencyInfo::default().memory_barriers(&barrier);
    // SAFETY: cmd is recording.
    unsafe { device.raw.cmd_pipeline_barrier2(cmd, &dep) };
}

/// Makes writes by `stage` (`access`) visible to the host: required before the CPU reads
/// GPU-written memory after the fence, even host-coherent memory (the fence alone only
/// orders execution; "Host Write Ordering Guarantees" in the spec cover the other direction).
pub fn host_read_barrier(
    device: &Device,
    cmd: vk::CommandBuffer,
    stage: vk::PipelineStageFlags2,
    access: vk::AccessFlags2,
) {
    let host = (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ);
    memory_barrier(device, cmd, (stage, access), host);
}
