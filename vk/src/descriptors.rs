//! Descriptor set layouts, a pool, and the sets allocated from it.

use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::{GpuError, VkContext};

/// One binding of a set layout: `count` descriptors of `kind` at `binding`, seen by `stages`.
pub fn binding(
    binding: u32,
    kind: vk::DescriptorType,
    count: u32,
    stages: vk::ShaderStageFlags,
) -> vk::DescriptorSetLayoutBinding<'static> {
    vk::DescriptorSetLayoutBinding::default()
        .binding(binding)
        .descriptor_type(kind)
        .descriptor_count(count)
        .stage_flags(stages)
}

/// A descriptor set layout.
pub struct DescriptorSetLayout {
    pub raw: vk::DescriptorSetLayout,
    device: Arc<Device>,
}

impl DescriptorSetLayout {
    pub fn create(
        device: &Arc<Device>,
        bindings: &[vk::DescriptorSetLayoutBinding<'_>],
        name: &str,
    ) -> Result<Self, GpuError> {
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(bindings);
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_descriptor_set_layout(&info, None) }
            .vk("vkCreateDescriptorSetLayout")?;
        device.set_name(raw, name);
        Ok(Self {
            raw,
            device: Arc::clone(device),
        })
    }
}

impl Drop for DescriptorSetLayout {
    fn drop(&mut self) {
        // SAFETY: pipelines layouts built from it keep no reference once created.
        unsafe {
            self.device
                .raw
                .destroy_descriptor_set_layout(self.raw, None)
        };
    }
}

/// A pool sized for a known set of descriptors; its sets are freed with it.
pub struct DescriptorPool {
    pub raw: vk::DescriptorPool,
    device: Arc<Device>,
}

impl DescriptorPool {
    pub fn create(
        device: &Arc<Device>,
        max_sets: u32,
        sizes: &[vk::DescriptorPoolSize],
        name: &str,
    ) -> Result<Self, GpuError> {
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(max_sets)
            .pool_sizes(sizes);
        // SAFETY: valid create info.
        let raw = unsafe { device.raw.create_descriptor_pool(&info, None) }
            .vk("vkCreateDescriptorPool")?;
        device.set_name(raw, name);
        Ok(Self {
            raw,
            device: Arc::clone(device),
        })
    }

    /// Allocates one set of `layout` (freed when the pool is dropped).
    pub fn allocate(
        &self,
        layout: &DescriptorSetLayout,
        name: &str,
    ) -> Result<vk::DescriptorSet, GpuError> {
        let layouts = [layout.raw];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.raw)
            .set_layouts(&layouts);
        // SAFETY: the pool was sized for the sets the renderer allocates.
        let set = unsafe { self.device.raw.allocate_descriptor_sets(&info) }
            .vk("vkAllocateDescriptorSets")?[0];
        self.device.set_name(set, name);
        Ok(set)
    }
}

impl Drop for DescriptorPool {
    fn drop(&mut self) {
        // SAFETY: no command buffer in flight uses its sets.
        unsafe { self.device.raw.destroy_descriptor_pool(self.raw, None) };
    }
}

/// Writes `buffer` (whole) at `binding` of `set`.
pub fn write_buffer(
    device: &Device,
    set: vk::DescriptorSet,
    binding: u32,
    kind: vk::DescriptorType,
    buffer: vk::Buffer,
) {
    let infos = [vk::DescriptorBufferInfo::default()
        .buffer(buffer)
        .offset(0)
        .range(vk::WHOLE_SIZE)];
    let write = vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(binding)
        .descriptor_type(kind)
        .buffer_info(&infos);
    // SAFETY: the set is not in use by a pending command buffer.
    unsafe { device.raw.update_descriptor_sets(&[write], &[]) };
}

/// Writes combined image samplers at `binding`, array elements 0..images.len().
pub fn write_images(
    device: &Device,
    set: vk::DescriptorSet,
    binding: u32,
    images: &[(vk::ImageView, vk::Sampler)],
) {
    let infos: Vec<vk::DescriptorImageInfo> = images
        .iter()
        .map(|&(view, sampler)| {
            vk::DescriptorImageInfo::default()
                .image_view(view)
                .sampler(sampler)
                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
        })
        .collect();
    let kind = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
    write_image_infos(device, (set, binding), kind, &infos);
}

/// Writes a storage image at `binding`, in the layout storage writes need (`GENERAL`).
pub fn write_storage_image(
    device: &Device,
    set: vk::DescriptorSet,
    binding: u32,
    view: vk::ImageView,
) {
    let infos = [vk::DescriptorImageInfo::default()
        .image_view(view)
        .image_layout(vk::ImageLayout::GENERAL)];
    let kind = vk::DescriptorType::STORAGE_IMAGE;
    write_image_infos(device, (set, binding), kind, &infos);
}

/// Writes image descriptors of `kind` at `binding` of `set`, array elements 0..infos.len().
fn write_image_infos(
    device: &Device,
    (set, binding): (vk::DescriptorSet, u32),
    kind: vk::DescriptorType,
    infos: &[vk::DescriptorImageInfo],
) {
    let write = vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(binding)
        .descriptor_type(kind)
        .image_info(infos);
    // SAFETY: the set is not in use by a pending command buffer.
    unsafe { device.raw.update_descriptor_sets(&[write], &[]) };
}
