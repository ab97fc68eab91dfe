//! The swapchain of a window surface: creation, recreation (resize, minimise), acquire and
//! present. Used by the live viewer only.
//!
//! Recreation passes the old swapchain as `oldSwapchain`; the caller then retires the old
//! one through its frames' deletion queue (`frames::FrameRing::defer`), because frames still
//! in flight may present its images. A window of zero size (minimised) has no swapchain: the
//! caller waits for a resize instead of creating one.

use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::surface::Surface;
use super::{GpuError, VkContext};

/// How presented images reach the screen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PresentPreference {
    /// `FIFO`: waits for vertical blank, never tears, never drops a frame; always available,
    /// so it is the default.
    #[default]
    Fifo,
    /// `MAILBOX`: the newest finished image replaces a waiting one (lowest latency, no
    /// tearing, frames may be dropped); FIFO where the surface does not offer it.
    Mailbox,
}

/// What to create a swapchain with.
#[derive(Debug, Clone, Copy)]
pub struct SwapchainDesc {
    /// The window's drawable size in pixels; used where the surface leaves the extent to the
    /// application (Wayland), clamped to the surface's limits.
    pub window_size: [u32; 2],
    pub present: PresentPreference,
}

/// A `VkSwapchainKHR`, its images and one "rendering done" semaphore per image.
/// Field order is teardown order; it holds the surface and the device, which outlive it.
pub struct Swapchain {
    pub raw: vk::SwapchainKHR,
    /// Owned by the swapchain (never destroyed by us).
    pub images: Vec<vk::Image>,
    /// One per image: signalled by the submission that drew the image, waited by its present.
    /// Indexed by image rather than by frame so that a semaphore is signalled again only after
    /// the image was acquired again, which guarantees its previous present consumed it.
    pub render_done: Vec<vk::Semaphore>,
    pub format: vk::SurfaceFormatKHR,
    pub extent: vk::Extent2D,
    pub present_mode: vk::PresentModeKHR,
    /// Whether the images allow `TRANSFER_SRC` (the viewer's `--screenshot` copies one).
    pub readable: bool,
    /// One colour view per image where the images allow `COLOR_ATTACHMENT` (the viewer's menu
    /// is drawn into them); empty otherwise.
    pub views: Vec<vk::ImageView>,
    loader: ash::khr::swapchain::Device,
    /// Held so that the surface outlives its swapchain.
    _surface: Arc<Surface>,
    device: Arc<Device>,
}

/// The result of [`Swapchain::acquire`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Acquired {
    /// Draw into this image; `suboptimal`: recreate after presenting it.
    Image { index: u32, suboptimal: bool },
    /// The surface changed (resize): recreate before drawing.
    OutOfDate,
}

