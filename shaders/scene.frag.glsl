#version 460
// scene.frag - the albedo (and optional light) of everything but the mirror. Shared by every
// cube method and every view, so equal inputs give equal pixels.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"
#include "materials.glsl"

SCENE_BINDINGS;

layout(location = 0) in vec3 in_world_pos;
layout(location = 1) in vec3 in_world_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_object;

layout(location = 0) out vec4 out_color;

void main() {
    MaterialData m = materials[objects[in_object].material.x];
    // One object per draw (or per instance): the texture slot is the same for every fragment
    // of a primitive, which dynamic indexing of a sampler array requires.
    vec3 albedo = material_albedo(m, in_world_pos, in_uv, textures[m.kind_texture.y]);
    out_color = vec4(shade(albedo, in_world_normal, frame), 1.0);
}
