//! The fitted models on the thesis room: their residuals recomputed here by another route
//! (the exact rays by f64 sphere geometry, the models' rays by their published formulas), each
//! fit the minimum of its own objective, the geometry of the viewpoint, and the exports read
//! back to the same numbers.

use glam::{DVec2, DVec3};

use super::*;

fn thesis() -> (Calibration, RayMap) {
    let scene = crate::scene::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/thesis-room.toml"
    )))
    .unwrap();
    Calibration::of_scene(&scene, 0.0).unwrap()
}

/// The thesis sensor from the scene file alone, in the sensor camera's frame (x right, y down,
/// z forward): the eye at the origin looking along +z at the sphere's centre `offset` away
/// (the sensor sits on the mirror's axis), pixel centre (x, y) looking along
/// (ndc_x tan_x, ndc_y tan_y, 1).
struct Sensor {
    width: u32,
    height: u32,
    tan_x: f64,
    tan_y: f64,
    offset: f64,
    radius: f64,
}

/// What a pixel sees through the mirror, by f64 geometry independent of the engine's f32
/// `mirror_reflection`.
struct ExactRay {
    /// Unit direction after the mirror, camera frame.
    direction: DVec3,
    /// The cosine of the angle of incidence: near 0 for a ray grazing the sphere, where the
    /// reflected direction is most sensitive to rounding (it turns by 2 / cos per radian the
    /// incidence angle moves).
    cos_incidence: f64,
}

impl Sensor {
    fn thesis() -> Self {
        let scene = crate::scene::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/thesis-room.toml"
        )))
        .unwrap();
        let [width, height] = scene.sensor.resolution;
        let tan_y = (f64::from(scene.sensor.fov_y_deg).to_radians() / 2.0).tan();
        Self {
            width,
            height,
            tan_x: tan_y * f64::from(width) / f64::from(height),
            tan_y,
            offset: f64::from(scene.sensor.offset_m),
            radius: f64::from(scene.mirror.radius_m),
        }
    }

    /// The ray's closest approach to the sphere's centre, relative to the radius, minus 1:
    /// negative when the pixel sees the mirror.
    fn miss_margin(&self, x: u32, y: u32) -> f64 {
        let d = self.camera_ray(x, y);
        let along = d.z * self.offset;
        (self.offset * self.offset - along * along).max(0.0).sqrt() / self.radius - 1.0
    }

    fn camera_ray(&self, x: u32, y: u32) -> DVec3 {
        let ndc_x = 2.0 * (f64::from(x) + 0.5) / f64::from(self.width) - 1.0;
        let ndc_y = 2.0 * (f64::from(y) + 0.5) / f64::from(self.height) - 1.0;
        DVec3::new(ndc_x * self.tan_x, ndc_y * self.tan_y, 1.0).normalize()
    }

    /// The reflected ray of pixel (x, y); None when its ray passes the sphere. A ray grazing
    /// it (the discriminant rounds below 0) reflects as the tangent it is.
    fn exact(&self, x: u32, y: u32, grazing_counts: bool) -> Option<ExactRay> {
        let d = self.camera_ray(x, y);
        let centre = DVec3::new(0.0, 0.0, self.offset);
        let along = d.dot(centre);
        let squared_gap = self.radius * self.radius - (centre.length_squared() - along * along);
        if squared_gap < 0.0 && !grazing_counts {
            return None;
        }
        let t = along - squared_gap.max(0.0).sqrt();
        let normal = (d * t - centre) / self.radius;
        let cos_incidence = -d.dot(normal);
        Some(ExactRay {
            direction: (d + 2.0 * cos_incidence * normal).normalize(),
            cos_incidence,
        })
    }
}

/// The angle between two unit vectors in degrees, by the chord: 2 asin(|a - b| / 2) (the
/// engine takes atan2 of the cross and dot products).
fn chord_angle_deg(a: DVec3, b: DVec3) -> f64 {
    (2.0 * ((a - b).length() / 2.0).min(1.0).asin()).to_degrees()
}

