//! Frames in flight for an interactive program: per-frame command buffers, fences and
//! "image available" semaphores, and a deletion queue tied to the frames' fences.
//!
//! The CPU records frame N+1 while the GPU still runs frame N (and the presentation engine
//! shows frame N-1). So an object the GPU may still use (a retired swapchain, a replaced
//! renderer whose images a blit still reads) must not be destroyed when the program lets go
//! of it: [`FrameRing::defer`] keeps it until every frame submitted before that moment has
//! finished (its fence signalled), as Granite's per-frame deletion queues do.

use std::any::Any;
use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::{GpuError, VkContext};

/// Two frames in flight: the CPU prepares one while the GPU draws the other. More would add
/// latency without speed: the renderer's own work is serial (see docs/viewer.md).
pub const FRAMES_IN_FLIGHT: usize = 2;

/// What one frame in flight owns. Reused every `FRAMES_IN_FLIGHT` frames, after its fence.
pub struct FrameSlot {
    /// Recorded anew each time the slot comes round (its pool is reset first).
    pub cmd: vk::CommandBuffer,
    /// Signalled by `vkAcquireNextImageKHR` when the swapchain image may be written; waited by
    /// this frame's submission.
    pub image_available: vk::Semaphore,
    /// Signalled when this slot's last submission finished; created signalled so that the
    /// first wait returns at once.
    fence: vk::Fence,
    pool: vk::CommandPool,
    /// Serial number of this slot's last submission (0: none yet).
    submitted: u64,
    /// Serial of the last submission of this slot seen finished.
    finished: u64,
}

/// An object waiting for the frames that may use it: `pending[s]` is the serial of slot s's
/// last submission when it was deferred.
struct Deferred {
    pending: Vec<u64>,
    /// Never read: dropping it is the point.
    _object: Box<dyn Any>,
}

/// The ring of frames in flight and the deletion queue.
pub struct FrameRing {
    /// Declared first: dropped (after the fences were waited in `Drop`) before the slots.
    deletions: Vec<Deferred>,
    slots: Vec<FrameSlot>,
    current: usize,
    serial: u64,
    device: Arc<Device>,
}

impl FrameRing {
    pub fn create(device: &Arc<Device>, count: usize) -> Result<Self, GpuError> {
        let mut ring = Self {
            deletions: Vec::new(),
            slots: Vec::with_capacity(count),
            current: 0,
            serial: 0,
            device: Arc::clone(device),
        };
        for i in 0..count {
            let slot = create_slot(device)?;
            ring.slots.push(slot);
            let slot = &ring.slots[i];
            device.set_name(slot.cmd, &format!("frame {i}"));
            device.set_name(slot.fence, &format!("frame {i} finished"));
            device.set_name(slot.image_available, &format!("frame {i} image available"));
        }
        Ok(ring)
    }

    /// Waits until the current slot's previous frame has finished, destroys what is no longer
    /// in use, and starts recording the slot's command buffer.
    pub fn begin(&mut self) -> Result<&FrameSlot, GpuError> {
        self.wait_slot(self.current)?;
        self.collect()?;
        let slot = &self.slots[self.current];
        let d = &self.device.raw;
        // SAFETY: the slot's last submission finished (fence waited), so its buffer is idle.
        unsafe { d.reset_command_pool(slot.pool, vk::CommandPoolResetFlags::empty()) }
            .vk("vkResetCommandPool")?;
        let info = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the buffer is in the initial state after the pool reset.
        unsafe { d.begin_command_buffer(slot.cmd, &info) }.vk("vkBeginCommandBuffer")?;
        Ok(slot)
    }

    /// Whether [`Self::begin`] would start at once: the current slot's last frame finished
    /// (a loop that must not wait for the GPU asks this first).
    pub fn ready(&self) -> Result<bool, GpuError> {
        let slot = &self.slots[self.current];
        // SAFETY: the fence is live.
        unsafe { self.device.raw.get_fence_status(slot.fence) }.vk("vkGetFenceStatus")
    }

