//! The mirror's shape: a plug-in with one home per shape (this folder), used by the scene
//! loader, the reference, the sensor's optics and, through the renderer's `FrameData`, the
//! shaders.
//!
//! - `sphere`: the thesis's mirror (non-central: the reflected rays do not pass through one
//!   point, so a cube lookup from its centre has a parallax error);
//! - `hyperboloid`: a central mirror (Baker and Nayar) seen by a perspective camera at its
//!   outer focus; every reflected ray's line passes through the inner focus, the viewpoint;
//! - `paraboloid`: a central mirror seen by an orthographic camera looking up its axis; every
//!   reflected ray's line passes through its focus;
//! - `cone`: the cheap non-central mirror, its apex pointing down at a pinhole on its axis.
//!
//! Every shape lives in the mirror's frame: its viewpoint (the sphere's centre, a central
//! mirror's inner focus, the centre of the smallest sphere holding a cone) at the origin, its
//! axis along +Y. The cube map is rendered from that point unless the scene moves it
//! (`cube.offset`), and the sensor camera sits on the axis below it.
//!
//! A shape is one module beside this file with a [`ShapeKind`] (its name, its scene fields
//! and how to build it from them) and one line in [`REGISTRY`]. What it builds is a
//! [`MirrorShape`]: the surface the shaders and the reference intersect (a sphere, or a
//! quadric of revolution cut at a rim: one branch of `mirror_hit` in
//! `shaders/include/mirror.glsl` each), its reach, its camera and, for a central shape, the
//! unified model's xi. A shape that is a quadric needs no GLSL of its own.

mod cone;
mod hyperboloid;
mod paraboloid;
mod quadric;
mod sphere;

use std::fmt;

pub use cone::Cone;
pub use hyperboloid::Hyperboloid;
pub use paraboloid::Paraboloid;
pub use quadric::{Quadric, ShapeHit};
pub use sphere::sphere;

use glam::DVec3;

/// Every mirror shape, in the order the docs and error messages list them. The sphere comes
/// first: it is the default.
static REGISTRY: &[&ShapeKind] = &[
    &sphere::KIND,
    &hyperboloid::KIND,
    &paraboloid::KIND,
    &cone::KIND,
];

/// One mirror shape: what the scene file calls it and how it is made from its fields.
pub struct ShapeKind {
    /// `mirror.shape` in the scene file.
    pub name: &'static str,
    /// One line for the docs and `specchio info`.
    pub summary: &'static str,
    /// The `[mirror]` fields it reads, all required, in order; `build` gets their values in
    /// this order, each already checked against its [`FieldUnit`].
    pub fields: &'static [ShapeField],
    /// Makes the shape, or says which field is wrong and why (geometry the renderer cannot
    /// draw faithfully: lengths beyond single precision, a camera inside the mirror).
    pub build: fn(&[f64]) -> Result<MirrorShape, ShapeError>,
}

impl fmt::Debug for ShapeKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name)
    }
}

/// Kinds are registry entries: equal when they are the same entry.
impl PartialEq for ShapeKind {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

/// A field of `[mirror]` a shape reads.
#[derive(Debug, Clone, Copy)]
pub struct ShapeField {
    /// The key in the scene file (`mirror.<name>`).
    pub name: &'static str,
    pub unit: FieldUnit,
    /// What it is, for the docs.
    pub doc: &'static str,
}

/// How the loader checks a field before the shape sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FieldUnit {
    /// A length in metres: finite and positive (in single precision too).
    Metres,
    /// An angle in degrees, strictly between the two bounds.
    Degrees { above: f64, below: f64 },
}

/// A field the shape refuses, and why (the loader adds the file and line).
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeError {
    /// The field's key without `mirror.`.
    pub field: &'static str,
    pub message: String,
}

/// The registered shapes, sphere first.
pub fn kinds() -> impl Iterator<Item = &'static ShapeKind> {
    REGISTRY.iter().copied()
}

/// The shape called `name` in a scene file.
pub fn kind(name: &str) -> Option<&'static ShapeKind> {
    kinds().find(|k| k.name == name)
}

/// Whether `key` is a field of some shape (the scene format reads those as numbers).
pub fn is_shape_field(key: &str) -> bool {
    kinds().any(|k| k.fields.iter().any(|f| f.name == key))
}

/// The surface the shaders and the reference intersect: one form per branch of `mirror_hit`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Surface {
    /// A sphere of this radius (m) about the viewpoint.
    Sphere { radius_m: f32 },
    /// A quadric of revolution about the axis, cut at its rim and closed there by a flat disc.
    Quadric(Quadric),
}

/// The sensor camera that goes with a shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ShapeCamera {
    /// A pinhole on the axis looking up: `distance_m` below the viewpoint where the shape
    /// fixes it (a hyperboloid's outer focus), else where the scene puts it (`sensor.offset`).
    Pinhole { distance_m: Option<f64> },
    /// An orthographic (telecentric) camera looking up the axis.
    Orthographic,
}

