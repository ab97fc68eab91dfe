#version 460
// scene.vert - one object's vertices into one view (a cube face in six-pass, or a camera).
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "scene_vertex.glsl"

void main() {
    vec3 world = scene_vertex(push.object_index);
    gl_Position = world_to_clip(views[push.view_index], world);
}
