//! The Vulkan instance, the optional Khronos validation layer and its message sink.

use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

use ash::vk;

use super::loader::VALIDATION_LAYER;
use super::{GpuError, VkContext};

/// The `pMessageIdName` the Vulkan loader gives the messages it sends itself (e.g. "env var
/// 'VK_INSTANCE_LAYERS' defined"): they describe the user's environment, not our API usage,
/// so they are shown but do not count as validation messages.
const LOADER_MESSAGE_ID: &CStr = c"Loader Message";

/// The environment variable that turns validation on without `--validate`.
pub const VALIDATE_ENV: &str = "SPECCHIO_VALIDATE";

/// What to create the instance with.
#[derive(Debug, Clone, Default)]
pub struct InstanceDesc {
    /// Enable `VK_LAYER_KHRONOS_validation`, with its synchronization checks
    /// (`VK_EXT_validation_features`), and a messenger that records every warning and error
    /// (it is an error if the layer or its synchronization checks are missing: a silent
    /// fallback would hide bugs).
    pub validation: bool,
}

impl InstanceDesc {
    /// Validation on when `requested` or when `SPECCHIO_VALIDATE` is set to anything but `0`.
    pub fn from_env(requested: bool) -> Self {
        let env = std::env::var(VALIDATE_ENV).map(|v| v != "0" && !v.is_empty());
        Self {
            validation: requested || env.unwrap_or(false),
        }
    }
}

/// Every warning and error the validation layer reported, in order.
///
/// Shared (`Arc`) so that a caller can keep reading it after the instance is gone: the
/// layer's leak report is emitted while the device is destroyed.
#[derive(Debug, Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<String>>,
    loader_notes: Mutex<Vec<String>>,
}

impl ValidationLog {
    /// The validation layer's messages so far (a copy). Any one of them is a failure.
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }

    /// The loader's own warnings so far (a copy): about the environment (e.g. layers added
    /// through `VK_INSTANCE_LAYERS`), never about our use of the API, so not failures.
    pub fn loader_notes(&self) -> Vec<String> {
        self.loader_notes
            .lock()
            .map(|m| m.clone())
            .unwrap_or_default()
    }

    fn push(&self, source: MessageSource, message: String) {
        let list = match source {
            MessageSource::Layer => &self.messages,
            MessageSource::Loader => &self.loader_notes,
        };
        if let Ok(mut list) = list.lock() {
            list.push(message);
        }
    }
}

/// Who sent a debug-utils message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MessageSource {
    /// The Vulkan loader, about the environment.
    Loader,
    /// A layer (the validation layer): about the application's use of the API.
    Layer,
}

impl MessageSource {
    fn of(message_id_name: Option<&CStr>) -> Self {
        if message_id_name == Some(LOADER_MESSAGE_ID) {
            Self::Loader
        } else {
            Self::Layer
        }
    }
}

/// Owns the loader entry, the instance and (with validation) the debug messenger.
pub struct Instance {
    /// The process's loader (`loader::entry`, never unloaded): the surface and debug-utils
    /// functions are loaded through it.
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    /// `VK_EXT_debug_utils` at instance level: the messenger. `None` when the extension is absent.
    pub debug_utils: Option<ash::ext::debug_utils::Instance>,
    messenger: vk::DebugUtilsMessengerEXT,
    /// The messenger's user data points into this `Arc`'s allocation; it outlives `messenger`.
    log: Arc<ValidationLog>,
    pub validation: bool,
}

impl Instance {
    /// The instance the offline commands use: no extensions beyond debug utilities and the
    /// validation features.
    pub fn create(desc: &InstanceDesc) -> Result<Arc<Self>, GpuError> {
        Self::create_with_extensions(desc, &[])
    }

