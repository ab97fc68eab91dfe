//! The optional device features a fill method or a mirror lookup may need, as one table:
//! each row says what the feature is called in messages, the device extensions it needs, how
//! its [`DeviceFeatures`] fields are read from the feature structs `physical.rs` queries
//! ([`Queried`]), whether a device offers it, and what asking for it enables when the device
//! is created. `OptionalFeatures` names the rows a renderer wants; a new optional feature is a
//! field there, its field(s) in `DeviceFeatures`, and a row here (and, for a feature struct
//! not queried yet, a field in `Queried` and `Enables` and a link in each chain).

use std::ffi::CStr;

use ash::vk;
use serde::{Deserialize, Serialize};

/// What a device offers, as `specchio info` prints it: read from [`Queried`] by
/// [`Queried::offered`] (the optional features through their rows).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
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

/// `VK_EXT_mesh_shader`: enabled with the mesh row; its feature and property structs are
/// queried only where the device offers it (SwiftShader warns about structs it does not know).
pub(super) const MESH_EXTENSIONS: &[&CStr] = &[ash::ext::mesh_shader::NAME];

/// `VK_KHR_ray_query` with what it builds on, in the order device creation names them; the
/// ray-query and acceleration-structure feature structs are queried only where the device
/// offers all three.
pub(super) const RAY_EXTENSIONS: &[&CStr] = &[
    ash::khr::acceleration_structure::NAME,
    ash::khr::ray_query::NAME,
    // Required by VK_KHR_acceleration_structure (we build on the device only).
    ash::khr::deferred_host_operations::NAME,
];

/// Optional device features a renderer can ask for on top of the core set. Device creation
/// enables exactly these and refuses a device that lacks one; the cube fill methods and the
/// lookups state theirs as this type (`render::methods::Needs`, `render::lookups`).
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

/// One optional feature: its row of the table.
struct Optional {
    /// The Vulkan names, as messages say them.
    vulkan: &'static str,
    /// Whether a renderer asks for it.
    wanted: fn(&OptionalFeatures) -> bool,
    /// The device extensions it needs: enabled with it (after what `enable` adds).
    extensions: &'static [&'static CStr],
    /// Its fields of `DeviceFeatures`, read from the queried feature structs.
    query: fn(&Queried, &mut DeviceFeatures),
    /// Whether the device offers it, from the fields `query` set.
    offered: fn(&DeviceFeatures) -> bool,
    /// What asking for it enables at device creation.
    enable: fn(&mut Enables),
}

