//! The pipeline cache on disk, so that a driver which keeps compiled pipelines in its
//! `VkPipelineCache` (`vk::PipelineCache`) skips the compile in the next run too.
//!
//! - **Where:** `$LAMINA_CACHE/pipelines/` (default `~/.cache/lamina/pipelines/`), beside the
//!   tables (`cache::root`). A [`Gpu`](crate::Gpu) opened with `Gpu::new` uses it;
//!   `Gpu::validated`, the tests' device, keeps its cache in memory (a test that wants a file
//!   names a scratch directory, `Gpu::with_pipeline_cache`).
//! - **Key:** one file per device and driver build, named after what makes a driver's data
//!   reusable: `<vendorID>-<deviceID>-<driverID>-<driverVersion>-<pipelineCacheUUID>.bin`, in
//!   hex ([`file_name`]). The driver ID is there so that two drivers of one device (RADV and
//!   AMDVLK) keep a file each instead of replacing each other's.
//! - **Format:** `LAMPIPE1`, the length of the driver's data (u64, little-endian), its FNV-1a
//!   checksum (u64), then the data as `vkGetPipelineCacheData` returned it, Vulkan header first.
//! - **Trust:** the data reaches the driver only when its length and checksum match and its
//!   Vulkan header names this device's vendor, device and pipeline cache UUID
//!   (`vk::CacheData::check`). Anything else — a truncated, damaged or foreign file, another
//!   device's data — is ignored ([`Origin::Ignored`] says why): the cache starts empty and the
//!   file is rewritten at the next save. Never an error, never a crash.
//! - **Saving:** commands call [`PersistentCache::save`] when they end; dropping the `Gpu`
//!   saves too (the fallback when a command fails half-way). Nothing is written when the data
//!   equals the file's. The write is atomic (temporary file, then rename), so a crash or a
//!   concurrent run leaves one whole file. A failed save costs compiles later, not the run: the
//!   drop path prints a warning. Saving removes the files of the same vendor, device and driver
//!   with another driver version or UUID: the stale data of a driver update.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use crate::cache::{self, checksum};
use crate::error::Result;
use crate::imageio;
use crate::vk::{CacheData, Device, DeviceReport, PipelineCache};

const MAGIC: &[u8; 8] = b"LAMPIPE1";
/// Magic, length and checksum.
const PREFIX_BYTES: usize = 24;

/// Why a cache file's contents were not used.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FileError {
    #[error("not a lamina pipeline cache file")]
    NotOurs,
    #[error("{found} bytes of data where the file says {expected}: truncated or extended")]
    Length { expected: u64, found: u64 },
    #[error("the data does not match its checksum: damaged after it was written")]
    Checksum,
}

/// The directory [`Gpu::new`](crate::Gpu::new) keeps its pipeline cache in.
pub fn default_dir() -> Option<PathBuf> {
    Some(cache::root()?.join("pipelines"))
}

/// The prefix every file of this vendor, device and driver starts with, whatever its version.
fn driver_prefix(report: &DeviceReport) -> String {
    format!(
        "{:x}-{:x}-{:x}-",
        report.vendor_id, report.device_id, report.driver_id
    )
}

/// The file name of `report`'s device and driver build.
pub fn file_name(report: &DeviceReport) -> String {
    let uuid: String = report
        .pipeline_cache_uuid
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    format!(
        "{}{:x}-{uuid}.bin",
        driver_prefix(report),
        report.driver_version
    )
}

/// The file's bytes for the driver's `data`.
pub fn encode(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(PREFIX_BYTES + data.len());
    out.extend(MAGIC);
    out.extend((data.len() as u64).to_le_bytes());
    out.extend(checksum(data).to_le_bytes());
    out.extend(data);
    out
}

/// The driver's data in a file's bytes, if they are whole.
pub fn decode(file: &[u8]) -> Result<&[u8], FileError> {
    if file.len() < PREFIX_BYTES || &file[..8] != MAGIC {
        return Err(FileError::NotOurs);
    }
    let word = |i: usize| u64::from_le_bytes(file[i..i + 8].try_into().expect("8 bytes"));
    let (expected, sum) = (word(8), word(16));
    let data = &file[PREFIX_BYTES..];
    if data.len() as u64 != expected {
        return Err(FileError::Length {
            expected,
            found: data.len() as u64,
        });
    }
    if checksum(data) != sum {
        return Err(FileError::Checksum);
    }
    Ok(data)
}

/// What a [`PersistentCache`] started from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// No directory: the cache lives in memory only, nothing is read or written.
    Memory,
    /// No file for this device yet.
    Empty,
    /// Seeded with the file's data, this many bytes.
    Loaded { bytes: usize },
    /// The file was not used, for `reason`; the next save rewrites it.
    Ignored { reason: String },
}

