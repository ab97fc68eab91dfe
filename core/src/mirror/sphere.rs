//! The thesis's mirror: a sphere about the viewpoint, seen by a pinhole on its axis. It is not
//! central: the reflected rays' lines do not meet in one point, so a cube map rendered at its
//! centre is looked up with a parallax error that the better lookups correct.

use glam::DVec3;

use super::{
    FieldUnit, MirrorShape, ShapeCamera, ShapeError, ShapeField, ShapeHit, ShapeKind, Surface,
};

pub(super) static KIND: ShapeKind = ShapeKind {
    name: "sphere",
    summary: "the thesis's mirror ball; a pinhole below it (non-central)",
    fields: &[ShapeField {
        name: "radius",
        unit: FieldUnit::Metres,
        doc: "the sphere's radius",
    }],
    build,
};

fn build(values: &[f64]) -> Result<MirrorShape, ShapeError> {
    // The renderer's radius is single precision; the record keeps what the file said.
    let mut shape = sphere(values[0] as f32);
    shape.values[0] = values[0];
    Ok(shape)
}

/// A sphere of radius `radius_m` about the viewpoint.
pub const fn sphere(radius_m: f32) -> MirrorShape {
    MirrorShape {
        kind: &KIND,
        surface: Surface::Sphere { radius_m },
        camera: ShapeCamera::Pinhole { distance_m: None },
        reach_m: radius_m as f64,
        xi: None,
        values: [radius_m as f64, 0.0, 0.0, 0.0],
    }
}

/// The sphere in f64 (the same careful form as the f32 one in `reference::intersect`).
pub(super) fn hit(o: DVec3, d: DVec3, r: f64) -> Option<ShapeHit> {
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
