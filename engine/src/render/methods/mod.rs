//! Cube fill methods. Each one renders the dirty faces of a [`CubePlan`] into the cube's mip 0
//! and must give the same pixels as every other (tested bit for bit).
//!
//! Adding a method means one variant here, one module beside this file, and its shaders.

pub mod geometry;
pub mod instanced;
pub mod multiview;
pub mod six_pass;

use ash::vk;

use crate::vk::device::DeviceInfo;

/// How the six faces of the cube map are filled.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// One render pass per face, CPU-culled per face (the thesis).
    #[default]
    SixPass,
    /// One pass with `VK_KHR_multiview`, view mask 0x3F; `gl_ViewIndex` picks the face.
    Multiview,
    /// One layered pass; a geometry shader sends each triangle to the faces it touches.
    Geometry,
    /// One layered pass; each (object, face) pair that survives culling is an instance whose
    /// vertex shader writes `gl_Layer`, all from one indirect draw.
    Instanced,
}

impl Method {
    pub const ALL: [Method; 4] = [
        Method::SixPass,
        Method::Multiview,
        Method::Geometry,
        Method::Instanced,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::SixPass => "six-pass",
            Method::Multiview => "multiview",
            Method::Geometry => "geometry",
            Method::Instanced => "instanced",
        }
    }

    pub fn parse(name: &str) -> Option<Method> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Why the device cannot run this method by its features (None: it can, as far as features
    /// go; multiview is also probed, see `render::probe`).
    pub fn missing_features(self, info: &DeviceInfo) -> Option<String> {
        let f = &info.features;
        let lacks = |what: &str| Some(format!("the device lacks {what}"));
        match self {
            Method::SixPass => None,
            Method::Multiview if !f.multiview => lacks("the multiview feature (VK_KHR_multiview)"),
            Method::Multiview if info.limits.max_multiview_view_count < 6 => Some(format!(
                "maxMultiviewViewCount is {}, 6 views are needed",
                info.limits.max_multiview_view_count
            )),
            Method::Geometry if !f.geometry_shader => lacks("geometryShader"),
            Method::Instanced if !f.shader_output_layer => {
                lacks("shaderOutputLayer (gl_Layer in a vertex shader)")
            }
            Method::Instanced if !f.multi_draw_indirect || !f.draw_indirect_first_instance => {
                lacks("multiDrawIndirect and drawIndirectFirstInstance")
            }
            _ => None,
        }
    }

    /// The device features this method needs enabled (on top of the core set).
    pub fn features(self) -> RequiredFeatures {
        let mut r = RequiredFeatures::default();
        match self {
            Method::SixPass => {}
            Method::Multiview => r.multiview = true,
            Method::Geometry => r.geometry_shader = true,
            Method::Instanced => {
                r.shader_output_layer = true;
                r.multi_draw_indirect = true;
            }
        }
        r
    }

    /// Records the fill of `plan`'s dirty faces into mip 0 (layouts are set by the caller).
    pub(crate) fn record(
        self,
        r: &crate::render::Renderer,
        cmd: vk::CommandBuffer,
        plan: &crate::render::cube_fill::CubePlan,
    ) {
        match self {
            Method::SixPass => six_pass::record(r, cmd, plan),
            Method::Multiview => multiview::record(r, cmd, plan),
            Method::Geometry => geometry::record(r, cmd, plan),
            Method::Instanced => instanced::record(r, cmd, plan),
        }
    }

    /// Rendering-scope layer count and view mask.
    pub(crate) fn layers_and_view_mask(self) -> (u32, u32) {
        match self {
            Method::SixPass => (1, 0),
            Method::Multiview => (0, 0x3F),
            Method::Geometry | Method::Instanced => (6, 0),
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Optional device features a method needs; `Device::create` enables exactly these.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RequiredFeatures {
    pub multiview: bool,
    pub geometry_shader: bool,
    pub shader_output_layer: bool,
    /// multiDrawIndirect and drawIndirectFirstInstance.
    pub multi_draw_indirect: bool,
}

impl RequiredFeatures {
    pub fn union(self, o: Self) -> Self {
        Self {
            multiview: self.multiview || o.multiview,
            geometry_shader: self.geometry_shader || o.geometry_shader,
            shader_output_layer: self.shader_output_layer || o.shader_output_layer,
            multi_draw_indirect: self.multi_draw_indirect || o.multi_draw_indirect,
        }
    }
}

/// The shader stages of a method's cube pipeline.
pub(crate) fn stages(
    method: Method,
    gs_invocations: bool,
) -> Vec<(vk::ShaderStageFlags, &'static [u32])> {
    use crate::shaders as s;
    let frag = (vk::ShaderStageFlags::FRAGMENT, s::SCENE_FRAG);
    match method {
        Method::SixPass => vec![(vk::ShaderStageFlags::VERTEX, s::SCENE_VERT), frag],
        Method::Multiview => vec![(vk::ShaderStageFlags::VERTEX, s::CUBE_MULTIVIEW_VERT), frag],
        Method::Geometry => vec![
            (vk::ShaderStageFlags::VERTEX, s::CUBE_LAYERED_VERT),
            (
                vk::ShaderStageFlags::GEOMETRY,
                if gs_invocations {
                    s::CUBE_LAYERED_INVOCATIONS_GEOM
                } else {
                    s::CUBE_LAYERED_GEOM
                },
            ),
            frag,
        ],
        Method::Instanced => vec![(vk::ShaderStageFlags::VERTEX, s::CUBE_INSTANCED_VERT), frag],
    }
}
