//! The CPU twin of `shaders/include/materials.glsl`: the same functions, line by line, so that
//! the reference shades exactly like the GPU and the only difference left is the cube map.

use glam::{Vec2, Vec3};

use crate::scene::{DirectionalLight, Material, MaterialKind, TextureData};

/// GLSL `mod(x, y)` for y > 0 (result in [0, y)), unlike Rust's `%`.
fn glsl_mod(x: f32, y: f32) -> f32 {
    x - y * (x / y).floor()
}

/// GLSL `fract`.
fn fract(x: f32) -> f32 {
    x - x.floor()
}

/// `checker_parity`: 0 or 1 by the parity of the integer cell holding uv * tiles.
pub fn checker_parity(uv: Vec2, tiles: f32) -> f32 {
    let cell = (uv * tiles).floor();
    glsl_mod(cell.x + cell.y, 2.0)
}

/// `grid_line`: 1 on a grid line (cell borders, `w` of a cell wide), 0 inside a cell.
pub fn grid_line(uv: Vec2, tiles: f32, w: f32) -> f32 {
    let f = Vec2::new(fract(uv.x * tiles), fract(uv.y * tiles));
    let step = |edge: f32, x: f32| if x < edge { 0.0f32 } else { 1.0 };
    let on_x = step(f.x, 0.5 * w) + step(1.0 - 0.5 * w, f.x);
    let on_y = step(f.y, 0.5 * w) + step(1.0 - 0.5 * w, f.y);
    (on_x + on_y).min(1.0)
}

fn mix(a: Vec3, b: Vec3, t: f32) -> Vec3 {
    a * (1.0 - t) + b * t
}

/// The sRGB-to-linear decode a `*_SRGB` texture format applies to each texel.
pub fn srgb_to_linear(c: u8) -> f32 {
    let v = f32::from(c) / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Bilinear, repeating lookup of a texture at `uv` (texel centres at (i + 0.5) / size), each
/// texel decoded from sRGB before filtering, as the GPU's sampler does. A GPU filters with
/// limited sub-texel precision (8 bits is typical), so the two agree to about 1/256 of the
/// difference between neighbouring texels, not to float rounding.
pub fn sample_bilinear(t: &TextureData, uv: Vec2) -> Vec3 {
    let (w, h) = (t.width as i64, t.height as i64);
    let x = uv.x * t.width as f32 - 0.5;
    let y = uv.y * t.height as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |i: i64, j: i64| {
        let (i, j) = (i.rem_euclid(w), j.rem_euclid(h));
        let k = ((j * w + i) * 4) as usize;
        Vec3::new(
            srgb_to_linear(t.rgba8[k]),
            srgb_to_linear(t.rgba8[k + 1]),
            srgb_to_linear(t.rgba8[k + 2]),
        )
    };
    let (i, j) = (x0 as i64, y0 as i64);
    let top = mix(texel(i, j), texel(i + 1, j), fx);
    let bottom = mix(texel(i, j + 1), texel(i + 1, j + 1), fx);
    mix(top, bottom, fy)
}

/// `material_albedo`: `p` is in render space (relative to the mirror centre).
pub fn material_albedo(m: &Material, p: Vec3, uv: Vec2, textures: &[TextureData]) -> Vec3 {
    match &m.kind {
        MaterialKind::Color { color } => *color,
        MaterialKind::Checker { a, b, tiles } => mix(*a, *b, checker_parity(uv, *tiles)),
        MaterialKind::Grid {
            background,
            line,
            tiles,
            line_width,
        } => mix(*background, *line, grid_line(uv, *tiles, *line_width)),
        MaterialKind::Texture {
            texture,
            tint,
            tiles,
        } => *tint * sample_bilinear(&textures[*texture], uv * *tiles),
        MaterialKind::Direction => Vec3::splat(0.5) + 0.5 * p.normalize(),
    }
}

/// `shade`: unlit albedo, or albedo * (ambient + (1 - ambient) * max(0, N.L)).
pub fn shade(albedo: Vec3, n: Vec3, light: Option<&DirectionalLight>) -> Vec3 {
    match light {
        None => albedo,
        Some(l) => {
            let lambert = n.normalize().dot(l.direction).max(0.0);
            albedo * (l.ambient + (1.0 - l.ambient) * lambert)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checker_and_grid_known_answers() {
        assert_eq!(checker_parity(Vec2::new(0.05, 0.05), 10.0), 0.0);
        assert_eq!(checker_parity(Vec2::new(0.15, 0.05), 10.0), 1.0);
        // Negative cells keep GLSL's mod: (-1 + 0) mod 2 = 1.
        assert_eq!(checker_parity(Vec2::new(-0.05, 0.05), 10.0), 1.0);
        assert_eq!(grid_line(Vec2::new(0.5, 0.5), 1.0, 0.1), 0.0);
        assert_eq!(grid_line(Vec2::new(0.01, 0.5), 1.0, 0.1), 1.0);
    }

    #[test]
    fn bilinear_between_two_texels_is_their_mean() {
        let t = TextureData {
            path: "t".into(),
            width: 2,
            height: 1,
            rgba8: vec![0, 0, 0, 255, 255, 255, 255, 255],
        };
        // Halfway between texel centres 0.25 and 0.75.
        let c = sample_bilinear(&t, Vec2::new(0.5, 0.5));
        assert!((c - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        // On a texel centre: that texel.
        assert_eq!(sample_bilinear(&t, Vec2::new(0.75, 0.5)), Vec3::ONE);
    }
}
