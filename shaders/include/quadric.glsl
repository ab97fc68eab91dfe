// quadric.glsl - ray / mirror intersection for every shape but the sphere: the hyperboloid,
// the paraboloid and the cone (each a quadric of revolution about the viewpoint's vertical
// axis), cut at its rim and closed there by a flat disc. core/src/mirror/quadric.rs is the
// same algorithm in f64.
//
// About its vertex (s the height above it, the axis +Y) the surface is
//     F(p) = x^2 + z^2 + a s^2 + b s = 0,  the mirror's inside F < 0,
// with no constant term: about the viewpoint, a flat hyperboloid's constant and s^2 terms are
// huge and nearly cancel at the mirror, beyond what f32 holds. The body is F < 0 between the
// height low_y (a hyperboloid's centre or a cone's apex: below it lies the other sheet or
// nappe) and the rim's height.
// It is convex, so a ray meets it in one interval.
#ifndef QUADRIC_GLSL
#define QUADRIC_GLSL

// Beyond every room (their corners are at most 1e12 m away): an interval's open end.
const float INF = 3.0e38;

// Heights are the vertex's frame's: above the vertex.
struct Quadric {
    vec2 ab;     // a, b
    float rim_y; // the rim's height
    float low_y; // the body's lowest height
};

// F at v (the vertex's frame).
float quadric_value(Quadric q, vec3 v) {
    return dot(v.xz, v.xz) + (q.ab.x * v.y + q.ab.y) * v.y;
}

// The outward unit normal at v (the vertex's frame): F's gradient.
vec3 quadric_normal(Quadric q, vec3 v) {
    vec3 g = vec3(v.x, q.ab.x * v.y + 0.5 * q.ab.y, v.z);
    // The gradient vanishes only at a cone's apex (b = 0), which has no tangent plane: it
    // faces straight down the axis, at the camera.
    return dot(g, g) > 0.0 ? normalize(g) : vec3(0.0, -1.0, 0.0);
}

// The ray's interval (from o) between the two cutting heights; false when it runs level
// outside them.
bool quadric_slab(Quadric q, vec3 o, vec3 d, out vec2 span) {
    if (d.y == 0.0) {
        span = vec2(-INF, INF);
        return o.y < q.rim_y && o.y > q.low_y;
    }
    float t_rim = (q.rim_y - o.y) / d.y;
    float t_low = (q.low_y - o.y) / d.y;
    span = vec2(min(t_rim, t_low), max(t_rim, t_low));
    return true;
}

// The root t of F along the ray o + t d, polished by one Newton step taken at its own point.
// Solved from o alone, a root carries the rounding of F(o), which for a wide flat mirror is
// large: its s^2 term (a = -10^6 at a latus rectum 10^3 times the focal distance) makes F of
// order 10^4 a few decimetres from the vertex, so f32's disc lost the root by micrometres,
// pixels where the rim plane meets the surface at 0.05 degrees. At the root's own point F is
// of the rounding of that point alone, and F is so nearly linear over a step that one step
// is enough. A step longer than `max_step` (half the distance to the other root) is not
// taken: near a double root (a grazing ray) the slope is itself rounding, and the step
// could throw the root anywhere.
float quadric_polish(Quadric q, vec3 o, vec3 d, float t, float max_step) {
    if (!(abs(t) < 1.0e15)) {
        return t; // beyond every room (and F there would overflow): nothing to polish
    }
    vec3 p = o + t * d;
    float slope = 2.0 * dot(vec3(p.x, q.ab.x * p.y + 0.5 * q.ab.y, p.z), d); // dF/dt at p
    float step = slope != 0.0 ? quadric_value(q, p) / slope : 0.0;
    return abs(step) <= max_step ? t - step : t;
}

// The intervals of the ray from o where F < 0: `count` of them (0, 1 or 2), in order.
int quadric_inside(Quadric q, vec3 o, vec3 d, out vec2 first, out vec2 second) {
    float qa = dot(d.xz, d.xz) + q.ab.x * d.y * d.y;       // F(o + t d) = qa t^2 + 2 hb t + qc
    float hb = dot(o.xz, d.xz) + (q.ab.x * o.y + 0.5 * q.ab.y) * d.y;
    float qc = quadric_value(q, o);
    first = vec2(-INF, INF);
    second = first;
    // Linear (a ray parallel to an asymptote): one root. Where qa is merely tiny, q / qa
    // below is a large root and qc / q the accurate small one.
    if (qa == 0.0) {
        if (hb == 0.0) {
            return qc < 0.0 ? 1 : 0;
        }
        float root = -qc / (2.0 * hb);
        first = hb < 0.0 ? vec2(root, INF) : vec2(-INF, root);
        return 1;
    }
    float disc = hb * hb - qa * qc;
    if (disc < 0.0) {
        return qa < 0.0 ? 1 : 0; // no crossing: inside everywhere or nowhere
    }
    // The roots without subtracting nearly equal numbers: q / qa and qc / q.
    float s = -(hb + (hb < 0.0 ? -1.0 : 1.0) * sqrt(disc));
    float r1 = s / qa;
    float r2 = s == 0.0 ? 0.0 : qc / s;
    float max_step = 0.5 * abs(r2 - r1);
    r1 = quadric_polish(q, o, d, r1, max_step);
    r2 = quadric_polish(q, o, d, r2, max_step);
    vec2 roots = vec2(min(r1, r2), max(r1, r2));
    if (qa > 0.0) {
        first = roots;
        return 1;
    }
    first = vec2(-INF, roots.x);
    second = vec2(roots.y, INF);
    return 2;
}

// Nearest t > 0 where the unit ray o + t d (the vertex's frame) enters the body, and the
// outward normal there; false on a miss or when o is inside. Solved from the ray's point
// nearest the vertex, so that an eye far from a small mirror keeps the coefficients of its
// size.
bool intersect_quadric(Quadric q, vec3 o, vec3 d, out float t, out vec3 n) {
    float t0 = -dot(o, d);
    vec3 o0 = o + t0 * d;
    vec2 slab;
    if (!quadric_slab(q, o0, d, slab)) {
        return false;
    }
    vec2 spans[2];
    int count = quadric_inside(q, o0, d, spans[0], spans[1]);
    for (int i = 0; i < count; i++) {
        float lo = max(spans[i].x, slab.x);
        float hi = min(spans[i].y, slab.y);
        if (lo < hi) {
            t = t0 + lo;
            if (!(t > 0.0) || t >= INF) {
                return false; // starts inside, or the body lies behind the ray
            }
            // Entered through the rim's disc where its plane bounds the interval.
            n = slab.x > spans[i].x ? vec3(0.0, 1.0, 0.0) : quadric_normal(q, o0 + lo * d);
            return true;
        }
    }
    return false;
}

// Where the ray meets the surface continued past the rim (no disc on top): for the footprint
// of a pixel whose neighbour passes beside the rim. False where it misses that too.
bool quadric_surface_normal(Quadric q, vec3 o, vec3 d, out float t, out vec3 n) {
    Quadric open_q = q;
    open_q.rim_y = INF;
    return intersect_quadric(open_q, o, d, t, n);
}

#endif