/// The pipeline cache every pipeline of a `Gpu` is created through, and the file it is loaded
/// from and saved to.
pub struct PersistentCache {
    cache: PipelineCache,
    file: Option<PathBuf>,
    origin: Origin,
    /// The checksum of the data the file holds (as loaded, or as last saved), or of the data
    /// whose save failed: a save of the same data is not tried (and warned about) twice.
    on_disk: Mutex<Option<u64>>,
}

impl PersistentCache {
    /// The cache of `device`, seeded from its file in `dir` when that file is valid; `None`:
    /// in memory only.
    pub fn open(device: &Arc<Device>, dir: Option<&Path>) -> Result<Self> {
        let name = "pipeline cache";
        let Some(dir) = dir else {
            return Ok(Self {
                cache: PipelineCache::new(device, None, name)?,
                file: None,
                origin: Origin::Memory,
                on_disk: Mutex::new(None),
            });
        };
        let file = dir.join(file_name(&device.report));
        let bytes = match std::fs::read(&file) {
            Ok(bytes) => Some(bytes),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => {
                return Self::fresh(device, file, format!("reading it failed: {e}"));
            }
        };
        let Some(bytes) = bytes else {
            return Ok(Self {
                cache: PipelineCache::new(device, None, name)?,
                file: Some(file),
                origin: Origin::Empty,
                on_disk: Mutex::new(None),
            });
        };
        let data = match decode(&bytes) {
            Ok(data) => data,
            Err(e) => return Self::fresh(device, file, e.to_string()),
        };
        let checked = match CacheData::check(device, data) {
            Ok(checked) => checked,
            Err(e) => return Self::fresh(device, file, e.to_string()),
        };
        match PipelineCache::new(device, Some(checked), name) {
            Ok(cache) => Ok(Self {
                cache,
                file: Some(file),
                origin: Origin::Loaded { bytes: data.len() },
                on_disk: Mutex::new(Some(checksum(data))),
            }),
            Err(e) => Self::fresh(device, file, format!("the driver refused it: {e}")),
        }
    }

    /// An empty cache, its file ignored for `reason`.
    fn fresh(device: &Arc<Device>, file: PathBuf, reason: String) -> Result<Self> {
        Ok(Self {
            cache: PipelineCache::new(device, None, "pipeline cache")?,
            file: Some(file),
            origin: Origin::Ignored { reason },
            on_disk: Mutex::new(None),
        })
    }

    pub fn cache(&self) -> &PipelineCache {
        &self.cache
    }

    pub fn origin(&self) -> &Origin {
        &self.origin
    }

    /// Writes the cache to its file (atomically) unless the file already holds this data, or
    /// saving this data failed before; the path when it wrote.
    pub fn save(&self) -> Result<Option<PathBuf>> {
        let Some(file) = &self.file else {
            return Ok(None);
        };
        let data = self.cache.data()?;
        let sum = checksum(&data);
        let mut on_disk = self.on_disk.lock().expect("pipeline cache lock poisoned");
        if *on_disk == Some(sum) {
            return Ok(None);
        }
        *on_disk = Some(sum);
        imageio::write_file_atomically(file, encode(&data))?;
        remove_stale(file, &self.cache.device().report);
        Ok(Some(file.clone()))
    }
}

impl Drop for PersistentCache {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        if let Err(e) = self.save() {
            eprintln!(
                "warning: the pipeline cache was not saved (the next run compiles again): {e}"
            );
        }
    }
}

/// Deletes the files of `report`'s vendor, device and driver other than `current`: what an
/// earlier driver version left.
fn remove_stale(current: &Path, report: &DeviceReport) {
    let (Some(dir), Some(current)) = (current.parent(), current.file_name()) else {
        return;
    };
    let prefix = driver_prefix(report);
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let text = name.to_string_lossy();
        if name != current && text.starts_with(&prefix) && text.ends_with(".bin") {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_whole_files_decode() {
        let data = b"driver data, header first".to_vec();
        let file = encode(&data);
        assert_eq!(decode(&file), Ok(&data[..]));
        assert_eq!(decode(&file[..10]), Err(FileError::NotOurs));
        assert_eq!(
            decode(b"random bytes that are long enough"),
            Err(FileError::NotOurs)
        );
        assert_eq!(
            decode(&file[..file.len() - 1]),
            Err(FileError::Length {
                expected: data.len() as u64,
                found: data.len() as u64 - 1
            })
        );
        let mut damaged = file.clone();
        *damaged.last_mut().unwrap() ^= 1;
        assert_eq!(decode(&damaged), Err(FileError::Checksum));
        assert_eq!(decode(&encode(&[])), Ok(&[][..]));
    }
}
