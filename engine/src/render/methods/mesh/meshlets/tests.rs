//! Known answers for the meshlet builders: the guarantees of the module's comment on the
//! built-in shapes, a grid, a strip longer than one meshlet, and degenerate input.

use std::collections::HashMap;

use glam::{DVec3, Vec3};

use super::*;
use crate::scene::Mesh;

/// Every guarantee of both builders: each triangle exactly once with its winding, the limits,
/// the sphere around the vertices, the cone around the normals.
fn check_guarantees(positions: &[Vec3], indices: &[u32], meshlets: &[Meshlet]) {
    let mut want: HashMap<[u32; 3], usize> = HashMap::new();
    for t in indices.chunks_exact(3) {
        *want.entry([t[0], t[1], t[2]]).or_default() += 1;
    }
    let mut got: HashMap<[u32; 3], usize> = HashMap::new();
    for m in meshlets {
        assert!(!m.triangles.is_empty(), "an empty meshlet");
        assert!(
            m.vertices.len() <= MAX_VERTICES,
            "{} vertices",
            m.vertices.len()
        );
        assert!(
            m.triangles.len() <= MAX_TRIANGLES,
            "{} triangles",
            m.triangles.len()
        );
        for t in &m.triangles {
            *got.entry(t.map(|i| m.vertices[i as usize])).or_default() += 1;
        }
        let center = m.center.as_dvec3();
        for &v in &m.vertices {
            let d = positions[v as usize].as_dvec3().distance(center);
            assert!(
                d <= f64::from(m.radius),
                "vertex {v} at {d} outside {}",
                m.radius
            );
        }
        if m.cone_cutoff != NEVER_BACK_FACING {
            // Every normal lies within the cone's half-angle less the margin (measured from
            // the stored axis: acos is steep near 0, where one f32 rounding moves it by 1e-5).
            let half_angle = f64::from(m.cone_cutoff).asin() - CONE_MARGIN_RAD;
            let axis = m.cone_axis.as_dvec3().normalize();
            for t in &m.triangles {
                let n = face_normal(positions, t.map(|i| m.vertices[i as usize])).normalize();
                let angle = n.dot(axis).clamp(-1.0, 1.0).acos();
                assert!(
                    angle <= half_angle + 1e-6,
                    "normal at {angle} > {half_angle}"
                );
            }
        }
    }
    assert_eq!(
        got, want,
        "every triangle exactly once, wound as in the mesh"
    );
}

/// The triangles of `meshlets` in meshlet order, as mesh indices.
fn replay(meshlets: &[Meshlet]) -> Vec<u32> {
    meshlets
        .iter()
        .flat_map(|m| {
            m.triangles
                .iter()
                .flat_map(|t| t.map(|i| m.vertices[i as usize]))
        })
        .collect()
}

fn shapes() -> Vec<(&'static str, Mesh)> {
    vec![
        ("box", Mesh::cuboid(Vec3::new(0.5, 1.0, 2.0))),
        ("sphere 32x16", Mesh::uv_sphere(0.5, 32, 16)),
        ("sphere 128x64", Mesh::uv_sphere(2.0, 128, 64)),
        ("cylinder 32", Mesh::cylinder(0.5, 0.5, 32)),
        ("grid 40x30", grid(40, 30)),
    ]
}

/// A flat (nx x ny)-quad grid in the z = 0 plane facing +Z, rows in index order.
fn grid(nx: u32, ny: u32) -> Mesh {
    let positions: Vec<Vec3> = (0..=ny)
        .flat_map(|y| (0..=nx).map(move |x| Vec3::new(x as f32, y as f32, 0.0)))
        .collect();
    let row = nx + 1;
    let indices = (0..ny)
        .flat_map(|y| {
            (0..nx).flat_map(move |x| {
                let a = y * row + x;
                [a, a + 1, a + row + 1, a, a + row + 1, a + row]
            })
        })
        .collect();
    Mesh {
        normals: vec![Vec3::Z; positions.len()],
        uvs: vec![glam::Vec2::ZERO; positions.len()],
        bounds_min: Vec3::ZERO,
        bounds_max: Vec3::new(nx as f32, ny as f32, 0.0),
        positions,
        indices,
        closed: false,
    }
}

