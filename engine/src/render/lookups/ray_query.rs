//! The `ray-query` lookup: the exact mirror on the GPU. The mirror's fragment shader traces
//! the reflected pixel-centre ray with `VK_KHR_ray_query` through a top-level acceleration
//! structure of every drawable (walls and objects) and shades the hit with `materials.glsl`,
//! as the CPU reference does. No cube map is read, so the renderer skips the cube fill. The
//! acceleration structures (and why the top level is rebuilt, not refit) are in
//! [`super::tracing`], which `distance-exact` shares.

use ash::vk;

use super::tracing::SceneTrace;
use super::{LookupContext, LookupNeeds, LookupPass, MirrorLookup};
use crate::render::gpu::{ObjectData, LOOKUP_RAY_QUERY};
use crate::render::targets::{DIRECTION_FORMAT, VIEW_FORMAT};
use crate::scene::Lookup;
use crate::vk::descriptors::{DescriptorPool, DescriptorSetLayout};
use crate::vk::device::OptionalFeatures;
use crate::vk::pipeline::{Pipeline, PipelineLayout};
use crate::vk::GpuError;

pub struct RayQuery;

impl MirrorLookup for RayQuery {
    fn lookup(&self) -> Lookup {
        Lookup::RayQuery
    }

    fn summary(&self) -> &'static str {
        "the reflected ray traced through the scene (VK_KHR_ray_query): exact, no cube map"
    }

    fn needs(&self) -> LookupNeeds {
        LookupNeeds {
            features: OptionalFeatures {
                ray_query: true,
                ..Default::default()
            },
        }
    }

    fn uses_cube(&self) -> bool {
        false
    }

    fn flag(&self) -> u32 {
        LOOKUP_RAY_QUERY
    }

    fn create(&self, ctx: &LookupContext<'_>) -> Result<Box<dyn LookupPass>, GpuError> {
        if !ctx.device.enabled.ray_query {
            return Err(GpuError::Unsupported(
                "lookup ray-query: the device was created without ray queries".into(),
            ));
        }
        Ok(Box::new(RayQueryPass::create(ctx)?))
    }
}

/// The ray-query lookup's per-renderer state. Field order is drop order.
struct RayQueryPass {
    colour: Pipeline,
    directions: Pipeline,
    layout: PipelineLayout,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    _set_layout: DescriptorSetLayout,
    trace: SceneTrace,
}

impl RayQueryPass {
    fn create(ctx: &LookupContext<'_>) -> Result<Self, GpuError> {
        let device = ctx.device;
        let res = ctx.resources;
        let trace = SceneTrace::create(ctx)?;
        let set_layout =
            DescriptorSetLayout::create(device, &SceneTrace::bindings(0), "ray-query set layout")?;
        let pool = DescriptorPool::create(
            device,
            1,
            &SceneTrace::pool_sizes(),
            "ray-query descriptors",
        )?;
        let set = pool.allocate(&set_layout, "ray-query set")?;
        trace.write(ctx, set, 0);
        let layout = PipelineLayout::create(
            device,
            &[res.scene_set_layout.raw, set_layout.raw],
            ctx.push_size,
            "ray-query mirror layout",
        )?;
        let colour = crate::render::pipelines::mirror_pipeline(
            device,
            &layout,
            crate::shaders::MIRROR_RAY_QUERY_FRAG,
            VIEW_FORMAT,
            "ray-query mirror pipeline",
        )?;
        let directions = crate::render::pipelines::mirror_pipeline(
            device,
            &layout,
            crate::shaders::MIRROR_RAY_QUERY_DIRECTION_FRAG,
            DIRECTION_FORMAT,
            "ray-query mirror direction pipeline",
        )?;
        Ok(Self {
            colour,
            directions,
            layout,
            _pool: pool,
            set,
            _set_layout: set_layout,
            trace,
        })
    }
}

impl LookupPass for RayQueryPass {
    fn pipeline(&self, directions: bool) -> &Pipeline {
        if directions {
            &self.directions
        } else {
            &self.colour
        }
    }

    fn layout(&self) -> &PipelineLayout {
        &self.layout
    }

    fn set(&self) -> vk::DescriptorSet {
        self.set
    }

    fn prepare(&mut self, objects: &[ObjectData]) -> Result<(), GpuError> {
        self.trace.prepare(objects)
    }

    fn record(&self, cmd: vk::CommandBuffer) {
        self.trace.record(cmd);
    }
}
