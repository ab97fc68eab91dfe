//! Physical-device selection, the logical device, its queue and its memory allocator.

use std::ffi::{CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::features::Enables;
use super::instance::Instance;
use super::{GpuError, VkContext};

pub use super::features::OptionalFeatures;

// The physical side (what a device can do, and which one is chosen) lives in `physical.rs`;
// re-exported so that callers keep one path for everything about devices.
use super::physical::select;
pub use super::physical::{
    choose, enumerate, mesa_major, parse_mesa_version, Candidate, DeviceFeatures, DeviceInfo,
    DeviceLimits, MIN_MESA_MAJOR,
};

/// How to pick and set up a device.
#[derive(Debug, Clone, Default)]
pub struct DeviceDesc {
    /// `--device`: an index into the enumeration order, or a case-insensitive part of the
    /// device's name, short name (`lavapipe`, `swiftshader`) or driver name. `None`: the
    /// best-ranked usable device (see `DeviceInfo::rank`).
    pub selector: Option<String>,
    /// Optional features to enable (those of the cube methods that will run); the device is
    /// rejected if it lacks one.
    pub features: OptionalFeatures,
}

/// A device limit a renderer may need a minimum of (the methods state theirs as data).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limit {
    MultiviewViewCount,
    GeometryOutputVertices,
    GeometryShaderInvocations,
    MeshOutputLayers,
}

impl Limit {
    /// The limit's Vulkan name.
    pub fn name(self) -> &'static str {
        match self {
            Limit::MultiviewViewCount => "maxMultiviewViewCount",
            Limit::GeometryOutputVertices => "maxGeometryOutputVertices",
            Limit::GeometryShaderInvocations => "maxGeometryShaderInvocations",
            Limit::MeshOutputLayers => "maxMeshOutputLayers",
        }
    }

    pub fn value(self, limits: &DeviceLimits) -> u32 {
        match self {
            Limit::MultiviewViewCount => limits.max_multiview_view_count,
            Limit::GeometryOutputVertices => limits.max_geometry_output_vertices,
            Limit::GeometryShaderInvocations => limits.max_geometry_shader_invocations,
            Limit::MeshOutputLayers => limits.max_mesh_output_layers,
        }
    }
}

/// The logical device. Owns the allocator, so every buffer and image (which hold an
/// `Arc<Device>`) is freed before the device is destroyed.
pub struct Device {
    pub raw: ash::Device,
    pub physical: vk::PhysicalDevice,
    pub info: DeviceInfo,
    /// The optional features this device was created with.
    pub enabled: OptionalFeatures,
    /// The one queue used for everything: a graphics queue (also does transfers). Locked:
    /// Vulkan wants every use of a queue (a submission, a present, a wait for the idle
    /// device) externally synchronized, and the viewer presents from a thread of its own.
    queue: Mutex<vk::Queue>,
    pub queue_family: u32,
    /// Object names and command labels for captures; `None` without `VK_EXT_debug_utils`.
    debug_utils: Option<ash::ext::debug_utils::Device>,
    /// Dropped by hand in `Drop`, before `vkDestroyDevice`.
    allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Declared last: the instance must outlive the device.
    pub instance: Arc<Instance>,
}

impl Device {
    pub fn create(instance: &Arc<Instance>, desc: &DeviceDesc) -> Result<Arc<Self>, GpuError> {
        Self::create_with_extensions(instance, desc, &[])
    }

