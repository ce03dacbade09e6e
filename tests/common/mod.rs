//! Shared by the integration tests: a validated device on lavapipe (or whatever is present) and
//! the rule that any validation message fails the test.
#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::path::{Path, PathBuf};

use lamina::imageio::{self, HdrImage};
use lamina::model::LayerParams;
use lamina::vk::{DeviceSelector, InstanceDesc};
use lamina::Gpu;

/// A device with the Khronos validation layer on.
pub fn gpu() -> Gpu {
    Gpu::validated().expect("a Vulkan device with the validation layer (run scripts/setup.sh)")
}

/// [`gpu`] with its pipeline cache's file in `dir` (the tests' default keeps it in memory).
pub fn gpu_with_pipeline_cache(dir: &Path) -> Gpu {
    Gpu::with_pipeline_cache(InstanceDesc::validated(), &DeviceSelector::Best, Some(dir))
        .expect("a Vulkan device with the validation layer (run scripts/setup.sh)")
}

/// Fails when the validation layer said anything of warning or error severity.
pub fn assert_validation_clean(gpu: &Gpu) {
    let messages = gpu.device.instance().messages();
    assert_eq!(
        messages.problems(),
        0,
        "validation layer messages: {:?}",
        messages.first_errors()
    );
}

pub fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub fn studio() -> HdrImage {
    imageio::read_exr(&repo_path("assets/env/studio.exr")).expect("bundled environment map")
}

/// A fresh, empty directory under the target directory for one test's files.
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

/// A single rough gold layer (ALGORITHMS.md §12.2 n, k): the baseline's default material.
pub fn gold() -> Vec<LayerParams> {
    vec![LayerParams {
        ior: [0.143245, 0.377423, 1.43919],
        kappa: [3.98479, 2.3847, 1.60434],
        roughness: 0.2,
        depth: 0.0,
        sigma_s: [0.0; 3],
        sigma_a: [0.0; 3],
        g: 0.0,
        diffuse: None,
    }]
}
