//! The view into an image of the window's size (`backdrop.rs`): the blit (scaled to fit,
//! aspect kept, centred on black); that image into the swapchain image, a copy; and the end
//! of a frame (to PRESENT_SRC, or through a copy for the screenshot).

use ash::vk;
use specchio::vk::commands::{image_barriers, ImageBarrier};
use specchio::vk::device::Device;
use specchio::vk::image::color_copy_region;
use specchio::vk::memory::Buffer;

use super::shown::ShownImage;
use vk::AccessFlags2 as A;
use vk::ImageLayout as L;
use vk::PipelineStageFlags2 as S;

/// Records into `target` (in TRANSFER_DST, `extent` large): a clear where the blit leaves
/// bars (all of it before the first view came), then the blit from `source` (ready for
/// `BLIT` reads, see `shown.rs`). Written at BLIT (and CLEAR).
pub(super) fn compose(
    device: &Device,
    cmd: vk::CommandBuffer,
    source: Option<&ShownImage>,
    target: vk::Image,
    extent: vk::Extent2D,
) {
    let Some(source) = source else {
        clear_bars(device, cmd, target);
        return;
    };
    let (rect, covers) = fit(source.width, source.height, extent);
    if !covers {
        clear_bars(device, cmd, target);
    }
    // 1:1 copies every texel exactly; a scaled view is filtered.
    let filter = if [rect[2], rect[3]] == [source.width, source.height] {
        vk::Filter::NEAREST
    } else {
        vk::Filter::LINEAR
    };
    let region = blit_region(source, rect);
    // SAFETY: both images are in the layouts named, the regions lie inside them.
    unsafe {
        device.raw.cmd_blit_image(
            cmd,
            source.image,
            L::TRANSFER_SRC_OPTIMAL,
            target,
            L::TRANSFER_DST_OPTIMAL,
            &[region],
            filter,
        )
    };
}

/// Records the copy of `composed` (TRANSFER_SRC, visible to COPY, the swapchain's format and
/// `extent`) into the swapchain image `target`: UNDEFINED -> TRANSFER_DST first, its first
/// scope the COPY stage that waited on the acquire semaphore. `target` is left in
/// TRANSFER_DST, written at COPY.
pub(super) fn record_copy(
    device: &Device,
    cmd: vk::CommandBuffer,
    composed: vk::Image,
    target: vk::Image,
    extent: vk::Extent2D,
) {
    let acquired = target_barrier(
        target,
        (L::UNDEFINED, S::COPY, A::NONE),
        (L::TRANSFER_DST_OPTIMAL, S::COPY, A::TRANSFER_WRITE),
    );
    image_barriers(device, cmd, &[acquired]);
    let region = vk::ImageCopy {
        src_subresource: COLOR_LAYER,
        src_offset: vk::Offset3D::default(),
        dst_subresource: COLOR_LAYER,
        dst_offset: vk::Offset3D::default(),
        extent: vk::Extent3D {
            width: extent.width,
            height: extent.height,
            depth: 1,
        },
    };
    // SAFETY: both images are `extent` large, of one format, in the layouts named.
    unsafe {
        device.raw.cmd_copy_image(
            cmd,
            composed,
            L::TRANSFER_SRC_OPTIMAL,
            target,
            L::TRANSFER_DST_OPTIMAL,
            &[region],
        )
    };
}

/// A barrier on a window-sized image's one subresource.
fn target_barrier(target: vk::Image, from: (L, S, A), to: (L, S, A)) -> ImageBarrier {
    ImageBarrier {
        image: target,
        range: COLOR_RANGE,
        from,
        to,
    }
}

/// Black where the view leaves bars: the whole image cleared before the blit writes its
/// rectangle (ordered after the clear).
fn clear_bars(device: &Device, cmd: vk::CommandBuffer, target: vk::Image) {
    let black = vk::ClearColorValue {
        float32: [0.0, 0.0, 0.0, 1.0],
    };
    // SAFETY: the image is in TRANSFER_DST layout; the range is its only subresource.
    unsafe {
        (device.raw).cmd_clear_color_image(
            cmd,
            target,
            L::TRANSFER_DST_OPTIMAL,
            &black,
            &[COLOR_RANGE],
        )
    };
    let written = (L::TRANSFER_DST_OPTIMAL, S::CLEAR, A::TRANSFER_WRITE);
    let blit_writes = (L::TRANSFER_DST_OPTIMAL, S::BLIT, A::TRANSFER_WRITE);
    image_barriers(device, cmd, &[target_barrier(target, written, blit_writes)]);
}

