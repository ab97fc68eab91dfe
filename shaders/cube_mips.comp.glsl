#version 460
// build: cube_mips_rgba16f=FORMAT_RGBA16F cube_mips_rgba8=FORMAT_RGBA8
// cube_mips.comp - one level of the cube's mip chain from the level above it: each texel the
// mean of the texels above it (2 x 2, or up to 3 x 3 where a level's side is odd), summed in
// one fixed order, in this shader's arithmetic.
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
// A level of odd side (a 96² face's 3² level, a 100² face's 25²) is box-filtered over the
// span each texel covers, three texels an axis, so the chain lines up with how the sampler
// maps every level onto the face: nothing dropped, nothing shifted.

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

// One axis: the weights of the three texels 2x, 2x + 1, 2x + 2 of a level of `n` that texel x
// of the next reads. An even level halves exactly: a half each of the first two. An odd one,
// 2w + 1 texels for w, is box-filtered over the span x (2w + 1) / w .. (x + 1)(2w + 1) / w that
// texel x covers: (w - x), w and (x + 1) over 2w + 1.
vec3 weights(int x, int n) {
    if ((n & 1) == 0) {
        return vec3(0.5, 0.5, 0.0);
    }
    float w = float(n / 2);
    return vec3(w - float(x), w, float(x) + 1.0) / float(n);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, box.size))) {
        return;
    }
    ivec2 at = box.origin + p;
    int face = box.first_face + int(gl_GlobalInvocationID.z);
    ivec2 n = textureSize(above, 0).xy;
    vec3 wx = weights(at.x, n.x);
    vec3 wy = weights(at.y, n.y);
    // Row by row, tap by tap, always in this order: the same sum wherever it is dispatched.
    vec4 sum = vec4(0.0);
    for (int j = 0; j < 3; j++) {
        if (wy[j] == 0.0) {
            continue;
        }
        vec4 row = vec4(0.0);
        for (int i = 0; i < 3; i++) {
            if (wx[i] != 0.0) {
                row += wx[i] * texelFetch(above, ivec3(2 * at + ivec2(i, j), face), 0);
            }
        }
        sum += wy[j] * row;
    }
    imageStore(level, ivec3(at, face), sum);
}
