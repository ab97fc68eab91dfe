//! The benchmark's floors: what a cube update costs when part of the work is taken away. Each
//! is recorded exactly like a method's update (same cube, same faces, same mip rebuild), so
//! their times compare directly with the methods' (docs/benchmarks.md, "Floors"):
//!
//! - **clear**: each face's rendering scope opened with a clear and closed, nothing drawn;
//! - **fill**: one triangle per face covering it, shaded by the real `scene.frag` as the face's
//!   wall (every texel shaded once, no overdraw, no scene geometry);
//! - **geometry**: six-pass's culled draws with rasterizer discard (all vertex work, no pixel).
//!
//! A method cannot beat clear; a perfect one would cost about geometry + fill − clear.

use ash::vk;

use super::gpu::Push;
use super::methods::{CubePlan, CubeRecorder};
use super::targets::DEPTH_FORMAT;
use super::{FrameReport, Readback, Renderer};
use crate::vk::pipeline::{GraphicsPipelineDesc, Pipeline, ShaderStage};
use crate::vk::GpuError;

/// A floor of the cube update's cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Floor {
    Clear,
    Fill,
    Geometry,
}

impl Floor {
    pub const ALL: [Floor; 3] = [Floor::Clear, Floor::Fill, Floor::Geometry];

    pub fn name(self) -> &'static str {
        match self {
            Floor::Clear => "clear",
            Floor::Fill => "fill",
            Floor::Geometry => "geometry",
        }
    }
}

/// The floors' pipelines, made on first use (rendering never needs them).
pub(super) struct FloorPipelines {
    fill: Pipeline,
    geometry: Pipeline,
}

impl Renderer {
    /// One full cube update with `floor` in place of the method's draws, at time `t_s`, timed
    /// like [`Renderer::render_frame`] (nothing is read back): a frame like every other,
    /// asked with its cube filled by the floor. The cube's contents are not a picture
    /// afterwards: the next real frame re-renders every face.
    pub fn render_floor(
        &mut self,
        floor: Floor,
        frame: u64,
        t_s: f64,
    ) -> Result<FrameReport, GpuError> {
        self.prepare_floors()?;
        let ask = super::FrameAsk {
            cube: super::CubeWork::Floor(floor),
            ..super::FrameAsk::new(frame, t_s, Readback::default())
        };
        let (report, _) = self.render_asked(ask)?;
        Ok(report)
    }

    /// Builds the floors' pipelines now (a benchmark does it before timing anything).
    pub fn prepare_floors(&mut self) -> Result<(), GpuError> {
        if self.floor_pipelines.is_none() {
            self.floor_pipelines = Some(self.create_floor_pipelines()?);
        }
        Ok(())
    }

    /// Records `floor` into every face of `plan` (the caller set the layouts).
    pub(super) fn record_floor(&self, rec: &CubeRecorder<'_>, plan: &CubePlan, floor: Floor) {
        let pipelines = self.floor_pipelines.as_ref().expect("made by render_floor");
        for face in plan.faces() {
            rec.begin_face(face, &[]);
            let push = Push {
                view_index: face,
                ..Push::default()
            };
            match floor {
                Floor::Clear => {}
                Floor::Geometry => {
                    rec.draw_objects(&pipelines.geometry, push, &plan.visible[face as usize])
                }
                Floor::Fill => {
                    // Wall `face` is the one a face looks at (walls are in cube-face order).
                    rec.bind(&pipelines.fill);
                    rec.set_cull_back(false);
                    rec.push(Push {
                        object_index: face,
                        ..push
                    });
                    // SAFETY: the scene is bound; floor_fill.vert makes its 3 vertices.
                    unsafe { rec.device().raw.cmd_draw(rec.cmd(), 3, 1, 0, 0) };
                }
            }
            rec.end_face(face);
        }
    }

    fn create_floor_pipelines(&self) -> Result<FloorPipelines, GpuError> {
        let layout = &self.scene_layout;
        let vertex = |spirv| ShaderStage::new(vk::ShaderStageFlags::VERTEX, spirv);
        let fragment = ShaderStage::new(vk::ShaderStageFlags::FRAGMENT, crate::shaders::SCENE_FRAG);
        let (bindings, attributes) = super::pipelines::vertex_layout();
        // The fill floor makes its own vertices; the geometry floor draws the scene's.
        let make = |vertex_spirv, discard, with_vertices: bool, name| {
            let stages = [vertex(vertex_spirv), fragment];
            let desc = GraphicsPipelineDesc {
                stages: &stages,
                vertex_bindings: if with_vertices { &bindings } else { &[] },
                vertex_attributes: if with_vertices { &attributes } else { &[] },
                color_formats: &[self.cube.format],
                depth_format: DEPTH_FORMAT,
                cull_mode: vk::CullModeFlags::NONE,
                // Every cube pipeline sets its culling per draw.
                dynamic_culling: true,
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
                color_writes: true,
                view_mask: 0,
                rasterizer_discard: discard,
            };
            Pipeline::create_graphics(&self.device, layout, &desc, name)
        };
        let fill_vs = crate::shaders::FLOOR_FILL_VERT;
        let scene_vs = crate::shaders::SCENE_VERT;
        Ok(FloorPipelines {
            fill: make(fill_vs, false, false, "fill floor pipeline")?,
            geometry: make(scene_vs, true, true, "geometry floor pipeline")?,
        })
    }
}
