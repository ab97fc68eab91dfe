#version 460
// scene.frag - the albedo (and optional light) of everything but the mirror. Shared by every
// cube method and every view, so equal inputs give equal pixels.
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

void main() {
    MaterialData m = materials[objects[in_object].material.x];
    vec3 albedo = material_albedo(m, in_world_pos, in_uv);
    out_color = vec4(shade(albedo, in_world_normal, frame), 1.0);
}