/// The whole view onto `rect` ([x, y, width, height]) of the window-sized image.
fn blit_region(source: &ShownImage, rect: [u32; 4]) -> vk::ImageBlit {
    let corner = |x: u32, y: u32| vk::Offset3D {
        x: x as i32,
        y: y as i32,
        z: 1,
    };
    vk::ImageBlit {
        src_subresource: COLOR_LAYER,
        src_offsets: [vk::Offset3D::default(), corner(source.width, source.height)],
        dst_subresource: COLOR_LAYER,
        dst_offsets: [
            vk::Offset3D {
                x: rect[0] as i32,
                y: rect[1] as i32,
                z: 0,
            },
            corner(rect[0] + rect[2], rect[1] + rect[3]),
        ],
    }
}

/// Records the end of a frame: `target` from `last` (the copy's or the menu's writes) to
/// PRESENT_SRC, or via TRANSFER_SRC and a copy into `readback` (the screenshot).
pub(super) fn record_finish(
    device: &Device,
    cmd: vk::CommandBuffer,
    target: vk::Image,
    extent: vk::Extent2D,
    last: (vk::ImageLayout, vk::PipelineStageFlags2, vk::AccessFlags2),
    readback: Option<&Buffer>,
) {
    let dst = |from, to| target_barrier(target, from, to);
    let present = (L::PRESENT_SRC_KHR, S::NONE, A::NONE);
    let Some(buffer) = readback else {
        image_barriers(device, cmd, &[dst(last, present)]);
        return;
    };
    let readable = (L::TRANSFER_SRC_OPTIMAL, S::COPY, A::TRANSFER_READ);
    image_barriers(device, cmd, &[dst(last, readable)]);
    let copy = color_copy_region(0, 1, [extent.width, extent.height]);
    // SAFETY: the image is in TRANSFER_SRC layout; the buffer holds width x height x 4 bytes.
    unsafe {
        device.raw.cmd_copy_image_to_buffer(
            cmd,
            target,
            L::TRANSFER_SRC_OPTIMAL,
            buffer.raw,
            &[copy],
        )
    };
    specchio::vk::commands::host_read_barrier(device, cmd, S::COPY, A::TRANSFER_WRITE);
    image_barriers(device, cmd, &[dst(readable, present)]);
}

/// The one colour subresource of a window-sized image.
const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};
const COLOR_LAYER: vk::ImageSubresourceLayers = vk::ImageSubresourceLayers {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    mip_level: 0,
    base_array_layer: 0,
    layer_count: 1,
};

/// Where a `w` x `h` image goes in `extent`: [x, y, width, height], as large as fits with its
/// aspect ratio kept, centred; and whether it covers the whole extent.
pub fn fit(w: u32, h: u32, extent: vk::Extent2D) -> ([u32; 4], bool) {
    let (ew, eh) = (u64::from(extent.width), u64::from(extent.height));
    let (w64, h64) = (u64::from(w), u64::from(h));
    // Width-limited when ew / eh <= w / h (compared in integers: no rounding).
    let (fw, fh) = if ew * h64 <= eh * w64 {
        (ew, (ew * h64 / w64).max(1))
    } else {
        ((eh * w64 / h64).max(1), eh)
    };
    let (x, y) = ((ew - fw) / 2, (eh - fh) / 2);
    let rect = [x as u32, y as u32, fw as u32, fh as u32];
    (rect, fw == ew && fh == eh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(width: u32, height: u32) -> vk::Extent2D {
        vk::Extent2D { width, height }
    }

    #[test]
    fn an_image_fits_its_window_with_its_aspect_kept() {
        assert_eq!(fit(1200, 450, e(1200, 450)), ([0, 0, 1200, 450], true));
        // Twice as tall a window: bars above and below.
        assert_eq!(fit(1200, 450, e(1200, 900)), ([0, 225, 1200, 450], false));
        // A wider window: bars left and right.
        assert_eq!(fit(800, 600, e(1000, 600)), ([100, 0, 800, 600], false));
        assert_eq!(fit(800, 600, e(400, 300)), ([0, 0, 400, 300], true));
    }
}
