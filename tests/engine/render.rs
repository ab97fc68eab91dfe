//! GPU integration tests, each under the Khronos validation layer: any validation message
//! fails the test. They render small cube maps on the default device (lavapipe in CI); the
//! known-answer tests run on every installed driver (lavapipe and SwiftShader).

#[path = "../common/mod.rs"]
mod common;

use common::{close, devices, render_once, scene, Gpu};
use glam::Vec3;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::scene::camera::{ViewBasis, FACE_NAMES};

/// scenes/test/six-colour-room.toml states the colour of each wall.
const WALLS: [[f32; 3]; 6] = [
    [1.0, 0.0, 0.0], // +X red
    [0.0, 1.0, 1.0], // -X cyan
    [0.0, 1.0, 0.0], // +Y green
    [1.0, 0.0, 1.0], // -Y magenta
    [0.0, 0.0, 1.0], // +Z blue
    [1.0, 1.0, 0.0], // -Z yellow
];

#[test]
fn each_cube_face_centre_shows_its_wall() {
    for device in devices() {
        let gpu = Gpu::on(&device, Default::default());
        let (_, images) = render_once(&gpu, scene("scenes/test/six-colour-room.toml"), 16, 0.0);
        let faces = images.cube.expect("cube read back");
        for (f, img) in faces.iter().enumerate() {
            // The four texels around the centre of an even-sized face.
            for (x, y) in [(7, 7), (8, 7), (7, 8), (8, 8)] {
                let p = img.pixel(x, y);
                // Plain unlit colours of 0 and 1 are exact in RGBA16F.
                assert_eq!(
                    [p[0], p[1], p[2]],
                    WALLS[f],
                    "{device}: face {} texel ({x},{y})",
                    FACE_NAMES[f]
                );
            }
        }
        gpu.finish();
    }
}

/// Every texel of every face shows the direction of its own texel-centre ray (the `direction`
/// material colours a point by its direction from the mirror centre): the rendered orientation
/// is the one Vulkan's cube lookup expects, texel by texel.
#[test]
fn every_cube_texel_shows_its_own_direction() {
    for device in devices() {
        let gpu = Gpu::on(&device, Default::default());
        let n = 16;
        let (_, images) = render_once(&gpu, scene("scenes/test/direction-room.toml"), n, 0.0);
        let faces = images.cube.expect("cube read back");
        let mut worst = 0.0f32;
        for (f, img) in faces.iter().enumerate() {
            let basis = ViewBasis::cube_face(Vec3::ZERO, f);
            for y in 0..n {
                for x in 0..n {
                    let ndc = |i: u32| 2.0 * (i as f32 + 0.5) / n as f32 - 1.0;
                    let d = basis.ray(ndc(x), ndc(y)).normalize();
                    let want = 0.5 + 0.5 * d;
                    let got = img.pixel(x, y);
                    let err = (Vec3::new(got[0], got[1], got[2]) - want)
                        .abs()
                        .max_element();
                    worst = worst.max(err);
                    // RGBA16F keeps 11 bits: 1/2048 relative; interpolation adds float rounding.
                    assert!(
                        err < 2e-3,
                        "{device}: face {} texel ({x},{y}): got {got:?}, want {want}",
                        FACE_NAMES[f]
                    );
                }
            }
        }
        eprintln!("{device}: worst direction error {worst}");
        gpu.finish();
    }
}

