//! Filling the cube map: layout transitions, the chosen method's pass(es), the mip chain.

use ash::vk;

use super::draw::{barrier, COLOR_OUT, DEPTH_RW, SAMPLED};
use crate::scene::camera::{Frustum, ViewBasis};

use super::methods::{CubeLayout, CubePlan, CubeRecorder};
use super::{FrameReport, Renderer, TS_FILL, TS_MIPS};
use crate::vk::commands::image_barriers;

/// What fills the dirty faces of a cube update: the renderer's method, or another recording
/// into the same cube and faces (the benchmark's floors), which gets one timestamp pair, no
/// per-face marks and no id cube. Given as a recording, not as a floor, so that this module
/// knows nothing of the floors (they use it, not the other way round).
#[derive(Clone, Copy)]
pub(super) enum Fill<'a> {
    /// The renderer's method.
    Method,
    Other {
        name: &'static str,
        record: &'a dyn Fn(&CubeRecorder<'_>, &CubePlan),
    },
}

impl Renderer {
    /// Culls every dirty face against its frustum.
    pub(super) fn plan_cube(&self, views: &[ViewBasis], dirty: u8) -> CubePlan {
        let mut plan = CubePlan {
            dirty,
            order: self.drawn.order.clone(),
            ..Default::default()
        };
        for f in plan.faces().collect::<Vec<_>>() {
            let frustum = Frustum::new(
                &views[f as usize],
                self.scene.cube.near_m,
                self.scene.cube.far_m,
            );
            plan.visible[f as usize] = self.drawn.visible(&frustum);
        }
        plan
    }

    /// Whether the renderer's method brackets each face with its own statistics query and
    /// timestamp (a per-face layout); the one-pass methods and the floors get one query for
    /// the whole fill.
    pub(super) fn per_face_marks(&self) -> bool {
        self.method.layout() == CubeLayout::PerFace
    }

    /// Re-renders the dirty faces with the renderer's method, then rebuilds the mips.
    pub(super) fn record_cube(
        &self,
        cmd: vk::CommandBuffer,
        plan: &CubePlan,
        first_fill: bool,
        report: &mut FrameReport,
    ) {
        self.record_cube_fill(cmd, plan, first_fill, report, Fill::Method);
    }

    /// Like [`Self::record_cube`], with `fill` drawing the faces (the method or a floor).
    pub(super) fn record_cube_fill(
        &self,
        cmd: vk::CommandBuffer,
        plan: &CubePlan,
        first_fill: bool,
        report: &mut FrameReport,
        fill: Fill,
    ) {
        let name = match fill {
            Fill::Method => self.method.name(),
            Fill::Other { name, .. } => name,
        };
        self.device.begin_label(cmd, &format!("cube fill ({name})"));
        let per_face_marks = matches!(fill, Fill::Method) && self.per_face_marks();
        self.cube_to_fill(cmd, first_fill);
        if let (Some(q), false) = (&self.queries().statistics, per_face_marks) {
            q.begin(cmd, 0);
        }
        if !per_face_marks {
            // Per-face timestamps exist only for per-face methods; keep every slot answered.
            self.queries().face_timestamps(cmd, 0..6);
        }
        match fill {
            Fill::Method => {
                let ids = self.cube.ids.is_some();
                let parts = self.fill_parts();
                let rec = CubeRecorder::new(parts, cmd, self.method.layout(), per_face_marks, ids);
                self.fill.record(&rec, plan);
            }
            Fill::Other { record, .. } => {
                // Other fills write no ids: the id cube keeps what it had (the floors are
                // benchmark passes, which never read ids).
                let rec =
                    CubeRecorder::new(self.fill_parts(), cmd, CubeLayout::PerFace, false, false);
                record(&rec, plan);
            }
        }
        if let (Some(q), false) = (&self.queries().statistics, per_face_marks) {
            q.end(cmd, 0);
        }
        for f in 0..6 {
            report.draws_per_face[f] = plan.visible[f].len() as u32;
        }
        report.faces_rendered = plan.dirty.count_ones();
        report.face_mask = plan.dirty;
        if let Some(q) = &self.queries().timestamps {
            q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_GRAPHICS, TS_FILL);
        }
        self.cube_to_read(cmd);
        super::mips::record(&self.device, cmd, &self.cube, plan.dirty);
        if let Some(q) = &self.queries().timestamps {
            q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, TS_MIPS);
        }
        self.device.end_label(cmd);
    }

    /// The cube's mip 0, depth and ids made ready to render into. Clean faces keep their
    /// pixels, colour and depth (the `distance` lookup's distance map), so the old layout is
    /// named (UNDEFINED only before the first fill); the last readers were the mirror's
    /// fragment shaders. The id cube, where there is one, goes the same way as the depth:
    /// kept for the clean faces, read by the sensor ray passes' fragment shaders.
    fn cube_to_fill(&self, cmd: vk::CommandBuffer, first_fill: bool) {
        let cube = &self.cube;
        let mip0 = vk::ImageSubresourceRange {
            level_count: 1,
            ..cube.color.full_range()
        };
        let old = if first_fill {
            vk::ImageLayout::UNDEFINED
        } else {
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL
        };
        let mut to_fill = vec![
            barrier(
                cube.color.raw,
                mip0,
                (old, SAMPLED),
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
            ),
            barrier(
                cube.depth.raw,
                cube.depth.full_range(),
                (old, SAMPLED),
                (vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, DEPTH_RW),
            ),
        ];
        to_fill.extend(cube.ids.as_ref().map(|ids| {
            barrier(
                ids.image.raw,
                ids.image.full_range(),
                (old, SAMPLED),
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
            )
        }));
        image_barriers(&self.device, cmd, &to_fill);
    }

    /// The depth the fill wrote, for the mirror's fragment shaders (distance lookup, sensor
    /// ray passes), and the ids it wrote (sensor ray passes), made ready to sample. (The
    /// colour goes on to the mip chain.)
    fn cube_to_read(&self, cmd: vk::CommandBuffer) {
        let cube = &self.cube;
        let mut to_read = vec![barrier(
            cube.depth.raw,
            cube.depth.full_range(),
            (vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, DEPTH_RW),
            (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED),
        )];
        to_read.extend(cube.ids.as_ref().map(|ids| {
            barrier(
                ids.image.raw,
                ids.image.full_range(),
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, COLOR_OUT),
                (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED),
            )
        }));
        image_barriers(&self.device, cmd, &to_read);
    }
}
