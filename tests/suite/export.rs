//! `lamina export`: frozen SPIR-V that validates and holds no specialization constant, its
//! values beside it, and the stacks it refuses named.

use std::process::Command;

use crate::common::{self, lamina, text};
use lamina::shader::freeze::spec_constant_count;

fn spirv_val(path: &std::path::Path) {
    let out = Command::new("spirv-val")
        .args(["--target-env", "vulkan1.3"])
        .arg(path)
        .output()
        .expect("spirv-val runs (Debian: spirv-tools)");
    assert!(
        out.status.success(),
        "{}: {}",
        path.display(),
        text(&out.stderr)
    );
}

#[test]
fn exported_modules_validate_and_hold_no_specialization_constant() {
    // (variant, material, SpecId, the value the pass gives it): `max_layers` (1) under the
    // generic pass, the stack's layer count (8) under the per-material ones.
    for (variant, material, id, value) in [
        ("model=tm2,mode=specialized", "varnished-gold", 8, 2),
        ("model=tm6,mode=specialized-values", "dusty-varnish", 8, 2),
        ("model=tm2,max_layers=8", "five-layers", 1, 8),
    ] {
        let dir = common::scratch_dir(&format!("export-{material}"));
        let out = lamina(
            &[
                "export",
                "--variant",
                variant,
                "--material",
                material,
                "--out",
                "x",
            ],
            &dir,
        );
        assert!(out.status.success(), "{variant}: {}", text(&out.stderr));
        for module in ["forward.vert.spv", "forward.frag.spv"] {
            let path = dir.join("x").join(module);
            spirv_val(&path);
            let bytes = std::fs::read(&path).unwrap();
            let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
            assert_eq!(
                spec_constant_count(&words).unwrap(),
                0,
                "{variant}: {module}"
            );
        }
        let spec: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("x/spec.json")).unwrap()).unwrap();
        assert!(spec["variant"]
            .as_str()
            .unwrap()
            .contains(variant.split(',').next().unwrap()));
        let constants = spec["constants"].as_array().unwrap();
        let constant = constants.iter().find(|c| c["id"] == id).unwrap();
        assert_eq!(constant["bits"], value, "{variant}: SpecId {id}");
    }
}

/// A varying stack under `mode=specialized` draws a stencil mark and one pipeline per class:
/// each is exported to its own directory, frozen to its own constants (the class's layer
/// count, SpecId 8; the mark's layer, SpecId 27).
#[test]
fn a_routed_pass_exports_each_of_its_draws() {
    let dir = common::scratch_dir("export-routed");
    let out = lamina(
        &[
            "export",
            "--variant",
            "mode=specialized",
            "--material",
            "worn-lacquered-copper",
            "--out",
            "x",
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    for (draw, fragment, id, value) in [
        ("mark-layer-1", "classify.frag.spv", 27, 0),
        ("class-01", "forward.frag.spv", 8, 2),
        ("class-00", "forward.frag.spv", 8, 1),
    ] {
        for module in ["forward.vert.spv", fragment] {
            let path = dir.join("x").join(draw).join(module);
            spirv_val(&path);
            let words: Vec<u32> = bytemuck::pod_collect_to_vec(&std::fs::read(&path).unwrap());
            assert_eq!(spec_constant_count(&words).unwrap(), 0, "{draw}: {module}");
        }
        let spec: serde_json::Value = serde_json::from_slice(
            &std::fs::read(dir.join("x").join(draw).join("spec.json")).unwrap(),
        )
        .unwrap();
        assert!(spec["draw"].is_string(), "{draw}: says what it draws");
        let constants = spec["constants"].as_array().unwrap();
        let constant = constants.iter().find(|c| c["id"] == id).unwrap();
        assert_eq!(constant["bits"], value, "{draw}: SpecId {id}");
    }
}

/// On the deferred path the shading kernels are exported: a classified pass's kernel per class
/// and, by tile, the generic kernel of its mixed tiles, each frozen (the work group's width
/// included, SpecId 6); an unclassified pass of several classes is refused by name.
#[test]
fn a_classified_deferred_pass_exports_its_kernel_per_bin() {
    let dir = common::scratch_dir("export-deferred");
    let args = |variant: &'static str, out: &'static str| {
        [
            "export",
            "--variant",
            variant,
            "--material",
            "worn-lacquered-copper",
            "--out",
            out,
        ]
    };
    let out = lamina(
        &args("mode=specialized,path=deferred,classify=tiles", "x"),
        &dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    for (bin, id, value) in [("class-01", 8, 2), ("class-00", 8, 1), ("mixed", 7, 0)] {
        let path = dir.join("x").join(bin).join("deferred_bins.comp.spv");
        spirv_val(&path);
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&std::fs::read(&path).unwrap());
        assert_eq!(spec_constant_count(&words).unwrap(), 0, "{bin}");
        let spec: serde_json::Value = serde_json::from_slice(
            &std::fs::read(dir.join("x").join(bin).join("spec.json")).unwrap(),
        )
        .unwrap();
        let constants = spec["constants"].as_array().unwrap();
        let constant = |id: u32| constants.iter().find(|c| c["id"] == id).unwrap()["bits"].clone();
        assert_eq!(constant(id), value, "{bin}: SpecId {id}");
        assert_eq!(constant(6), 8, "{bin}: the work group's width");
    }
    let refused = lamina(&args("mode=specialized,path=deferred", "y"), &dir);
    assert!(!refused.status.success());
    assert!(
        text(&refused.stderr).contains("classify=pixels"),
        "{}",
        text(&refused.stderr)
    );
    assert!(!dir.join("y").exists());
}

#[test]
fn export_refuses_baked_passes_and_unknown_materials_by_name() {
    let dir = common::scratch_dir("export-refused");
    let baked = lamina(
        &[
            "export",
            "--variant",
            "model=tm2,mode=baked",
            "--material",
            "gold",
            "--out",
            "x",
        ],
        &dir,
    );
    assert!(!baked.status.success());
    assert!(
        text(&baked.stderr).contains("mode=baked"),
        "{}",
        text(&baked.stderr)
    );
    let unknown = lamina(&["export", "--material", "unobtainium", "--out", "x"], &dir);
    assert!(!unknown.status.success());
    assert!(text(&unknown.stderr).contains("unobtainium"));
    assert!(
        !dir.join("x").exists(),
        "nothing is written when the export fails"
    );
}