impl Swapchain {
    /// Creates a swapchain for `surface`, replacing `old` if given. `Ok(None)` when the
    /// window has no area (minimised): nothing can be presented until it is resized.
    pub fn create(
        device: &Arc<Device>,
        surface: &Arc<Surface>,
        desc: &SwapchainDesc,
        old: Option<&Swapchain>,
    ) -> Result<Option<Self>, GpuError> {
        let support = surface.support(device)?;
        let caps = support.capabilities;
        let Some(extent) = choose_extent(&caps, desc.window_size) else {
            return Ok(None);
        };
        // The viewer blits its view into an image of this format (optimal tiling; copied
        // into these images each frame), so the format must take a blit destination and
        // transfers (optional for swapchain formats in general; sRGB ones lack BLIT_DST on
        // some GPUs).
        let blittable = |format| {
            // SAFETY: a query on the device's own physical device; no handles are created.
            let props = unsafe {
                (device.instance.raw).get_physical_device_format_properties(device.physical, format)
            };
            let needed = vk::FormatFeatureFlags::BLIT_DST
                | vk::FormatFeatureFlags::TRANSFER_SRC
                | vk::FormatFeatureFlags::TRANSFER_DST;
            (props.optimal_tiling_features).contains(needed)
        };
        let format = choose_format(&support.formats, blittable)?;
        let present_mode = choose_present_mode(&support.present_modes, desc.present);
        let usage = choose_usage(caps.supported_usage_flags)?;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(image_count(&caps))
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(choose_alpha(caps.supported_composite_alpha))
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old.map_or(vk::SwapchainKHR::null(), |o| o.raw));
        let loader = ash::khr::swapchain::Device::new(&device.instance.raw, &device.raw);
        // SAFETY: the surface and device are live; `old` (if any) is not retired yet.
        let raw = unsafe { loader.create_swapchain(&info, None) }.vk("vkCreateSwapchainKHR")?;
        let mut swapchain = Self {
            raw,
            images: Vec::new(),
            render_done: Vec::new(),
            format,
            extent,
            present_mode,
            readable: usage.contains(vk::ImageUsageFlags::TRANSFER_SRC),
            views: Vec::new(),
            loader,
            _surface: Arc::clone(surface),
            device: Arc::clone(device),
        };
        swapchain.per_image(usage.contains(vk::ImageUsageFlags::COLOR_ATTACHMENT))?;
        Ok(Some(swapchain))
    }

    /// The images, and per image its "drawn" semaphore and (where it can be drawn into,
    /// `drawable`) its colour view. Anything made is destroyed with the swapchain.
    fn per_image(&mut self, drawable: bool) -> Result<(), GpuError> {
        let device = &self.device;
        // SAFETY: the swapchain was just created.
        self.images =
            unsafe { self.loader.get_swapchain_images(self.raw) }.vk("vkGetSwapchainImagesKHR")?;
        for (i, &image) in self.images.iter().enumerate() {
            // SAFETY: valid create info on a live device.
            let s = unsafe {
                device
                    .raw
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
            }
            .vk("vkCreateSemaphore")?;
            self.render_done.push(s);
            device.set_name(s, &format!("swapchain image {i} drawn"));
            device.set_name(image, &format!("swapchain image {i}"));
            if drawable {
                self.views
                    .push(color_view(device, image, self.format.format)?);
            }
        }
        Ok(())
    }

    /// Acquires the next image; `image_available` is signalled when it may be written.
    pub fn acquire(&self, image_available: vk::Semaphore) -> Result<Acquired, GpuError> {
        // SAFETY: the semaphore is unsignalled with no pending wait (the frame that last used
        // it has finished: its fence was waited).
        let result = unsafe {
            self.loader
                .acquire_next_image(self.raw, u64::MAX, image_available, vk::Fence::null())
        };
        match result {
            Ok((index, suboptimal)) => Ok(Acquired::Image { index, suboptimal }),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(result) => Err(GpuError::Vk {
                call: "vkAcquireNextImageKHR",
                result,
            }),
        }
    }

    /// Presents image `index` once its `render_done` semaphore is signalled. On a CPU driver
    /// this returns only after every submission before it has run (Mesa's software present
    /// copies the finished image), so the viewer calls it from a thread of its own. `Ok(true)`: the
    /// swapchain no longer matches the surface and must be recreated.
    pub fn present(&self, index: u32) -> Result<bool, GpuError> {
        let swapchains = [self.raw];
        let indices = [index];
        let wait = [self.render_done[index as usize]];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&wait)
            .swapchains(&swapchains)
            .image_indices(&indices);
        let queue = self.device.queue();
        // SAFETY: the image was acquired and its drawing submitted with `wait[0]` to signal;
        // the queue is held. (The caller keeps the swapchain itself to one thread at a time:
        // the viewer acquires only after the last present returned.)
        let presented = unsafe { self.loader.queue_present(*queue, &info) };
        match super::fault::present(presented) {
            Ok(suboptimal) => Ok(suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(true),
            Err(result) => Err(GpuError::Vk {
                call: "vkQueuePresentKHR",
                result,
            }),
        }
    }

    /// Whether the chosen format stores sRGB-encoded values (a blit from a linear image then
    /// encodes them, as the PNG writer does).
    pub fn is_srgb(&self) -> bool {
        is_srgb(self.format.format)
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        // SAFETY: the owner drops a swapchain only after the frames that used it finished
        // (deletion queue) or after the device went idle; the images belong to the swapchain.
        unsafe {
            for &s in &self.render_done {
                self.device.raw.destroy_semaphore(s, None);
            }
            for &v in &self.views {
                self.device.raw.destroy_image_view(v, None);
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}

/// A 2D colour view of a swapchain image, for rendering into it.
fn color_view(
    device: &Device,
    image: vk::Image,
    format: vk::Format,
) -> Result<vk::ImageView, GpuError> {
    let info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(format)
        .subresource_range(vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 1,
        });
    // SAFETY: the image belongs to a live swapchain of this device; the view is destroyed
    // with the swapchain.
    unsafe { device.raw.create_image_view(&info, None) }.vk("vkCreateImageView")
}

/// The surface's fixed extent, or the window's size clamped to its limits; `None` for a
/// window without area.
fn choose_extent(caps: &vk::SurfaceCapabilitiesKHR, window: [u32; 2]) -> Option<vk::Extent2D> {
    let extent = if caps.current_extent.width != u32::MAX {
        caps.current_extent
    } else {
        vk::Extent2D {
            width: window[0].clamp(caps.min_image_extent.width, caps.max_image_extent.width),
            height: window[1].clamp(caps.min_image_extent.height, caps.max_image_extent.height),
        }
    };
    (extent.width > 0 && extent.height > 0).then_some(extent)
}

/// The images' usage: the viewer copies into them (TRANSFER_DST, required), reads one back
/// for screenshots (TRANSFER_SRC) and draws the menu into them (COLOR_ATTACHMENT) where the
/// surface allows.
fn choose_usage(supported: vk::ImageUsageFlags) -> Result<vk::ImageUsageFlags, GpuError> {
    if !supported.contains(vk::ImageUsageFlags::TRANSFER_DST) {
        return Err(GpuError::Unsupported(
            "the window's swapchain images cannot be transfer destinations".into(),
        ));
    }
    let optional = vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::COLOR_ATTACHMENT;
    Ok(vk::ImageUsageFlags::TRANSFER_DST | (supported & optional))
}

/// One more than the minimum, so acquiring never waits for the presentation engine to
/// release an image while we could be drawing (a maximum of 0 means none).
fn image_count(caps: &vk::SurfaceCapabilitiesKHR) -> u32 {
    let count = caps.min_image_count + 1;
    match caps.max_image_count {
        0 => count,
        max => count.min(max),
    }
}

/// Opaque where the surface allows it, else the first mode it offers.
fn choose_alpha(supported: vk::CompositeAlphaFlagsKHR) -> vk::CompositeAlphaFlagsKHR {
    [
        vk::CompositeAlphaFlagsKHR::OPAQUE,
        vk::CompositeAlphaFlagsKHR::INHERIT,
        vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
        vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
    ]
    .into_iter()
    .find(|&a| supported.contains(a))
    .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE)
}