    /// [`Self::create`] with `extra` device extensions enabled as well (the viewer's
    /// `VK_KHR_swapchain`); a device that lacks one is refused by name.
    pub fn create_with_extensions(
        instance: &Arc<Instance>,
        desc: &DeviceDesc,
        extra: &[&'static CStr],
    ) -> Result<Arc<Self>, GpuError> {
        let candidates = enumerate(instance)?;
        let (physical, info, queue_family) = select(&candidates, desc.selector.as_deref())?;
        let want = desc.features;
        let missing = want.missing(&info.features);
        if !missing.is_empty() {
            return Err(GpuError::Unsupported(format!(
                "{} lacks {}",
                info.name,
                missing.join(", ")
            )));
        }
        check_extensions(instance, physical, &info, extra)?;
        let raw = create_raw(instance, (physical, &info, queue_family), want, extra)?;
        // SAFETY: family and index 0 were requested at creation.
        let queue = unsafe { raw.get_device_queue(queue_family, 0) };
        let allocator = match allocator(instance, &raw, physical, want.ray_query) {
            Ok(allocator) => allocator,
            Err(e) => {
                // SAFETY: nothing was made on the device yet.
                unsafe { raw.destroy_device(None) };
                return Err(e);
            }
        };
        let debug_utils = instance
            .debug_utils
            .as_ref()
            .map(|_| ash::ext::debug_utils::Device::new(&instance.raw, &raw));
        let device = Arc::new(Self {
            raw,
            physical,
            info,
            enabled: want,
            queue: Mutex::new(queue),
            queue_family,
            debug_utils,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            instance: Arc::clone(instance),
        });
        device.set_name(queue, "main queue");
        Ok(device)
    }

    /// The shader stages a graphics pipeline on this device can have: every classic graphics
    /// stage, plus task and mesh when mesh shading is enabled. Push-constant ranges and shared
    /// descriptor bindings use this set, so any pipeline built on this device can read them
    /// (naming a mesh stage without the feature would be invalid).
    pub fn graphics_stages(&self) -> vk::ShaderStageFlags {
        let mut stages = vk::ShaderStageFlags::ALL_GRAPHICS;
        if self.enabled.mesh_shader {
            stages |= vk::ShaderStageFlags::TASK_EXT | vk::ShaderStageFlags::MESH_EXT;
        }
        stages
    }

    /// The queue, locked for one submission or present (see the field). Poisoning only
    /// follows a panic elsewhere; the handle is still good.
    pub fn queue(&self) -> MutexGuard<'_, vk::Queue> {
        self.queue.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The allocator, locked. Poisoning only follows a panic elsewhere; recover the data.
    pub fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Names an object for validation messages and captures (no-op without debug utils).
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        let (Some(du), Ok(name)) = (&self.debug_utils, CString::new(name)) else {
            return;
        };
        let info = vk::DebugUtilsObjectNameInfoEXT::default()
            .object_handle(handle)
            .object_name(&name);
        // SAFETY: the handle belongs to this device. A naming failure is harmless: ignore it.
        let _ = unsafe { du.set_debug_utils_object_name(&info) };
    }

    /// Opens a labelled region in a command buffer (shows as a group in RenderDoc).
    pub fn begin_label(&self, cmd: vk::CommandBuffer, label: &str) {
        let (Some(du), Ok(label)) = (&self.debug_utils, CString::new(label)) else {
            return;
        };
        let info = vk::DebugUtilsLabelEXT::default().label_name(&label);
        // SAFETY: cmd is in the recording state.
        unsafe { du.cmd_begin_debug_utils_label(cmd, &info) };
    }

    pub fn end_label(&self, cmd: vk::CommandBuffer) {
        if let Some(du) = &self.debug_utils {
            // SAFETY: paired with begin_label on the same recording command buffer.
            unsafe { du.cmd_end_debug_utils_label(cmd) };
        }
    }

    /// Waits until the device has finished everything submitted. It holds the queue's lock
    /// meanwhile (Vulkan asks that every queue be left alone during the wait), so it also
    /// waits for a present in progress on another thread.
    pub fn wait_idle(&self) -> Result<(), GpuError> {
        let _queue = self.queue();
        // SAFETY: the device is live; its one queue is held.
        unsafe { self.raw.device_wait_idle() }.vk("vkDeviceWaitIdle")
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: every resource holds an Arc<Device>, so none is alive; the GPU may still be
        // finishing the last submission, hence the wait.
        unsafe {
            let _ = self.raw.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.raw.destroy_device(None);
        }
    }
}

