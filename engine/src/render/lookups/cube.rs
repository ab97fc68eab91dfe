//! The cube-map lookups, `plain` and `box`: the mirror samples the cube map (set 1: the
//! environment cube), in the reflected direction or in the box-corrected one. One pass serves
//! both; `FrameData.flags.y` tells `mirror.glsl` which direction to look up.

use ash::vk;

use super::{
    as_is, LookupContext, LookupPass, MirrorLookup, MirrorPipelines, MirrorShaders, Rung, Start,
};
use crate::scene::Lookup;
use crate::vk::GpuError;

/// A lookup into the cube map.
pub struct CubeLookup {
    start: Start,
    summary: &'static str,
    rungs: &'static [Rung],
}

pub static PLAIN: CubeLookup = CubeLookup {
    start: Start::Reflection,
    summary: "the cube map in the reflected direction (the thesis; exact only for an \
              environment infinitely far away)",
    rungs: &[Rung {
        label: "plain",
        lookup: Lookup::Plain,
        order: 0,
        configure: as_is,
        footprint: false,
    }],
};

pub static BOX: CubeLookup = CubeLookup {
    start: Start::RoomBox,
    summary: "the cube map towards where the reflected ray leaves the room's box \
              (parallax-corrected; exact for an empty box room up to texel sampling)",
    rungs: &[
        Rung {
            label: "box",
            lookup: Lookup::Box,
            order: 1,
            configure: as_is,
            footprint: false,
        },
        // The same images, the cube filled only where the sensor reads it.
        Rung {
            label: "box-footprint",
            lookup: Lookup::Box,
            order: 2,
            configure: as_is,
            footprint: true,
        },
    ],
};

impl MirrorLookup for CubeLookup {
    fn summary(&self) -> &'static str {
        self.summary
    }

    fn uses_cube(&self) -> bool {
        true
    }

    fn marks_footprint(&self) -> bool {
        true
    }

    fn start(&self) -> Start {
        self.start
    }

    fn rungs(&self) -> &'static [Rung] {
        self.rungs
    }

    fn create(&self, ctx: &LookupContext<'_>) -> Result<Box<dyn LookupPass>, GpuError> {
        let res = ctx.resources;
        let shaders = MirrorShaders {
            colour: crate::shaders::MIRROR_FRAG,
            directions: crate::shaders::MIRROR_DIRECTION_FRAG,
        };
        let pipelines =
            MirrorPipelines::create(ctx, res.environment_set_layout.raw, shaders, "mirror")?;
        Ok(Box::new(CubePass {
            pipelines,
            set: res.environment_set,
        }))
    }
}

/// The cube lookups' pipelines.
struct CubePass {
    pipelines: MirrorPipelines,
    /// The environment set (the cube map), owned by the scene resources.
    set: vk::DescriptorSet,
}

impl LookupPass for CubePass {
    fn pipelines(&self) -> &MirrorPipelines {
        &self.pipelines
    }

    fn set(&self) -> vk::DescriptorSet {
        self.set
    }
}
