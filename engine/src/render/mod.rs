//! The renderer: fills the dynamic cube map (by the chosen method: six passes, one pass with
//! layered or multiview rendering, instancing or meshlets) and draws the observer, the sensor
//! and the side-by-side views with the analytic mirror.
//!
//! One frame (see `docs/architecture.md`, "One frame, as passes", and `docs/renderer.md`):
//! 1. evaluate the scene at time t ([`SceneState`]) and decide, by the refresh policy,
//!    whether the cube map must be re-rendered;
//! 2. write the per-frame buffers (views, object transforms);
//! 3. record: the lookup's own work, the cube fill of the dirty faces (skipped for a lookup
//!    that reads no cube) + mip chain, then each view pass (culled draws + the mirror), then
//!    copies of the images to read back;
//! 4. submit; when the frame's slot comes round again (or the caller asks for its results),
//!    wait for its fence and read timestamps, counters and pixels (`in_flight.rs`).

pub mod budget;
pub mod cube_fill;
pub mod dataset;
pub mod display;
mod draw;
pub mod floors;
mod footprint;
pub use footprint::refusal as footprint_refusal;
mod frame;
mod frame_data;
mod frame_parts;
pub mod gpu;
pub mod graph;
mod in_flight;
pub mod lookups;
pub mod material_check;
pub mod methods;
mod mip_pass;
mod mips;
mod mirror;
mod passes;
pub(crate) mod pipelines;
mod queries;
mod readback;
mod refresh;
pub mod resources;
mod retired;
mod scene_draw;
mod sensor_rays;
pub mod snapping;
pub mod targets;

use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use glam::Vec3;

use refresh::Dirty;
use resources::SceneResources;
use targets::{CubeTarget, ViewTargets};

pub use crate::image::RgbaImage;
use crate::scene::camera::ViewBasis;
use crate::scene::state::SceneState;
use crate::scene::{RefreshPolicy, Scene};
use crate::vk::commands::Submitter;
use crate::vk::device::Device;
use crate::vk::memory::{Buffer, BufferDesc};
use crate::vk::pipeline::{GraphicsPipelineDesc, Pipeline, PipelineLayout, ShaderStage};
use crate::vk::GpuError;
pub use frame::{FrameImages, FrameReport, Readback, RefreshCounters, RenderOptions};
pub use in_flight::MAX_FRAMES_IN_FLIGHT;
use queries::*;

/// The side-by-side image of the thesis: observer left, sensor right.
pub const PAIR_SIZE: [u32; 2] = [1200, 450];
/// The observer and sensor cameras draw everything at least this far from the eye (metres),
/// and the mirror whatever its distance ([`camera_clearance`]): their near plane is placed so
/// that its corners are that far (`ViewBasis::near_plane_for`); their far plane is at infinity.
pub const CAMERA_NEAR_M: f32 = 0.05;

/// The face size of the stand-in cube of a renderer whose fixed lookup samples none
/// (`RenderOptions::lookup_fixed`): the bindings need an image, and nothing reads it.
const STAND_IN_FACE_PX: u32 = 1;

/// How far from a camera at `eye` (render space: the mirror's centre at the origin) its view
/// keeps everything: [`CAMERA_NEAR_M`], or half the eye's distance to the mirror's surface when
/// that is less. Every point of the sphere in view is then at least twice the near plane's
/// distance away along the view (a point in the frustum at distance D has depth at least D
/// over the corner rays' stretch, which `near_plane_for` divides by too), so the near plane
/// clips none of it and its fragment depths (reverse-Z: near / depth) stay at most 0.5. A fixed
/// 5 cm would cut a 1 cm mirror seen from 3 cm below (`scenes/hard/close-sensor.toml`). The
/// floor of 1 micrometre only keeps the projection finite for an eye inside the sphere,
/// which the scene loader refuses and the viewer's keys do not reach.
pub fn camera_clearance(eye: Vec3, mirror_radius_m: f32) -> f32 {
    CAMERA_NEAR_M
        .min(0.5 * (eye.length() - mirror_radius_m))
        .max(1e-6)
}