/// Refuses a device that lacks one of the `extra` extensions, by name.
fn check_extensions(
    instance: &Instance,
    physical: vk::PhysicalDevice,
    info: &DeviceInfo,
    extra: &[&'static CStr],
) -> Result<(), GpuError> {
    // SAFETY: physical comes from this instance.
    let offered = unsafe { instance.raw.enumerate_device_extension_properties(physical) }
        .vk("vkEnumerateDeviceExtensionProperties")?;
    let has = |name: &CStr| (offered.iter()).any(|e| e.extension_name_as_c_str() == Ok(name));
    match extra.iter().find(|&&name| !has(name)) {
        Some(absent) => Err(GpuError::Unsupported(format!(
            "{} offers no device extension {}",
            info.name,
            absent.to_string_lossy()
        ))),
        None => Ok(()),
    }
}

/// `vkCreateDevice` with one queue of `queue_family`, the core features plus what `want`
/// adds (`features.rs`), and the extensions both need plus `extra`.
fn create_raw(
    instance: &Instance,
    (physical, info, queue_family): (vk::PhysicalDevice, &DeviceInfo, u32),
    want: OptionalFeatures,
    extra: &[&'static CStr],
) -> Result<ash::Device, GpuError> {
    let priorities = [1.0f32];
    let queue_infos = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(queue_family)
        .queue_priorities(&priorities)];
    let mut enables = want.enables(core_enables(&info.features));
    if let Some(mesh) = &mut enables.mesh {
        // Mesh and task invocations are counted by the statistics query only with this.
        *mesh = mesh.mesh_shader_queries(info.features.mesh_shader_queries);
    }
    let extensions: Vec<*const std::ffi::c_char> = (extra.iter().chain(&enables.extensions))
        .map(|name| name.as_ptr())
        .collect();
    let Enables {
        core,
        v11,
        v12,
        v13,
        mesh,
        acceleration,
        ray_query,
        ..
    } = &mut enables;
    let mut create_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_infos)
        .enabled_features(core)
        .push_next(v11)
        .push_next(v12)
        .push_next(v13);
    if let Some(m) = mesh {
        create_info = create_info.push_next(m);
    }
    if let Some(a) = acceleration {
        create_info = create_info.push_next(a);
    }
    if let Some(r) = ray_query {
        create_info = create_info.push_next(r);
    }
    let create_info = create_info.enabled_extension_names(&extensions);
    // SAFETY: physical comes from this instance; create_info points at live locals.
    unsafe { instance.raw.create_device(physical, &create_info, None) }.vk("vkCreateDevice")
}

/// The memory allocator of a new device. Buffers read by address (acceleration-structure
/// inputs) need their memory allocated with the device-address flag.
fn allocator(
    instance: &Instance,
    raw: &ash::Device,
    physical: vk::PhysicalDevice,
    device_address: bool,
) -> Result<Allocator, GpuError> {
    Allocator::new(&AllocatorCreateDesc {
        instance: instance.raw.clone(),
        device: raw.clone(),
        physical_device: physical,
        debug_settings: Default::default(),
        buffer_device_address: device_address,
        allocation_sizes: Default::default(),
    })
    .map_err(|source| GpuError::Alloc {
        name: "allocator".into(),
        source,
    })
}

/// The features every device is created with, whatever the renderer asks for: dynamic
/// rendering and synchronization2 (required), the texture array's indexing, and what the
/// device offers of work counters. (Anisotropic filtering is the mirror shaders' own, not the
/// sampler's: `samplerAnisotropy` is reported by `specchio info` but not enabled.)
fn core_enables(offered: &super::physical::DeviceFeatures) -> Enables {
    Enables {
        core: vk::PhysicalDeviceFeatures::default()
            .pipeline_statistics_query(offered.pipeline_statistics)
            // Materials pick their texture from an array by index...
            .shader_sampled_image_array_dynamic_indexing(true),
        // ... an index that may vary within a draw (materials.glsl, nonuniformEXT).
        v12: vk::PhysicalDeviceVulkan12Features::default()
            .shader_sampled_image_array_non_uniform_indexing(true)
            // Mandatory since Vulkan 1.2; a frame held for a test waits on one (`fault`).
            .timeline_semaphore(true),
        v13: vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true)
            // SPIR-V 1.6 turns `discard` into OpDemoteToHelperInvocation (mandatory in 1.3).
            .shader_demote_to_helper_invocation(true)
            // glslang may write any stage's workgroup size as LocalSizeId at SPIR-V 1.6 (12.0
            // does for compute shaders too), which needs maintenance4 (mandatory in 1.3).
            .maintenance4(true),
        ..Enables::default()
    }
}