    /// Whether every slot's last frame has finished (no wait).
    pub fn all_finished(&self) -> Result<bool, GpuError> {
        for slot in &self.slots {
            // SAFETY: the fence is live.
            if !unsafe { self.device.raw.get_fence_status(slot.fence) }.vk("vkGetFenceStatus")? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// The index of the slot [`Self::begin`] started (for state kept per slot elsewhere: it
    /// is free to reuse once `begin` returned).
    pub fn current_index(&self) -> usize {
        self.current
    }

    /// The slot [`Self::begin`] started.
    pub fn slot(&self) -> &FrameSlot {
        &self.slots[self.current]
    }

    /// Ends the current slot's recording and submits it: it waits for `wait` (the acquired
    /// image) at the given stage and signals `signal` (the image's "drawn" semaphore) and the
    /// slot's fence. The next `begin` uses the next slot.
    pub fn submit(
        &mut self,
        wait: (vk::Semaphore, vk::PipelineStageFlags2),
        signal: vk::Semaphore,
    ) -> Result<(), GpuError> {
        let d = &self.device.raw;
        let slot = &self.slots[self.current];
        // SAFETY: the buffer is recording (begin).
        unsafe { d.end_command_buffer(slot.cmd) }.vk("vkEndCommandBuffer")?;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(wait.0)
            .stage_mask(wait.1)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(signal)
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let submit = [vk::SubmitInfo2::default()
            .command_buffer_infos(&cmds)
            .wait_semaphore_infos(&waits)
            .signal_semaphore_infos(&signals)];
        // Reset only now: a frame abandoned before submission (swapchain out of date) leaves
        // the fence signalled, so the next wait on it cannot hang.
        // SAFETY: the fence was waited in `begin`, so no submission uses it.
        unsafe { d.reset_fences(&[slot.fence]) }.vk("vkResetFences")?;
        let queue = self.device.queue();
        // SAFETY: every handle in `submit` is live; the fence is unsignalled; the queue is held.
        unsafe { d.queue_submit2(*queue, &submit, slot.fence) }.vk("vkQueueSubmit2")?;
        self.serial += 1;
        self.slots[self.current].submitted = self.serial;
        self.current = (self.current + 1) % self.slots.len();
        Ok(())
    }

    /// Abandons the frame `begin` started (nothing was submitted): its command buffer is left
    /// recording and is reset when the slot comes round again.
    pub fn abandon(&mut self) -> Result<(), GpuError> {
        let slot = &self.slots[self.current];
        // SAFETY: the buffer is recording; ending it makes it executable, never submitted.
        unsafe { self.device.raw.end_command_buffer(slot.cmd) }.vk("vkEndCommandBuffer")?;
        Ok(())
    }

    /// Keeps `object` until every frame submitted so far has finished, then drops it.
    pub fn defer(&mut self, object: impl Any) {
        self.deletions.push(Deferred {
            pending: self.slots.iter().map(|s| s.submitted).collect(),
            _object: Box::new(object),
        });
    }

    /// Waits for every frame in flight and drops everything deferred.
    pub fn wait_all(&mut self) -> Result<(), GpuError> {
        for s in 0..self.slots.len() {
            self.wait_slot(s)?;
        }
        self.collect()
    }

    fn wait_slot(&mut self, s: usize) -> Result<(), GpuError> {
        let slot = &self.slots[s];
        // SAFETY: the fence is live; it was submitted with its slot or created signalled.
        let waited = unsafe {
            self.device
                .raw
                .wait_for_fences(&[slot.fence], true, u64::MAX)
        };
        super::fault::fence_wait(waited).vk("vkWaitForFences")?;
        self.slots[s].finished = self.slots[s].submitted;
        Ok(())
    }

    /// Drops the deferred objects whose frames have all finished; polls the other slots'
    /// fences first (without waiting).
    fn collect(&mut self) -> Result<(), GpuError> {
        for slot in &mut self.slots {
            // SAFETY: the fence is live.
            if unsafe { self.device.raw.get_fence_status(slot.fence) }.vk("vkGetFenceStatus")? {
                slot.finished = slot.submitted;
            }
        }
        let slots = &self.slots;
        self.deletions.retain(|d| {
            let in_use = d
                .pending
                .iter()
                .zip(slots)
                .any(|(&pending, slot)| slot.finished < pending);
            in_use
        });
        Ok(())
    }
}

impl Drop for FrameRing {
    fn drop(&mut self) {
        // Nothing may be destroyed under a running frame; on error (device lost) wait for the
        // whole device instead.
        if self.wait_all().is_err() {
            let _ = self.device.wait_idle();
        }
        self.deletions.clear();
        let d = &self.device.raw;
        for slot in &self.slots {
            // SAFETY: every submission finished (waited above); each handle is destroyed once.
            unsafe {
                d.destroy_semaphore(slot.image_available, None);
                d.destroy_fence(slot.fence, None);
                d.destroy_command_pool(slot.pool, None);
            }
        }
    }
}

fn create_slot(device: &Arc<Device>) -> Result<FrameSlot, GpuError> {
    let d = &device.raw;
    let pool_info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(device.queue_family)
        // Recorded once per use, reset as a whole.
        .flags(vk::CommandPoolCreateFlags::TRANSIENT);
    // SAFETY (all creations): valid create infos on a live device; on an error the handles
    // created so far leak until the device is destroyed, which the error path then does.
    let pool = unsafe { d.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
    let alloc = vk::CommandBufferAllocateInfo::default()
        .command_pool(pool)
        .level(vk::CommandBufferLevel::PRIMARY)
        .command_buffer_count(1);
    let cmd = unsafe { d.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?[0];
    let signalled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
    let fence = unsafe { d.create_fence(&signalled, None) }.vk("vkCreateFence")?;
    let image_available = unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
        .vk("vkCreateSemaphore")?;
    Ok(FrameSlot {
        cmd,
        image_available,
        fence,
        pool,
        submitted: 0,
        finished: 0,
    })
}
