#version 460
// mirror.frag - the analytic mirror: the pixel-centre ray hits the sphere, reflects, and the
// reflected direction (world space, no texture-matrix rotation) looks up the cube map.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"
#include "sphere.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;
layout(set = 1, binding = 0) uniform samplerCube environment;

layout(location = 0) out vec4 out_color;

void main() {
    ViewData view = views[push.view_index];
    // The same pixel-centre ray the rasterizer samples (gl_FragCoord is the pixel centre).
    vec2 ndc = (gl_FragCoord.xy - view.viewport.xy) / view.viewport.zw * 2.0 - 1.0;
    vec3 dir = normalize(view.ray_forward.xyz + ndc.x * view.ray_right.xyz + ndc.y * view.ray_down.xyz);
    vec3 centre = frame.mirror.xyz;
    float radius = frame.mirror.w;
    float t;
    if (!intersect_sphere(view.eye.xyz, dir, centre, radius, t)) {
        discard;
    }
    // Normal from the sphere equation; the hit point is put back on the surface.
    vec3 n = normalize(view.eye.xyz + t * dir - centre);
    vec3 hit = centre + radius * n;
    vec3 r = reflect(dir, n); // R = I - 2 (N.I) N
    out_color = vec4(texture(environment, r).rgb, 1.0);
    vec4 clip = view.world_to_clip * vec4(hit, 1.0);
    gl_FragDepth = clip.z / clip.w;
}
