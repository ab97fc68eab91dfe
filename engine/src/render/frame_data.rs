//! A frame's data for the GPU, written through its slot's uploads: the frame's constants
//! ([`FrameData`]), the views (six cube faces, then the observer, the sensor and the pair's
//! halves, [`ViewData`]) and the drawables' transforms ([`ObjectData`]); the draw order and
//! the lookup's own per-frame data follow from them.

use glam::{Mat4, UVec4, Vec4};

use super::gpu::{self, FrameData, ObjectData, ViewData};
use super::resources::VIEW_COUNT;
use super::{camera_clearance, draw, lookups, Renderer, PAIR_SIZE};
use crate::scene::camera::{self, ViewBasis};
use crate::scene::state::SceneState;
use crate::scene::{RefreshPolicy, Scene};
use crate::vk::GpuError;

impl Renderer {
    /// Writes frame data, views and object transforms, and has the lookup prepare its own;
    /// returns the views (render space) and the lookup's host time (ms).
    pub(super) fn write_frame_buffers(
        &mut self,
        state: &SceneState,
    ) -> Result<(Vec<ViewBasis>, f64), GpuError> {
        let scene = &self.scene;
        let uploads = &mut self.frames.current_mut().uploads;
        uploads.write(&self.resources.frame, &[frame_data(scene, state)])?;
        let bases = view_bases(scene, state);
        let views = view_data(scene, &bases, self.cube.size as f32);
        debug_assert_eq!(views.len(), VIEW_COUNT);
        uploads.write(&self.resources.views, &views)?;
        let objects = objects_data(scene, state);
        uploads.write(&self.resources.objects, &objects)?;
        let bounds = (objects.iter().zip(&self.resources.drawables))
            .map(|(o, d)| camera::transform_aabb(&o.model_to_world, d.bounds_min, d.bounds_max))
            .collect();
        self.drawn = draw::DrawOrder::of(bounds, scene.cube.offset_m);
        let lookup_start = std::time::Instant::now();
        let frame = lookups::FrameObjects {
            objects: &objects,
            bounds: &self.drawn.bounds,
            every_frame: scene.refresh == RefreshPolicy::EveryFrame,
        };
        (self.mirror.pass).prepare(uploads, &frame)?;
        let lookup_ms = lookup_start.elapsed().as_secs_f64() * 1e3;
        Ok((bases, lookup_ms))
    }
}

impl Renderer {
    /// What SwiftShader leaves out of the frame at `t_s` (`snapping`), whichever device this
    /// is: per surface, the views it loses triangles in, of every view (the cube's faces where
    /// the lookup reads a cube).
    pub fn snapping_losses(&self, t_s: f64) -> Vec<String> {
        let cube = lookups::plugin(self.scene.mirror.lookup).uses_cube();
        let first = if cube { 0 } else { 6 };
        let every: Vec<u32> = (first..VIEW_COUNT as u32).collect();
        self.losses_at(&SceneState::at(&self.scene, t_s), &every)
    }

    /// At the first frame, on SwiftShader: what it leaves out of the views the frame `ask`
    /// draws (the cube's faces too where `fill_cube`), said once. Only then: a warning is said
    /// once, and the check costs a pass over every triangle.
    pub(super) fn say_snapping_losses(
        &mut self,
        state: &SceneState,
        ask: &super::FrameAsk,
        fill_cube: bool,
    ) {
        if self.snapping_said || self.device.info.short_name != "swiftshader" {
            return;
        }
        self.snapping_said = true;
        let mut drawn = self.views.drawn_views(ask.readback, ask.display);
        drawn.extend((0..6).filter(|_| fill_cube));
        super::snapping::warn(&self.losses_at(state, &drawn));
    }

    fn losses_at(&self, state: &SceneState, drawn: &[u32]) -> Vec<String> {
        let bases = view_bases(&self.scene, state);
        let views = view_data(&self.scene, &bases, self.cube.size as f32);
        super::snapping::losses(&self.scene, state, &views, drawn)
    }
}

