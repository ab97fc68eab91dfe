//! `mirror.shape` and its fields: every bad value refused with its field and line, the
//! hyperboloid's camera and field of view derived from its geometry.

use std::path::Path;

use crate::mirror::Hyperboloid;
use crate::scene::load_str;

/// A room with a hyperboloid: `mirror` replaces the [mirror] table's body.
fn with_mirror(mirror: &str, extra: &str) -> String {
    format!(
        "[room]\ncenter = [0, 3, 0]\nsize = [10, 6, 10]\nwalls = \"w\"\n\
         [mirror]\ncenter = [0, 3, 0]\n{mirror}\n\
         [[materials]]\nname = \"w\"\ntype = \"color\"\ncolor = [0.5, 0.5, 0.5]\n{extra}"
    )
}

const HYPERBOLOID: &str =
    "shape = \"hyperboloid\"\nfocal_distance = 2\nlatus_rectum = 2\nrim_radius = 1.3";

#[test]
fn a_hyperboloid_puts_its_camera_at_the_outer_focus_and_fits_the_rim() {
    let s = load_str(&with_mirror(HYPERBOLOID, ""), Path::new("h.toml")).unwrap();
    let h = Hyperboloid {
        focal_distance_m: 2.0,
        latus_rectum_m: 2.0,
        rim_radius_m: 1.3,
    };
    assert_eq!(s.mirror.shape, h.shape());
    assert_eq!(s.sensor.offset_m, 2.0);
    assert_eq!(
        f64::from(s.mirror.radius_m),
        h.bounding_radius_m() as f32 as f64
    );
    // The default field of view holds the rim with a 5 % margin on the shorter side.
    let (rim_r, rim_y) = s.mirror.shape.rim().unwrap();
    let rim_tan = rim_r / (rim_y + 2.0);
    let half = (f64::from(s.sensor.fov_y_deg).to_radians() / 2.0).tan();
    assert!(
        (half - 1.05 * rim_tan).abs() < 1e-5,
        "{half} against {rim_tan}"
    );
    // A misaligned camera: moved and turned as the file says.
    let text = with_mirror(HYPERBOLOID, "[sensor]\nshift = [0.001, 0, 0]\ntilt = 1\n");
    let m = load_str(&text, Path::new("m.toml")).unwrap();
    assert_eq!(m.sensor.shift_m, glam::Vec3::new(0.001, 0.0, 0.0));
    let view = m.sensor.view(m.sensor.up, 1.0);
    assert_eq!(view.eye, glam::Vec3::new(0.001, -2.0, 0.0));
    assert!((view.forward.z.atan2(view.forward.y).to_degrees() - 1.0).abs() < 1e-4);
    assert!(view.forward.z > 0.0, "tilted towards +Z");
    // The robot's heading turns the whole camera, its misalignment with it: the view at a
    // heading is the view at 0 turned about +Y.
    let mut turned = m.sensor.clone();
    turned.heading_rad = 1.0;
    let (v0, v1) = (view, turned.view(turned.up, 1.0));
    let turn = glam::Quat::from_rotation_y(1.0);
    for (a, b) in [
        (v0.eye, v1.eye),
        (v0.forward, v1.forward),
        (v0.right, v1.right),
        (v0.down, v1.down),
    ] {
        assert!((turn * a - b).length() < 1e-6, "{a} turned is not {b}");
    }
    // A paraboloid: an orthographic camera that fits the rim, as far again below the mirror as
    // it reaches, or halfway from its reach to the floor where that is nearer (here: the
    // viewpoint 3 m above the floor, (1.22 + 3) / 2 = 2.11 < 2.44).
    let para = "shape = \"paraboloid\"\nlatus_rectum = 2\nrim_radius = 1.2";
    let p = load_str(&with_mirror(para, ""), Path::new("p.toml")).unwrap();
    assert_eq!(p.mirror.radius_m, 1.22);
    assert!((p.sensor.offset_m - 0.5 * (1.22 + 3.0)).abs() < 1e-6);
    let high = with_mirror(para, "").replace("size = [10, 6, 10]", "size = [10, 16, 10]");
    let p_high = load_str(&high, Path::new("p.toml")).unwrap();
    assert_eq!(p_high.sensor.offset_m, 2.0 * 1.22);
    assert!((p.sensor.orthographic_half_m - 1.05 * 1.2).abs() < 1e-6);
    let view = p.sensor.view(p.sensor.up, 1.0);
    assert!(view.is_orthographic() && view.tan_y == 0.0);
    // The sphere is still the default shape.
    let sphere = load_str(&with_mirror("radius = 1", ""), Path::new("s.toml")).unwrap();
    assert_eq!(sphere.mirror.shape, crate::mirror::sphere(1.0));
}