/// Mei's ray for OpenCV pixel `px` by the model's geometry rather than the engine's algebra:
/// K^-1, then the radial distortion undone by bisection on its increasing branch (the
/// tangential terms are left out: the fit's are below 1e-8, checked in the test, and move a
/// direction by less than 3 |p| r^2 < 1e-7 rad), then the lift to the unit sphere in polar
/// form: a direction at angle theta from the axis projects to r = sin(theta) / (cos(theta) +
/// xi), so theta = atan(r) + asin(r xi / sqrt(1 + r^2)) (the root nearer the axis), which
/// exists while r^2 (xi^2 - 1) <= 1: beyond, the pixel is past the model's horizon (None).
fn mei_ray(m: &MeiModel, px: DVec2) -> Option<DVec3> {
    let yd = (px.y - m.cy) / m.fy;
    let xd = (px.x - m.cx - m.skew * yd) / m.fx;
    let rd = xd.hypot(yd);
    let distort = |r: f64| r * (1.0 + m.k1 * r * r + m.k2 * r.powi(4));
    // The branch ends where d/dr distort = 1 + 3 k1 r^2 + 5 k2 r^4 first reaches 0 (a root
    // s = r^2 of 5 k2 s^2 + 3 k1 s + 1; with k2 = 0, of 3 k1 s + 1).
    let disc = 9.0 * m.k1 * m.k1 - 20.0 * m.k2;
    let roots = if m.k2 == 0.0 {
        vec![-1.0 / (3.0 * m.k1)]
    } else if disc >= 0.0 {
        [-1.0, 1.0]
            .map(|sign| (-3.0 * m.k1 + sign * disc.sqrt()) / (10.0 * m.k2))
            .to_vec()
    } else {
        Vec::new()
    };
    let end = roots
        .into_iter()
        .filter(|s| *s > 0.0)
        .fold(f64::INFINITY, f64::min)
        .sqrt();
    let mut hi = if end.is_finite() { end } else { 1.0 };
    while !end.is_finite() && distort(hi) < rd {
        hi *= 2.0;
    }
    if distort(hi) < rd {
        return None;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if distort(mid) < rd {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let r = 0.5 * (lo + hi);
    let s = r * m.xi / (1.0 + r * r).sqrt();
    if s > 1.0 {
        return None;
    }
    let theta = r.atan() + s.asin();
    let (ux, uy) = if rd > 0.0 {
        (xd / rd, yd / rd)
    } else {
        (0.0, 0.0)
    };
    Some(DVec3::new(theta.sin() * ux, theta.sin() * uy, theta.cos()))
}

/// Mei's projection of the direction `d` (OpenCV's `omnidir::projectPoints`, written out from
/// Mei and Rives' paper): None behind the second centre.
fn mei_pixel(m: &MeiModel, d: DVec3) -> Option<DVec2> {
    let s = d.normalize();
    let w = s.z + m.xi;
    if w <= 0.0 {
        return None;
    }
    let (x, y) = (s.x / w, s.y / w);
    let r2 = x * x + y * y;
    let radial = 1.0 + m.k1 * r2 + m.k2 * r2 * r2;
    let xd = x * radial + 2.0 * m.p1 * x * y + m.p2 * (r2 + 2.0 * x * x);
    let yd = y * radial + m.p1 * (r2 + 2.0 * y * y) + 2.0 * m.p2 * x * y;
    Some(DVec2::new(m.fx * xd + m.skew * yd + m.cx, m.fy * yd + m.cy))
}

/// OCamCalib's `cam2world` as its toolbox documents it: (row, col) through the inverse affine
/// part to (x', y'), the ray (x', y', f(rho)).
fn ocam_ray(m: &OcamModel, row: f64, col: f64) -> DVec3 {
    let det = m.c - m.d * m.e;
    let (r, c) = (row - m.xc, col - m.yc);
    let (x, y) = ((r - m.d * c) / det, (-m.e * r + m.c * c) / det);
    let rho = x.hypot(y);
    let f =
        m.ss.iter()
            .enumerate()
            .map(|(k, a)| a * rho.powi(k as i32))
            .sum();
    DVec3::new(x, y, f).normalize()
}

/// Mean, nearest-rank p99 (the ceil(0.99 n)-th smallest) and maximum, computed here.
fn summary(mut values: Vec<f64>) -> (f64, f64, f64) {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    let mean = values.iter().sum::<f64>() / n as f64;
    let p99 = values[(0.99 * n as f64).ceil() as usize - 1];
    (mean, p99, values[n - 1])
}

/// The residuals are not compared with figures from a run: they are recomputed here, pixel by
/// pixel, by another route (the exact ray by f64 sphere geometry from the scene file, the
/// model's ray by its formula written out above, the angle by the chord), and so are their
/// mean, p99 and max and the pixels without a ray. (That each fit is as good as its model
/// allows is the next test's.)
///
/// Tolerances: the engine's ray map is f32. Its ray-sphere discriminant b^2 - (|eye|^2 - R^2)
/// is rounded at |eye|^2 = 6.25 (7.5e-7 absolute); the discriminant's square root is the
/// incidence cosine c (R = 1), so the hit distance carries 7.5e-7 / 2c, which turns the
/// normal by as much and the reflected ray by twice that: 7.5e-7 / c rad = 4.3e-5 / c deg.
/// A pixel's residual may differ from ours by that; we allow 1e-4 / c deg, plus 1e-5 deg for
/// the rounding of the f32 directions themselves (c is 4e-3 at the most grazing mirror pixel
/// here, 0.03 deg; most pixels have c near 1). A mean differs by at most the mean of those
/// allowances, a p99 or max by at most the largest (they are 1-Lipschitz in the values).
#[test]
fn the_residuals_are_the_angles_between_the_models_rays_and_the_exact_rays() {
    let (cal, map) = thesis();
    let sensor = Sensor::thesis();
    let (w, h) = (sensor.width, sensor.height);
    assert_eq!((cal.width, cal.height), (w, h));
    let ambiguous = assert_mirror_pixels_are_the_spheres(&sensor, &map);
    let exact = exact_rays_of_mirror_pixels(&sensor, &map);
    assert!(ambiguous < 100, "{ambiguous} pixels graze the sphere");
    assert_eq!(cal.mirror_pixels, exact.len());
    let worst_tolerance = exact
        .iter()
        .map(|(_, _, e)| residual_tolerance(e))
        .fold(0.0, f64::max);
    let mean_tolerance = exact
        .iter()
        .map(|(_, _, e)| residual_tolerance(e))
        .sum::<f64>()
        / exact.len() as f64;

    // Mei / omnidir: frame (right, down, -forward). Our route leaves the tangential terms
    // out, which holds while they are this small (`mei_ray`); a pixel has no ray exactly
    // where ours has none, past the model's horizon.
    assert!(
        cal.mei.p1.abs() < 1e-8 && cal.mei.p2.abs() < 1e-8,
        "{:?}",
        cal.mei
    );
    let (mei, mei_without) = recomputed_mei_residuals(&cal, &exact);
    assert_eq!(cal.mei_residual.without_ray, mei_without);

    // OCamCalib: frame (down, right, forward); its polynomial gives every pixel a ray.
    let ocam = recomputed_ocam_residuals(&cal, &exact);
    assert_eq!(cal.ocam_residual.without_ray, 0);

    for (name, stats, values) in [
        ("omnidir", cal.mei_residual.stats, mei),
        ("OCamCalib", cal.ocam_residual.stats, ocam),
    ] {
        assert_summary_recomputed(name, stats, values, mean_tolerance, worst_tolerance);
    }
    assert_symmetric_about_the_axis(&cal);
}

/// Asserts that the map's mirror pixels are those whose ray meets the sphere, except within
/// 1e-5 of grazing; returns how many pixels are that close.
fn assert_mirror_pixels_are_the_spheres(sensor: &Sensor, map: &RayMap) -> usize {
    // The mirror pixels: those whose ray passes the centre closer than the radius. A ray
    // within 1e-5 of the radius of grazing may round either way in f32 (the engine's
    // discriminant carries ~1e-6 of rounding): those are the only ones allowed to differ. The
    // band is 0.005 px wide around a rim of 1,200 px, so it holds a handful of pixel centres;
    // counted, so that the exemption stays that small.
    let mut ambiguous = 0;
    for y in 0..sensor.height {
        for x in 0..sensor.width {
            let margin = sensor.miss_margin(x, y);
            if margin.abs() < 1e-5 {
                ambiguous += 1;
            } else {
                assert_eq!(map.get(x, y).is_some(), margin < 0.0, "pixel ({x}, {y})");
            }
        }
    }
    ambiguous
}

/// The exact f64 reflected ray of every pixel the map has a ray for, with its (x, y).
fn exact_rays_of_mirror_pixels(sensor: &Sensor, map: &RayMap) -> Vec<(u32, u32, ExactRay)> {
    (0..sensor.height)
        .flat_map(|y| (0..sensor.width).map(move |x| (x, y)))
        .filter(|&(x, y)| map.get(x, y).is_some())
        .map(|(x, y)| (x, y, sensor.exact(x, y, true).unwrap()))
        .collect()
}

/// How far (degrees) the engine's f32 residual may be from ours at a pixel (see the test).
fn residual_tolerance(e: &ExactRay) -> f64 {
    1e-5 + 1e-4 / e.cos_incidence
}

/// Mei's residuals recomputed at every exact ray, each asserted against the engine's: (the
/// residuals where the model has a ray, the pixels where it has none).
fn recomputed_mei_residuals(
    cal: &Calibration,
    exact: &[(u32, u32, ExactRay)],
) -> (Vec<f64>, usize) {
    let w = cal.width;
    let omnidir = |d: DVec3| DVec3::new(d.x, d.y, -d.z);
    let (mut mei, mut mei_without) = (Vec::new(), 0);
    for (x, y, e) in exact {
        let i = (y * w + x) as usize;
        let engine = cal.mei_residual.degrees[i].expect("a mirror pixel");
        match mei_ray(&cal.mei, DVec2::new(f64::from(*x), f64::from(*y))) {
            Some(ray) => {
                let deg = chord_angle_deg(ray, omnidir(e.direction));
                assert!(
                    (engine - deg).abs() <= residual_tolerance(e),
                    "omnidir ({x}, {y}): {engine} against {deg}"
                );
                mei.push(deg);
            }
            None => {
                assert!(engine.is_nan(), "omnidir ({x}, {y}): {engine}, no ray here");
                mei_without += 1;
            }
        }
    }
    (mei, mei_without)
}

/// OCamCalib's residuals recomputed at every exact ray, each asserted against the engine's.
fn recomputed_ocam_residuals(cal: &Calibration, exact: &[(u32, u32, ExactRay)]) -> Vec<f64> {
    let w = cal.width;
    let ocamcalib = |d: DVec3| DVec3::new(d.y, d.x, d.z);
    let mut ocam = Vec::new();
    for (x, y, e) in exact {
        let i = (y * w + x) as usize;
        let engine = cal.ocam_residual.degrees[i].expect("a mirror pixel");
        let deg = chord_angle_deg(
            ocam_ray(&cal.ocam, f64::from(*y), f64::from(*x)),
            ocamcalib(e.direction),
        );
        assert!(
            (engine - deg).abs() <= residual_tolerance(e),
            "OCamCalib ({x}, {y}): {engine} against {deg}"
        );
        ocam.push(deg);
    }
    ocam
}

/// Asserts the engine's mean, p99 and max of model `name` against ours from `values`.
fn assert_summary_recomputed(
    name: &str,
    stats: record::Summary,
    values: Vec<f64>,
    mean_tolerance: f64,
    worst_tolerance: f64,
) {
    let (mean, p99, max) = summary(values);
    for (what, got, want, tolerance) in [
        ("mean", stats.mean, mean, mean_tolerance),
        ("p99", stats.p99, p99, worst_tolerance),
        ("max", stats.max, max, worst_tolerance),
    ] {
        assert!(
            (got - want).abs() <= tolerance,
            "{name} {what}: {got} against {want} recomputed"
        );
    }
}

/// Asserts both fits' centres on the image's centre and Mei's pixels square.
fn assert_symmetric_about_the_axis(cal: &Calibration) {
    // The set-up is symmetric about the sensor's axis: centred, square, no tangential terms.
    let centre = (cal.width as f64 - 1.0) / 2.0;
    assert!((cal.mei.cx - centre).abs() < 1e-3 && (cal.mei.cy - centre).abs() < 1e-3);
    assert!((cal.mei.fx / cal.mei.fy - 1.0).abs() < 1e-6);
    assert!((cal.ocam.xc - centre).abs() < 1e-3 && (cal.ocam.yc - centre).abs() < 1e-3);
}

/// One parameter of Mei's model, to step.
type MeiField = fn(&mut MeiModel) -> &mut f64;
/// A step of one parameter of OCamCalib's model.
type OcamStep = Box<dyn Fn(&mut OcamModel, f64)>;

/// Each fit is the least-squares minimum of its own objective, written out here from the
/// models' definitions over the exact ray map's rays (checked against f64 geometry above):
/// moving any one parameter a little either way raises it. This is what the copied residual
/// figures used to guard (a fit that gets worse fails) without depending on a run: a fit that
/// stopped early, or converged on something else, has a direction downhill. The objectives:
/// omnidir, the reprojection error in pixels (OpenCV's and Kalibr's); OCamCalib, the chord
/// between the model's and the exact unit ray. The cost each fit reports is ours (1e-9: the
/// same terms summed in another order).
#[test]
fn each_fit_is_the_minimum_of_its_objective() {
    let (cal, map) = thesis();
    let exact = exact_directions_in_camera_frame(&cal, &map);
    let best = mei_cost(&exact, &cal.mei);
    assert!(
        agrees_to_1e9(best, cal.mei_fit.final_cost),
        "{best} {:?}",
        cal.mei_fit
    );
    for (name, field, step) in mei_steps(&cal.mei) {
        for sign in [-1.0, 1.0] {
            let mut m = cal.mei;
            *field(&mut m) += sign * step;
            let cost = mei_cost(&exact, &m);
            assert!(
                cost > best,
                "omnidir {name} {:+e}: {cost} <= {best}",
                sign * step
            );
        }
    }

    let best = ocam_cost(&exact, &cal.ocam);
    assert!(
        agrees_to_1e9(best, cal.ocam_fit.final_cost),
        "{best} {:?}",
        cal.ocam_fit
    );
    for (name, apply, step) in &ocam_steps(&cal.ocam) {
        for sign in [-1.0, 1.0] {
            let mut m = cal.ocam.clone();
            apply(&mut m, sign * step);
            let cost = ocam_cost(&exact, &m);
            assert!(
                cost > best,
                "OCamCalib {name} {:+e}: {cost} <= {best}",
                sign * step
            );
        }
    }
}

/// Pixel centre (OpenCV's 0-based x, y) and exact direction in the camera frame (right,
/// down, forward) of every pixel of `map` with a ray.
fn exact_directions_in_camera_frame(cal: &Calibration, map: &RayMap) -> Vec<(DVec2, DVec3)> {
    let axes = cal.axes;
    (0..map.height)
        .flat_map(|y| (0..map.width).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            let d = map.get(x, y)?.direction.as_dvec3().normalize();
            Some((
                DVec2::new(f64::from(x), f64::from(y)),
                DVec3::new(d.dot(axes.right), d.dot(axes.down), d.dot(axes.forward)),
            ))
        })
        .collect()
}

/// Mei's objective: the squared reprojection errors in pixels, summed over `exact`.
fn mei_cost(exact: &[(DVec2, DVec3)], m: &MeiModel) -> f64 {
    // Lost points cost 1e4 px in the fit, as in `MeiModel::fit`.
    exact
        .iter()
        .map(|&(px, d)| {
            let p = mei_pixel(m, DVec3::new(d.x, d.y, -d.z));
            p.map_or(2.0 * 1e8, |p| (p - px).length_squared())
        })
        .sum()
}

/// OCamCalib's objective: the squared chords between model and exact rays, summed.
fn ocam_cost(exact: &[(DVec2, DVec3)], m: &OcamModel) -> f64 {
    exact
        .iter()
        .map(|&(px, d)| (ocam_ray(m, px.y, px.x) - DVec3::new(d.y, d.x, d.z)).length_squared())
        .sum()
}

/// Whether the cost `a` is the reported `b` to 1e-9 relative.
fn agrees_to_1e9(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b
}

/// Each of Mei's nine parameters with the step to move it by.
fn mei_steps(mei: &MeiModel) -> [(&'static str, MeiField, f64); 9] {
    // Steps well above the noise of a sum over 117,652 pixels and well inside the minimum's
    // basin: 1e-4 of a focal length, 0.01 px, 1e-4 in xi and k, 1e-5 in p.
    let f = mei.fx;
    [
        ("fx", |m| &mut m.fx, 1e-4 * f),
        ("fy", |m| &mut m.fy, 1e-4 * f),
        ("cx", |m| &mut m.cx, 0.01),
        ("cy", |m| &mut m.cy, 0.01),
        ("xi", |m| &mut m.xi, 1e-4),
        ("k1", |m| &mut m.k1, 1e-4),
        ("k2", |m| &mut m.k2, 1e-4),
        ("p1", |m| &mut m.p1, 1e-5),
        ("p2", |m| &mut m.p2, 1e-5),
    ]
}

/// Each of OCamCalib's fitted parameters with a step of it and its size.
fn ocam_steps(ocam: &OcamModel) -> Vec<(String, OcamStep, f64)> {
    // 0.01 px for the centre, 1e-5 for the affine part, 1e-4 of each coefficient.
    let mut steps: Vec<(String, OcamStep, f64)> = vec![
        ("xc".into(), Box::new(|m, s| m.xc += s), 0.01),
        ("yc".into(), Box::new(|m, s| m.yc += s), 0.01),
        ("c".into(), Box::new(|m, s| m.c += s), 1e-5),
        ("d".into(), Box::new(|m, s| m.d += s), 1e-5),
        ("e".into(), Box::new(|m, s| m.e += s), 1e-5),
    ];
    for k in [0, 2, 3, 4] {
        let step = 1e-4 * ocam.ss[k].abs();
        steps.push((format!("ss{k}"), Box::new(move |m, s| m.ss[k] += s), step));
    }
    steps
}

/// Every reflected ray lies in a plane through the sensor's axis, so the point nearest to all
/// of them is on that axis, inside the sphere (between its centre and its lowest point, where
/// the paraxial rays' virtual focus is), and the grazing rim rays pass it at most a radius
/// away.
#[test]
fn the_viewpoint_is_on_the_axis_inside_the_sphere() {
    let (cal, _) = thesis();
    let v = cal.viewpoint;
    assert!(v.x.abs() < 1e-6 && v.z.abs() < 1e-6, "{v}");
    // Local coordinates: the sphere's centre at y = 0 (radius 1 m).
    assert!(v.y < 0.0 && v.y > -1.0, "{v}");
    assert!(cal.ray_distance_m.max < 1.0, "{:?}", cal.ray_distance_m);
}

/// The exports, read back, are the fitted models exactly (17 significant digits).
#[test]
fn the_exports_read_back_to_the_same_models() {
    let (cal, _) = thesis();
    let (w, h) = (cal.width, cal.height);
    let (mei, size) = export::read_opencv_yaml(&export::opencv_yaml(&cal.mei, w, h)).unwrap();
    assert_eq!((mei, size), (cal.mei, [w, h]));
    let (mei, size) =
        export::read_kalibr_yaml(&export::kalibr_yaml(&cal.mei, w, h, "/camera/image_clean"))
            .unwrap();
    assert_eq!((mei, size), (cal.mei, [w, h]));
    let ocam = export::read_ocamcalib_txt(&export::ocamcalib_txt(&cal.ocam)).unwrap();
    assert_eq!(ocam, cal.ocam);
}

/// A point far along a pixel's exact ray projects, through both models, near that pixel:
/// where the angular residual is small, so is the pixel error.
#[test]
fn far_points_project_near_their_pixels() {
    let (cal, map) = thesis();
    let points = cal.check_points(&map, 32, &[1000.0]);
    // One point per pixel of the stride-32 grid (16, 48, ..., 496 in rows and columns) that
    // sees the mirror, by the f64 geometry; none of those pixels grazes the sphere.
    let sensor = Sensor::thesis();
    let grid: Vec<(u32, u32)> = (16..sensor.height)
        .step_by(32)
        .flat_map(|y| (16..sensor.width).step_by(32).map(move |x| (x, y)))
        .collect();
    assert!(grid
        .iter()
        .all(|&(x, y)| sensor.miss_margin(x, y).abs() > 1e-5));
    let on_mirror = grid
        .iter()
        .filter(|&&(x, y)| sensor.exact(x, y, false).is_some())
        .count();
    assert_eq!(points.len(), on_mirror);
    for p in &points {
        let [x, y] = p.pixel.map(f64::from);
        let degrees = cal.mei_residual.degrees[(p.pixel[1] * cal.width + p.pixel[0]) as usize];
        if degrees.is_some_and(|d| d < 0.5) {
            let [u, v] = p
                .omnidir_pixel
                .expect("a small residual means a projection");
            assert!((u - x).hypot(v - y) < 1.0, "{p:?}");
        }
        let ocam = cal.ocam_residual.degrees[(p.pixel[1] * cal.width + p.pixel[0]) as usize];
        if ocam.is_some_and(|d| d < 0.5) {
            let [r, c] = p.ocamcalib_row_col;
            assert!((r - y).hypot(c - x) < 1.0, "{p:?}");
        }
    }
}