/// Draws one scene. Field order is teardown order (everything holds an `Arc<Device>`).
pub struct Renderer {
    /// The frames in flight: first, so that dropping the renderer waits for them before
    /// anything they use is destroyed.
    frames: in_flight::InFlight,
    /// The benchmark's floor pipelines (made on first `render_floor`).
    floor_pipelines: Option<floors::FloorPipelines>,
    /// The cube fill: the method and its pass (pipeline and per-renderer state).
    cube_fill: cube_fill::CubeFill,
    /// The mirror lookup's pipelines and per-renderer state, and the lookup it is for (the
    /// pass is rebuilt when `scene.mirror.lookup` is switched in place).
    mirror: mirror::Mirror,
    /// The view passes: their targets, pipelines and the sensor ray map's pass.
    views: passes::ViewPasses,
    /// Set 0 (the scene) and the push constants: every scene pipeline's layout, after them.
    scene_layout: PipelineLayout,
    cube: CubeTarget,
    resources: SceneResources,
    /// One-off work: uploads at creation, acceleration-structure builds, the material check.
    submitter: Submitter,
    /// What the cube shows, which faces a frame re-renders, and the counts of both.
    refresh: refresh::Refresh,
    /// The tiles of the cube the views read, and those it holds (`RenderOptions::footprint`).
    footprint: Option<footprint::Footprint>,
    /// This frame's drawables: their render-space bounds and their draw order.
    drawn: draw::DrawOrder,
    /// Whether the first frame's SwiftShader losses were looked for (`snapping`).
    snapping_said: bool,
    /// Whether the cube is a one-texel stand-in (`RenderOptions::lookup_fixed`): no frame
    /// may fill it.
    cube_stand_in: bool,
    pub scene: Scene,
    pub device: Arc<Device>,
}

impl Renderer {
    pub fn new(
        device: &Arc<Device>,
        mut scene: Scene,
        options: &RenderOptions,
    ) -> Result<Self, GpuError> {
        let cube_setting = match options.cube_size {
            Some(size) => {
                scene.cube.face_size_px = size;
                options.cube_size_option.unwrap_or("--cube-size")
            }
            None => "cube.face_size",
        };
        if let Some(policy) = options.refresh {
            scene.refresh = policy;
        }
        if let Some(lookup) = options.lookup {
            scene.mirror.lookup = lookup;
        }
        let cube_stand_in =
            options.lookup_fixed && !lookups::needs_cube(scene.mirror.lookup, options.id_cube);
        if cube_stand_in {
            scene.cube.face_size_px = STAND_IN_FACE_PX;
        }
        let frames_in_flight = options.frames_in_flight.max(1);
        if frames_in_flight > MAX_FRAMES_IN_FLIGHT {
            return Err(GpuError::Unsupported(format!(
                "{frames_in_flight} frames in flight (at most {MAX_FRAMES_IN_FLIGHT})"
            )));
        }
        budget::check_targets(device, &scene, cube_setting, options.id_cube)?;
        let submitter = Submitter::create(device, "frame")?;
        let resources = SceneResources::create(device, &scene, &submitter)?;
        let cube = CubeTarget::create(device, &scene.cube, options.id_cube)?;
        let targets = ViewTargets::create(device, &scene)?;
        if let Some(why) = options.method.missing_features(&device.info) {
            return Err(GpuError::Unsupported(format!(
                "method {}: {why}",
                options.method
            )));
        }
        let (scene_layout, view_pipelines) = pipelines::create_pipelines(device, &resources)?;
        let mirror = mirror::Mirror::create(
            (&scene, device, &resources, &cube, &submitter),
            scene.mirror.lookup,
            (options.trace_order, options.trace_in, options.bvh_layout),
            frames_in_flight,
        )?;
        let fill = options.method.create(&methods::MethodContext {
            device,
            scene: &scene,
            drawables: &resources.drawables,
            vertices: &resources.vertices,
            indices: &resources.indices,
            scene_set_layout: resources.scene_set_layout.raw,
            scene_layout: &scene_layout,
            cube_format: cube.format,
            ids: options.id_cube,
            layout: options.method.layout(),
            submitter: &submitter,
        })?;
        crate::vk::descriptors::write_images(
            device,
            resources.environment_set,
            0,
            &[(cube.cube_view.raw, cube.sampler.raw)],
        );
        let footprint = (options.footprint && !cube_stand_in)
            .then(|| {
                let (size, views) = (cube.size, resources::VIEW_COUNT);
                footprint::Footprint::create(device, (size, views), options.footprint_poison)
            })
            .transpose()?;
        Ok(Self {
            frames: in_flight::InFlight::create(device, frames_in_flight)?,
            floor_pipelines: None,
            cube_fill: cube_fill::CubeFill::new(options.method, fill, options.patching),
            mirror,
            views: passes::ViewPasses::new(targets, view_pipelines),
            scene_layout,
            cube,
            resources,
            submitter,
            refresh: refresh::Refresh::new(options.full_updates, options.whole_faces),
            footprint,
            drawn: draw::DrawOrder::default(),
            snapping_said: false,
            cube_stand_in,
            scene,
            device: Arc::clone(device),
        })
    }

