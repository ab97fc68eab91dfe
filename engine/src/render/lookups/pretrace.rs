//! A pretraced lookup's compute walk (`shaders/include/pretrace.glsl` says why): each camera
//! view's reflections traced once a frame by `trace_view.comp` into one record a pixel, which
//! the mirror's colour, direction and ray-map passes then read instead of walking. Where it
//! runs is the device's choice ([`TraceIn`]); the images are the same either way.

use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::LookupContext;
use crate::render::gpu::Push;
use crate::render::graph::{PassRecorder, Resource, Use};
use crate::render::resources::{VIEW_OBSERVER, VIEW_PAIR_LEFT, VIEW_PAIR_RIGHT, VIEW_SENSOR};
use crate::render::PAIR_SIZE;
use crate::shaders::shared::{TRACED_PIXEL_BYTES, TRACE_GROUP_SIDE};
use crate::vk::device::{Device, DeviceInfo};
use crate::vk::memory::{Buffer, BufferDesc};
use crate::vk::physical::DeviceLimits;
use crate::vk::pipeline::{Pipeline, PipelineLayout};
use crate::vk::GpuError;

/// Where a tracing lookup walks its rays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TraceIn {
    /// In the mirror's fragment shaders, every pass that draws it.
    Fragment,
    /// In a compute pass before a view is drawn, once for all its passes.
    Compute,
}

impl TraceIn {
    pub const ALL: [Self; 2] = [Self::Fragment, Self::Compute];

    pub fn name(self) -> &'static str {
        match self {
            Self::Fragment => "fragment",
            Self::Compute => "compute",
        }
    }

    pub fn parse(text: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == text)
    }

    /// The device's default: a compute pass on a GPU (on the H200 many-objects' sensor view
    /// took 0.56 ms so, 5.7 in the fragment shaders, docs/gpu.md); the fragment shaders on a
    /// CPU driver, where the compute pass measured 1.1x to 1.7x their walk (it walks the view's
    /// whole rectangle; the rasterizer runs the fragment shader on the mirror's pixels alone).
    pub fn default_for(device: &DeviceInfo) -> Self {
        if device.is_cpu() {
            Self::Fragment
        } else {
            Self::Compute
        }
    }
}

/// The camera views' pixels, in the records' order (`pretrace.glsl`'s `traced_index`).
fn camera_view_pixels(scene: &crate::scene::Scene) -> [(u32, u64); 4] {
    let pixels = |[w, h]: [u32; 2]| u64::from(w) * u64::from(h);
    let half = [PAIR_SIZE[0] / 2, PAIR_SIZE[1]];
    [
        (VIEW_OBSERVER, pixels(scene.observer.resolution)),
        (VIEW_SENSOR, pixels(scene.sensor.resolution)),
        (VIEW_PAIR_LEFT, pixels(half)),
        (VIEW_PAIR_RIGHT, pixels(half)),
    ]
}

/// The records and the pass that fills them. Field order is drop order.
pub struct Pretrace {
    pipeline: Pipeline,
    layout: PipelineLayout,
    /// Each view's size in pixels, for its dispatch.
    sizes: [[u32; 2]; 4],
    device: Arc<Device>,
}

/// The records' buffer: one record a camera-view pixel where the lookup pretraces, else one
/// record (the binding is in the lookup's set either way; nothing reads it then).
pub fn records(ctx: &LookupContext<'_>, pretraced: bool) -> Result<Buffer, GpuError> {
    let pixels: u64 = if pretraced {
        camera_view_pixels(ctx.scene).iter().map(|v| v.1).sum()
    } else {
        1
    };
    let size = pixels * u64::from(TRACED_PIXEL_BYTES);
    check_fits(size, &ctx.device.info.limits)?;
    let desc = BufferDesc {
        size,
        usage: vk::BufferUsageFlags::STORAGE_BUFFER,
        location: MemoryLocation::GpuOnly,
    };
    Buffer::create(ctx.device, &desc, "pretraced records")
}

/// One buffer, one descriptor: both must hold the records (views at the loader's 8192² need
/// 4.3 GB, past a 32-bit storage range and lavapipe's 2 GiB allocations).
fn check_fits(size: u64, limits: &DeviceLimits) -> Result<(), GpuError> {
    let range = Some(limits.max_storage_buffer_range).filter(|&r| r > 0);
    let allocation = limits.max_memory_allocation_bytes;
    let limit = range.map_or(allocation, |r| r.min(allocation));
    if size <= limit {
        return Ok(());
    }
    Err(GpuError::Unsupported(format!(
        "the compute walk keeps {TRACED_PIXEL_BYTES} bytes a pixel of the observer, the sensor \
         and the two-view image: {} in one buffer, more than this device's {} (its storage \
         range or allocation limit); lower observer.resolution or sensor.resolution, or walk \
         in the fragment shaders (--trace-in fragment)",
        crate::render::budget::bytes_text(size),
        crate::render::budget::bytes_text(limit)
    )))
}

