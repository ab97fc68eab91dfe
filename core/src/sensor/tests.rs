//! Known answers for the sensor outputs from the exact reference, in the six-colour room
//! (walls 5 m from the mirror's centre, +X red, -X cyan, +Y green, -Y magenta, +Z blue,
//! -Z yellow; unlit, so the colours are exact).

use glam::Vec3;

use super::outputs::{SensorOutputs, NO_ID};
use super::panorama::{PanoramaKind, PanoramaLayout};
use crate::reference::Reference;
use crate::scene::Scene;

fn six_colour() -> Scene {
    crate::scene::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/test/six-colour-room.toml"
    )))
    .unwrap()
}

fn reference_outputs(scene: &Scene) -> SensorOutputs {
    let reference = Reference::new(scene, 0.0);
    let [w, h] = scene.sensor.resolution;
    let (images, _) = reference.render(&reference.sensor_view(), w, h, 1);
    SensorOutputs::from_reference(scene, 0.0, &images)
}

/// The angle (radians) between two directions, in f64 from the chord: f32's
/// `angle_between` (an acos) cannot resolve angles below about 3e-4 rad.
pub(crate) fn angle(a: Vec3, b: Vec3) -> f64 {
    let (a, b) = (a.as_dvec3().normalize(), b.as_dvec3().normalize());
    2.0 * ((a - b).length() / 2.0).asin()
}

/// The wall (cube-face order) a point on the room's surface lies on, from its coordinates.
fn wall_of(p: Vec3) -> u32 {
    let axis = p.abs().max_position();
    2 * axis as u32 + u32::from(p[axis] < 0.0)
}

/// Every mirror pixel's ray, followed for its range, ends on a wall of the 10 m room (a
/// coordinate at +-5 m), on the wall its id names, in the direction (from the mirror's centre)
/// the reference's own direction layer gives.
#[test]
fn each_ray_ends_where_the_reference_says() {
    let scene = six_colour();
    let reference = Reference::new(&scene, 0.0);
    let [w, h] = scene.sensor.resolution;
    let (images, _) = reference.render(&reference.sensor_view(), w, h, 1);
    let out = SensorOutputs::from_reference(&scene, 0.0, &images);
    let (mut checked, mut worst) = (0, 0.0f64);
    for (i, ray) in out.rays.rays.iter().enumerate() {
        let Some(ray) = ray else {
            assert_eq!(out.ids[i], NO_ID);
            continue;
        };
        let end = ray.origin + out.range[i] * ray.direction;
        assert!(
            (end.abs().max_element() - 5.0).abs() < 1e-4,
            "pixel {i}: {end}"
        );
        // Within a millimetre of an edge, which of two walls is met is a matter of rounding.
        let on_walls = (end.abs() - Vec3::splat(5.0))
            .abs()
            .cmplt(Vec3::splat(1e-3));
        if on_walls.bitmask().count_ones() == 1 {
            assert_eq!(out.ids[i], wall_of(end), "pixel {i}: {end}");
        }
        let d = images.direction.pixels[i];
        let want = Vec3::new(d[0], d[1], d[2]);
        worst = worst.max(angle(end, want));
        checked += 1;
    }
    eprintln!("largest angle between the ray's end and the reference's direction: {worst:e} rad");
    // The reference's reflected ray leaves from the mirror point moved off the sphere by a
    // few hundred float steps (offset_ray_origin, about 3e-5 m here): 3e-5 m seen from 4 m
    // and more is under 1e-5 rad.
    assert!(worst < 1e-5);
    assert!(checked > 1000, "{checked} mirror pixels");
}

/// Known columns: at the horizon (elevation 0) the azimuths 0, 90, 180 and 270 degrees look
/// at the centres of the +X, +Z, -X and -Z walls; the bottom row looks down at the floor. In
/// both panorama kinds, from the reference's sensor image.
#[test]
fn an_unwrap_puts_each_wall_in_its_known_column() {
    let scene = six_colour();
    let out = reference_outputs(&scene);
    for kind in PanoramaKind::ALL {
        let layout = PanoramaLayout::for_sensor(&out.optics, kind);
        let pano = layout.unwrap(&out.optics, &out.image);
        let horizon = layout.row(0.0) as u32;
        for (azimuth_deg, colour) in [
            (0.0, [1.0, 0.0, 0.0]),
            (90.0, [0.0, 0.0, 1.0]),
            (180.0, [0.0, 1.0, 1.0]),
            (270.0, [1.0, 1.0, 0.0]),
        ] {
            let column = layout.column(f64::to_radians(azimuth_deg)) as u32;
            let p = pano.pixel(column, horizon);
            assert_eq!(&p[..3], &colour, "{kind:?} at {azimuth_deg} degrees");
        }
        // The lon-lat panorama's bottom row looks nearly straight down, the cylinder's at -45
        // degrees, which from the mirror meets the floor 5 m down and at most 5 m out.
        let bottom = pano.pixel(layout.width / 3, layout.height - 1);
        assert_eq!(
            &bottom[..3],
            &[1.0, 0.0, 1.0],
            "{kind:?} bottom row is the floor"
        );
    }
}

