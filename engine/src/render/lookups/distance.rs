//! The `distance` lookup: the reflected ray is searched through the cube's own depth buffer
//! (Szirmay-Kalos et al. 2005, "Approximate ray-tracing on the GPU with distance impostors";
//! GPU Gems 3 ch. 17), and the colour is looked up in the direction of the point where the
//! ray meets the surface the cube stored, instead of the reflected direction (`plain`) or the
//! room box's exit (`box`).
//!
//! The distance map is the depth every fill method already writes (32-bit float, reverse-Z),
//! kept after the fill and read texel by texel, so no method changes. The search itself is in
//! `shaders/include/distance_search.glsl`; set 1 holds the colour cube (binding 0, filtered
//! as for `box`) and the depth's six layers (binding 1, read with `texelFetch`).

use std::sync::Arc;

use ash::vk;

use super::{LookupContext, LookupPass, MirrorLookup, MirrorPipelines, MirrorShaders, Rung, Start};
use crate::scene::Lookup;
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::Device;
use crate::vk::image::Sampler;
use crate::vk::GpuError;

pub struct Distance;

impl MirrorLookup for Distance {
    fn searches_depth(&self) -> bool {
        true
    }

    fn summary(&self) -> &'static str {
        "the reflected ray searched through the cube's depth, looked up where it meets it \
         (exact for surfaces the cube's centre sees, up to the search's steps)"
    }

    fn uses_cube(&self) -> bool {
        true
    }

    fn start(&self) -> Start {
        Start::RoomBox
    }

    /// At three linear step counts (its secant steps as the scene sets them): fewer steps
    /// cost less and miss thin features between two samples.
    fn rungs(&self) -> &'static [Rung] {
        &[
            Rung {
                label: "distance-8",
                lookup: Lookup::Distance,
                order: 3,
                configure: |s| s.mirror.distance_steps = 8,
                footprint: false,
            },
            Rung {
                label: "distance-16",
                lookup: Lookup::Distance,
                order: 4,
                configure: |s| s.mirror.distance_steps = 16,
                footprint: false,
            },
            Rung {
                label: "distance-32",
                lookup: Lookup::Distance,
                order: 5,
                configure: |s| s.mirror.distance_steps = 32,
                footprint: false,
            },
        ]
    }

    fn create(&self, ctx: &LookupContext<'_>) -> Result<Box<dyn LookupPass>, GpuError> {
        let device = ctx.device;
        let set_layout =
            DescriptorSetLayout::create(device, &cube_bindings(), "distance set layout")?;
        let pool = DescriptorPool::create(device, 1, &[cube_pool_size()], "distance descriptors")?;
        let set = pool.allocate(&set_layout, "distance set")?;
        let nearest = depth_sampler(device)?;
        write_cube(ctx, set, &nearest);
        let shaders = MirrorShaders {
            colour: crate::shaders::MIRROR_DISTANCE_FRAG,
            directions: crate::shaders::MIRROR_DISTANCE_DIRECTION_FRAG,
        };
        let pipelines = MirrorPipelines::create(ctx, set_layout.raw, shaders, "distance mirror")?;
        Ok(Box::new(DistancePass {
            pipelines,
            _pool: pool,
            set,
            _set_layout: set_layout,
            _nearest: nearest,
        }))
    }
}

/// Bindings 0 and 1 of set 1 of the lookups that search the cube's depth (distance and
/// distance-exact): the colour cube and its depth's six layers.
pub(super) fn cube_bindings() -> [vk::DescriptorSetLayoutBinding<'static>; 2] {
    let stage = vk::ShaderStageFlags::FRAGMENT;
    let sampled = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
    [
        descriptors::binding(0, sampled, 1, stage),
        descriptors::binding(1, sampled, 1, stage),
    ]
}

/// What a pool needs for [`cube_bindings`].
pub(super) fn cube_pool_size() -> vk::DescriptorPoolSize {
    vk::DescriptorPoolSize {
        ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        descriptor_count: 2,
    }
}

/// The depth's sampler, nearest ([`Sampler::nearest`]).
pub(super) fn depth_sampler(device: &Arc<Device>) -> Result<Sampler, GpuError> {
    Sampler::nearest(device, "cube depth sampler")
}

/// Points [`cube_bindings`] of `set` at the cube's colour (filtered as for `box`) and depth.
pub(super) fn write_cube(ctx: &LookupContext<'_>, set: vk::DescriptorSet, nearest: &Sampler) {
    let cube = ctx.cube;
    let device = ctx.device;
    descriptors::write_images(device, set, 0, &[(cube.cube_view.raw, cube.sampler.raw)]);
    descriptors::write_images(device, set, 1, &[(cube.depth_layers_view.raw, nearest.raw)]);
}

/// The distance lookup's pipelines and set. Field order is drop order.
struct DistancePass {
    pipelines: MirrorPipelines,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    _set_layout: DescriptorSetLayout,
    _nearest: Sampler,
}

impl LookupPass for DistancePass {
    fn pipelines(&self) -> &MirrorPipelines {
        &self.pipelines
    }

    fn set(&self) -> vk::DescriptorSet {
        self.set
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::camera::ViewBasis;
    use glam::Vec3;

    /// The distance from the cube's centre, in direction `d` (any length), of the surface a
    /// cube face stored at reverse-Z `depth` (`near`, `far`: the faces' planes): what
    /// `distance_search.glsl` computes (`depth_to_z`, `behind`), restated to check the maths.
    /// The face's view depth is z = b / (depth - a) with a = -near / (far - near) and
    /// b = near far / (far - near) (`ViewBasis::view_to_clip`), and the point in direction d
    /// at view depth z lies z |d| / max|d_i| from the centre.
    fn depth_to_distance(depth: f32, near: f32, far: f32, d: glam::Vec3) -> f32 {
        let a = -near / (far - near);
        let b = near * far / (far - near);
        let z = b / (depth - a);
        z * d.length() / d.abs().max_element()
    }

    /// Known answers: a point projected by a cube face's own matrix comes back at its
    /// distance from the centre, for points on every face, near and far.
    #[test]
    fn depth_turns_back_into_the_distance_from_the_centre() {
        let (near, far) = (0.05, 40.0);
        let points = [
            Vec3::new(2.0, 0.5, -0.25),
            Vec3::new(-0.3, 0.2, 0.1),
            Vec3::new(0.0, 7.0, 6.9),
            Vec3::new(0.4, -3.0, 1.0),
            Vec3::new(-10.0, 10.0, 39.0),
            Vec3::new(0.1, 0.0, -0.06),
        ];
        for p in points {
            let (face, _, _) = crate::scene::camera::cube_face_lookup(p);
            let view = ViewBasis::cube_face(Vec3::ZERO, face);
            let clip = view.world_to_clip(near, far) * p.extend(1.0);
            let depth = clip.z / clip.w;
            assert!((0.0..=1.0).contains(&depth), "{p}: depth {depth}");
            let got = depth_to_distance(depth, near, far, p * 3.0);
            let want = p.length();
            // f32 rounding of the projection and its inverse: a few ulps.
            assert!((got - want).abs() <= 1e-5 * want, "{p}: {got} != {want}");
        }
        // The cleared depth (0) is the far plane; depth 1 the near plane.
        assert!((depth_to_distance(0.0, near, far, Vec3::Z) - far).abs() < 1e-3);
        assert!((depth_to_distance(1.0, near, far, Vec3::X) - near).abs() < 1e-6);
    }
}
