//! The cube's mip chain after a fill: mips 1.. of the dirty faces rebuilt by halving blits (a
//! clean face's mips still match its unchanged mip 0; a face re-rendered only in its dirty
//! rectangles gets only the texels above them, level by level), then every level of every
//! face ready for sampling. The barriers name the last readers, so they hold when frames
//! overlap.

use ash::vk;

use super::graph::{FrameGraph, Resource, Use};
use super::methods::CubePlan;
use super::targets::CubeTarget;
use crate::scene::pixel_rect::PixelRect;
use crate::vk::device::Device;

/// Records the chain for `plan`'s dirty faces, level 0 coming from the fill's colour
/// attachment. Every use is declared to `graph`, which places the barriers: the
/// dirty faces' level m is overwritten whole, so its old contents can go, but not before the
/// last frame's mirror has sampled them (a write after read: with frames in flight that frame
/// may still be drawing); the graph's source side names those reads.
pub(super) fn record(
    (dev, graph): (&Device, &mut FrameGraph),
    cmd: vk::CommandBuffer,
    cube: &CubeTarget,
    plan: &CubePlan,
) {
    let chain = Chain::of(cube, plan);
    let mut declare = |uses: &[(Resource, Use)]| graph.declare(dev, cmd, uses);
    if chain.levels == 1 {
        declare(&[(cube.color_levels(0, 1, None), Use::FragmentRead)]);
        return;
    }
    dev.begin_label(cmd, "cube mips");
    declare(&[(cube.color_levels(0, 1, None), Use::BlitSource)]);
    for m in 1..chain.levels {
        declare(&chain.per_face(m, None));
        chain.blit_down_to(dev, cmd, m);
        declare(&chain.per_face(m, Some(Use::BlitSource)));
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
    /// Each dirty face and the bounding box of its dirty rectangles at level 0 (`None`: the
    /// whole face). One box, not the rectangles: a blit region costs lavapipe some 15 µs
    /// whatever its size, and many-objects' few dozen rectangles a face over nine levels
    /// took 18 ms where the whole faces took 5.
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

    /// The rectangle of level `m` of a face whose level-0 box is `rect`: each texel above a
    /// changed one, `None` for the whole level. A rectangle halves exactly only while every
    /// level above it does (power-of-two sides): a level that does not is rebuilt whole, and
    /// so is every level below it.
    fn rect_at(&self, rect: Option<PixelRect>, m: u32) -> Option<PixelRect> {
        let halving = (1..=m).all(|k| self.side(k - 1) == 2 * self.side(k));
        let r = rect.filter(|_| halving)?;
        let up = |x: u32| x.div_ceil(1 << m);
        Some(PixelRect {
            x0: r.x0 >> m,
            y0: r.y0 >> m,
            x1: up(r.x1),
            y1: up(r.y1),
        })
    }

    /// Level `m` of each dirty face, used as `how`; `None`: as a blit destination, whole
    /// (old contents dropped) or in its box (the rest kept).
    fn per_face(&self, m: u32, how: Option<Use>) -> Vec<(Resource, Use)> {
        (self.faces.iter())
            .map(|&(f, rect)| {
                let dst = match self.rect_at(rect, m) {
                    None => Use::BlitDestination,
                    Some(_) => Use::BlitKept,
                };
                (self.cube.color_levels(m, 1, Some(f)), how.unwrap_or(dst))
            })
            .collect()
    }

    /// Level `m` of each dirty face (or its box), halved from level `m - 1` with a linear
    /// filter. A box's blit is exactly 2:1 and aligned, so each texel averages the same four
    /// texels as the whole level's blit would.
    fn blit_down_to(&self, dev: &Device, cmd: vk::CommandBuffer, m: u32) {
        let layer = |mip, f| vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: mip,
            base_array_layer: f,
            layer_count: 1,
        };
        let corners = |r: &PixelRect, k: u32| {
            let at = |x: u32, y: u32| vk::Offset3D {
                x: (x * k) as i32,
                y: (y * k) as i32,
                z: 0,
            };
            [
                at(r.x0, r.y0),
                vk::Offset3D {
                    z: 1,
                    ..at(r.x1, r.y1)
                },
            ]
        };
        let mut blits = Vec::new();
        for &(f, rect) in &self.faces {
            let blit = |src: [vk::Offset3D; 2], dst: [vk::Offset3D; 2]| {
                vk::ImageBlit::default()
                    .src_subresource(layer(m - 1, f))
                    .src_offsets(src)
                    .dst_subresource(layer(m, f))
                    .dst_offsets(dst)
            };
            blits.push(match self.rect_at(rect, m) {
                None => {
                    let whole = |level| corners(&PixelRect::whole(self.side(level)), 1);
                    blit(whole(m - 1), whole(m))
                }
                Some(r) => blit(corners(&r, 2), corners(&r, 1)),
            });
        }
        let image = self.cube.color.raw;
        // SAFETY: level m-1 is TRANSFER_SRC, level m of these faces TRANSFER_DST; the format
        // supports linear blits (checked when the cube was created); every region lies in its
        // level (a rectangle at level m is within `side(m)`, twice it within `side(m - 1)`).
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
