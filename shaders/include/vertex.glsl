// vertex.glsl - the one scene-vertex transform every cube method and view uses.
// `precise` forbids the compiler from fusing or reordering these products, so a vertex lands on
// bit-identical clip coordinates whichever stage (vertex or geometry) computes them.
#ifndef VERTEX_GLSL
#define VERTEX_GLSL

#include "shared.glsl"

vec3 object_to_world(ObjectData object, vec3 p) {
    precise vec4 world = object.model_to_world * vec4(p, 1.0);
    return world.xyz;
}

vec3 normal_to_world(ObjectData object, vec3 n) {
    return (object.normal_to_world * vec4(n, 0.0)).xyz;
}

vec4 world_to_clip(ViewData view, vec3 world) {
    precise vec4 clip = view.world_to_clip * vec4(world, 1.0);
    return clip;
}

#endif
