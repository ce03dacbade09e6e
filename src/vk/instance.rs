//! Vulkan instance, validation layer and the debug messenger that counts messages.
//!
//! The messenger's counters are the contract the tests rely on: any validation message of error
//! severity (or warning, which lavapipe never emits for correct usage) fails a test. Messages are
//! also printed to stderr so a failing run shows what the layer said.

use std::ffi::{c_void, CStr, CString};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;

use ash::vk;

use super::error::{Check, VkError, VkResult};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How the instance is checked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct InstanceDesc {
    /// Enable the Khronos validation layer (an error when it is not installed).
    pub validation: bool,
    /// Also enable synchronization validation (implies `validation`).
    pub sync_validation: bool,
    /// Enable `VK_KHR_surface` and the window-system surface extensions the loader offers
    /// (X11, Wayland), so a window can be presented to (the viewer).
    pub surface: bool,
}

impl InstanceDesc {
    pub fn validated() -> Self {
        Self {
            validation: true,
            ..Self::default()
        }
    }
}

/// Validation message counts by severity, plus the first few error texts for reports.
#[derive(Debug, Default)]
pub struct MessageCounts {
    pub errors: AtomicU32,
    pub warnings: AtomicU32,
    pub infos: AtomicU32,
    first_errors: Mutex<Vec<String>>,
}

impl MessageCounts {
    fn record(&self, severity: vk::DebugUtilsMessageSeverityFlagsEXT, text: &str) {
        if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
            self.errors.fetch_add(1, Ordering::Relaxed);
            if let Ok(mut first) = self.first_errors.lock() {
                if first.len() < 8 {
                    first.push(text.to_owned());
                }
            }
        } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
            self.warnings.fetch_add(1, Ordering::Relaxed);
        } else {
            self.infos.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Errors plus warnings seen so far.
    pub fn problems(&self) -> u32 {
        self.errors.load(Ordering::Relaxed) + self.warnings.load(Ordering::Relaxed)
    }

    pub fn first_errors(&self) -> Vec<String> {
        self.first_errors
            .lock()
            .map(|v| v.clone())
            .unwrap_or_default()
    }
}

/// The window-system surface extensions lamina enables when the loader has them.
const SURFACE_EXTENSIONS: [&CStr; 3] = [
    ash::khr::xlib_surface::NAME,
    ash::khr::xcb_surface::NAME,
    ash::khr::wayland_surface::NAME,
];

pub struct Instance {
    /// Keeps the loader library loaded for as long as the instance lives.
    pub(crate) entry: ash::Entry,
    pub(crate) raw: ash::Instance,
    pub(crate) debug_utils: Option<ash::ext::debug_utils::Instance>,
    messenger: vk::DebugUtilsMessengerEXT,
    /// Boxed so the pointer handed to the messenger stays put.
    counts: Box<MessageCounts>,
    pub validation: bool,
    /// Whether the surface extensions are enabled ([`InstanceDesc::surface`]).
    pub surface: bool,
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the loader passes a valid callback-data pointer for the duration of the call, and
    // `user` is the `MessageCounts` box owned by the `Instance`, which destroys the messenger
    // before dropping the box.
    let (text, counts) = unsafe {
        let text = data
            .as_ref()
            .and_then(|d| d.message_as_c_str())
            .map(|m| m.to_string_lossy().into_owned())
            .unwrap_or_default();
        (text, &*(user as *const MessageCounts))
    };
    counts.record(severity, &text);
    if severity.intersects(
        vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
            | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
    ) {
        eprintln!("[vulkan {severity:?} {types:?}] {text}");
    }
    vk::FALSE
}

impl Instance {
    pub fn new(desc: InstanceDesc) -> VkResult<Self> {
        // SAFETY: loading the system loader library; no other Vulkan state exists yet.
        let entry = unsafe { ash::Entry::load()? };
        let validation = desc.validation || desc.sync_validation;

        // SAFETY: plain enumeration calls on a loaded entry.
        let layers = unsafe { entry.enumerate_instance_layer_properties() }
            .check("vkEnumerateInstanceLayerProperties")?;
        let has_validation = layers
            .iter()
            .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
        if validation && !has_validation {
            return Err(VkError::Unsupported(
                "the Khronos validation layer (Debian package vulkan-validationlayers) is not installed"
                    .into(),
            ));
        }
        // SAFETY: plain enumeration through a loaded entry; no layer name is passed.
        let extensions = unsafe { entry.enumerate_instance_extension_properties(None) }
            .check("vkEnumerateInstanceExtensionProperties")?;
        let has_debug_utils = extensions
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::debug_utils::NAME));

        let app_name = CString::new("lamina").expect("static name has no NUL");
        let app = vk::ApplicationInfo::default()
            .application_name(&app_name)
            .application_version(1)
            .engine_name(&app_name)
            .api_version(vk::API_VERSION_1_3);
        let layer_ptrs: Vec<*const i8> = if validation {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            Vec::new()
        };
        let has = |name: &CStr| {
            extensions
                .iter()
                .any(|e| e.extension_name_as_c_str() == Ok(name))
        };
        let mut ext_ptrs: Vec<*const i8> = Vec::new();
        if has_debug_utils {
            ext_ptrs.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let surface = desc.surface && has(ash::khr::surface::NAME);
        if desc.surface && !surface {
            return Err(VkError::Unsupported(
                "the Vulkan loader offers no VK_KHR_surface: no window can be presented to".into(),
            ));
        }
        if surface {
            ext_ptrs.push(ash::khr::surface::NAME.as_ptr());
            ext_ptrs.extend(
                SURFACE_EXTENSIONS
                    .iter()
                    .filter(|n| has(n))
                    .map(|n| n.as_ptr()),
            );
        }
        let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut validation_features =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
        let mut create_info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layer_ptrs)
            .enabled_extension_names(&ext_ptrs);
        if desc.sync_validation {
            create_info = create_info.push_next(&mut validation_features);
        }
        // SAFETY: every pointer in `create_info` borrows locals that outlive the call.
        let raw = unsafe { entry.create_instance(&create_info, None) }.check("vkCreateInstance")?;

        let counts = Box::new(MessageCounts::default());
        let (debug_utils, messenger) = if has_debug_utils {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &raw);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(&*counts as *const MessageCounts as *mut c_void);
            // SAFETY: the callback's user data is the boxed counts, which outlive the messenger
            // (destroyed first in `Drop`).
            let messenger = match unsafe { loader.create_debug_utils_messenger(&info, None) } {
                Ok(m) => m,
                Err(result) => {
                    // SAFETY: nothing has been created from the instance yet.
                    unsafe { raw.destroy_instance(None) };
                    return Err(VkError::Vk {
                        call: "vkCreateDebugUtilsMessengerEXT",
                        result,
                    });
                }
            };
            (Some(loader), messenger)
        } else {
            (None, vk::DebugUtilsMessengerEXT::null())
        };

        Ok(Self {
            entry,
            raw,
            debug_utils,
            messenger,
            counts,
            validation,
            surface,
        })
    }

    /// Validation messages seen so far.
    pub fn messages(&self) -> &MessageCounts {
        &self.counts
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: devices hold an `Arc<Instance>`, so all children are gone by now.
        unsafe {
            if let Some(loader) = &self.debug_utils {
                loader.destroy_debug_utils_messenger(self.messenger, None);
            }
            self.raw.destroy_instance(None);
        }
    }
}
