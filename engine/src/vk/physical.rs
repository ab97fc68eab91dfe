//! Physical devices: what each can do (`DeviceInfo`: limits, features, driver), which are
//! usable, and which one a `--device` selector or the default ranking picks. The logical
//! device made from the choice is `device.rs`.

use ash::vk;
use serde::{Deserialize, Serialize};

use super::instance::Instance;
use super::{GpuError, VkContext};

/// Oldest Mesa whose lavapipe we trust (older ones miss fixes later methods rely on).
pub const MIN_MESA_MAJOR: u32 = 24;

/// What a device is and can do: everything `specchio info` prints.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    /// A short, stable name for `--device` and reports: `lavapipe`, `swiftshader` for the two
    /// CPU drivers we test on, else the driver's name in lower case.
    pub short_name: String,
    pub device_type: String,
    pub vendor_id: u32,
    pub device_id: u32,
    pub driver_name: String,
    pub driver_info: String,
    /// Packed driver version, decoded the Vulkan way (vendor-specific for some drivers).
    pub driver_version: String,
    pub api_version: String,
    /// Mesa version parsed from the driver info string, when the driver is Mesa.
    pub mesa_version: Option<String>,
    pub limits: DeviceLimits,
    pub features: DeviceFeatures,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeviceLimits {
    /// Bits of sub-texel position a linear filter uses (its weights are that coarse).
    pub sub_texel_precision_bits: u32,
    /// Bits of sub-pixel position the rasterizer snaps vertices to (at least 4; lavapipe 8,
    /// SwiftShader 4).
    pub sub_pixel_precision_bits: u32,
    pub max_image_dimension_cube: u32,
    pub max_image_dimension_2d: u32,
    pub max_image_array_layers: u32,
    pub max_push_constants_size: u32,
    pub max_sampler_anisotropy: f32,
    pub max_multiview_view_count: u32,
    pub max_geometry_output_vertices: u32,
    pub max_geometry_shader_invocations: u32,
    pub max_mesh_output_layers: u32,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f32,
    /// `maxMemoryAllocationSize`: the largest single allocation (one image or buffer) the
    /// driver promises to make (lavapipe: 2 GiB); larger requests may fail.
    pub max_memory_allocation_bytes: u64,
    /// The largest device-local heap: all the memory our images and buffers can share.
    pub device_local_heap_bytes: u64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeviceFeatures {
    pub dynamic_rendering: bool,
    pub synchronization2: bool,
    pub multiview: bool,
    pub geometry_shader: bool,
    /// `shaderOutputLayer`: `gl_Layer` written from the vertex shader.
    pub shader_output_layer: bool,
    pub mesh_shader: bool,
    pub task_shader: bool,
    /// Task and mesh shader invocations are counted by pipeline-statistics queries.
    pub mesh_shader_queries: bool,
    /// `rayQuery`, `accelerationStructure` and `bufferDeviceAddress` together: what tracing
    /// a ray from a fragment shader needs.
    pub ray_query: bool,
    pub timestamps: bool,
    pub pipeline_statistics: bool,
    pub sampler_anisotropy: bool,
    pub multi_draw_indirect: bool,
    pub draw_indirect_first_instance: bool,
}

/// One physical device with what we know about it, or why it cannot be used.
pub struct Candidate {
    pub physical: vk::PhysicalDevice,
    pub info: DeviceInfo,
    pub queue_family: Option<u32>,
    pub rejected: Option<String>,
}

/// Every physical device, with its info and (if unusable) the reason.
pub fn enumerate(instance: &Instance) -> Result<Vec<Candidate>, GpuError> {
    // SAFETY: plain query on a live instance.
    let physicals =
        unsafe { instance.raw.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    Ok(physicals
        .into_iter()
        .enumerate()
        .map(|(index, physical)| describe(instance, index, physical))
        .collect())
}

/// The size of the largest heap flagged device-local (every device has at least one).
fn device_local_heap_bytes(inst: &ash::Instance, physical: vk::PhysicalDevice) -> u64 {
    // SAFETY: plain query on an enumerated physical device.
    let memory = unsafe { inst.get_physical_device_memory_properties(physical) };
    let heaps = &memory.memory_heaps[..memory.memory_heap_count as usize];
    heaps
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or(0)
}

fn describe(instance: &Instance, index: usize, physical: vk::PhysicalDevice) -> Candidate {
    let inst = &instance.raw;
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut multiview_props = vk::PhysicalDeviceMultiviewProperties::default();
    let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut mesh_props = vk::PhysicalDeviceMeshShaderPropertiesEXT::default();
    // SAFETY: plain query; a failure reads as "no extensions".
    let exts: Vec<String> = unsafe { inst.enumerate_device_extension_properties(physical) }
        .unwrap_or_default()
        .iter()
        .filter_map(|e| e.extension_name_as_c_str().ok())
        .map(|n| n.to_string_lossy().into_owned())
        .collect();
    let has_ext = |n: &std::ffi::CStr| exts.iter().any(|e| e.as_bytes() == n.to_bytes());
    let mut props2 = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut driver)
        .push_next(&mut multiview_props)
        .push_next(&mut maintenance3);
    // Chained only where the extension exists: SwiftShader warns on stderr about structs it
    // does not know.
    if has_ext(ash::ext::mesh_shader::NAME) {
        props2 = props2.push_next(&mut mesh_props);
    }
    // SAFETY: the chained structs are core 1.2+ or belong to a supported extension.
    unsafe { inst.get_physical_device_properties2(physical, &mut props2) };
    let props = props2.properties;

    let mut f11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut mesh = vk::PhysicalDeviceMeshShaderFeaturesEXT::default();
    let mut rq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut accel = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let api_ok = props.api_version >= vk::API_VERSION_1_3;
    let mut features2 = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut f11)
        .push_next(&mut f12);
    if api_ok {
        features2 = features2.push_next(&mut f13);
    }
    if has_ext(ash::ext::mesh_shader::NAME) {
        features2 = features2.push_next(&mut mesh);
    }
    let ray_exts = has_ext(ash::khr::ray_query::NAME)
        && has_ext(ash::khr::acceleration_structure::NAME)
        && has_ext(ash::khr::deferred_host_operations::NAME);
    if ray_exts {
        features2 = features2.push_next(&mut rq).push_next(&mut accel);
    }
    // SAFETY: only structs the device understands (by version or extension) are chained.
    unsafe { inst.get_physical_device_features2(physical, &mut features2) };
    let base = features2.features;

    // SAFETY: plain query.
    let families = unsafe { inst.get_physical_device_queue_family_properties(physical) };
    let queue_family = families
        .iter()
        .position(|f| {
            f.queue_flags.contains(vk::QueueFlags::GRAPHICS) && f.timestamp_valid_bits > 0
        })
        .or_else(|| {
            families
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))
        })
        .map(|i| i as u32);
    let timestamps = queue_family
        .map(|q| families[q as usize].timestamp_valid_bits > 0)
        .unwrap_or(false)
        && props.limits.timestamp_period > 0.0;

    let name = props
        .device_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let driver_info = driver
        .driver_info_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let driver_name = driver
        .driver_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let info = DeviceInfo {
        index,
        name,
        short_name: short_name(driver.driver_id, &driver_name),
        device_type: format!("{:?}", props.device_type),
        vendor_id: props.vendor_id,
        device_id: props.device_id,
        driver_name,
        mesa_version: parse_mesa_version(&driver_info),
        driver_info,
        driver_version: version_string(props.driver_version),
        api_version: version_string(props.api_version),
        limits: DeviceLimits {
            sub_texel_precision_bits: props.limits.sub_texel_precision_bits,
            sub_pixel_precision_bits: props.limits.sub_pixel_precision_bits,
            max_image_dimension_cube: props.limits.max_image_dimension_cube,
            max_image_dimension_2d: props.limits.max_image_dimension2_d,
            max_image_array_layers: props.limits.max_image_array_layers,
            max_push_constants_size: props.limits.max_push_constants_size,
            max_sampler_anisotropy: props.limits.max_sampler_anisotropy,
            max_multiview_view_count: multiview_props.max_multiview_view_count,
            max_geometry_output_vertices: props.limits.max_geometry_output_vertices,
            max_geometry_shader_invocations: props.limits.max_geometry_shader_invocations,
            max_mesh_output_layers: if mesh.mesh_shader == vk::TRUE {
                mesh_props.max_mesh_output_layers
            } else {
                0
            },
            timestamp_period_ns: props.limits.timestamp_period,
            max_memory_allocation_bytes: maintenance3.max_memory_allocation_size,
            device_local_heap_bytes: device_local_heap_bytes(inst, physical),
        },
        features: DeviceFeatures {
            dynamic_rendering: f13.dynamic_rendering == vk::TRUE,
            synchronization2: f13.synchronization2 == vk::TRUE,
            multiview: f11.multiview == vk::TRUE,
            geometry_shader: base.geometry_shader == vk::TRUE,
            shader_output_layer: f12.shader_output_layer == vk::TRUE,
            mesh_shader: mesh.mesh_shader == vk::TRUE,
            task_shader: mesh.task_shader == vk::TRUE,
            mesh_shader_queries: mesh.mesh_shader_queries == vk::TRUE
                && base.pipeline_statistics_query == vk::TRUE,
            ray_query: rq.ray_query == vk::TRUE
                && accel.acceleration_structure == vk::TRUE
                && f12.buffer_device_address == vk::TRUE,
            timestamps,
            pipeline_statistics: base.pipeline_statistics_query == vk::TRUE,
            sampler_anisotropy: base.sampler_anisotropy == vk::TRUE,
            multi_draw_indirect: base.multi_draw_indirect == vk::TRUE,
            draw_indirect_first_instance: base.draw_indirect_first_instance == vk::TRUE,
        },
    };
    let rejected = if !api_ok {
        Some(format!(
            "supports Vulkan {} only; 1.3 is required",
            info.api_version
        ))
    } else if queue_family.is_none() {
        Some("has no graphics queue".into())
    } else if base.shader_sampled_image_array_dynamic_indexing != vk::TRUE
        || f12.shader_sampled_image_array_non_uniform_indexing != vk::TRUE
    {
        Some(
            "lacks shaderSampledImageArrayDynamicIndexing or ...NonUniformIndexing (material \
             textures)"
                .into(),
        )
    } else if !info.features.dynamic_rendering || !info.features.synchronization2 {
        Some("lacks dynamicRendering or synchronization2 (Vulkan 1.3 core features)".into())
    } else {
        None
    };
    Candidate {
        physical,
        info,
        queue_family,
        rejected,
    }
}