    /// The method that fills the cube.
    pub fn method(&self) -> methods::Method {
        self.cube_fill.method()
    }

    /// Whether the lookup walks its rays in a compute pass before the views
    /// (`lookups::TraceIn::Compute` taken), rather than in the mirror's fragment shaders.
    pub fn pretraced(&self) -> bool {
        self.mirror.pass.pretraces()
    }

    /// How the lookup's trees are laid out, as taken (`RenderOptions::bvh_layout`, else the
    /// device's default); None for a lookup without trees of its own.
    pub fn bvh_layout(&self) -> Option<crate::bvh::BvhLayout> {
        self.mirror.pass.bvh_layout()
    }

    /// How many frames updated the cube, skipped it, and the faces rendered, so far.
    pub fn counters(&self) -> RefreshCounters {
        self.refresh.counters
    }

    /// Renders frame `frame` at scene time `t_s`, waits for it and reads back what
    /// `readback` asks for. Frames submitted before it (by [`Self::submit_frame`]) are
    /// finished too; their results stay queued for [`Self::finish_frame`].
    pub fn render_frame(
        &mut self,
        frame: u64,
        t_s: f64,
        readback: Readback,
    ) -> Result<(FrameReport, FrameImages), GpuError> {
        self.render_asked(FrameAsk::new(frame, t_s, readback))
    }

    /// Submits the frame `ask` asks for and waits for it (and every frame before it).
    fn render_asked(&mut self, ask: FrameAsk) -> Result<(FrameReport, FrameImages), GpuError> {
        self.submit(ask)?;
        self.drain()?;
        Ok(self
            .frames
            .take_newest()
            .expect("the frame just submitted was finished by drain"))
    }