/// The table: every optional feature, in the order messages list them.
const OPTIONAL: [Optional; 6] = [
    Optional {
        vulkan: "multiview",
        wanted: |w| w.multiview,
        extensions: &[],
        query: |q, d| d.multiview = on(q.f11.multiview),
        offered: |d| d.multiview,
        enable: |e| e.v11.multiview = vk::TRUE,
    },
    Optional {
        vulkan: "geometryShader",
        wanted: |w| w.geometry_shader,
        extensions: &[],
        query: |q, d| d.geometry_shader = on(q.base.geometry_shader),
        offered: |d| d.geometry_shader,
        enable: |e| e.core.geometry_shader = vk::TRUE,
    },
    Optional {
        vulkan: "shaderOutputLayer",
        wanted: |w| w.shader_output_layer,
        extensions: &[],
        query: |q, d| d.shader_output_layer = on(q.f12.shader_output_layer),
        offered: |d| d.shader_output_layer,
        enable: |e| e.v12.shader_output_layer = vk::TRUE,
    },
    Optional {
        vulkan: "multiDrawIndirect + drawIndirectFirstInstance",
        wanted: |w| w.multi_draw_indirect,
        extensions: &[],
        query: |q, d| {
            d.multi_draw_indirect = on(q.base.multi_draw_indirect);
            d.draw_indirect_first_instance = on(q.base.draw_indirect_first_instance);
        },
        offered: |d| d.multi_draw_indirect && d.draw_indirect_first_instance,
        enable: |e| {
            e.core.multi_draw_indirect = vk::TRUE;
            e.core.draw_indirect_first_instance = vk::TRUE;
        },
    },
    Optional {
        vulkan: "meshShader + taskShader (VK_EXT_mesh_shader)",
        wanted: |w| w.mesh_shader,
        extensions: MESH_EXTENSIONS,
        query: |q, d| {
            d.mesh_shader = on(q.mesh.mesh_shader);
            d.task_shader = on(q.mesh.task_shader);
        },
        offered: |d| d.mesh_shader && d.task_shader,
        enable: |e| {
            // (A task or mesh shader's workgroup size is LocalSizeId at SPIR-V 1.6, which needs
            // maintenance4: every device is created with it, `device::core_enables`.)
            e.mesh = Some(
                vk::PhysicalDeviceMeshShaderFeaturesEXT::default()
                    .mesh_shader(true)
                    .task_shader(true),
            );
        },
    },
    Optional {
        vulkan: "rayQuery + accelerationStructure (VK_KHR_ray_query, \
                 VK_KHR_acceleration_structure)",
        wanted: |w| w.ray_query,
        extensions: RAY_EXTENSIONS,
        query: |q, d| {
            d.ray_query = on(q.ray_query.ray_query)
                && on(q.acceleration.acceleration_structure)
                && on(q.f12.buffer_device_address)
        },
        offered: |d| d.ray_query,
        enable: |e| {
            // Acceleration-structure builds read their inputs by device address.
            e.v12.buffer_device_address = vk::TRUE;
            e.acceleration = Some(
                vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default()
                    .acceleration_structure(true),
            );
            e.ray_query = Some(vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true));
        },
    },
];

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
        (OPTIONAL.iter())
            .filter(|o| (o.wanted)(&self) && !(o.offered)(have))
            .map(|o| o.vulkan)
            .collect()
    }

    /// What device creation enables for these features, on top of `core`.
    pub(super) fn enables(self, core: Enables) -> Enables {
        let mut e = core;
        for o in OPTIONAL.iter().filter(|o| (o.wanted)(&self)) {
            (o.enable)(&mut e);
            e.extensions.extend(o.extensions);
        }
        e
    }
}

/// The feature structs `vkGetPhysicalDeviceFeatures2` filled (`physical.rs`): core, the 1.1 to
/// 1.3 sets, and the extensions' (all zero where the device lacks the extension: not chained).
pub(super) struct Queried {
    pub base: vk::PhysicalDeviceFeatures,
    pub f11: vk::PhysicalDeviceVulkan11Features<'static>,
    pub f12: vk::PhysicalDeviceVulkan12Features<'static>,
    pub f13: vk::PhysicalDeviceVulkan13Features<'static>,
    pub mesh: vk::PhysicalDeviceMeshShaderFeaturesEXT<'static>,
    pub ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR<'static>,
    pub acceleration: vk::PhysicalDeviceAccelerationStructureFeaturesKHR<'static>,
}

impl Queried {
    /// What the device offers, as the project names it: the features every device is created
    /// with (or with what it offers of them) here, the optional ones by their rows.
    pub(super) fn offered(&self, timestamps: bool) -> DeviceFeatures {
        let base = &self.base;
        let mut offered = DeviceFeatures {
            dynamic_rendering: on(self.f13.dynamic_rendering),
            synchronization2: on(self.f13.synchronization2),
            mesh_shader_queries: on(self.mesh.mesh_shader_queries)
                && on(base.pipeline_statistics_query),
            timestamps,
            pipeline_statistics: on(base.pipeline_statistics_query),
            sampler_anisotropy: on(base.sampler_anisotropy),
            // The optional features' fields: set by their rows, below.
            ..DeviceFeatures::default()
        };
        for o in &OPTIONAL {
            (o.query)(self, &mut offered);
        }
        offered
    }
}

fn on(b: vk::Bool32) -> bool {
    b == vk::TRUE
}

