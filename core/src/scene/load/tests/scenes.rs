//! The shipped scenes load with their stated contents; generated objects are deterministic,
//! placed by the rules and share their meshes.

use std::path::Path;

use glam::Vec3;

use super::{repo, MINIMAL};
use crate::scene::anim::Animation;
use crate::scene::load::{position_at, sample_times};
use crate::scene::mesh::Mesh;
use crate::scene::{load, load_str, MaterialKind, RefreshPolicy, Scene};

#[test]
fn shipped_scenes_load() {
    for rel in [
        "scenes/thesis-room.toml",
        "scenes/furnished-room.toml",
        "scenes/held-out-room.toml",
        "scenes/moving-objects.toml",
        "scenes/many-objects.toml",
        "scenes/test/six-colour-room.toml",
        "scenes/test/direction-room.toml",
        "scenes/hard/near-walls.toml",
        "scenes/hard/far-field.toml",
        "scenes/heavy.toml",
    ] {
        let s = load(&repo(rel)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.mirror.radius_m, 1.0, "{rel}");
        for o in &s.objects {
            assert!(o.mesh < s.meshes.len() && o.material < s.materials.len());
        }
        for m in s.room.wall_materials {
            assert!(m < s.materials.len());
        }
    }
    // The heavy scene states its size: about a million triangles.
    let heavy = load(&repo("scenes/heavy.toml")).unwrap();
    let triangles: usize = heavy
        .objects
        .iter()
        .map(|o| heavy.meshes[o.mesh].triangle_count())
        .sum();
    assert_eq!((heavy.objects.len(), triangles + 12), (2800, 974_440));
    let thesis = load(&repo("scenes/thesis-room.toml")).unwrap();
    assert_eq!(thesis.sensor.offset_m, 2.5);
    assert_eq!(thesis.cube.face_size_px, 512);
    assert_eq!(thesis.textures.len(), 1);
    assert_eq!(
        (thesis.textures[0].width, thesis.textures[0].height),
        (128, 128)
    );
    assert!(thesis.objects.iter().any(|o| o.animation.is_some()));

    let moving = load(&repo("scenes/moving-objects.toml")).unwrap();
    let moving_count = moving
        .objects
        .iter()
        .filter(|o| o.animation.is_some())
        .count();
    assert!(moving_count >= 6);
    assert!(moving.mirror.animation.is_some());
    // Distinct meshes: one unit box, sphere and cylinder whatever their sizes (2 box sizes, 2
    // sphere radii and 2 cylinders in the file), the OBJ and the glTF.
    assert_eq!(moving.meshes.len(), 5);

    // The furnished room: furniture plus three moving things, and free floor for the 0.5 m
    // landmark grid of the localisation experiment (docs/sensor.md).
    let furnished = load(&repo("scenes/furnished-room.toml")).unwrap();
    let moving = furnished.objects.iter().filter(|o| o.animation.is_some());
    assert_eq!(moving.count(), 3);
    assert!(furnished.objects.len() >= 15 && furnished.materials.len() >= 15);
    let grid = crate::sensor::localise::poses::grid(&furnished, 0.5, 0.0).unwrap();
    assert!(grid.len() >= 200, "{} landmarks", grid.len());

    let six = load(&repo("scenes/test/six-colour-room.toml")).unwrap();
    let colour = |face: usize| match &six.materials[six.room.wall_materials[face]].kind {
        MaterialKind::Color { color } => *color,
        other => panic!("{other:?}"),
    };
    assert_eq!(colour(0), Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(colour(1), Vec3::new(0.0, 1.0, 1.0));
    assert_eq!(colour(2), Vec3::new(0.0, 1.0, 0.0));
    assert_eq!(colour(3), Vec3::new(1.0, 0.0, 1.0));
    assert_eq!(colour(4), Vec3::new(0.0, 0.0, 1.0));
    assert_eq!(colour(5), Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(six.refresh, RefreshPolicy::EveryFrame);
}

fn triangles(s: &Scene) -> usize {
    s.objects
        .iter()
        .map(|o| s.meshes[o.mesh].triangle_count())
        .sum()
}

/// An object as exactly comparable data: name, mesh, material, the bits of position,
/// rotation and scale, and the animation.
type ObjectBits = (String, usize, usize, [u32; 10], Option<Animation>);

fn bits(s: &Scene) -> Vec<ObjectBits> {
    s.objects
        .iter()
        .map(|o| {
            let (p, r, k) = (o.position, o.rotation, o.scale);
            let v = [p.x, p.y, p.z, r.x, r.y, r.z, r.w, k.x, k.y, k.z];
            (
                o.name.clone(),
                o.mesh,
                o.material,
                v.map(f32::to_bits),
                o.animation.clone(),
            )
        })
        .collect()
}

#[test]
fn many_objects_scene_has_the_stated_counts() {
    let s = load(&repo("scenes/many-objects.toml")).unwrap_or_else(|e| panic!("{e}"));
    let moving = s.objects.iter().filter(|o| o.animation.is_some()).count();
    let tris = triangles(&s);
    eprintln!(
        "many-objects: {} objects, {tris} triangles, {moving} moving, {} meshes",
        s.objects.len(),
        s.meshes.len()
    );
    assert_eq!(s.objects.len(), 2000);
    assert!((190_000..=210_000).contains(&tris), "{tris} triangles");
    assert_eq!(moving, 200);
    // One mesh per (shape, tessellation): box, sphere 16, cylinder 16.
    assert_eq!(s.meshes.len(), 3);
    assert_eq!(s.refresh, RefreshPolicy::OnChange);
    assert_eq!(s.cube.face_size_px, 512);
    assert_eq!(s.mirror.radius_m, 1.0);
}

#[test]
fn generation_is_deterministic_and_seeded() {
    let path = repo("scenes/many-objects.toml");
    let a = load(&path).unwrap();
    let b = load(&path).unwrap();
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.meshes, b.meshes);

    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("seed = 7\n"));
    let c = load_str(&text.replace("seed = 7\n", "seed = 8\n"), &path).unwrap();
    let (a, c) = (bits(&a), bits(&c));
    // The first generator is untouched; the reseeded one has a different layout.
    assert_eq!(a[..1800], c[..1800]);
    let same = a[1800..]
        .iter()
        .zip(&c[1800..])
        .filter(|(x, y)| x.3[..3] == y.3[..3])
        .count();
    assert_eq!(same, 0, "{same} of 200 positions unchanged by the new seed");
}

