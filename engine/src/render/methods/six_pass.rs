//! Six-pass: one rendering scope per dirty face, drawing what that face's frustum holds (the
//! thesis's method, and the reference every other method must match bit for bit); on an
//! incremental update, only the face's dirty rectangles, each what its own frustum holds.

use ash::vk;

use super::{CubeLayout, CubePlan, CubeRecorder, FillMethod, FillPass, MethodContext, Needs};
use crate::render::gpu::Push;
use crate::vk::pipeline::Pipeline;
use crate::vk::GpuError;

pub struct SixPass;

impl FillMethod for SixPass {
    fn name(&self) -> &'static str {
        "six-pass"
    }

    fn summary(&self) -> &'static str {
        "one pass per dirty face; each object culled per face on the CPU"
    }

    fn needs(&self) -> Needs {
        Needs::default()
    }

    fn layout(&self) -> CubeLayout {
        CubeLayout::PerFace
    }

    fn create(&self, ctx: &MethodContext<'_>) -> Result<Box<dyn FillPass>, GpuError> {
        let vertex = (vk::ShaderStageFlags::VERTEX, crate::shaders::SCENE_VERT);
        let pipeline = ctx.pipeline(&[vertex], "cube pipeline (six-pass)")?;
        Ok(Box::new(SixPassFill { pipeline }))
    }
}

struct SixPassFill {
    pipeline: Pipeline,
}

impl FillPass for SixPassFill {
    fn record(&self, rec: &CubeRecorder<'_>, plan: &CubePlan) {
        for face in 0..6u32 {
            if plan.dirty & (1 << face) != 0 {
                let patches = &plan.patches[face as usize];
                rec.begin_face(face, patches);
                let push = Push {
                    view_index: face,
                    ..Push::default()
                };
                if patches.is_empty() {
                    rec.draw_objects(&self.pipeline, push, &plan.visible[face as usize]);
                }
                // Each dirty rectangle: what its frustum holds, scissored to it.
                for patch in patches {
                    rec.scissor(patch);
                    rec.draw_objects(&self.pipeline, push, &patch.visible);
                }
                rec.end_face(face);
            }
            rec.face_timestamp(face);
        }
    }
}
