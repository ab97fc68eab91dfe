//! The sensor's ray map on the GPU: two passes over the sensor view that write, per mirror
//! pixel, the mirror point with the range (`MIRROR_RAY_*ORIGIN_FRAG`) and the reflected
//! direction with the id of what the ray meets (`MIRROR_RAY_*DIRECTION_FRAG`). The ray itself
//! is every lookup's (`mirror_hit`, `reflect`); what it meets comes from one of two places
//! ([`GroundTruth`]):
//!
//! - traced (`mirror_ray.frag.glsl` built with `TRACED` and the lookup's tracer), when the lookup
//!   traces (`ray-query`, `bvh`): through the lookup's own set, exactly as the colour pass's
//!   trace, so the colour, the range and the ids of a frame come from one light path;
//! - through the cube (`mirror_ray.frag.glsl`, `shaders/include/sensor_ray.glsl`) otherwise:
//!   the distance lookup's search along the reflected ray through the cube's depth, and the id
//!   cube's texel where it lands. That is exact only where the cube's centre saw what the ray
//!   meets, and the colour's lookup may look elsewhere: the outputs' JSON says which it was.
//!
//! The renderer owns the passes rather than a lookup plug-in and makes them on first use.
//! `sensor::SensorOutputs::from_gpu` turns the two images into the ray map, range and ids.

use std::sync::Arc;

use ash::vk;

use super::lookups::TraceSet;
use super::pipelines::mirror_pipeline;
use super::targets::{CubeTarget, ViewTarget, DIRECTION_FORMAT};
use super::Renderer;
use crate::sensor::GroundTruth;
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::Device;
use crate::vk::image::Sampler;
use crate::vk::pipeline::{Pipeline, PipelineLayout};
use crate::vk::GpuError;

/// What the mirror writes in a view pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum MirrorOutput {
    /// The lookup's colour.
    Colour,
    /// The direction the lookup looked up (`--directions`).
    LookupDirection,
    /// The ray map's hit point and range.
    RayOrigin,
    /// The ray map's reflected direction and id.
    RayDirection,
}

/// The two ray-map pipelines (origin, direction) and the set they read at set 1: the lookup's
/// trace set, or a set of their own with the cube's depth (binding 1) and the id cube (binding
/// 2), both read texel by texel. Field order is drop order.
pub(super) struct SensorRays {
    pub origin: Pipeline,
    pub direction: Pipeline,
    pub layout: PipelineLayout,
    pub set: vk::DescriptorSet,
    /// The cube path's own set and what it holds (None when the set is the lookup's).
    _cube_set: Option<CubeSet>,
}

/// The cube path's set 1 and what it reads. Field order is drop order.
struct CubeSet {
    _pool: DescriptorPool,
    _layout: DescriptorSetLayout,
    _nearest: Sampler,
}

impl SensorRays {
    /// The traced passes: the lookup's ray-map shaders, reading its trace set
    /// (`LookupPass::trace_set`).
    fn traced(
        device: &Arc<Device>,
        scene_set_layout: vk::DescriptorSetLayout,
        trace: TraceSet,
        push_size: u32,
    ) -> Result<Self, GpuError> {
        let layouts = [scene_set_layout, trace.layout];
        let (origin, direction, layout) =
            Self::pipelines(device, &layouts, trace.ray_map, push_size)?;
        Ok(Self {
            origin,
            direction,
            layout,
            set: trace.set,
            _cube_set: None,
        })
    }

    /// The passes through `cube`, which must have an id cube (`RenderOptions::id_cube`).
    fn through_cube(
        device: &Arc<Device>,
        scene_set_layout: vk::DescriptorSetLayout,
        cube: &CubeTarget,
        push_size: u32,
    ) -> Result<Self, GpuError> {
        let ids = cube.ids.as_ref().ok_or_else(|| {
            GpuError::Unsupported(
                "the sensor's ray map reads the id cube, and this renderer was made without \
                 one (RenderOptions::id_cube)"
                    .into(),
            )
        })?;
        let stage = vk::ShaderStageFlags::FRAGMENT;
        let sampled = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let bindings = [
            descriptors::binding(1, sampled, 1, stage),
            descriptors::binding(2, sampled, 1, stage),
        ];
        let set_layout = DescriptorSetLayout::create(device, &bindings, "sensor ray set layout")?;
        let size = vk::DescriptorPoolSize {
            ty: sampled,
            descriptor_count: 2,
        };
        let pool = DescriptorPool::create(device, 1, &[size], "sensor ray descriptors")?;
        let set = pool.allocate(&set_layout, "sensor ray set")?;
        let nearest = Sampler::nearest(device, "sensor ray sampler")?;
        descriptors::write_images(device, set, 1, &[(cube.depth_layers_view.raw, nearest.raw)]);
        descriptors::write_images(device, set, 2, &[(ids.layers_view.raw, nearest.raw)]);
        let shaders = [
            crate::shaders::MIRROR_RAY_ORIGIN_FRAG,
            crate::shaders::MIRROR_RAY_DIRECTION_FRAG,
        ];
        let layouts = [scene_set_layout, set_layout.raw];
        let (origin, direction, layout) = Self::pipelines(device, &layouts, shaders, push_size)?;
        Ok(Self {
            origin,
            direction,
            layout,
            set,
            _cube_set: Some(CubeSet {
                _pool: pool,
                _layout: set_layout,
                _nearest: nearest,
            }),
        })
    }

    /// The origin and direction pipelines of `shaders` over sets `layouts`.
    fn pipelines(
        device: &Arc<Device>,
        layouts: &[vk::DescriptorSetLayout; 2],
        [origin, direction]: [&[u32]; 2],
        push_size: u32,
    ) -> Result<(Pipeline, Pipeline, PipelineLayout), GpuError> {
        let layout = PipelineLayout::create(device, layouts, push_size, "sensor ray layout")?;
        let make = |spirv, name| mirror_pipeline(device, &layout, spirv, DIRECTION_FORMAT, name);
        let origin = make(origin, "sensor ray origin pipeline")?;
        let direction = make(direction, "sensor ray direction pipeline")?;
        Ok((origin, direction, layout))
    }
}

impl Renderer {
    /// The ray map's passes and two full-float targets at the sensor's resolution, made on
    /// the first frame that reads the ray map back: traced where the lookup traces, else
    /// through the cube.
    pub(super) fn prepare_sensor_rays(&mut self) -> Result<(), GpuError> {
        if self.views.sensor_rays.is_some() {
            return Ok(());
        }
        let scene_layout = self.resources.scene_set_layout.raw;
        let push_size = std::mem::size_of::<super::gpu::Push>() as u32;
        let passes = match self.mirror.pass.trace_set() {
            Some(trace) => SensorRays::traced(&self.device, scene_layout, trace, push_size)?,
            None => SensorRays::through_cube(&self.device, scene_layout, &self.cube, push_size)?,
        };
        let [w, h] = self.scene.sensor.resolution;
        let targets = [
            ViewTarget::create(&self.device, DIRECTION_FORMAT, w, h, "sensor ray origins")?,
            ViewTarget::create(
                &self.device,
                DIRECTION_FORMAT,
                w,
                h,
                "sensor ray directions",
            )?,
        ];
        self.views.sensor_rays = Some((passes, targets));
        Ok(())
    }

    /// Where this renderer's sensor range and ids come from (its lookup decides).
    pub fn sensor_ground_truth(&self) -> GroundTruth {
        if self.mirror.pass.trace_set().is_some() {
            GroundTruth::Traced
        } else {
            GroundTruth::Cube
        }
    }
}
