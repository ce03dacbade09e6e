//! Physical-device choice, the logical device, its queue and the memory allocator.
//!
//! lamina needs Vulkan 1.3 (dynamic rendering, synchronization2, maintenance4 — SPIR-V 1.6
//! compute shaders declare their workgroup size with `LocalSizeId`), host query reset and pipeline
//! statistics queries; `shaderFloat16` and `VK_KHR_pipeline_executable_properties` are enabled
//! when present and reported otherwise. One queue family with graphics + compute does all work.

use std::ffi::CStr;
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::error::{Check, VkError, VkResult};
use super::instance::{Instance, InstanceDesc};

/// Which physical device to use: by index in enumeration order, or by a case-insensitive
/// substring of its name.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum DeviceSelector {
    /// Prefer a discrete GPU, then integrated, then anything (lavapipe when it is the only one).
    #[default]
    Best,
    Index(usize),
    Name(String),
}

impl std::str::FromStr for DeviceSelector {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.parse::<usize>() {
            Ok(i) => Self::Index(i),
            Err(_) => Self::Name(s.to_owned()),
        })
    }
}

/// What a physical device offers, as far as lamina cares.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceReport {
    pub index: usize,
    pub name: String,
    pub driver_name: String,
    pub driver_info: String,
    pub vendor_id: u32,
    pub device_id: u32,
    /// `VkDriverId`: which driver, whatever its version.
    pub driver_id: u32,
    /// The driver's own version encoding (not the API's).
    pub driver_version: u32,
    /// Pipeline-cache data is compatible between devices that report the same vendor, device
    /// and UUID (`src/vk/pipeline_cache.rs`).
    pub pipeline_cache_uuid: [u8; vk::UUID_SIZE],
    pub device_type: String,
    pub api_version: String,
    pub shader_float16: bool,
    /// Lanes that execute in lockstep (`VkPhysicalDeviceSubgroupProperties`): llvmpipe's SIMD
    /// vector width in 32-bit lanes, a GPU's warp or wave.
    pub subgroup_size: u32,
    pub timestamps: bool,
    pub timestamp_period_ns: f32,
    pub timestamp_valid_bits: u32,
    pub pipeline_statistics: bool,
    pub pipeline_executable_properties: bool,
    pub dynamic_rendering: bool,
    pub synchronization2: bool,
    /// Core in Vulkan 1.3 and required there; glslang's SPIR-V 1.6 output uses `LocalSizeId`.
    pub maintenance4: bool,
    pub host_query_reset: bool,
    pub max_image_dimension_3d: u32,
    pub max_image_dimension_cube: u32,
    pub sub_texel_precision_bits: u32,
}

fn version_string(v: u32) -> String {
    format!(
        "{}.{}.{}",
        vk::api_version_major(v),
        vk::api_version_minor(v),
        vk::api_version_patch(v)
    )
}

fn c_str_lossy(r: Result<&CStr, std::ffi::FromBytesUntilNulError>) -> String {
    r.map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The queue family that can do graphics and compute, and whether it has timestamps.
fn universal_queue_family(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Option<(u32, u32)> {
    // SAFETY: `pd` was enumerated from `instance`.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    families.iter().enumerate().find_map(|(i, f)| {
        f.queue_flags
            .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
            .then_some((i as u32, f.timestamp_valid_bits))
    })
}

fn has_extension(instance: &ash::Instance, pd: vk::PhysicalDevice, name: &CStr) -> bool {
    // SAFETY: `pd` was enumerated from `instance`.
    unsafe { instance.enumerate_device_extension_properties(pd) }
        .map(|exts| exts.iter().any(|e| e.extension_name_as_c_str() == Ok(name)))
        .unwrap_or(false)
}

fn report(instance: &ash::Instance, index: usize, pd: vk::PhysicalDevice) -> DeviceReport {
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut driver)
        .push_next(&mut subgroup);
    // SAFETY: `pd` was enumerated from `instance`; the chain borrows locals.
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let props = props2.properties;

    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut features2 = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut f12)
        .push_next(&mut f13);
    // SAFETY: as above.
    unsafe { instance.get_physical_device_features2(pd, &mut features2) };
    let core = features2.features;

    let exec_props = has_extension(instance, pd, ash::khr::pipeline_executable_properties::NAME);
    let (_, ts_bits) = universal_queue_family(instance, pd).unwrap_or((0, 0));
    DeviceReport {
        index,
        name: c_str_lossy(props.device_name_as_c_str()),
        driver_name: c_str_lossy(driver.driver_name_as_c_str()),
        driver_info: c_str_lossy(driver.driver_info_as_c_str()),
        vendor_id: props.vendor_id,
        device_id: props.device_id,
        driver_id: driver.driver_id.as_raw() as u32,
        driver_version: props.driver_version,
        pipeline_cache_uuid: props.pipeline_cache_uuid,
        device_type: format!("{:?}", props.device_type),
        api_version: version_string(props.api_version),
        shader_float16: f12.shader_float16 == vk::TRUE,
        timestamps: props.limits.timestamp_compute_and_graphics == vk::TRUE && ts_bits > 0,
        timestamp_period_ns: props.limits.timestamp_period,
        timestamp_valid_bits: ts_bits,
        pipeline_statistics: core.pipeline_statistics_query == vk::TRUE,
        pipeline_executable_properties: exec_props,
        dynamic_rendering: f13.dynamic_rendering == vk::TRUE,
        synchronization2: f13.synchronization2 == vk::TRUE,
        maintenance4: f13.maintenance4 == vk::TRUE,
        host_query_reset: f12.host_query_reset == vk::TRUE,
        max_image_dimension_3d: props.limits.max_image_dimension3_d,
        max_image_dimension_cube: props.limits.max_image_dimension_cube,
        sub_texel_precision_bits: props.limits.sub_texel_precision_bits,
        subgroup_size: subgroup.subgroup_size,
    }
}

