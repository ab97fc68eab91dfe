//! Timestamp and pipeline-statistics query pools.
//!
//! Results reach the host through a buffer, not `vkGetQueryPoolResults`: a frame's command
//! buffer ends by copying the results it will read ([`QueryPool::copy_results`]) into its
//! pool's host-visible buffer, which the host reads after the frame's fence. That is how a
//! GPU with frames in flight is asked anyway, and on lavapipe it is the only way that does
//! not wait: its `vkGetQueryPoolResults` begins by waiting for the idle device, so reading
//! one finished frame's timestamps waited for the next frame in flight too (a whole slow
//! frame in the viewer's loop, measured).

use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::memory::{Buffer, BufferDesc};
use super::{GpuError, VkContext};

/// The pipeline statistics every pool records, in the bit order Vulkan writes them.
pub const PIPELINE_STATISTICS: vk::QueryPipelineStatisticFlags =
    vk::QueryPipelineStatisticFlags::from_raw(
        vk::QueryPipelineStatisticFlags::VERTEX_SHADER_INVOCATIONS.as_raw()
            | vk::QueryPipelineStatisticFlags::CLIPPING_INVOCATIONS.as_raw()
            | vk::QueryPipelineStatisticFlags::CLIPPING_PRIMITIVES.as_raw()
            | vk::QueryPipelineStatisticFlags::FRAGMENT_SHADER_INVOCATIONS.as_raw(),
    );

/// Added on devices created with mesh shaders whose queries count them (meshShaderQueries);
/// their bits come after the fragment shader's, so their results follow.
pub const MESH_STATISTICS: vk::QueryPipelineStatisticFlags =
    vk::QueryPipelineStatisticFlags::from_raw(
        vk::QueryPipelineStatisticFlags::TASK_SHADER_INVOCATIONS_EXT.as_raw()
            | vk::QueryPipelineStatisticFlags::MESH_SHADER_INVOCATIONS_EXT.as_raw(),
    );

/// Work counters of one query (see [`PIPELINE_STATISTICS`]). The task and mesh counters are
/// `None` where the device does not count them (absent, never zero).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PipelineStats {
    pub vertex_invocations: u64,
    pub clipping_invocations: u64,
    pub clipping_primitives: u64,
    pub fragment_invocations: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub task_invocations: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh_invocations: Option<u64>,
}

impl std::ops::AddAssign for PipelineStats {
    fn add_assign(&mut self, o: Self) {
        let add = |a: Option<u64>, b: Option<u64>| match (a, b) {
            (None, None) => None,
            (a, b) => Some(a.unwrap_or(0) + b.unwrap_or(0)),
        };
        self.vertex_invocations += o.vertex_invocations;
        self.clipping_invocations += o.clipping_invocations;
        self.clipping_primitives += o.clipping_primitives;
        self.fragment_invocations += o.fragment_invocations;
        self.task_invocations = add(self.task_invocations, o.task_invocations);
        self.mesh_invocations = add(self.mesh_invocations, o.mesh_invocations);
    }
}

impl std::iter::Sum for PipelineStats {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::default(), |mut a, s| {
            a += s;
            a
        })
    }
}

/// A query pool of one type.
pub struct QueryPool {
    pub raw: vk::QueryPool,
    pub count: u32,
    kind: vk::QueryType,
    /// Statistics pools: whether task and mesh invocations are counted too.
    mesh_counted: bool,
    /// Bytes of one query's results (64-bit values).
    stride: u64,
    /// Where [`Self::copy_results`] puts them for the host (query i at `i * stride`).
    results: Buffer,
    device: Arc<Device>,
}

impl QueryPool {
    pub fn timestamps(device: &Arc<Device>, count: u32, name: &str) -> Result<Self, GpuError> {
        Self::create(device, vk::QueryType::TIMESTAMP, count, name)
    }

    pub fn pipeline_statistics(
        device: &Arc<Device>,
        count: u32,
        name: &str,
    ) -> Result<Self, GpuError> {
        Self::create(device, vk::QueryType::PIPELINE_STATISTICS, count, name)
    }

