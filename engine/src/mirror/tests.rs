//! Known answers of the shapes' geometry, in f64.

use glam::DVec3;

use super::{Hyperboloid, MirrorShape};

/// A hyperboloid of the kind a robot carries (d = 10 cm), the large one of the scenes, a flat
/// one and a nearly parabolic one.
fn hyperboloids() -> [Hyperboloid; 4] {
    [
        Hyperboloid {
            focal_distance_m: 0.1,
            latus_rectum_m: 0.04,
            rim_radius_m: 0.03,
        },
        Hyperboloid {
            focal_distance_m: 2.0,
            latus_rectum_m: 2.0,
            rim_radius_m: 1.3,
        },
        // Flat (p far above d: eccentricity about 400, nearly a cone).
        Hyperboloid {
            focal_distance_m: 0.01,
            latus_rectum_m: 4.0,
            rim_radius_m: 1.0,
        },
        // Nearly a paraboloid (p far below d: eccentricity 1.025).
        Hyperboloid {
            focal_distance_m: 4.0,
            latus_rectum_m: 0.2,
            rim_radius_m: 0.5,
        },
    ]
}

fn reflect(d: DVec3, n: DVec3) -> DVec3 {
    d - 2.0 * d.dot(n) * n
}

/// Directions towards the viewpoint from all around it, below the rim's elevation.
fn towards_viewpoint(max_elevation: f64) -> impl Iterator<Item = DVec3> {
    (0..24).flat_map(move |i| {
        (0..36).map(move |j| {
            let elevation = -1.5 + (max_elevation + 1.5) * f64::from(i) / 24.0;
            let azimuth = f64::from(j) * 10f64.to_radians();
            let (se, ce) = elevation.sin_cos();
            let out = DVec3::new(ce * azimuth.cos(), se, ce * azimuth.sin());
            -out
        })
    })
}

#[test]
fn a_ray_aimed_at_the_inner_focus_reflects_through_the_outer_one() {
    for h in hyperboloids() {
        let shape = MirrorShape::Hyperboloid(h);
        let q = h.quadric();
        let rim_elevation = q.rim_y.atan2(q.rim_r);
        let camera = DVec3::new(0.0, -h.focal_distance_m, 0.0);
        let mut hits = 0;
        for d in towards_viewpoint(rim_elevation - 1e-3) {
            let from = -d * 50.0 * h.focal_distance_m;
            let hit = shape
                .hit(from, d)
                .expect("aimed at the focus inside the mirror");
            let p = from + hit.t * d;
            let r = reflect(d, hit.normal);
            // The reflected line's distance from the outer focus, relative to the mirror's size.
            let miss = (camera - p).cross(r).length() / h.focal_distance_m;
            assert!(miss < 1e-9, "{h:?}: {d} reflects {miss} off the focus");
            assert!(r.dot(camera - p) > 0.0, "towards the camera, not away");
            // On the surface: |P F2| - |P F1| = 2a.
            let (a, _) = h.semi_axes();
            let gap = (p - camera).length() - p.length() - 2.0 * a;
            assert!(gap.abs() < 1e-12 * 50.0, "{gap}");
            hits += 1;
        }
        assert_eq!(hits, 24 * 36);
    }
}

#[test]
fn rays_above_the_rim_or_from_inside_miss_and_the_cap_faces_up() {
    let h = hyperboloids()[1];
    let shape = MirrorShape::Hyperboloid(h);
    let q = h.quadric();
    // Aimed at the viewpoint from above the rim's elevation: over the rim, into the cap.
    let down = DVec3::new(0.0, -1.0, 0.0);
    let hit = shape.hit(DVec3::new(0.2, 5.0, 0.1), down).expect("the cap");
    assert_eq!(hit.normal, DVec3::Y);
    assert!((5.0 - hit.t - q.rim_y).abs() < 1e-12);
    // Beside the rim, straight down: nothing.
    assert!(shape
        .hit(DVec3::new(q.rim_r + 1e-6, 5.0, 0.0), down)
        .is_none());
    // From the viewpoint (inside the body) outwards: nothing.
    assert!(shape.hit(DVec3::ZERO, DVec3::X).is_none());
    // Away from the mirror: nothing.
    assert!(shape.hit(DVec3::new(0.0, -3.0, 0.0), down).is_none());
}