#[test]
fn generated_objects_stay_in_their_region_and_clear_of_the_mirror() {
    let s = load(&repo("scenes/many-objects.toml")).unwrap();
    let (lo, hi) = (
        s.room.center - s.room.size_m * 0.5,
        s.room.center + s.room.size_m * 0.5,
    );
    let regions = [
        (
            "clutter[",
            Vec3::new(-4.6, 0.2, -4.6),
            Vec3::new(4.6, 5.6, 4.6),
        ),
        (
            "orbiters[",
            Vec3::new(-4.5, 0.5, -4.5),
            Vec3::new(4.5, 5.5, 4.5),
        ),
    ];
    let keep_clear = 0.5;
    let sensor = s.mirror.center - Vec3::Y * s.sensor.offset_m;
    // The regions are written in world coordinates; positions are local to the mirror.
    let local = s.origin.as_vec3();
    for o in &s.objects {
        let (_, rmin, rmax) = regions
            .iter()
            .find(|r| o.name.starts_with(r.0))
            .map(|&(n, a, b)| (n, a - local, b - local))
            .unwrap_or_else(|| panic!("{}", o.name));
        assert!(
            o.position.cmpge(rmin).all() && o.position.cmple(rmax).all(),
            "{} at {} outside its region",
            o.name,
            o.position
        );
        // Built-in unit shapes: the scale is the size.
        let size = o.scale.x;
        assert!(o.scale == Vec3::splat(size) && (0.1..=0.4).contains(&size));
        for t in sample_times(o.animation.as_ref()) {
            let p = position_at(o.animation.as_ref(), o.position, t);
            assert!(
                p.cmpge(lo).all() && p.cmple(hi).all(),
                "{} leaves the room",
                o.name
            );
            let d = p.distance(s.mirror.center);
            assert!(
                d > s.mirror.radius_m + keep_clear + size - 1e-4,
                "{} at t = {t} is {d} m from the mirror centre",
                o.name
            );
            // The sensor's line of sight (the vertical segment below the mirror centre).
            let y = p.y.clamp(sensor.y, s.mirror.center.y);
            let to_axis = p.distance(Vec3::new(sensor.x, y, sensor.z));
            assert!(to_axis > s.mirror.radius_m + keep_clear + size - 1e-4);
            assert!(p.distance(s.observer.position) > keep_clear + size - 1e-4);
        }
    }
}

