//! The cube's mip chain after a fill: mips 1.. of all six faces rebuilt by halving blits, then
//! every level of every face ready for sampling. The barriers name the last readers, so they
//! hold when frames overlap.
//!
//! Always all six faces, whole, whatever the fill re-rendered: that makes an incremental
//! update's mips the very commands a full update records, on the same level 0, so they are
//! the same bits on every driver. Rebuilding less is not exact everywhere (both found by an
//! adversarial pass, 30 November 2026): SwiftShader's linear blit of a cube face reads the
//! border it keeps from the neighbouring faces, so a clean face's old mips differ near its
//! edges from what its neighbours' new texels give; and lavapipe's blit of a box of a level
//! is not bit-identical to the same texels of the whole level's blit (half-float steps).

use ash::vk;

use super::graph::{FrameGraph, Use};
use super::targets::CubeTarget;
use crate::vk::device::Device;

/// Records the chain, level 0 coming from the fill's colour attachment. Every use is declared
/// to `graph`, which places the barriers: level m is overwritten whole, so its old contents
/// can go, but not before the last frame's mirror has sampled them (a write after read: with
/// frames in flight that frame may still be drawing); the graph's source side names those
/// reads.
pub(super) fn record(
    (dev, graph): (&Device, &mut FrameGraph),
    cmd: vk::CommandBuffer,
    cube: &CubeTarget,
) {
    let levels = cube.mip_levels();
    let mut declare = |level: u32, count: u32, how: Use| {
        graph.declare(dev, cmd, &[(cube.color_levels(level, count), how)]);
    };
    if levels == 1 {
        declare(0, 1, Use::FragmentRead);
        return;
    }
    dev.begin_label(cmd, "cube mips");
    declare(0, 1, Use::BlitSource);
    for m in 1..levels {
        declare(m, 1, Use::BlitDestination);
        blit_down_to(dev, cmd, cube, m);
        declare(m, 1, Use::BlitSource);
    }
    declare(0, levels, Use::FragmentRead);
    dev.end_label(cmd);
}

/// Level `m` of the six faces, halved from level `m - 1` with a linear filter.
fn blit_down_to(dev: &Device, cmd: vk::CommandBuffer, cube: &CubeTarget, m: u32) {
    let layers = |mip| vk::ImageSubresourceLayers {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        mip_level: mip,
        base_array_layer: 0,
        layer_count: 6,
    };
    let corners = |mip: u32| {
        let side = (cube.size >> mip).max(1) as i32;
        [
            vk::Offset3D::default(),
            vk::Offset3D {
                x: side,
                y: side,
                z: 1,
            },
        ]
    };
    let blit = vk::ImageBlit::default()
        .src_subresource(layers(m - 1))
        .src_offsets(corners(m - 1))
        .dst_subresource(layers(m))
        .dst_offsets(corners(m));
    // SAFETY: level m-1 is TRANSFER_SRC, level m TRANSFER_DST (declared above); the format
    // supports linear blits (checked when the cube was created); both regions are their
    // levels whole.
    unsafe {
        dev.raw.cmd_blit_image(
            cmd,
            cube.color.raw,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            cube.color.raw,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &[blit],
            vk::Filter::LINEAR,
        )
    };
}