/// Known answers for the mirror. The observer looks along -Z at the sphere: the ray through
/// the sphere's centre comes straight back, so the middle of the sphere shows the +Z wall
/// (behind the viewer, blue). The sensor looks up at the sphere's bottom: it sees the floor
/// (-Y, magenta). Outside the sphere the observer sees the -Z wall (yellow).
#[test]
fn mirror_shows_what_is_behind_the_viewer() {
    for device in devices() {
        let gpu = Gpu::on(&device, Default::default());
        let s = scene("scenes/test/six-colour-room.toml");
        let (ow, oh) = (s.observer.resolution[0], s.observer.resolution[1]);
        let (sw, sh) = (s.sensor.resolution[0], s.sensor.resolution[1]);
        let (_, images) = render_once(&gpu, s, 32, 0.0);
        let observer = images.observer.expect("observer");
        let sensor = images.sensor.expect("sensor");
        let centre = observer.pixel(ow / 2, oh / 2);
        assert!(
            close(centre, WALLS[4], 1e-3),
            "{device}: observer centre {centre:?} should be +Z blue"
        );
        let corner = observer.pixel(2, 2);
        assert!(
            close(corner, WALLS[5], 1e-3)
                || close(corner, WALLS[2], 1e-3)
                || close(corner, WALLS[1], 1e-3),
            "{device}: observer corner {corner:?} should be a wall, not the mirror"
        );
        let up = sensor.pixel(sw / 2, sh / 2);
        assert!(
            close(up, WALLS[3], 1e-3),
            "{device}: sensor centre {up:?} should be the floor (magenta)"
        );
        gpu.finish();
    }
}

/// The same frame rendered twice, by two renderers, gives identical bytes.
#[test]
fn two_renders_are_identical() {
    let gpu = Gpu::new();
    let (_, a) = render_once(&gpu, scene("scenes/thesis-room.toml"), 64, 1.25);
    let (_, b) = render_once(&gpu, scene("scenes/thesis-room.toml"), 64, 1.25);
    assert_eq!(a.cube, b.cube);
    assert_eq!(a.observer, b.observer);
    assert_eq!(a.sensor, b.sensor);
    assert_eq!(a.pair, b.pair);
    gpu.finish();
}

/// `on-change`: a frame where nothing moved skips the cube update (and the cube is unchanged);
/// a frame where the orbiting object moved updates it.
#[test]
fn on_change_skips_updates_when_nothing_moves() {
    let gpu = Gpu::new();
    let s = scene("scenes/thesis-room.toml");
    assert_eq!(
        s.refresh,
        specchio::scene::RefreshPolicy::OnChange,
        "thesis-room uses on-change"
    );
    let mut r = Renderer::new(
        &gpu.device,
        s,
        &RenderOptions {
            cube_size: Some(32),
            ..Default::default()
        },
    )
    .unwrap();
    let all = Readback {
        cube: true,
        views: false,
        ..Default::default()
    };
    let (r0, i0) = r.render_frame(0, 0.5, all).unwrap();
    let (r1, i1) = r.render_frame(1, 0.5, all).unwrap();
    let (r2, i2) = r.render_frame(2, 0.75, all).unwrap();
    assert!(r0.cube_updated, "the first frame always fills the cube");
    assert!(!r1.cube_updated, "same time, nothing moved: no update");
    assert_eq!(r1.faces_rendered, 0);
    assert_eq!(
        i0.cube, i1.cube,
        "a skipped update leaves the cube as it was"
    );
    assert!(r2.cube_updated, "the orbiting object moved");
    assert_ne!(i1.cube, i2.cube);
    assert_eq!((r.counters().cube_updates, r.counters().cube_skips), (2, 1));
    drop(r);
    gpu.finish();
}

/// `Renderer::cube_shows_scene_at` (what a viewer drawing on demand asks before it stops):
/// under `every-4`, a moved mirror leaves the cube behind until the next fourth frame, and the
/// renderer says so until then.
#[test]
fn the_cube_says_whether_it_shows_the_scene() {
    let gpu = Gpu::new();
    let mut s = scene("scenes/test/six-colour-room.toml");
    s.refresh = specchio::scene::RefreshPolicy::EveryN(4);
    let options = RenderOptions {
        cube_size: Some(32),
        ..Default::default()
    };
    let mut r = Renderer::new(&gpu.device, s, &options).unwrap();
    assert!(!r.cube_shows_scene_at(0.0), "nothing filled yet");
    r.render_frame(0, 0.0, Readback::default()).unwrap();
    assert!(r.cube_shows_scene_at(0.0));
    r.scene.mirror.center += Vec3::new(0.5, 0.0, 0.0);
    for frame in 1..4 {
        assert!(
            !r.cube_shows_scene_at(0.0),
            "frame {frame}: the cube is behind"
        );
        r.render_frame(frame, 0.0, Readback::default()).unwrap();
    }
    assert!(!r.cube_shows_scene_at(0.0));
    r.render_frame(4, 0.0, Readback::default()).unwrap();
    assert!(r.cube_shows_scene_at(0.0), "the fourth frame updated it");
    drop(r);
    gpu.finish();
}