    /// Records and submits the frame `ask` asks for: the one entry point of every frame the
    /// renderer renders (a frame read back, a window's view, a benchmark's floor). It does
    /// not wait for the GPU; its results come from the frames' queue.
    fn submit(&mut self, ask: FrameAsk) -> Result<(), GpuError> {
        let record_start = Instant::now();
        // Asked before anything is recorded, and again below once the frame follows a switch
        // of lookup (the ray map's ground truth is the pass's, which the switch replaces).
        let fills = ask.floor().is_some() || self.fills_cube(ask.readback);
        if fills && self.cube_stand_in {
            return Err(GpuError::Unsupported(format!(
                "a frame that fills the cube map, from a renderer made without one (its \
                 lookup was fixed, {}, which samples none: RenderOptions::lookup_fixed)",
                self.scene.mirror.lookup
            )));
        }
        self.acquire_slot()?;
        self.follow_lookup()?;
        let state = SceneState::at(&self.scene, ask.t_s);
        let (views, cpu_lookup_ms) = self.write_frame_buffers(&state)?;
        let floor = ask.floor();
        let fill_cube = floor.is_some() || self.fills_cube(ask.readback);
        self.say_snapping_losses(&state, &ask, fill_cube);
        if ask.readback.rays {
            self.prepare_sensor_rays()?;
        }
        let footprint_ms = match (floor, fill_cube) {
            (None, true) => self.mark_footprint(&state, &ask)?,
            _ => 0.0,
        };
        let (dirty, patching) = match (floor, fill_cube) {
            // A floor stands in for a full update: every face, whole.
            (Some(_), _) => (Dirty::faces(0x3F), Default::default()),
            (None, true) => (
                self.faces_to_fill(ask.frame, &state, &views),
                self.cube_fill.patching(),
            ),
            (None, false) => (Dirty::default(), self.cube_fill.patching()),
        };
        let plan = (self.frame_parts()).plan_cube(&views, dirty, patching);
        let dirty = plan.dirty;
        if floor.is_none() {
            self.prepare_fill(&plan)?;
        }
        let copies = self.plan_copies(ask.readback, ask.display);
        self.grow_readback(&copies)?;
        let mut report = FrameReport {
            frame: ask.frame,
            time_s: ask.t_s,
            cube_updated: dirty != 0,
            // A floor's frame times the fill alone: the lookup's host work is not its.
            cpu_lookup_ms: if floor.is_some() { 0.0 } else { cpu_lookup_ms },
            cpu_footprint_ms: self.footprint_texels().map(|_| footprint_ms),
            footprint_texels: self
                .footprint_texels()
                .filter(|_| fill_cube && floor.is_none()),
            ..Default::default()
        };
        let mut graph = self.frame_graph();
        let cmd = self.begin_frame(&mut graph)?;
        let graph = self.record_frame((cmd, graph), &plan, &views, &ask, &copies, &mut report);
        // A floor's statistics are its one query's, whatever the method.
        let per_face = floor.is_none() && self.cube_fill.per_face_marks();
        let views_read = StatsRead::views_drawn(ask.readback, ask.display.is_some());
        let stats = StatsRead::of(
            dirty != 0,
            per_face,
            u32::from(report.face_mask),
            views_read,
        );
        self.end_frame((cmd, graph), record_start, &mut report, stats);
        // The cube shows `state` once this frame has run (later frames run after it), except
        // after an `every-n` frame that skipped the update, and after a floor, which leaves
        // no picture in it.
        if floor.is_some() {
            self.refresh.shows(None);
        } else if dirty != 0 || (fill_cube && self.scene.refresh == RefreshPolicy::OnChange) {
            self.refresh.shows(Some(state));
        }
        self.submit_slot(in_flight::Pending {
            report,
            copies,
            stats,
            per_face,
            traced: floor.is_none(),
            submitted: Instant::now(),
            number: 0,
        })
    }

    /// The mirror's pass follows the scene's lookup, switched in place. Nothing waits: the old
    /// pass, and the ray map's pass made for it, are kept until the frames in flight that
    /// may use them have finished (`retired.rs`).
    fn follow_lookup(&mut self) -> Result<(), GpuError> {
        let in_flight = self.frames.last_in_flight();
        if self.mirror.lookup() != self.scene.mirror.lookup {
            // The ray map's pass was chosen for the old lookup (and, traced, read its set):
            // made again for the new one on the next frame that reads them.
            if let Some(rays) = self.views.sensor_rays.take() {
                self.frames.retire(Box::new(rays));
            }
        }
        self.mirror.follow(
            (
                &self.scene,
                &self.device,
                &self.resources,
                &self.cube,
                &self.submitter,
            ),
            self.scene.mirror.lookup,
            in_flight,
        )
    }

    /// Whether this frame fills the cube. A lookup that does not read it (ray-query) skips
    /// its fill, unless the cube itself or a ray map that reads its depth and ids is read
    /// back; the cube then keeps what it last showed.
    fn fills_cube(&self, readback: Readback) -> bool {
        let rays_read_cube =
            readback.rays && self.sensor_ground_truth() == crate::sensor::GroundTruth::Cube;
        // The scene's lookup, which the mirror's pass follows (`follow_lookup`): asked before
        // the frame follows a switch too.
        lookups::plugin(self.scene.mirror.lookup).uses_cube() || readback.cube || rays_read_cube
    }

