#version 460
// scene.frag - the albedo (and optional light) of everything but the mirror.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"
#include "materials.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

layout(location = 0) in vec3 in_world_pos;
layout(location = 1) in vec3 in_world_normal;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec4 out_color;

void main() {
    MaterialData m = materials[objects[push.object_index].material.x];
    // The slot is the same for a whole draw (one object), so indexing is dynamically uniform.
    vec3 albedo = material_albedo(m, in_world_pos, in_uv, textures[m.kind_texture.y]);
    out_color = vec4(shade(albedo, in_world_normal, frame), 1.0);
}
