//! The footprint's unit: square tiles of a cube face's level 0, one bit each
//! ([`Tiles`]), as the marking pass writes them (`footprint_marks.glsl`: face after face, row
//! after row), and the disjoint rectangles of pixels a set of tiles covers, which the cube
//! fill's dirty-rectangles path draws.

use crate::scene::pixel_rect::PixelRect;

/// One bit a tile of each of a cube's six faces.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tiles {
    /// Level-0 texels a face side.
    face_size: u32,
    /// Texels a tile side (the last tile of a row or column may be cut by the face's edge).
    tile: u32,
    /// Tiles a face side.
    per_side: u32,
    /// Bit `i` of the flat index face · per_side² + row · per_side + column.
    words: Vec<u32>,
}

/// A tile's side for faces of `face_size` texels: a sixteenth of the face, within 8 to 32
/// texels. Smaller tiles fit the footprint closer, but each rectangle costs the fill its
/// draws' set-up; at 512² faces a tile is 32 × 32 (a level-5 texel), 16 × 16 tiles a face.
pub fn tile_side(face_size: u32) -> u32 {
    (face_size / 16).clamp(8, 32)
}

impl Tiles {
    /// No tile of faces of `face_size` texels.
    pub fn none(face_size: u32) -> Self {
        let tile = tile_side(face_size);
        let per_side = face_size.div_ceil(tile).max(1);
        let bits = 6 * per_side as usize * per_side as usize;
        Self {
            face_size,
            tile,
            per_side,
            words: vec![0; bits.div_ceil(32)],
        }
    }

    /// Every tile.
    pub fn all(face_size: u32) -> Self {
        let mut t = Self::none(face_size);
        for i in 0..t.count() {
            t.set_index(i);
        }
        t
    }

    /// The marks as the pass wrote them (`words` holds at least [`Self::words`] words).
    pub fn from_words(face_size: u32, words: &[u32]) -> Self {
        let mut t = Self::none(face_size);
        let n = t.words.len();
        t.words.copy_from_slice(&words[..n]);
        // Bits past the last tile are not tiles.
        for i in t.count()..n * 32 {
            t.words[i / 32] &= !(1 << (i % 32));
        }
        t
    }

    /// Words the marks take.
    pub fn words(face_size: u32) -> usize {
        Self::none(face_size).words.len()
    }

    /// Texels a tile side, and tiles a face side.
    pub fn layout(&self) -> (u32, u32) {
        (self.tile, self.per_side)
    }

    fn count(&self) -> usize {
        6 * (self.per_side * self.per_side) as usize
    }

    fn index(&self, face: usize, tx: u32, ty: u32) -> usize {
        (face * self.per_side as usize + ty as usize) * self.per_side as usize + tx as usize
    }

    fn set_index(&mut self, i: usize) {
        self.words[i / 32] |= 1 << (i % 32);
    }

    /// Whether tile (tx, ty) of `face` is marked.
    pub fn has(&self, face: usize, tx: u32, ty: u32) -> bool {
        let i = self.index(face, tx, ty);
        self.words[i / 32] & (1 << (i % 32)) != 0
    }

    /// Marks tile (tx, ty) of `face`.
    pub fn set(&mut self, face: usize, tx: u32, ty: u32) {
        let i = self.index(face, tx, ty);
        self.set_index(i);
    }

    /// Marks every tile of `face` that shares a pixel with `r`.
    pub fn set_under(&mut self, face: usize, r: &PixelRect) {
        if r.area() == 0 {
            return;
        }
        let last = self.per_side - 1;
        for ty in (r.y0 / self.tile).min(last)..=((r.y1 - 1) / self.tile).min(last) {
            for tx in (r.x0 / self.tile).min(last)..=((r.x1 - 1) / self.tile).min(last) {
                self.set(face, tx, ty);
            }
        }
    }

    /// Each word combined with `other`'s by `op`.
    fn zip(&self, other: &Self, op: impl Fn(u32, u32) -> u32) -> Self {
        assert_eq!(self.face_size, other.face_size, "tiles of one cube");
        let mut t = self.clone();
        for (w, o) in t.words.iter_mut().zip(&other.words) {
            *w = op(*w, *o);
        }
        t
    }

    pub fn union(&self, other: &Self) -> Self {
        self.zip(other, |a, b| a | b)
    }

    pub fn intersection(&self, other: &Self) -> Self {
        self.zip(other, |a, b| a & b)
    }

    /// The tiles of `self` not in `other`.
    pub fn without(&self, other: &Self) -> Self {
        self.zip(other, |a, b| a & !b)
    }

    /// The pixels of tile (tx, ty), cut by the face's edge.
    fn tile_rect(&self, tx: u32, ty: u32) -> PixelRect {
        let at = |t: u32| (t * self.tile).min(self.face_size);
        PixelRect {
            x0: at(tx),
            y0: at(ty),
            x1: at(tx + 1),
            y1: at(ty + 1),
        }
    }

