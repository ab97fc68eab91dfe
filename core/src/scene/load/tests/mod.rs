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
