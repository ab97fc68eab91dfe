//! The cube's fill plan: which faces an update re-renders and what each of them sees.

/// What one cube update draws: the faces to re-render and, per face, the visible drawables.
#[derive(Debug, Clone, Default)]
pub struct CubePlan {
    /// Bit f set: face f is re-rendered; the others keep their contents.
    pub dirty: u8,
    /// Per face, the drawables whose bounds meet the face's frustum (empty for clean faces),
    /// in `order`.
    pub visible: [Vec<u32>; 6],
    /// The frame's draw order (front to back from the cube's centre, walls last).
    pub order: Vec<u32>,
}

impl CubePlan {
    pub fn faces(&self) -> impl Iterator<Item = u32> + '_ {
        (0..6u32).filter(|f| self.dirty & (1 << f) != 0)
    }

    /// Every drawable visible in at least one dirty face, in draw order (the one-pass
    /// methods that cannot cull per face draw these).
    pub fn union(&self) -> Vec<u32> {
        let mut seen = vec![false; self.order.iter().max().map_or(0, |&m| m as usize + 1)];
        for &o in self.visible.iter().flatten() {
            seen[o as usize] = true;
        }
        self.order
            .iter()
            .copied()
            .filter(|&o| seen[o as usize])
            .collect()
    }

    /// Each drawable's position in `order`.
    pub fn ranks(&self) -> Vec<u32> {
        let mut rank = vec![u32::MAX; self.order.iter().max().map_or(0, |&m| m as usize + 1)];
        for (r, &o) in self.order.iter().enumerate() {
            rank[o as usize] = r as u32;
        }
        rank
    }
}
