#version 460
// build: cube_mips_rgba16f=FORMAT_RGBA16F cube_mips_rgba8=FORMAT_RGBA8
// cube_mips.comp - one level of the cube's mip chain from the level above it: each texel the
// mean of the 2 x 2 texels above it, summed in one fixed order, in this shader's arithmetic.
//
// Why not vkCmdBlitImage, the usual way: a blit is the driver's to filter, and two drivers
// filter a cube face in ways that break an update on change. SwiftShader keeps a one-texel
// border around each face, copied from its neighbours for seamless sampling, and its linear
// blit reads it: a face's mips then depend on its neighbours' texels when they were made, so
// a clean face's old mips differ from a full update's. lavapipe's blit of a box of a level
// is not bit for bit the same texels of the whole level's blit. Here a texel is a function of
// its own face's four texels alone, whatever box is dispatched, so an update on change that
// rebuilds only the boxes above what it re-rendered gives a full update's bits on every
// device (docs/methods.md, "Dirty rectangles", item 5).
//
// A level of odd side (a 96² face's 3² level) drops its last row and column, as the mip
// chain's sizes do (side >> 1): texel x reads 2x and 2x + 1, which always lie inside.

#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

layout(local_size_x = MIP_GROUP_SIDE, local_size_y = MIP_GROUP_SIDE, local_size_z = 1) in;

// Level m - 1, six faces; read texel by texel (the sampler's filter is never used).
layout(set = 0, binding = 0) uniform sampler2DArray above;
// Level m, six faces; written where dispatched, the rest kept.
#ifdef FORMAT_RGBA16F
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2DArray level;
#else
layout(set = 0, binding = 1, rgba8) uniform writeonly image2DArray level;
#endif

// The box of level m to write, on faces first_face .. first_face + (dispatch depth) - 1.
MIP_BOX_PUSH_CONSTANTS;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, box.size))) {
        return;
    }
    ivec2 at = box.origin + p;
    int face = box.first_face + int(gl_GlobalInvocationID.z);
    ivec2 src = 2 * at;
    vec4 sum = texelFetch(above, ivec3(src, face), 0);
    sum += texelFetch(above, ivec3(src + ivec2(1, 0), face), 0);
    sum += texelFetch(above, ivec3(src + ivec2(0, 1), face), 0);
    sum += texelFetch(above, ivec3(src + ivec2(1, 1), face), 0);
    imageStore(level, ivec3(at, face), sum * 0.25);
}
