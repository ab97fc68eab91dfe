// sensor_ray.glsl - what the sensor's reflected ray meets, through the cube: its range and
// the id of the drawable it meets. Shared by the two halves of the sensor's ray map
// (mirror_ray.frag: its origin half writes the range, its direction half the id), which must
// agree on every pixel, so both make the same search.
//
// The range comes from the distance lookup's search through the cube's depth
// (distance_search.glsl): the point where the reflected ray meets the surface the cube
// stored. The id is the id cube's texel in that point's direction, read with texelFetch on
// the texel the point falls in (nearest, never filtered: blending depth invents surfaces
// between an object and what lies behind it, and blending ids invents objects).
//
// What the cube's centre did not see, the cube cannot answer: where the mirror point sees
// past an occluder into a surface the centre never saw (disocclusion), the search steps over
// the jump and takes the next surface the cube did store, and at a silhouette the nearest
// texel may belong to either side. Where the search meets nothing it can call a hit, the
// answer is the room box's: the distance to the wall the ray leaves the room through, and
// that wall's id (what the box lookup shows there).
#ifndef SENSOR_RAY_GLSL
#define SENSOR_RAY_GLSL

#include "shared.glsl"
#include "mirror.glsl"
#include "distance_search.glsl"

// Set 1, binding 2 of the ray map's pass through the cube: the id cube, six R32_UINT layers in face order
// (binding 1 is the cube's depth, declared by distance_search.glsl).
layout(set = 1, binding = 2) uniform usampler2DArray cube_ids;

// The range (metres along r from p) and the drawable id the reflected ray from the mirror
// point p along unit r meets, through the depth and id cubes; the room box's answer where the
// search finds no hit or the texel holds no drawable.
void sensor_range_id(FrameData f, vec3 p, vec3 r, out float range, out uint id) {
    vec3 found;
    float t;
    if (distance_search_range(f, p, r, false, found, t) == SEARCH_HIT) {
        vec2 st;
        uint face = cube_face(found, st);
        int size = textureSize(cube_ids, 0).x;
        // The texel the point falls in, as stored_z_edge's `nearest`.
        ivec2 texel = clamp(ivec2(st * float(size)), ivec2(0), ivec2(size - 1));
        uint stored = texelFetch(cube_ids, ivec3(texel, face), 0).r;
        if (stored != OBJECT_NONE) {
            range = t;
            id = stored;
            return;
        }
    }
    range = room_exit_distance(p, r, f, id);
}

#endif
