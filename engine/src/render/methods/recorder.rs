//! What a fill method sees of the renderer: a context to build its pipeline and state once,
//! per-update inputs, and a recorder for the cube's rendering scopes and the scene's draws.

use std::sync::Arc;

use ash::vk;

use super::{CubeLayout, CubePlan, Patch};
use crate::render::draw::{Attachments, Facing, CUBE_FRONT};
use crate::render::gpu::Push;
use crate::render::queries::FrameQueries;
use crate::render::resources::Drawable;
use crate::render::scene_draw::SceneDraw;
use crate::render::targets::CubeTarget;
use crate::scene::pixel_rect::PixelRect;
use crate::scene::Scene;
use crate::vk::commands::Submitter;
use crate::vk::device::Device;
use crate::vk::memory::{Buffer, Upload};
use crate::vk::pipeline::{Pipeline, PipelineLayout, ShaderStage};
use crate::vk::uploads::FrameUploads;
use crate::vk::GpuError;

/// What a method may use to build its pipeline and state ([`super::FillMethod::create`]).
pub struct MethodContext<'a> {
    pub device: &'a Arc<Device>,
    /// The resolved scene (its meshes, objects and room, for methods that preprocess them).
    pub scene: &'a Scene,
    /// Walls 0..6, then one per object: where each one's triangles sit in the shared buffers.
    pub drawables: &'a [Drawable],
    /// The shared scene vertex (`gpu::Vertex`) and index buffers.
    pub vertices: &'a Buffer,
    pub indices: &'a Buffer,
    /// Set 0 (the scene) and the layout of set 0 plus the push constants ([`Push`]).
    pub scene_set_layout: vk::DescriptorSetLayout,
    pub scene_layout: &'a PipelineLayout,
    pub cube_format: vk::Format,
    /// The fill writes the id cube too (`RenderOptions::id_cube`): the pipelines get its
    /// attachment and `scene_id.frag` instead of `scene.frag`.
    pub ids: bool,
    /// The method's own layout (its pipeline's view mask follows from it).
    pub layout: CubeLayout,
    /// For uploads at creation ([`Self::upload`]); idle between them.
    pub submitter: &'a Submitter,
}

/// A shader stage of a method's cube pipeline: its stage and SPIR-V (`crate::shaders`).
pub type Stage = (vk::ShaderStageFlags, &'static [u32]);

impl MethodContext<'_> {
    /// Device-local buffers holding data a method builds once (meshlets, say), uploaded in
    /// one submission through staging buffers: one per `(bytes, usage, name)` (cast typed
    /// data with `bytemuck::cast_slice`).
    pub fn upload(
        &self,
        buffers: &[(&[u8], vk::BufferUsageFlags, &str)],
    ) -> Result<Vec<Buffer>, GpuError> {
        let mut upload = Upload::begin(self.device, self.submitter)?;
        let made = buffers
            .iter()
            .map(|&(data, usage, name)| upload.buffer(data, usage, name))
            .collect::<Result<Vec<_>, _>>()?;
        upload.finish()?;
        Ok(made)
    }

    /// A cube pipeline with the scene's pipeline layout (see [`Self::pipeline_with`]).
    pub fn pipeline(&self, stages: &[Stage], name: &str) -> Result<Pipeline, GpuError> {
        self.pipeline_with(self.scene_layout, stages, name)
    }

    /// A cube pipeline: `stages` followed by `scene.frag` (`scene_id.frag` with the id cube),
    /// which every method shares so that equal inputs give equal pixels; the scene's vertex
    /// layout unless it is a mesh pipeline; reverse-Z depth; culling set per draw; the cube's
    /// colour format (and the id cube's) and the layout's view mask. `layout` must start with
    /// set 0 and the scene's push range.
    pub fn pipeline_with(
        &self,
        layout: &PipelineLayout,
        stages: &[Stage],
        name: &str,
    ) -> Result<Pipeline, GpuError> {
        let stages: Vec<ShaderStage<'_>> = (stages.iter())
            .map(|&(stage, spirv)| ShaderStage::new(stage, spirv))
            .collect();
        self.pipeline_of(layout, &stages, name)
    }

    /// [`Self::pipeline_with`] for stages that set specialization constants.
    pub fn pipeline_of(
        &self,
        layout: &PipelineLayout,
        stages: &[ShaderStage<'_>],
        name: &str,
    ) -> Result<Pipeline, GpuError> {
        let shader = if self.ids {
            crate::shaders::SCENE_ID_FRAG
        } else {
            crate::shaders::SCENE_FRAG
        };
        let fragment = ShaderStage::new(vk::ShaderStageFlags::FRAGMENT, shader);
        let stages: Vec<ShaderStage<'_>> = stages.iter().copied().chain([fragment]).collect();
        // The cube's colour, then the id cube's ids when the fill writes them.
        let formats = [self.cube_format, crate::render::targets::ID_FORMAT];
        let color_formats = if self.ids {
            &formats[..]
        } else {
            &formats[..1]
        };
        crate::render::pipelines::scene_pipeline(
            self.device,
            layout,
            &stages,
            crate::render::pipelines::SceneTargets {
                color_formats,
                view_mask: self.layout.view_mask(),
            },
            name,
        )
    }
}

/// Per-update inputs of [`super::FillPass::prepare`].
pub struct Prepare<'a> {
    pub device: &'a Arc<Device>,
    pub drawables: &'a [Drawable],
    /// Per drawable: whether its back faces may be culled in the cube this update.
    pub cull_back: &'a [bool],
    /// This frame's uploads: a method's per-update data goes to its device buffers through
    /// them (frames in flight may still read the last update's: see `vk::uploads`).
    pub uploads: &'a mut FrameUploads,
}

