//! The triangles SwiftShader drops, said rather than left silent.
//!
//! SwiftShader (5.0, `SetupRoutine`) rasterizes a triangle that leaves the view by clipping it
//! to a polygon, but sets up the planes it interpolates depth and colours on, and the direction
//! it walks the polygon's edges in, from the *unclipped* corners, each projected and snapped
//! to 1/16 pixel (their `w` signs folded in). When those snapped corners have no area, the
//! planes are 0/0 (a floor's corners on one row of sub-pixels: nothing drawn, measured);
//! when their area has the wrong sign, the polygon is walked the wrong way round and nothing
//! is drawn either. It happens to a
//! triangle that crosses the
//! view's eye plane nearly edge-on and reaches far: a floor 3 m below a 64² cube face's eye
//! that reaches 3,500 m to each side projects every corner within half a sub-pixel of the
//! horizon, and the four side faces lose the floor (exactly from a room 6,144 m across at 64²,
//! 12,288 m at 128²: the threshold scales with the face size). lavapipe clips first and is right.
//!
//! We take the same steps on the CPU for the frame's first poses, where the driver is
//! SwiftShader, and say which surfaces and views it drops. Nothing is changed: what is drawn
//! is the driver's.

use std::collections::HashSet;
use std::sync::Mutex;

use glam::{DVec4, Mat4, Vec3, Vec4};

use super::gpu::ViewData;
use crate::scene::camera::FACE_NAMES;
use crate::scene::state::{room_meshes, SceneState};
use crate::scene::{Mesh, Scene};

/// Sub-pixel steps a pixel (SwiftShader's `SUBPIXEL_PRECISION_BITS` of 4).
const SUBPIXELS: f32 = 16.0;

/// The least a view must show of a triangle for its loss to be said: 16 pixels, at least one
/// pixel wide on average (its area over its longest extent). Less is a facet or a sliver seen
/// edge-on, whose snapped area rounding flips (two to seven pixels of a thin pole's facets in
/// `scenes/hard/pole-and-box.toml`, the closed pole's other facets still drawn there; a line
/// half a pixel wide of a table top at the eye's height): no surface gone.
const SHOWN_PX: f64 = 16.0;

/// Whether SwiftShader draws no pixel of the triangle `clip` (clip-space corners) that the
/// view at `viewport` (x, y, width, height) shows [`SHOWN_PX`] pixels or more of, from its
/// front: `front` is the sign of [`orientation`]'s negation for a front face (+1 in a camera
/// view, -1 in a cube face, which sees the world mirrored). A back face is culled on a closed
/// mesh, and no surface anyone sees on an open one.
pub fn dropped(clip: [Vec4; 3], viewport: Vec4, front: f64) -> bool {
    let clipped = clip.iter().any(|c| outside(*c));
    if !clipped {
        // Unclipped, the polygon is the snapped triangle itself: the two agree.
        return false;
    }
    let exact = -orientation(clip);
    if exact * front <= 0.0 {
        return false;
    }
    let snapped = snapped_area(clip, viewport);
    let wrong = snapped == 0.0 || (snapped > 0.0) != (exact > 0.0);
    // Last, as it is the dearest.
    wrong && shown_px(clip, viewport).is_some_and(|(area, width)| area >= SHOWN_PX && width >= 1.0)
}

/// SwiftShader's clip test: outside any of `-w <= x, y <= w`, `0 <= z <= w`.
fn outside(c: Vec4) -> bool {
    c.x > c.w || c.y > c.w || c.z > c.w || c.x < -c.w || c.y < -c.w || c.z < 0.0
}