#[test]
fn bad_mirror_shapes_are_refused_naming_the_field() {
    let cases: &[(&str, &str, &str)] = &[
        ("shape = \"ellipsoid\"\nradius = 1", "", "mirror.shape"),
        ("shape = \"sphere\"", "", "mirror.radius: required field is missing"),
        ("radius = 1\nrim_radius = 0.5", "", "mirror.rim_radius: not allowed here: a sphere mirror reads only mirror.radius"),
        (&format!("{HYPERBOLOID}\nradius = 1"), "", "mirror.radius: not allowed here: a hyperboloid mirror reads only"),
        ("shape = \"hyperboloid\"\nfocal_distance = 2\nrim_radius = 1", "", "mirror.latus_rectum: required field is missing"),
        ("shape = \"hyperboloid\"\nfocal_distance = 0\nlatus_rectum = 2\nrim_radius = 1", "", "mirror.focal_distance: must be positive"),
        ("shape = \"hyperboloid\"\nfocal_distance = 2\nlatus_rectum = -1\nrim_radius = 1", "", "mirror.latus_rectum: must be positive"),
        // Degenerate: a hyperboloid 10^4 times flatter than its focal distance.
        ("shape = \"hyperboloid\"\nfocal_distance = 0.001\nlatus_rectum = 10\nrim_radius = 0.0005", "", "mirror.latus_rectum: is 10000 times the focal distance"),
        // A rim wider than the camera's distance: the camera would be inside the mirror's reach.
        ("shape = \"hyperboloid\"\nfocal_distance = 2\nlatus_rectum = 2\nrim_radius = 2.5", "", "mirror.rim_radius: makes the mirror reach"),
        // The camera at the outer focus below the floor.
        ("shape = \"hyperboloid\"\nfocal_distance = 3.5\nlatus_rectum = 2\nrim_radius = 1", "", "mirror.focal_distance: puts the sensor at y = -0.5"),
        (HYPERBOLOID, "[sensor]\noffset = 2\n", "sensor.offset: not allowed here: a hyperboloid mirror's camera sits at its outer focus"),
        // A field of view that cuts off the rim (it is 30.6 degrees from the axis).
        (HYPERBOLOID, "[sensor]\nfov_y = 50\n", "sensor.fov_y: cuts off the mirror"),
        (HYPERBOLOID, "[sensor]\nfov_y = 80\nresolution = [200, 400]\n", "sensor.fov_y: cuts off the mirror"),
        // An up direction along the tilted axis leaves the camera no right direction (NaN).
        (HYPERBOLOID, "[sensor]\ntilt = 30\nup = [0, 0.8660254, 0.5]\n", "sensor.up: must be non-zero and not parallel to the camera's axis"),
        // A tilt or a shift that takes the rim out of the image, or the camera out of the room.
        (HYPERBOLOID, "[sensor]\ntilt = 45\n", "sensor.tilt: turns or moves the camera so that the hyperboloid mirror's rim leaves the image"),
        (HYPERBOLOID, "[sensor]\nshift = [0.5, 0, 0]\n", "sensor.shift: turns or moves the camera"),
        (HYPERBOLOID, "[sensor]\nshift = [20, 0, 0]\n", "sensor.shift: puts the sensor at [20, 1, 0] (t = 0.000 s), outside the room"),
        (HYPERBOLOID, "[sensor]\nshift = [0, -1.5, 0]\n", "sensor.shift: puts the sensor at y = -0.5"),
        // A derived field of view beyond 179.99 degrees: the image too narrow for the rim.
        ("shape = \"hyperboloid\"\nfocal_distance = 0.5\nlatus_rectum = 10\nrim_radius = 0.4", "[sensor]\nresolution = [1, 8192]\n", "sensor.resolution: is too narrow for the mirror: fitting its rim across the image's width needs a vertical field of view of 179.99089 degrees, more than the 179.99 a camera may have; give the image more columns"),
        // Below 0.1 degrees: the mirror too small from the camera, said as the distance.
        ("shape = \"cone\"\nhalf_angle = 45\nrim_radius = 1e-5", "", "mirror.rim_radius: the mirror's rim is 0.00022918312 degrees from the camera's axis with the camera 2.5 m from the mirror (sensor.offset), and fitting it needs a vertical field of view of 0.0004812845 degrees, less than the 0.1 a camera may have"),
        // A room too large for the mirror's reach names the shape's own size field.
        ("shape = \"hyperboloid\"\nfocal_distance = 0.000001\nlatus_rectum = 0.000001\nrim_radius = 0.0000005", "", "mirror.rim_radius: is too small for the room"),
        // Misalignment: a tilt past 45 degrees, a shift into the mirror's reach.
        (HYPERBOLOID, "[sensor]\ntilt = 50\n", "sensor.tilt: must be in [0, 45]"),
        (HYPERBOLOID, "[sensor]\ntilt = -1\n", "sensor.tilt"),
        (HYPERBOLOID, "[sensor]\nshift = [0, 1.5, 0]\n", "sensor.shift: moves the sensor to 0.5 m from the mirror's viewpoint"),
        (HYPERBOLOID, "[sensor]\nshift = [0, 0]\n", "sensor.shift"),
        // The paraboloid: its own fields, an orthographic camera without a field of view.
        ("shape = \"paraboloid\"\nlatus_rectum = 2\nrim_radius = 1.2\nfocal_distance = 2", "", "mirror.focal_distance: not allowed here: a paraboloid mirror reads only mirror.latus_rectum, mirror.rim_radius"),
        ("shape = \"paraboloid\"\nlatus_rectum = 2", "", "mirror.rim_radius: required field is missing"),
        ("shape = \"paraboloid\"\nlatus_rectum = 2\nrim_radius = 1.2", "[sensor]\nfov_y = 60\n", "sensor.fov_y: not allowed here: a paraboloid's camera is orthographic"),
        ("shape = \"paraboloid\"\nlatus_rectum = 2\nrim_radius = 2500", "", "mirror.rim_radius: is 1250 times the latus rectum"),
        ("shape = \"paraboloid\"\nlatus_rectum = 2\nrim_radius = 1.2", "[sensor]\noffset = 1\n", "sensor.offset: must be greater than the mirror's reach from its centre (1.22 m)"),
        // The cone, and what every shape's fields get from the registry.
        ("shape = \"cone\"\nhalf_angle = 90\nrim_radius = 1", "", "mirror.half_angle: must be in (0.1, 89.9)"),
        ("shape = \"cone\"\nhalf_angle = 0.05\nrim_radius = 1", "", "mirror.half_angle: must be in (0.1, 89.9)"),
        ("shape = \"cone\"\nhalf_angle = \"45\"\nrim_radius = 1", "", "mirror.half_angle: invalid type: string, expected a number"),
        ("shape = \"cone\"\nhalf_angle = 45\nrim_radius = 1\nradius = 1", "", "mirror.radius: not allowed here: a cone mirror reads only mirror.half_angle, mirror.rim_radius"),
        ("shape = \"cone\"\nrim_radius = 1", "", "mirror.half_angle: required field is missing (a cone mirror needs it)"),
        ("radius = 1\nraduis = 1", "", "mirror.raduis: unknown field `raduis`, expected one of `shape`, `center`"),
        ("shape = \"ellipsoid\"\nradius = 1", "", "unknown mirror shape \"ellipsoid\" (known: sphere, hyperboloid, paraboloid, cone)"),
    ];
    for (mirror, extra, needle) in cases {
        let text = with_mirror(mirror, extra);
        let err = load_str(&text, Path::new("case.toml")).expect_err(mirror);
        let msg = err.to_string();
        assert!(
            msg.contains(needle),
            "{mirror:?} {extra:?}: expected {needle:?} in {msg}"
        );
        assert!(msg.starts_with("case.toml:"), "{msg}");
        assert!(err.line().is_some(), "{msg}");
    }
    // Through the ceiling: the room is 6 m high, the viewpoint at 5.5 m.
    let high = with_mirror(HYPERBOLOID, "").replace(
        "[mirror]\ncenter = [0, 3, 0]",
        "[mirror]\ncenter = [0, 5.5, 0]",
    );
    let msg = load_str(&high, Path::new("case.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("mirror.center: the mirror (reaching 1.31"),
        "{msg}"
    );
}

/// A cone: a pinhole `sensor.offset` below its viewpoint, the field of view fitted to its
/// rim; a field's error points at the field's own line.
#[test]
fn a_cone_loads_with_its_pinhole_and_errors_point_at_the_field() {
    let cone = "shape = \"cone\"\nhalf_angle = 55\nrim_radius = 1";
    let s = load_str(&with_mirror(cone, ""), Path::new("c.toml")).unwrap();
    let want = crate::mirror::Cone {
        half_angle_deg: 55.0,
        rim_radius_m: 1.0,
    };
    assert_eq!(s.mirror.shape, want.shape());
    assert_eq!(s.sensor.offset_m, 2.5);
    assert_eq!(s.mirror.shape.xi(), None);
    let (rim_r, rim_y) = s.mirror.shape.rim().unwrap();
    let half = (f64::from(s.sensor.fov_y_deg).to_radians() / 2.0).tan();
    assert!((half - 1.05 * rim_r / (rim_y + 2.5)).abs() < 1e-5);
    for (mirror, key) in [
        ("radius = 1\nraduis = 1", "raduis"),
        (
            "shape = \"cone\"\nhalf_angle = 95\nrim_radius = 1",
            "half_angle",
        ),
    ] {
        let text = with_mirror(mirror, "");
        let line = text.lines().position(|l| l.starts_with(key)).unwrap() as u32 + 1;
        let err = load_str(&text, Path::new("c.toml")).unwrap_err();
        assert_eq!(err.line(), Some(line), "{err}");
    }
}
