//! What comes back from the GPU after a frame: the readback buffer's layout (cube faces, then
//! the view images in slot order), planned once per frame as [`Copies`], which records the
//! copies into it and decodes its texels; and the timestamp and statistics queries.

use ash::vk;

use std::sync::Arc;

use super::display::{DisplayPixels, DisplayView};
use super::graph::{FrameGraph, Resource, Use};
use super::passes::{copy_offset, texel_bytes, Slot};
use super::sensor_rays::RayMapTargets;
use super::targets::{CubeTarget, ViewTarget};
use super::*;
use crate::sensor::quantities::QuantityImages;
use crate::vk::image::color_copy_region;

/// Where one frame's images sit in its slot's readback buffer: planned before the frame is
/// recorded (the buffer is grown to [`Copies::bytes`]), then used to record the copies and,
/// after the frame's fence, to decode them. The cube's six faces come first, at 0, then the
/// view images in slot order, each at a 16-byte boundary ([`copy_offset`]).
#[derive(Debug, Default, Clone)]
pub(super) struct Copies {
    cube: Option<CubeCopy>,
    views: Vec<ViewCopy>,
    bytes: u64,
    /// The one view is a window's: handed over as it is, not decoded.
    display: bool,
}

/// Mip 0 of the cube's six faces.
#[derive(Debug, Clone)]
struct CubeCopy {
    image: vk::Image,
    /// Mip 0, as the frame graph tracks it.
    mip0: Resource,
    size: u32,
    /// RGBA8 unorm (a `--full`-size cube's format), else RGBA16F.
    unorm: bool,
}

/// One view image: a view pass's, or one of the ray map's quantities.
#[derive(Debug, Clone)]
struct ViewCopy {
    of: Copied,
    image: vk::Image,
    /// Its colour, as the frame graph tracks it.
    resource: Resource,
    width: u32,
    height: u32,
    offset: u64,
}

/// Whose image a view copy is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Copied {
    View(Slot),
    /// The ray map's quantity at this location (`shaders::SENSOR_QUANTITIES`).
    Quantity(usize),
}

impl Copied {
    /// Bytes per texel of its image's format.
    fn texel_bytes(self) -> u64 {
        match self {
            Copied::View(slot) => texel_bytes(slot),
            Copied::Quantity(_) => 16,
        }
    }
}

impl Copies {
    /// The copies `readback` asks for: the cube's faces when asked, the view targets `slots`
    /// names (the view passes', in their order), and the ray map's quantities.
    pub fn plan(
        readback: Readback,
        cube: &CubeTarget,
        slots: Vec<(Slot, &ViewTarget)>,
        ray_map: Option<&RayMapTargets>,
    ) -> Self {
        let mut copies = Copies::default();
        if readback.cube {
            let unorm = cube.format == vk::Format::R8G8B8A8_UNORM;
            let texel = if unorm { 4 } else { 8 };
            copies.bytes = 6 * u64::from(cube.size) * u64::from(cube.size) * texel;
            copies.cube = Some(CubeCopy {
                image: cube.color.raw,
                mip0: cube.color_levels(0, 1, None),
                size: cube.size,
                unorm,
            });
        }
        let views =
            (slots.into_iter()).map(|(slot, t)| (Copied::View(slot), &t.color, t.width, t.height));
        let quantities = (ray_map.iter()).flat_map(|t| {
            (t.quantities.iter().enumerate())
                .map(|(i, (_, image))| (Copied::Quantity(i), image, t.width, t.height))
        });
        for (of, image, width, height) in views.chain(quantities) {
            let offset = copy_offset(copies.bytes);
            copies.views.push(ViewCopy {
                of,
                image: image.raw,
                resource: Resource::whole(image),
                width,
                height,
                offset,
            });
            copies.bytes = offset + u64::from(width) * u64::from(height) * of.texel_bytes();
        }
        copies
    }

