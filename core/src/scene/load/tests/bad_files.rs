//! Every file in tests/scenes/bad fails, naming its file, line and field.

use super::repo;
use crate::scene::error::SceneError;
use crate::scene::load;

/// (file in tests/scenes/bad, expected line, text the field/message must contain).
/// The expectations repeat each file's first-line comment.
const BAD: &[(&str, Option<u32>, &str)] = &[
    (
        "object-through-mirror.toml",
        Some(16),
        "objects[0].position: object \"rod\" reaches into the mirror (centre [0, 3, 0], radius 1)",
    ),
    (
        "sensor-frame-animated.toml",
        Some(20),
        "objects[0].animation: not allowed here: an object in the sensor's frame moves with the \
         sensor camera",
    ),
    (
        "sensor-frame-far.toml",
        Some(17),
        "objects[0].position: an offset of 12 m from the sensor camera",
    ),
    (
        "sensor-frame-in-mirror.toml",
        Some(21),
        "objects[0].position: object \"rod\" reaches into the mirror",
    ),
    (
        "sensor-frame-through-floor.toml",
        Some(22),
        "objects[0].position: the robot's part \"mast\" reaches 0.6 m out of the room at time 0",
    ),
    (
        "sensor-shift-carries-a-part-out.toml",
        Some(23),
        "objects[0].position: the robot's part \"mast\" reaches 0.02 m out of the room at time 0 (sensor.shift [4.97, 0, 0] m moves the sensor and what it carries)",
    ),
    (
        "sensor-frame-unknown.toml",
        Some(14),
        "objects[0].frame: unknown variant `robot`, expected `world` or `sensor`",
    ),
    ("syntax-error.toml", Some(4), "TOML syntax error"),
    ("unknown-field.toml", Some(4), "mirror.radus"),
    (
        "negative-radius.toml",
        Some(4),
        "mirror.radius: must be positive",
    ),
    (
        "nan-radius.toml",
        Some(4),
        "mirror.radius: must be a finite number",
    ),
    (
        "zero-face-size.toml",
        Some(6),
        "cube.face_size: must be in 1..=8192, got 0",
    ),
    (
        "huge-face-size.toml",
        Some(6),
        "cube.face_size: must be in 1..=8192, got 16384",
    ),
    (
        "zero-distance-steps.toml",
        Some(5),
        "mirror.distance_steps: must be in 1..=256, got 0",
    ),
    (
        "many-secant-steps.toml",
        Some(5),
        "mirror.secant_steps: must be in 0..=32, got 33",
    ),
    (
        "missing-texture.toml",
        Some(12),
        "materials[0].file: cannot load",
    ),
    ("missing-mesh.toml", Some(8), "objects[0].file: cannot load"),
    ("mirror-outside-room.toml", Some(3), "mirror.center"),
    ("observer-inside-mirror.toml", Some(6), "observer.position"),
    (
        "empty.toml",
        None,
        "scene is empty: expected at least [room] and [mirror]",
    ),
    ("wrong-type.toml", Some(4), "mirror.radius"),
    (
        "unknown-material.toml",
        Some(9),
        "objects[0].material: unknown material \"gold\"",
    ),
    (
        "inf-position.toml",
        Some(8),
        "objects[0].position[0]: must be a finite number, got inf",
    ),
    ("near-not-below-far.toml", Some(7), "cube.far"),
    (
        "animated-mirror-leaves-room.toml",
        Some(5),
        "mirror.animation",
    ),
    ("sensor-up-parallel.toml", Some(6), "sensor.up"),
    ("sensor-inside-mirror.toml", Some(6), "sensor.offset"),
    (
        "keyframes-not-increasing.toml",
        Some(5),
        "mirror.animation.times[2]",
    ),
    (
        "keyframes-equal-in-f32.toml",
        Some(5),
        "mirror.animation.times[2]: key times must strictly increase, got 1.00000001 after 1; \
         they are equal in single precision",
    ),
    (
        "colour-out-of-range.toml",
        Some(12),
        "materials[0].color[1]",
    ),
    (
        "generate-count-zero.toml",
        Some(11),
        "generate[0].count: must be in 1..=100000, got 0",
    ),
    (
        "generate-count-huge.toml",
        Some(11),
        "generate[0].count: must be in 1..=100000, got 1000000000",
    ),
    (
        "generate-region-outside-room.toml",
        Some(15),
        "generate[0].region_max[1]: 7.5 is outside the room (y from 0 to 6)",
    ),
    (
        "generate-unknown-material.toml",
        Some(16),
        "generate[0].materials[1]: unknown material \"gold\"",
    ),
    (
        "generate-nan-size.toml",
        Some(13),
        "generate[0].size[0]: must be a finite number, got NaN",
    ),
    ("cube-far-clips-room.toml", Some(15), "cube.far: clips the room"),
    ("cube-near-outside-mirror.toml", Some(15), "cube.near: clips reflections"),
    ("room-too-big-for-f32.toml", Some(7), "room.size: the room reaches"),
    ("room-near-f32-max.toml", Some(7), "at most 1e12 m is allowed"),
    ("mirror-too-small-for-room.toml", Some(4), "mirror.radius: is too small for the room"),
    ("fov-179-999.toml", Some(15), "observer.fov_y: must be in [0.1, 179.99], got 179.999"),
    ("fov-rounds-to-zero.toml", Some(15), "got 1e-50 (0 in single precision)"),
    ("fov-rounds-to-180.toml", Some(15), "(180 in single precision)"),
    ("pitch-rounds-to-90.toml", Some(15), "observer.pitch: must be in (-90, 90), got 89.999999999 (90 in single precision)"),
    ("sensor-fov-180.toml", Some(15), "sensor.fov_y: must be in [0.1, 179.99], got 180"),
    ("generate-at-maxima.toml", Some(15), "generate[0].count: too much geometry: count 100000 x 65024 triangles"),
    ("too-many-objects.toml", Some(32), "generate[2].count: too many objects: this generator brings the scene to 200001"),
    ("size-extra-element.toml", Some(7), "room.size: invalid length 4, expected an array of exactly 3 elements"),
    ("center-too-short.toml", Some(3), "mirror.center: invalid length 2, expected an array of exactly 3 elements"),
    ("resolution-three-elements.toml", Some(15), "observer.resolution: invalid length 3, expected an array of exactly 2 elements"),
    ("colour-four-elements.toml", Some(13), "materials[0].color: invalid length 4"),
    ("keyframe-position-four-elements.toml", Some(19), "objects[0].animation.positions[1]: invalid length 4"),
    ("generate-size-three-elements.toml", Some(17), "generate[0].size: invalid length 3, expected an array of exactly 2 elements"),
    ("walls-number.toml", Some(8), "room.walls: invalid type: integer `5`, expected a material name for all six walls, or a table { px, nx, py, ny, pz, nz }"),
    ("walls-missing-nz.toml", Some(8), "room.walls.nz: required field is missing"),
    ("scale-string.toml", Some(18), "objects[0].scale: invalid type: string \"big\", expected a number (uniform scale) or an array of exactly 3 numbers"),
    ("scale-two-elements.toml", Some(18), "objects[0].scale: invalid length 2"),
    ("scale-overflows-f32.toml", Some(18), "objects[0].scale: size x scale is"),
    ("scale-too-thin.toml", Some(18), "objects[0].scale: size x scale is [1, 0.0000000000001, 1]: each axis must be within [1e-11, 1e11]"),
    ("generate-size-too-small.toml", Some(18), "generate[0].size: a box of size 1e-12 m is scaled by"),
    ("radius-1e-310.toml", Some(4), "mirror.radius: must be positive, got 1e-310 (0 in single precision)"),
    ("radius-beyond-f32.toml", Some(4), "mirror.radius: out of range: at most 3.4028235e38 in magnitude (single precision), got 1e39"),
    ("line-width-rounds-to-zero.toml", Some(19), "materials[1].line_width: must be in (0, 0.5], got 1e-50 (0 in single precision)"),
    ("deep-dotted-header.toml", Some(14), "nesting too deep"),
    ("deep-array.toml", Some(14), "nesting too deep"),
    ("utf16.toml", Some(1), "the file is UTF-16"),
    ("latin1.toml", Some(2), "byte 0xE0 is not UTF-8"),
];