/// The device `Device::create` would pick for `selector`, without creating it.
pub fn choose(instance: &Instance, selector: Option<&str>) -> Result<DeviceInfo, GpuError> {
    let candidates = enumerate(instance)?;
    select(&candidates, selector).map(|(_, info, _)| info)
}

/// Picks a device: the one the selector names, else the best-ranked usable one.
pub(super) fn select(
    candidates: &[Candidate],
    selector: Option<&str>,
) -> Result<(vk::PhysicalDevice, DeviceInfo, u32), GpuError> {
    let mut report = Vec::new();
    let mut best: Option<(&Candidate, Rank)> = None;
    for c in candidates {
        let matches = selector.is_none_or(|s| c.info.selected_by(s));
        if !matches {
            report.push(format!(
                "  [{}] {}: not selected by --device {}",
                c.info.index,
                c.info.name,
                selector.unwrap_or("")
            ));
            continue;
        }
        if let Some(why) = &c.rejected {
            report.push(format!("  [{}] {}: {why}", c.info.index, c.info.name));
            continue;
        }
        let rank = c.info.rank();
        if best.as_ref().is_none_or(|(_, r)| rank > *r) {
            best = Some((c, rank));
        }
    }
    match best {
        Some((c, _)) => Ok((
            c.physical,
            c.info.clone(),
            c.queue_family
                .expect("usable candidates have a graphics queue"),
        )),
        None if candidates.is_empty() => Err(GpuError::NoDevice(
            "  the loader found no device; install a driver (Debian: mesa-vulkan-drivers)".into(),
        )),
        None => Err(GpuError::NoDevice(report.join("\n"))),
    }
}

