//! The pipeline cache on disk (`lamina::pipeline_cache`): saved by one `Gpu`, loaded by the
//! next; broken, truncated and foreign files ignored and rewritten; older driver builds' files
//! replaced; a cache that cannot be written fails its save, not the run.
//!
//! lavapipe (Mesa 22.3) serialises only the 32-byte Vulkan header and reports valid creation
//! feedback that never says "hit": there, the tests check that the saved data is loaded back;
//! on drivers that keep pipelines in the data they also check that the second build is a hit.

use crate::common;

use lamina::gpu::ComputeKernel;
use lamina::pipeline_cache::{decode, encode, file_name, Origin};
use lamina::shader::kernel::KernelSpec;
use lamina::tables::tir;
use lamina::vk::{CacheData, PipelineCreation};
use lamina::Gpu;

/// Bytes of `VkPipelineCacheHeaderVersionOne`.
const VULKAN_HEADER: usize = 32;

/// Builds the TIR table's kernel (a small compute pipeline) and says how its creation went.
fn build(gpu: &Gpu) -> PipelineCreation {
    ComputeKernel::build(gpu, &tir::KERNEL, &[], &[], KernelSpec::default())
        .expect("the TIR kernel builds")
        .pipeline
        .creation
}

#[test]
fn a_second_gpu_loads_what_the_first_saved() {
    let dir = common::scratch_dir("pipeline-cache-reuse");
    let first = common::gpu_with_pipeline_cache(&dir);
    assert_eq!(first.pipeline_cache().origin(), &Origin::Empty);
    let built = build(&first);
    assert_ne!(built.cache_hit, Some(true), "an empty cache holds nothing");
    let path = first
        .pipeline_cache()
        .save()
        .unwrap()
        .expect("a new cache is written");
    assert_eq!(
        path.file_name().unwrap().to_str(),
        Some(&file_name(&first.device.report)[..])
    );
    assert_eq!(
        first.pipeline_cache().save().unwrap(),
        None,
        "nothing new: the file is not rewritten"
    );
    let data = first.pipeline_cache().cache().data().unwrap();
    assert_eq!(decode(&std::fs::read(&path).unwrap()), Ok(&data[..]));
    common::assert_validation_clean(&first);
    drop(first);

    let second = common::gpu_with_pipeline_cache(&dir);
    assert_eq!(
        second.pipeline_cache().origin(),
        &Origin::Loaded { bytes: data.len() }
    );
    let again = build(&second);
    eprintln!(
        "{}: {} bytes of cache data; first build {:?} ({}), second {:?} ({})",
        second.device.report.name,
        data.len(),
        built.duration,
        built.cache_outcome(),
        again.duration,
        again.cache_outcome()
    );
    if data.len() > VULKAN_HEADER {
        assert_eq!(
            again.cache_hit,
            Some(true),
            "the driver keeps pipelines in its cache data: the second build is found there"
        );
    }
    common::assert_validation_clean(&second);
}

#[test]
fn a_broken_or_foreign_file_is_ignored_and_rewritten() {
    let dir = common::scratch_dir("pipeline-cache-broken");
    let gpu = common::gpu_with_pipeline_cache(&dir);
    build(&gpu);
    let path = gpu.pipeline_cache().save().unwrap().expect("written");
    common::assert_validation_clean(&gpu);
    drop(gpu);
    let valid = std::fs::read(&path).unwrap();
    let data = decode(&valid).unwrap().to_vec();
    let patched = |at: usize| {
        let mut d = data.clone();
        d[at] ^= 0x5a;
        encode(&d)
    };
    let mut damaged = valid.clone();
    *damaged.last_mut().unwrap() ^= 1;
    // A fixed pseudo-random sequence (64-bit LCG), so that a failure repeats.
    let random: Vec<u8> = (0..4096u64)
        .scan(0x9e37_79b9_7f4a_7c15u64, |x, _| {
            *x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            Some((*x >> 56) as u8)
        })
        .collect();
    let cases: [(&str, Vec<u8>, &str); 8] = [
        ("random bytes", random, "not a lamina pipeline cache"),
        ("an empty file", Vec::new(), "not a lamina pipeline cache"),
        ("a truncated file", valid[..30].to_vec(), "truncated"),
        ("damaged data", damaged, "checksum"),
        (
            "a truncated Vulkan header",
            encode(&data[..20]),
            "shorter than the 32-byte",
        ),
        ("another device's vendor", patched(8), "made for device"),
        ("another device", patched(12), "made for device"),
        ("another driver build", patched(20), "another driver build"),
    ];
    for (what, bytes, reason) in cases {
        std::fs::write(&path, &bytes).unwrap();
        let gpu = common::gpu_with_pipeline_cache(&dir);
        match gpu.pipeline_cache().origin() {
            Origin::Ignored { reason: said } => {
                assert!(said.contains(reason), "{what}: `{said}` lacks `{reason}`")
            }
            other => panic!("{what}: the file was not ignored: {other:?}"),
        }
        build(&gpu);
        assert_eq!(
            gpu.pipeline_cache().save().unwrap(),
            Some(path.clone()),
            "{what}: rewritten"
        );
        let rewritten = std::fs::read(&path).unwrap();
        let saved = decode(&rewritten).unwrap_or_else(|e| panic!("{what}: {e}"));
        CacheData::check(&gpu.device, saved).unwrap_or_else(|e| panic!("{what}: {e}"));
        common::assert_validation_clean(&gpu);
    }
}

#[test]
fn saving_replaces_older_driver_builds_files_only() {
    let dir = common::scratch_dir("pipeline-cache-stale");
    let gpu = common::gpu_with_pipeline_cache(&dir);
    let r = &gpu.device.report;
    let older = format!(
        "{:x}-{:x}-{:x}-{:x}-{}.bin",
        r.vendor_id,
        r.device_id,
        r.driver_id,
        r.driver_version.wrapping_add(1),
        "00".repeat(16)
    );
    let other_driver = format!(
        "{:x}-{:x}-{:x}-{:x}-{}.bin",
        r.vendor_id,
        r.device_id,
        r.driver_id.wrapping_add(1),
        r.driver_version,
        "00".repeat(16)
    );
    for name in [&older, &other_driver] {
        std::fs::write(dir.join(name), encode(b"old")).unwrap();
    }
    build(&gpu);
    let path = gpu.pipeline_cache().save().unwrap().expect("written");
    assert!(path.is_file());
    assert!(
        !dir.join(&older).exists(),
        "an older build's file is removed"
    );
    assert!(
        dir.join(&other_driver).exists(),
        "another driver's file stays"
    );
    common::assert_validation_clean(&gpu);
}

#[test]
fn a_cache_that_cannot_be_saved_fails_the_save_once_and_nothing_else() {
    let dir = common::scratch_dir("pipeline-cache-unwritable");
    let not_a_dir = dir.join("a file");
    std::fs::write(&not_a_dir, b"in the way").unwrap();
    let gpu = common::gpu_with_pipeline_cache(&not_a_dir);
    assert!(
        matches!(gpu.pipeline_cache().origin(), Origin::Ignored { .. }),
        "{:?}",
        gpu.pipeline_cache().origin()
    );
    build(&gpu);
    let e = gpu.pipeline_cache().save().unwrap_err().to_string();
    assert!(e.contains("a file"), "the error names the path: {e}");
    assert_eq!(
        gpu.pipeline_cache().save().unwrap(),
        None,
        "the same data is not tried again (nor warned about at drop)"
    );
    common::assert_validation_clean(&gpu);
}