    /// What this frame re-renders (the refresh policy's choice), counted.
    fn faces_to_fill(&mut self, frame: u64, state: &SceneState, views: &[ViewBasis]) -> Dirty {
        let drawables = &self.resources.drawables;
        let at = (frame, self.cube.size);
        let mut dirty = (self.refresh).dirty(&self.scene, drawables, at, state, views);
        dirty = self.within_footprint(dirty);
        if self.method().layout() == methods::CubeLayout::Multiview {
            // A multiview pass clears and draws every view alike: the same rectangles in all
            // six, each face culled for them, or objects seen only there would vanish.
            dirty = dirty.in_every_face(self.cube.size);
        }
        self.refresh.count(dirty.mask);
        dirty
    }

    /// The method's per-update data for `plan` (nothing without an update).
    fn prepare_fill(&mut self, plan: &methods::CubePlan) -> Result<(), GpuError> {
        if plan.dirty == 0 {
            return Ok(());
        }
        let cull_back = self.frame_parts().cube_facing().cull;
        let mut prepare = methods::Prepare {
            device: &self.device,
            drawables: &self.resources.drawables,
            cull_back: &cull_back,
            uploads: &mut self.frames.current_mut().uploads,
        };
        self.cube_fill.prepare(plan, &mut prepare)
    }

