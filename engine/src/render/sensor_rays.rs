//! The sensor's ray map on the GPU: one pass over the sensor view that writes, per mirror
//! pixel, every per-pixel quantity (`sensor::quantities`; `shaders/include/quantities/`), each
//! to a full-float colour attachment of its own ([`RayMapTargets`]), from one trace. The ray
//! itself is every lookup's (`mirror_hit`, `reflect`); what it meets comes from one of two
//! places ([`GroundTruth`]):
//!
//! - traced (`MIRROR_RAY_TRACED_FRAG`, `MIRROR_RAY_BVH_FRAG`), when the lookup traces
//!   (`ray-query`, `bvh`): through the lookup's own set, exactly as the colour pass's trace, so
//!   the colour, the range and the ids of a frame come from one light path;
//! - through the cube (`MIRROR_RAY_CUBE_FRAG`, `shaders/include/sensor_ray.glsl`) otherwise:
//!   the distance lookup's search along the reflected ray through the cube's depth, and the id
//!   cube's texel where it lands. That is exact only where the cube's centre saw what the ray
//!   meets, and the colour's lookup may look elsewhere: the outputs' JSON says which it was.
//!
//! The renderer owns the pass rather than a lookup plug-in and makes it on first use.
//! `sensor::SensorOutputs::from_gpu` turns the quantities into the ray map, range and ids.

use std::sync::Arc;

use ash::vk;

use super::draw::Attachments;
use super::graph::{Resource, Use};
use super::lookups::TraceSet;
use super::pipelines::{depth_only_pipeline, mirror_pipeline};
use super::targets::{CubeTarget, ViewTarget, DIRECTION_FORMAT};
use super::Renderer;
use crate::sensor::GroundTruth;
use crate::shaders;
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::Device;
use crate::vk::image::{Image, ImageView, Sampler};
use crate::vk::pipeline::{Pipeline, PipelineLayout};
use crate::vk::GpuError;

/// Every Vulkan device renders to 4 colour attachments at once (the spec's minimum of
/// `maxColorAttachments`), one per quantity: a fifth quantity would need that limit checked,
/// or a second pass.
const _: () = assert!(shaders::SENSOR_QUANTITIES.len() <= 4);

/// What the mirror writes in a view pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum MirrorOutput {
    /// The lookup's colour.
    Colour,
    /// The direction the lookup looked up (`--directions`).
    LookupDirection,
    /// The ray map's quantities.
    RayMap,
}

/// The ray map's pipeline, the depth-only scene pipeline drawn before it into the same
/// attachments, and the set the ray map reads at set 1: the lookup's trace set, or a set of its
/// own with the cube's depth (binding 1) and the id cube (binding 2), both read texel by texel.
/// Field order is drop order.
pub(super) struct SensorRays {
    pub pipeline: Pipeline,
    /// The scene's depth, under [`RayMapTargets`]' colour attachments.
    pub scene_depth: Pipeline,
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
    /// The traced pass: the lookup's ray-map shader, reading its trace set
    /// (`LookupPass::trace_set`).
    fn traced(scene: SceneLayouts<'_>, trace: TraceSet) -> Result<Self, GpuError> {
        let layouts = [scene.set_layout, trace.layout];
        let (pipeline, scene_depth, layout) = Self::pipelines(scene, &layouts, trace.ray_map)?;
        Ok(Self {
            pipeline,
            scene_depth,
            layout,
            set: trace.set,
            _cube_set: None,
        })
    }

    /// The pass through `cube`, which must have an id cube (`RenderOptions::id_cube`).
    fn through_cube(scene: SceneLayouts<'_>, cube: &CubeTarget) -> Result<Self, GpuError> {
        let device = scene.device;
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
        let layouts = [scene.set_layout, set_layout.raw];
        let shader = crate::shaders::MIRROR_RAY_CUBE_FRAG;
        let (pipeline, scene_depth, layout) = Self::pipelines(scene, &layouts, shader)?;
        Ok(Self {
            pipeline,
            scene_depth,
            layout,
            set,
            _cube_set: Some(CubeSet {
                _pool: pool,
                _layout: set_layout,
                _nearest: nearest,
            }),
        })
    }