/// Reports for every physical device, in enumeration order.
pub fn enumerate(instance: &Instance) -> VkResult<Vec<DeviceReport>> {
    // SAFETY: plain enumeration on a live instance.
    let pds =
        unsafe { instance.raw.enumerate_physical_devices() }.check("vkEnumeratePhysicalDevices")?;
    Ok(pds
        .iter()
        .enumerate()
        .map(|(i, &pd)| report(&instance.raw, i, pd))
        .collect())
}

/// The logical device with everything lamina's passes need.
pub struct Device {
    pub(crate) raw: ash::Device,
    pub(crate) physical: vk::PhysicalDevice,
    /// `VK_KHR_swapchain`, enabled when the instance has surfaces and the device offers it.
    pub(crate) swapchain: Option<ash::khr::swapchain::Device>,
    pub(crate) queue: vk::Queue,
    pub(crate) queue_family: u32,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    pub(crate) debug_utils: Option<ash::ext::debug_utils::Device>,
    pub(crate) exec_props: Option<ash::khr::pipeline_executable_properties::Device>,
    pub report: DeviceReport,
    /// Last: the instance must outlive the device.
    pub(crate) instance: Arc<Instance>,
}

/// The physical device `selector` picks among the instance's, with its report; an error when
/// it names none, or when the one it names lacks what lamina needs.
fn choose(
    instance: &Instance,
    selector: &DeviceSelector,
) -> VkResult<(vk::PhysicalDevice, DeviceReport)> {
    // SAFETY: plain enumeration on a live instance.
    let pds =
        unsafe { instance.raw.enumerate_physical_devices() }.check("vkEnumeratePhysicalDevices")?;
    let reports: Vec<DeviceReport> = pds
        .iter()
        .enumerate()
        .map(|(i, &pd)| report(&instance.raw, i, pd))
        .collect();
    let usable = |r: &DeviceReport| {
        r.dynamic_rendering
            && r.synchronization2
            && r.maintenance4
            && r.host_query_reset
            && universal_queue_family(&instance.raw, pds[r.index]).is_some()
    };
    let chosen = match selector {
        DeviceSelector::Index(i) => reports.get(*i),
        DeviceSelector::Name(n) => {
            let n = n.to_lowercase();
            reports.iter().find(|r| r.name.to_lowercase().contains(&n))
        }
        DeviceSelector::Best => {
            let rank = |r: &DeviceReport| match r.device_type.as_str() {
                "DISCRETE_GPU" => 0,
                "INTEGRATED_GPU" => 1,
                "VIRTUAL_GPU" => 2,
                _ => 3,
            };
            reports.iter().filter(|r| usable(r)).min_by_key(|r| rank(r))
        }
    };
    let Some(chosen) = chosen.cloned() else {
        return Err(VkError::NoSuchDevice {
            wanted: format!("{selector:?}"),
            available: reports
                .iter()
                .map(|r| format!("{}: {}", r.index, r.name))
                .collect::<Vec<_>>()
                .join(", "),
        });
    };
    if !usable(&chosen) {
        return Err(VkError::Unsupported(format!(
            "device `{}` lacks Vulkan 1.3 dynamic rendering, synchronization2, maintenance4, host \
             query reset or a graphics+compute queue",
            chosen.name
        )));
    }
    Ok((pds[chosen.index], chosen))
}

/// The logical device on `physical` with one queue of `queue_family`, the features lamina
/// uses and the extensions `chosen` reports (pipeline executable properties; the swapchain
/// when the instance has a surface); and whether it has the swapchain.
fn create_logical(
    instance: &Instance,
    physical: vk::PhysicalDevice,
    chosen: &DeviceReport,
    queue_family: u32,
) -> VkResult<(ash::Device, bool)> {
    let priorities = [1.0f32];
    let queue_infos = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(queue_family)
        .queue_priorities(&priorities)];
    let mut extensions: Vec<*const i8> = Vec::new();
    if chosen.pipeline_executable_properties {
        extensions.push(ash::khr::pipeline_executable_properties::NAME.as_ptr());
    }
    // SAFETY: plain enumeration on a live physical device.
    let device_extensions = unsafe { instance.raw.enumerate_device_extension_properties(physical) }
        .check("vkEnumerateDeviceExtensionProperties")?;
    let swapchain = instance.surface
        && device_extensions
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(ash::khr::swapchain::NAME));
    if swapchain {
        extensions.push(ash::khr::swapchain::NAME.as_ptr());
    }
    let core =
        vk::PhysicalDeviceFeatures::default().pipeline_statistics_query(chosen.pipeline_statistics);
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
        .host_query_reset(true)
        .shader_float16(chosen.shader_float16);
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true)
        .maintenance4(true);
    let mut exec = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
        .pipeline_executable_info(true);
    let mut info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_infos)
        .enabled_extension_names(&extensions)
        .enabled_features(&core)
        .push_next(&mut f12)
        .push_next(&mut f13);
    if chosen.pipeline_executable_properties {
        info = info.push_next(&mut exec);
    }
    // SAFETY: the features requested were reported as supported by `physical`.
    let raw =
        unsafe { instance.raw.create_device(physical, &info, None) }.check("vkCreateDevice")?;
    Ok((raw, swapchain))
}

