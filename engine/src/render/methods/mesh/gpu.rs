//! `#[repr(C)]` mirrors of what `shaders/include/cube_mesh.glsl` declares. The constants the
//! CPU needs are written here a second time (build.rs generates constants from shared.glsl
//! only); the tests compare both sides: the constants with the header's text, the offsets
//! with the SPIR-V.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

/// `TASK_MESHLETS`: meshlet draws one task workgroup culls (one invocation each).
pub const TASK_MESHLETS: u32 = 128;
/// `SPEC_SUB_PIXEL_BITS`: the mesh shader's specialization constant id for the device's
/// `subPixelPrecisionBits`.
pub const SPEC_SUB_PIXEL_BITS: u32 = 0;

/// `Meshlet`: one meshlet in its mesh's object space.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Meshlet {
    /// xyz: centre, w: radius.
    pub sphere: Vec4,
    /// xyz: unit axis of the normals, w: the cone cutoff (`meshlets::Meshlet::cone_cutoff`).
    pub cone: Vec4,
    pub first_vertex: u32,
    pub first_triangle: u32,
    pub vertex_count: u32,
    pub triangle_count: u32,
}

/// `MeshletDraw`: one meshlet of one object to draw this update.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct MeshletDraw {
    pub meshlet: u32,
    pub object: u32,
    /// Bit f: face f is dirty and the object's bounds meet its frustum.
    pub face_mask: u32,
    /// 1: the object's back faces are culled this update, so back-facing meshlets (task
    /// shader) and triangles (mesh shader) may go.
    pub cull_back: u32,
}

/// `MeshPush`: one draw call's range of draws. As large as the scene's `Push`: the two
/// pipeline layouts have the same push range, so either can push.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct MeshPush {
    pub first_draw: u32,
    pub draw_count: u32,
    pub pad0: u32,
    pub pad1: u32,
}

const _: () = assert!(std::mem::size_of::<Meshlet>() == 48);
const _: () = assert!(std::mem::size_of::<MeshletDraw>() == 16);
const _: () =
    assert!(std::mem::size_of::<MeshPush>() == std::mem::size_of::<crate::render::gpu::Push>());

/// A triangle's three local vertex indices packed as `meshlet_triangles` stores them.
pub fn pack_triangle(t: [u8; 3]) -> u32 {
    u32::from(t[0]) | u32::from(t[1]) << 8 | u32::from(t[2]) << 16
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::methods::mesh::meshlets;
    use std::mem::offset_of;

    #[test]
    fn constants_match_the_glsl_header() {
        let header = include_str!("../../../../../shaders/include/cube_mesh.glsl");
        let define = |name: &str| -> u32 {
            header
                .lines()
                .find_map(|l| l.strip_prefix(&format!("#define {name} ")))
                .unwrap_or_else(|| panic!("cube_mesh.glsl defines {name}"))
                .trim()
                .parse()
                .unwrap_or_else(|_| panic!("{name} is an integer"))
        };
        // The builder's limits are the mesh shader's output limits.
        assert_eq!(
            define("MESHLET_MAX_VERTICES") as usize,
            meshlets::MAX_VERTICES
        );
        assert_eq!(
            define("MESHLET_MAX_TRIANGLES") as usize,
            meshlets::MAX_TRIANGLES
        );
        assert_eq!(define("TASK_MESHLETS"), TASK_MESHLETS);
        assert_eq!(define("SPEC_SUB_PIXEL_BITS"), SPEC_SUB_PIXEL_BITS);
        // A face index (0..6) fits its bits, and a draw index within a task workgroup the rest.
        let face_bits = define("MESH_FACE_BITS");
        assert!(6 <= 1 << face_bits && TASK_MESHLETS <= u32::MAX >> face_bits);
    }

    /// The `constant_id` of every specialization constant in a SPIR-V module: its
    /// `OpDecorate %c SpecId N` instructions (opcode 71, decoration 1).
    fn spec_ids(words: &[u32]) -> Vec<u32> {
        let mut ids = Vec::new();
        let mut at = 5; // past the header
        while at < words.len() {
            let (count, opcode) = ((words[at] >> 16) as usize, words[at] & 0xffff);
            if opcode == 71 && count >= 4 && words[at + 2] == 1 {
                ids.push(words[at + 3]);
            }
            at += count.max(1);
        }
        ids
    }

    /// Both mesh shaders take the device's sub-pixel bits under the id the method sets.
    #[test]
    fn the_mesh_shaders_read_the_sub_pixel_bits_the_method_gives() {
        for spirv in [
            crate::shaders::CUBE_MESH_MESH,
            crate::shaders::CUBE_MESH_NARROW_MESH,
        ] {
            assert_eq!(spec_ids(spirv), [SPEC_SUB_PIXEL_BITS]);
        }
        assert!(spec_ids(crate::shaders::CUBE_MESH_TASK).is_empty());
    }

    #[test]
    fn rust_mirrors_match_spirv_offsets() {
        let rust: &[(&str, &str, usize)] = &[
            ("Meshlet", "sphere", offset_of!(Meshlet, sphere)),
            ("Meshlet", "cone", offset_of!(Meshlet, cone)),
            ("Meshlet", "first_vertex", offset_of!(Meshlet, first_vertex)),
            (
                "Meshlet",
                "first_triangle",
                offset_of!(Meshlet, first_triangle),
            ),
            ("Meshlet", "vertex_count", offset_of!(Meshlet, vertex_count)),
            (
                "Meshlet",
                "triangle_count",
                offset_of!(Meshlet, triangle_count),
            ),
            ("MeshletDraw", "meshlet", offset_of!(MeshletDraw, meshlet)),
            ("MeshletDraw", "object", offset_of!(MeshletDraw, object)),
            (
                "MeshletDraw",
                "face_mask",
                offset_of!(MeshletDraw, face_mask),
            ),
            (
                "MeshletDraw",
                "cull_back",
                offset_of!(MeshletDraw, cull_back),
            ),
            ("MeshPush", "first_draw", offset_of!(MeshPush, first_draw)),
            ("MeshPush", "draw_count", offset_of!(MeshPush, draw_count)),
            ("MeshPush", "pad0", offset_of!(MeshPush, pad0)),
            ("MeshPush", "pad1", offset_of!(MeshPush, pad1)),
            // The scene's vertices as the mesh shader reads them: gpu::Vertex's floats.
            ("SceneVertex", "px", 0),
            (
                "SceneVertex",
                "nx",
                offset_of!(crate::render::gpu::Vertex, normal),
            ),
            (
                "SceneVertex",
                "u",
                offset_of!(crate::render::gpu::Vertex, uv),
            ),
        ];
        for &(s, m, offset) in rust {
            let spirv = crate::shaders::SPIRV_MEMBER_OFFSETS
                .iter()
                .find(|(s2, m2, _)| *s2 == s && *m2 == m)
                .unwrap_or_else(|| panic!("{s}.{m} is not in any shader's SPIR-V"));
            assert_eq!(spirv.2 as usize, offset, "{s}.{m}");
        }
        for (s, m, _) in crate::shaders::SPIRV_MEMBER_OFFSETS {
            if ["Meshlet", "MeshletDraw", "MeshPush"].contains(s) {
                assert!(
                    rust.iter().any(|(s2, m2, _)| s2 == s && m2 == m),
                    "{s}.{m} not mirrored"
                );
            }
        }
    }

    #[test]
    fn triangles_pack_one_byte_per_index() {
        assert_eq!(pack_triangle([1, 2, 63]), 0x003F_0201);
    }
}