/// What `vkCreateDevice` is given: the feature structs (chained in `device.rs`) and the
/// device extensions.
#[derive(Default)]
pub(super) struct Enables {
    pub core: vk::PhysicalDeviceFeatures,
    pub v11: vk::PhysicalDeviceVulkan11Features<'static>,
    pub v12: vk::PhysicalDeviceVulkan12Features<'static>,
    pub v13: vk::PhysicalDeviceVulkan13Features<'static>,
    pub mesh: Option<vk::PhysicalDeviceMeshShaderFeaturesEXT<'static>>,
    pub acceleration: Option<vk::PhysicalDeviceAccelerationStructureFeaturesKHR<'static>>,
    pub ray_query: Option<vk::PhysicalDeviceRayQueryFeaturesKHR<'static>>,
    pub extensions: Vec<&'static CStr>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn every() -> OptionalFeatures {
        OptionalFeatures {
            multiview: true,
            geometry_shader: true,
            shader_output_layer: true,
            multi_draw_indirect: true,
            mesh_shader: true,
            ray_query: true,
        }
    }

    /// Each feature alone, in the order of the table's rows.
    fn singles() -> [OptionalFeatures; 6] {
        [
            OptionalFeatures {
                multiview: true,
                ..Default::default()
            },
            OptionalFeatures {
                geometry_shader: true,
                ..Default::default()
            },
            OptionalFeatures {
                shader_output_layer: true,
                ..Default::default()
            },
            OptionalFeatures {
                multi_draw_indirect: true,
                ..Default::default()
            },
            OptionalFeatures {
                mesh_shader: true,
                ..Default::default()
            },
            OptionalFeatures {
                ray_query: true,
                ..Default::default()
            },
        ]
    }

    /// Every field of `OptionalFeatures` has its row: asking for one feature alone enables
    /// something and, on a device that offers nothing, is missing by exactly one name.
    #[test]
    fn every_feature_has_its_row() {
        let nothing: DeviceFeatures = serde_json::from_value(serde_json::json!({
            "dynamic_rendering": true, "synchronization2": true, "multiview": false,
            "geometry_shader": false, "shader_output_layer": false, "mesh_shader": false,
            "task_shader": false, "mesh_shader_queries": false, "ray_query": false,
            "timestamps": false, "pipeline_statistics": false, "sampler_anisotropy": false,
            "multi_draw_indirect": false, "draw_indirect_first_instance": false
        }))
        .unwrap();
        let all = every();
        let single = singles();
        assert_eq!(
            single
                .iter()
                .fold(OptionalFeatures::default(), |a, b| a.union(*b)),
            all
        );
        for (f, row) in single.iter().zip(&OPTIONAL) {
            assert_eq!(f.missing(&nothing), [row.vulkan], "{f:?}");
        }
        assert_eq!(
            OptionalFeatures::default().missing(&nothing),
            Vec::<&str>::new()
        );
        let enabled = all.enables(Enables::default());
        assert_eq!(enabled.v11.multiview, vk::TRUE);
        assert_eq!(enabled.core.geometry_shader, vk::TRUE);
        assert_eq!(enabled.v12.buffer_device_address, vk::TRUE);
        assert!(enabled.mesh.is_some() && enabled.ray_query.is_some());
        // In the order of the rows, each row's own in its order.
        assert_eq!(
            enabled.extensions,
            [
                ash::ext::mesh_shader::NAME,
                ash::khr::acceleration_structure::NAME,
                ash::khr::ray_query::NAME,
                ash::khr::deferred_host_operations::NAME,
            ]
        );
        let none = OptionalFeatures::default().enables(Enables::default());
        assert!(none.extensions.is_empty() && none.mesh.is_none());
    }

    /// The feature structs device creation is given, as if a device had answered the query
    /// with them.
    fn as_queried(e: Enables) -> Queried {
        Queried {
            base: e.core,
            f11: e.v11,
            f12: e.v12,
            f13: e.v13,
            mesh: e.mesh.unwrap_or_default(),
            ray_query: e.ray_query.unwrap_or_default(),
            acceleration: e.acceleration.unwrap_or_default(),
        }
    }

    /// Each row's query reads what its enable sets: a device offering exactly what asking for
    /// one feature enables offers that feature; one offering nothing lacks every row.
    #[test]
    fn each_row_queries_what_it_enables() {
        let names: Vec<&str> = OPTIONAL.iter().map(|o| o.vulkan).collect();
        let nothing = as_queried(Enables::default()).offered(false);
        assert_eq!(every().missing(&nothing), names);
        for (alone, o) in singles().iter().zip(&OPTIONAL) {
            let offered = as_queried(alone.enables(Enables::default())).offered(false);
            assert!(alone.missing(&offered).is_empty(), "{}", o.vulkan);
            assert_eq!(
                every().missing(&offered).len(),
                names.len() - 1,
                "{}",
                o.vulkan
            );
        }
    }
}
