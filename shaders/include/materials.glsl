// materials.glsl - albedo and shading. Written with plain float operations so that the CPU
// reference ray tracer mirrors each function line by line in Rust
// (core/src/reference/materials.rs); materials_check.comp runs them for the test that
// compares the two.
#ifndef MATERIALS_GLSL
#define MATERIALS_GLSL

#include "shared.glsl"

// The including shader declares the scene's bindings (SCENE_BINDINGS: `textures`) first and
// enables GL_EXT_nonuniform_qualifier (material_albedo indexes the texture array with it).
#ifndef GL_EXT_nonuniform_qualifier
#error "materials.glsl needs #extension GL_EXT_nonuniform_qualifier : require"
#endif

// Parity of the integer cell containing uv * tiles: 0 or 1.
float checker_parity(vec2 uv, float tiles) {
    vec2 cell = floor(uv * tiles);
    return mod(cell.x + cell.y, 2.0);
}

// 1 on a grid line, 0 inside a cell. Lines sit on the cell borders, width w (cell fraction).
float grid_line(vec2 uv, float tiles, float w) {
    vec2 f = fract(uv * tiles);
    vec2 on = step(f, vec2(0.5 * w)) + step(vec2(1.0 - 0.5 * w), f);
    return min(on.x + on.y, 1.0);
}

// The material's albedo (linear RGB) at a surface point. p is in render space, so the
// direction material's "from the mirror centre" is just normalize(p - mirror centre).
vec3 material_albedo(MaterialData m, vec3 p, vec2 uv) {
    uint kind = m.kind_texture.x;
    float tiles = m.params.x;
    if (kind == MATERIAL_CHECKER) {
        return mix(m.color_a.rgb, m.color_b.rgb, checker_parity(uv, tiles));
    } else if (kind == MATERIAL_GRID) {
        return mix(m.color_a.rgb, m.color_b.rgb, grid_line(uv, tiles, m.params.y));
    } else if (kind == MATERIAL_TEXTURE) {
        // Level 0, bilinear, sRGB decoded by the sampler. Explicit LOD: the sampler allows
        // only level 0 anyway, and this also runs in the compute check (no derivatives).
        // nonuniformEXT: one draw may shade several objects (a mesh-shader workgroup list,
        // instanced draws), so the texture slot need not be the same across the draw, and
        // indexing a descriptor array with a non-uniform value is undefined without it.
        uint slot = m.kind_texture.y;
        return m.color_a.rgb * textureLod(textures[nonuniformEXT(slot)], uv * tiles, 0.0).rgb;
    } else if (kind == MATERIAL_DIRECTION) {
        return 0.5 + 0.5 * normalize(p);
    }
    return m.color_a.rgb; // MATERIAL_COLOR
}

// Unlit albedo (the thesis), or albedo * (ambient + (1 - ambient) * max(0, N.L)).
vec3 shade(vec3 albedo, vec3 n, FrameData f) {
    if (f.flags.x == 0u) {
        return albedo;
    }
    float lambert = max(dot(normalize(n), f.light_dir_ambient.xyz), 0.0);
    float ambient = f.light_dir_ambient.w;
    return albedo * (ambient + (1.0 - ambient) * lambert);
}

#endif
