//! The cube's refresh, one part of the renderer: what the cube map shows, which faces a
//! frame must re-render by the scene's refresh policy, and the counts of updates and skips.

use super::resources::Drawable;
use super::RefreshCounters;
use crate::scene::camera::{self, ViewBasis};
use crate::scene::state::SceneState;
use crate::scene::{RefreshPolicy, Scene};

pub(super) struct Refresh {
    /// The state the cube map shows; `None` before the first fill (or after a floor).
    shown: Option<SceneState>,
    pub counters: RefreshCounters,
    /// Every update re-renders all six faces (the benchmark's full updates).
    full_updates: bool,
}

impl Refresh {
    pub fn new(full_updates: bool) -> Self {
        Self {
            shown: None,
            counters: RefreshCounters::default(),
            full_updates,
        }
    }

    /// Whether the cube shows what the scene holds in `state` (a policy that updates every n
    /// frames may show an older state until its next update).
    pub fn shows_state(&self, state: &SceneState) -> bool {
        self.shown
            .as_ref()
            .is_some_and(|shown| !shown.cube_differs(state))
    }

    /// Whether the cube has never been filled (its old contents are then undefined).
    pub fn first_fill(&self) -> bool {
        self.shown.is_none()
    }

    /// The cube now shows `state` (`None`: nothing a later frame may keep).
    pub fn shows(&mut self, state: Option<SceneState>) {
        self.shown = state;
    }

    /// Counts a frame that re-rendered the faces in `dirty` (none: a skip).
    pub fn count(&mut self, dirty: u8) {
        self.counters.frames += 1;
        if dirty != 0 {
            self.counters.cube_updates += 1;
            self.counters.faces_rendered += u64::from(dirty.count_ones());
        } else {
            self.counters.cube_skips += 1;
        }
    }

    /// Which faces must be re-rendered this frame (bit f: face f), by the refresh policy.
    pub fn dirty_faces(
        &self,
        scene: &Scene,
        drawables: &[Drawable],
        frame: u64,
        state: &SceneState,
        views: &[ViewBasis],
    ) -> u8 {
        const ALL: u8 = 0x3F;
        let Some(old) = &self.shown else {
            return ALL;
        };
        match scene.refresh {
            RefreshPolicy::EveryFrame => ALL,
            RefreshPolicy::EveryN(n) => {
                if frame % u64::from(n.max(1)) == 0 {
                    ALL
                } else {
                    0
                }
            }
            RefreshPolicy::OnChange if !state.cube_differs(old) => 0,
            // The mirror moved: every direction changed.
            RefreshPolicy::OnChange
                if self.full_updates || old.mirror_center != state.mirror_center =>
            {
                ALL
            }
            RefreshPolicy::OnChange => {
                // Only objects moved: the faces that see where a moved object was or now is.
                let frusta: Vec<camera::Frustum> = views[..6]
                    .iter()
                    .map(|v| camera::Frustum::new(v, scene.cube.near_m, scene.cube.far_m))
                    .collect();
                let mut mask = 0u8;
                for (i, (a, b)) in old
                    .object_positions
                    .iter()
                    .zip(&state.object_positions)
                    .enumerate()
                {
                    if a == b {
                        continue;
                    }
                    let d = &drawables[6 + i];
                    for m in [
                        old.object_to_render(scene, i),
                        state.object_to_render(scene, i),
                    ] {
                        let (lo, hi) = camera::transform_aabb(&m, d.bounds_min, d.bounds_max);
                        for (f, fr) in frusta.iter().enumerate() {
                            if fr.intersects_aabb(lo, hi) {
                                mask |= 1 << f;
                            }
                        }
                    }
                }
                mask
            }
        }
    }
}
