// sphere.glsl - ray / sphere intersection in the numerically careful form
// (Haines et al., "Precision Improvements for Ray/Sphere Intersection", Ray Tracing Gems ch. 7).
#ifndef SPHERE_GLSL
#define SPHERE_GLSL

// Nearest t > 0 with |o + t d - c| = r, for unit d; false on a miss or when o is inside.
bool intersect_sphere(vec3 o, vec3 d, vec3 c, float r, out float t) {
    vec3 f = o - c;
    float b = -dot(f, d);                 // distance along d to the closest approach
    vec3 l = f + b * d;                   // closest-approach vector, computed directly:
    float disc = r * r - dot(l, l);       // r^2 - |l|^2 avoids cancellation in b^2 - c
    if (disc < 0.0) {
        return false;
    }
    float cc = dot(f, f) - r * r;
    if (cc <= 0.0) {
        return false;                     // origin inside the sphere: no outside hit
    }
    float q = b + sign(b) * sqrt(disc);
    float t0 = cc / q;                    // the two roots without subtracting near-equals
    float t1 = q;
    t = min(t0, t1);
    return b > 0.0 && t > 0.0;
}

#endif
