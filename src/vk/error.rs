//! The error type of the Vulkan layer.
//!
//! `vk::Result`s that the caller cannot anticipate come back as [`VkError::Vk`] with the call that
//! produced them; missing features are [`VkError::Unsupported`] with what was asked for, so the
//! CLI can tell a user which device capability is absent instead of failing deep inside a driver.

use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error("could not load the Vulkan loader (libvulkan.so.1): {0}")]
    Loading(#[from] ash::LoadingError),
    #[error("{call} failed: {result}")]
    Vk {
        call: &'static str,
        result: vk::Result,
    },
    #[error("allocating GPU memory for `{name}` failed: {source}")]
    Alloc {
        name: String,
        source: gpu_allocator::AllocationError,
    },
    #[error("unsupported: {0}")]
    Unsupported(String),
    #[error("no Vulkan device matches `{wanted}`; available: {available}")]
    NoSuchDevice { wanted: String, available: String },
    #[error("capture: {0}")]
    Capture(String),
    #[error("timestamp queries are not available on queue family {0}")]
    NoTimestamps(u32),
}

pub type VkResult<T> = Result<T, VkError>;

/// Attaches the name of the failing call to a raw `vk::Result`.
pub(crate) trait Check<T> {
    fn check(self, call: &'static str) -> VkResult<T>;
}

impl<T> Check<T> for Result<T, vk::Result> {
    fn check(self, call: &'static str) -> VkResult<T> {
        self.map_err(|result| VkError::Vk { call, result })
    }
}
