//! The per-frame context every pass records with ([`FrameParts`]): the renderer's shared
//! parts, borrowed for one frame. A pass that is a part of its own (the view passes, a fill
//! method through its cube recorder) owns its state and sees the rest of the renderer only
//! through this: the scene's draws, the scene, the frame's draw order and bounds, the mirror
//! lookup's pass and this frame's queries.

use ash::vk;
use glam::Vec3;

use super::draw::{DrawOrder, Facing, CUBE_FRONT, VIEW_FRONT};
use super::lookups::LookupPass;
use super::methods::{CubePlan, FillParts, Patch, Patching};
use super::queries::FrameQueries;
use super::refresh::Dirty;
use super::scene_draw::SceneDraw;
use super::targets::CubeTarget;
use super::Renderer;
use crate::scene::camera::{Frustum, ViewBasis};
use crate::scene::Scene;

/// What one frame's passes record with.
pub(super) struct FrameParts<'a> {
    pub draw: SceneDraw<'a>,
    pub scene: &'a Scene,
    /// The frame's draw order and each drawable's render-space bounds.
    pub drawn: &'a DrawOrder,
    /// The mirror lookup's pass (its pipelines and set 1).
    pub lookup: &'a dyn LookupPass,
    /// This frame's queries (its slot's: read after its fence).
    pub queries: &'a FrameQueries,
    /// The cube map: filled by the cube fill, sampled by the mirror, copied by the readback.
    pub cube: &'a CubeTarget,
}

impl Renderer {
    /// The current frame's context.
    pub(super) fn frame_parts(&self) -> FrameParts<'_> {
        FrameParts {
            draw: self.scene_draw(),
            scene: &self.scene,
            drawn: &self.drawn,
            lookup: self.mirror.pass.as_ref(),
            queries: self.queries(),
            cube: &self.cube,
        }
    }
}

impl<'a> FrameParts<'a> {
    /// Culls every dirty face against its frustum, and each of its dirty rectangles against
    /// the rectangle's: a face's `visible` is then what meets some rectangle, the patches say
    /// what meets which, drawn as `how` says.
    pub fn plan_cube(&self, views: &[ViewBasis], dirty: Dirty, how: Patching) -> CubePlan {
        let mut plan = CubePlan {
            dirty: dirty.mask,
            order: self.drawn.order.clone(),
            ..Default::default()
        };
        let (near, far) = (self.scene.cube.near_m, self.scene.cube.far_m);
        for f in plan.faces().collect::<Vec<_>>() {
            let f = f as usize;
            let visible = self.drawn.visible(&Frustum::new(&views[f], near, far));
            let frusta: Vec<Frustum> = (dirty.rects[f].iter())
                .map(|r| Frustum::of_rect(&views[f], near, far, self.cube.size, r))
                .collect();
            let meets = |k: usize, i: u32| {
                let (lo, hi) = self.drawn.bounds[i as usize];
                frusta[k].intersects_aabb(lo, hi)
            };
            plan.patches[f] = Patch::cover(&dirty.rects[f], &visible, meets, how);
            plan.visible[f] = match &plan.patches[f][..] {
                [] => visible,
                // What the patches draw: the drawables that meet some dirty rectangle.
                patches => Patch::drawn(patches, &visible),
            };
        }
        plan
    }

    /// What a cube fill records into: the scene's draws, the cube, the queries, and how the
    /// cube's faces see each drawable.
    pub fn fill_parts(&self) -> FillParts<'a> {
        FillParts {
            draw: self.draw,
            cube: self.cube,
            queries: self.queries,
            facing: self.cube_facing(),
        }
    }

    /// Indices of the drawables whose render-space bounds meet `frustum`, in draw order.
    pub fn visible(&self, frustum: &Frustum) -> Vec<u32> {
        self.drawn.visible(frustum)
    }

    /// The facing of the cube faces: mirrored winding, eye at the cube's centre, near plane
    /// `cube.near` with corners `near * sqrt(3)` away (90-degree faces).
    pub fn cube_facing(&self) -> Facing {
        let reach = self.scene.cube.near_m * 3f32.sqrt();
        self.facing(CUBE_FRONT, self.scene.cube.offset_m, reach)
    }

    /// The facing of a camera view: its near plane's corners are `camera_clearance` from the
    /// eye (`ViewBasis::near_plane_for`).
    pub fn view_facing(&self, view: &crate::scene::camera::ViewBasis) -> Facing {
        let reach = super::camera_clearance(view.eye, self.scene.mirror.radius_m);
        if view.is_orthographic() {
            // The near plane spans the whole image: a drawable within reach of that plane,
            // anywhere across it, may be cut open there.
            let f = view.forward;
            let cull = (self.draw.resources.drawables.iter().zip(&self.drawn.bounds))
                .map(|(d, &(lo, hi))| {
                    let nearest = Vec3::select(f.cmpge(Vec3::ZERO), lo, hi);
                    d.cull_back && f.dot(nearest - view.eye) > reach
                })
                .collect();
            return Facing {
                front: VIEW_FRONT,
                cull,
            };
        }
        self.facing(VIEW_FRONT, view.eye, reach)
    }

    fn facing(&self, front: vk::FrontFace, eye: Vec3, reach: f32) -> Facing {
        let cull = (self.draw.resources.drawables)
            .iter()
            .zip(&self.drawn.bounds)
            .map(|(d, &(lo, hi))| {
                // Nearest point of the box to the eye; culling only when it is out of reach.
                d.cull_back && eye.clamp(lo, hi).distance(eye) > reach
            })
            .collect();
        Facing { front, cull }
    }
}