/// Per-face culling draws fewer objects into a face than the scene holds (a wall behind a
/// face is never drawn into it), and the counters say so.
#[test]
fn faces_draw_only_what_their_frustum_holds() {
    let gpu = Gpu::new();
    let (report, _) = render_once(&gpu, scene("scenes/test/six-colour-room.toml"), 16, 0.0);
    for (f, &n) in report.draws_per_face.iter().enumerate() {
        // Four side walls and the facing wall; the opposite wall is behind the face.
        assert_eq!(n, 5, "face {}", FACE_NAMES[f]);
    }
    gpu.finish();
}

/// A camera inside the mirror's bounding cube (but outside the sphere) still sees the mirror:
/// the bounding cube's far faces are drawn, which the near plane cannot clip away.
#[test]
fn mirror_is_drawn_from_inside_its_bounding_cube() {
    let gpu = Gpu::new();
    let path = common::root().join("scenes/test/six-colour-room.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    // 1.07 m from the centre of the unit sphere, inside its [-1, 1]^3 bounding cube, looking
    // at the centre: the middle pixel's ray comes back towards the camera and hits +Z (blue).
    let pitch = (-0.5f32).atan2(0.95).to_degrees();
    let text = text.replace(
        "[observer]\nposition = [0, 0, 4]\nyaw = 0\n",
        &format!("[observer]\nposition = [0, 0.5, 0.95]\nyaw = 0\npitch = {pitch}\n"),
    );
    assert!(
        text.contains("0.95"),
        "the observer block of six-colour-room.toml changed"
    );
    let s = specchio::scene::load_str(&text, &path).expect("scene");
    let (w, h) = (s.observer.resolution[0], s.observer.resolution[1]);
    let (_, images) = render_once(&gpu, s, 16, 0.0);
    let centre = images.observer.unwrap().pixel(w / 2, h / 2);
    assert!(
        close(centre, WALLS[4], 1e-3),
        "centre {centre:?} should reflect +Z (blue)"
    );
    gpu.finish();
}

/// The optional directional light, known answers: light straight down from above (towards
/// +Y), ambient 1/4. The floor faces the light (full albedo), the ceiling faces away and the
/// walls are edge-on (ambient only).
#[test]
fn directional_light_known_answers() {
    for device in devices() {
        let gpu = Gpu::on(&device, Default::default());
        let path = common::root().join("scenes/test/six-colour-room.toml");
        let text = std::fs::read_to_string(&path).unwrap()
            + "\n[light]\ndirection = [0, 1, 0]\nambient = 0.25\n";
        let s = specchio::scene::load_str(&text, &path).expect("scene with a light");
        let (_, images) = render_once(&gpu, s, 16, 0.0);
        let faces = images.cube.unwrap();
        for (f, wall) in WALLS.iter().enumerate() {
            let scale = if f == 3 { 1.0 } else { 0.25 }; // -Y (floor) faces the light
            let want = wall.map(|c| c * scale);
            let got = faces[f].pixel(8, 8);
            assert!(
                close(got, want, 1e-3),
                "{device}: face {}: got {got:?}, want {want:?}",
                FACE_NAMES[f]
            );
        }
        gpu.finish();
    }
}

/// The scene with every shape, OBJ and glTF meshes and a moving mirror renders under
/// validation, and its cube draws mesh objects as well as walls.
#[test]
fn moving_objects_scene_renders() {
    let gpu = Gpu::new();
    let s = scene("scenes/moving-objects.toml");
    let objects = s.objects.len() as u32;
    assert!(objects >= 6);
    let (report, images) = render_once(&gpu, s, 32, 2.0);
    let drawn: u32 = report.draws_per_face.iter().sum();
    // Each face draws at most its five walls plus every object; together they draw some
    // objects, and culling keeps the total below drawing everything into every face.
    assert!(drawn > 6 * 5 - 6, "faces drew {drawn} objects");
    assert!(
        drawn < 6 * (6 + objects),
        "culling removed nothing ({drawn})"
    );
    let faces = images.cube.unwrap();
    assert!(faces
        .iter()
        .flat_map(|f| &f.pixels)
        .all(|p| p.iter().all(|c| c.is_finite())));
    gpu.finish();
}

/// The thesis's 8-bit cube format renders the same plain colours (0 and 1 are exact in both).
#[test]
fn rgba8_cube_format_renders_the_walls() {
    let gpu = Gpu::new();
    let path = common::root().join("scenes/test/six-colour-room.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("[cube]\n", "[cube]\nformat = \"rgba8\"\n");
    let s = specchio::scene::load_str(&text, &path).expect("scene with an 8-bit cube");
    assert_eq!(s.cube.format, specchio::scene::CubeFormat::Rgba8Unorm);
    let (_, images) = render_once(&gpu, s, 16, 0.0);
    for (f, img) in images.cube.unwrap().iter().enumerate() {
        let p = img.pixel(8, 8);
        assert_eq!([p[0], p[1], p[2]], WALLS[f], "face {}", FACE_NAMES[f]);
    }
    let sensor = images.sensor.unwrap();
    let (w, h) = (sensor.width, sensor.height);
    assert!(
        close(sensor.pixel(w / 2, h / 2), WALLS[3], 1e-3),
        "the mirror samples the 8-bit cube"
    );
    gpu.finish();
}

/// six-colour-room with `edit` applied to its text (loaded as if it were that file).
fn six_colour_room_with(edit: impl Fn(String) -> String) -> specchio::scene::Scene {
    let path = common::root().join("scenes/test/six-colour-room.toml");
    let text = edit(std::fs::read_to_string(&path).unwrap());
    specchio::scene::load_str(&text, &path).unwrap_or_else(|e| panic!("{e}"))
}

/// A room far larger than the old fixed far plane (100 m): the cube's far plane comes from the
/// room, so every face still shows its wall rather than the black clear colour.
#[test]
fn a_room_beyond_100_m_fills_every_face() {
    let s = six_colour_room_with(|t| t.replace("size = [10, 10, 10]", "size = [300, 300, 300]"));
    assert!(s.cube.far_m > 150.0 * 3f32.sqrt(), "far {}", s.cube.far_m);
    let gpu = Gpu::new();
    let (_, images) = render_once(&gpu, s, 16, 0.0);
    for (f, img) in images.cube.expect("cube").iter().enumerate() {
        for (x, y) in [(0, 0), (7, 8), (15, 15)] {
            let p = img.pixel(x, y);
            assert_eq!(
                [p[0], p[1], p[2]],
                WALLS[f],
                "face {} ({x},{y})",
                FACE_NAMES[f]
            );
        }
    }
    gpu.finish();
}

/// A field of view near the 179.99-degree limit: the near plane follows the field of view, so
/// the walls beside the observer are drawn. Looking along -Z, the middle of the left edge looks
/// along about -X (cyan), the right +X (red), the top +Y (green), the bottom -Y (magenta).
#[test]
fn a_179_99_degree_view_shows_the_walls_beside_the_observer() {
    let s = six_colour_room_with(|t| t.replace("yaw = 0", "yaw = 0\nfov_y = 179.99"));
    let [w, h] = s.observer.resolution;
    let gpu = Gpu::new();
    let (_, images) = render_once(&gpu, s, 16, 0.0);
    let observer = images.observer.expect("observer");
    for ((x, y), wall) in [
        ((0, h / 2), 1),
        ((w - 1, h / 2), 0),
        ((w / 2, 0), 2),
        ((w / 2, h - 1), 3),
    ] {
        let p = observer.pixel(x, y);
        assert!(
            close(p, WALLS[wall], 1e-3),
            "({x},{y}): {p:?}, want {:?}",
            WALLS[wall]
        );
    }
    gpu.finish();
}
