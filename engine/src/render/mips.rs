//! The cube's mip chain after a fill: mips 1.. of the dirty faces rebuilt level by level by
//! `cube_mips.comp` (a clean face's mips still match its unchanged mip 0; a face re-rendered
//! only in its dirty rectangles gets only the texels above them), then every level of every
//! face ready for sampling. The barriers name the last readers, so they hold when frames
//! overlap.
//!
//! A compute pass of our own, not `vkCmdBlitImage`: each texel is the mean of the texels
//! above it on its own face (four, or up to nine under a level of odd side), in the shader's
//! arithmetic, so a box of a level is the whole level's
//! texels there and a clean face's old mips are a full update's, on every device. Blits were
//! not (an adversarial pass, 30 November 2026): SwiftShader's blit of a cube face reads the
//! border it keeps from the neighbouring faces, and lavapipe's blit of a box of a level was
//! not bit for bit the same texels of the whole level's blit.

use ash::vk;

use super::gpu::MipBox;
use super::graph::{FrameGraph, Resource, Use};
use super::methods::CubePlan;
use super::mip_pass::MipPass;
use super::targets::CubeTarget;
use crate::scene::pixel_rect::PixelRect;
use crate::shaders::shared::MIP_GROUP_SIDE;
use crate::vk::device::Device;

/// Records the chain for `plan`'s dirty faces, level 0 coming from the fill's colour
/// attachment. Every use is declared to `graph`, which places the barriers: a dirty face's
/// level m stored whole drops its old contents, but not before the last frame's mirror has
/// sampled them (a write after read: with frames in flight that frame may still be drawing);
/// the graph's source side names those reads.
pub(super) fn record(
    (dev, graph): (&Device, &mut FrameGraph),
    cmd: vk::CommandBuffer,
    cube: &CubeTarget,
    plan: &CubePlan,
) {
    let mut declare = |uses: &[(Resource, Use)]| graph.declare(dev, cmd, uses);
    let Some(pass) = &cube.mips else {
        declare(&[(cube.color_levels(0, 1, None), Use::FragmentRead)]);
        return;
    };
    let chain = Chain::of(cube, plan);
    dev.begin_label(cmd, "cube mips");
    // SAFETY: the pipeline is live while the cube is.
    unsafe { (dev.raw).cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pass.pipeline.raw) };
    for m in 1..chain.levels {
        declare(&[(cube.color_levels(m - 1, 1, None), Use::ComputeSampled)]);
        declare(&chain.stored(m));
        chain.make(dev, cmd, pass, m);
    }
    // Everything the pass touched goes back to sampling by the views.
    declare(&[(cube.color_levels(0, chain.levels, None), Use::FragmentRead)]);
    dev.end_label(cmd);
}

/// The cube's colour image and the faces whose chain is rebuilt.
struct Chain<'a> {
    cube: &'a CubeTarget,
    levels: u32,
    /// Each dirty face and the bounding box of its dirty rectangles at level 0 (`None`: the
    /// whole face). One box, not the rectangles: many-objects has a few dozen a face.
    faces: Vec<(u32, Option<PixelRect>)>,
}

impl<'a> Chain<'a> {
    fn of(cube: &'a CubeTarget, plan: &'a CubePlan) -> Self {
        Self {
            cube,
            levels: cube.mip_levels(),
            faces: (plan.faces())
                .map(|f| {
                    let rects = plan.dirty_rects(f as usize);
                    (f, rects.iter().copied().reduce(|a, b| a.union(&b)))
                })
                .collect(),
        }
    }

    fn side(&self, level: u32) -> u32 {
        (self.cube.size >> level).max(1)
    }

    /// The box of level `m` above level 0's `rect`: each texel that reads a changed one,
    /// level by level (`cube_mips.comp`: texel x reads 2x and 2x + 1 of an even level, and
    /// 2x + 2 too of an odd one). `None`: the whole level.
    fn rect_at(&self, rect: Option<PixelRect>, m: u32) -> Option<PixelRect> {
        let mut r = rect?;
        for level in 1..=m {
            let (above, side) = (self.side(level - 1), self.side(level));
            // The first texel that reads texel a: a / 2, or (a - 1) / 2 where it may be the
            // third tap; the last that reads texel b - 1: (b - 1) / 2.
            let first = |a: u32| match above % 2 {
                0 => a / 2,
                _ => a.saturating_sub(1) / 2,
            };
            let end = |b: u32| b.div_ceil(2).min(side);
            r = PixelRect {
                x0: first(r.x0).min(side),
                y0: first(r.y0).min(side),
                x1: end(r.x1),
                y1: end(r.y1),
            };
        }
        Some(r)
    }

    /// Level `m` of the six faces as the pass stores it: a dirty face whole, or in its box,
    /// the rest kept. The clean faces too: the set's view of the level spans all six, and a
    /// storage image's view must be in `GENERAL` wherever it reaches.
    fn stored(&self, m: u32) -> Vec<(Resource, Use)> {
        (0..6)
            .map(|f| {
                let dirty = self.faces.iter().find(|&&(g, _)| g == f);
                let how = match dirty.map(|&(_, rect)| self.rect_at(rect, m)) {
                    Some(None) => Use::ComputeStored,
                    _ => Use::ComputeStoredKept,
                };
                (self.cube.color_levels(m, 1, Some(f)), how)
            })
            .collect()
    }

    /// Level `m` of each dirty face (or its box) from level `m - 1`: one dispatch for six
    /// whole faces (a full update), else one a face.
    fn make(&self, dev: &Device, cmd: vk::CommandBuffer, pass: &MipPass, m: u32) {
        let whole = PixelRect::whole(self.side(m));
        let mut boxes: Vec<(i32, u32, PixelRect)> = (self.faces.iter())
            .map(|&(f, rect)| (f as i32, 1, self.rect_at(rect, m).unwrap_or(whole)))
            .collect();
        if boxes.len() == 6 && boxes.iter().all(|&(_, _, r)| r == whole) {
            boxes = vec![(0, 6, whole)];
        }
        let set = [pass.sets[m as usize - 1]];
        // SAFETY: the set names levels m - 1 (sampled) and m (stored), in the layouts the
        // graph declared just before.
        unsafe {
            (dev.raw).cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                pass.layout.raw,
                0,
                &set,
                &[],
            )
        };
        for (first_face, faces, r) in boxes {
            let (w, h) = (r.x1.saturating_sub(r.x0), r.y1.saturating_sub(r.y0));
            if w == 0 || h == 0 {
                continue;
            }
            let push = MipBox {
                origin: [r.x0 as i32, r.y0 as i32],
                size: [w as i32, h as i32],
                first_face,
            };
            // SAFETY: the push range is the layout's; the dispatch covers the box (the shader
            // returns past its size).
            unsafe {
                (dev.raw).cmd_push_constants(
                    cmd,
                    pass.layout.raw,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    bytemuck::bytes_of(&push),
                );
                (dev.raw).cmd_dispatch(
                    cmd,
                    w.div_ceil(MIP_GROUP_SIDE),
                    h.div_ceil(MIP_GROUP_SIDE),
                    faces,
                );
            }
        }
    }
}
