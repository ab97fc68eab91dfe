#version 460
// materials_check.comp - evaluates material_albedo and shade, exactly as scene.frag does, at
// arbitrary points, and writes full f32 results: the GPU side of the test that the CPU
// reference's twin of materials.glsl computes the same thing (not a rendering pass).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_nonuniform_qualifier : require
#include "shared.glsl"

SCENE_BINDINGS;

#include "materials.glsl"
CHECK_PUSH_CONSTANTS;

layout(set = 1, binding = 0, std430) readonly buffer SampleBlock { MaterialSample samples[]; };
layout(set = 1, binding = 1, std430) writeonly buffer ResultBlock { vec4 results[]; };

layout(local_size_x = 64) in;

void main() {
    if (gl_GlobalInvocationID.x >= check.count) {
        return;
    }
    uint i = check.first + gl_GlobalInvocationID.x;
    MaterialData m = materials[check.material];
    vec3 albedo = material_albedo(m, samples[i].position.xyz, samples[i].uv.xy);
    results[i] = vec4(shade(albedo, samples[i].normal.xyz, frame), 1.0);
}