/// Every panorama pixel shows its own direction, the rim's row too: a central mirror (its
/// reflected rays share a viewpoint) in a room whose walls are painted with the direction
/// they are seen in (`direction` material), unwrapped from the reference's sensor image. At
/// the rim a bilinear tap falls beside the mirror, on the camera's direct view of the room:
/// mixed in, the top row was up to 14 degrees off (the rest under 0.05).
#[test]
fn every_panorama_pixel_shows_its_own_direction_up_to_the_rim() {
    let text = "[room]\ncenter = [0, 3, 0]\nsize = [12, 6, 10]\nwalls = \"d\"\n\
        [mirror]\nshape = \"hyperboloid\"\ncenter = [0.3, 3, -0.2]\nfocal_distance = 2.0\n\
        latus_rectum = 2.0\nrim_radius = 1.3\n\
        [[materials]]\nname = \"d\"\ntype = \"direction\"\n\
        [sensor]\nresolution = [64, 64]\nup = [0.6, 0, -0.8]\n\
        [observer]\nresolution = [16, 12]\n[cube]\nface_size = 8\n";
    let scene = crate::scene::load_str(text, std::path::Path::new("direction-room.toml")).unwrap();
    let out = reference_outputs(&scene);
    for kind in PanoramaKind::ALL {
        let layout = PanoramaLayout::for_sensor(&out.optics, kind);
        let pano = layout.unwrap(&out.optics, &out.image);
        let (mut worst, mut shown) = (0.0f64, 0);
        for i in 0..layout.height {
            for j in 0..layout.width {
                let p = pano.pixel(j, i);
                if p[3] == 0.0 {
                    continue;
                }
                shown += 1;
                let (e, a) = layout.pixel_angles(j, i);
                let seen = Vec3::new(p[0], p[1], p[2]) * 2.0 - Vec3::ONE;
                worst = worst.max(angle(seen, crate::sensor::optics::direction(e, a)));
            }
        }
        assert!(
            shown > layout.width * layout.height / 2,
            "{kind:?}: {shown} shown"
        );
        assert!(
            worst.to_degrees() < 1.0,
            "{kind:?}: {} degrees",
            worst.to_degrees()
        );
    }
}

/// The column of a known wall point: the corner where the +X and +Z walls meet at the
/// mirror's height lies at azimuth 45 degrees, and the colour changes from red to blue there
/// (within the pixel or two that the mirror's non-central rays shift it by).
#[test]
fn the_red_blue_corner_is_at_45_degrees() {
    let scene = six_colour();
    let out = reference_outputs(&scene);
    let layout = PanoramaLayout::for_sensor(&out.optics, PanoramaKind::LonLat);
    let pano = layout.unwrap(&out.optics, &out.image);
    let row = layout.row(0.0) as u32;
    let corner = layout.column(f64::to_radians(45.0));
    let red_until = (0..layout.width / 4)
        .take_while(|&j| pano.pixel(j, row)[2] < 0.5)
        .last()
        .unwrap();
    // The corner's direction from a point on the mirror differs from the centre's by at most
    // asin(R / distance) = asin(1 / 7.07): bound the shift by that angle in columns.
    let slack = (1.0f64 / 50f64.sqrt()).asin() / std::f64::consts::TAU * f64::from(layout.width);
    assert!(
        (f64::from(red_until) + 1.0 - corner).abs() <= slack + 1.0,
        "red ends at column {red_until}, the corner is at {corner:.1} (slack {slack:.1})"
    );
}

/// camera.json's positions are in the scene frame and say so: the thesis room's mirror sits at
/// (0, 3, 0) in its file (the scene's origin), the sensor 2.5 m below it; adding
/// `scene_origin_m` gives the file's coordinates.
#[test]
fn camera_positions_are_local_with_the_scene_origin_beside_them() {
    let scene = crate::scene::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/thesis-room.toml"
    )))
    .unwrap();
    let mut small = scene.clone();
    small.sensor.resolution = [32, 32];
    let record = reference_outputs(&small).camera_record(Default::default());
    assert_eq!(record.scene_origin_m, [0.0, 3.0, 0.0]);
    assert!(record.frame.contains("scene_origin_m"));
    let world = |local: [f32; 3]| {
        glam::DVec3::from_array(record.scene_origin_m) + Vec3::from_array(local).as_dvec3()
    };
    assert!((world(record.mirror.centre_m) - glam::DVec3::new(0.0, 3.0, 0.0)).length() < 1e-6);
    assert!((world(record.sensor.position_m) - glam::DVec3::new(0.0, 0.5, 0.0)).length() < 1e-6);
}

#[test]
fn range16_is_whole_millimetres_and_zero_for_no_return() {
    let metres = [2.0, 1.2344, 0.0, 0.0004, 65.535, 65.6, f32::NAN, 3.0006];
    assert_eq!(
        super::files::range_mm(&metres),
        [2000, 1234, 0, 0, 65535, 0, 0, 3001]
    );
}

/// The reference's quantities, computed when asked, are the ray map's own data: on each
/// mirror pixel the mirror point in render space with the range, the direction with 1 + the
/// id; 0 (in every channel, the mask) off the mirror.
#[test]
fn the_references_quantities_are_its_rays_range_and_ids() {
    use super::quantities::{DIRECTION_ID, ORIGIN_RANGE};
    let s = six_colour();
    let o = reference_outputs(&s);
    let (origin, direction) = (o.quantity(&ORIGIN_RANGE), o.quantity(&DIRECTION_ID));
    let mut seen = 0;
    for (i, ray) in o.rays.rays.iter().enumerate() {
        let (a, b) = (origin.pixels[i], direction.pixels[i]);
        let Some(ray) = ray else {
            assert_eq!((a, b), ([0.0; 4], [0.0; 4]), "pixel {i} off the mirror");
            continue;
        };
        seen += 1;
        let point = ray.origin - o.optics.mirror_center;
        assert_eq!(a, [point.x, point.y, point.z, o.range[i]], "pixel {i}");
        let d = ray.direction;
        assert_eq!(b, [d.x, d.y, d.z, (o.ids[i] + 1) as f32], "pixel {i}");
        assert!(
            o.ids[i] < 6 && o.range[i] > 4.0,
            "pixel {i}: a wall 5 m away"
        );
    }
    assert!(seen > 1000, "{seen} mirror pixels");
}