/// How a device ranks for the default choice: GPUs before CPUs, then the one that can run
/// more (lavapipe before SwiftShader), then by name, so that the choice does not depend on
/// the order in which the loader lists its drivers.
type Rank = (u32, u32, std::cmp::Reverse<String>);

impl DeviceInfo {
    fn rank(&self) -> Rank {
        let kind = match self.device_type.as_str() {
            "DISCRETE_GPU" => 4,
            "INTEGRATED_GPU" => 3,
            "VIRTUAL_GPU" => 2,
            "CPU" => 1,
            _ => 0,
        };
        let f = &self.features;
        let abilities = [
            f.multiview,
            f.geometry_shader,
            f.shader_output_layer,
            f.mesh_shader,
            f.ray_query,
            f.pipeline_statistics,
            f.timestamps,
        ];
        let can = abilities.iter().filter(|&&b| b).count() as u32;
        (kind, can, std::cmp::Reverse(self.name.clone()))
    }

    /// Whether `--device SELECTOR` names this device: its index, or a case-insensitive part
    /// of its name, short name or driver name.
    pub fn selected_by(&self, selector: &str) -> bool {
        if let Ok(i) = selector.parse::<usize>() {
            return i == self.index;
        }
        let s = selector.to_lowercase();
        [&self.name, &self.short_name, &self.driver_name]
            .iter()
            .any(|n| n.to_lowercase().contains(&s))
    }
}

/// See [`DeviceInfo::short_name`].
fn short_name(id: vk::DriverId, driver_name: &str) -> String {
    match id {
        vk::DriverId::MESA_LLVMPIPE => "lavapipe".into(),
        vk::DriverId::GOOGLE_SWIFTSHADER => "swiftshader".into(),
        _ => driver_name.to_lowercase().replace(' ', "-"),
    }
}

fn version_string(v: u32) -> String {
    format!(
        "{}.{}.{}",
        vk::api_version_major(v),
        vk::api_version_minor(v),
        vk::api_version_patch(v)
    )
}

/// "Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)" -> "25.0.7".
pub fn parse_mesa_version(driver_info: &str) -> Option<String> {
    let rest = driver_info.split("Mesa ").nth(1)?;
    let version: String = rest
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.')
        .collect();
    (!version.is_empty()).then_some(version)
}

/// The Mesa major version, when the driver is Mesa.
pub fn mesa_major(info: &DeviceInfo) -> Option<u32> {
    info.mesa_version
        .as_deref()?
        .split('.')
        .next()?
        .parse()
        .ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mesa_version_is_parsed_from_driver_info() {
        assert_eq!(
            parse_mesa_version("Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)").as_deref(),
            Some("25.0.7")
        );
        assert_eq!(parse_mesa_version("NVIDIA 550.1"), None);
    }
}
