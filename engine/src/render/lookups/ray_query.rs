//! The `ray-query` lookup: the exact mirror on the GPU. The mirror's fragment shader traces
//! the reflected pixel-centre ray with `VK_KHR_ray_query` through a top-level acceleration
//! structure of every drawable (walls and objects) and shades the hit with `materials.glsl`,
//! as the CPU reference does. No cube map is read, so the renderer skips the cube fill. The
//! acceleration structures (and why the top level is rebuilt, not refit) are in
//! [`super::tracing`], which `distance-exact` shares.

use ash::vk;

use super::tracing::SceneTrace;
use super::{
    as_is, FrameObjects, LookupContext, LookupNeeds, LookupPass, MirrorLookup, MirrorPipelines,
    MirrorShaders, Rung, Start, TraceSet,
};
use crate::render::graph::{PassRecorder, Resource, Use};
use crate::scene::Lookup;
use crate::vk::descriptors::{DescriptorPool, DescriptorSetLayout};
use crate::vk::device::DeviceInfo;
use crate::vk::uploads::FrameUploads;
use crate::vk::GpuError;

pub struct RayQuery;

impl MirrorLookup for RayQuery {
    fn summary(&self) -> &'static str {
        "the reflected ray traced through the scene (VK_KHR_ray_query): exact, no cube map"
    }

    fn needs(&self) -> LookupNeeds {
        SceneTrace::NEEDS
    }

    fn builds_scene_trace(&self) -> bool {
        true
    }

    fn uses_cube(&self) -> bool {
        false
    }

    fn traces_ray_map(&self) -> bool {
        true
    }

    /// First on a GPU, whose ray queries have ray-tracing hardware behind them; after bvh on
    /// a CPU driver, where bvh measured cheaper (lavapipe: see `bvh.rs`).
    fn ground_truth_rank(&self, device: &DeviceInfo) -> u32 {
        if device.is_cpu() {
            1
        } else {
            0
        }
    }

    fn start(&self) -> Start {
        Start::Reflection
    }

    fn rungs(&self) -> &'static [Rung] {
        &[Rung {
            label: "ray-query",
            lookup: Lookup::RayQuery,
            order: 7,
            configure: as_is,
            footprint: false,
        }]
    }

    fn create(&self, ctx: &LookupContext<'_>) -> Result<Box<dyn LookupPass>, GpuError> {
        SceneTrace::require(ctx, ctx.lookup.name())?;
        Ok(Box::new(RayQueryPass::create(ctx)?))
    }
}

/// The ray-query lookup's per-renderer state. Field order is drop order.
struct RayQueryPass {
    pipelines: MirrorPipelines,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    set_layout: DescriptorSetLayout,
    trace: SceneTrace,
}

impl RayQueryPass {
    fn create(ctx: &LookupContext<'_>) -> Result<Self, GpuError> {
        let device = ctx.device;
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
        let shaders = MirrorShaders {
            colour: crate::shaders::MIRROR_RAY_QUERY_FRAG,
            directions: crate::shaders::MIRROR_RAY_QUERY_DIRECTION_FRAG,
        };
        let pipelines = MirrorPipelines::create(ctx, set_layout.raw, shaders, "ray-query mirror")?;
        Ok(Self {
            pipelines,
            _pool: pool,
            set,
            set_layout,
            trace,
        })
    }
}

impl LookupPass for RayQueryPass {
    fn pipelines(&self) -> &MirrorPipelines {
        &self.pipelines
    }

    fn set(&self) -> vk::DescriptorSet {
        self.set
    }

    fn trace_set(&self) -> Option<TraceSet> {
        Some(TraceSet {
            layout: self.set_layout.raw,
            set: self.set,
            ray_map: crate::shaders::MIRROR_RAY_TRACED_FRAG,
        })
    }

    fn prepare(
        &mut self,
        uploads: &mut FrameUploads,
        frame: &FrameObjects<'_>,
    ) -> Result<(), GpuError> {
        self.trace.prepare(uploads, frame.objects, frame.bounds)
    }

    fn resources(&self, _slot: usize) -> Vec<(Resource, Use)> {
        self.trace.resources()
    }

    fn record(&self, pass: &mut PassRecorder<'_>) {
        self.trace.record(pass);
    }
}
