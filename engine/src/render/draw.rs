//! Recording helpers shared by every pass: barriers' stage/access pairs, a rendering scope's
//! attachments, how a pass's draws face the viewer (culling) and the frame's draw order. The
//! scene's own draws and scopes are a part of their own (`scene_draw.rs`); which way each
//! drawable faces a pass is asked of the frame's context (`frame_parts.rs`).

use ash::vk;
use glam::Vec3;

use crate::scene::camera::Frustum;
use crate::vk::commands::ImageBarrier;

/// A stage and access pair, one side of a barrier.
pub(super) type Sync = (vk::PipelineStageFlags2, vk::AccessFlags2);

pub(super) const COLOR_OUT: Sync = (
    vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw()
            | vk::AccessFlags2::COLOR_ATTACHMENT_READ.as_raw(),
    ),
);
pub(super) const DEPTH_RW: Sync = (
    vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS.as_raw()
            | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw(),
    ),
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ.as_raw()
            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw(),
    ),
);
pub(super) const SAMPLED: Sync = (
    vk::PipelineStageFlags2::FRAGMENT_SHADER,
    vk::AccessFlags2::SHADER_SAMPLED_READ,
);
pub(super) const COPY_READ: Sync = (
    vk::PipelineStageFlags2::COPY,
    vk::AccessFlags2::TRANSFER_READ,
);
pub(super) const COPY_WRITE: Sync = (
    vk::PipelineStageFlags2::COPY,
    vk::AccessFlags2::TRANSFER_WRITE,
);
pub(super) const NOTHING: Sync = (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);

pub(super) fn barrier(
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    from: (vk::ImageLayout, Sync),
    to: (vk::ImageLayout, Sync),
) -> ImageBarrier {
    ImageBarrier {
        image,
        range,
        from: (from.0, from.1 .0, from.1 .1),
        to: (to.0, to.1 .0, to.1 .1),
    }
}

/// The attachments of one rendering scope.
pub(super) struct Attachments {
    pub color: vk::ImageView,
    /// The id cube's view, attachment 1 of a cube fill that writes ids.
    pub ids: Option<vk::ImageView>,
    /// Colour attachments after the first, cleared as it is (the ray map's quantities).
    pub more_colors: Vec<vk::ImageView>,
    pub depth: vk::ImageView,
    pub size: [u32; 2],
    /// Layers rendered (layered cube fills: 6); ignored when `view_mask` is set.
    pub layers: u32,
    /// Multiview view mask (0: not multiview).
    pub view_mask: u32,
    /// Clear on load (the whole attachment); otherwise keep the contents and let the method
    /// clear the layers it re-renders.
    pub clear: bool,
    /// Keep the depth after the scope: the cube's depth is the `distance` lookup's distance
    /// map, and a face not re-rendered keeps it; a view's depth is needed only within.
    pub store_depth: bool,
}

/// How a front face (counter-clockwise seen from the front, as every mesh is wound) turns on
/// screen: a view keeps it; a cube face sees the world mirrored (its u axis runs the other
/// way, docs/conventions.md), which turns it clockwise.
pub(super) const VIEW_FRONT: vk::FrontFace = vk::FrontFace::COUNTER_CLOCKWISE;
pub(super) const CUBE_FRONT: vk::FrontFace = vk::FrontFace::CLOCKWISE;

/// How one pass's draws face the viewer: the winding of a front face on its screen, and per
/// drawable whether its back faces may be culled. They may when the mesh is closed and stays
/// out of the ball around the eye that reaches the corners of the near plane: an eye inside a
/// closed mesh, or a near plane cutting into one, would see its inside, which culling would
/// remove (the reference, which does not cull, shows it).
pub(super) struct Facing {
    pub front: vk::FrontFace,
    pub cull: Vec<bool>,
}

/// Clear values: transparent black colour (a direction image is then zero, alpha included,
/// wherever the mirror is not; the room covers every other target), and the far plane for
/// reverse-Z depth.
pub(super) const CLEAR_COLOR: vk::ClearValue = vk::ClearValue {
    color: vk::ClearColorValue {
        float32: [0.0, 0.0, 0.0, 0.0],
    },
};
/// The id cube's clear value: no drawable (`OBJECT_NONE`).
pub(super) const CLEAR_ID: vk::ClearValue = vk::ClearValue {
    color: vk::ClearColorValue {
        uint32: [crate::shaders::shared::OBJECT_NONE; 4],
    },
};
pub(super) const CLEAR_DEPTH: vk::ClearValue = vk::ClearValue {
    depth_stencil: vk::ClearDepthStencilValue {
        depth: 0.0,
        stencil: 0,
    },
};

/// This frame's drawables in render space: their bounds (walls first) and the order they are
/// drawn in. One part, remade each frame by `write_frame_buffers`; culling, the draw order and
/// the back-face guard read it.
#[derive(Default)]
pub(super) struct DrawOrder {
    /// Render-space bounds of every drawable, walls first.
    pub bounds: Vec<(Vec3, Vec3)>,
    /// Objects front to back from the cube's centre, walls last ([`DrawOrder::of`]).
    pub order: Vec<u32>,
}

impl DrawOrder {
    /// The order for `bounds`: objects by the distance of their bounds from the cube's centre
    /// (`centre`, render space), nearest first, then the six walls. Every cube face looks out from
    /// that one point, so this one order is front to back for all six faces at once: the
    /// depth test then rejects hidden fragments before they are shaded (early depth), instead
    /// of shading every wall texel and painting objects over it. Ties go by index, so the order
    /// is deterministic and every method uses the same one (equal depths resolve alike).
    pub fn of(bounds: Vec<(Vec3, Vec3)>, centre: Vec3) -> Self {
        let walls = 6;
        let mut objects: Vec<(f32, u32)> = (walls..bounds.len())
            .map(|i| {
                let (lo, hi) = bounds[i];
                // Distance from the centre to the nearest point of the box (0 inside it).
                let nearest = centre.clamp(lo, hi);
                (nearest.distance_squared(centre), i as u32)
            })
            .collect();
        objects.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let order = (objects.into_iter().map(|(_, i)| i))
            .chain(0..walls as u32)
            .collect();
        Self { bounds, order }
    }

    /// Indices of the drawables whose render-space bounds meet `frustum`, in draw order.
    pub fn visible(&self, frustum: &Frustum) -> Vec<u32> {
        (self.order.iter().copied())
            .filter(|&i| {
                let (lo, hi) = self.bounds[i as usize];
                frustum.intersects_aabb(lo, hi)
            })
            .collect()
    }
}