    /// [`Self::create`] with `extra` instance extensions enabled as well (the viewer's surface
    /// extensions, `surface::Surface::required_extensions`); one the loader does not offer is
    /// refused by name.
    pub fn create_with_extensions(
        desc: &InstanceDesc,
        extra: &[&'static CStr],
    ) -> Result<Arc<Self>, GpuError> {
        // The process's one loader, its drivers (and the layer) held open: see `loader`.
        let entry = super::loader::entry(desc.validation)?.clone();
        let offered = Offered::check(&entry, desc.validation, extra)?;
        let log: Arc<ValidationLog> = Arc::default();
        let use_messenger = desc.validation && offered.debug_utils;
        let raw = create_raw(&entry, desc.validation, extra, offered, &log)?;
        let debug_utils =
            (offered.debug_utils).then(|| ash::ext::debug_utils::Instance::new(&entry, &raw));
        let mut messenger = vk::DebugUtilsMessengerEXT::null();
        if let (true, Some(du)) = (use_messenger, &debug_utils) {
            // SAFETY: user data points into `log`'s allocation, dropped after the messenger.
            match unsafe { du.create_debug_utils_messenger(&messenger_info(&log), None) } {
                Ok(m) => messenger = m,
                Err(result) => {
                    // SAFETY: nothing was created from the instance yet.
                    unsafe { raw.destroy_instance(None) };
                    return Err(GpuError::Vk {
                        call: "vkCreateDebugUtilsMessengerEXT",
                        result,
                    });
                }
            }
        }
        Ok(Arc::new(Self {
            entry,
            raw,
            debug_utils,
            messenger,
            log,
            validation: desc.validation,
        }))
    }

    /// The validation messages sink (empty forever when validation is off).
    pub fn validation_log(&self) -> Arc<ValidationLog> {
        Arc::clone(&self.log)
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        if let Some(du) = &self.debug_utils {
            if self.messenger != vk::DebugUtilsMessengerEXT::null() {
                // SAFETY: the messenger was created from this instance and is destroyed once.
                unsafe { du.destroy_debug_utils_messenger(self.messenger, None) };
            }
        }
        // SAFETY: every child object holds an Arc<Instance>, so none is alive any more.
        unsafe { self.raw.destroy_instance(None) };
    }
}

/// What the loader offers of what the instance may enable.
#[derive(Clone, Copy)]
struct Offered {
    /// `VK_EXT_debug_utils`: object names and labels (RenderDoc) and the messenger.
    debug_utils: bool,
    /// `VK_EXT_validation_features` (from the layer), which turns its synchronization checks
    /// on (off by default: hazards such as two unordered writes pass silently).
    validation_features: bool,
}

impl Offered {
    /// Asks the loader; refuses validation without the layer or its synchronization checks,
    /// and an `extra` extension the loader lacks, by name.
    fn check(
        entry: &ash::Entry,
        validation: bool,
        extra: &[&'static CStr],
    ) -> Result<Self, GpuError> {
        // SAFETY: plain enumeration calls on a loaded entry.
        let layers = unsafe { entry.enumerate_instance_layer_properties() }
            .vk("vkEnumerateInstanceLayerProperties")?;
        let extensions = unsafe { entry.enumerate_instance_extension_properties(None) }
            .vk("vkEnumerateInstanceExtensionProperties")?;
        let has_layer = (layers.iter()).any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
        if validation && !has_layer {
            return Err(GpuError::NoValidationLayer);
        }
        let validation_features = validation && {
            // SAFETY: plain enumeration call for a layer the loader listed.
            let layer_extensions =
                unsafe { entry.enumerate_instance_extension_properties(Some(VALIDATION_LAYER)) }
                    .vk("vkEnumerateInstanceExtensionProperties")?;
            (layer_extensions.iter())
                .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::validation_features::NAME))
        };
        if validation && !validation_features {
            return Err(GpuError::NoSynchronizationValidation);
        }
        let has =
            |name: &CStr| (extensions.iter()).any(|e| e.extension_name_as_c_str() == Ok(name));
        if let Some(absent) = extra.iter().find(|&&name| !has(name)) {
            return Err(GpuError::Unsupported(format!(
                "the Vulkan loader offers no instance extension {}",
                absent.to_string_lossy()
            )));
        }
        Ok(Self {
            debug_utils: has(ash::ext::debug_utils::NAME),
            validation_features,
        })
    }
}

