//! The exact reference against known answers and against the rasterizer.

#[path = "../common/mod.rs"]
mod common;

use common::{close, render_once, scene, Gpu};
use glam::Vec3;
use specchio::reference::Reference;

/// The same known answers as the rasterizer's mirror test: looking at the sphere's centre
/// shows what is behind the viewer (+Z, blue); the sensor sees the floor (-Y, magenta).
#[test]
fn reference_mirror_known_answers() {
    let s = scene("scenes/test/six-colour-room.toml");
    let r = Reference::new(&s, 0.0);
    let [w, h] = s.observer.resolution;
    let (obs, stats) = r.render(&r.observer_view(), w, h, 1);
    assert_eq!(stats.misses, 0);
    assert!(close(obs.color.pixel(w / 2, h / 2), [0.0, 0.0, 1.0], 1e-6));
    assert_eq!(
        obs.object.pixel(w / 2, h / 2)[0],
        4.0,
        "the +Z wall is drawable 4"
    );
    assert_eq!(obs.object.pixel(w / 2, h / 2)[1], 1.0, "seen in the mirror");
    let [sw, sh] = s.sensor.resolution;
    let (sensor, _) = r.render(&r.sensor_view(), sw, sh, 1);
    assert!(close(
        sensor.color.pixel(sw / 2, sh / 2),
        [1.0, 0.0, 1.0],
        1e-6
    ));
    // The exact direction at the sensor's centre pixel points straight down.
    let d = sensor.direction.pixel(sw / 2, sh / 2);
    assert!(Vec3::new(d[0], d[1], d[2]).angle_between(Vec3::NEG_Y) < 0.01);
}

/// No ray escapes a closed room: watertight triangles, padded BVH boxes, offset origins.
#[test]
fn no_ray_escapes_the_closed_rooms() {
    for rel in [
        "scenes/thesis-room.toml",
        "scenes/moving-objects.toml",
        "scenes/test/six-colour-room.toml",
    ] {
        let s = scene(rel);
        let r = Reference::new(&s, 0.7);
        let (_, a) = r.render(&r.observer_view(), 160, 120, 4);
        let (_, b) = r.render(&r.sensor_view(), 128, 128, 4);
        assert_eq!(a.misses + b.misses, 0, "{rel}: rays escaped");
        assert!(b.mirror_pixels > 0, "{rel}: the sensor sees the mirror");
    }
}

/// Where the camera sees the room directly, reference and rasterizer agree (same cameras,
/// pixel centres and materials); the mirror is where they may differ (the cube map's
/// approximation). On the six-colour room almost every pixel agrees.
#[test]
fn reference_agrees_with_the_rasterizer_off_the_mirror() {
    let gpu = Gpu::new();
    let s = scene("scenes/test/six-colour-room.toml");
    let [w, h] = s.observer.resolution;
    let r = Reference::new(&s, 0.0);
    let (reference, _) = r.render(&r.observer_view(), w, h, 1);
    let (_, raster) = render_once(&gpu, s, 256, 0.0);
    let raster = raster.observer.expect("observer");
    let (mut direct, mut direct_equal) = (0, 0);
    for (i, (a, b)) in reference
        .color
        .pixels
        .iter()
        .zip(&raster.pixels)
        .enumerate()
    {
        if reference.object.pixels[i][1] == 0.0 {
            direct += 1;
            if (0..3).all(|c| (a[c] - b[c]).abs() < 1e-3) {
                direct_equal += 1;
            }
        }
    }
    // Only pixels on a wall edge may differ (the two pick different sides of the edge).
    assert!(
        direct_equal as f64 >= 0.995 * direct as f64,
        "{direct_equal} of {direct} direct pixels agree"
    );
    gpu.finish();
}

/// The CPU twin of `materials.glsl` against the GPU: every texel of the thesis-room cube map
/// (checker, grid and texture walls, a lit-free ball) against the reference's colour for the
/// same texel-centre ray from the cube's centre. Agreement to RGBA16F rounding except where a
/// texel centre lies on a pattern edge (the two sides of a float tie) or on a texture texel
/// edge (GPU filtering uses limited sub-texel precision): at most 1 % of the texels.
#[test]
fn cpu_materials_match_the_gpu_cube_texels() {
    use specchio::scene::camera::ViewBasis;
    let gpu = Gpu::new();
    let s = scene("scenes/thesis-room.toml");
    let n = 128;
    let (_, images) = render_once(&gpu, s.clone(), n, 0.0);
    let faces = images.cube.expect("cube");
    let r = Reference::new(&s, 0.0);
    let (mut total, mut off) = (0, 0);
    let mut worst = 0.0f32;
    for (f, face) in faces.iter().enumerate() {
        let (cpu, _) = r.render(&ViewBasis::cube_face(Vec3::ZERO, f), n, n, 1);
        for (a, b) in face.pixels.iter().zip(&cpu.color.pixels) {
            let err = (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max);
            total += 1;
            // f16 keeps 11 bits: 1/1024 of a value below 1, and the sRGB texture path ~1/256.
            if err > 4.0 / 1024.0 {
                off += 1;
            } else {
                worst = worst.max(err);
            }
        }
    }
    eprintln!("materials: {off} of {total} texels differ; worst agreeing error {worst}");
    assert!(off * 100 <= total, "{off} of {total} texels differ");
    gpu.finish();
}

