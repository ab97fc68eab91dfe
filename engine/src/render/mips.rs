//! The cube's mip chain after a fill: mips 1.. of the dirty faces rebuilt by halving blits (a
//! clean face's mips still match its unchanged mip 0), then every level of every face ready
//! for sampling. The barriers name the last readers, so they hold when frames overlap.

use ash::vk;

use super::graph::{self, FrameGraph, Resource, Use};
use super::targets::CubeTarget;
use crate::vk::device::Device;

/// Records the chain for the faces set in `dirty` (bit f: face f), level 0 coming from the
/// fill's colour attachment. Every use is declared to `graph`, which places the barriers: the
/// dirty faces' level m is overwritten whole, so its old contents can go, but not before the
/// last frame's mirror has sampled them (a write after read: with frames in flight that frame
/// may still be drawing); the graph's source side names those reads.
pub(super) fn record(
    (dev, graph): (&Device, &mut FrameGraph),
    cmd: vk::CommandBuffer,
    cube: &CubeTarget,
    dirty: u8,
) {
    let chain = Chain::of(cube, dirty);
    let mut declare = |uses: &[(Resource, Use)]| graph::record(dev, cmd, &graph.uses(uses));
    if chain.levels == 1 {
        declare(&[(cube.color_levels(0, 1, None), Use::FragmentRead)]);
        return;
    }
    dev.begin_label(cmd, "cube mips");
    declare(&[(cube.color_levels(0, 1, None), Use::BlitSource)]);
    for m in 1..chain.levels {
        declare(&chain.per_face(m, Use::BlitDestination));
        chain.blit_down_to(dev, cmd, m);
        declare(&chain.per_face(m, Use::BlitSource));
    }
    // Everything the blits touched goes back to sampling; clean faces' levels 1.. never
    // left it (and need no barrier: a read after reads).
    let all = cube.color_levels(0, chain.levels, None);
    declare(&[(all, Use::FragmentRead)]);
    dev.end_label(cmd);
}

/// The cube's colour image and the faces whose chain is rebuilt.
struct Chain<'a> {
    cube: &'a CubeTarget,
    levels: u32,
    faces: Vec<u32>,
}

impl<'a> Chain<'a> {
    fn of(cube: &'a CubeTarget, dirty: u8) -> Self {
        Self {
            cube,
            levels: cube.mip_levels(),
            faces: (0..6u32).filter(|f| dirty & (1 << f) != 0).collect(),
        }
    }

    /// Level `m` of each dirty face, used as `how`.
    fn per_face(&self, m: u32, how: Use) -> Vec<(Resource, Use)> {
        (self.faces.iter())
            .map(|&f| (self.cube.color_levels(m, 1, Some(f)), how))
            .collect()
    }

    /// Level `m` of each dirty face, halved from level `m - 1` with a linear filter.
    fn blit_down_to(&self, dev: &Device, cmd: vk::CommandBuffer, m: u32) {
        let side = |level: u32| (self.cube.size >> level).max(1) as i32;
        let corner = |s: i32| [vk::Offset3D::default(), vk::Offset3D { x: s, y: s, z: 1 }];
        let layer = |mip, f| vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: mip,
            base_array_layer: f,
            layer_count: 1,
        };
        let blits: Vec<vk::ImageBlit> = (self.faces.iter())
            .map(|&f| {
                vk::ImageBlit::default()
                    .src_subresource(layer(m - 1, f))
                    .src_offsets(corner(side(m - 1)))
                    .dst_subresource(layer(m, f))
                    .dst_offsets(corner(side(m)))
            })
            .collect();
        let image = self.cube.color.raw;
        // SAFETY: level m-1 is TRANSFER_SRC, level m of these faces TRANSFER_DST; the format
        // supports linear blits (checked when the cube was created).
        unsafe {
            dev.raw.cmd_blit_image(
                cmd,
                image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &blits,
                vk::Filter::LINEAR,
            )
        };
    }
}