    /// Disjoint rectangles of pixels covering the marked tiles of `face` and nothing else:
    /// each row's runs of marked tiles, a run merged with the same run in the rows below.
    pub fn rects(&self, face: usize) -> Vec<PixelRect> {
        // Open runs: (first column, end column, first row), extended while the next row has
        // the same run.
        let mut open: Vec<(u32, u32, u32)> = Vec::new();
        let mut done = Vec::new();
        let close = |(x0, x1, y0): (u32, u32, u32), y1: u32, done: &mut Vec<PixelRect>| {
            let (a, b) = (self.tile_rect(x0, y0), self.tile_rect(x1 - 1, y1 - 1));
            done.push(a.union(&b));
        };
        for ty in 0..=self.per_side {
            let runs = if ty < self.per_side {
                self.runs(face, ty)
            } else {
                Vec::new()
            };
            let (kept, ended): (Vec<_>, Vec<_>) =
                (open.into_iter()).partition(|&(x0, x1, _)| runs.contains(&(x0, x1)));
            for run in ended {
                close(run, ty, &mut done);
            }
            open = kept;
            for (x0, x1) in runs {
                if !open.iter().any(|&(a, b, _)| (a, b) == (x0, x1)) {
                    open.push((x0, x1, ty));
                }
            }
        }
        done
    }

    /// Row `ty` of `face`'s runs of marked tiles: (first column, end column).
    fn runs(&self, face: usize, ty: u32) -> Vec<(u32, u32)> {
        let mut runs = Vec::new();
        let mut tx = 0;
        while tx < self.per_side {
            if !self.has(face, tx, ty) {
                tx += 1;
                continue;
            }
            let start = tx;
            while tx < self.per_side && self.has(face, tx, ty) {
                tx += 1;
            }
            runs.push((start, tx));
        }
        runs
    }

    /// Level-0 texels the marked tiles hold, over all six faces.
    pub fn texels(&self) -> u64 {
        (0..6).flat_map(|f| self.rects(f)).map(|r| r.area()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x0: u32, y0: u32, x1: u32, y1: u32) -> PixelRect {
        PixelRect { x0, y0, x1, y1 }
    }

    /// The rectangles cover exactly the marked tiles' pixels, once each, the last tile cut at
    /// the face's edge (a 100-texel face: 8-texel tiles, 13 a side, the last 4 wide).
    #[test]
    fn the_rectangles_are_the_marked_tiles_exactly() {
        let size = 100;
        let mut t = Tiles::none(size);
        assert_eq!(t.layout(), (8, 13));
        let marked = [
            (0, 0),
            (1, 0),
            (1, 1),
            (12, 12),
            (5, 3),
            (6, 3),
            (5, 4),
            (6, 4),
            (5, 6),
        ];
        for &(x, y) in &marked {
            t.set(2, x, y);
        }
        let rects = t.rects(2);
        let mut covered = vec![0u8; (size * size) as usize];
        for r in &rects {
            for y in r.y0..r.y1 {
                for x in r.x0..r.x1 {
                    covered[(y * size + x) as usize] += 1;
                }
            }
        }
        for y in 0..size {
            for x in 0..size {
                let want = u8::from(marked.contains(&(x / 8, y / 8)));
                assert_eq!(covered[(y * size + x) as usize], want, "pixel {x}, {y}");
            }
        }
        // The 2 x 2 block is one rectangle; the corner tile is cut to 4 x 4.
        assert!(rects.contains(&rect(40, 24, 56, 40)), "{rects:?}");
        assert!(rects.contains(&rect(96, 96, 100, 100)), "{rects:?}");
        assert_eq!(t.texels(), 8 * 64 + 16);
        assert!(Tiles::none(size).rects(2).is_empty());
        assert_eq!(Tiles::all(size).rects(5), [rect(0, 0, 100, 100)]);
    }

    /// The pass's words: bits past the last tile are dropped; set operations by tile.
    #[test]
    fn words_and_sets() {
        let n = Tiles::words(512);
        assert_eq!(n, 6 * 16 * 16 / 32);
        let t = Tiles::from_words(512, &vec![u32::MAX; n]);
        assert_eq!(t, Tiles::all(512));
        let odd = Tiles::from_words(100, &vec![u32::MAX; Tiles::words(100)]);
        assert_eq!(odd, Tiles::all(100));
        let mut a = Tiles::none(512);
        a.set_under(1, &rect(30, 30, 40, 33));
        assert!(a.has(1, 0, 0) && a.has(1, 1, 0) && a.has(1, 0, 1) && a.has(1, 1, 1));
        assert!(!a.has(1, 2, 0) && !a.has(0, 0, 0));
        let mut b = Tiles::none(512);
        b.set(1, 0, 0);
        assert_eq!(a.intersection(&b), b);
        assert!(!a.without(&b).has(1, 0, 0) && a.without(&b).has(1, 1, 1));
        assert_eq!(b.union(&a), a);
    }
}
