//! Physical devices: what each can do (`DeviceInfo`: limits, features, driver), which are
//! usable, and which one a `--device` selector or the default ranking picks. The logical
//! device made from the choice is `device.rs`.

use ash::vk;
use serde::{Deserialize, Serialize};

use super::features::{Queried, MESH_EXTENSIONS, RAY_EXTENSIONS};
use super::instance::Instance;
use super::{GpuError, VkContext};

// What a device offers is read from the queried structs by the feature table (`features.rs`);
// re-exported here, beside the rest of what `specchio info` prints.
pub use super::features::DeviceFeatures;

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
    /// `maxStorageBufferRange`: the most bytes one storage-buffer descriptor may span (at least
    /// 2^27). Not written into records (their schema is fixed: bench/src/record.rs); one read
    /// back from a record has 0, unknown.
    #[serde(skip)]
    pub max_storage_buffer_range: u64,
    /// The largest device-local heap: all the memory our images and buffers can share.
    pub device_local_heap_bytes: u64,
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

/// One physical device as a candidate: what it is, what it has, and why it cannot be used
/// (if it cannot).
fn describe(instance: &Instance, index: usize, physical: vk::PhysicalDevice) -> Candidate {
    let inst = &instance.raw;
    let extensions = extensions(inst, physical);
    let has = |n: &std::ffi::CStr| extensions.iter().any(|e| e.as_bytes() == n.to_bytes());
    let p = Properties::query(inst, physical, &has);
    let f = query_features(inst, physical, &has, p.core.api_version);
    let (queue_family, timestamp_bits) = graphics_queue(inst, physical);
    let timestamps = timestamp_bits && p.core.limits.timestamp_period > 0.0;
    let text = |c: Result<&std::ffi::CStr, _>| c.map(|s| s.to_string_lossy().into_owned());
    let name = text(p.core.device_name_as_c_str()).unwrap_or_default();
    let driver_info = text(p.driver.driver_info_as_c_str()).unwrap_or_default();
    let driver_name = text(p.driver.driver_name_as_c_str()).unwrap_or_default();
    let info = DeviceInfo {
        index,
        name,
        short_name: short_name(p.driver.driver_id, &driver_name),
        device_type: format!("{:?}", p.core.device_type),
        vendor_id: p.core.vendor_id,
        device_id: p.core.device_id,
        driver_name,
        mesa_version: parse_mesa_version(&driver_info),
        driver_info,
        driver_version: version_string(p.core.driver_version),
        api_version: version_string(p.core.api_version),
        limits: p.limits(&f, device_local_heap_bytes(inst, physical)),
        features: f.offered(timestamps),
    };
    let rejected = rejection(&info, &f, p.core.api_version, queue_family);
    Candidate {
        physical,
        info,
        queue_family,
        rejected,
    }
}

/// The device extensions it offers, by name (a failed query reads as none).
fn extensions(inst: &ash::Instance, physical: vk::PhysicalDevice) -> Vec<String> {
    // SAFETY: plain query on an enumerated physical device.
    unsafe { inst.enumerate_device_extension_properties(physical) }
        .unwrap_or_default()
        .iter()
        .filter_map(|e| e.extension_name_as_c_str().ok())
        .map(|n| n.to_string_lossy().into_owned())
        .collect()
}

/// The first graphics queue family with timestamps, else the first graphics one; and
/// whether it has timestamps.
fn graphics_queue(inst: &ash::Instance, physical: vk::PhysicalDevice) -> (Option<u32>, bool) {
    // SAFETY: plain query on an enumerated physical device.
    let families = unsafe { inst.get_physical_device_queue_family_properties(physical) };
    let graphics =
        |f: &&vk::QueueFamilyProperties| f.queue_flags.contains(vk::QueueFlags::GRAPHICS);
    let family = (families
        .iter()
        .position(|f| graphics(&f) && f.timestamp_valid_bits > 0))
    .or_else(|| families.iter().position(|f| graphics(&f)));
    let timestamps = family.is_some_and(|q| families[q].timestamp_valid_bits > 0);
    (family.map(|q| q as u32), timestamps)
}

