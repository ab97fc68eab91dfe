//! Multiview fill: one pass with view mask 0x3F over the 6-layer cube; each object visible in
//! some dirty face is drawn once and the driver replays it for the six views.
//!
//! A pipeline's view mask is fixed, so a partial update re-renders all six faces (still exact:
//! a clean face re-rendered from an unchanged scene gives the same pixels).

use ash::vk;

use crate::render::cube_fill::CubePlan;
use crate::render::gpu::Push;
use crate::render::Renderer;

pub(crate) fn record(r: &Renderer, cmd: vk::CommandBuffer, plan: &CubePlan) {
    r.begin_layered(cmd, 0x3F, super::Method::Multiview);
    let objects = plan.union();
    let facing = r.cube_facing();
    r.draw_objects(cmd, &r.pipelines.cube, Push::default(), &objects, &facing);
    r.end_rendering(cmd);
}
