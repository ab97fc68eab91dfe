//! Six-pass: one rendering scope per dirty face, drawing what that face's frustum holds.

use ash::vk;

use crate::render::cube_fill::CubePlan;
use crate::render::gpu::Push;
use crate::render::Renderer;

pub(crate) fn record(r: &Renderer, cmd: vk::CommandBuffer, plan: &CubePlan) {
    let facing = r.cube_facing();
    for face in 0..6u32 {
        if plan.dirty & (1 << face) != 0 {
            r.device.begin_label(
                cmd,
                &format!("face {}", crate::render::camera::FACE_NAMES[face as usize]),
            );
            if let Some(q) = &r.statistics {
                q.begin(cmd, face);
            }
            r.begin_face(cmd, face);
            let push = Push {
                view_index: face,
                ..Push::default()
            };
            let visible = &plan.visible[face as usize];
            r.draw_objects(cmd, &r.pipelines.cube, push, visible, &facing);
            r.end_rendering(cmd);
            if let Some(q) = &r.statistics {
                q.end(cmd, face);
            }
            r.device.end_label(cmd);
        }
        r.face_timestamps(cmd, face..face + 1);
    }
}