/// The properties queried, core and chained.
struct Properties {
    core: vk::PhysicalDeviceProperties,
    driver: vk::PhysicalDeviceDriverProperties<'static>,
    multiview: vk::PhysicalDeviceMultiviewProperties<'static>,
    maintenance3: vk::PhysicalDeviceMaintenance3Properties<'static>,
    /// Zero where the device has no mesh shaders.
    mesh: vk::PhysicalDeviceMeshShaderPropertiesEXT<'static>,
}

impl Properties {
    fn query(
        inst: &ash::Instance,
        physical: vk::PhysicalDevice,
        has: &dyn Fn(&std::ffi::CStr) -> bool,
    ) -> Self {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut multiview = vk::PhysicalDeviceMultiviewProperties::default();
        let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
        let mut mesh = vk::PhysicalDeviceMeshShaderPropertiesEXT::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default()
            .push_next(&mut driver)
            .push_next(&mut multiview)
            .push_next(&mut maintenance3);
        // Chained only where the extension exists: SwiftShader warns on stderr about structs
        // it does not know.
        if MESH_EXTENSIONS.iter().all(|&n| has(n)) {
            props2 = props2.push_next(&mut mesh);
        }
        // SAFETY: the chained structs are core 1.2+ or belong to a supported extension.
        unsafe { inst.get_physical_device_properties2(physical, &mut props2) };
        let core = props2.properties;
        // The chain's pointers are not followed again: each struct is kept for its values.
        let null = std::ptr::null_mut();
        Self {
            core,
            driver: vk::PhysicalDeviceDriverProperties {
                p_next: null,
                ..driver
            },
            multiview: vk::PhysicalDeviceMultiviewProperties {
                p_next: null,
                ..multiview
            },
            maintenance3: vk::PhysicalDeviceMaintenance3Properties {
                p_next: null,
                ..maintenance3
            },
            mesh: vk::PhysicalDeviceMeshShaderPropertiesEXT {
                p_next: null,
                ..mesh
            },
        }
    }

    fn limits(&self, f: &Queried, device_local_heap_bytes: u64) -> DeviceLimits {
        let l = &self.core.limits;
        DeviceLimits {
            sub_texel_precision_bits: l.sub_texel_precision_bits,
            sub_pixel_precision_bits: l.sub_pixel_precision_bits,
            max_image_dimension_cube: l.max_image_dimension_cube,
            max_image_dimension_2d: l.max_image_dimension2_d,
            max_image_array_layers: l.max_image_array_layers,
            max_push_constants_size: l.max_push_constants_size,
            max_sampler_anisotropy: l.max_sampler_anisotropy,
            max_multiview_view_count: self.multiview.max_multiview_view_count,
            max_geometry_output_vertices: l.max_geometry_output_vertices,
            max_geometry_shader_invocations: l.max_geometry_shader_invocations,
            max_mesh_output_layers: if f.mesh.mesh_shader == vk::TRUE {
                self.mesh.max_mesh_output_layers
            } else {
                0
            },
            timestamp_period_ns: l.timestamp_period,
            max_memory_allocation_bytes: self.maintenance3.max_memory_allocation_size,
            max_storage_buffer_range: u64::from(l.max_storage_buffer_range),
            device_local_heap_bytes,
        }
    }
}

