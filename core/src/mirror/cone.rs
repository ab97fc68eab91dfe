//! The conical mirror: the cheap non-central mirror, its apex pointing down at a pinhole on
//! its axis (`sensor.offset` below the viewpoint). Every generator line is straight, so the
//! camera's rays in one meridian plane all meet the same normal: the reflected rays' lines
//! meet no single point (the camera's reflections in the flanks form a circle around the
//! axis), and the apex itself, where the normal is undefined, shows the camera.
//!
//! As a quadric about its apex (s the height above it, α the half-angle between the axis and
//! the flank): x² + z² − tan²α s² = 0, a = −tan²α, b = 0, the body cut at the apex (below it
//! lies the other nappe) and at the rim. The viewpoint, where the cube map is rendered by
//! default, is the centre of the smallest sphere that holds the mirror: inside the body (on
//! the rim's disc, its boundary, for a cone no taller than its rim radius: α ≥ 45°).

use super::quadric::Quadric;
use super::{FieldUnit, MirrorShape, ShapeCamera, ShapeError, ShapeField, ShapeKind, Surface};

pub(super) static KIND: ShapeKind = ShapeKind {
    name: "cone",
    summary: "non-central: a cone, apex down, with a pinhole on its axis below it",
    fields: &[
        ShapeField {
            name: "half_angle",
            // tan between 1.7e-3 and 573: the quadric's a = −tan² stays within what single
            // precision resolves beside its other terms.
            unit: FieldUnit::Degrees {
                above: 0.1,
                below: 89.9,
            },
            doc: "α, the angle between the axis and the flank (degrees, 45 reflects the rays \
                  along the axis horizontally)",
        },
        ShapeField {
            name: "rim_radius",
            unit: FieldUnit::Metres,
            doc: "the rim's distance from the axis",
        },
    ],
    build,
};

fn build(v: &[f64]) -> Result<MirrorShape, ShapeError> {
    let cone = Cone {
        half_angle_deg: v[0],
        rim_radius_m: v[1],
    };
    Ok(cone.shape())
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cone {
    /// α: the angle between the axis and the flank (degrees), in (0, 90).
    pub half_angle_deg: f64,
    /// The rim's radius from the axis (m), > 0.
    pub rim_radius_m: f64,
}

impl Cone {
    /// The mirror as its consumers see it.
    pub fn shape(&self) -> MirrorShape {
        MirrorShape {
            kind: &KIND,
            surface: Surface::Quadric(self.quadric()),
            camera: ShapeCamera::Pinhole { distance_m: None },
            reach_m: self.bounding_radius_m(),
            xi: None,
            values: [self.half_angle_deg, self.rim_radius_m, 0.0, 0.0],
        }
    }

    /// The apex's height below the rim (m).
    pub fn height_m(&self) -> f64 {
        self.rim_radius_m / self.half_angle_deg.to_radians().tan()
    }

    /// The height above the apex of the viewpoint, the centre of the smallest sphere holding
    /// the cone: the rim's centre for a wide cone (the apex within a rim radius of it), else
    /// the point as far from the apex as from the rim, c = (h² + R²) / 2h.
    fn viewpoint_above_apex(&self) -> f64 {
        let (h, r) = (self.height_m(), self.rim_radius_m);
        if h <= r {
            h
        } else {
            (h * h + r * r) / (2.0 * h)
        }
    }

    pub fn quadric(&self) -> Quadric {
        let tan = self.half_angle_deg.to_radians().tan();
        let apex_y = -self.viewpoint_above_apex();
        Quadric {
            a: -tan * tan,
            b: 0.0,
            vertex_y: apex_y,
            rim_y: apex_y + self.height_m(),
            rim_r: self.rim_radius_m,
            low_y: apex_y,
        }
    }

    /// The radius of the smallest sphere holding the cone: the rim radius for a wide cone,
    /// else the apex's distance from the viewpoint.
    pub fn bounding_radius_m(&self) -> f64 {
        self.rim_radius_m.max(self.viewpoint_above_apex())
    }
}
