//! Frame captures through RenderDoc's in-application API (`renderdoc_app.h`, through the
//! `renderdoc` crate): `--capture FILE.rdc` on `render` and `bench`.
//!
//! RenderDoc captures Vulkan through its layer (`VK_LAYER_RENDERDOC_Capture`, an implicit layer
//! its package installs), which the loader enables only in a process that has loaded
//! `librenderdoc.so` before it created its instance: [`Capturer::load`] must come before the
//! [`Device`] it captures. Headless work has no window, so a capture names the device by its
//! instance (`RENDERDOC_DEVICEPOINTER_FROM_VKINSTANCE`) and spans exactly the commands
//! submitted between its start and its end.

use std::ffi::c_void;
use std::path::{Path, PathBuf};

use ash::vk::Handle;
use renderdoc::{RenderDoc, V141};

use super::device::Device;
use super::error::{VkError, VkResult};

/// RenderDoc's library, as its Debian package (`librenderdoc`) installs it.
pub const LIBRARY: &str = "librenderdoc.so";

/// RenderDoc loaded into this process, ready to capture.
pub struct Capturer {
    api: RenderDoc<V141>,
    /// Last: the API's function table lives in the library, which stays loaded while it is used.
    _library: libloading::Library,
}

impl Capturer {
    /// Loads RenderDoc's library and its in-application API; before any Vulkan instance of
    /// this process, or RenderDoc's layer will not see it. An error names the library and its
    /// package when it is missing.
    pub fn load() -> VkResult<Self> {
        Self::load_from(LIBRARY)
    }

    /// [`Capturer::load`] from the library `name` (a file name the dynamic loader searches
    /// for, or a path).
    pub fn load_from(name: &str) -> VkResult<Self> {
        // SAFETY: loading runs the library's initialisers, which install RenderDoc's hooks;
        // that is what loading it is for, and nothing of Vulkan exists yet (the caller's
        // contract above).
        let library = unsafe { libloading::Library::new(name) }.map_err(|e| {
            VkError::Capture(format!(
                "RenderDoc's library {name} could not be loaded ({e}); on Debian: \
                 `apt install librenderdoc`"
            ))
        })?;
        let api = RenderDoc::<V141>::new().map_err(|e| {
            VkError::Capture(format!(
                "{name} loaded but gave no in-application API of version 1.4.1 or later: {e}"
            ))
        })?;
        Ok(Self {
            api,
            _library: library,
        })
    }

    /// RenderDoc's version, `major.minor.patch`, as its API reports it.
    pub fn version(&self) -> String {
        let (major, minor, patch) = self.api.get_api_version();
        format!("{major}.{minor}.{patch}")
    }

    /// Runs `work` inside one capture of `device` and moves the capture to `file` (written
    /// under a temporary name beside it, then renamed, so `file` is whole or absent). An error
    /// when RenderDoc wrote no capture: the device was created before [`Capturer::load`], or
    /// RenderDoc's layer is not installed.
    pub fn capture<R, E>(
        &mut self,
        device: &Device,
        file: &Path,
        work: impl FnOnce() -> Result<R, E>,
    ) -> Result<Result<R, E>, VkError> {
        let dir = match file.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&dir).map_err(|e| {
            VkError::Capture(format!(
                "creating the capture's folder {}: {e}",
                dir.display()
            ))
        })?;
        let stem = file
            .file_stem()
            .map_or_else(|| "capture".into(), |s| s.to_string_lossy().into_owned());
        let template = dir.join(format!(".{stem}.tmp-{}", std::process::id()));
        self.api.set_capture_file_path_template(template);
        let before = self.api.get_num_captures();
        let instance = device.instance.raw.handle().as_raw() as *const *const c_void;
        // SAFETY: a dispatchable handle points to the loader's object, whose first member is
        // its dispatch table: the pointer RenderDoc identifies the instance's devices by
        // (`RENDERDOC_DEVICEPOINTER_FROM_VKINSTANCE`). The instance lives while `device` does.
        let pointer = unsafe { *instance };
        self.api.start_frame_capture(pointer, std::ptr::null());
        let result = work();
        self.api.end_frame_capture(pointer, std::ptr::null());
        if self.api.get_num_captures() <= before {
            return Err(VkError::Capture(format!(
                "RenderDoc wrote no capture of {}: its Vulkan layer (VK_LAYER_RENDERDOC_Capture) \
                 did not see the device",
                device.report.name
            )));
        }
        let (written, _) = self.api.get_capture(before).ok_or_else(|| {
            VkError::Capture("RenderDoc counted a capture it does not list".into())
        })?;
        std::fs::rename(&written, file).map_err(|e| {
            VkError::Capture(format!(
                "moving the capture {} to {}: {e}",
                written.display(),
                file.display()
            ))
        })?;
        Ok(result)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_library_is_named_with_its_package() {
        let Err(e) = Capturer::load_from("librenderdoc-absent.so") else {
            panic!("a library that does not exist loaded");
        };
        let message = e.to_string();
        assert!(
            message.contains("librenderdoc-absent.so")
                && message.contains("apt install librenderdoc"),
            "{message}"
        );
    }
}
