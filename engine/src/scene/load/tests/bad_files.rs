//! Every file in tests/scenes/bad fails, naming its file, line and field.

use super::repo;
use crate::scene::error::SceneError;
use crate::scene::load;

/// (file in tests/scenes/bad, expected line, text the field/message must contain).
/// The expectations repeat each file's first-line comment.
const BAD: &[(&str, Option<u32>, &str)] = &[
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
