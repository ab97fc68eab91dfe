//! The hyperbolic mirror: one sheet of a hyperboloid of two sheets, seen by a perspective
//! camera at the outer focus. A ray aimed at the inner focus (the viewpoint) reflects off the
//! sheet towards the outer focus, so the camera sees the world as from one point (Baker and
//! Nayar 1999, "A theory of single-viewpoint catadioptric image formation").
//!
//! With the viewpoint at the origin and the outer focus at `-d` on the axis, the hyperbola's
//! centre is at `-d/2` and, with semi-axes `a` (along the axis) and `b`:
//!
//! ```text
//! (y + d/2)² / a² - r² / b² = 1,   a² + b² = (d/2)²,   latus rectum 4p = 2 b² / a
//! ```
//!
//! The scene gives `d` (`focal_distance`) and `4p` (`latus_rectum`), the two numbers the
//! unified model's xi is made of (Mei and Rives 2007, table 1): xi = d / sqrt(d² + 4p²)
//! (p itself, not 4p, squared).

use super::quadric::Quadric;
use super::{
    lengths_resolved, number, FieldUnit, MirrorShape, ShapeCamera, ShapeError, ShapeField,
    ShapeKind, Surface,
};

pub(super) static KIND: ShapeKind = ShapeKind {
    name: "hyperboloid",
    summary: "central: a perspective camera at the outer focus, the viewpoint at the inner one",
    fields: &[
        ShapeField {
            name: "focal_distance",
            unit: FieldUnit::Metres,
            doc: "d, the distance between the foci (the camera sits d below the viewpoint)",
        },
        ShapeField {
            name: "latus_rectum",
            unit: FieldUnit::Metres,
            doc: "4p, the chord through a focus square to the axis",
        },
        ShapeField {
            name: "rim_radius",
            unit: FieldUnit::Metres,
            doc: "the rim's distance from the axis",
        },
    ],
    build,
};

/// Refuses a hyperboloid the renderer cannot draw faithfully: lengths too different for
/// single precision, or a mirror that reaches past its own camera.
fn build(v: &[f64]) -> Result<MirrorShape, ShapeError> {
    let h = Hyperboloid {
        focal_distance_m: v[0],
        latus_rectum_m: v[1],
        rim_radius_m: v[2],
    };
    let d = h.focal_distance_m;
    lengths_resolved(
        "latus_rectum",
        h.latus_rectum_m / d,
        "the focal distance",
        d,
    )?;
    lengths_resolved("rim_radius", h.rim_radius_m / d, "the focal distance", d)?;
    let reach = h.bounding_radius_m();
    if reach >= d {
        return Err(ShapeError {
            field: "rim_radius",
            message: format!(
                "makes the mirror reach {} m from its viewpoint, at least as far as its camera \
                 at the outer focus {} m below it: the camera would be inside the mirror's \
                 reach; a smaller rim or a larger focal_distance keeps it outside",
                crate::text::approx_text(reach),
                number(d)
            ),
        });
    }
    Ok(h.shape())
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hyperboloid {
    /// d: the distance between the foci (m), > 0.
    pub focal_distance_m: f64,
    /// 4p: the chord through a focus square to the axis (m), > 0.
    pub latus_rectum_m: f64,
    /// The rim's radius from the axis (m), > 0.
    pub rim_radius_m: f64,
}

impl Hyperboloid {
    /// The mirror as its consumers see it.
    pub fn shape(&self) -> MirrorShape {
        MirrorShape {
            kind: &KIND,
            surface: Surface::Quadric(self.quadric()),
            camera: ShapeCamera::Pinhole {
                distance_m: Some(self.focal_distance_m),
            },
            reach_m: self.bounding_radius_m(),
            xi: Some(self.xi()),
            values: [
                self.focal_distance_m,
                self.latus_rectum_m,
                self.rim_radius_m,
                0.0,
            ],
        }
    }

    /// The semi-axes (a along the axis, b across it), from d and 4p: b² = 2ap and
    /// a² + b² = d²/4 give a² + 2pa - d²/4 = 0, whose positive root is written without
    /// cancelling `-p + sqrt(p² + d²/4)` for a flat (p much larger than d) hyperboloid.
    pub fn semi_axes(&self) -> (f64, f64) {
        let p = 0.25 * self.latus_rectum_m;
        let c = 0.5 * self.focal_distance_m;
        let a = c * c / (p + (p * p + c * c).sqrt());
        (a, (2.0 * a * p).sqrt())
    }

    /// The surface as the implicit quadric of `quadric.rs`, about the vertex (the centre y0 =
    /// -d/2 plus a): with s the height above the vertex, (a + s)²/a² − r²/b² = 1 is
    /// r² = (b²/a²) s² + (2b²/a) s = k s² + 4p s.
    pub fn quadric(&self) -> Quadric {
        let (a, b) = self.semi_axes();
        let k = (b * b) / (a * a);
        let y0 = -0.5 * self.focal_distance_m;
        let r = self.rim_radius_m;
        Quadric {
            a: -k,
            b: -self.latus_rectum_m,
            vertex_y: y0 + a,
            rim_y: y0 + a * (1.0 + (r * r) / (b * b)).sqrt(),
            rim_r: r,
            low_y: y0,
        }
    }

    /// The unified model's xi: d / sqrt(d² + 4p²), with p a quarter of the latus rectum.
    pub fn xi(&self) -> f64 {
        let (d, p) = (self.focal_distance_m, 0.25 * self.latus_rectum_m);
        d / d.hypot(2.0 * p)
    }

    /// The lowest point of the mirror, its vertex, below the viewpoint (m, negative).
    pub fn vertex_y(&self) -> f64 {
        -0.5 * self.focal_distance_m + self.semi_axes().0
    }

    /// The farthest point of the mirror from the viewpoint is on its rim: a point's distance
    /// from a focus grows along the sheet (r = e x - a), and the rim's disc lies inside it.
    pub fn bounding_radius_m(&self) -> f64 {
        let q = self.quadric();
        q.rim_r.hypot(q.rim_y).max(-self.vertex_y())
    }
}
