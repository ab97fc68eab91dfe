//! The loader's tests: bad files and rules with the field and line each names
//! (`bad_files`, `rules`), and the shipped and generated scenes (`scenes`).

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};

use super::*;
use crate::scene::{CubeFormat, RefreshPolicy};

mod bad_files;
mod imaging;
mod mirror_shapes;
mod rules;
mod scenes;

pub(super) fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel)
}

pub(super) const MINIMAL: &str = "[room]\ncenter = [0, 3, 0]\nsize = [10, 6, 10]\nwalls = \"w\"\n\
    [mirror]\ncenter = [0, 3, 0]\nradius = 1\n\
    [[materials]]\nname = \"w\"\ntype = \"color\"\ncolor = [0.5, 0.5, 0.5]\n";

#[test]
fn rotation_is_rx_ry_rz_as_documented() {
    let text = format!(
        "{MINIMAL}[[objects]]\nshape = \"box\"\nsize = [1, 1, 1]\nposition = [2, 2, 2]\n\
         rotation = [30, 45, 60]\nmaterial = \"w\"\n"
    );
    let s = load_str(&text, Path::new("rot.toml")).unwrap();
    let expected = Quat::from_rotation_x(30f32.to_radians())
        * Quat::from_rotation_y(45f32.to_radians())
        * Quat::from_rotation_z(60f32.to_radians());
    assert!(s.objects[0].rotation.dot(expected).abs() > 1.0 - 1e-6);
}

#[test]
fn defaults_are_applied() {
    let s = load_str(MINIMAL, Path::new("min.toml")).unwrap();
    assert_eq!(s.cube.face_size_px, 512);
    assert_eq!(s.cube.format, CubeFormat::Rgba16Float);
    // Near: half the mirror's radius; far: 1.01 x the farthest room corner from the mirror
    // (room 10 x 6 x 10 centred on the mirror: sqrt(5^2 + 3^2 + 5^2)).
    assert_eq!(s.cube.near_m, 0.5);
    assert!(
        (s.cube.far_m - 59f32.sqrt() * 1.01).abs() < 1e-5,
        "{}",
        s.cube.far_m
    );
    assert!(s.cube.mipmaps);
    assert_eq!(s.cube.anisotropy, 16);
    assert_eq!(s.refresh, RefreshPolicy::OnChange);
    assert_eq!(s.observer.resolution, [800, 600]);
    assert_eq!(s.observer.fov_y_deg, 60.0);
    assert_eq!(s.sensor.resolution, [512, 512]);
    assert_eq!(s.sensor.up, Vec3::NEG_Z);
    assert_eq!(s.sensor.offset_m, 2.5);
    assert!(s.light.is_none());
    assert!(s.objects.is_empty());
}

/// An object in the sensor's frame sits at the camera's eye plus its offset along the
/// camera's axes (x right, y down, z forward: with the default up -Z and the camera looking
/// up, right is -X and down is +Z), follows the mirror's animation, and turns with the
/// robot's heading; a turn alone is a change the cube map must see.
#[test]
fn objects_in_the_sensor_frame_move_and_turn_with_the_camera() {
    use crate::scene::state::SceneState;
    use crate::scene::ObjectFrame;
    let text = "[room]\ncenter = [0, 3, 0]\nsize = [10, 6, 10]\nwalls = \"w\"\n\
        [mirror]\ncenter = [0, 3, 0]\nradius = 1\n\
        animation = { type = \"linear\", to = [1, 3, 0], duration = 4 }\n\
        [[materials]]\nname = \"w\"\ntype = \"color\"\ncolor = [0.5, 0.5, 0.5]\n\
        [[objects]]\nframe = \"sensor\"\nshape = \"box\"\nsize = [0.1, 0.1, 0.1]\n\
        position = [0.2, 0, -0.1]\nrotation = [90, 0, 0]\nmaterial = \"w\"\n";
    let mut s = load_str(text, Path::new("body.toml")).unwrap();
    assert_eq!(s.objects[0].frame, ObjectFrame::Sensor);
    let near = |a: Vec3, b: Vec3| (a - b).length() < 1e-6;
    let at = |s: &Scene, t: f64| SceneState::at(s, t);
    // The camera is 2.5 m below the mirror's centre (the scene's origin at time 0).
    let zero = at(&s, 0.0);
    assert!(
        near(zero.object_positions[0], Vec3::new(-0.2, -2.6, 0.0)),
        "{zero:?}"
    );
    // The object's y axis (turned onto the camera's z by its rotation) is the camera's
    // forward, +Y in the world.
    assert!(near(zero.object_rotations[0] * Vec3::Y, Vec3::Y));
    let later = at(&s, 2.0);
    assert!(
        near(later.object_positions[0], Vec3::new(0.3, -2.6, 0.0)),
        "{later:?}"
    );
    // Turned 90 degrees: the camera's right, -X, becomes +Z.
    s.sensor.heading_rad = std::f32::consts::FRAC_PI_2;
    let turned = at(&s, 0.0);
    assert!(
        near(turned.object_positions[0], Vec3::new(0.0, -2.6, 0.2)),
        "{turned:?}"
    );
    assert!(turned.cube_differs(&zero) && turned.object_moved(&zero, 0));
    // On the camera's axis a turn leaves the position but not the orientation.
    s.objects[0].position = Vec3::new(0.0, 0.0, -0.1);
    let (a, b) = (at(&s, 0.0), {
        s.sensor.heading_rad = 0.0;
        at(&s, 0.0)
    });
    assert!(near(a.object_positions[0], b.object_positions[0]));
    assert!(a.object_rotations[0].dot(b.object_rotations[0]).abs() < 0.9);
    assert!(a.cube_differs(&b), "the turn alone must refill the cube");
}
