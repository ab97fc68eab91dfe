// pixel_hit.glsl - what one sensor pixel's centre ray found, the input of every per-pixel
// quantity of the ray map (include/quantities/*.glsl). Its CPU twin, field for field, is
// core/src/sensor/quantities/mod.rs's PixelHit, from which the reference computes the same
// quantities.
#ifndef PIXEL_HIT_GLSL
#define PIXEL_HIT_GLSL

struct PixelHit {
    vec3 mirror_point; // where the ray meets the mirror, render space (from the mirror's centre)
    vec3 reflected;    // the unit reflected direction
    float range;       // metres along the reflected ray to what it meets
    uint id;           // the drawable it meets: walls 0..6, objects 6 + i
};

#endif
