//! The sensor outputs (docs/sensor.md): the GPU's ray map against the exact CPU one on every
//! device, and the cube path's range and ids against the reference in an empty room (scenes
//! with objects: tests/engine/sensor_cube.rs; `--sensor-outputs` on the command line:
//! tests/cli/sensor_outputs.rs).

#[path = "../common/mod.rs"]
mod common;

use common::{devices, scene, Gpu};
use glam::Vec3;
use specchio::reference::Reference;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::sensor::{RayMap, SensorOptics, SensorOutputs};

/// The angle (radians) between two directions, in f64 from the chord (f32's acos-based
/// `angle_between` cannot resolve angles below about 3e-4 rad).
fn angle(a: Vec3, b: Vec3) -> f64 {
    let (a, b) = (a.as_dvec3().normalize(), b.as_dvec3().normalize());
    2.0 * ((a - b).length() / 2.0).asin()
}

/// The GPU's sensor outputs of `scene` on `gpu`, with a 64-texel cube.
fn gpu_outputs(gpu: &Gpu, scene: specchio::scene::Scene) -> SensorOutputs {
    gpu_outputs_with(gpu, scene, 64, Default::default())
}

/// The GPU's sensor outputs of `scene` on `gpu` with a `cube_size` cube filled by `method`.
fn gpu_outputs_with(
    gpu: &Gpu,
    scene: specchio::scene::Scene,
    cube_size: u32,
    method: specchio::render::methods::Method,
) -> SensorOutputs {
    let options = RenderOptions {
        cube_size: Some(cube_size),
        method,
        id_cube: true,
        ..Default::default()
    };
    let mut r = Renderer::new(&gpu.device, scene, &options).expect("renderer");
    let readback = Readback {
        cube: true,
        views: true,
        rays: true,
        ..Default::default()
    };
    let (_, images) = r.render_frame(0, 0.0, readback).expect("frame");
    let quantities = images.sensor_quantities.expect("the ray map read back");
    let sensor = images.sensor.expect("sensor read back");
    let truth = r.sensor_ground_truth();
    SensorOutputs::from_gpu(
        &r.scene,
        0.0,
        (&r.scene.mirror.lookup.to_string(), truth),
        sensor,
        quantities,
        images.cube,
    )
}

/// On every device, the GPU's ray map is the exact one to float rounding. Inside the disc
/// (more than 2 pixels from the rim) origins agree within 2e-6 m on the 1 m sphere and
/// directions within 1e-5 rad. Towards the rim the ray grazes the sphere: the hit's position
/// along the ray is ill-conditioned there (its error grows as 1 / sqrt of the discriminant),
/// and a driver's own sqrt and fused multiply-adds move it further, so there the bounds are
/// 1e-4 m and 1e-4 rad; the masks may differ only where the discriminant rounds to 0.
/// Measured maxima are printed.
#[test]
fn the_gpu_ray_map_is_the_exact_one_on_every_device() {
    // The sphere, the central mirrors (their quadric in f32 against f64; the paraboloid's
    // camera orthographic) and the cone (a quadric with an apex).
    for rel in [
        "scenes/test/six-colour-room.toml",
        "scenes/hyperbolic-room.toml",
        "scenes/parabolic-room.toml",
        "scenes/conical-room.toml",
    ] {
        gpu_ray_map_is_exact(rel);
    }
}

