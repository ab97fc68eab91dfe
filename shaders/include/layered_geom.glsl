// layered_geom.glsl - the body shared by the two geometry-shader cube fills: project the
// triangle into face `face`, drop it if it lies wholly outside one clip plane, emit it with
// gl_Layer = face.
#ifndef LAYERED_GEOM_GLSL
#define LAYERED_GEOM_GLSL

#include "shared.glsl"
#include "vertex.glsl"

layout(location = 0) in vec3 in_world_pos[];
layout(location = 1) in vec3 in_world_normal[];
layout(location = 2) in vec2 in_uv[];
layout(location = 3) flat in uint in_object[];

layout(location = 0) out vec3 out_world_pos;
layout(location = 1) out vec3 out_world_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out uint out_object;

// True when all three vertices are outside the same plane of the clip volume
// (-w <= x, y <= w; reverse-Z 0 <= z <= w).
bool outside(vec4 c[3]) {
    for (int axis = 0; axis < 2; axis++) {
        if (c[0][axis] > c[0].w && c[1][axis] > c[1].w && c[2][axis] > c[2].w) return true;
        if (c[0][axis] < -c[0].w && c[1][axis] < -c[1].w && c[2][axis] < -c[2].w) return true;
    }
    if (c[0].z > c[0].w && c[1].z > c[1].w && c[2].z > c[2].w) return true; // before near
    if (c[0].z < 0.0 && c[1].z < 0.0 && c[2].z < 0.0) return true;          // beyond far
    return false;
}

void emit_to_face(uint face) {
    vec4 clip[3];
    for (int i = 0; i < 3; i++) {
        clip[i] = world_to_clip(views[face], in_world_pos[i]);
    }
    if (outside(clip)) {
        return;
    }
    for (int i = 0; i < 3; i++) {
        out_world_pos = in_world_pos[i];
        out_world_normal = in_world_normal[i];
        out_uv = in_uv[i];
        out_object = in_object[i];
        gl_Layer = int(face);
        gl_Position = clip[i];
        EmitVertex();
    }
    EndPrimitive();
}

#endif
