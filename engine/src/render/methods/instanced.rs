//! Instanced layered fill: every (object, dirty face) pair that survived culling becomes one
//! indirect draw of one instance whose `firstInstance` encodes `object << 3 | face`; the vertex
//! shader writes `gl_Layer`. One `vkCmdDrawIndexedIndirect` draws them all.

use ash::vk;

use crate::render::cube_fill::CubePlan;
use crate::render::gpu::INSTANCE_FACE_BITS;
use crate::render::resources::Drawable;
use crate::render::Renderer;

/// The indirect commands for `plan`, object-major in the plan's draw order, so that within a
/// face objects are drawn in the same order as six-pass draws them (front to back; equal
/// depths resolve the same way).
pub(crate) fn commands(
    drawables: &[Drawable],
    plan: &CubePlan,
) -> Vec<vk::DrawIndexedIndirectCommand> {
    let rank = plan.ranks();
    let mut pairs: Vec<(u32, u32)> = plan
        .faces()
        .flat_map(|f| plan.visible[f as usize].iter().map(move |&o| (o, f)))
        .collect();
    pairs.sort_unstable_by_key(|&(o, f)| (rank[o as usize], f));
    pairs
        .into_iter()
        .map(|(o, f)| {
            let d = &drawables[o as usize];
            vk::DrawIndexedIndirectCommand {
                index_count: d.index_count,
                instance_count: 1,
                first_index: d.first_index,
                vertex_offset: d.vertex_offset,
                first_instance: (o << INSTANCE_FACE_BITS) | f,
            }
        })
        .collect()
}

pub(crate) fn record(r: &Renderer, cmd: vk::CommandBuffer, _plan: &CubePlan) {
    let Some((buffer, count)) = r.indirect.as_ref().map(|(b, n)| (b.raw, *n)) else {
        return;
    };
    r.begin_layered(cmd, _plan.dirty, super::Method::Instanced);
    r.bind_scene(cmd, &r.pipelines.cube);
    if count > 0 {
        let stride = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u32;
        // SAFETY: the buffer holds `count` commands written before recording; the device has
        // multiDrawIndirect and drawIndirectFirstInstance (checked when the method was chosen).
        unsafe {
            r.device
                .raw
                .cmd_draw_indexed_indirect(cmd, buffer, 0, count, stride)
        };
    }
    r.end_rendering(cmd);
}
