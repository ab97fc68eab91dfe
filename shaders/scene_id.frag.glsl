#version 460
// scene_id.frag - scene.frag for a cube fill that also writes the id cube: the same albedo
// (and optional light) to attachment 0, and the drawable's index (walls 0..6, objects 6 + i,
// the numbering of the sensor's id image) to the R32_UINT attachment 1. Ids are exact
// integers: the id cube is read texel by texel (texelFetch), never filtered, because a blend
// of two ids is no id at all. Used only when the renderer was made with an id cube
// (RenderOptions::id_cube), so the benchmark's fills never pay for the second attachment.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_nonuniform_qualifier : require
#include "shared.glsl"

SCENE_BINDINGS;

#include "materials.glsl"

layout(location = 0) in vec3 in_world_pos;
layout(location = 1) in vec3 in_world_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_object;

layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;

void main() {
    MaterialData m = materials[objects[in_object].material.x];
    vec3 albedo = material_albedo(m, in_world_pos, in_uv);
    out_color = vec4(shade(albedo, in_world_normal, frame), 1.0);
    out_id = in_object;
}
