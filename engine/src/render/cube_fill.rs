//! Filling the cube map, a part of the renderer ([`CubeFill`]: the method and its pass):
//! layout transitions, the method's pass(es) (or a floor's), the mip chain. It records with
//! the frame's context ([`FrameParts`], which holds the cube it fills) and owns nothing else.

use ash::vk;

use super::frame_parts::FrameParts;
use super::graph::{self, FrameGraph, Use};
use super::methods::{CubeLayout, CubePlan, CubeRecorder, FillPass, Method, Patching, Prepare};
use super::{FrameReport, TS_FILL, TS_MIPS};
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
    /// How the method draws a face's dirty rectangles.
    patching: Patching,
}

impl CubeFill {
    /// `patching` is the caller's choice for a per-face method; a layered or multiview scope
    /// has one scissor for every face, so its rectangles always go under one box a face.
    pub fn new(method: Method, pass: Box<dyn FillPass>, patching: Patching) -> Self {
        let patching = match method.layout() {
            CubeLayout::Layered | CubeLayout::Multiview => Patching::OneBox,
            CubeLayout::PerFace => patching,
        };
        Self {
            pass,
            method,
            patching,
        }
    }

    /// How the method draws a face's dirty rectangles.
    pub fn patching(&self) -> Patching {
        self.patching
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
    /// then rebuilds the mips. The cube's images are `graph`'s (imported fresh before the
    /// first fill).
    pub fn record(
        &self,
        (f, graph): (&FrameParts, &mut FrameGraph),
        cmd: vk::CommandBuffer,
        plan: &CubePlan,
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
        let ids = matches!(fill, Fill::Method);
        graph.declare(device, cmd, &fill_uses(f, ids));
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
            report.draws_per_face[f] = match &plan.patches[f][..] {
                [] => plan.visible[f].len(),
                patches => patches.iter().map(|p| p.visible.len()).sum(),
            } as u32;
        }
        report.texels_rendered = plan.texels(f.cube.size);
        report.faces_rendered = plan.dirty.count_ones();
        report.face_mask = plan.dirty;
        if let Some(q) = &f.queries.timestamps {
            q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_GRAPHICS, TS_FILL);
        }
        graph.declare(device, cmd, &read_uses(f, ids));
        super::mips::record((device, graph), cmd, f.cube, plan);
        if let Some(q) = &f.queries.timestamps {
            q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, TS_MIPS);
        }
        device.end_label(cmd);
    }
}

/// The fill's uses: the cube's mip 0 and depth, and with `ids` the id cube, drawn into with
/// the clean faces kept (their colour, their depth, which is the `distance` lookup's distance
/// map, and their ids, which the ray-map pass reads through the cube). Other fills (the floors) write no
/// ids: the id cube keeps what it had and is not declared.
fn fill_uses(f: &FrameParts, ids: bool) -> Vec<(graph::Resource, Use)> {
    let (depth, id_cube) = f.cube.depth_and_ids();
    let mut uses = vec![
        (f.cube.color_levels(0, 1, None), Use::ColorKept),
        (depth, Use::DepthKept),
    ];
    uses.extend(id_cube.filter(|_| ids).map(|i| (i, Use::ColorKept)));
    uses
}

/// The depth the fill wrote, for the mirror's fragment shaders (distance lookup, the ray map's
/// pass through the cube), and the ids it wrote (the same pass), read from here on. (The colour goes on
/// to the mip chain.)
fn read_uses(f: &FrameParts, ids: bool) -> Vec<(graph::Resource, Use)> {
    let (depth, id_cube) = f.cube.depth_and_ids();
    let mut uses = vec![(depth, Use::FragmentRead)];
    uses.extend(id_cube.filter(|_| ids).map(|i| (i, Use::FragmentRead)));
    uses
}
