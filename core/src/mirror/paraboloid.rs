//! The parabolic mirror, seen by an orthographic (telecentric) camera looking up its axis. A
//! ray aimed at the focus (the viewpoint) reflects off the paraboloid parallel to the axis,
//! straight down into the camera, so the camera sees the world as from one point (Nayar 1997,
//! "Catadioptric omnidirectional camera").
//!
//! With the focus at the origin and the axis +Y, the surface is y = r² / 4p − p: its vertex p
//! below the focus, 4p its latus rectum (`latus_rectum` in the scene, as for the hyperboloid).
//! The unified model has xi = 1 and a focal length 2p times the camera's pixels per metre
//! (Mei and Rives 2007, table 1).

use super::quadric::Quadric;
use super::{
    lengths_resolved, FieldUnit, MirrorShape, ShapeCamera, ShapeError, ShapeField, ShapeKind,
    Surface,
};

pub(super) static KIND: ShapeKind = ShapeKind {
    name: "paraboloid",
    summary: "central: an orthographic camera looking up the axis, the viewpoint at the focus",
    fields: &[
        ShapeField {
            name: "latus_rectum",
            unit: FieldUnit::Metres,
            doc: "4p, the chord through the focus square to the axis",
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
    let p = Paraboloid {
        latus_rectum_m: v[0],
        rim_radius_m: v[1],
    };
    let ratio = p.rim_radius_m / p.latus_rectum_m;
    lengths_resolved("rim_radius", ratio, "the latus rectum", p.latus_rectum_m)?;
    Ok(p.shape())
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Paraboloid {
    /// 4p: the chord through the focus square to the axis (m), > 0.
    pub latus_rectum_m: f64,
    /// The rim's radius from the axis (m), > 0.
    pub rim_radius_m: f64,
}

impl Paraboloid {
    /// The mirror as its consumers see it.
    pub fn shape(&self) -> MirrorShape {
        MirrorShape {
            kind: &KIND,
            surface: Surface::Quadric(self.quadric()),
            camera: ShapeCamera::Orthographic,
            reach_m: self.bounding_radius_m(),
            xi: Some(1.0),
            values: [self.latus_rectum_m, self.rim_radius_m, 0.0, 0.0],
        }
    }

    /// p: the focal length, the vertex's distance below the focus (m).
    pub fn focal_length_m(&self) -> f64 {
        0.25 * self.latus_rectum_m
    }

    /// F = r² − 4p s about the vertex (s the height above it), no lower cut.
    pub fn quadric(&self) -> Quadric {
        let p = self.focal_length_m();
        let r = self.rim_radius_m;
        Quadric {
            a: 0.0,
            b: -4.0 * p,
            vertex_y: -p,
            rim_y: r * r / (4.0 * p) - p,
            rim_r: r,
            low_y: f64::NEG_INFINITY,
        }
    }

    /// The farthest point of the mirror from the focus is on its rim: a point's distance from
    /// the focus is its height above the directrix (y + 2p), largest at the rim.
    pub fn bounding_radius_m(&self) -> f64 {
        self.quadric().rim_y + 2.0 * self.focal_length_m()
    }
}