/// Every material kind, lit: materials.glsl run by `materials_check.comp` (full f32) against
/// the CPU twin in `reference::materials`, at 4,096 random points per material plus uvs placed
/// exactly on checker and grid cell borders (where floor() decides). Colour, checker, grid and
/// direction materials and the lighting must agree to float rounding (a few ulps); a texture
/// to the sampler's sub-texel precision (linear-filter weights have only
/// `subTexelPrecisionBits` bits, 8 on lavapipe), which is 2 * 2^-bits of the texel range.
#[test]
fn cpu_materials_match_the_gpu_in_f32() {
    use specchio::render::{RenderOptions, Renderer};
    let s = material_check_scene();
    let gpu = Gpu::new();
    let bits = gpu.device.info.limits.sub_texel_precision_bits;
    let mut r = Renderer::new(&gpu.device, s.clone(), &RenderOptions::default()).unwrap();
    let points = random_material_points(&s);
    let gpu_rgb = r.evaluate_materials(&points).expect("materials check");
    drop(r);
    for (m, material) in s.materials.iter().enumerate() {
        let (worst, exact, count) = cpu_against_gpu(&s, m, &points, &gpu_rgb);
        eprintln!(
            "{}: {} of {} points bit-identical; worst difference {worst:e}",
            material.name, exact, count
        );
        let tolerance = material_tolerance(&material.name, bits);
        assert!(
            worst <= tolerance,
            "{}: worst {worst:e} > {tolerance:e}",
            material.name
        );
    }
    gpu.finish();
}

/// The material check's scene: a room and a sphere, lit, with one material of every kind.
fn material_check_scene() -> specchio::scene::Scene {
    let text = r#"
        [room]
        center = [0, 0, 0]
        size = [10, 10, 10]
        walls = "color"
        [mirror]
        center = [0, 0, 0]
        radius = 1
        [light]
        direction = [0.3, 1, 0.2]
        ambient = 0.35
        [[materials]]
        name = "color"
        type = "color"
        color = [0.95, 0.75, 0.1]
        [[materials]]
        name = "checker"
        type = "checker"
        a = [0.85, 0.15, 0.12]
        b = [0.95, 0.85, 0.8]
        tiles = 5
        [[materials]]
        name = "grid"
        type = "grid"
        background = [0.15, 0.6, 0.2]
        line = [0.95, 0.95, 0.9]
        tiles = 6
        line_width = 0.08
        [[materials]]
        name = "texture"
        type = "texture"
        file = "textures/orientation.png"
        tint = [0.9, 0.8, 1.0]
        tiles = 3
        [[materials]]
        name = "direction"
        type = "direction"
    "#;
    let path = common::root().join("scenes/material-check.toml");
    specchio::scene::load_str(text, &path).expect("scene")
}

/// 4,096 seeded random points per material of `s`, every fourth with u on a cell border.
fn random_material_points(
    s: &specchio::scene::Scene,
) -> Vec<(usize, specchio::render::gpu::MaterialSample)> {
    use specchio::render::gpu::MaterialSample;
    // The random points: the project's one seeded sequence, so a failure replays.
    let mut rng = specchio::random::SplitMix64::new(12345);
    let mut next = move |lo: f32, hi: f32| lo + (hi - lo) * rng.unit() as f32;
    let mut points = Vec::new();
    for (m, material) in s.materials.iter().enumerate() {
        let tiles = match material.kind {
            specchio::scene::MaterialKind::Checker { tiles, .. }
            | specchio::scene::MaterialKind::Grid { tiles, .. } => tiles,
            _ => 1.0,
        };
        for i in 0..4096 {
            let mut uv = glam::Vec2::new(next(-2.5, 2.5), next(-2.5, 2.5));
            if i % 4 == 0 {
                // Exactly on a cell border, as far as f32 can say.
                uv.x = (uv.x * tiles).round() / tiles;
            }
            let sample = MaterialSample {
                position: Vec3::new(next(-4.9, 4.9), next(-4.9, 4.9), next(-4.9, 4.9)).extend(1.0),
                normal: Vec3::new(next(-1.0, 1.0), next(-1.0, 1.0), next(-1.0, 1.0)).extend(0.0),
                uv: uv.extend(0.0).extend(0.0),
            };
            points.push((m, sample));
        }
    }
    points
}

