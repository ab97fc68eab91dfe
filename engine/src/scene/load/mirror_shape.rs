//! `mirror.shape` and the fields each shape reads: a sphere's `radius`; a hyperboloid's
//! `focal_distance`, `latus_rectum` and `rim_radius`; a paraboloid's `latus_rectum` and
//! `rim_radius`. A field another shape reads is refused,
//! so a scene never carries a number that does nothing.

use super::numbers::num_text;
use super::{Ctx, R};
use crate::mirror::{Hyperboloid, MirrorShape, Paraboloid};
use crate::scene::format::{MirrorShapeSpec, MirrorSpec};

/// The smallest ratio between a hyperboloid's lengths (d, 4p, rim radius) that single
/// precision still resolves in the shaders' quadric: its coefficients are ratios of squares
/// of these lengths, and f32 keeps about 7 digits.
const MIN_LENGTH_RATIO: f64 = 1e-3;

impl Ctx<'_> {
    pub(super) fn mirror_shape(&self, spec: &MirrorSpec) -> R<MirrorShape> {
        let shape = spec.shape.unwrap_or(MirrorShapeSpec::Sphere);
        let fields = [
            ("mirror.radius", spec.radius),
            ("mirror.focal_distance", spec.focal_distance),
            ("mirror.latus_rectum", spec.latus_rectum),
            ("mirror.rim_radius", spec.rim_radius),
        ];
        let reads: &[&str] = match shape {
            MirrorShapeSpec::Sphere => &["mirror.radius"],
            MirrorShapeSpec::Hyperboloid => &[
                "mirror.focal_distance",
                "mirror.latus_rectum",
                "mirror.rim_radius",
            ],
            MirrorShapeSpec::Paraboloid => &["mirror.latus_rectum", "mirror.rim_radius"],
        };
        let name = match shape {
            MirrorShapeSpec::Sphere => "sphere",
            MirrorShapeSpec::Hyperboloid => "hyperboloid",
            MirrorShapeSpec::Paraboloid => "paraboloid",
        };
        for (field, value) in fields {
            match (reads.contains(&field), value) {
                (true, None) => {
                    return Err(self.missing(field, &format!("a {name} mirror needs it")));
                }
                (false, Some(_)) => {
                    return Err(self.unused(
                        field,
                        &format!("a {name} mirror reads only {}", reads.join(", ")),
                    ));
                }
                _ => {}
            }
        }
        let value = |field: &str| fields.iter().find(|f| f.0 == field).and_then(|f| f.1);
        let length = |field: &str| -> R<f64> {
            let v = value(field).expect("checked above");
            self.positive(field, v)?; // finite, and positive in single precision too
            Ok(v)
        };
        match shape {
            MirrorShapeSpec::Sphere => Ok(MirrorShape::Sphere {
                radius_m: self.positive("mirror.radius", value("mirror.radius").unwrap())?,
            }),
            MirrorShapeSpec::Hyperboloid => {
                let h = Hyperboloid {
                    focal_distance_m: length("mirror.focal_distance")?,
                    latus_rectum_m: length("mirror.latus_rectum")?,
                    rim_radius_m: length("mirror.rim_radius")?,
                };
                self.hyperboloid_fits(&h)?;
                Ok(MirrorShape::Hyperboloid(h))
            }
            MirrorShapeSpec::Paraboloid => {
                let p = Paraboloid {
                    latus_rectum_m: length("mirror.latus_rectum")?,
                    rim_radius_m: length("mirror.rim_radius")?,
                };
                let ratio = p.rim_radius_m / p.latus_rectum_m;
                self.lengths_resolved(
                    "mirror.rim_radius",
                    ratio,
                    "the latus rectum",
                    p.latus_rectum_m,
                )?;
                Ok(MirrorShape::Paraboloid(p))
            }
        }
    }

    /// Refuses a hyperboloid the renderer cannot draw faithfully: lengths too different for
    /// single precision, or a mirror that reaches past its own camera.
    fn hyperboloid_fits(&self, h: &Hyperboloid) -> R<()> {
        let (d, l, r) = (h.focal_distance_m, h.latus_rectum_m, h.rim_radius_m);
        for (field, v) in [("mirror.latus_rectum", l), ("mirror.rim_radius", r)] {
            self.lengths_resolved(field, v / d, "the focal distance", d)?;
        }
        let reach = h.bounding_radius_m();
        if reach >= d {
            return Err(self.invalid(
                "mirror.rim_radius",
                format!(
                    "makes the mirror reach {} m from its viewpoint, as far as its camera at \
                     the outer focus ({} m below it): the camera would be inside the mirror's \
                     reach; a smaller rim or a larger focal_distance keeps it outside",
                    num_text(reach),
                    num_text(d)
                ),
            ));
        }
        Ok(())
    }

    /// Refuses a length `ratio` times another (`other`, `other_m` long) beyond what single
    /// precision resolves in the quadric's coefficients.
    fn lengths_resolved(&self, field: &str, ratio: f64, other: &str, other_m: f64) -> R<()> {
        if (MIN_LENGTH_RATIO..=1.0 / MIN_LENGTH_RATIO).contains(&ratio) {
            return Ok(());
        }
        Err(self.invalid(
            field,
            format!(
                "is {} times {other} {} m; between {} and {} times is allowed (single \
                 precision resolves the mirror's shape within that)",
                num_text(ratio),
                num_text(other_m),
                num_text(MIN_LENGTH_RATIO),
                num_text(1.0 / MIN_LENGTH_RATIO)
            ),
        ))
    }
}
