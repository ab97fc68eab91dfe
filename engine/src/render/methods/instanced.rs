//! Instanced layered fill: every (object, dirty face) pair that survived culling becomes one
//! indirect draw of one instance whose `firstInstance` encodes `object << 3 | face`; the vertex
//! shader writes `gl_Layer`. One `vkCmdDrawIndexedIndirect` draws them all.

use ash::vk;

use crate::render::cube_fill::CubePlan;
use crate::render::draw::CUBE_FRONT;
use crate::render::gpu::INSTANCE_FACE_BITS;
use crate::render::resources::Drawable;
use crate::render::Renderer;

/// Consecutive indirect commands drawn with one cull mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Run {
    pub first: u32,
    pub count: u32,
    pub cull_back: bool,
}

/// The indirect commands for `plan`, object-major in the plan's draw order, so that within a
/// face objects are drawn in the same order as six-pass draws them (front to back; equal
/// depths resolve the same way); and the runs of commands that share a cull mode (one
/// indirect draw each), from `cull` (per drawable: back faces may be culled in the cube).
pub(crate) fn commands(
    drawables: &[Drawable],
    plan: &CubePlan,
    cull: &[bool],
) -> (Vec<vk::DrawIndexedIndirectCommand>, Vec<Run>) {
    let rank = plan.ranks();
    let mut pairs: Vec<(u32, u32)> = plan
        .faces()
        .flat_map(|f| plan.visible[f as usize].iter().map(move |&o| (o, f)))
        .collect();
    pairs.sort_unstable_by_key(|&(o, f)| (rank[o as usize], f));
    let mut runs: Vec<Run> = Vec::new();
    for (k, &(o, _)) in pairs.iter().enumerate() {
        let cull_back = cull[o as usize];
        match runs.last_mut() {
            Some(run) if run.cull_back == cull_back => run.count += 1,
            _ => runs.push(Run {
                first: k as u32,
                count: 1,
                cull_back,
            }),
        }
    }
    let commands = pairs
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
        .collect();
    (commands, runs)
}

pub(crate) fn record(r: &Renderer, cmd: vk::CommandBuffer, plan: &CubePlan) {
    let Some((buffer, runs)) = r.indirect.as_ref() else {
        return;
    };
    r.begin_layered(cmd, plan.dirty, super::Method::Instanced);
    r.bind_scene(cmd, &r.pipelines.cube);
    r.set_front_face(cmd, CUBE_FRONT);
    let stride = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u32;
    for run in runs {
        r.set_cull_back(cmd, run.cull_back);
        // SAFETY: the buffer holds the commands of every run, written before recording; the
        // device has multiDrawIndirect and drawIndirectFirstInstance (checked when the method
        // was chosen).
        unsafe {
            r.device.raw.cmd_draw_indexed_indirect(
                cmd,
                buffer.raw,
                u64::from(run.first) * u64::from(stride),
                run.count,
                stride,
            )
        };
    }
    r.end_rendering(cmd);
}