#[test]
fn the_sphere_in_f64_agrees_with_the_references_f32_sphere() {
    let shape = MirrorShape::Sphere { radius_m: 1.0 };
    for i in 0..200 {
        let a = f64::from(i) * 0.1;
        let o = DVec3::new(3.0 * a.cos(), -2.0 + 0.01 * f64::from(i), 3.0 * a.sin());
        let d = (DVec3::new(0.3 * a.sin(), 0.2, 0.0) - o).normalize();
        let f64_hit = shape.hit(o, d).map(|h| h.t);
        let f32_hit = crate::reference::intersect::ray_sphere(
            o.as_vec3(),
            d.as_vec3(),
            glam::Vec3::ZERO,
            1.0,
        );
        match (f64_hit, f32_hit) {
            (Some(a), Some(b)) => assert!((a - f64::from(b)).abs() < 1e-5),
            (None, None) => {}
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn xi_is_d_over_the_hypotenuse_and_the_semi_axes_make_the_foci() {
    for h in hyperboloids() {
        let (a, b) = h.semi_axes();
        let c = 0.5 * h.focal_distance_m;
        assert!((a * a + b * b - c * c).abs() < 1e-12 * c * c.max(1.0));
        assert!((2.0 * b * b / a - h.latus_rectum_m).abs() < 1e-9 * h.latus_rectum_m);
        assert!(h.xi() > 0.0 && h.xi() < 1.0);
    }
    let h = hyperboloids()[0];
    // d = 0.1, 4p = 0.04: p = 0.01, 4p² = 0.0004.
    assert!((h.xi() - 0.1 / (0.01f64 + 0.0004).sqrt()).abs() < 1e-15);
}

#[test]
fn a_ray_aimed_at_a_paraboloids_focus_reflects_along_its_axis() {
    use super::Paraboloid;
    for p in [
        Paraboloid {
            latus_rectum_m: 2.0,
            rim_radius_m: 1.2,
        },
        Paraboloid {
            latus_rectum_m: 0.02,
            rim_radius_m: 0.03,
        },
    ] {
        let shape = MirrorShape::Paraboloid(p);
        let q = p.quadric();
        assert!(
            (q.rim_y - (p.rim_radius_m.powi(2) / p.latus_rectum_m - p.latus_rectum_m / 4.0)).abs()
                < 1e-12
        );
        let rim_elevation = q.rim_y.atan2(q.rim_r);
        let mut hits = 0;
        for d in towards_viewpoint(rim_elevation - 1e-3) {
            let from = -d * 100.0 * p.latus_rectum_m;
            let hit = shape
                .hit(from, d)
                .expect("aimed at the focus inside the mirror");
            let r = reflect(d, hit.normal);
            assert!(
                (r - DVec3::NEG_Y).length() < 1e-9,
                "{p:?}: {d} reflects to {r}"
            );
            // On the surface: as far from the focus as from the directrix y = -2p.
            let at = from + hit.t * d;
            let gap = at.length() - (at.y + 0.5 * p.latus_rectum_m);
            assert!(gap.abs() < 1e-12 * 100.0, "{gap}");
            hits += 1;
        }
        assert_eq!(hits, 24 * 36);
        // Straight up the axis (the quadratic's leading term is 0): the vertex, facing down.
        let up = shape
            .hit(DVec3::new(0.0, -5.0, 0.0), DVec3::Y)
            .expect("the vertex");
        assert!((up.t - (5.0 - 0.25 * p.latus_rectum_m)).abs() < 1e-12);
        assert_eq!(up.normal, DVec3::NEG_Y);
    }
}