/// Records a cube fill: the rendering scopes on the cube, the scene's draws, and the
/// per-face marks (statistics queries, timestamps) of per-face methods. A method records
/// through this and through `device()` / `cmd()` for draw calls of its own.
pub struct CubeRecorder<'a> {
    parts: FillParts<'a>,
    cmd: vk::CommandBuffer,
    layout: CubeLayout,
    /// Per-face statistics queries and timestamps (six-pass); off for one-pass methods and
    /// the floors, which get one query for the whole fill.
    per_face_marks: bool,
    /// The fill writes the id cube (the method's pipelines were made with it); the
    /// benchmark's floors never do.
    ids: bool,
}

/// The parts of the renderer a cube fill records into (`FrameParts::fill_parts`): the
/// scene's draws, the cube, this frame's queries, and how the cube's faces see each drawable.
pub(in crate::render) struct FillParts<'a> {
    pub draw: SceneDraw<'a>,
    pub cube: &'a CubeTarget,
    pub queries: &'a FrameQueries,
    pub facing: Facing,
}

impl<'a> CubeRecorder<'a> {
    pub(in crate::render) fn new(
        parts: FillParts<'a>,
        cmd: vk::CommandBuffer,
        layout: CubeLayout,
        per_face_marks: bool,
        ids: bool,
    ) -> Self {
        Self {
            parts,
            cmd,
            layout,
            per_face_marks,
            ids,
        }
    }

    /// The id cube's view `pick` (a face's or the six layers'), when this fill writes it.
    fn id_view(
        &self,
        pick: impl Fn(&crate::render::targets::IdCube) -> vk::ImageView,
    ) -> Option<vk::ImageView> {
        self.parts
            .cube
            .ids
            .as_ref()
            .filter(|_| self.writes_ids())
            .map(pick)
    }

    /// Whether this fill writes the id cube.
    fn writes_ids(&self) -> bool {
        self.ids && self.parts.cube.ids.is_some()
    }

    pub fn device(&self) -> &Device {
        self.parts.draw.device
    }

    pub fn cmd(&self) -> vk::CommandBuffer {
        self.cmd
    }

    pub fn face_size(&self) -> u32 {
        self.parts.cube.size
    }

    /// Opens a rendering scope on face `face` alone with its viewport (and, for a per-face
    /// method, its statistics query), and clears what it re-renders: the whole face, or with
    /// `patches` only their rectangles, the rest of the face kept as it was.
    pub fn begin_face(&self, face: u32, patches: &[Patch]) {
        let dev = self.device();
        let name = crate::scene::camera::FACE_NAMES[face as usize];
        dev.begin_label(self.cmd, &format!("face {name}"));
        if let (Some(q), true) = (&self.parts.queries.statistics, self.per_face_marks) {
            q.begin(self.cmd, face);
        }
        let size = self.face_size();
        self.parts.draw.begin_rendering(
            self.cmd,
            &Attachments {
                color: self.parts.cube.face_views[face as usize].raw,
                ids: self.id_view(|ids| ids.face_views[face as usize].raw),
                more_colors: Vec::new(),
                depth: self.parts.cube.depth_views[face as usize].raw,
                size: [size, size],
                layers: 1,
                view_mask: 0,
                clear: patches.is_empty(),
                store_depth: true,
            },
        );
        if !patches.is_empty() {
            let rects: Vec<_> = patches
                .iter()
                .flat_map(|p| &p.rects)
                .map(|&r| (0, r))
                .collect();
            (self.parts.draw).clear_rects(self.cmd, &rects, self.writes_ids());
        }
        self.parts
            .draw
            .set_viewport(self.cmd, 0.0, 0.0, size as f32, size as f32);
    }

