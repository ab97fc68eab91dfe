//! Instanced layered fill: every (object, dirty face) pair that survived culling becomes one
//! indirect draw of one instance whose `firstInstance` encodes `object << 3 | face`; the vertex
//! shader writes `gl_Layer`. One `vkCmdDrawIndexedIndirect` per run of equal culling draws
//! them all.

use ash::vk;

use super::{
    CubeLayout, CubePlan, CubeRecorder, FillMethod, FillPass, MethodContext, Needs, Prepare,
};
use crate::render::gpu::INSTANCE_FACE_BITS;
use crate::render::resources::Drawable;
use crate::vk::device::OptionalFeatures;
use crate::vk::memory::{Buffer, BufferDesc};
use crate::vk::pipeline::Pipeline;
use crate::vk::GpuError;

pub struct Instanced;

impl FillMethod for Instanced {
    fn name(&self) -> &'static str {
        "instanced"
    }

    fn summary(&self) -> &'static str {
        "one layered pass; one instance per (object, face) pair, gl_Layer from the vertex shader"
    }

    fn needs(&self) -> Needs {
        Needs {
            features: OptionalFeatures {
                shader_output_layer: true,
                multi_draw_indirect: true,
                ..Default::default()
            },
            limits: &[],
            probe: false,
        }
    }

    fn layout(&self) -> CubeLayout {
        CubeLayout::Layered
    }

    fn create(&self, ctx: &MethodContext<'_>) -> Result<Box<dyn FillPass>, GpuError> {
        let vertex = (
            vk::ShaderStageFlags::VERTEX,
            crate::shaders::CUBE_INSTANCED_VERT,
        );
        let pipeline = ctx.pipeline(&[vertex], "cube pipeline (instanced)")?;
        // At most one command per drawable and face: sized once, so that no frame in flight
        // ever reads a buffer that was replaced.
        let most = 6 * ctx.drawables.len() as u64;
        let command = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u64;
        let desc =
            BufferDesc::new_device_local(most * command, vk::BufferUsageFlags::INDIRECT_BUFFER);
        let indirect = Buffer::create(ctx.device, &desc, "indirect draws")?;
        Ok(Box::new(InstancedFill {
            pipeline,
            indirect,
            runs: Vec::new(),
        }))
    }
}

struct InstancedFill {
    pipeline: Pipeline,
    /// This update's indirect commands (device-local, filled through the frame's uploads).
    indirect: Buffer,
    /// The runs of commands that share a cull mode, one indirect draw each.
    runs: Vec<Run>,
}

/// Consecutive indirect commands drawn with one cull mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Run {
    first: u32,
    count: u32,
    cull_back: bool,
}

impl FillPass for InstancedFill {
    fn prepare(&mut self, plan: &CubePlan, ctx: &mut Prepare<'_>) -> Result<(), GpuError> {
        let (commands, runs) = commands(ctx.drawables, plan, ctx.cull_back);
        self.runs = runs;
        ctx.uploads.write(&self.indirect, &as_words(&commands))
    }

    fn record(&self, rec: &CubeRecorder<'_>, plan: &CubePlan) {
        rec.begin_cube(plan);
        if !self.runs.is_empty() {
            let buffer = &self.indirect;
            rec.bind(&self.pipeline);
            let stride = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u32;
            for run in &self.runs {
                rec.set_cull_back(run.cull_back);
                // SAFETY: the buffer holds the commands of every run, written in `prepare`;
                // the device has multiDrawIndirect and drawIndirectFirstInstance (the
                // method's needs).
                unsafe {
                    rec.device().raw.cmd_draw_indexed_indirect(
                        rec.cmd(),
                        buffer.raw,
                        u64::from(run.first) * u64::from(stride),
                        run.count,
                        stride,
                    )
                };
            }
        }
        rec.end_cube();
    }
}

/// The indirect commands for `plan`, object-major in the plan's draw order, so that within a
/// face objects are drawn in the same order as six-pass draws them (front to back; equal
/// depths resolve the same way); and the runs of commands that share a cull mode, from
/// `cull` (per drawable: back faces may be culled in the cube).
fn commands(
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

/// `VkDrawIndexedIndirectCommand` is five 32-bit fields; copy them as plain words.
fn as_words(commands: &[vk::DrawIndexedIndirectCommand]) -> Vec<u32> {
    commands
        .iter()
        .flat_map(|c| {
            [
                c.index_count,
                c.instance_count,
                c.first_index,
                c.vertex_offset as u32,
                c.first_instance,
            ]
        })
        .collect()
}
