//! Command recording for one frame's views (observer, sensor, pair, and the direction and
//! ray-map pass); the readback is in `readback.rs`, the pipelines in `pipelines.rs`.

use ash::vk;

use super::draw::Attachments;
use super::frame_parts::FrameParts;
use super::gpu::Push;
use super::graph::{FrameGraph, Resource, Use};
use super::pipelines::ViewPipelines;
use super::resources::{VIEW_OBSERVER, VIEW_PAIR_LEFT, VIEW_PAIR_RIGHT, VIEW_SENSOR};
use super::sensor_rays::{MirrorOutput, RayMapTargets, SensorRays};
use super::targets::ViewTarget;
use super::*;
use crate::scene::camera::{Frustum, ViewBasis};

/// The view images a frame can read back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Slot {
    Observer,
    Sensor,
    Pair,
    ObserverDirection,
    SensorDirection,
}

/// Where a view's copy into the readback buffer may start, at or after `offset`: a multiple of
/// 16 bytes, the largest texel here and a multiple of every other (Vulkan wants a copy's
/// buffer offset to be a multiple of its format's texel size; an odd-sized 8-byte image before
/// a 16-byte one would break that).
pub(super) fn copy_offset(offset: u64) -> u64 {
    offset.next_multiple_of(16)
}

/// Bytes per texel of a view target's colour format.
pub(super) fn texel_bytes(slot: Slot) -> u64 {
    match slot {
        Slot::ObserverDirection | Slot::SensorDirection => 16,
        _ => 8,
    }
}

/// The view passes, a part of the renderer: the view targets, the scene pipelines that draw
/// into them, and the sensor ray map's pass. They record with the frame's context
/// ([`FrameParts`]) and own nothing else.
pub(super) struct ViewPasses {
    /// The sensor ray map's pass and its targets (a quantity each), made on first use.
    pub sensor_rays: Option<(SensorRays, RayMapTargets)>,
    pipelines: ViewPipelines,
    /// Observer, sensor, pair, and the two direction images.
    pub targets: ViewTargets,
}

impl ViewPasses {
    pub fn new(targets: ViewTargets, pipelines: ViewPipelines) -> Self {
        Self {
            sensor_rays: None,
            pipelines,
            targets,
        }
    }

    /// Observer, sensor and the side-by-side pair, each: culled scene draws, then the mirror.
    /// The view targets `readback` asks for, in readback order.
    pub fn slots(&self, readback: Readback) -> Vec<(Slot, &ViewTarget)> {
        let mut slots = Vec::new();
        if readback.views {
            slots.push((Slot::Observer, &self.targets.observer));
            slots.push((Slot::Sensor, &self.targets.sensor));
            slots.push((Slot::Pair, &self.targets.pair));
        } else if readback.sensor {
            slots.push((Slot::Sensor, &self.targets.sensor));
        }
        if readback.directions {
            slots.push((Slot::ObserverDirection, &self.targets.observer_directions));
            slots.push((Slot::SensorDirection, &self.targets.sensor_directions));
        }
        slots
    }

    /// The views (`ViewData` indices) the frame that asks for `readback`, or shows `display`,
    /// draws the scene in: its passes' views, and the sensor's for the ray map.
    pub fn drawn_views(
        &self,
        readback: Readback,
        display: Option<super::display::DisplayView>,
    ) -> Vec<u32> {
        let slots = match display {
            Some(view) => vec![self.display_slot(view)],
            None => self.slots(readback),
        };
        let mut views: Vec<u32> = (slots.iter())
            .flat_map(|(slot, _)| pass_of(*slot).views.iter().copied())
            .collect();
        if readback.rays {
            views.push(VIEW_SENSOR);
        }
        views.sort_unstable();
        views.dedup();
        views
    }

    /// The ray map's targets, when `readback` asks for the ray map.
    pub fn ray_map(&self, readback: Readback) -> Option<&RayMapTargets> {
        (self.sensor_rays.as_ref())
            .filter(|_| readback.rays)
            .map(|(_, targets)| targets)
    }

