//! The cube's mip chain after a fill: mips 1.. of the dirty faces rebuilt by halving blits (a
//! clean face's mips still match its unchanged mip 0), then every level of every face ready
//! for sampling. The barriers name the last readers, so they hold when frames overlap.

use ash::vk;

use super::draw::{barrier, Sync, COLOR_OUT, SAMPLED};
use super::targets::CubeTarget;
use crate::vk::commands::{image_barriers, ImageBarrier};
use crate::vk::device::Device;

const BLIT_WRITE: Sync = (
    vk::PipelineStageFlags2::BLIT,
    vk::AccessFlags2::TRANSFER_WRITE,
);
const BLIT_READ: Sync = (
    vk::PipelineStageFlags2::BLIT,
    vk::AccessFlags2::TRANSFER_READ,
);

/// Records the chain for the faces set in `dirty` (bit f: face f), level 0 coming from the
/// fill's colour attachment.
pub(super) fn record(dev: &Device, cmd: vk::CommandBuffer, cube: &CubeTarget, dirty: u8) {
    let chain = Chain::of(cube, dirty);
    if chain.levels == 1 {
        image_barriers(dev, cmd, &[chain.level0(COLOR_OUT, SAMPLED)]);
        return;
    }
    dev.begin_label(cmd, "cube mips");
    image_barriers(dev, cmd, &[chain.level0(COLOR_OUT, BLIT_READ)]);
    for m in 1..chain.levels {
        // The dirty faces' level m is overwritten whole: its old contents can go, but not
        // before the last frame's mirror has sampled them (a write after read: with frames
        // in flight that frame may still be drawing).
        let undefined = (vk::ImageLayout::UNDEFINED, SAMPLED);
        let dst = (vk::ImageLayout::TRANSFER_DST_OPTIMAL, BLIT_WRITE);
        let src = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, BLIT_READ);
        image_barriers(dev, cmd, &chain.per_face(m, undefined, dst));
        chain.blit_down_to(dev, cmd, m);
        image_barriers(dev, cmd, &chain.per_face(m, dst, src));
    }
    image_barriers(dev, cmd, &chain.back_to_sampling());
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

    /// Levels `first..first + count` of face `face` (None: all six faces).
    fn range(&self, first: u32, count: u32, face: Option<u32>) -> vk::ImageSubresourceRange {
        let all = self.cube.color.full_range();
        vk::ImageSubresourceRange {
            base_mip_level: first,
            level_count: count,
            base_array_layer: face.unwrap_or(all.base_array_layer),
            layer_count: if face.is_some() { 1 } else { all.layer_count },
            ..all
        }
    }

    /// Level 0 of every face, from the fill's colour attachment to `to` (sampling, or the
    /// blits' source).
    fn level0(&self, from: Sync, to: Sync) -> ImageBarrier {
        let layout = if to == SAMPLED {
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL
        } else {
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL
        };
        barrier(
            self.cube.color.raw,
            self.range(0, 1, None),
            (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, from),
            (layout, to),
        )
    }

    /// Level `m` of each dirty face, from `from` to `to`.
    fn per_face(
        &self,
        m: u32,
        from: (vk::ImageLayout, Sync),
        to: (vk::ImageLayout, Sync),
    ) -> Vec<ImageBarrier> {
        (self.faces.iter())
            .map(|&f| barrier(self.cube.color.raw, self.range(m, 1, Some(f)), from, to))
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

    /// Everything the blits touched goes back to sampling (all of level 0, levels 1.. of the
    /// dirty faces); clean faces' levels 1.. never left it.
    fn back_to_sampling(&self) -> Vec<ImageBarrier> {
        let src = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, BLIT_READ);
        let sampled = (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED);
        let image = self.cube.color.raw;
        let upper = |f| barrier(image, self.range(1, self.levels - 1, Some(f)), src, sampled);
        let mut back: Vec<ImageBarrier> = self.faces.iter().map(|&f| upper(f)).collect();
        back.push(barrier(image, self.range(0, 1, None), src, sampled));
        back
    }
}