    /// The copy of a window's view (a display frame's only readback): its texels as the
    /// target holds them (`targets::VIEW_FORMAT`), for a window on another device.
    pub fn display((slot, target): (Slot, &ViewTarget)) -> Self {
        let (width, height) = (target.width, target.height);
        let view = ViewCopy {
            of: Copied::View(slot),
            image: target.color.raw,
            resource: target.color_resource(),
            width,
            height,
            offset: 0,
        };
        Self {
            cube: None,
            views: vec![view],
            bytes: u64::from(width) * u64::from(height) * texel_bytes(slot),
            display: true,
        }
    }

    /// The readback buffer's size for them (0: nothing is read back).
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Copies mip 0 of the cube faces and the view images into `buffer`, for the host. The
    /// copies' sources and the buffer are declared to `graph`, whose `finish` gives the cube
    /// back to the fragment shaders and the buffer to the host.
    pub fn record(
        &self,
        dev: &Device,
        graph: &mut FrameGraph,
        cmd: vk::CommandBuffer,
        buffer: &Buffer,
    ) {
        let cube = self.cube.iter().map(|c| (c.mip0, Use::CopySource));
        let views = self.views.iter().map(|v| (v.resource, Use::CopySource));
        let into = (Resource::Buffer(buffer.raw), Use::CopyDestination);
        let uses: Vec<_> = cube.chain(views).chain([into]).collect();
        graph.declare(dev, cmd, &uses);
        if let Some(cube) = &self.cube {
            copy_to_buffer(dev, cmd, buffer, (cube.image, 6), [cube.size; 2], 0);
        }
        for v in &self.views {
            copy_to_buffer(
                dev,
                cmd,
                buffer,
                (v.image, 1),
                [v.width, v.height],
                v.offset,
            );
        }
    }

    /// A finished frame's pixels, decoded from its slot's readback `buffer`.
    pub fn decode(&self, buffer: Option<&Arc<Buffer>>) -> Result<FrameImages, GpuError> {
        let mut images = FrameImages::default();
        let Some(buffer) = buffer else {
            return Ok(images);
        };
        if let (true, [v]) = (self.display, &self.views[..]) {
            // Not copied: the window reads the buffer itself, which this renderer then
            // leaves to it (`grow_readback`).
            let bytes = self.bytes as usize;
            images.display = Some(DisplayPixels::new(
                [v.width, v.height],
                Arc::clone(buffer),
                bytes,
            ));
            return Ok(images);
        }
        let bytes = buffer.mapped()?;
        if let Some(cube) = &self.cube {
            let s = cube.size;
            let face_bytes = (s * s) as usize * if cube.unorm { 4 } else { 8 };
            let face = |f: usize| {
                let b = &bytes[f * face_bytes..(f + 1) * face_bytes];
                match cube.unorm {
                    true => decode_unorm8(b, s, s),
                    false => decode_f16(b, s, s),
                }
            };
            images.cube = Some((0..6).map(face).collect());
        }
        let mut quantities = Vec::new();
        for v in &self.views {
            let n = u64::from(v.width) * u64::from(v.height) * v.of.texel_bytes();
            let b = &bytes[v.offset as usize..(v.offset + n) as usize];
            let (w, h) = (v.width, v.height);
            let slot = match v.of {
                Copied::View(slot) => slot,
                Copied::Quantity(i) => {
                    let name = crate::shaders::SENSOR_QUANTITIES[i];
                    quantities.push((name, decode_f32(b, w, h)));
                    continue;
                }
            };
            match slot {
                Slot::Observer => images.observer = Some(decode_f16(b, w, h)),
                Slot::Sensor => images.sensor = Some(decode_f16(b, w, h)),
                Slot::Pair => images.pair = Some(decode_f16(b, w, h)),
                Slot::ObserverDirection => images.observer_direction = Some(decode_f32(b, w, h)),
                Slot::SensorDirection => images.sensor_direction = Some(decode_f32(b, w, h)),
            }
        }
        if !quantities.is_empty() {
            images.sensor_quantities = Some(QuantityImages::new(quantities));
        }
        Ok(images)
    }
}