impl Device {
    /// Creates an instance per `desc` and a device chosen by `selector`.
    pub fn create(desc: InstanceDesc, selector: &DeviceSelector) -> VkResult<Arc<Self>> {
        let instance = Arc::new(Instance::new(desc)?);
        Self::new(instance, selector)
    }

    pub fn new(instance: Arc<Instance>, selector: &DeviceSelector) -> VkResult<Arc<Self>> {
        let (physical, chosen) = choose(&instance, selector)?;
        let (queue_family, _) =
            universal_queue_family(&instance.raw, physical).expect("checked by `usable`");
        let (raw, swapchain) = create_logical(&instance, physical, &chosen, queue_family)?;
        // SAFETY: family and index were requested in `create_logical`'s queue infos.
        let queue = unsafe { raw.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.raw.clone(),
            device: raw.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: nothing was created from the device yet.
                unsafe { raw.destroy_device(None) };
                return Err(VkError::Alloc {
                    name: "allocator".into(),
                    source,
                });
            }
        };
        let debug_utils = instance
            .debug_utils
            .as_ref()
            .map(|_| ash::ext::debug_utils::Device::new(&instance.raw, &raw));
        let exec_props = chosen
            .pipeline_executable_properties
            .then(|| ash::khr::pipeline_executable_properties::Device::new(&instance.raw, &raw));

        let swapchain = swapchain.then(|| ash::khr::swapchain::Device::new(&instance.raw, &raw));
        Ok(Arc::new(Self {
            raw,
            physical,
            swapchain,
            queue,
            queue_family,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            debug_utils,
            exec_props,
            report: chosen,
            instance,
        }))
    }

    pub fn instance(&self) -> &Arc<Instance> {
        &self.instance
    }

    /// Validation messages counted by the instance's messenger so far.
    pub fn validation_problems(&self) -> u32 {
        self.instance.messages().problems()
    }

    /// The debug names of the allocations alive now: what would leak if the device went away
    /// (every owner releases its allocation in `Drop`; the device reports any left at exit).
    pub fn live_allocations(&self) -> Vec<String> {
        let allocator = self.allocator.lock().expect("allocator lock poisoned");
        allocator
            .generate_report()
            .allocations
            .into_iter()
            .map(|a| a.name)
            .collect()
    }

    pub fn supports_fp16(&self) -> bool {
        self.report.shader_float16
    }

    /// Whether `STENCIL_FORMAT` can be a stencil attachment here (optimal tiling).
    pub fn supports_stencil_target(&self) -> bool {
        // SAFETY: `physical` was enumerated from this device's instance, which outlives it.
        let props = unsafe {
            self.instance
                .raw
                .get_physical_device_format_properties(self.physical, super::STENCIL_FORMAT)
        };
        props
            .optimal_tiling_features
            .contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
    }

    pub fn wait_idle(&self) -> VkResult<()> {
        // SAFETY: the device is alive; waiting has no other precondition.
        unsafe { self.raw.device_wait_idle() }.check("vkDeviceWaitIdle")
    }

    /// Names a Vulkan object for validation messages and capture tools. A no-op without
    /// `VK_EXT_debug_utils`.
    pub(crate) fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(utils) = &self.debug_utils else {
            return;
        };
        let Ok(name) = std::ffi::CString::new(name) else {
            return;
        };
        let info = vk::DebugUtilsObjectNameInfoEXT::default()
            .object_handle(handle)
            .object_name(&name);
        // SAFETY: `handle` belongs to this device (callers name objects they just created).
        // Naming is advisory, so a failure is ignored.
        let _ = unsafe { utils.set_debug_utils_object_name(&info) };
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        if std::thread::panicking() {
            // Children skipped their release too; leak the lot rather than destroy a device
            // with live children.
            return;
        }
        let leaked = self.live_allocations();
        if !leaked.is_empty() {
            eprintln!(
                "warning: {} GPU allocation(s) were never freed: {}",
                leaked.len(),
                leaked.join(", ")
            );
        }
        // SAFETY: every child object holds an `Arc<Device>`, so none is alive; waiting idle makes
        // sure no submitted work still references memory owned by the allocator.
        unsafe {
            let _ = self.raw.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.raw.destroy_device(None);
        }
    }
}