fn is_srgb(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB | vk::Format::A8B8G8R8_SRGB_PACK32
    )
}

/// Of the formats the surface offers that can be blitted into, an 8-bit sRGB one when there
/// is one (the blit then encodes linear colours exactly as the PNG writer does), else the
/// first.
fn choose_format(
    formats: &[vk::SurfaceFormatKHR],
    blittable: impl Fn(vk::Format) -> bool,
) -> Result<vk::SurfaceFormatKHR, GpuError> {
    let usable: Vec<&vk::SurfaceFormatKHR> =
        formats.iter().filter(|f| blittable(f.format)).collect();
    let srgb = |f: &&&vk::SurfaceFormatKHR| {
        is_srgb(f.format) && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR
    };
    (usable.iter().find(srgb).or_else(|| usable.first()))
        .map(|&&f| f)
        .ok_or_else(|| {
            GpuError::Unsupported(format!(
                "none of the window surface's {} format(s) can be blitted into \
                 (VK_FORMAT_FEATURE_BLIT_DST_BIT), which the viewer needs",
                formats.len()
            ))
        })
}

fn choose_present_mode(
    offered: &[vk::PresentModeKHR],
    preference: PresentPreference,
) -> vk::PresentModeKHR {
    match preference {
        PresentPreference::Mailbox if offered.contains(&vk::PresentModeKHR::MAILBOX) => {
            vk::PresentModeKHR::MAILBOX
        }
        // FIFO is the one mode every surface must offer.
        _ => vk::PresentModeKHR::FIFO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn caps(current: [u32; 2], min: [u32; 2], max: [u32; 2]) -> vk::SurfaceCapabilitiesKHR {
        let e = |[width, height]: [u32; 2]| vk::Extent2D { width, height };
        vk::SurfaceCapabilitiesKHR {
            current_extent: e(current),
            min_image_extent: e(min),
            max_image_extent: e(max),
            ..Default::default()
        }
    }

    #[test]
    fn the_extent_is_the_surfaces_or_the_clamped_window_and_none_when_minimised() {
        let fixed = caps([640, 480], [1, 1], [4096, 4096]);
        let e = choose_extent(&fixed, [1200, 450]).unwrap();
        assert_eq!((e.width, e.height), (640, 480));
        let free = caps([u32::MAX, u32::MAX], [1, 1], [1000, 1000]);
        let e = choose_extent(&free, [1200, 450]).unwrap();
        assert_eq!((e.width, e.height), (1000, 450));
        // A minimised X11 window reports a current extent of 0 x 0.
        assert!(choose_extent(&caps([0, 0], [0, 0], [4096, 4096]), [1200, 450]).is_none());
    }

    #[test]
    fn fifo_unless_mailbox_is_asked_for_and_offered() {
        use vk::PresentModeKHR as M;
        let both = [M::IMMEDIATE, M::MAILBOX, M::FIFO];
        assert_eq!(choose_present_mode(&both, PresentPreference::Fifo), M::FIFO);
        assert_eq!(
            choose_present_mode(&both, PresentPreference::Mailbox),
            M::MAILBOX
        );
        assert_eq!(
            choose_present_mode(&[M::FIFO], PresentPreference::Mailbox),
            M::FIFO
        );
    }

    #[test]
    fn an_srgb_format_is_preferred() {
        let f = |format| vk::SurfaceFormatKHR {
            format,
            color_space: vk::ColorSpaceKHR::SRGB_NONLINEAR,
        };
        let offered = [f(vk::Format::B8G8R8A8_UNORM), f(vk::Format::B8G8R8A8_SRGB)];
        let all = |_| true;
        assert_eq!(
            choose_format(&offered, all).unwrap().format,
            vk::Format::B8G8R8A8_SRGB
        );
        assert!(choose_format(&[], all).is_err());
        // An sRGB format that cannot be blitted into is passed over, and without any format
        // that can, the viewer is refused with the reason.
        let unorm_only = |format| format == vk::Format::B8G8R8A8_UNORM;
        assert_eq!(
            choose_format(&offered, unorm_only).unwrap().format,
            vk::Format::B8G8R8A8_UNORM
        );
        let error = choose_format(&offered, |_| false).unwrap_err().to_string();
        assert!(error.contains("BLIT_DST"), "{error}");
    }
}
