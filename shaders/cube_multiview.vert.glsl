#version 460
// cube_multiview.vert - multiview cube fill: one pass with view mask 0x3F; the driver runs
// this shader once per view and gl_ViewIndex (0..5) picks the face's view-projection.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_multiview : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "scene_vertex.glsl"

void main() {
    vec3 world = scene_vertex(push.object_index);
    gl_Position = world_to_clip(views[gl_ViewIndex], world);
}
