//! The mirror's shape: a plug-in with one home per shape (this folder), used by the scene
//! loader, the reference, the sensor's optics and, through the renderer's `FrameData`, the
//! shaders.
//!
//! - `sphere`: the thesis's mirror (non-central: the reflected rays do not pass through one
//!   point, so a cube lookup from its centre has a parallax error);
//! - `hyperboloid`: a central mirror (Baker and Nayar) seen by a perspective camera at its
//!   outer focus; every reflected ray's line passes through the inner focus, the viewpoint;
//! - `paraboloid`: a central mirror seen by an orthographic camera looking up its axis; every
//!   reflected ray's line passes through its focus.
//!
//! Every shape lives in the mirror's frame: its viewpoint (the sphere's centre, a central
//! mirror's inner focus) at the origin, its axis along +Y. The cube map is rendered from that
//! point, and the sensor camera sits on the axis below it.

mod hyperboloid;
mod paraboloid;
mod quadric;

pub use hyperboloid::Hyperboloid;
pub use paraboloid::Paraboloid;
pub use quadric::{Quadric, ShapeHit};

use glam::DVec3;

/// The mirror's surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MirrorShape {
    /// A sphere of this radius (m) about the viewpoint.
    Sphere {
        radius_m: f32,
    },
    Hyperboloid(Hyperboloid),
    Paraboloid(Paraboloid),
}

impl MirrorShape {
    /// The name the scene file uses.
    pub fn name(&self) -> &'static str {
        match self {
            MirrorShape::Sphere { .. } => "sphere",
            MirrorShape::Hyperboloid(_) => "hyperboloid",
            MirrorShape::Paraboloid(_) => "paraboloid",
        }
    }

    /// The radius of the sphere about the viewpoint that holds the whole mirror (m): what
    /// the loader keeps objects and cameras out of, and the shaders' bounding box.
    pub fn bounding_radius_m(&self) -> f32 {
        match self {
            MirrorShape::Sphere { radius_m } => *radius_m,
            MirrorShape::Hyperboloid(h) => h.bounding_radius_m() as f32,
            MirrorShape::Paraboloid(p) => p.bounding_radius_m() as f32,
        }
    }

    /// Where the unit ray `o + t d` (mirror frame) first meets the mirror from outside, in
    /// f64. The sphere's f32 form, which the sensor's ray map and the shaders share, is
    /// `reference::intersect::ray_sphere`.
    pub fn hit(&self, o: DVec3, d: DVec3) -> Option<ShapeHit> {
        match self {
            MirrorShape::Sphere { radius_m } => sphere_hit(o, d, f64::from(*radius_m)),
            _ => self
                .quadric()
                .expect("every other shape is a quadric")
                .hit(o, d),
        }
    }

    /// [`Self::hit`] on the surface continued past a central mirror's rim (no disc on top),
    /// for a ray that grazes the rim's edge.
    pub fn surface_hit(&self, o: DVec3, d: DVec3) -> Option<ShapeHit> {
        match self {
            MirrorShape::Sphere { .. } => self.hit(o, d),
            _ => Quadric {
                rim_y: f64::INFINITY,
                ..self.quadric().expect("every other shape is a quadric")
            }
            .hit(o, d),
        }
    }

    /// The distance below the viewpoint at which the shape's own camera sits (m): the outer
    /// focus of a hyperboloid; None where the scene chooses it (`sensor.offset`: the sphere's
    /// pinhole, the paraboloid's orthographic image plane).
    pub fn camera_distance_m(&self) -> Option<f64> {
        match self {
            MirrorShape::Hyperboloid(h) => Some(h.focal_distance_m),
            _ => None,
        }
    }

    /// Whether the shape's camera is orthographic (looking up the axis with parallel rays).
    pub fn orthographic_camera(&self) -> bool {
        matches!(self, MirrorShape::Paraboloid(_))
    }

    /// The unified (Mei) model's xi of a central shape with its camera at its focus; None
    /// for a non-central one.
    pub fn xi(&self) -> Option<f64> {
        match self {
            MirrorShape::Sphere { .. } => None,
            MirrorShape::Hyperboloid(h) => Some(h.xi()),
            MirrorShape::Paraboloid(_) => Some(1.0),
        }
    }

    /// The rim: its radius from the axis and its height above the viewpoint (m); None for
    /// the closed sphere.
    pub fn rim(&self) -> Option<(f64, f64)> {
        self.quadric().map(|q| (q.rim_r, q.rim_y))
    }

    /// The implicit quadric of a central shape (what `shaders/include/quadric.glsl`
    /// intersects); None for the sphere, which the shaders intersect in its own careful form.
    pub fn quadric(&self) -> Option<Quadric> {
        match self {
            MirrorShape::Sphere { .. } => None,
            MirrorShape::Hyperboloid(h) => Some(h.quadric()),
            MirrorShape::Paraboloid(p) => Some(p.quadric()),
        }
    }
}

/// The sphere in f64 (the same careful form as the f32 one).
fn sphere_hit(o: DVec3, d: DVec3, r: f64) -> Option<ShapeHit> {
    let b = -o.dot(d);
    let l = o + b * d;
    let disc = r * r - l.dot(l);
    let cc = o.dot(o) - r * r;
    if disc < 0.0 || cc <= 0.0 || b <= 0.0 {
        return None;
    }
    let q = b + disc.sqrt();
    let t = (cc / q).min(q);
    Some(ShapeHit {
        t,
        normal: (o + t * d).normalize(),
    })
}

#[cfg(test)]
mod tests;
