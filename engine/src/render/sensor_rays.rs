//! The sensor's ray map on the GPU: two passes over the sensor view that write, per mirror
//! pixel, the sphere hit with the range (`mirror_ray.frag.glsl` built as `mirror_ray_origin`) and the reflected
//! direction with the id of what the ray meets (built as `mirror_ray_direction`). Range and
//! id come through the cube (`shaders/include/sensor_ray.glsl`): the distance lookup's search
//! along the reflected ray through the cube's depth, and the id cube's texel where it lands.
//! They depend on no lookup (the ray is the same whatever the cube lookup does with it), so
//! the renderer owns them rather than a lookup plug-in, and makes them on first use.
//! `sensor::SensorOutputs::from_gpu` turns the two images into the ray map, range and ids.

use std::sync::Arc;

use ash::vk;

use super::pipelines::mirror_pipeline;
use super::targets::{CubeTarget, ViewTarget, DIRECTION_FORMAT};
use super::Renderer;
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

/// The two ray-map pipelines (origin, direction) and their set 1: the cube's depth
/// (binding 1) and the id cube (binding 2), both read texel by texel. Field order is drop
/// order.
pub(super) struct SensorRays {
    pub origin: Pipeline,
    pub direction: Pipeline,
    pub layout: PipelineLayout,
    _pool: DescriptorPool,
    pub set: vk::DescriptorSet,
    _set_layout: DescriptorSetLayout,
    _nearest: Sampler,
}

impl SensorRays {
    /// The passes over `cube`, which must have an id cube (`RenderOptions::id_cube`).
    fn create(
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
        let layout = PipelineLayout::create(
            device,
            &[scene_set_layout, set_layout.raw],
            push_size,
            "sensor ray layout",
        )?;
        let origin = mirror_pipeline(
            device,
            &layout,
            crate::shaders::MIRROR_RAY_ORIGIN_FRAG,
            DIRECTION_FORMAT,
            "sensor ray origin pipeline",
        )?;
        let direction = mirror_pipeline(
            device,
            &layout,
            crate::shaders::MIRROR_RAY_DIRECTION_FRAG,
            DIRECTION_FORMAT,
            "sensor ray direction pipeline",
        )?;
        Ok(Self {
            origin,
            direction,
            layout,
            _pool: pool,
            set,
            _set_layout: set_layout,
            _nearest: nearest,
        })
    }
}

impl Renderer {
    /// The ray map's passes and two full-float targets at the sensor's resolution, made on
    /// the first frame that reads the ray map back.
    pub(super) fn prepare_sensor_rays(&mut self) -> Result<(), GpuError> {
        if self.sensor_rays.is_some() {
            return Ok(());
        }
        let passes = SensorRays::create(
            &self.device,
            self.resources.scene_set_layout.raw,
            &self.cube,
            std::mem::size_of::<super::gpu::Push>() as u32,
        )?;
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
        self.sensor_rays = Some((passes, targets));
        Ok(())
    }
}
