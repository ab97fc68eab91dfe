//! A window's Vulkan surface (`VK_KHR_surface` + the platform's extension), for the live
//! viewer only: the offline commands create no surface and enable none of these extensions.
//!
//! The window itself belongs to the caller (winit in the CLI); this module only sees its raw
//! handles, so the engine does not depend on a windowing library.

use std::ffi::CStr;
use std::sync::Arc;

use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use super::device::Device;
use super::instance::Instance;
use super::{GpuError, VkContext};

/// A `VkSurfaceKHR` and the extension functions that query it. Destroyed on drop; it holds
/// the instance, so the instance outlives it. The caller keeps the window alive longer (see
/// the viewer's field order).
pub struct Surface {
    pub raw: vk::SurfaceKHR,
    pub loader: ash::khr::surface::Instance,
    /// Held so that the instance outlives the surface.
    _instance: Arc<Instance>,
}

/// What the surface allows a swapchain on one device to be.
#[derive(Debug, Clone)]
pub struct SurfaceSupport {
    pub capabilities: vk::SurfaceCapabilitiesKHR,
    pub formats: Vec<vk::SurfaceFormatKHR>,
    pub present_modes: Vec<vk::PresentModeKHR>,
}

impl Surface {
    /// The instance extensions a surface on `display` needs (`VK_KHR_surface` and e.g.
    /// `VK_KHR_xlib_surface`), for `Instance::create_with_extensions`.
    pub fn required_extensions(display: RawDisplayHandle) -> Result<Vec<&'static CStr>, GpuError> {
        let names = ash_window::enumerate_required_extensions(display)
            .vk("vkEnumerateInstanceExtensionProperties (surface)")?;
        // SAFETY: ash-window returns pointers to ash's static, NUL-terminated extension names.
        Ok(names
            .iter()
            .map(|&p| unsafe { CStr::from_ptr(p) })
            .collect())
    }

    /// The surface of the window behind `display` and `window`. The window must outlive it.
    pub fn create(
        instance: &Arc<Instance>,
        display: RawDisplayHandle,
        window: RawWindowHandle,
    ) -> Result<Self, GpuError> {
        // SAFETY: the handles come from a live window (the caller keeps it alive longer) and
        // the instance was created with `required_extensions(display)`.
        let raw = unsafe {
            ash_window::create_surface(&instance.entry, &instance.raw, display, window, None)
        }
        .vk("vkCreate*SurfaceKHR")?;
        let loader = ash::khr::surface::Instance::new(&instance.entry, &instance.raw);
        Ok(Self {
            raw,
            loader,
            _instance: Arc::clone(instance),
        })
    }

    /// Whether `device`'s queue can present to this surface (refused with a reason if not).
    pub fn check_present(&self, device: &Device) -> Result<(), GpuError> {
        // SAFETY: the physical device and the surface come from the same instance.
        let ok = unsafe {
            self.loader.get_physical_device_surface_support(
                device.physical,
                device.queue_family,
                self.raw,
            )
        }
        .vk("vkGetPhysicalDeviceSurfaceSupportKHR")?;
        if ok {
            Ok(())
        } else {
            Err(GpuError::Unsupported(format!(
                "{} cannot present to this window (its queue family {} has no present support)",
                device.info.name, device.queue_family
            )))
        }
    }

    /// Capabilities, formats and present modes for `device`, asked anew (the extent changes
    /// with the window).
    pub fn support(&self, device: &Device) -> Result<SurfaceSupport, GpuError> {
        let (pd, s) = (device.physical, self.raw);
        // SAFETY (all three): the physical device and the surface come from the same instance.
        let capabilities = unsafe { self.loader.get_physical_device_surface_capabilities(pd, s) }
            .vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        let formats = unsafe { self.loader.get_physical_device_surface_formats(pd, s) }
            .vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let present_modes = unsafe { self.loader.get_physical_device_surface_present_modes(pd, s) }
            .vk("vkGetPhysicalDeviceSurfacePresentModesKHR")?;
        Ok(SurfaceSupport {
            capabilities,
            formats,
            present_modes,
        })
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        // SAFETY: every swapchain made on this surface holds an `Arc<Surface>`, so none is
        // alive; the instance is (we hold it).
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}