    /// Records the frame's work between its start and its end: the lookup's own, the cube
    /// update (or its timestamps alone), the views, the readback `copies`.
    fn record_frame(
        &self,
        (cmd, mut graph): (vk::CommandBuffer, graph::FrameGraph),
        plan: &methods::CubePlan,
        views: &[ViewBasis],
        ask: &FrameAsk,
        copies: &readback::Copies,
        report: &mut FrameReport,
    ) -> graph::FrameGraph {
        let frame = self.frame_parts();
        let floor = ask.floor();
        // The lookup's own work (the ray-query TLAS build) comes first: without a cube update
        // it is all that lies between the start and fill timestamps (`gpu_fill_ms`). A
        // floor's frame has none: it times the fill alone.
        if floor.is_none() {
            frame
                .lookup
                .record(&mut graph::PassRecorder::new(&self.device, cmd, &mut graph));
        }
        if plan.dirty != 0 {
            if floor.is_none() {
                self.record_poison(&mut graph, cmd);
            }
            let graph = (&frame, &mut graph);
            match floor {
                None => (self.cube_fill).record(graph, cmd, plan, report, cube_fill::Fill::Method),
                Some(f) => {
                    let record = |rec: &methods::CubeRecorder<'_>, plan: &methods::CubePlan| {
                        self.record_floor(rec, plan, f)
                    };
                    let fill = cube_fill::Fill::Other {
                        name: f.name(),
                        record: &record,
                    };
                    (self.cube_fill).record(graph, cmd, plan, report, fill);
                }
            }
        } else if let Some(q) = &frame.queries.timestamps {
            for ts in TS_FACE0..=TS_MIPS {
                q.write_timestamp(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, ts);
            }
        }
        // With nothing asked of them (a floor's), the views keep the timestamps answered.
        let shown = (ask.readback, ask.display);
        (self.views).record((&frame, &mut graph), cmd, views, shown);
        if floor.is_none() {
            let mut pass = graph::PassRecorder::new(&self.device, cmd, &mut graph);
            (frame.lookup).record_after_views(&mut pass, self.frames.current_index());
        }
        self.record_readback(&mut graph, cmd, copies);
        graph
    }

    /// The frame graph, with every resource the frame's passes may use at rest (the uploads'
    /// destinations are imported by `begin_frame`): the lookup's own buffers, the cube's
    /// images (fresh before its first fill), the view targets, the slot's readback buffer and
    /// its queries' result buffers.
    fn frame_graph(&self) -> graph::FrameGraph {
        let mut graph = graph::FrameGraph::default();
        for (resource, rest) in self.mirror.pass.resources(self.frames.current_index()) {
            graph.import(resource, rest, false);
        }
        let fresh = self.refresh.first_fill();
        for (resource, rest) in self.cube.resources() {
            graph.import(resource, rest, fresh);
        }
        for (resource, rest) in self.views.every_resource() {
            graph.import(resource, rest, false);
        }
        if let Some(buffer) = &self.frames.current().readback {
            let buffer = graph::Resource::Buffer(buffer.raw);
            graph.import(buffer, graph::Use::HostRead, false);
        }
        for buffer in self.queries().result_buffers() {
            graph.import(graph::Resource::Buffer(buffer), graph::Use::HostRead, false);
        }
        graph
    }

    /// The current frame's queries (per frame in flight: a slot's are read after its fence).
    fn queries(&self) -> &FrameQueries {
        &self.frames.current().queries
    }

    /// Starts recording a frame in the current slot (acquired: its last frame finished): the
    /// frame's uploads copied (after the last frame's reads of their buffers, before any of
    /// this frame's, whatever reads them), queries reset, the start timestamp written.
    fn begin_frame(
        &mut self,
        graph: &mut graph::FrameGraph,
    ) -> Result<vk::CommandBuffer, GpuError> {
        let device = Arc::clone(&self.device);
        let slot = self.frames.current_mut();
        let cmd = slot.submitter.begin()?;
        let copied: Vec<_> = (slot.uploads.destinations().into_iter())
            .map(graph::Resource::Buffer)
            .collect();
        for &buffer in &copied {
            // At rest between frames as read by any command.
            graph.import(buffer, graph::Use::ReadAnywhere, false);
        }
        let uses = |how| copied.iter().map(|&b| (b, how)).collect::<Vec<_>>();
        graph.declare(&device, cmd, &uses(graph::Use::CopyDestination));
        slot.uploads.record_copies(cmd)?;
        graph.declare(&device, cmd, &uses(graph::Use::ReadAnywhere));
        slot.queries.begin_frame(cmd);
        Ok(cmd)
    }

    /// Ends a frame begun by [`Self::begin_frame`] with its last timestamp and the copy of
    /// the query results it reads (`stats`), then the barriers that leave every resource of
    /// its `graph` at rest (the results visible to the host among them); the CPU recording
    /// time (since `record_start`) goes in `report`.
    fn end_frame(
        &self,
        (cmd, mut graph): (vk::CommandBuffer, graph::FrameGraph),
        record_start: Instant,
        report: &mut FrameReport,
        stats: StatsRead,
    ) {
        let queries = self.queries();
        if let Some(q) = &queries.timestamps {
            q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, TS_READBACK);
        }
        let results = queries.result_buffers().map(graph::Resource::Buffer);
        let uses: Vec<_> = results.map(|r| (r, graph::Use::CopyDestination)).collect();
        graph.declare(&self.device, cmd, &uses);
        queries.copy_results(cmd, stats);
        graph.rest(&self.device, cmd);
        report.cpu_record_ms = record_start.elapsed().as_secs_f64() * 1e3;
    }
}

/// What one frame is asked for: its number and scene time, what it reads back, the one view
/// a window shows (then nothing else is drawn or read back), and what fills its cube.
#[derive(Debug, Clone, Copy)]
pub(super) struct FrameAsk {
    pub frame: u64,
    pub t_s: f64,
    pub readback: Readback,
    pub display: Option<display::DisplayView>,
    pub cube: CubeWork,
}

/// What fills a frame's cube: the method, as the refresh policy asks; or a floor of its cost
/// in its place over every face (`render_floor`).
#[derive(Debug, Clone, Copy)]
pub(super) enum CubeWork {
    Method,
    Floor(floors::Floor),
}

impl FrameAsk {
    /// A frame filled by the method, no view shown in a window.
    pub fn new(frame: u64, t_s: f64, readback: Readback) -> Self {
        Self {
            frame,
            t_s,
            readback,
            display: None,
            cube: CubeWork::Method,
        }
    }

    fn floor(&self) -> Option<floors::Floor> {
        match self.cube {
            CubeWork::Method => None,
            CubeWork::Floor(f) => Some(f),
        }
    }
}
