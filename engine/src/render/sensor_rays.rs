//! The sensor's ray map on the GPU: two passes over the sensor view that write, per mirror
//! pixel, the sphere hit with the room-box range (`mirror_ray_origin.frag.glsl`) and the
//! reflected direction with the room-box wall (`mirror_ray_direction.frag.glsl`). They
//! depend on no lookup (the ray is the same whatever the cube lookup does with it), so the
//! renderer owns them rather than a lookup plug-in. `sensor::SensorOutputs::from_gpu` turns
//! the two images into the ray map, range and ids.

use std::sync::Arc;

use super::pipelines::mirror_pipeline;
use super::targets::{ViewTarget, DIRECTION_FORMAT};
use super::Renderer;
use crate::vk::device::Device;
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
    /// The ray map's reflected direction and wall.
    RayDirection,
}

/// The two ray-map pipelines (origin, direction), on the scene's layout: they read set 0 only.
pub(super) fn create_pipelines(
    device: &Arc<Device>,
    scene_layout: &PipelineLayout,
) -> Result<[Pipeline; 2], GpuError> {
    let origin = mirror_pipeline(
        device,
        scene_layout,
        crate::shaders::MIRROR_RAY_ORIGIN_FRAG,
        DIRECTION_FORMAT,
        "sensor ray origin pipeline",
    )?;
    let direction = mirror_pipeline(
        device,
        scene_layout,
        crate::shaders::MIRROR_RAY_DIRECTION_FRAG,
        DIRECTION_FORMAT,
        "sensor ray direction pipeline",
    )?;
    Ok([origin, direction])
}

impl Renderer {
    /// The ray map's two full-float targets at the sensor's resolution.
    pub(super) fn create_ray_targets(&self) -> Result<[ViewTarget; 2], GpuError> {
        let [w, h] = self.scene.sensor.resolution;
        Ok([
            ViewTarget::create(&self.device, DIRECTION_FORMAT, w, h, "sensor ray origins")?,
            ViewTarget::create(
                &self.device,
                DIRECTION_FORMAT,
                w,
                h,
                "sensor ray directions",
            )?,
        ])
    }
}