impl Pretrace {
    /// The pass over the scene set and the lookup's `set_layout`, running `shader`.
    pub fn create(
        ctx: &LookupContext<'_>,
        set_layout: vk::DescriptorSetLayout,
        shader: &[u32],
    ) -> Result<Self, GpuError> {
        let layout = PipelineLayout::create_compute(
            ctx.device,
            &[ctx.resources.scene_set_layout.raw, set_layout],
            ctx.push_size,
            "pretrace layout",
        )?;
        let pipeline = Pipeline::create_compute(ctx.device, &layout, shader, "pretrace")?;
        let s = ctx.scene;
        let half = [PAIR_SIZE[0] / 2, PAIR_SIZE[1]];
        Ok(Self {
            pipeline,
            layout,
            sizes: [s.observer.resolution, s.sensor.resolution, half, half],
            device: Arc::clone(ctx.device),
        })
    }

    /// Traces camera view `view` into its records: their write declared first (after the
    /// last frame's reads), the view passes' read after.
    pub fn record(
        &self,
        pass: &mut PassRecorder<'_>,
        records: &Buffer,
        sets: [vk::DescriptorSet; 2],
        view: u32,
    ) {
        let [w, h] = self.sizes[(view - VIEW_OBSERVER) as usize];
        let buffer = Resource::Buffer(records.raw);
        pass.declare(&[(buffer, Use::ComputeWrite)]);
        let (d, cmd) = (&self.device.raw, pass.cmd());
        let push = Push {
            view_index: view,
            ..Push::default()
        };
        // SAFETY: cmd is recording outside any rendering; the pipeline, its layout and both
        // sets live as long as the renderer; the push range is the layout's.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline.raw);
            let point = vk::PipelineBindPoint::COMPUTE;
            d.cmd_bind_descriptor_sets(cmd, point, self.layout.raw, 0, &sets, &[]);
            let stages = vk::ShaderStageFlags::COMPUTE;
            let bytes = bytemuck::bytes_of(&push);
            d.cmd_push_constants(cmd, self.layout.raw, stages, 0, bytes);
            let side = TRACE_GROUP_SIDE;
            d.cmd_dispatch(cmd, w.div_ceil(side), h.div_ceil(side), 1);
        }
        pass.declare(&[(buffer, Use::FragmentStorageRead)]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_records_follow_the_views_and_the_shaders_constants() {
        assert_eq!(VIEW_OBSERVER, crate::shaders::shared::FIRST_CAMERA_VIEW);
        assert_eq!(
            [VIEW_OBSERVER, VIEW_SENSOR, VIEW_PAIR_LEFT, VIEW_PAIR_RIGHT],
            std::array::from_fn(|i| VIEW_OBSERVER + i as u32)
        );
        assert_eq!(crate::shaders::shared::CAMERA_VIEWS, 4);
        for name in ["fragment", "compute"] {
            assert_eq!(TraceIn::parse(name).map(TraceIn::name), Some(name));
        }
    }

    /// The records fit the smaller of the storage range and the allocation limit, or the
    /// refusal says how to do without them.
    #[test]
    fn records_past_the_devices_limits_are_refused() {
        let baseline = include_str!("../../../../bench/baselines/quick.json");
        let record: serde_json::Value = serde_json::from_str(baseline).unwrap();
        let mut limits: DeviceLimits =
            serde_json::from_value(record["device"]["limits"].clone()).unwrap();
        assert_eq!(
            limits.max_storage_buffer_range, 0,
            "an older record: unknown"
        );
        limits.max_memory_allocation_bytes = 2 << 30;
        assert!(check_fits(2 << 30, &limits).is_ok());
        assert!(check_fits((2 << 30) + 1, &limits).is_err());
        limits.max_storage_buffer_range = (1 << 32) - 1;
        limits.max_memory_allocation_bytes = 1 << 40;
        let e = check_fits(4_310_000_000, &limits).unwrap_err().to_string();
        assert!(
            e.contains("--trace-in fragment") && e.contains("sensor.resolution"),
            "{e}"
        );
        assert!(check_fits((1 << 32) - 1, &limits).is_ok());
    }
}