/// The frame's constants: the light, the mirror (render space is centred on its viewpoint)
/// and its shape, the lookup's start and search steps, the room, the cube.
pub(super) fn frame_data(scene: &Scene, state: &SceneState) -> FrameData {
    let light = scene.light.as_ref();
    let shape = gpu::MirrorShapeData::of(&scene.mirror.shape);
    let room = |sign: f32| {
        (scene.room.center + sign * 0.5 * scene.room.size_m - state.mirror_center).extend(1.0)
    };
    FrameData {
        light_dir_ambient: light.map_or(Vec4::ZERO, |l| l.direction.extend(l.ambient)),
        mirror: Vec4::new(0.0, 0.0, 0.0, scene.mirror.radius_m),
        flags: UVec4::new(
            u32::from(light.is_some()),
            lookups::plugin(scene.mirror.lookup).start().code(),
            scene.mirror.distance_steps,
            scene.mirror.secant_steps,
        ),
        room_min: room(-1.0),
        room_max: room(1.0),
        cube: Vec4::new(
            scene.cube.near_m,
            scene.cube.far_m,
            scene.cube.anisotropy as f32,
            0.0,
        ),
        mirror_shape: shape.code,
        mirror_quadric: shape.quadric,
        mirror_extent: shape.extent,
        cube_centre: scene.cube.offset_m.extend(1.0),
    }
}

/// The frame's views, in `ViewData` order: the six cube faces, the observer and the sensor
/// at their own resolutions, then both at the pair's half-width aspect.
pub(super) fn view_bases(scene: &Scene, state: &SceneState) -> Vec<ViewBasis> {
    let aspect = |[w, h]: [u32; 2]| w as f32 / h as f32;
    let observer = |a| state.observer_view(scene, a);
    let sensor = |a| state.sensor_view(scene, a);
    let half_pair = aspect([PAIR_SIZE[0] / 2, PAIR_SIZE[1]]);
    let mut bases: Vec<ViewBasis> = (0..6)
        .map(|f| ViewBasis::cube_face(scene.cube.offset_m, f))
        .collect();
    bases.push(observer(aspect(scene.observer.resolution)));
    bases.push(sensor(aspect(scene.sensor.resolution)));
    bases.push(observer(half_pair));
    bases.push(sensor(half_pair));
    bases
}

/// Each view's matrices, rays and viewport: a cube face spans the face (`cube_size`) between
/// the cube's planes; a camera keeps its clearance from the mirror ([`camera_clearance`]).
pub(super) fn view_data(scene: &Scene, bases: &[ViewBasis], cube_size: f32) -> Vec<ViewData> {
    let [ow, oh] = scene.observer.resolution;
    let [sw, sh] = scene.sensor.resolution;
    let half_w = (PAIR_SIZE[0] / 2) as f32;
    let viewports = [
        [0.0, 0.0, ow as f32, oh as f32],
        [0.0, 0.0, sw as f32, sh as f32],
        [0.0, 0.0, half_w, PAIR_SIZE[1] as f32],
        [half_w, 0.0, half_w, PAIR_SIZE[1] as f32],
    ];
    (bases.iter().enumerate())
        .map(|(i, b)| {
            let (near, far, vp) = if i < 6 {
                let face = [0.0, 0.0, cube_size, cube_size];
                (scene.cube.near_m, scene.cube.far_m, face)
            } else {
                (
                    b.near_plane_for(camera_clearance(b.eye, scene.mirror.radius_m)),
                    view_far(b, scene),
                    viewports[i - 6],
                )
            };
            ViewData {
                world_to_clip: b.world_to_clip(near, far),
                eye: b.eye.extend(1.0),
                ray_right: (b.right * b.tan_x).extend(0.0),
                ray_down: (b.down * b.tan_y).extend(0.0),
                ray_forward: b.forward.extend(0.0),
                viewport: Vec4::from_array(vp),
                origin_right: (b.right * b.half_x).extend(0.0),
                origin_down: (b.down * b.half_y).extend(0.0),
            }
        })
        .collect()
}

/// The drawables' transforms and materials, walls first (render space: the mirror's
/// viewpoint at the origin).
fn objects_data(scene: &Scene, state: &SceneState) -> Vec<ObjectData> {
    let walls = state.world_to_render();
    let mut objects: Vec<ObjectData> = (0..6)
        .map(|f| object_data(walls, scene.room.wall_materials[f]))
        .collect();
    objects.extend(
        (0..scene.objects.len())
            .map(|i| object_data(state.object_to_render(scene, i), scene.objects[i].material)),
    );
    objects
}

/// A camera view's far plane: none for a pinhole (reverse-Z keeps its precision to infinity);
/// an orthographic view's depth is linear, so it ends past the room's farthest corner from
/// the cube's centre (`cube.far`), seen from the eye.
fn view_far(view: &ViewBasis, scene: &Scene) -> f32 {
    if view.is_orthographic() {
        scene.cube.far_m + view.eye.distance(scene.cube.offset_m)
    } else {
        f32::INFINITY
    }
}

fn object_data(model: Mat4, material: usize) -> ObjectData {
    ObjectData {
        model_to_world: model,
        normal_to_world: model.inverse().transpose(),
        material: UVec4::new(material as u32, 0, 0, 0),
    }
}