    fn create(
        device: &Arc<Device>,
        kind: vk::QueryType,
        count: u32,
        name: &str,
    ) -> Result<Self, GpuError> {
        let mut info = vk::QueryPoolCreateInfo::default()
            .query_type(kind)
            .query_count(count.max(1));
        let mesh_counted = kind == vk::QueryType::PIPELINE_STATISTICS
            && device.enabled.mesh_shader
            && device.info.features.mesh_shader_queries;
        if kind == vk::QueryType::PIPELINE_STATISTICS {
            let mesh = if mesh_counted {
                MESH_STATISTICS
            } else {
                vk::QueryPipelineStatisticFlags::empty()
            };
            info = info.pipeline_statistics(PIPELINE_STATISTICS | mesh);
        }
        let values = match kind {
            vk::QueryType::PIPELINE_STATISTICS if mesh_counted => 6,
            vk::QueryType::PIPELINE_STATISTICS => 4,
            _ => 1,
        };
        let stride = 8 * values;
        let count = count.max(1);
        let desc = BufferDesc::new_readback(stride * u64::from(count));
        let results = Buffer::create(device, &desc, &format!("{name} results"))?;
        // SAFETY: valid create info; the feature was enabled when the type needs one.
        let raw = unsafe { device.raw.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        device.set_name(raw, name);
        Ok(Self {
            raw,
            count,
            kind,
            mesh_counted,
            stride,
            results,
            device: Arc::clone(device),
        })
    }

    /// Resets every query (recorded; must precede their use in the same command buffer).
    pub fn reset(&self, cmd: vk::CommandBuffer) {
        // SAFETY: cmd is recording outside a render pass.
        unsafe {
            self.device
                .raw
                .cmd_reset_query_pool(cmd, self.raw, 0, self.count)
        };
    }

    /// Writes a timestamp once all previous work has passed `stage`.
    pub fn write_timestamp(
        &self,
        cmd: vk::CommandBuffer,
        stage: vk::PipelineStageFlags2,
        index: u32,
    ) {
        debug_assert_eq!(self.kind, vk::QueryType::TIMESTAMP);
        // SAFETY: index < count; the query was reset in this command buffer.
        unsafe {
            self.device
                .raw
                .cmd_write_timestamp2(cmd, stage, self.raw, index)
        };
    }

    pub fn begin(&self, cmd: vk::CommandBuffer, index: u32) {
        // SAFETY: index < count; the query was reset and is not active.
        unsafe {
            self.device
                .raw
                .cmd_begin_query(cmd, self.raw, index, vk::QueryControlFlags::empty())
        };
    }

    pub fn end(&self, cmd: vk::CommandBuffer, index: u32) {
        // SAFETY: paired with begin on the same command buffer.
        unsafe { self.device.raw.cmd_end_query(cmd, self.raw, index) };
    }

    /// The buffer [`Self::copy_results`] copies into, which the host reads.
    pub fn results_buffer(&self) -> vk::Buffer {
        self.results.raw
    }

    /// Records the copy of queries `first..first + n`'s results into the pool's buffer, once
    /// the GPU has them (`WAIT`: each must have been written or ended in this frame). The
    /// caller makes the copies visible to the host (a barrier from `COPY` to the host's
    /// reads).
    pub fn copy_results(&self, cmd: vk::CommandBuffer, first: u32, n: u32) {
        debug_assert!(first + n <= self.count);
        let flags = vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT;
        let offset = u64::from(first) * self.stride;
        // SAFETY: the range lies in the pool and its results fit the buffer at `offset`; cmd
        // is recording outside a render pass.
        unsafe {
            self.device.raw.cmd_copy_query_pool_results(
                cmd,
                self.raw,
                first,
                n,
                self.results.raw,
                offset,
                self.stride,
                flags,
            )
        };
    }

    /// Results of queries `first..first + n`, each a `T` of 64-bit values, as
    /// [`Self::copy_results`] left them: read after the fence of the frame that copied them.
    fn results<T: bytemuck::Pod>(&self, first: u32, n: u32) -> Result<Vec<T>, GpuError> {
        debug_assert_eq!(std::mem::size_of::<T>() as u64, self.stride);
        let bytes = self.results.mapped()?;
        let at = |i: u32| (u64::from(i) * self.stride) as usize;
        let range = bytes.get(at(first)..at(first + n)).ok_or_else(|| {
            GpuError::Unsupported(format!("queries {first}..{} out of the pool", first + n))
        })?;
        Ok(range
            .chunks_exact(self.stride as usize)
            .map(bytemuck::pod_read_unaligned)
            .collect())
    }

    /// Whether each of queries `0..n` holds a result, without waiting (a query that was
    /// reset and never written has none).
    pub fn availability(&self, n: u32) -> Result<Vec<bool>, GpuError> {
        let mut data = vec![[0u64; 2]; n as usize];
        // SAFETY: each element holds one 64-bit result and its 64-bit availability word, the
        // layout WITH_AVAILABILITY writes; without WAIT, unavailable queries are skipped.
        let result = unsafe {
            self.device.raw.get_query_pool_results(
                self.raw,
                0,
                &mut data,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WITH_AVAILABILITY,
            )
        };
        match result {
            Ok(()) | Err(vk::Result::NOT_READY) => Ok(data.iter().map(|d| d[1] != 0).collect()),
            Err(e) => Err(e).vk("vkGetQueryPoolResults"),
        }
    }

    /// Timestamps in nanoseconds (raw ticks times the device's period).
    pub fn timestamps_ns(&self, n: u32) -> Result<Vec<f64>, GpuError> {
        let period = f64::from(self.device.info.limits.timestamp_period_ns);
        Ok(self
            .results::<u64>(0, n)?
            .iter()
            .map(|&t| t as f64 * period)
            .collect())
    }

    /// Statistics of queries `first..first + n` (each must have been begun and ended).
    pub fn statistics(&self, first: u32, n: u32) -> Result<Vec<PipelineStats>, GpuError> {
        let rows: Vec<[u64; 6]> = if self.mesh_counted {
            self.results::<[u64; 6]>(first, n)?
        } else {
            let four = self.results::<[u64; 4]>(first, n)?;
            four.iter()
                .map(|c| [c[0], c[1], c[2], c[3], 0, 0])
                .collect()
        };
        let counted = |c: &[u64; 6], i: usize| self.mesh_counted.then_some(c[i]);
        Ok(rows
            .iter()
            .map(|c| PipelineStats {
                vertex_invocations: c[0],
                clipping_invocations: c[1],
                clipping_primitives: c[2],
                fragment_invocations: c[3],
                task_invocations: counted(c, 4),
                mesh_invocations: counted(c, 5),
            })
            .collect())
    }
}

impl Drop for QueryPool {
    fn drop(&mut self) {
        // SAFETY: no command buffer in flight uses the pool.
        unsafe { self.device.raw.destroy_query_pool(self.raw, None) };
    }
}