    /// Every view target's images there are, with how each rests between frames, for the
    /// frame graph to track.
    pub fn every_resource(&self) -> Vec<(Resource, Use)> {
        let t = &self.targets;
        let views = [&t.observer, &t.sensor, &t.pair]
            .into_iter()
            .chain([&t.observer_directions, &t.sensor_directions]);
        let rays = self.sensor_rays.iter().flat_map(|(_, t)| t.resources());
        views.flat_map(|t| t.resources()).chain(rays).collect()
    }

    /// Observer, sensor and the side-by-side pair (culled scene draws, then the mirror), with
    /// `readback.directions` the lookup-direction passes of observer and sensor, and with
    /// `readback.rays` the ray map's. With `display`, only that view is drawn (the viewer's
    /// frame). What is read back of them is the readback's (`readback.rs`, `Copies`).
    pub fn record(
        &self,
        (f, graph): (&FrameParts, &mut FrameGraph),
        cmd: vk::CommandBuffer,
        views: &[ViewBasis],
        (readback, display): (Readback, Option<super::display::DisplayView>),
    ) {
        let slots = match display {
            Some(view) => vec![self.display_slot(view)],
            None => self.slots(readback),
        };
        let (before, after) = undrawn_timestamps(&slots);
        mark(f, cmd, &before);
        let p = &self.pipelines;
        // The camera views a pretraced lookup has traced this frame (bit v - VIEW_OBSERVER).
        let mut traced = 0u32;
        for (slot, target) in slots {
            let pass = pass_of(slot);
            pretrace((f, &mut *graph), cmd, pass.views, &mut traced);
            let scene = match pass.output {
                MirrorOutput::Colour => &p.colour,
                _ => &p.depth_only,
            };
            let drawn = (target.drawn().to_vec(), view_attachments(target));
            let stats = pass.statistics;
            let pass_views = (pass.views, views);
            let how = (scene, pass.output);
            self.record_view(
                (f, &mut *graph),
                cmd,
                drawn,
                pass_views,
                how,
                stats,
                pass.name,
            );
            if let (Some(q), Some(ts)) = (&f.queries.timestamps, pass.timestamp) {
                q.write_timestamp(cmd, vk::PipelineStageFlags2::ALL_GRAPHICS, ts);
            }
        }
        if display.is_none() {
            self.record_ray_map((f, &mut *graph), cmd, views, readback, &mut traced);
        }
        mark(f, cmd, &after);
    }

    /// The ray map's pass over the sensor view, when `readback` asks for it: the scene's depth,
    /// then the mirror writing every quantity to its attachment (`sensor_rays.rs`).
    fn record_ray_map(
        &self,
        (f, graph): (&FrameParts, &mut FrameGraph),
        cmd: vk::CommandBuffer,
        views: &[ViewBasis],
        readback: Readback,
        traced: &mut u32,
    ) {
        let (Some((rays, _)), Some(targets)) = (&self.sensor_rays, self.ray_map(readback)) else {
            return;
        };
        pretrace((f, &mut *graph), cmd, &[VIEW_SENSOR], traced);
        let drawn = (targets.drawn(), targets.attachments());
        let how = (&rays.scene_depth, MirrorOutput::RayMap);
        let pass_views = (&[VIEW_SENSOR][..], views);
        self.record_view((f, graph), cmd, drawn, pass_views, how, None, "ray map");
    }

    /// Records one view pass: the barriers its `uses` need, then into `attachments` each of
    /// `view_ids`' views drawn (culled scene draws, then the mirror), inside `stats_slot`'s
    /// statistics query.
    #[allow(clippy::too_many_arguments)]
    fn record_view(
        &self,
        (f, graph): (&FrameParts, &mut FrameGraph),
        cmd: vk::CommandBuffer,
        (uses, attachments): (Vec<(Resource, Use)>, Attachments),
        (view_ids, views): (&[u32], &[ViewBasis]),
        (scene_pipeline, output): (&Pipeline, MirrorOutput),
        stats_slot: Option<u32>,
        name: &str,
    ) {
        let dev = f.draw.device;
        dev.begin_label(cmd, name);
        graph.declare(dev, cmd, &uses);
        if let (Some(q), Some(slot)) = (&f.queries.statistics, stats_slot) {
            q.begin(cmd, slot);
        }
        f.draw.begin_rendering(cmd, &attachments);
        for &v in view_ids {
            let size = attachments.size;
            self.draw_view(f, cmd, size, v, views, (scene_pipeline, output));
        }
        f.draw.end_rendering(cmd);
        if let (Some(q), Some(slot)) = (&f.queries.statistics, stats_slot) {
            q.end(cmd, slot);
        }
        dev.end_label(cmd);
    }