/// `det [x y w]` of the corners, in f64: its sign is the clipped polygon's winding, whatever
/// side of the eye each corner is on.
fn orientation(clip: [Vec4; 3]) -> f64 {
    let [a, b, c] = clip.map(|p| [f64::from(p.x), f64::from(p.y), f64::from(p.w)]);
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// The area SwiftShader computes from the unclipped corners, step for step in f32: each
/// corner projected with `1/w` (`w` = ±0 taken as ±1), moved to the viewport (whose origin
/// is half a pixel in, `X0xF`), snapped to the nearest 1/16 pixel (clamped below 2^31 as its
/// `RoundIntClamped`, NaN to the top), the area `(y0 - y2) x1 + (y2 - y1) x0 + (y1 - y0) x2`,
/// negated when an odd number of corners is behind the eye.
fn snapped_area(clip: [Vec4; 3], viewport: Vec4) -> f32 {
    const TOP: f32 = 2_147_483_520.0;
    let half = [viewport.z / 2.0 * SUBPIXELS, viewport.w / 2.0 * SUBPIXELS];
    let centre = [
        (viewport.x + viewport.z / 2.0) * SUBPIXELS - SUBPIXELS / 2.0,
        (viewport.y + viewport.w / 2.0) * SUBPIXELS - SUBPIXELS / 2.0,
    ];
    let snap = |v: f32| {
        let v = if v.is_nan() { TOP } else { v.min(TOP) };
        v.round_ties_even() as i32 as f32
    };
    let [(x0, y0), (x1, y1), (x2, y2)] = clip.map(|c| {
        let rhw = 1.0 / if c.w == 0.0 { 1f32.copysign(c.w) } else { c.w };
        (
            snap(centre[0] + c.x * rhw * half[0]),
            snap(centre[1] + c.y * rhw * half[1]),
        )
    });
    let area = (y0 - y2) * x1 + (y2 - y1) * x0 + (y1 - y0) * x2;
    let behind = clip.iter().filter(|c| c.w.is_sign_negative()).count();
    if behind % 2 == 1 {
        -area
    } else {
        area
    }
}

/// What the view shows of the triangle, clipped to it in f64 and projected: its area in
/// pixels and its mean width (the area over its longest extent), where it covers some pixel
/// centre (crossed with each row of centres it spans); None where it covers none.
fn shown_px(clip: [Vec4; 3], viewport: Vec4) -> Option<(f64, f64)> {
    let mut polygon: Vec<DVec4> = clip.iter().map(|c| c.as_dvec4()).collect();
    let planes: [fn(DVec4) -> f64; 6] = [
        |p| p.w - p.x,
        |p| p.w + p.x,
        |p| p.w - p.y,
        |p| p.w + p.y,
        |p| p.z,
        |p| p.w - p.z,
    ];
    for plane in planes {
        polygon = clip_polygon(&polygon, plane);
        if polygon.len() < 3 {
            return None;
        }
    }
    let (w, h) = (f64::from(viewport.z), f64::from(viewport.w));
    let screen: Vec<[f64; 2]> = (polygon.iter())
        .map(|p| [(p.x / p.w + 1.0) * w / 2.0, (p.y / p.w + 1.0) * h / 2.0])
        .collect();
    let (lo, hi) = (screen.iter()).fold((f64::MAX, f64::MIN), |(lo, hi), p| {
        (lo.min(p[1]), hi.max(p[1]))
    });
    let rows = ((lo - 0.5).ceil().max(0.0) as u32)..=((hi - 0.5).floor().min(h - 1.0) as u32);
    let covers = rows.into_iter().any(|row| {
        let y = f64::from(row) + 0.5;
        // The convex polygon's span on this row: where its edges cross it.
        let (left, right) = (0..screen.len())
            .filter_map(|i| {
                let (a, b) = (screen[i], screen[(i + 1) % screen.len()]);
                let crosses = (a[1] <= y && y <= b[1]) || (b[1] <= y && y <= a[1]);
                (crosses && a[1] != b[1]).then(|| a[0] + (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]))
            })
            .fold((f64::MAX, f64::MIN), |(l, r), x| (l.min(x), r.max(x)));
        let first = (left - 0.5).ceil().max(0.0);
        first <= right - 0.5 && first < w
    });
    if !covers {
        return None;
    }
    let twice: f64 = (0..screen.len())
        .map(|i| {
            let (a, b) = (screen[i], screen[(i + 1) % screen.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    let extent = (screen.iter())
        .flat_map(|a| screen.iter().map(move |b| (a[0] - b[0]).hypot(a[1] - b[1])))
        .fold(0.0, f64::max);
    let area = twice.abs() / 2.0;
    Some((area, area / extent.max(f64::MIN_POSITIVE)))
}

/// One Sutherland–Hodgman step: the part of `polygon` where `inside(p) >= 0`.
fn clip_polygon(polygon: &[DVec4], inside: fn(DVec4) -> f64) -> Vec<DVec4> {
    let mut kept = Vec::with_capacity(polygon.len() + 1);
    for (i, &a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % polygon.len()];
        let (da, db) = (inside(a), inside(b));
        if da >= 0.0 {
            kept.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            kept.push(a + (b - a) * (da / (da - db)));
        }
    }
    kept
}

/// The frame's views by name, in `ViewData` order.
fn view_name(i: usize) -> String {
    match i {
        0..6 => format!("cube face {}", FACE_NAMES[i]),
        6 => "observer".into(),
        7 => "sensor".into(),
        8 => "observer (side by side)".into(),
        _ => "sensor (side by side)".into(),
    }
}

/// What SwiftShader drops of the frame at `state`: per surface (a wall of the room or an
/// object, by name) those of the views `drawn` (indices into `views`) it loses triangles in.
pub fn losses(scene: &Scene, state: &SceneState, views: &[ViewData], drawn: &[u32]) -> Vec<String> {
    let walls = room_meshes(&scene.room);
    let surfaces = (walls.iter().enumerate())
        .map(|(f, m)| {
            (
                format!("the room's {} wall", FACE_NAMES[f]),
                m,
                state.world_to_render(),
            )
        })
        .chain(scene.objects.iter().enumerate().map(|(i, o)| {
            (
                format!("object {}", o.name),
                &scene.meshes[o.mesh],
                state.object_to_render(scene, i),
            )
        }));
    let mut said = Vec::new();
    for (name, mesh, to_render) in surfaces {
        let lost: Vec<String> = (drawn.iter().map(|&i| i as usize))
            .filter(|&i| {
                let front = if i < 6 { -1.0 } else { 1.0 };
                let to_clip = views[i].world_to_clip * to_render;
                mesh_loses(mesh, to_clip, views[i].viewport, front)
            })
            .map(view_name)
            .collect();
        if !lost.is_empty() {
            said.push(format!("{name} in {}", lost.join(", ")));
        }
    }
    said
}

/// Whether any triangle of `mesh`, taken to clip space by `to_clip`, is dropped.
fn mesh_loses(mesh: &Mesh, to_clip: Mat4, viewport: Vec4, front: f64) -> bool {
    let clip: Vec<Vec4> = (mesh.positions.iter())
        .map(|&p: &Vec3| to_clip * p.extend(1.0))
        .collect();
    // Only a triangle with corners on both sides of the eye plane or beyond a side can be
    // clipped: a mesh wholly in front and inside is drawn as the driver snaps it.
    if !clip.iter().any(|&c| outside(c)) {
        return false;
    }
    (mesh.indices.chunks_exact(3))
        .any(|t| dropped([0, 1, 2].map(|k| clip[t[k] as usize]), viewport, front))
}

/// Says, once a process for each different text, what SwiftShader drops of the frame: a
/// warning (`crate::warnings`), since it is what the images will show, not an error.
pub fn warn(lost: &[String]) {
    static SAID: Mutex<Option<HashSet<String>>> = Mutex::new(None);
    if lost.is_empty() {
        return;
    }
    let text = format!(
        "SwiftShader leaves out triangles of {}: they cross the view's eye plane \
         nearly edge-on and reach far, and it sets a clipped triangle up from its unclipped \
         corners snapped to 1/16 pixel, which have no area (docs/scene-format.md); split those \
         surfaces into smaller pieces, raise the cube's face size, or render on lavapipe",
        lost.join("; ")
    );
    let mut said = SAID.lock().unwrap_or_else(|e| e.into_inner());
    if said.get_or_insert_with(HashSet::new).insert(text.clone()) {
        crate::warnings::warn(&text);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::ViewBasis;

    /// A cube face's front: the world is seen mirrored there.
    const CUBE_FRONT: f64 = -1.0;

    /// The two triangles of a square floor `size` m across, 3 m below the eye, in face +X's
    /// clip space, in both windings (the floor seen from above, then from below).
    fn floor(size: f32) -> Vec<[Vec4; 3]> {
        let h = size / 2.0;
        let corners = [(-h, -h), (h, -h), (h, h), (-h, h)].map(|(x, z)| Vec3::new(x, -3.0, z));
        let to_clip = ViewBasis::cube_face(Vec3::ZERO, 0).world_to_clip(0.05, 1e5);
        [[0, 2, 1], [0, 3, 2], [0, 1, 2], [0, 2, 3]]
            .map(|t| t.map(|k| to_clip * corners[k].extend(1.0)))
            .to_vec()
    }

    fn face(size: f32) -> Vec4 {
        Vec4::new(0.0, 0.0, size, size)
    }

    #[test]
    fn a_far_floor_is_dropped_where_its_corners_snap_onto_one_line() {
        // The corners' height on a face of C texels: 3 / (S/2) * C/2 * 16 sub-pixels, which
        // rounds to 0 below 1/2: S > 6,144 m at 64², 12,288 m at 128² (both measured so).
        for (c, kept, lost) in [(64.0, 6000.0, 7000.0), (128.0, 12000.0, 12500.0)] {
            let dropped_at = |size| -> Vec<bool> {
                (floor(size).iter())
                    .map(|&t| dropped(t, face(c), CUBE_FRONT))
                    .collect()
            };
            assert_eq!(dropped_at(kept), [false; 4], "{kept} m at {c}");
            // The triangle that reaches into the face, seen from above; from below (a back
            // face, culled on a closed mesh, seen by no one on an open one) it is not said.
            assert_eq!(
                dropped_at(lost),
                [true, false, false, false],
                "{lost} m at {c}"
            );
        }
    }

    #[test]
    fn a_triangle_in_front_or_behind_is_never_dropped() {
        let to_clip = ViewBasis::cube_face(Vec3::ZERO, 0).world_to_clip(0.05, 100.0);
        let corners = |x: f32| {
            [
                Vec3::new(x, -1.0, -1.0),
                Vec3::new(x, 1.0, 0.0),
                Vec3::new(x, -1.0, 1.0),
            ]
            .map(|p| to_clip * p.extend(1.0))
        };
        for front in [1.0, -1.0] {
            // In front and wholly inside, then reaching out of the face: drawn as snapped.
            assert!(!dropped(corners(5.0), face(64.0), front));
            assert!(!dropped(corners(0.5), face(64.0), front));
            // Behind the eye: nothing to draw.
            assert!(!dropped(corners(-5.0), face(64.0), front));
        }
    }

    #[test]
    fn what_is_shown_counts_pixel_centres_and_width() {
        let to_clip = ViewBasis::cube_face(Vec3::ZERO, 0).world_to_clip(0.05, 100.0);
        // `high` texels high from the face's middle row boundary (centres at 31.5 and 32.5),
        // 57.6 texels wide at its base.
        let sliver = |high: f32| {
            let y = high / 32.0 * 10.0;
            [
                Vec3::new(10.0, 0.0, -9.0),
                Vec3::new(10.0, 0.0, 9.0),
                Vec3::new(10.0, y, 0.0),
            ]
            .map(|p| to_clip * p.extend(1.0))
        };
        // 5.76 texels in area between two rows of centres: none shown.
        assert_eq!(shown_px(sliver(0.2), face(64.0)), None);
        // Across a row of centres, 25.9 texels but 0.45 wide; then 4 texels high.
        let (area, width) = shown_px(sliver(0.9), face(64.0)).unwrap();
        assert!(
            (area - 25.92).abs() < 1e-3 && (width - 0.45).abs() < 1e-3,
            "{area} {width}"
        );
        let (area, width) = shown_px(sliver(4.0), face(64.0)).unwrap();
        assert!(
            (area - 115.2).abs() < 1e-3 && (width - 2.0).abs() < 1e-3,
            "{area} {width}"
        );
    }
}
