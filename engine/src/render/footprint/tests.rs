//! `fill_within` against a pixel-by-pixel account of what an update must re-render.

use super::*;

fn rect(x0: u32, y0: u32, x1: u32, y1: u32) -> PixelRect {
    PixelRect { x0, y0, x1, y1 }
}

/// Faces of 64 texels (8-texel tiles): per pixel, whether `tiles` marks its tile.
fn marked(tiles: &Tiles, f: usize, x: u32, y: u32) -> bool {
    tiles.has(f, x / 8, y / 8)
}

/// What the update re-renders covers, once each, exactly the needed tiles not valid and the
/// pixels `dirty` changed within needed tiles; every needed tile is valid afterwards, and a
/// valid one the update changed is not, unless needed.
#[test]
fn an_update_re_renders_the_stale_tiles_and_the_dirty_pixels_it_needs() {
    let size = 64;
    let mut needed = Tiles::none(size);
    let mut valid = Tiles::none(size);
    for (f, tx, ty) in [
        (0, 0, 0),
        (0, 1, 0),
        (0, 2, 2),
        (0, 3, 2),
        (1, 5, 5),
        (3, 7, 7),
    ] {
        needed.set(f, tx, ty);
    }
    for (f, tx, ty) in [
        (0, 0, 0),
        (0, 2, 2),
        (0, 6, 0),
        (0, 6, 6),
        (1, 5, 5),
        (4, 1, 1),
    ] {
        valid.set(f, tx, ty);
    }
    let mut dirty = Dirty::faces(0b1_0011);
    dirty.rects[0] = vec![
        rect(4, 4, 20, 6),
        rect(18, 17, 30, 40),
        rect(50, 50, 52, 52),
    ];
    dirty.rects[1] = vec![rect(0, 0, 3, 3)];
    // Face 4 dirty whole: its valid tile is changed and, not needed, no longer valid.
    let (fill, after) = fill_within(&needed, &valid, &dirty, size);
    let in_dirty = |f: usize, x: u32, y: u32| {
        dirty.mask & (1 << f) != 0
            && (dirty.rects[f].is_empty()
                || (dirty.rects[f].iter())
                    .any(|r| (r.x0..r.x1).contains(&x) && (r.y0..r.y1).contains(&y)))
    };
    for f in 0..6 {
        let rects = &fill.rects[f];
        let whole = fill.mask & (1 << f) != 0 && rects.is_empty();
        for y in 0..size {
            for x in 0..size {
                let times = if whole {
                    1
                } else {
                    (rects.iter())
                        .filter(|r| (r.x0..r.x1).contains(&x) && (r.y0..r.y1).contains(&y))
                        .count()
                };
                let need = marked(&needed, f, x, y);
                let want = need && (!marked(&valid, f, x, y) || in_dirty(f, x, y));
                assert_eq!(times, usize::from(want), "face {f}, pixel {x}, {y}");
            }
        }
    }
    // Face 1's needed tile is valid and its dirty rectangle misses it; face 4's dirty whole
    // face needs nothing.
    assert_eq!(fill.mask, 0b1001, "faces 0 and 3 (a stale tile) re-render");
    assert_eq!(
        after,
        needed.union(&valid.without(&changed_tiles(&dirty, size)))
    );
    assert!(after.has(0, 6, 0), "valid and untouched: kept");
    assert!(
        !after.has(0, 6, 6),
        "valid, under a dirty rectangle and not needed: dropped"
    );
    assert!(
        !after.has(4, 1, 1),
        "valid, changed and not needed: dropped"
    );
}

/// Nothing dirty and nothing newly needed: nothing re-rendered. Every tile needed and none
/// valid: whole faces.
#[test]
fn the_extremes() {
    let size = 64;
    let all = Tiles::all(size);
    let (fill, after) = fill_within(&all, &all, &Dirty::default(), size);
    assert_eq!(fill, Dirty::default());
    assert_eq!(after, all);
    let (fill, after) = fill_within(&all, &Tiles::none(size), &Dirty::default(), size);
    assert_eq!(fill, Dirty::faces(0x3F));
    assert_eq!(after, all);
}