    /// Draws view `v` into its viewport of a target of `size`: the scene objects its frustum
    /// sees, then the mirror.
    fn draw_view(
        &self,
        f: &FrameParts,
        cmd: vk::CommandBuffer,
        size: [u32; 2],
        v: u32,
        views: &[ViewBasis],
        (scene_pipeline, output): (&Pipeline, MirrorOutput),
    ) {
        let vp = viewport(size, v);
        f.draw.set_viewport(cmd, vp[0], vp[1], vp[2], vp[3]);
        let view = &views[v as usize];
        let clearance = camera_clearance(view.eye, f.scene.mirror.radius_m);
        let frustum = Frustum::new(view, view.near_plane_for(clearance), f32::INFINITY);
        let visible = f.visible(&frustum);
        let push = Push {
            view_index: v,
            ..Push::default()
        };
        let facing = f.view_facing(view);
        f.draw
            .draw_objects(cmd, scene_pipeline, push, &visible, &facing);
        self.draw_mirror(f, cmd, output, v);
    }

    /// Draws the mirror's bounding cube with the lookup's colour or direction pipeline, or
    /// the sensor ray map's (which traces, or reads the cube's depth and ids).
    fn draw_mirror(&self, f: &FrameParts, cmd: vk::CommandBuffer, output: MirrorOutput, view: u32) {
        let d = &f.draw.device.raw;
        let lookup = f.lookup;
        let (pipeline, layout, sets) = match output {
            MirrorOutput::Colour | MirrorOutput::LookupDirection => (
                lookup.pipeline(output == MirrorOutput::LookupDirection).raw,
                lookup.layout().raw,
                vec![f.draw.resources.scene_set, lookup.set()],
            ),
            MirrorOutput::RayMap => {
                let (rays, _) = self
                    .sensor_rays
                    .as_ref()
                    .expect("the ray map's pass is drawn only when it was made");
                (
                    rays.pipeline.raw,
                    rays.layout.raw,
                    vec![f.draw.resources.scene_set, rays.set],
                )
            }
        };
        // SAFETY: recording inside a view pass; what set 1 holds is ready for reading (the
        // cube's colour, depth and ids in SHADER_READ_ONLY layout, or the lookup's own data
        // after its barrier).
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
            d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, layout, 0, &sets, &[]);
        }
        f.draw.push(
            cmd,
            layout,
            Push {
                view_index: view,
                ..Push::default()
            },
        );
        // SAFETY: as above; 36 vertices generated by mirror.vert.
        unsafe { d.cmd_draw(cmd, 36, 1, 0, 0) };
    }

    /// The slot and target of a view drawn for a window.
    pub fn display_slot(&self, view: super::display::DisplayView) -> (Slot, &ViewTarget) {
        use super::display::DisplayView;
        match view {
            DisplayView::Pair => (Slot::Pair, &self.targets.pair),
            DisplayView::Observer => (Slot::Observer, &self.targets.observer),
            DisplayView::Sensor => (Slot::Sensor, &self.targets.sensor),
        }
    }
}

/// Writes the timestamps `stamps` of views not drawn.
fn mark(f: &FrameParts, cmd: vk::CommandBuffer, stamps: &[u32]) {
    if let Some(q) = &f.queries.timestamps {
        for &ts in stamps {
            q.write_timestamp(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, ts);
        }
    }
}