#[test]
fn generated_meshes_are_shared_and_scaled() {
    let text = format!(
        "{MINIMAL}[[objects]]\nshape = \"mesh\"\nfile = \"meshes/arrow.obj\"\n\
         position = [3, 1, 3]\nmaterial = \"w\"\n\
         [[generate]]\nname = \"a\"\ncount = 50\nshapes = [\"box\", \"sphere\", \"mesh\"]\n\
         file = \"meshes/arrow.obj\"\nsize = [0.2, 0.2]\nsegments = 8\n\
         region_min = [-4, 1, -4]\nregion_max = [4, 5, 4]\nmaterials = [\"w\"]\n\
         [[generate]]\nname = \"b\"\ncount = 50\nshapes = [\"box\", \"cylinder\"]\n\
         size = [0.3, 0.5]\nsegments = 8\n\
         region_min = [-4, 1, -4]\nregion_max = [4, 5, 4]\nmaterials = [\"w\"]\n"
    );
    let s = load_str(&text, &repo("scenes/gen.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.objects.len(), 101);
    assert_eq!(s.objects[1].name, "a[0]");
    assert_eq!(s.objects[100].name, "b[49]");
    // arrow (shared with the file's object), unit box, sphere 8, cylinder 8.
    assert_eq!(s.meshes.len(), 4);
    let arrow = &s.meshes[s.objects[0].mesh];
    let side = (arrow.bounds_max - arrow.bounds_min).max_element();
    for o in &s.objects[1..] {
        let m = &s.meshes[o.mesh];
        // Every generated object's bounding box has the drawn size as its largest side.
        let extent = ((m.bounds_max - m.bounds_min) * o.scale).max_element();
        if o.name.starts_with("a[") {
            assert!((extent - 0.2).abs() < 1e-5, "{}: {extent}", o.name);
        } else {
            assert!((0.3 - 1e-5..=0.5 + 1e-5).contains(&extent), "{}", o.name);
        }
        if o.mesh == s.objects[0].mesh {
            assert!((o.scale.x - 0.2 / side).abs() < 1e-6);
        }
    }
    let sphere = s
        .meshes
        .iter()
        .filter(|m| m.triangle_count() == 8 * 6)
        .count();
    assert_eq!(sphere, 1, "sphere of 8 segments x 4 rings: 48 triangles");
}

#[test]
fn obj_and_gltf_meshes_load_with_expected_triangles() {
    let obj = Mesh::from_obj(&repo("scenes/meshes/arrow.obj")).unwrap();
    assert_eq!(obj.triangle_count(), 18);
    let gltf = Mesh::from_gltf(&repo("scenes/meshes/pyramid.gltf")).unwrap();
    assert_eq!(gltf.triangle_count(), 6);
    // The node's scale 0.5 and translation +0.25 y are applied.
    assert!((gltf.bounds_min - Vec3::new(-0.5, 0.25, -0.5)).length() < 1e-6);
    assert!((gltf.bounds_max - Vec3::new(0.5, 1.0, 0.5)).length() < 1e-6);
    for m in [&obj, &gltf] {
        // Closed and outward: positive signed volume; face normals agree with winding.
        let vol: f32 = m
            .indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!(vol > 0.0);
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
            assert!((b - a).cross(c - a).dot(m.normals[t[0] as usize]) > 0.0);
        }
    }
    assert!(Mesh::from_obj(&repo("scenes/meshes/missing.obj")).is_err());
}

/// `[[objects]]` of any size share one unit mesh per shape, sized by their transform: 1,000
/// spheres of different radii are one mesh, and each one's bounds are its own size.
#[test]
fn objects_share_unit_meshes_scaled_to_their_size() {
    let mut text = MINIMAL.to_string();
    for k in 0..1000 {
        let r = 0.01 + 0.0001 * k as f64;
        text += &format!(
            "[[objects]]\nshape = \"sphere\"\nradius = {r}\nposition = [3, 1, 3]\nmaterial = \"w\"\n"
        );
    }
    text += "[[objects]]\nshape = \"box\"\nsize = [1, 2, 3]\nposition = [3, 1, 3]\nscale = [2, 1, 1]\nmaterial = \"w\"\n\
             [[objects]]\nshape = \"cylinder\"\nradius = 0.5\nheight = 2\nposition = [3, 1, 3]\nmaterial = \"w\"\n";
    let s = load_str(&text, Path::new("shared.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.meshes.len(), 3, "one unit sphere, box and cylinder");
    let extent = |o: &crate::scene::Object| {
        let m = &s.meshes[o.mesh];
        (m.bounds_max - m.bounds_min) * o.scale
    };
    for (k, o) in s.objects[..1000].iter().enumerate() {
        let d = 2.0 * (0.01 + 0.0001 * k as f32);
        assert!(
            (extent(o) - Vec3::splat(d)).abs().max_element() < 1e-6,
            "{k}: {}",
            extent(o)
        );
        assert_eq!(s.meshes[o.mesh].triangle_count(), 48 * (2 * 24 - 2));
    }
    // The box's size and its per-axis scale multiply; the cylinder is 1 across and 2 high.
    assert_eq!(extent(&s.objects[1000]), Vec3::new(2.0, 2.0, 3.0));
    assert_eq!(extent(&s.objects[1001]), Vec3::new(1.0, 2.0, 1.0));
}

/// Work is bounded before it is done: a generator at its documented maxima (100,000 spheres of
/// 256 segments, 6.5e9 triangles a pass) and too many objects are refused, naming the count.
#[test]
fn budgets_refuse_scenes_too_big_to_render() {
    let gen = |count: u32, segments: u32| {
        format!(
            "[[generate]]\ncount = {count}\nshapes = [\"sphere\"]\nsegments = {segments}\nsize = [0.1, 0.2]\n\
             region_min = [-4, 1, -4]\nregion_max = [4, 5, 4]\nmaterials = [\"w\"]\n"
        )
    };
    let err = load_str(
        &format!("{MINIMAL}{}", gen(100_000, 256)),
        Path::new("g.toml"),
    )
    .unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("generate[0].count: too much geometry: count 100000 x 65024 triangles"),
        "{msg}"
    );
    assert!(
        msg.contains("6.5024e9 triangles a pass, at most 20000000"),
        "{msg}"
    );
    assert_eq!(err.line(), Some(13), "{msg}");
    let three = format!(
        "{MINIMAL}{}{}{}",
        gen(100_000, 3),
        gen(100_000, 3),
        gen(1, 3)
    );
    let err = load_str(&three, Path::new("g.toml")).unwrap_err();
    assert!(err.to_string().contains("generate[2].count: too many objects: this generator brings the scene to 200001, at most 200000"), "{err}");
}
