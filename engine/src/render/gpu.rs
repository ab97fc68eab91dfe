//! `#[repr(C)]` mirrors of the structs in `shaders/include/shared.glsl`.
//!
//! Field names match the GLSL members; a test compares every offset with what glslang put in
//! the SPIR-V, so a change on one side without the other fails `cargo test`.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, UVec4, Vec4};

/// Texture slots in the shaders' `textures[]` array (shared.glsl `MAX_TEXTURES`).
pub const MAX_TEXTURES: usize = 16;

/// `MaterialData.kind_texture.x` values (shared.glsl `MATERIAL_*`).
pub const MATERIAL_COLOR: u32 = 0;
pub const MATERIAL_CHECKER: u32 = 1;
pub const MATERIAL_GRID: u32 = 2;
pub const MATERIAL_TEXTURE: u32 = 3;
pub const MATERIAL_DIRECTION: u32 = 4;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FrameData {
    pub light_dir_ambient: Vec4,
    pub mirror: Vec4,
    pub flags: UVec4,
    pub room_min: Vec4,
    pub room_max: Vec4,
}

/// `FrameData.flags.y` values (shared.glsl `LOOKUP_*`).
pub const LOOKUP_PLAIN: u32 = 0;
pub const LOOKUP_BOX: u32 = 1;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ViewData {
    pub world_to_clip: Mat4,
    pub eye: Vec4,
    pub ray_right: Vec4,
    pub ray_down: Vec4,
    pub ray_forward: Vec4,
    pub viewport: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ObjectData {
    pub model_to_world: Mat4,
    pub normal_to_world: Mat4,
    pub material: UVec4,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MaterialData {
    pub kind_texture: UVec4,
    pub color_a: Vec4,
    pub color_b: Vec4,
    pub params: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Push {
    pub view_index: u32,
    pub object_index: u32,
    /// Layered cube fills: bit f set renders face f.
    pub face_mask: u32,
    pub pad: u32,
}

/// One point for the materials check (`materials_check.comp`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MaterialSample {
    pub position: Vec4,
    pub normal: Vec4,
    pub uv: Vec4,
}

/// `materials_check.comp`'s push constants: samples `first..first + count`, one material.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct CheckPush {
    pub first: u32,
    pub count: u32,
    pub material: u32,
    pub pad: u32,
}

/// Instanced cube fill: `gl_InstanceIndex = object << INSTANCE_FACE_BITS | face`.
pub const INSTANCE_FACE_BITS: u32 = 3;

/// One vertex of the scene's vertex buffer (locations 0, 1, 2 of scene.vert).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
}

// std430 array strides must equal the Rust sizes; build.rs reads member offsets only, so the
// sizes are pinned here by hand (each is a multiple of 16, as std430 arrays of these need).
const _: () = assert!(std::mem::size_of::<FrameData>() == 80);
const _: () = assert!(std::mem::size_of::<ViewData>() == 144);
const _: () = assert!(std::mem::size_of::<ObjectData>() == 144);
const _: () = assert!(std::mem::size_of::<MaterialData>() == 64);
const _: () = assert!(std::mem::size_of::<Push>() == 16);
const _: () = assert!(std::mem::size_of::<Vertex>() == 32);

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    #[test]
    fn rust_mirrors_match_spirv_offsets() {
        let rust: &[(&str, &str, usize)] = &[
            (
                "FrameData",
                "light_dir_ambient",
                offset_of!(FrameData, light_dir_ambient),
            ),
            ("FrameData", "mirror", offset_of!(FrameData, mirror)),
            ("FrameData", "flags", offset_of!(FrameData, flags)),
            ("FrameData", "room_min", offset_of!(FrameData, room_min)),
            ("FrameData", "room_max", offset_of!(FrameData, room_max)),
            (
                "ViewData",
                "world_to_clip",
                offset_of!(ViewData, world_to_clip),
            ),
            ("ViewData", "eye", offset_of!(ViewData, eye)),
            ("ViewData", "ray_right", offset_of!(ViewData, ray_right)),
            ("ViewData", "ray_down", offset_of!(ViewData, ray_down)),
            ("ViewData", "ray_forward", offset_of!(ViewData, ray_forward)),
            ("ViewData", "viewport", offset_of!(ViewData, viewport)),
            (
                "ObjectData",
                "model_to_world",
                offset_of!(ObjectData, model_to_world),
            ),
            (
                "ObjectData",
                "normal_to_world",
                offset_of!(ObjectData, normal_to_world),
            ),
            ("ObjectData", "material", offset_of!(ObjectData, material)),
            (
                "MaterialData",
                "kind_texture",
                offset_of!(MaterialData, kind_texture),
            ),
            ("MaterialData", "color_a", offset_of!(MaterialData, color_a)),
            ("MaterialData", "color_b", offset_of!(MaterialData, color_b)),
            ("MaterialData", "params", offset_of!(MaterialData, params)),
            ("Push", "view_index", offset_of!(Push, view_index)),
            ("Push", "object_index", offset_of!(Push, object_index)),
            ("Push", "face_mask", offset_of!(Push, face_mask)),
            ("Push", "pad", offset_of!(Push, pad)),
            (
                "MaterialSample",
                "position",
                offset_of!(MaterialSample, position),
            ),
            (
                "MaterialSample",
                "normal",
                offset_of!(MaterialSample, normal),
            ),
            ("MaterialSample", "uv", offset_of!(MaterialSample, uv)),
            ("CheckPush", "first", offset_of!(CheckPush, first)),
            ("CheckPush", "count", offset_of!(CheckPush, count)),
            ("CheckPush", "material", offset_of!(CheckPush, material)),
            ("CheckPush", "pad", offset_of!(CheckPush, pad)),
        ];
        for &(s, m, offset) in rust {
            let spirv = crate::shaders::SPIRV_MEMBER_OFFSETS
                .iter()
                .find(|(s2, m2, _)| *s2 == s && *m2 == m)
                .unwrap_or_else(|| panic!("{s}.{m} is not in any shader's SPIR-V"));
            assert_eq!(spirv.2 as usize, offset, "{s}.{m}");
        }
        // And every member glslang knows of a mirrored struct is mirrored.
        for (s, m, _) in crate::shaders::SPIRV_MEMBER_OFFSETS {
            if rust.iter().any(|(s2, _, _)| s2 == s) {
                assert!(
                    rust.iter().any(|(s2, m2, _)| s2 == s && m2 == m),
                    "{s}.{m} not mirrored"
                );
            }
        }
    }
}