/// A mirror as every consumer sees it: what its plug-in made of the scene's fields.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MirrorShape {
    pub kind: &'static ShapeKind,
    pub surface: Surface,
    pub camera: ShapeCamera,
    /// The radius of the sphere about the viewpoint that holds the whole mirror (m).
    pub reach_m: f64,
    /// The unified (Mei) model's xi of a central shape with its camera at its focus.
    pub xi: Option<f64>,
    /// The values of the kind's fields, in its order (the rest 0): what the scene said.
    pub values: [f64; MAX_FIELDS],
}

/// The most fields a shape reads.
pub const MAX_FIELDS: usize = 4;

impl MirrorShape {
    /// The name the scene file uses.
    pub fn name(&self) -> &'static str {
        self.kind.name
    }

    /// The value of the field `name` (`"focal_distance"`) as the scene gave it; None for a
    /// field the shape does not read.
    pub fn field(&self, name: &str) -> Option<f64> {
        let i = self.kind.fields.iter().position(|f| f.name == name)?;
        Some(self.values[i])
    }

    /// Every field the shape reads, with its value, in the kind's order.
    pub fn fields(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        (self.kind.fields.iter().zip(self.values)).map(|(f, v)| (f.name, v))
    }

    /// The radius of the sphere about the viewpoint that holds the whole mirror (m): what
    /// the loader keeps objects and cameras out of, and the shaders' bounding box.
    pub fn bounding_radius_m(&self) -> f32 {
        self.reach_m as f32
    }

    /// Where the unit ray `o + t d` (mirror frame) first meets the mirror from outside, in
    /// f64. The sphere's f32 form, which the sensor's ray map and the shaders share, is
    /// `reference::intersect::ray_sphere`.
    pub fn hit(&self, o: DVec3, d: DVec3) -> Option<ShapeHit> {
        match self.surface {
            Surface::Sphere { radius_m } => sphere::hit(o, d, f64::from(radius_m)),
            Surface::Quadric(q) => q.hit(o, d),
        }
    }

    /// [`Self::hit`] on the surface continued past the rim (no disc on top), for a ray that
    /// grazes the rim's edge.
    pub fn surface_hit(&self, o: DVec3, d: DVec3) -> Option<ShapeHit> {
        match self.surface {
            Surface::Sphere { .. } => self.hit(o, d),
            Surface::Quadric(q) => Quadric {
                rim_y: f64::INFINITY,
                ..q
            }
            .hit(o, d),
        }
    }

    /// The distance below the viewpoint at which the shape's own camera sits (m): the outer
    /// focus of a hyperboloid; None where the scene chooses it (`sensor.offset`).
    pub fn camera_distance_m(&self) -> Option<f64> {
        match self.camera {
            ShapeCamera::Pinhole { distance_m } => distance_m,
            ShapeCamera::Orthographic => None,
        }
    }

    /// Whether the shape's camera is orthographic (looking up the axis with parallel rays).
    pub fn orthographic_camera(&self) -> bool {
        self.camera == ShapeCamera::Orthographic
    }

    /// The unified (Mei) model's xi of a central shape with its camera at its focus; None
    /// for a non-central one.
    pub fn xi(&self) -> Option<f64> {
        self.xi
    }

    /// The rim: its radius from the axis and its height above the viewpoint (m); None for
    /// the closed sphere.
    pub fn rim(&self) -> Option<(f64, f64)> {
        self.quadric().map(|q| (q.rim_r, q.rim_y))
    }

    /// The implicit quadric of a shape cut at a rim (what `shaders/include/quadric.glsl`
    /// intersects); None for the sphere, which the shaders intersect in its own careful form.
    pub fn quadric(&self) -> Option<Quadric> {
        match self.surface {
            Surface::Sphere { .. } => None,
            Surface::Quadric(q) => Some(q),
        }
    }
}

/// The smallest ratio between two of a quadric's lengths that single precision still
/// resolves in the shaders: its coefficients are ratios of squares of these lengths, and f32
/// keeps about 7 digits.
const MIN_LENGTH_RATIO: f64 = 1e-3;

/// Refuses `field`, `ratio` times another length (`other`, `other_m` long), beyond what
/// single precision resolves in a quadric's coefficients.
fn lengths_resolved(
    field: &'static str,
    ratio: f64,
    other: &str,
    other_m: f64,
) -> Result<(), ShapeError> {
    if (MIN_LENGTH_RATIO..=1.0 / MIN_LENGTH_RATIO).contains(&ratio) {
        return Ok(());
    }
    Err(ShapeError {
        field,
        message: format!(
            "is {} times {other} {} m; between {} and {} times is allowed (single precision \
             resolves the mirror's shape within that)",
            number(ratio),
            number(other_m),
            number(MIN_LENGTH_RATIO),
            number(1.0 / MIN_LENGTH_RATIO)
        ),
    })
}

/// A number for a message: as the scene loader writes them.
fn number(v: f64) -> String {
    crate::text::num_text(v)
}

#[cfg(test)]
mod tests;