    /// Draws that follow touch only `patch`'s scissor.
    pub fn scissor(&self, patch: &Patch) {
        self.parts.draw.set_scissor(self.cmd, &patch.scissor);
    }

    /// Closes the scope opened by [`Self::begin_face`].
    pub fn end_face(&self, face: u32) {
        self.parts.draw.end_rendering(self.cmd);
        if let (Some(q), true) = (&self.parts.queries.statistics, self.per_face_marks) {
            q.end(self.cmd, face);
        }
        self.device().end_label(self.cmd);
    }

    /// A per-face method calls this after face `face`'s work, for every face in order, dirty
    /// or not (a clean face's time is then zero).
    pub fn face_timestamp(&self, face: u32) {
        if self.per_face_marks {
            self.parts.queries.face_timestamps(self.cmd, face..face + 1);
        }
    }

    /// Opens the one rendering scope of a one-pass method over all six faces and clears what
    /// `plan` re-renders: its dirty faces, or their dirty rectangles, the draws then scissored
    /// to their union. A multiview plan has all six faces, whole or with the same rectangles
    /// (`Dirty::in_every_face`): a clear in a multiview scope reaches every view.
    pub fn begin_cube(&self, plan: &CubePlan) {
        let size = self.face_size();
        let view_mask = self.layout.view_mask();
        let scissor = plan.scissor();
        // Cleared whole by the scope's load op only when every face is re-rendered whole.
        let whole = plan.faces().all(|f| plan.patches[f as usize].is_empty());
        let all = plan.dirty == 0x3F && whole;
        self.parts.draw.begin_rendering(
            self.cmd,
            &Attachments {
                color: self.parts.cube.layers_view.raw,
                ids: self.id_view(|ids| ids.layers_view.raw),
                more_colors: Vec::new(),
                depth: self.parts.cube.depth_layers_view.raw,
                size: [size, size],
                // With a view mask the count is ignored; 1, not 0, so that a clear's layer 0
                // lies within it as validation layers check it.
                layers: if view_mask != 0 { 1 } else { 6 },
                view_mask,
                clear: all,
                store_depth: true,
            },
        );
        if !all && view_mask != 0 {
            // Layer 0 stands for every view of the mask (the only layer a clear may name
            // there), so face 0's rectangles clear all six.
            debug_assert!(plan.dirty == 0x3F);
            debug_assert!((1..6).all(|f| plan.dirty_rects(f) == plan.dirty_rects(0)));
            let rects: Vec<(u32, PixelRect)> =
                plan.dirty_rects(0).into_iter().map(|r| (0, r)).collect();
            (self.parts.draw).clear_rects(self.cmd, &rects, self.writes_ids());
        } else if !all {
            let rects: Vec<(u32, PixelRect)> = (plan.faces())
                .flat_map(|f| match plan.dirty_rects(f as usize)[..] {
                    [] => vec![(f, PixelRect::whole(size))],
                    ref rects => rects.iter().map(|&r| (f, r)).collect(),
                })
                .collect();
            (self.parts.draw).clear_rects(self.cmd, &rects, self.writes_ids());
        }
        self.parts
            .draw
            .set_viewport(self.cmd, 0.0, 0.0, size as f32, size as f32);
        if let Some(s) = scissor {
            self.parts.draw.set_scissor(self.cmd, &s);
        }
    }

    /// Closes the scope opened by [`Self::begin_cube`].
    pub fn end_cube(&self) {
        self.parts.draw.end_rendering(self.cmd);
    }

    /// Binds `pipeline` with the scene's set 0, vertex and index buffers, and the cube's
    /// front-face winding (cube faces see the world mirrored).
    pub fn bind(&self, pipeline: &Pipeline) {
        self.parts.draw.bind_scene(self.cmd, pipeline);
        self.parts.draw.set_front_face(self.cmd, CUBE_FRONT);
    }

    /// Binds `pipeline` and draws `objects` in order, one indexed draw each, with push
    /// constants `base` whose object index is set per draw, back faces culled where allowed.
    pub fn draw_objects(&self, pipeline: &Pipeline, base: Push, objects: &[u32]) {
        (self.parts.draw).draw_objects(self.cmd, pipeline, base, objects, &self.parts.facing);
    }

    /// Sets the push constants of the draws that follow.
    pub fn push(&self, push: Push) {
        (self.parts.draw).push(self.cmd, self.parts.draw.layout.raw, push);
    }

    /// Back faces culled (`true`) or drawn for the draws that follow.
    pub fn set_cull_back(&self, cull: bool) {
        self.parts.draw.set_cull_back(self.cmd, cull);
    }
}
