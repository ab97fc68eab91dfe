//! The central mirrors' surfaces: quadrics of revolution about the vertical axis through the
//! viewpoint, cut at a rim and closed there by a flat disc, in f64.
//!
//! Every shape but the sphere is written as one implicit function about its vertex (the axis
//! along +Y, the vertex `vertex_y` above the viewpoint, s = y − vertex_y the height above it):
//!
//! ```text
//! F(p) = x² + z² + a s² + b s        the surface is F = 0, the mirror's inside F < 0
//! ```
//!
//! (a hyperboloid: a = −b²/a², b = −4p; a paraboloid: a = 0, b = −4p; a cone: a = −tan²α,
//! b = 0). About the vertex there is
//! no constant term: written about the viewpoint, a flat hyperboloid's constant and its s²
//! term are huge and nearly cancel at the mirror, which f32 cannot hold (a latus rectum 10³
//! times the focal distance drew noise). The body is `F < 0` between two heights: the rim's
//! (`rim_y`, where a flat disc closes the body on top) and `low_y` (the hyperboloid's centre,
//! which cuts off the second sheet; a cone's apex, below which lies its other nappe; minus
//! infinity for the paraboloid). That body is convex,
//! so a ray meets it in one interval, and a reflected ray never meets the mirror again.
//! `shaders/include/quadric.glsl` is the same algorithm in f32.

use glam::DVec3;

/// Where a ray enters a mirror and the outward unit normal there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapeHit {
    /// Distance along the (unit) ray.
    pub t: f64,
    pub normal: DVec3,
}

/// A quadric of revolution about +Y, cut at the rim (see the module's comment). Heights are
/// above the viewpoint (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quadric {
    pub a: f64,
    pub b: f64,
    /// The vertex's height, where F's frame has its origin.
    pub vertex_y: f64,
    /// The rim's height and its radius from the axis (m).
    pub rim_y: f64,
    pub rim_r: f64,
    /// The lowest height the body reaches down to (m): the hyperboloid's centre, below which
    /// lies the sheet that is not the mirror; `-inf` where there is none.
    pub low_y: f64,
}

/// The parameter interval `(lo, hi)` of a ray inside a region (either end may be infinite).
type Span = (f64, f64);

impl Quadric {
    /// F at `p` (the viewpoint's frame): negative inside the mirror's surface.
    pub fn value(&self, p: DVec3) -> f64 {
        self.value_about_vertex(p - self.vertex())
    }

    /// The outward unit normal of the surface at `p` (the viewpoint's frame): F's gradient.
    pub fn normal(&self, p: DVec3) -> DVec3 {
        self.normal_about_vertex(p - self.vertex())
    }

    fn vertex(&self) -> DVec3 {
        DVec3::new(0.0, self.vertex_y, 0.0)
    }

    fn value_about_vertex(&self, v: DVec3) -> f64 {
        v.x * v.x + v.z * v.z + (self.a * v.y + self.b) * v.y
    }

    fn normal_about_vertex(&self, v: DVec3) -> DVec3 {
        // F's gradient vanishes only at a cone's apex (b = 0), where the surface has no
        // tangent plane: the apex faces straight down the axis, at the camera.
        DVec3::new(v.x, self.a * v.y + 0.5 * self.b, v.z)
            .try_normalize()
            .unwrap_or(DVec3::NEG_Y)
    }

    /// Where the unit ray `o + t d` (t > 0, the viewpoint's frame) enters the body, or None
    /// when it misses it or starts inside it.
    pub fn hit(&self, o: DVec3, d: DVec3) -> Option<ShapeHit> {
        // Solved about the vertex, from the ray's point nearest it: for an eye far from a small
        // mirror the coefficients then stay of the mirror's size (no cancellation).
        let from_vertex = o - self.vertex();
        let t0 = -from_vertex.dot(d);
        let o0 = from_vertex + t0 * d;
        let slab = self.slab(o0, d)?;
        // The body is convex, so at most one of F's inside intervals meets the slab.
        let (lo, from_cap) = self
            .inside_spans(o0, d)
            .into_iter()
            .flatten()
            .map(|span| (span.0.max(slab.0), span.1.min(slab.1), slab.0 > span.0))
            .find(|&(lo, hi, _)| lo < hi)
            .map(|(lo, _, cap)| (lo, cap))?;
        let t = t0 + lo;
        if !(t > 0.0 && t.is_finite()) {
            return None; // starts inside, or the body lies behind the ray
        }
        // Entered through a cutting plane: the rim's disc (F is positive all over the
        // hyperboloid's centre plane, so no ray enters through that one).
        let normal = if from_cap {
            DVec3::Y
        } else {
            self.normal_about_vertex(o0 + lo * d)
        };
        Some(ShapeHit { t, normal })
    }

