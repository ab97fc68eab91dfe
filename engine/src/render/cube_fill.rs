//! Filling the cube map, a part of the renderer ([`CubeFill`]: the method and its pass):
//! layout transitions, the method's pass(es) (or a floor's), the mip chain. It records with
//! the frame's context ([`FrameParts`], which holds the cube it fills) and owns nothing else.

use ash::vk;

use super::draw::{barrier, COLOR_OUT, DEPTH_RW, SAMPLED};
use super::frame_parts::FrameParts;
use super::methods::{CubeLayout, CubePlan, CubeRecorder, FillPass, Method, Prepare};
use super::{FrameReport, TS_FILL, TS_MIPS};
use crate::vk::commands::image_barriers;
use crate::vk::GpuError;

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

/// The cube fill: the renderer's method and its pass (pipeline and per-renderer state).
pub(super) struct CubeFill {
    pass: Box<dyn FillPass>,
    method: Method,
}

impl CubeFill {
    pub fn new(method: Method, pass: Box<dyn FillPass>) -> Self {
        Self { pass, method }
    }

    /// The method that fills the cube.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The method's per-update data for `plan`.
    pub fn prepare(&mut self, plan: &CubePlan, prepare: &mut Prepare) -> Result<(), GpuError> {
        self.pass.prepare(plan, prepare)
    }

    /// Whether the renderer's method brackets each face with its own statistics query and
    /// timestamp (a per-face layout); the one-pass methods and the floors get one query for
    /// the whole fill.
    pub fn per_face_marks(&self) -> bool {
        self.method.layout() == CubeLayout::PerFace
    }

    /// Re-renders the dirty faces of the frame's cube with `fill` (the method, or a floor),
    /// then rebuilds the mips.
    pub fn record(
        &self,
        f: &FrameParts,
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
        let device = f.draw.device;
        device.begin_label(cmd, &format!("cube fill ({name})"));
        let per_face_marks = matches!(fill, Fill::Method) && self.per_face_marks();
        cube_to_fill(f, cmd, first_fill);
        if let (Some(q), false) = (&f.queries.statistics, per_face_marks) {
            q.begin(cmd, 0);
        }
        if !per_face_marks {
            // Per-face timestamps exist only for per-face methods; keep every slot answered.
            f.queries.face_timestamps(cmd, 0..6);
        }
        match fill {
            Fill::Method => {
                let ids = f.cube.ids.is_some();
                let layout = self.method.layout();
                let rec = CubeRecorder::new(f.fill_parts(), cmd, layout, per_face_marks, ids);
                self.pass.record(&rec, plan);
            }
            Fill::Other { record, .. } => {
                // Other fills write no ids: the id cube keeps what it had (the floors are
                // benchmark passes, which never read ids).
                let rec = CubeRecorder::new(f.fill_parts(), cmd, CubeLayout::PerFace, false, false);
                record(&rec, plan);
            }
        }
        if let (Some(q), false) = (&f.queries.statistics, per_face_marks) {
            q.end(cmd, 0);
        }
        for f in 0..6 {
            report.draws_per_face[f] = plan.visible[f].len() as u32;
        }
        report.faces_rendered = plan.dirty.count_ones();
        report.face_mask = plan.dirty;
        if let Some(q) = &f.queries.timestamps {
            q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_GRAPHICS, TS_FILL);
        }
        cube_to_read(f, cmd);
        super::mips::record(device, cmd, f.cube, plan.dirty);
        if let Some(q) = &f.queries.timestamps {
            q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, TS_MIPS);
        }
        device.end_label(cmd);
    }
}

/// The cube's mip 0, depth and ids made ready to render into. Clean faces keep their
/// pixels, colour and depth (the `distance` lookup's distance map), so the old layout is
/// named (UNDEFINED only before the first fill); the last readers were the mirror's
/// fragment shaders. The id cube, where there is one, goes the same way as the depth:
/// kept for the clean faces, read by the sensor ray passes' fragment shaders.
fn cube_to_fill(f: &FrameParts, cmd: vk::CommandBuffer, first_fill: bool) {
    let cube = f.cube;
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
    image_barriers(f.draw.device, cmd, &to_fill);
}

/// The depth the fill wrote, for the mirror's fragment shaders (distance lookup, sensor
/// ray passes), and the ids it wrote (sensor ray passes), made ready to sample. (The
/// colour goes on to the mip chain.)
fn cube_to_read(f: &FrameParts, cmd: vk::CommandBuffer) {
    let cube = f.cube;
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
    image_barriers(f.draw.device, cmd, &to_read);
}