    /// The ray map's pipeline of `shader` over sets `layouts`, and the scene's depth-only
    /// pipeline into the same attachments (a pipeline's colour formats are its pass's).
    fn pipelines(
        scene: SceneLayouts<'_>,
        layouts: &[vk::DescriptorSetLayout; 2],
        shader: &[u32],
    ) -> Result<(Pipeline, Pipeline, PipelineLayout), GpuError> {
        let device = scene.device;
        let formats = vec![DIRECTION_FORMAT; shaders::SENSOR_QUANTITIES.len()];
        let layout = PipelineLayout::create(device, layouts, scene.push_size, "ray map layout")?;
        let pipeline = mirror_pipeline(device, &layout, shader, &formats, "ray map pipeline")?;
        let scene_depth = depth_only_pipeline(
            device,
            scene.pipeline_layout,
            &formats,
            "ray map scene depth",
        )?;
        Ok((pipeline, scene_depth, layout))
    }
}

/// What the ray map's pipelines are made on: the scene's set layout (set 0) and pipeline
/// layout, and the push constants' size.
#[derive(Clone, Copy)]
struct SceneLayouts<'a> {
    device: &'a Arc<Device>,
    set_layout: vk::DescriptorSetLayout,
    pipeline_layout: &'a PipelineLayout,
    push_size: u32,
}

/// The ray map's attachments at the sensor's resolution: one RGBA32F image per quantity, in
/// location order (`shaders::SENSOR_QUANTITIES`), and the depth they share. Field order is
/// drop order: views before their images.
pub(super) struct RayMapTargets {
    /// Per quantity: its view and image.
    pub quantities: Vec<(ImageView, Image)>,
    depth_view: ImageView,
    depth: Image,
    pub width: u32,
    pub height: u32,
}

impl RayMapTargets {
    fn create(device: &Arc<Device>, [width, height]: [u32; 2]) -> Result<Self, GpuError> {
        let [colour, depth] = ViewTarget::descs(DIRECTION_FORMAT, width, height);
        let view =
            |image: &Image, name: &str| image.view(vk::ImageViewType::TYPE_2D, 0, 1, 0, 1, name);
        let quantities = (shaders::SENSOR_QUANTITIES.iter())
            .map(|name| {
                let image = Image::create(device, &colour, &format!("ray map {name}"))?;
                Ok((view(&image, &format!("ray map {name}"))?, image))
            })
            .collect::<Result<_, GpuError>>()?;
        let depth = Image::create(device, &depth, "ray map depth")?;
        Ok(Self {
            quantities,
            depth_view: view(&depth, "ray map depth")?,
            depth,
            width,
            height,
        })
    }

    /// Every image as the frame graph tracks it, with how it rests between frames: each
    /// quantity copied out for the readback, the depth as its pass left it.
    pub fn resources(&self) -> Vec<(Resource, Use)> {
        let colours =
            (self.quantities.iter()).map(|(_, image)| (Resource::whole(image), Use::CopySource));
        let depth = Resource::whole(&self.depth);
        colours.chain([(depth, Use::DepthTarget)]).collect()
    }

    /// The uses of the pass that draws them: each cleared and drawn into.
    pub fn drawn(&self) -> Vec<(Resource, Use)> {
        let mut uses = self.resources();
        for (_, u) in uses.iter_mut().filter(|(_, u)| *u == Use::CopySource) {
            *u = Use::ColorTarget;
        }
        uses
    }

    /// The pass's attachments, every one cleared; the depth is not kept.
    pub fn attachments(&self) -> Attachments {
        let views: Vec<vk::ImageView> = self.quantities.iter().map(|(v, _)| v.raw).collect();
        Attachments {
            color: views[0],
            ids: None,
            more_colors: views[1..].to_vec(),
            depth: self.depth_view.raw,
            size: [self.width, self.height],
            layers: 1,
            view_mask: 0,
            clear: true,
            store_depth: false,
        }
    }
}

impl Renderer {
    /// The ray map's pass and its targets at the sensor's resolution, made on the first frame
    /// that reads the ray map back: traced where the lookup traces, else through the cube.
    pub(super) fn prepare_sensor_rays(&mut self) -> Result<(), GpuError> {
        if self.views.sensor_rays.is_some() {
            return Ok(());
        }
        let scene = SceneLayouts {
            device: &self.device,
            set_layout: self.resources.scene_set_layout.raw,
            pipeline_layout: &self.scene_layout,
            push_size: std::mem::size_of::<super::gpu::Push>() as u32,
        };
        let passes = match self.mirror.pass.trace_set() {
            Some(trace) => SensorRays::traced(scene, trace)?,
            None => SensorRays::through_cube(scene, &self.cube)?,
        };
        let targets = RayMapTargets::create(&self.device, self.scene.sensor.resolution)?;
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
