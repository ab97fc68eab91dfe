//! Geometry-shader layered fill: one pass over the 6-layer cube; each object visible in some
//! dirty face is drawn once, and `cube_layered.geom` emits each triangle to the dirty faces
//! whose clip volume it touches.

use ash::vk;

use crate::render::cube_fill::CubePlan;
use crate::render::gpu::Push;
use crate::render::Renderer;

pub(crate) fn record(r: &Renderer, cmd: vk::CommandBuffer, plan: &CubePlan) {
    r.begin_layered(cmd, plan.dirty, super::Method::Geometry);
    let push = Push {
        face_mask: u32::from(plan.dirty),
        ..Push::default()
    };
    let objects = plan.union();
    r.draw_objects(cmd, &r.pipelines.cube, push, &objects, &r.cube_facing());
    r.end_rendering(cmd);
}
