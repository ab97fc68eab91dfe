//! The renderer's own pipelines: the scene's vertex layout, the view scene pipeline, the
//! mirror pipelines every lookup builds on, and the fixed set made once per renderer.

use ash::vk;

use super::gpu::Push;
use super::targets::{DEPTH_FORMAT, DIRECTION_FORMAT, VIEW_FORMAT};
use super::*;

/// The scene vertex buffer's layout: `gpu::Vertex` (position, normal, uv) at binding 0.
pub(super) fn vertex_layout() -> (
    [vk::VertexInputBindingDescription; 1],
    [vk::VertexInputAttributeDescription; 3],
) {
    let bindings = [vk::VertexInputBindingDescription {
        binding: 0,
        stride: std::mem::size_of::<gpu::Vertex>() as u32,
        input_rate: vk::VertexInputRate::VERTEX,
    }];
    let attr = |location, format, offset| vk::VertexInputAttributeDescription {
        location,
        binding: 0,
        format,
        offset,
    };
    let attributes = [
        attr(0, vk::Format::R32G32B32_SFLOAT, 0),
        attr(1, vk::Format::R32G32B32_SFLOAT, 12),
        attr(2, vk::Format::R32G32_SFLOAT, 24),
    ];
    (bindings, attributes)
}

/// The attachments a scene pipeline renders to.
#[derive(Debug, Clone, Copy)]
pub(super) struct SceneTargets<'a> {
    /// The colour attachments' formats: the image's, then the id cube's when the fill writes
    /// ids too (`scene_id.frag`), or the ray map's quantities' (colour writes off).
    pub color_formats: &'a [vk::Format],
    /// Multiview view mask (0: none).
    pub view_mask: u32,
}

/// A scene pipeline: `stages` (vertex or mesh stages, then a fragment shader), the scene's
/// vertex layout unless the stages include a mesh shader, reverse-Z depth, culling set per
/// draw. Used by the views and, through `methods::MethodContext`, by every cube method.
pub(super) fn scene_pipeline(
    device: &Arc<Device>,
    layout: &PipelineLayout,
    stages: &[ShaderStage<'_>],
    targets: SceneTargets<'_>,
    name: &str,
) -> Result<Pipeline, GpuError> {
    scene_pipeline_with_writes(device, layout, stages, targets, true, name)
}

fn scene_pipeline_with_writes(
    device: &Arc<Device>,
    layout: &PipelineLayout,
    stages: &[ShaderStage<'_>],
    targets: SceneTargets<'_>,
    color_writes: bool,
    name: &str,
) -> Result<Pipeline, GpuError> {
    let SceneTargets {
        color_formats,
        view_mask,
    } = targets;
    let (bindings, attributes) = vertex_layout();
    let mesh = stages
        .iter()
        .any(|s| s.stage.contains(vk::ShaderStageFlags::MESH_EXT));
    Pipeline::create_graphics(
        device,
        layout,
        &GraphicsPipelineDesc {
            stages,
            vertex_bindings: if mesh { &[] } else { &bindings },
            vertex_attributes: if mesh { &[] } else { &attributes },
            color_formats,
            depth_format: DEPTH_FORMAT,
            // Set per draw: room walls are seen from inside and meshes may be open.
            cull_mode: vk::CullModeFlags::NONE,
            dynamic_culling: true,
            depth_compare: vk::CompareOp::GREATER,
            depth_write: true,
            color_writes,
            view_mask,
            rasterizer_discard: false,
        },
        name,
    )
}

/// A mirror pipeline: the bounding cube of `mirror.vert` and `fragment` (a lookup's shader),
/// reverse-Z depth written from the sphere's hit point. Each lookup makes its own
/// (`lookups::LookupPass`).
pub(crate) fn mirror_pipeline(
    device: &Arc<Device>,
    layout: &PipelineLayout,
    fragment: &[u32],
    color_formats: &[vk::Format],
    name: &str,
) -> Result<Pipeline, GpuError> {
    Pipeline::create_graphics(
        device,
        layout,
        &GraphicsPipelineDesc {
            stages: &[
                ShaderStage::new(vk::ShaderStageFlags::VERTEX, crate::shaders::MIRROR_VERT),
                ShaderStage::new(vk::ShaderStageFlags::FRAGMENT, fragment),
            ],
            vertex_bindings: &[],
            vertex_attributes: &[],
            color_formats,
            depth_format: DEPTH_FORMAT,
            // Back faces of the bounding cube: still on screen when the camera is inside it.
            cull_mode: vk::CullModeFlags::FRONT,
            dynamic_culling: false,
            depth_compare: vk::CompareOp::GREATER,
            depth_write: true,
            color_writes: true,
            view_mask: 0,
            rasterizer_discard: false,
        },
        name,
    )
}

/// The scene pipelines of the views (on the renderer's scene layout, which outlives them).
pub(super) struct ViewPipelines {
    /// The views' colour pass.
    pub colour: Pipeline,
    /// Direction pass: scene depth only, then the mirror's lookup directions.
    pub depth_only: Pipeline,
}

/// The scene's pipeline layout, and the view and depth-only pipelines on it (reverse-Z depth
/// everywhere); the cube's pipeline belongs to its method, the mirror's to its lookup.
pub(super) fn create_pipelines(
    device: &Arc<Device>,
    res: &SceneResources,
) -> Result<(PipelineLayout, ViewPipelines), GpuError> {
    let push = std::mem::size_of::<Push>() as u32;
    let scene_layout =
        PipelineLayout::create(device, &[res.scene_set_layout.raw], push, "scene layout")?;
    // The views use the plain vertex shader and RGBA16F. The direction pass lays down depth
    // only, then the lookup writes the mirror's directions in full float.
    let scene_stages = [
        ShaderStage::new(vk::ShaderStageFlags::VERTEX, crate::shaders::SCENE_VERT),
        ShaderStage::new(vk::ShaderStageFlags::FRAGMENT, crate::shaders::SCENE_FRAG),
    ];
    let view = |color_formats| SceneTargets {
        color_formats,
        view_mask: 0,
    };
    let view_scene = scene_pipeline(
        device,
        &scene_layout,
        &scene_stages,
        view(&[VIEW_FORMAT]),
        "scene pipeline (views)",
    )?;
    let depth_only = depth_only_pipeline(
        device,
        &scene_layout,
        &[DIRECTION_FORMAT],
        "depth-only pipeline (directions)",
    )?;
    let views = ViewPipelines {
        colour: view_scene,
        depth_only,
    };
    Ok((scene_layout, views))
}

/// A view's scene pipeline that lays down depth only, for a pass whose colour attachments
/// (`color_formats`) only the mirror writes: the lookup directions, the ray map's quantities.
pub(super) fn depth_only_pipeline(
    device: &Arc<Device>,
    scene_layout: &PipelineLayout,
    color_formats: &[vk::Format],
    name: &str,
) -> Result<Pipeline, GpuError> {
    let scene_stages = [
        ShaderStage::new(vk::ShaderStageFlags::VERTEX, crate::shaders::SCENE_VERT),
        ShaderStage::new(vk::ShaderStageFlags::FRAGMENT, crate::shaders::SCENE_FRAG),
    ];
    let targets = SceneTargets {
        color_formats,
        view_mask: 0,
    };
    scene_pipeline_with_writes(device, scene_layout, &scene_stages, targets, false, name)
}
