#ifndef FOOTPRINT_FILTER_GLSL
#define FOOTPRINT_FILTER_GLSL
// footprint_filter.glsl - anisotropic filtering of a cube-map lookup over a pixel's footprint,
// done in the shader so that every device filters alike.
//
// A mirror pixel covers a parallelogram of lookup directions, spanned by the differences to
// its right and lower neighbours (d_dx, d_dy from lookup_gradients in mirror.glsl). textureGrad
// with those two vectors filters isotropically: one trilinear sample at the mip level of the
// LONGER side, so a footprint stretched towards the mirror's grazing rim (many texels long, one
// wide) is blurred across its width as much as along its length.
//
// Anisotropic filtering (the model of EXT_texture_filter_anisotropic) instead takes
// N = min(ceil(long / short), max_taps) trilinear samples spread evenly along the long side,
// each filtered at the level of the SHORT side (or of long / N, whichever is larger), and
// averages them. The sampler could do this (maxAnisotropy), but what a device does with it is
// its own choice: lavapipe 25 and SwiftShader ignore it for explicit gradients, GPUs use
// approximations of their own. Done here, the images are the same on every device, and
// `[cube] anisotropy` is the N a footprint may take.
//
// The short side is the parallelogram's height over the long one (area / long), not the other
// gradient's length: a sheared footprint is thin even when both of its gradients are long.
// Lengths are measured as angles (the gradients' parts across the lookup direction, over its
// length), which is what the cube map's texels tile; the sampler then projects each sample's
// gradients onto its face to choose the level, as for any textureGrad.
//
// Needs: max_taps >= 1, and each sample as FOOTPRINT_TAP(at, gx, gy): by default a
// trilinear textureGrad of the cube map `environment` declared before this file. The footprint
// pass (footprint_mark.comp) defines it to mark the texels the sample would read instead,
// so that what it marks is what this filter reads, tap for tap.
#ifndef FOOTPRINT_TAP
#define FOOTPRINT_TAP(at, gx, gy) textureGrad(environment, at, gx, gy).rgb
#endif

vec3 filter_footprint(vec3 lookup, vec3 d_dx, vec3 d_dy, float max_taps) {
    float len = length(lookup);
    if (!(len > 0.0)) {
        return FOOTPRINT_TAP(lookup, d_dx, d_dy); // no direction: as ever
    }
    vec3 axis = lookup / len;
    // Each gradient's part across the lookup direction, as an angle (radians): the part along
    // it only changes the vector's length, which a cube lookup ignores.
    vec3 across_x = (d_dx - dot(d_dx, axis) * axis) / len;
    vec3 across_y = (d_dy - dot(d_dy, axis) * axis) / len;
    bool x_longer = dot(across_x, across_x) >= dot(across_y, across_y);
    vec3 long_side = x_longer ? across_x : across_y;
    vec3 other_side = x_longer ? across_y : across_x;
    // The short side: the other gradient without its part along the long side.
    vec3 short_side =
        other_side - dot(other_side, long_side) / max(dot(long_side, long_side), 1e-30) * long_side;
    float taps = clamp(ceil(length(long_side) / max(length(short_side), 1e-30)), 1.0, max_taps);
    if (!(taps > 1.0)) {
        // Isotropic (or max_taps 1, or a degenerate footprint): the sampler's own filter.
        return FOOTPRINT_TAP(lookup, d_dx, d_dy);
    }
    // Back at the lookup vector's scale, which textureGrad reads its gradients against.
    vec3 step_along = long_side * (len / taps);
    vec3 across = short_side * len;
    vec3 sum = vec3(0.0);
    for (float k = 0.0; k < taps; k += 1.0) {
        // Sample centres at (k + 1/2) / N of the long side, centred on the pixel's lookup.
        vec3 at = lookup + ((k + 0.5) - 0.5 * taps) * step_along;
        sum += FOOTPRINT_TAP(at, step_along, across);
    }
    return sum / taps;
}

#endif
