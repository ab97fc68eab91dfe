//! Images, their views and samplers.

use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::device::Device;
use super::{GpuError, VkContext};

/// What an image is.
#[derive(Debug, Clone)]
pub struct ImageDesc {
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    /// 6 for a cube map.
    pub layers: u32,
    pub mip_levels: u32,
    pub usage: vk::ImageUsageFlags,
    /// Allows cube views of the layers.
    pub cube_compatible: bool,
}

impl ImageDesc {
    pub fn new_2d(format: vk::Format, width: u32, height: u32, usage: vk::ImageUsageFlags) -> Self {
        Self {
            format,
            width,
            height,
            layers: 1,
            mip_levels: 1,
            usage,
            cube_compatible: false,
        }
    }

    pub fn new_cube(
        format: vk::Format,
        size: u32,
        mip_levels: u32,
        usage: vk::ImageUsageFlags,
    ) -> Self {
        Self {
            format,
            width: size,
            height: size,
            layers: 6,
            mip_levels,
            usage,
            cube_compatible: true,
        }
    }

    /// The create info of an optimally tiled, single-sample, exclusive image: shared by
    /// [`Image::create`] and by the memory estimate that runs before anything is created.
    pub fn create_info(&self) -> vk::ImageCreateInfo<'static> {
        vk::ImageCreateInfo::default()
            .flags(if self.cube_compatible {
                vk::ImageCreateFlags::CUBE_COMPATIBLE
            } else {
                vk::ImageCreateFlags::empty()
            })
            .image_type(vk::ImageType::TYPE_2D)
            .format(self.format)
            .extent(vk::Extent3D {
                width: self.width,
                height: self.height,
                depth: 1,
            })
            .mip_levels(self.mip_levels)
            .array_layers(self.layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(self.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
    }

    /// The bytes this image needs on `device`, asked of the driver without creating it
    /// (`vkGetDeviceImageMemoryRequirements`, Vulkan 1.3).
    pub fn memory_bytes(&self, device: &Device) -> u64 {
        let info = self.create_info();
        let query = vk::DeviceImageMemoryRequirements::default().create_info(&info);
        let mut out = vk::MemoryRequirements2::default();
        // SAFETY: valid create info; the query creates nothing.
        unsafe {
            device
                .raw
                .get_device_image_memory_requirements(&query, &mut out)
        };
        out.memory_requirements.size
    }

    pub fn aspect(&self) -> vk::ImageAspectFlags {
        match self.format {
            vk::Format::D32_SFLOAT | vk::Format::D16_UNORM => vk::ImageAspectFlags::DEPTH,
            _ => vk::ImageAspectFlags::COLOR,
        }
    }
}

/// The number of levels in a full mip chain for a `size`-texel side.
/// The copy between a tightly packed buffer, from `offset`, and mip 0 of a colour image's
/// first `layers` layers, `[width, height]` texels each (uploads, readbacks).
pub fn color_copy_region(
    offset: u64,
    layers: u32,
    [width, height]: [u32; 2],
) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .buffer_offset(offset)
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: layers,
        })
        .image_extent(vk::Extent3D {
            width,
            height,
            depth: 1,
        })
}

pub fn full_mip_count(size: u32) -> u32 {
    32 - size.max(1).leading_zeros()
}

/// A device-local image and its memory.
pub struct Image {
    pub raw: vk::Image,
    pub desc: ImageDesc,
    allocation: Option<Allocation>,
    device: Arc<Device>,
}

impl Image {
    pub fn create(device: &Arc<Device>, desc: &ImageDesc, name: &str) -> Result<Self, GpuError> {
        let info = desc.create_info();
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_image(&info, None) }.vk("vkCreateImage")?;
        // SAFETY: raw was just created on this device.
        let requirements = unsafe { device.raw.get_image_memory_requirements(raw) };
        let allocation = device
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| {
                // SAFETY: the image is unused and bound to nothing.
                unsafe { device.raw.destroy_image(raw, None) };
                GpuError::Alloc {
                    name: name.into(),
                    source,
                }
            })?;
        // SAFETY: memory and offset come from an allocation sized for this image.
        let bound = unsafe {
            device
                .raw
                .bind_image_memory(raw, allocation.memory(), allocation.offset())
        };
        let image = Self {
            raw,
            desc: desc.clone(),
            allocation: Some(allocation),
            device: Arc::clone(device),
        };
        bound.vk("vkBindImageMemory")?;
        device.set_name(raw, name);
        Ok(image)
    }

    /// A view of `layers` starting at `base_layer`, mips `base_mip..base_mip+mips`.
    pub fn view(
        &self,
        view_type: vk::ImageViewType,
        base_layer: u32,
        layers: u32,
        base_mip: u32,
        mips: u32,
        name: &str,
    ) -> Result<ImageView, GpuError> {
        let info = vk::ImageViewCreateInfo::default()
            .image(self.raw)
            .view_type(view_type)
            .format(self.desc.format)
            .subresource_range(vk::ImageSubresourceRange {
                aspect_mask: self.desc.aspect(),
                base_mip_level: base_mip,
                level_count: mips,
                base_array_layer: base_layer,
                layer_count: layers,
            });
        // SAFETY: the range lies within the image (callers pass in-range values).
        let raw =
            unsafe { self.device.raw.create_image_view(&info, None) }.vk("vkCreateImageView")?;
        self.device.set_name(raw, name);
        Ok(ImageView {
            raw,
            device: Arc::clone(&self.device),
        })
    }

    /// The whole subresource range (all mips, all layers).
    pub fn full_range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.desc.aspect(),
            base_mip_level: 0,
            level_count: self.desc.mip_levels,
            base_array_layer: 0,
            layer_count: self.desc.layers,
        }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: views hold no reference to the image in Vulkan terms but are dropped first by
        // their owners (field order); the last fence that used the image has signalled.
        unsafe { self.device.raw.destroy_image(self.raw, None) };
        if let Some(a) = self.allocation.take() {
            let _ = self.device.allocator().free(a);
        }
    }
}

/// An image view; must be dropped before its image (owners declare views first).
pub struct ImageView {
    pub raw: vk::ImageView,
    device: Arc<Device>,
}

impl Drop for ImageView {
    fn drop(&mut self) {
        // SAFETY: no command buffer still in flight uses the view.
        unsafe { self.device.raw.destroy_image_view(self.raw, None) };
    }
}

/// A sampler.
pub struct Sampler {
    pub raw: vk::Sampler,
    device: Arc<Device>,
}

impl Sampler {
    pub fn create(
        device: &Arc<Device>,
        info: &vk::SamplerCreateInfo<'_>,
        name: &str,
    ) -> Result<Self, GpuError> {
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_sampler(info, None) }.vk("vkCreateSampler")?;
        device.set_name(raw, name);
        Ok(Self {
            raw,
            device: Arc::clone(device),
        })
    }

    /// Nearest filtering, clamped at the edges: for images read texel by texel (`texelFetch`
    /// ignores the filter, but a combined sampler is still needed; an integer image may not
    /// be sampled with a linear filter at all).
    pub fn nearest(device: &Arc<Device>, name: &str) -> Result<Self, GpuError> {
        let clamp = vk::SamplerAddressMode::CLAMP_TO_EDGE;
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(clamp)
            .address_mode_v(clamp)
            .address_mode_w(clamp);
        Self::create(device, &info, name)
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: no command buffer still in flight uses the sampler.
        unsafe { self.device.raw.destroy_sampler(self.raw, None) };
    }
}
