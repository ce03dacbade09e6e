//! The pipeline cache: every pipeline is created through one, so that a driver that keeps
//! compiled pipelines in it can skip the compile the next time, within a run and — when its data
//! is saved and handed back (`crate::pipeline_cache`) — across runs.
//!
//! `vkCreatePipelineCache` may only be given data an earlier `vkGetPipelineCacheData` returned
//! (VUID-VkPipelineCacheCreateInfo-initialDataSize-00769), and drivers differ in how well they
//! survive anything else. So initial data reaches the driver only as [`CacheData`], whose
//! Vulkan header (`VkPipelineCacheHeaderVersionOne`: size, version, vendor, device, pipeline
//! cache UUID, all little-endian) has been checked against the device first.

use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{Check, VkResult};

/// Bytes in `VkPipelineCacheHeaderVersionOne`.
const HEADER_BYTES: usize = 32;

/// Why pipeline-cache data is not for this device.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CacheDataError {
    #[error("{0} bytes, shorter than the {HEADER_BYTES}-byte Vulkan header")]
    Short(usize),
    #[error("header size {0}, expected {HEADER_BYTES}")]
    HeaderSize(u32),
    #[error("header version {0}, expected 1")]
    HeaderVersion(u32),
    #[error("made for device {vendor:#x}:{device:#x}, this one is {expected_vendor:#x}:{expected_device:#x}")]
    OtherDevice {
        vendor: u32,
        device: u32,
        expected_vendor: u32,
        expected_device: u32,
    },
    #[error("made by another driver build (its pipeline cache UUID differs)")]
    OtherDriver,
}

/// Pipeline-cache data whose Vulkan header matches a device: what may seed a
/// [`PipelineCache`] on it.
#[derive(Clone, Copy, Debug)]
pub struct CacheData<'a> {
    bytes: &'a [u8],
}

impl<'a> CacheData<'a> {
    /// `bytes` if their header names `device`'s vendor, device and pipeline cache UUID.
    pub fn check(device: &Device, bytes: &'a [u8]) -> Result<Self, CacheDataError> {
        if bytes.len() < HEADER_BYTES {
            return Err(CacheDataError::Short(bytes.len()));
        }
        let word = |i: usize| u32::from_le_bytes(bytes[i * 4..i * 4 + 4].try_into().unwrap());
        let header_size = word(0);
        if header_size as usize != HEADER_BYTES {
            return Err(CacheDataError::HeaderSize(header_size));
        }
        let version = word(1);
        if version != vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32 {
            return Err(CacheDataError::HeaderVersion(version));
        }
        let report = &device.report;
        let (vendor, device_id) = (word(2), word(3));
        if (vendor, device_id) != (report.vendor_id, report.device_id) {
            return Err(CacheDataError::OtherDevice {
                vendor,
                device: device_id,
                expected_vendor: report.vendor_id,
                expected_device: report.device_id,
            });
        }
        if bytes[16..HEADER_BYTES] != report.pipeline_cache_uuid {
            return Err(CacheDataError::OtherDriver);
        }
        Ok(Self { bytes })
    }
}

/// A `VkPipelineCache`, internally synchronized (created without
/// `EXTERNALLY_SYNCHRONIZED`), so pipelines may be created through a shared reference.
pub struct PipelineCache {
    pub(crate) device: Arc<Device>,
    pub(crate) raw: vk::PipelineCache,
}

impl PipelineCache {
    /// An empty cache, or one seeded with `initial`.
    pub fn new(device: &Arc<Device>, initial: Option<CacheData<'_>>, name: &str) -> VkResult<Self> {
        let info = vk::PipelineCacheCreateInfo::default()
            .initial_data(initial.map_or(&[][..], |data| data.bytes));
        // SAFETY: initial data, when there is any, passed `CacheData::check` for a device like
        // this one (same vendor, device and pipeline cache UUID); the driver ignores data it
        // finds incompatible beyond that.
        let raw = unsafe { device.raw.create_pipeline_cache(&info, None) }
            .check("vkCreatePipelineCache")?;
        device.set_name(raw, name);
        Ok(Self {
            device: device.clone(),
            raw,
        })
    }

    /// The cache's contents as the driver serialises them, Vulkan header first: what a later
    /// [`PipelineCache::new`] on a device like this one may be seeded with.
    pub fn data(&self) -> VkResult<Vec<u8>> {
        // SAFETY: the cache is alive; reading its data needs no external synchronization.
        unsafe { self.device.raw.get_pipeline_cache_data(self.raw) }.check("vkGetPipelineCacheData")
    }

    pub fn device(&self) -> &Arc<Device> {
        &self.device
    }
}

impl Drop for PipelineCache {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: pipeline creation through the cache has returned (it borrows the cache), and
        // pipelines do not depend on the cache they were created with.
        unsafe { self.device.raw.destroy_pipeline_cache(self.raw, None) };
    }
}