#[test]
fn both_builders_keep_every_guarantee_on_every_shape() {
    for (name, mesh) in shapes() {
        for (builder, meshlets) in [
            ("ordered", ordered(&mesh.positions, &mesh.indices)),
            ("clustered", clustered(&mesh.positions, &mesh.indices)),
        ] {
            eprintln!("{name}, {builder}: {} meshlets", meshlets.len());
            check_guarantees(&mesh.positions, &mesh.indices, &meshlets);
        }
    }
}

#[test]
fn ordered_meshlets_replay_the_index_buffer() {
    for (name, mesh) in shapes() {
        let meshlets = ordered(&mesh.positions, &mesh.indices);
        assert_eq!(replay(&meshlets), mesh.indices, "{name}");
    }
}

/// A strip of 300 quads: 301 x 2 vertices, 600 triangles in index order. Each ordered
/// meshlet takes 31 quads (64 vertices) and the next starts where it stopped.
#[test]
fn ordered_meshlets_split_where_a_limit_is_reached() {
    let positions: Vec<Vec3> = (0..=300)
        .flat_map(|i| [Vec3::new(i as f32, 0.0, 0.0), Vec3::new(i as f32, 1.0, 0.0)])
        .collect();
    let indices: Vec<u32> = (0..300u32)
        .flat_map(|i| {
            let a = 2 * i;
            [a, a + 2, a + 3, a, a + 3, a + 1]
        })
        .collect();
    let meshlets = ordered(&positions, &indices);
    let sizes: Vec<(usize, usize)> = meshlets
        .iter()
        .map(|m| (m.vertices.len(), m.triangles.len()))
        .collect();
    assert_eq!(sizes[0], (64, 62));
    assert_eq!(sizes.len(), 10, "{sizes:?}");
    assert_eq!(sizes.iter().map(|s| s.1).sum::<usize>(), 600);
    check_guarantees(&positions, &indices, &meshlets);
}

/// A box is one meshlet (24 vertices, 12 triangles) either way; its normals point everywhere,
/// so it is never back-facing as a whole.
#[test]
fn a_box_is_one_meshlet_never_back_facing() {
    let mesh = Mesh::cuboid(Vec3::splat(0.5));
    for meshlets in [
        ordered(&mesh.positions, &mesh.indices),
        clustered(&mesh.positions, &mesh.indices),
    ] {
        assert_eq!(meshlets.len(), 1);
        let m = &meshlets[0];
        assert_eq!((m.vertices.len(), m.triangles.len()), (24, 12));
        assert_eq!(m.cone_cutoff, NEVER_BACK_FACING);
        assert!(!m.back_facing_from(Vec3::new(0.0, 0.0, -100.0)));
        // The box's corners are sqrt(3) / 2 from its centre.
        assert_eq!(m.center, Vec3::ZERO);
        assert!((m.radius - 0.75f32.sqrt()).abs() < 1e-6);
    }
}

/// A flat grid facing +Z: every cone is +Z with a half-angle of just the margin; an eye below
/// the plane sees every meshlet from behind, one above sees none from behind.
#[test]
fn a_flat_grid_has_cones_of_just_the_margin() {
    let mesh = grid(40, 30);
    let meshlets = clustered(&mesh.positions, &mesh.indices);
    for m in &meshlets {
        assert_eq!(m.cone_axis, Vec3::Z);
        assert!((f64::from(m.cone_cutoff) - CONE_MARGIN_RAD.sin()).abs() < 1e-6);
        assert!(m.back_facing_from(Vec3::new(20.0, 15.0, -100.0)));
        assert!(!m.back_facing_from(Vec3::new(20.0, 15.0, 100.0)));
    }
}

