//! The `distance-exact` lookup: the distance search (`distance`), and for the rays it cannot
//! resolve, the exact ray traced with a ray query through the scene (`ray-query`'s
//! acceleration structures, [`super::tracing`]).
//!
//! Unresolved means: before meeting the stored surface, the search crossed a jump in the
//! stored distance that was no hit; or a step crossed a silhouette outwards (from a near
//! surface to a far one) while the ray reached the near surface's depth, so it may have
//! clipped that surface between two samples; or its hit lies on a silhouette texel; or it met
//! nothing. A jump is where the ray passes behind an occluder as seen from the cube's centre;
//! behind it lies what the centre never saw, the only place a surface the cube did not store
//! can be met (the disocclusion `distance` gets wrong). A ray crossing no jump moves through
//! space the centre sees all of, so the first surface the search meets is the one the ray
//! meets, up to the steps' resolution (which the corner test covers for the steps that cross
//! a silhouette). The test is conservative: a ray that passes behind an occluder and meets
//! nothing hidden is traced too, which costs time, not accuracy.
//!
//! Set 1: the colour cube and its depth at bindings 0 and 1, as `distance`; the traced scene
//! at 2..=5 (`shaders/mirror_distance_exact.frag.glsl`, both outputs); at 6 the tally of the rays traced
//! ([`super::tally`]), reported per frame.

use ash::vk;

use super::distance::{cube_bindings, cube_pool_size, depth_sampler, write_cube};
use super::tally::{FrameTally, TraceTally};
use super::tracing::SceneTrace;
use super::{
    FrameObjects, LookupContext, LookupNeeds, LookupPass, MirrorLookup, MirrorPipelines,
    MirrorShaders, Rung, Start,
};
use crate::render::graph::{PassRecorder, Resource, Use};
use crate::scene::Lookup;
use crate::vk::descriptors::{DescriptorPool, DescriptorSetLayout};
use crate::vk::image::Sampler;
use crate::vk::uploads::FrameUploads;
use crate::vk::GpuError;

/// Where the traced scene's bindings start (`RAY_QUERY_BINDING` in the shaders).
const TRACE_BINDING: u32 = 2;
/// The tally of traced rays, after the traced scene's four (`TALLY_BINDING`).
const TALLY_BINDING: u32 = TRACE_BINDING + 4;

pub struct DistanceExact;

impl MirrorLookup for DistanceExact {
    fn searches_depth(&self) -> bool {
        true
    }

    fn summary(&self) -> &'static str {
        "the distance search, with the rays it cannot resolve (behind an occluder as the \
         cube's centre sees it) traced exactly (VK_KHR_ray_query)"
    }

    fn needs(&self) -> LookupNeeds {
        SceneTrace::NEEDS
    }

    fn builds_scene_trace(&self) -> bool {
        true
    }

    fn uses_cube(&self) -> bool {
        true
    }

    fn start(&self) -> Start {
        Start::RoomBox
    }

    /// The disocclusion fix: the 16-step search, with the rays it cannot resolve traced.
    fn rungs(&self) -> &'static [Rung] {
        &[Rung {
            label: "distance-exact",
            lookup: Lookup::DistanceExact,
            order: 6,
            configure: |s| s.mirror.distance_steps = 16,
            footprint: false,
        }]
    }

    fn create(&self, ctx: &LookupContext<'_>) -> Result<Box<dyn LookupPass>, GpuError> {
        SceneTrace::require(ctx, ctx.lookup.name())?;
        Ok(Box::new(DistanceExactPass::create(ctx)?))
    }
}

/// The distance-exact lookup's per-renderer state. Field order is drop order.
struct DistanceExactPass {
    pipelines: MirrorPipelines,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    _set_layout: DescriptorSetLayout,
    _nearest: Sampler,
    trace: SceneTrace,
    tally: TraceTally,
}

impl DistanceExactPass {
    fn create(ctx: &LookupContext<'_>) -> Result<Self, GpuError> {
        let device = ctx.device;
        let trace = SceneTrace::create(ctx)?;
        let tally = TraceTally::create(device, ctx.frames_in_flight)?;
        let bindings: Vec<_> = cube_bindings()
            .into_iter()
            .chain(SceneTrace::bindings(TRACE_BINDING))
            .chain([TraceTally::binding(TALLY_BINDING)])
            .collect();
        let set_layout =
            DescriptorSetLayout::create(device, &bindings, "distance-exact set layout")?;
        let [structures, mut storage] = SceneTrace::pool_sizes();
        storage.descriptor_count += 1; // the tally
        let pool = DescriptorPool::create(
            device,
            1,
            &[cube_pool_size(), structures, storage],
            "distance-exact descriptors",
        )?;
        let set = pool.allocate(&set_layout, "distance-exact set")?;
        let nearest = depth_sampler(device)?;
        write_cube(ctx, set, &nearest);
        trace.write(ctx, set, TRACE_BINDING);
        tally.write(set, TALLY_BINDING);
        let shaders = MirrorShaders {
            colour: crate::shaders::MIRROR_DISTANCE_EXACT_FRAG,
            directions: crate::shaders::MIRROR_DISTANCE_EXACT_DIRECTION_FRAG,
        };
        let pipelines =
            MirrorPipelines::create(ctx, set_layout.raw, shaders, "distance-exact mirror")?;
        Ok(Self {
            pipelines,
            _pool: pool,
            set,
            _set_layout: set_layout,
            _nearest: nearest,
            trace,
            tally,
        })
    }
}

impl LookupPass for DistanceExactPass {
    fn pipelines(&self) -> &MirrorPipelines {
        &self.pipelines
    }

    fn set(&self) -> vk::DescriptorSet {
        self.set
    }

    fn prepare(
        &mut self,
        uploads: &mut FrameUploads,
        frame: &FrameObjects<'_>,
    ) -> Result<(), GpuError> {
        self.trace.prepare(uploads, frame.objects, frame.bounds)
    }

    fn resources(&self, slot: usize) -> Vec<(Resource, Use)> {
        let mut all = self.tally.resources(slot);
        all.extend(self.trace.resources());
        all
    }

    fn record(&self, pass: &mut PassRecorder<'_>) {
        self.tally.record_reset(pass);
        self.trace.record(pass);
    }

    fn record_after_views(&self, pass: &mut PassRecorder<'_>, slot: usize) {
        self.tally.record_to_host(pass, slot);
    }

    fn tally(&self, slot: usize) -> Result<Option<FrameTally>, GpuError> {
        self.tally.read(slot).map(Some)
    }
}