#[test]
fn every_bad_scene_fails_naming_file_line_and_field() {
    let dir = repo("tests/scenes/bad");
    let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = BAD.iter().map(|b| b.0.to_string()).collect();
    listed.sort();
    assert_eq!(
        on_disk, listed,
        "every bad scene needs an entry in the table"
    );

    for &(name, line, needle) in BAD {
        let path = dir.join(name);
        let err = match load(&path) {
            Ok(_) => panic!("{name} loaded but should fail"),
            Err(e) => e,
        };
        let text = err.to_string();
        assert!(
            text.contains(name),
            "{name}: message does not name the file: {text}"
        );
        assert_eq!(err.line(), line, "{name}: wrong line in {text}");
        if let Some(line) = line {
            assert!(text.contains(&format!("{name}:{line}:")), "{name}: {text}");
        }
        assert!(
            text.contains(needle),
            "{name}: expected {needle:?} in {text}"
        );
    }
}

#[test]
fn asset_errors_name_the_asset_path() {
    let err = load(&repo("tests/scenes/bad/missing-mesh.toml")).unwrap_err();
    assert!(matches!(err, SceneError::Asset { .. }));
    assert!(err.to_string().contains("does-not-exist.obj"), "{err}");
    let err = load(&repo("tests/scenes/bad/missing-texture.toml")).unwrap_err();
    assert!(err.to_string().contains("does-not-exist.png"), "{err}");
}
