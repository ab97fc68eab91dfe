//! Geometry-shader layered fill: one pass over the six-layer cube; each object visible in some
//! dirty face is drawn once, and the geometry shader emits each triangle to the dirty faces
//! whose clip volume it touches (`gl_Layer`).
//!
//! The method's shader loops over the faces in one invocation (`cube_layered.geom`). The
//! textbook form, six invocations per triangle (`cube_layered_invocations.geom`), is kept as
//! the variant `geometry-invocations` to measure the difference (docs/methods.md).

use ash::vk;

use super::{CubeLayout, CubePlan, CubeRecorder, FillMethod, FillPass, MethodContext, Needs};
use crate::render::gpu::Push;
use crate::vk::device::{Limit, OptionalFeatures};
use crate::vk::pipeline::Pipeline;
use crate::vk::GpuError;

/// What the geometry-shader methods need: the stage, and `limits` for their way of
/// emitting a triangle to each of the six faces.
fn needs(limits: &'static [(Limit, u32)]) -> Needs {
    Needs {
        features: OptionalFeatures {
            geometry_shader: true,
            ..Default::default()
        },
        limits,
        probe: false,
    }
}

fn create(
    ctx: &MethodContext<'_>,
    geometry: &'static [u32],
    name: &str,
) -> Result<Box<dyn FillPass>, GpuError> {
    let stages = [
        (
            vk::ShaderStageFlags::VERTEX,
            crate::shaders::CUBE_LAYERED_VERT,
        ),
        (vk::ShaderStageFlags::GEOMETRY, geometry),
    ];
    let pipeline = ctx.pipeline(&stages, &format!("cube pipeline ({name})"))?;
    Ok(Box::new(GeometryFill { pipeline }))
}

pub struct Geometry;

impl FillMethod for Geometry {
    fn name(&self) -> &'static str {
        "geometry"
    }

    fn summary(&self) -> &'static str {
        "one layered pass; a geometry shader sends each triangle to the faces it touches"
    }

    fn needs(&self) -> Needs {
        // One invocation emits up to six triangles.
        needs(&[(Limit::GeometryOutputVertices, 18)])
    }

    fn layout(&self) -> CubeLayout {
        CubeLayout::Layered
    }

    fn create(&self, ctx: &MethodContext<'_>) -> Result<Box<dyn FillPass>, GpuError> {
        create(ctx, crate::shaders::CUBE_LAYERED_GEOM, self.name())
    }
}

pub struct GeometryInvocations;

impl FillMethod for GeometryInvocations {
    fn name(&self) -> &'static str {
        "geometry-invocations"
    }

    fn summary(&self) -> &'static str {
        "geometry with `invocations = 6` (one per face) instead of the loop; kept to measure"
    }

    fn variant_of(&self) -> Option<&'static str> {
        Some("geometry")
    }

    fn needs(&self) -> Needs {
        needs(&[(Limit::GeometryShaderInvocations, 6)])
    }

    fn layout(&self) -> CubeLayout {
        CubeLayout::Layered
    }

    fn create(&self, ctx: &MethodContext<'_>) -> Result<Box<dyn FillPass>, GpuError> {
        create(
            ctx,
            crate::shaders::CUBE_LAYERED_INVOCATIONS_GEOM,
            self.name(),
        )
    }
}

struct GeometryFill {
    pipeline: Pipeline,
}

impl FillPass for GeometryFill {
    fn record(&self, rec: &CubeRecorder<'_>, plan: &CubePlan) {
        rec.begin_cube(plan);
        let push = Push {
            face_mask: u32::from(plan.dirty),
            ..Push::default()
        };
        rec.draw_objects(&self.pipeline, push, &plan.union());
        rec.end_cube();
    }
}