/// `target`'s colour and depth as one cleared layer; the depth is not kept.
fn view_attachments(target: &ViewTarget) -> Attachments {
    Attachments {
        color: target.color_view.raw,
        ids: None,
        more_colors: Vec::new(),
        depth: target.depth_view.raw,
        size: [target.width, target.height],
        layers: 1,
        view_mask: 0,
        clear: true,
        store_depth: false,
    }
}

/// View `v`'s viewport in a target of `size` (x, y, width, height): its half of the pair
/// image, or all of its own image.
fn viewport([width, height]: [u32; 2], v: u32) -> [f32; 4] {
    let half = (PAIR_SIZE[0] / 2) as f32;
    match v {
        VIEW_PAIR_LEFT => [0.0, 0.0, half, PAIR_SIZE[1] as f32],
        VIEW_PAIR_RIGHT => [half, 0.0, half, PAIR_SIZE[1] as f32],
        _ => [0.0, 0.0, width as f32, height as f32],
    }
}

/// A pretraced lookup's walk of each of `views` the frame has not traced yet (`traced`, bit
/// v - VIEW_OBSERVER), recorded before the first pass that draws it: the passes after it read
/// its records (`shaders/include/pretrace.glsl`), so a view's rays are walked once a frame.
fn pretrace(
    (f, graph): (&FrameParts, &mut FrameGraph),
    cmd: vk::CommandBuffer,
    views: &[u32],
    traced: &mut u32,
) {
    if !f.lookup.pretraces() {
        return;
    }
    for &v in views {
        let bit = 1 << (v - VIEW_OBSERVER);
        if *traced & bit == 0 {
            *traced |= bit;
            let mut pass = super::graph::PassRecorder::new(f.draw.device, cmd, graph);
            f.lookup.pretrace(&mut pass, f.draw.resources.scene_set, v);
        }
    }
}

/// A colour view that is not drawn still gets its timestamp, so every query has a result:
/// those before the first drawn view in slot order are written first, the others after the
/// drawn views, so the drawn view's time is its own. The two lists, in that order.
fn undrawn_timestamps(slots: &[(Slot, &ViewTarget)]) -> (Vec<u32>, Vec<u32>) {
    let colour = [
        (Slot::Observer, TS_OBSERVER),
        (Slot::Sensor, TS_SENSOR),
        (Slot::Pair, TS_PAIR),
    ];
    let drawn = |s: Slot| slots.iter().any(|&(d, _)| d == s);
    let first = (colour.iter().position(|&(s, _)| drawn(s))).unwrap_or(colour.len());
    let undrawn = |range: std::ops::Range<usize>| {
        (colour[range].iter())
            .filter(|&&(s, _)| !drawn(s))
            .map(|&(_, ts)| ts)
            .collect::<Vec<u32>>()
    };
    (undrawn(0..first), undrawn(first..colour.len()))
}

/// How one view image is drawn: the views it covers, its timestamp and statistics query
/// (colour views only), what the mirror writes, and its label.
struct ViewPass {
    views: &'static [u32],
    timestamp: Option<u32>,
    statistics: Option<u32>,
    output: MirrorOutput,
    name: &'static str,
}

/// The table of the view images.
fn pass_of(slot: Slot) -> ViewPass {
    use MirrorOutput::*;
    let pass = |views, timestamp, statistics, output, name| ViewPass {
        views,
        timestamp,
        statistics,
        output,
        name,
    };
    let pair: &'static [u32] = &[VIEW_PAIR_LEFT, VIEW_PAIR_RIGHT];
    match slot {
        Slot::Observer => pass(
            &[VIEW_OBSERVER],
            Some(TS_OBSERVER),
            Some(6),
            Colour,
            "observer",
        ),
        Slot::Sensor => pass(&[VIEW_SENSOR], Some(TS_SENSOR), Some(7), Colour, "sensor"),
        Slot::Pair => pass(pair, Some(TS_PAIR), Some(8), Colour, "views"),
        Slot::ObserverDirection => pass(
            &[VIEW_OBSERVER],
            None,
            None,
            LookupDirection,
            "observer directions",
        ),
        Slot::SensorDirection => pass(
            &[VIEW_SENSOR],
            None,
            None,
            LookupDirection,
            "sensor directions",
        ),
    }
}
