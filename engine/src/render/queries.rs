//! The frame's queries, one part of the renderer: timestamps at the frame's milestones and
//! pipeline statistics per face and per view, where the device has them. The fill, the view
//! passes and the readback write and read them through this part's pools and slots.

use std::sync::Arc;

use ash::vk;

use super::FrameReport;
use crate::vk::device::Device;
use crate::vk::queries::{PipelineStats, QueryPool};
use crate::vk::GpuError;

/// Timestamp slots: start, after each face (six-pass), after the fill, after the mips, after
/// each view, after the readback copies.
pub(super) const TS_START: u32 = 0;
pub(super) const TS_FACE0: u32 = 1;
pub(super) const TS_FILL: u32 = 7;
pub(super) const TS_MIPS: u32 = 8;
pub(super) const TS_OBSERVER: u32 = 9;
pub(super) const TS_SENSOR: u32 = 10;
pub(super) const TS_PAIR: u32 = 11;
pub(super) const TS_READBACK: u32 = 12;
pub(super) const TS_COUNT: u32 = 13;
/// Statistics slots: six faces, then the three views.
pub(super) const STATS_COUNT: u32 = 9;

/// The statistics queries a frame reads back (only queries begun in the frame have
/// results): decided when it is recorded, since their results are copied at its end.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct StatsRead {
    /// Bit f: statistics query f (a face of six-pass, or slot 0 for a one-pass fill).
    pub fill: u32,
    /// Bit v: the query of view v (observer, sensor, pair), drawn this frame.
    pub views: u32,
}

impl StatsRead {
    /// The views' queries a frame begins: observer, sensor and pair, or the sensor alone; none
    /// in a window's frame (`shown`), whose one view keeps no statistics.
    pub fn views_drawn(readback: super::Readback, shown: bool) -> u32 {
        match (readback.views, readback.sensor) {
            _ if shown => 0,
            (true, _) => 0b111,
            (false, true) => 0b010,
            (false, false) => 0,
        }
    }

    /// The statistics queries a frame reads: after a cube update, the faces a per-face
    /// method (`per_face`) rendered (a query each) or the one-pass fill's query 0; the views'
    /// when asked.
    pub fn of(update: bool, per_face: bool, face_mask: u32, views: u32) -> StatsRead {
        let fill = match (update, per_face) {
            (false, _) => 0,
            (true, true) => face_mask & 0x3F,
            (true, false) => 1,
        };
        StatsRead { fill, views }
    }
}

/// The two pools, each `None` where the device lacks its kind of query.
pub(super) struct FrameQueries {
    pub timestamps: Option<QueryPool>,
    pub statistics: Option<QueryPool>,
}

impl FrameQueries {
    /// A finished frame's timestamps and the statistics in `stats`, from the copies its
    /// commands ended with, into `report` (per face where the fill was `per_face`).
    pub fn read(
        &self,
        report: &mut FrameReport,
        stats: StatsRead,
        per_face: bool,
    ) -> Result<(), GpuError> {
        if let Some(q) = &self.timestamps {
            let t = q.timestamps_ns(TS_COUNT)?;
            let ms = |a: u32, b: u32| (t[b as usize] - t[a as usize]) / 1e6;
            if per_face {
                report.gpu_face_ms = Some(std::array::from_fn(|f| {
                    ms(TS_FACE0 + f as u32 - 1, TS_FACE0 + f as u32)
                }));
            }
            report.gpu_fill_ms = Some(ms(TS_START, TS_FILL));
            report.gpu_cube_ms = Some(ms(TS_START, TS_MIPS));
            report.gpu_mips_ms = Some(ms(TS_FILL, TS_MIPS));
            report.gpu_observer_ms = Some(ms(TS_MIPS, TS_OBSERVER));
            report.gpu_sensor_ms = Some(ms(TS_OBSERVER, TS_SENSOR));
            report.gpu_pair_ms = Some(ms(TS_SENSOR, TS_PAIR));
        }
        if let Some(q) = &self.statistics {
            if stats.fill != 0 && per_face {
                let mut faces = [PipelineStats::default(); 6];
                let mut total = PipelineStats::default();
                for f in 0..6u32 {
                    if stats.fill & (1 << f) != 0 {
                        faces[f as usize] = q.statistics(f, 1)?[0];
                        total += faces[f as usize];
                    }
                }
                report.face_stats = Some(faces);
                report.fill_stats = Some(total);
            } else if stats.fill != 0 {
                report.fill_stats = Some(q.statistics(0, 1)?[0]);
            }
            if stats.views != 0 {
                let mut views = [None; 3];
                for v in (0..3).filter(|v| stats.views & (1 << v) != 0) {
                    views[v as usize] = Some(q.statistics(6 + v, 1)?[0]);
                }
                report.view_stats = Some(views);
            }
        }
        Ok(())
    }

    pub fn create(device: &Arc<Device>) -> Result<Self, GpuError> {
        let features = &device.info.features;
        let timestamps = (features.timestamps)
            .then(|| QueryPool::timestamps(device, TS_COUNT, "frame timestamps"))
            .transpose()?;
        let statistics = (features.pipeline_statistics)
            .then(|| QueryPool::pipeline_statistics(device, STATS_COUNT, "frame statistics"))
            .transpose()?;
        Ok(Self {
            timestamps,
            statistics,
        })
    }

    /// At the start of a frame's commands: both pools reset, the start timestamp written.
    pub fn begin_frame(&self, cmd: vk::CommandBuffer) {
        if let Some(q) = &self.timestamps {
            q.reset(cmd);
            q.write_timestamp(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, TS_START);
        }
        if let Some(q) = &self.statistics {
            q.reset(cmd);
        }
    }

    /// Writes the per-face timestamp slots `faces` (six-pass: after each face).
    pub fn face_timestamps(&self, cmd: vk::CommandBuffer, faces: std::ops::Range<u32>) {
        if let Some(q) = &self.timestamps {
            for f in faces {
                q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_GRAPHICS, TS_FACE0 + f);
            }
        }
    }

    /// The buffers the results are copied into, for the host: declared to the frame graph,
    /// which makes the copies visible to the host once they are recorded.
    pub fn result_buffers(&self) -> impl Iterator<Item = vk::Buffer> + '_ {
        let pools = [&self.timestamps, &self.statistics];
        pools.into_iter().flatten().map(|q| q.results_buffer())
    }

    /// At the end of a frame's commands, after its last timestamp: the results it will read
    /// (every timestamp, the statistics in `read`) copied for the host.
    pub fn copy_results(&self, cmd: vk::CommandBuffer, read: StatsRead) {
        if let Some(q) = &self.timestamps {
            q.copy_results(cmd, 0, TS_COUNT);
        }
        if let Some(q) = &self.statistics {
            for f in (0..6).filter(|f| read.fill & (1 << f) != 0) {
                q.copy_results(cmd, f, 1);
            }
            for v in (0..3).filter(|v| read.views & (1 << v) != 0) {
                q.copy_results(cmd, 6 + v, 1);
            }
        }
    }
}