    /// The interval of the ray (from `o`, about the vertex) between the two cutting heights.
    fn slab(&self, o: DVec3, d: DVec3) -> Option<Span> {
        let (rim, low) = (self.rim_y - self.vertex_y, self.low_y - self.vertex_y);
        if d.y == 0.0 {
            let inside = o.y < rim && o.y > low;
            return inside.then_some((f64::NEG_INFINITY, f64::INFINITY));
        }
        let (t_rim, t_low) = ((rim - o.y) / d.y, (low - o.y) / d.y);
        Some((t_rim.min(t_low), t_rim.max(t_low)))
    }

    /// The root `t` of F along the ray `o + t d` (about the vertex), polished by one Newton
    /// step taken at its own point. Solved from `o` alone, a root carries the rounding of
    /// F(o), which for a wide flat mirror is large (its s² coefficient is −10⁶ at a latus
    /// rectum 10³ times the focal distance); at the root's own point F carries only that
    /// point's rounding. f64 hardly needs it; the shader's f32 lost pixels of the rim without
    /// it, and the two keep one algorithm. A step longer than `max_step` (half the distance to
    /// the other root) is not taken: near a double root the slope is rounding itself.
    fn polish(&self, o: DVec3, d: DVec3, t: f64, max_step: f64) -> f64 {
        if !t.is_finite() || t.abs() >= 1e15 {
            return t; // beyond every room: nothing to polish (and the shader's F overflows)
        }
        let p = o + t * d;
        let slope = 2.0 * DVec3::new(p.x, self.a * p.y + 0.5 * self.b, p.z).dot(d);
        let step = self.value_about_vertex(p) / slope;
        if slope != 0.0 && step.abs() <= max_step {
            t - step
        } else {
            t
        }
    }

    /// The (at most two) intervals of the ray from `o` (about the vertex) where F < 0, in
    /// order.
    fn inside_spans(&self, o: DVec3, d: DVec3) -> [Option<Span>; 2] {
        // F(o + t d) = qa t² + 2 hb t + qc.
        let qa = d.x * d.x + d.z * d.z + self.a * d.y * d.y;
        let hb = o.x * d.x + o.z * d.z + self.a * o.y * d.y + 0.5 * self.b * d.y;
        let qc = self.value_about_vertex(o);
        let (inf, ninf) = (f64::INFINITY, f64::NEG_INFINITY);
        if qa == 0.0 {
            // Linear: a ray along the paraboloid's axis, or parallel to an asymptote.
            let root = -qc / (2.0 * hb);
            return if hb < 0.0 {
                [Some((root, inf)), None]
            } else if hb > 0.0 {
                [Some((ninf, root)), None]
            } else {
                [(qc < 0.0).then_some((ninf, inf)), None]
            };
        }
        let disc = hb * hb - qa * qc;
        if disc < 0.0 {
            // No crossing: inside everywhere or nowhere, as the leading term's sign says.
            return [(qa < 0.0).then_some((ninf, inf)), None];
        }
        // The two roots without subtracting nearly equal numbers: q / qa and qc / q (q is 0
        // only when both roots are).
        let q = -(hb + hb.signum() * disc.sqrt());
        let (r1, r2) = if q == 0.0 {
            (0.0, 0.0)
        } else {
            let (r1, r2) = (q / qa, qc / q);
            let max_step = 0.5 * (r2 - r1).abs();
            (
                self.polish(o, d, r1, max_step),
                self.polish(o, d, r2, max_step),
            )
        };
        let (lo, hi) = (r1.min(r2), r1.max(r2));
        if qa > 0.0 {
            [Some((lo, hi)), None]
        } else {
            [Some((ninf, lo)), Some((hi, inf))]
        }
    }
}
