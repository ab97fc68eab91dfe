//! Known answers of the shapes' geometry, in f64.

use glam::DVec3;

use super::Hyperboloid;

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
        let shape = h.shape();
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
    let shape = h.shape();
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
    let shape = super::sphere(1.0);
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
        let shape = p.shape();
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

/// Every registered shape: a unique kebab-case name, at most [`super::MAX_FIELDS`] fields with
/// unique names, and built from values in range it keeps them, in its kind's order, and holds
/// itself (its rim, its reach) in its reach.
#[test]
fn every_registered_shape_builds_from_its_fields_and_keeps_them() {
    let mut names = std::collections::BTreeSet::new();
    for kind in super::kinds() {
        assert!(names.insert(kind.name), "{} registered twice", kind.name);
        assert!(kind
            .name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c == '-'));
        assert!(kind.fields.len() <= super::MAX_FIELDS, "{}", kind.name);
        assert_eq!(super::kind(kind.name), Some(kind));
        // Values a robot's mirror might have: decreasing lengths, a mid-range angle.
        let values: Vec<f64> = (kind.fields.iter().enumerate())
            .map(|(i, f)| match f.unit {
                super::FieldUnit::Metres => 0.1 / (1.0 + i as f64),
                super::FieldUnit::Degrees { above, below } => 0.5 * (above + below) - 3.0,
            })
            .collect();
        let shape = (kind.build)(&values).unwrap_or_else(|e| panic!("{}: {e:?}", kind.name));
        assert_eq!(shape.kind, kind);
        for (f, v) in kind.fields.iter().zip(&values) {
            assert_eq!(shape.field(f.name), Some(*v), "{}.{}", kind.name, f.name);
            assert!(super::is_shape_field(f.name));
        }
        assert_eq!(shape.fields().count(), kind.fields.len());
        assert!(shape.reach_m > 0.0 && shape.reach_m.is_finite());
        if let Some((r, y)) = shape.rim() {
            assert!(r.hypot(y) <= shape.reach_m * (1.0 + 1e-12), "{}", kind.name);
        }
    }
    assert_eq!(super::kind("ellipsoid"), None);
    assert!(!super::is_shape_field("center"));
}

/// A cone of half-angle α turns a ray at θ from its axis to the elevation 90° − 2α + θ
/// (reflection across a flank that stands at 90° − α); the ray up the axis meets the apex,
/// which faces straight down.
#[test]
fn a_cone_reflects_each_ray_by_its_flank() {
    for (alpha, rim) in [(45.0, 1.0), (55.0, 1.0), (30.0, 0.02), (80.0, 0.5)] {
        let cone = super::Cone {
            half_angle_deg: alpha,
            rim_radius_m: rim,
        };
        let shape = cone.shape();
        let q = cone.quadric();
        assert!((q.rim_y - q.vertex_y - cone.height_m()).abs() < 1e-12);
        // The viewpoint is within the body (on the rim's disc for a wide cone).
        assert!(q.value(DVec3::ZERO) < 0.0 && q.vertex_y < 0.0 && q.rim_y >= 0.0);
        let camera = DVec3::new(0.0, q.vertex_y - 3.0 * rim, 0.0);
        let rim_angle = rim.atan2(q.rim_y - camera.y);
        for i in 1..50 {
            let theta = rim_angle * f64::from(i) / 50.0;
            let d = DVec3::new(theta.sin(), theta.cos(), 0.0);
            let hit = shape.hit(camera, d).expect("inside the rim's angle");
            let p = camera + hit.t * d;
            // On the flank: its radius is its height above the apex times tan α.
            let s = p.y - q.vertex_y;
            assert!((p.x - s * alpha.to_radians().tan()).abs() < 1e-12 * rim.max(1.0));
            let r = reflect(d, hit.normal);
            let elevation = r.y.asin().to_degrees();
            let want = 90.0 - 2.0 * alpha + theta.to_degrees();
            assert!(
                (elevation - want).abs() < 1e-9,
                "α {alpha}: {elevation} != {want}"
            );
        }
        let apex = shape.hit(camera, DVec3::Y).expect("the apex");
        assert_eq!(apex.normal, DVec3::NEG_Y);
        assert!((camera.y + apex.t - q.vertex_y).abs() < 1e-12);
        // Beyond the rim's angle, nothing.
        let past = rim_angle * 1.01;
        assert!(shape
            .hit(camera, DVec3::new(past.sin(), past.cos(), 0.0))
            .is_none());
    }
}

/// docs/scene-format.md's `[mirror]` table lists every registered shape and a row for each
/// of its fields.
#[test]
fn the_scene_format_doc_covers_every_shape_and_field() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let doc = std::fs::read_to_string(root.join("docs/scene-format.md")).unwrap();
    let shape_row = doc
        .lines()
        .find(|l| l.starts_with("| `shape` | string |"))
        .expect("the shape row");
    for kind in super::kinds() {
        assert!(
            shape_row.contains(&format!("`{}`", kind.name)),
            "{}",
            kind.name
        );
        for f in kind.fields {
            let row = doc
                .lines()
                .find(|l| l.starts_with(&format!("| `{}` |", f.name)))
                .unwrap_or_else(|| panic!("no row for mirror.{}", f.name));
            assert!(row.contains(&format!("`{}`", kind.name)), "{row}");
        }
    }
}
