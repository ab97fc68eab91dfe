//! Physical-device selection, the logical device, its queue and its memory allocator.

use std::ffi::{CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::instance::Instance;
use super::{GpuError, VkContext};

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

/// Optional device features a renderer can ask for on top of the core set. Device creation
/// enables exactly these and refuses a device that lacks one; the cube fill methods state
/// theirs as this type (`render::methods::Needs`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OptionalFeatures {
    /// `VK_KHR_multiview` (core 1.1): one draw replayed per view.
    pub multiview: bool,
    pub geometry_shader: bool,
    /// `gl_Layer` written from a vertex shader (core 1.2).
    pub shader_output_layer: bool,
    /// multiDrawIndirect and drawIndirectFirstInstance, always asked for together.
    pub multi_draw_indirect: bool,
    /// `VK_EXT_mesh_shader` with its task shaders.
    pub mesh_shader: bool,
    /// `VK_KHR_ray_query` with `VK_KHR_acceleration_structure` (and the deferred host
    /// operations and buffer device addresses it requires): the exact mirror lookup.
    pub ray_query: bool,
}

impl OptionalFeatures {
    pub fn union(self, o: Self) -> Self {
        Self {
            multiview: self.multiview || o.multiview,
            geometry_shader: self.geometry_shader || o.geometry_shader,
            shader_output_layer: self.shader_output_layer || o.shader_output_layer,
            multi_draw_indirect: self.multi_draw_indirect || o.multi_draw_indirect,
            mesh_shader: self.mesh_shader || o.mesh_shader,
            ray_query: self.ray_query || o.ray_query,
        }
    }

    /// The features asked for that `have` lacks, by their Vulkan names.
    pub fn missing(self, have: &DeviceFeatures) -> Vec<&'static str> {
        [
            (self.multiview && !have.multiview, "multiview"),
            (
                self.geometry_shader && !have.geometry_shader,
                "geometryShader",
            ),
            (
                self.shader_output_layer && !have.shader_output_layer,
                "shaderOutputLayer",
            ),
            (
                self.multi_draw_indirect
                    && !(have.multi_draw_indirect && have.draw_indirect_first_instance),
                "multiDrawIndirect + drawIndirectFirstInstance",
            ),
            (
                self.mesh_shader && !(have.mesh_shader && have.task_shader),
                "meshShader + taskShader (VK_EXT_mesh_shader)",
            ),
            (
                self.ray_query && !have.ray_query,
                "rayQuery + accelerationStructure (VK_KHR_ray_query, VK_KHR_acceleration_structure)",
            ),
        ]
        .into_iter()
        .filter_map(|(lacks, name)| lacks.then_some(name))
        .collect()
    }
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
    /// The one queue used for everything: a graphics queue (also does transfers).
    pub queue: vk::Queue,
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

        let priorities = [1.0f32];
        let queue_infos = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        // Only what the renderer uses: anisotropic cube lookups and work counters when present.
        let features = vk::PhysicalDeviceFeatures::default()
            .sampler_anisotropy(info.features.sampler_anisotropy)
            .pipeline_statistics_query(info.features.pipeline_statistics)
            // Materials pick their texture from an array by index.
            .shader_sampled_image_array_dynamic_indexing(true)
            .geometry_shader(want.geometry_shader)
            .multi_draw_indirect(want.multi_draw_indirect)
            .draw_indirect_first_instance(want.multi_draw_indirect);
        let mut features11 =
            vk::PhysicalDeviceVulkan11Features::default().multiview(want.multiview);
        let mut features12 = vk::PhysicalDeviceVulkan12Features::default()
            .shader_output_layer(want.shader_output_layer)
            // ... an index that may vary within a draw (materials.glsl, nonuniformEXT).
            .shader_sampled_image_array_non_uniform_indexing(true)
            // Acceleration-structure builds read their inputs by device address.
            .buffer_device_address(want.ray_query);
        let mut features13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true)
            // SPIR-V 1.6 turns `discard` into OpDemoteToHelperInvocation (mandatory in 1.3).
            .shader_demote_to_helper_invocation(true)
            // glslang writes a task or mesh shader's workgroup size as LocalSizeId when it
            // targets SPIR-V 1.6, which needs maintenance4 (mandatory in 1.3).
            .maintenance4(want.mesh_shader);
        // Mesh and task shaders come from an extension; their invocations are counted by the
        // pipeline-statistics query only with meshShaderQueries.
        let mut mesh = vk::PhysicalDeviceMeshShaderFeaturesEXT::default()
            .mesh_shader(true)
            .task_shader(true)
            .mesh_shader_queries(info.features.mesh_shader_queries);
        let mut acceleration = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default()
            .acceleration_structure(true);
        let mut ray_query = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
        // SAFETY: physical comes from this instance.
        let offered = unsafe { instance.raw.enumerate_device_extension_properties(physical) }
            .vk("vkEnumerateDeviceExtensionProperties")?;
        if let Some(absent) = extra.iter().find(|&&name| {
            !offered
                .iter()
                .any(|e| e.extension_name_as_c_str() == Ok(name))
        }) {
            return Err(GpuError::Unsupported(format!(
                "{} offers no device extension {}",
                info.name,
                absent.to_string_lossy()
            )));
        }
        let mut extensions: Vec<*const std::ffi::c_char> =
            extra.iter().map(|name| name.as_ptr()).collect();
        let mut create_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_infos)
            .enabled_features(&features)
            .push_next(&mut features11)
            .push_next(&mut features12)
            .push_next(&mut features13);
        if want.mesh_shader {
            extensions.push(ash::ext::mesh_shader::NAME.as_ptr());
            create_info = create_info.push_next(&mut mesh);
        }
        if want.ray_query {
            extensions.extend([
                ash::khr::acceleration_structure::NAME.as_ptr(),
                ash::khr::ray_query::NAME.as_ptr(),
                // Required by VK_KHR_acceleration_structure (we build on the device only).
                ash::khr::deferred_host_operations::NAME.as_ptr(),
            ]);
            create_info = create_info
                .push_next(&mut acceleration)
                .push_next(&mut ray_query);
        }
        let create_info = create_info.enabled_extension_names(&extensions);
        // SAFETY: physical comes from this instance; create_info points at live locals.
        let raw = unsafe { instance.raw.create_device(physical, &create_info, None) }
            .vk("vkCreateDevice")?;
        // SAFETY: family and index 0 were requested above.
        let queue = unsafe { raw.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.raw.clone(),
            device: raw.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            // Buffers read by address (acceleration-structure inputs) need their memory
            // allocated with the device-address flag.
            buffer_device_address: want.ray_query,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| GpuError::Alloc {
            name: "allocator".into(),
            source,
        })?;
        let debug_utils = instance
            .debug_utils
            .as_ref()
            .map(|_| ash::ext::debug_utils::Device::new(&instance.raw, &raw));
        let device = Arc::new(Self {
            raw,
            physical,
            info,
            enabled: want,
            queue,
            queue_family,
            debug_utils,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            instance: Arc::clone(instance),
        });
        device.set_name(device.queue, "main queue");
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

    pub fn wait_idle(&self) -> Result<(), GpuError> {
        // SAFETY: no other thread submits to this device.
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