/// Records the copy of `layers` layers of mip 0 of `image` (in `TRANSFER_SRC_OPTIMAL`),
/// `size` texels each, into `buffer` at `offset`.
fn copy_to_buffer(
    dev: &Device,
    cmd: vk::CommandBuffer,
    buffer: &Buffer,
    (image, layers): (vk::Image, u32),
    [width, height]: [u32; 2],
    offset: u64,
) {
    let region = color_copy_region(offset, layers, [width, height]);
    // SAFETY: the image is in TRANSFER_SRC layout and the buffer has room (`Copies::bytes`).
    unsafe {
        dev.raw.cmd_copy_image_to_buffer(
            cmd,
            image,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer.raw,
            &[region],
        )
    };
}

impl Renderer {
    /// Where this frame's images will sit in its readback buffer.
    pub(super) fn plan_copies(&self, readback: Readback, display: Option<DisplayView>) -> Copies {
        match display {
            Some(view) => Copies::display(self.views.display_slot(view)),
            None => Copies::plan(
                readback,
                &self.cube,
                self.views.slots(readback),
                self.views.ray_map(readback),
            ),
        }
    }

    /// Makes the current slot's readback buffer large enough for `copies` (replacing it is
    /// safe: the slot's previous frame has finished). One a window still reads a view from
    /// (a [`DisplayPixels`] kept) is left to it: the slot takes its spare, or a new one, and
    /// keeps the held one as its spare.
    pub(super) fn grow_readback(&mut self, copies: &Copies) -> Result<(), GpuError> {
        let bytes = copies.bytes();
        let slot = self.frames.current_mut();
        let free = |b: &Option<Arc<Buffer>>| {
            b.as_ref()
                .is_some_and(|b| b.size >= bytes && Arc::strong_count(b) == 1)
        };
        if bytes == 0 || free(&slot.readback) {
            return Ok(());
        }
        let held = slot
            .readback
            .as_ref()
            .is_some_and(|b| Arc::strong_count(b) > 1);
        if held && free(&slot.spare) {
            std::mem::swap(&mut slot.readback, &mut slot.spare);
            return Ok(());
        }
        budget::check_buffer(&self.device, "this frame's readback", bytes)?;
        let buffer = Buffer::create(&self.device, &BufferDesc::new_readback(bytes), "readback")?;
        let slot = self.frames.current_mut();
        let old = slot.readback.replace(Arc::new(buffer));
        if held {
            slot.spare = old;
        }
        Ok(())
    }

    /// Records `copies` into the current slot's readback buffer (none: nothing is read back).
    pub(super) fn record_readback(
        &self,
        graph: &mut FrameGraph,
        cmd: vk::CommandBuffer,
        copies: &Copies,
    ) {
        if let Some(buffer) = &self.frames.current().readback {
            copies.record(&self.device, graph, cmd, buffer);
        }
    }
}

/// Decodes tightly packed texels of `texel_bytes` bytes each with `texel` into an image.
fn decode(
    bytes: &[u8],
    w: u32,
    h: u32,
    texel_bytes: usize,
    texel: impl Fn(&[u8]) -> [f32; 4],
) -> RgbaImage {
    let pixels = bytes.chunks_exact(texel_bytes).map(texel).collect();
    RgbaImage {
        width: w,
        height: h,
        pixels,
    }
}

/// RGBA16F texels.
fn decode_f16(bytes: &[u8], w: u32, h: u32) -> RgbaImage {
    decode(bytes, w, h, 8, |p| {
        std::array::from_fn(|c| half::f16::from_le_bytes([p[2 * c], p[2 * c + 1]]).to_f32())
    })
}

/// RGBA32F texels.
fn decode_f32(bytes: &[u8], w: u32, h: u32) -> RgbaImage {
    decode(bytes, w, h, 16, |p| {
        std::array::from_fn(|c| {
            f32::from_le_bytes([p[4 * c], p[4 * c + 1], p[4 * c + 2], p[4 * c + 3]])
        })
    })
}

/// RGBA8 unorm texels.
fn decode_unorm8(bytes: &[u8], w: u32, h: u32) -> RgbaImage {
    decode(bytes, w, h, 4, |p| {
        std::array::from_fn(|c| f32::from(p[c]) / 255.0)
    })
}
