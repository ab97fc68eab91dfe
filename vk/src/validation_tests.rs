//! The validation layer sees what we ask it to: synchronization hazards are reported (the
//! layer's synchronization checks are off unless enabled), and the loader's own notes are
//! kept apart from the layer's messages.

use ash::vk;

use super::commands::Submitter;
use super::device::{Device, DeviceDesc};
use super::instance::{Instance, InstanceDesc};
use super::memory::{Buffer, BufferDesc};

/// Two `vkCmdFillBuffer`s on the same bytes, with or without a transfer→transfer barrier
/// between them; returns the validation layer's messages for the whole run (device teardown
/// included).
fn two_fills(barrier: bool) -> Vec<String> {
    let instance = Instance::create(&InstanceDesc { validation: true })
        .expect("Vulkan with VK_LAYER_KHRONOS_validation");
    let log = instance.validation_log();
    {
        let device = Device::create(&instance, &DeviceDesc::default()).expect("a device");
        let desc = BufferDesc::new_device_local(256, vk::BufferUsageFlags::TRANSFER_DST);
        let buffer = Buffer::create(&device, &desc, "two fills").expect("buffer");
        let submitter = Submitter::create(&device, "two fills").expect("submitter");
        let cmd = submitter.begin().expect("begin");
        // SAFETY: cmd is recording; the buffer is live and has TRANSFER_DST usage.
        unsafe { device.raw.cmd_fill_buffer(cmd, buffer.raw, 0, 256, 1) };
        if barrier {
            // ALL_TRANSFER: drivers' and layers' versions differ on whether a fill is a
            // COPY or a CLEAR stage operation; all transfer stages cover both.
            let order = [vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
                .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)];
            let dep = vk::DependencyInfo::default().memory_barriers(&order);
            // SAFETY: cmd is recording.
            unsafe { device.raw.cmd_pipeline_barrier2(cmd, &dep) };
        }
        // SAFETY: as above.
        unsafe { device.raw.cmd_fill_buffer(cmd, buffer.raw, 0, 256, 2) };
        submitter.submit_and_wait().expect("submit");
    }
    drop(instance);
    log.messages()
}

#[test]
fn an_unordered_write_after_write_is_reported() {
    let messages = two_fills(false);
    assert!(
        messages
            .iter()
            .any(|m| m.contains("SYNC-HAZARD-WRITE-AFTER-WRITE")),
        "synchronization validation must report two unordered fills; got {messages:#?}"
    );
}

#[test]
fn the_same_writes_ordered_by_a_barrier_are_clean() {
    let messages = two_fills(true);
    assert!(messages.is_empty(), "{messages:#?}");
}