/// `vkCreateInstance` for Vulkan 1.3 with the layer when validating, debug utils where
/// offered, the synchronization checks on, and `extra`; messages from the call itself go to
/// `log`.
fn create_raw(
    entry: &ash::Entry,
    validation: bool,
    extra: &[&'static CStr],
    offered: Offered,
    log: &Arc<ValidationLog>,
) -> Result<ash::Instance, GpuError> {
    let app_info = vk::ApplicationInfo::default()
        .application_name(c"specchio")
        .application_version(vk::make_api_version(0, 0, 1, 0))
        .engine_name(c"specchio")
        // The core renderer needs Vulkan 1.3 (dynamic rendering, synchronization2).
        .api_version(vk::API_VERSION_1_3);
    let layer_names: Vec<*const i8> = match validation {
        true => vec![VALIDATION_LAYER.as_ptr()],
        false => vec![],
    };
    let mut extension_names: Vec<*const i8> = Vec::new();
    if offered.debug_utils {
        extension_names.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    if offered.validation_features {
        extension_names.push(ash::ext::validation_features::NAME.as_ptr());
    }
    extension_names.extend(extra.iter().map(|name| name.as_ptr()));
    let enabled_checks = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut validation_features =
        vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_checks);
    // One messenger description for the chain of vkCreateInstance (messages from the call
    // itself) and one for the messenger proper: a chained struct gets a pNext, which
    // vkCreateDebugUtilsMessengerEXT must not see.
    let mut messenger_for_create = messenger_info(log);
    let mut create_info = vk::InstanceCreateInfo::default()
        .application_info(&app_info)
        .enabled_layer_names(&layer_names)
        .enabled_extension_names(&extension_names);
    if offered.validation_features {
        create_info = create_info.push_next(&mut validation_features);
    }
    if validation && offered.debug_utils {
        // Chained so that messages from vkCreateInstance itself are caught too.
        create_info = create_info.push_next(&mut messenger_for_create);
    }
    // SAFETY: every pointer in create_info points at locals that outlive the call.
    unsafe { entry.create_instance(&create_info, None) }.vk("vkCreateInstance")
}

/// The messenger: warnings and errors of every type, into `log`.
fn messenger_info(log: &Arc<ValidationLog>) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(Arc::as_ptr(log) as *mut c_void)
}

/// Records every message in the [`ValidationLog`] and echoes it to stderr.
unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the sender passes a valid callback-data pointer for the duration of the call.
    let data = unsafe { data.as_ref() };
    // SAFETY: both strings are null or NUL-terminated, valid for the call.
    let message = data
        .and_then(|d| unsafe { d.message_as_c_str() })
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_else(|| "(no message)".to_owned());
    let source = MessageSource::of(data.and_then(|d| unsafe { d.message_id_name_as_c_str() }));
    let line = match source {
        MessageSource::Layer => format!("[vulkan {severity:?} {kind:?}] {message}"),
        MessageSource::Loader => format!("[vulkan loader {severity:?}] {message}"),
    };
    eprintln!("{line}");
    // SAFETY: user_data is the ValidationLog inside the Arc owned by the Instance.
    if let Some(log) = unsafe { (user_data as *const ValidationLog).as_ref() } {
        log.push(source, line);
    }
    vk::FALSE
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_loaders_messages_are_told_from_the_layers() {
        assert_eq!(
            MessageSource::of(Some(c"Loader Message")),
            MessageSource::Loader
        );
        assert_eq!(
            MessageSource::of(Some(c"SYNC-HAZARD-WRITE-AFTER-WRITE")),
            MessageSource::Layer
        );
        assert_eq!(MessageSource::of(None), MessageSource::Layer);
        let log = ValidationLog::default();
        log.push(MessageSource::Loader, "env var".into());
        log.push(MessageSource::Layer, "VUID".into());
        assert_eq!(log.messages(), ["VUID"]);
        assert_eq!(log.loader_notes(), ["env var"]);
    }
}