/// Clustered meshlets are compact: on a 128 x 64 sphere (8,321 vertices, 16,128 triangles)
/// they hold nearly as many triangles as a vertex-limited patch can (a 7 x 7-quad patch has
/// 8 x 8 = 64 vertices and 98 triangles), repeat few vertices, and their cones are narrow.
/// The ordered ones follow the rings, so their cones are wider.
#[test]
fn clustered_meshlets_are_compact() {
    let mesh = Mesh::uv_sphere(2.0, 128, 64);
    let meshlets = clustered(&mesh.positions, &mesh.indices);
    let triangles = mesh.indices.len() / 3;
    let vertices: usize = meshlets.iter().map(|m| m.vertices.len()).sum();
    let filled = triangles as f64 / (meshlets.len() * 98) as f64;
    let repeat = vertices as f64 / mesh.positions.len() as f64;
    let mean_cone = |ms: &[Meshlet]| {
        ms.iter()
            .map(|m| f64::from(m.cone_cutoff.min(1.0)).asin().to_degrees())
            .sum::<f64>()
            / ms.len() as f64
    };
    let ordered_cone = mean_cone(&ordered(&mesh.positions, &mesh.indices));
    eprintln!(
        "{} meshlets, {filled:.2} full, vertices x {repeat:.2}, mean cone {:.1} deg \
         (ordered {ordered_cone:.1})",
        meshlets.len(),
        mean_cone(&meshlets)
    );
    assert!(
        filled > 0.85,
        "meshlets {filled:.2} as full as a 7 x 7-quad patch"
    );
    assert!(repeat < 1.5, "vertices repeated x {repeat:.2}");
    assert!(mean_cone(&meshlets) < 25.0);
    assert!(mean_cone(&meshlets) < ordered_cone);
}

/// The cone test is conservative: from eyes all around a sphere and a cylinder, whenever a
/// meshlet counts as back-facing, every one of its triangles faces away from the eye (the eye
/// is behind its plane), by the margin. And it does cull: from afar, a sphere's far side.
#[test]
fn back_facing_meshlets_face_away_from_the_eye() {
    for mesh in [Mesh::uv_sphere(0.5, 32, 16), Mesh::cylinder(0.5, 0.5, 32)] {
        let meshlets = clustered(&mesh.positions, &mesh.indices);
        let mut culled = 0;
        let mut seen = 0;
        for k in 0..500 {
            // Eyes on a spiral of shells from just outside the shape to far away.
            let t = f64::from(k) + 0.5;
            let z = 1.0 - 2.0 * t / 500.0;
            let phi = t * 2.399_963;
            let r = (1.0 - z * z).sqrt();
            let distance = 0.9 + 20.0 * (t / 500.0).powi(2);
            let eye = DVec3::new(r * phi.cos(), z, r * phi.sin()) * distance;
            for m in &meshlets {
                seen += 1;
                if !m.back_facing_from(eye.as_vec3()) {
                    continue;
                }
                culled += 1;
                for t in &m.triangles {
                    let tri = t.map(|i| m.vertices[i as usize]);
                    let n = face_normal(&mesh.positions, tri).normalize();
                    for &v in &tri {
                        let to_vertex = mesh.positions[v as usize].as_dvec3() - eye;
                        let cos = n.dot(to_vertex.normalize());
                        assert!(cos > CONE_MARGIN_RAD.sin() * 0.999, "faces the eye: {cos}");
                    }
                }
            }
        }
        eprintln!("{culled} of {seen} (meshlet, eye) pairs back-facing");
        assert!(
            culled * 10 > seen,
            "the cone test hardly ever culls: {culled} of {seen}"
        );
    }
}

#[test]
fn degenerate_input_gives_no_or_never_culled_meshlets() {
    assert!(ordered(&[], &[]).is_empty());
    assert!(clustered(&[], &[]).is_empty());
    // A triangle whose three corners lie on one line has no facing.
    let positions = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0, Vec3::Y];
    let indices = [0, 1, 2, 0, 1, 3];
    for meshlets in [
        ordered(&positions, &indices),
        clustered(&positions, &indices),
    ] {
        check_guarantees(&positions, &indices, &meshlets);
        assert_eq!(meshlets.len(), 1);
        assert_eq!(meshlets[0].cone_cutoff, NEVER_BACK_FACING);
    }
}