fn gpu_ray_map_is_exact(rel: &str) {
    let s = scene(rel);
    let exact = RayMap::exact(&s, 0.0);
    let optics = SensorOptics::at(&s, 0.0);
    let (centre, radius) = (optics.disc_centre_px(), optics.disc_radius_px());
    for device in devices() {
        let gpu = Gpu::on(&device, Default::default());
        let out = gpu_outputs(&gpu, s.clone());
        gpu.finish();
        let mut mask_differs = 0;
        // [inside, rim]: the largest origin and direction differences.
        let mut worst = [(0.0f32, 0.0f64); 2];
        for (i, (a, b)) in out.rays.rays.iter().zip(&exact.rays).enumerate() {
            let pixel = glam::Vec2::new(
                (i as u32 % exact.width) as f32,
                (i as u32 / exact.width) as f32,
            );
            let rim = (pixel + glam::Vec2::splat(0.5) - centre).length() > radius - 2.0;
            match (a, b) {
                (Some(a), Some(b)) => {
                    let w = &mut worst[usize::from(rim)];
                    w.0 = w.0.max((a.origin - b.origin).length());
                    w.1 = w.1.max(angle(a.direction, b.direction));
                }
                (None, None) => {}
                _ => mask_differs += 1,
            }
        }
        eprintln!(
            "{rel}, {device}: {} mirror pixels, mask differs at {mask_differs}; inside: origins \
             within {:e} m, directions within {:e} rad; rim: {:e} m, {:e} rad",
            exact.mirror_pixels(),
            worst[0].0,
            worst[0].1,
            worst[1].0,
            worst[1].1
        );
        assert!(
            mask_differs <= 8,
            "{device}: {mask_differs} mask differences"
        );
        assert!(
            worst[0].0 < 2e-6 && worst[0].1 < 1e-5,
            "{device}: inside {:?}",
            worst[0]
        );
        assert!(
            worst[1].0 < 1e-4 && worst[1].1 < 1e-4,
            "{device}: rim {:?}",
            worst[1]
        );
    }
}

/// In the six-colour room there is nothing but the walls: the cube path's range (searched
/// through the depth cube) and id (the id cube's texel) must match the reference's, the ids
/// exactly away from the room's edges, the range within 1e-4 m (measured 6.7e-5 m: a plane's
/// reverse-Z depth blends exactly, so only the search's last secant step and float rounding
/// remain).
#[test]
fn range_and_ids_are_exact_in_an_empty_room() {
    // The sphere, and the room with each central mirror instead (its camera where the shape
    // puts it).
    let path = common::root().join("scenes/test/six-colour-room.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let sphere = "center = [0, 0, 0]\nradius = 1.0\n";
    let central = [
        "center = [0, 0, 0]\nshape = \"hyperboloid\"\nfocal_distance = 2.5\nlatus_rectum = 2\nrim_radius = 1.2\n",
        "center = [0, 0, 0]\nshape = \"paraboloid\"\nlatus_rectum = 2\nrim_radius = 1.2\n",
    ];
    assert!(text.contains(sphere));
    range_and_ids_exact(scene("scenes/test/six-colour-room.toml"));
    for mirror in central {
        let text = text
            .replace(sphere, mirror)
            .replace("[sensor]\noffset = 2.5\n", "[sensor]\n");
        range_and_ids_exact(specchio::scene::load_str(&text, &path).expect("the variant loads"));
    }
}

fn range_and_ids_exact(s: specchio::scene::Scene) {
    let reference = Reference::new(&s, 0.0);
    let [w, h] = s.sensor.resolution;
    let (images, _) = reference.render(&reference.sensor_view(), w, h, 1);
    let exact = SensorOutputs::from_reference(&s, 0.0, &images);
    let gpu = Gpu::new();
    let out = gpu_outputs(&gpu, s.clone());
    gpu.finish();
    let mut worst = 0.0f32;
    for (i, ray) in exact.rays.rays.iter().enumerate() {
        let (Some(ray), Some(_)) = (ray, out.rays.rays[i]) else {
            continue;
        };
        worst = worst.max((out.range[i] - exact.range[i]).abs());
        let end = ray.origin + exact.range[i] * ray.direction;
        let near_walls = (end.abs() - Vec3::splat(5.0))
            .abs()
            .cmplt(Vec3::splat(1e-2));
        if near_walls.bitmask().count_ones() == 1 {
            assert_eq!(out.ids[i], exact.ids[i], "pixel {i}: {end}");
        }
    }
    let shape = s.mirror.shape.name();
    eprintln!("{shape}: depth-cube range against the reference's: within {worst:e} m");
    assert!(worst < 1e-4, "{shape}: ranges differ by {worst} m");
}