/// Material `m`'s points, CPU twin against GPU: (worst component difference, bit-identical
/// points, points).
fn cpu_against_gpu(
    s: &specchio::scene::Scene,
    m: usize,
    points: &[(usize, specchio::render::gpu::MaterialSample)],
    gpu_rgb: &[Vec3],
) -> (f32, usize, usize) {
    use specchio::reference::materials::{material_albedo, shade};
    let material = &s.materials[m];
    let (mut worst, mut exact) = (0.0f32, 0);
    let mine: Vec<usize> = (0..points.len()).filter(|&i| points[i].0 == m).collect();
    for &i in &mine {
        let p = &points[i].1;
        let albedo = material_albedo(
            material,
            p.position.truncate(),
            p.uv.truncate().truncate(),
            &s.textures,
        );
        let cpu = shade(albedo, p.normal.truncate(), s.light.as_ref());
        let g = gpu_rgb[i];
        for c in 0..3 {
            let err = (g[c] - cpu[c]).abs();
            worst = worst.max(err);
        }
        exact += usize::from(g == cpu);
    }
    (worst, exact, mine.len())
}

/// The allowed CPU–GPU difference for material `name` on a sampler with `bits` sub-texel bits.
fn material_tolerance(name: &str, bits: u32) -> f32 {
    if name == "texture" {
        2.0 * (-(bits as f32)).exp2() + 1e-6
    } else {
        // Absolute, for values in [0, 1]: 4 ulps at 1 (more below, where ulps are finer);
        // the GPU may fuse or reorder a multiply-add.
        4.0 * f32::EPSILON
    }
}

/// The per-pixel layers are the pixel centre's at every sample count: from the centre sample
/// when the pattern has one (9 spp), from one extra centre path when it has not (16 spp), and
/// no extra path at 1 or 9 spp. The colour averages exactly `spp` camera paths.
#[test]
fn layers_are_the_pixel_centres_and_no_path_is_wasted() {
    let s = scene("scenes/thesis-room.toml");
    let r = Reference::new(&s, 0.0);
    let view = r.sensor_view();
    let (one, one_stats) = r.render(&view, 48, 48, 1);
    for spp in [9, 16] {
        let (many, stats) = r.render(&view, 48, 48, spp);
        assert_eq!(many.direction.pixels, one.direction.pixels, "{spp} spp");
        assert_eq!(many.distance.pixels, one.distance.pixels, "{spp} spp");
        assert_eq!(many.object.pixels, one.object.pixels, "{spp} spp");
        assert_eq!(stats.camera_paths, 48 * 48 * u64::from(spp));
        let centre_paths = if spp == 9 { 0 } else { 48 * 48 };
        assert_eq!(stats.centre_paths, centre_paths, "{spp} spp");
    }
    assert_eq!(one_stats.centre_paths, 0);
    assert_eq!(one_stats.camera_paths, 48 * 48);
}

/// Every mirror pixel is counted once by the layer its reflected hit is in, seen from the
/// mirror's centre, and the object layer's b says which: in the empty six-colour room all are
/// in the first layer; in pole-and-box some are behind the crate or the pole (an even count:
/// in and out of a closed object) and most are not.
#[test]
fn hidden_layers_count_every_mirror_pixel_once() {
    for (path, some_hidden) in [
        ("scenes/test/six-colour-room.toml", false),
        ("scenes/hard/pole-and-box.toml", true),
    ] {
        let s = scene(path);
        let r = Reference::new(&s, 0.0);
        let (images, stats) = r.render(&r.sensor_view(), 96, 96, 1);
        let h = stats.hidden_layers;
        assert_eq!(h.iter().sum::<u64>(), stats.mirror_pixels, "{path}: {h:?}");
        let mut from_image = [0u64; 8];
        for p in images.object.pixels.iter().filter(|p| p[1] == 1.0) {
            from_image[(p[2] as usize).min(7)] += 1;
        }
        assert_eq!(from_image, h, "{path}");
        let hidden: u64 = h[1..].iter().sum();
        assert_eq!(hidden > 0, some_hidden, "{path}: {h:?}");
        assert!(h[0] > 9 * hidden, "{path}: {h:?}");
    }
}