/// The features queried: core, the 1.1 to 1.3 sets, and the extensions' where offered.
fn query_features(
    inst: &ash::Instance,
    physical: vk::PhysicalDevice,
    has: &dyn Fn(&std::ffi::CStr) -> bool,
    api_version: u32,
) -> Queried {
    let offers = |names: &[&std::ffi::CStr]| names.iter().all(|&n| has(n));
    let mut f11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut mesh = vk::PhysicalDeviceMeshShaderFeaturesEXT::default();
    let mut ray_query = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut acceleration = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut features2 = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut f11)
        .push_next(&mut f12);
    if api_version >= vk::API_VERSION_1_3 {
        features2 = features2.push_next(&mut f13);
    }
    if offers(MESH_EXTENSIONS) {
        features2 = features2.push_next(&mut mesh);
    }
    if offers(RAY_EXTENSIONS) {
        features2 = features2
            .push_next(&mut ray_query)
            .push_next(&mut acceleration);
    }
    // SAFETY: only structs the device understands (by version or extension) are chained.
    unsafe { inst.get_physical_device_features2(physical, &mut features2) };
    let base = features2.features;
    // The chain's pointers are not followed again: each struct is kept for its values.
    let null = std::ptr::null_mut();
    Queried {
        base,
        f11: vk::PhysicalDeviceVulkan11Features {
            p_next: null,
            ..f11
        },
        f12: vk::PhysicalDeviceVulkan12Features {
            p_next: null,
            ..f12
        },
        f13: vk::PhysicalDeviceVulkan13Features {
            p_next: null,
            ..f13
        },
        mesh: vk::PhysicalDeviceMeshShaderFeaturesEXT {
            p_next: null,
            ..mesh
        },
        ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR {
            p_next: null,
            ..ray_query
        },
        acceleration: vk::PhysicalDeviceAccelerationStructureFeaturesKHR {
            p_next: null,
            ..acceleration
        },
    }
}

/// Why the device cannot be used at all (None: it can).
fn rejection(
    info: &DeviceInfo,
    f: &Queried,
    api_version: u32,
    queue_family: Option<u32>,
) -> Option<String> {
    if api_version < vk::API_VERSION_1_3 {
        Some(format!(
            "supports Vulkan {} only; 1.3 is required",
            info.api_version
        ))
    } else if queue_family.is_none() {
        Some("has no graphics queue".into())
    } else if f.base.shader_sampled_image_array_dynamic_indexing != vk::TRUE
        || f.f12.shader_sampled_image_array_non_uniform_indexing != vk::TRUE
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
    if let Some(s) = selector {
        refuse_unclear(candidates, s)?;
    }
    let mut report = Vec::new();
    let mut best: Option<(&Candidate, Rank)> = None;
    for c in candidates {
        let matches = selector.is_none_or(|s| c.info.selected_by(s));
        if !matches {
            report.push(format!(
                "  [{}] {}: not selected by --device {:?}",
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

/// Refuses a selector that names no device clearly: an empty one (it is in every name) and
/// one that more than one device's names contain (`e`): either would pick a device the user
/// did not name. An index, or a name one device alone has, is clear.
fn refuse_unclear(candidates: &[Candidate], selector: &str) -> Result<(), GpuError> {
    let named: Vec<String> = (candidates.iter())
        .filter(|c| c.info.selected_by(selector))
        .map(|c| {
            format!(
                "  [{}] {} ({})",
                c.info.index, c.info.name, c.info.short_name
            )
        })
        .collect();
    if selector.trim().is_empty() {
        return Err(GpuError::NoDevice(format!(
            "  --device {selector:?} names no device: give an index or part of a name \
             (`specchio info` lists them)"
        )));
    }
    if named.len() > 1 {
        return Err(GpuError::NoDevice(format!(
            "  --device {selector:?} is in more than one device's name; give its index or more \
             of its name:\n{}",
            named.join("\n")
        )));
    }
    Ok(())
}

/// How a device ranks for the default choice: GPUs before CPUs, then the one that can run
/// more (lavapipe before SwiftShader), then by name, so that the choice does not depend on
/// the order in which the loader lists its drivers.
type Rank = (u32, u32, std::cmp::Reverse<String>);

impl DeviceInfo {
    /// Whether the device is a CPU driver (lavapipe, SwiftShader): its shaders run on the
    /// host's cores, and it has no ray-tracing hardware behind its ray queries.
    pub fn is_cpu(&self) -> bool {
        self.device_type == "CPU"
    }

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
