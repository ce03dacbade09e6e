//! `lamina sweep --shard K/N` and `lamina merge`: a suite run whole and in three shards gives
//! the same results up to timing, each shard carries the baselines its points need, a study
//! that measures image error is split by material, and merging refuses what does not belong
//! together, writing nothing.

use std::path::Path;

use serde_json::Value;

use crate::common;

use common::{lamina, text};

const GRID: &str = r#"
name = "grid"
title = "Grid"
materials = ["varnished-gold", "gold"]
size = "32x32"
frames = 2
warmup = 1
[[axis]]
name = "model"
values = ["tm2", "tm6"]
[[axis]]
name = "max_layers"
values = [2, 4]
"#;

const TRUTH: &str = r#"
name = "truth"
materials = ["gold", "varnished-gold", "glazed-ceramic"]
[reference]
cosines = [1.0, 0.5]
paths = 2000
interfaces = ["single", "multiple"]
[reference.random]
count = 2
seed = 3
paths = 1000
"#;

const ERROR: &str = r#"
name = "error"
materials = ["gold", "varnished-gold", "lacquered-copper"]
base = "mode=specialized"
size = "32x32"
frames = 1
warmup = 0
reference_spp = 4
[[axis]]
name = "ibl"
values = ["split-sum", "matched"]
"#;

fn json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

fn run(args: &[&str], dir: &Path) {
    let out = lamina(args, dir);
    assert!(
        out.status.success(),
        "lamina {args:?}\n{}\n{}",
        text(&out.stdout),
        text(&out.stderr)
    );
}

/// What a run records that does not depend on timing: each run's variant, material, shader
/// size and fragment count.
fn layout(results: &Value) -> Vec<(String, String, Value, Value)> {
    results["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["variant"].as_str().unwrap().to_owned(),
                r["material"].as_str().unwrap().to_owned(),
                r["spirv_bytes"].clone(),
                r["fragment_invocations"].clone(),
            )
        })
        .collect()
}

#[test]
fn a_suite_in_three_shards_merges_into_the_whole_run() {
    let dir = common::scratch_dir("shard-suite");
    std::fs::write(dir.join("grid.toml"), GRID).unwrap();
    std::fs::write(dir.join("truth.toml"), TRUTH).unwrap();
    std::fs::write(dir.join("error.toml"), ERROR).unwrap();
    std::fs::write(
        dir.join("suite.toml"),
        "studies = [\"grid.toml\", \"truth.toml\", \"error.toml\"]\n",
    )
    .unwrap();
    run(
        &["--validation", "sweep", "suite.toml", "--out", "whole"],
        &dir,
    );
    for k in 1..=3 {
        let shard = format!("{k}/3");
        let out = format!("s{k}");
        run(
            &[
                "--validation",
                "sweep",
                "suite.toml",
                "--shard",
                &shard,
                "--out",
                &out,
            ],
            &dir,
        );
        // Each shard has a baseline for every material its points shade.
        let results = json(&dir.join(&out).join("grid/results.json"));
        let runs = results["runs"].as_array().unwrap();
        for r in runs {
            let material = &r["material"];
            assert!(
                runs.iter().any(|b| b["material"] == *material
                    && b["variant"].as_str().unwrap().starts_with("model=ggx")),
                "shard {shard}: no ggx baseline for {material}"
            );
        }
    }
    // A study that measures image error is split by material: each material's points, and its
    // references, in one shard.
    let mut seen: Vec<(usize, String)> = Vec::new();
    for k in 1..=3 {
        let results = json(&dir.join(format!("s{k}/error/results.json")));
        for r in results["runs"].as_array().unwrap() {
            let material = r["material"].as_str().unwrap().to_owned();
            assert!(
                !seen.iter().any(|(j, m)| *m == material && *j != k),
                "{material}: in shard {k} and another"
            );
            seen.push((k, material));
        }
    }
    run(&["merge", "s1", "s2", "s3", "--out", "merged"], &dir);
    for study in ["grid", "truth", "error"] {
        let whole = dir.join("whole").join(study);
        let merged = dir.join("merged").join(study);
        let (w, m) = (
            json(&whole.join("study.json")),
            json(&merged.join("study.json")),
        );
        assert_eq!(
            w["points"], m["points"],
            "{study}: the points and their runs"
        );
        assert_eq!(
            w["reference"], m["reference"],
            "{study}: the reference comparisons"
        );
        assert!(m.get("shard").is_none(), "{study}: a merged study is whole");
        let (w, m) = (
            json(&whole.join("results.json")),
            json(&merged.join("results.json")),
        );
        assert_eq!(layout(&w), layout(&m), "{study}: the runs");
        assert_eq!(w["git_rev"], m["git_rev"]);
    }
    let report = std::fs::read_to_string(dir.join("merged/REPORT.md")).unwrap();
    assert!(report.contains("## Grid"), "{report}");
}

#[test]
fn merge_refuses_what_does_not_belong_together_and_writes_nothing() {
    let dir = common::scratch_dir("shard-refusals");
    std::fs::write(dir.join("truth.toml"), TRUTH).unwrap();
    for k in 1..=2 {
        let shard = format!("{k}/2");
        run(
            &[
                "sweep",
                "truth.toml",
                "--shard",
                &shard,
                "--out",
                &format!("s{k}"),
            ],
            &dir,
        );
    }
    run(&["sweep", "truth.toml", "--out", "whole"], &dir);
    let copy = |from: &str, to: &str| {
        let target = dir.join(to);
        std::fs::create_dir_all(&target).unwrap();
        for f in ["results.json", "study.json", "sweep.toml"] {
            std::fs::copy(dir.join(from).join(f), target.join(f)).unwrap();
        }
    };
    copy("s2", "other-rev");
    let path = dir.join("other-rev/results.json");
    let mut results = json(&path);
    results["git_rev"] = Value::from("0123456789ab");
    std::fs::write(&path, serde_json::to_string(&results).unwrap()).unwrap();
    copy("s2", "other-sweep");
    std::fs::write(
        dir.join("other-sweep/sweep.toml"),
        TRUTH.replace("paths = 2000", "paths = 3000"),
    )
    .unwrap();
    for (dirs, expected) in [
        (&["s1", "s1"][..], "given twice"),
        (&["s1"][..], "shard 2/2 is missing"),
        (&["s1", "whole"][..], "not a shard"),
        (&["s1", "other-rev"][..], "revision"),
        (&["s1", "other-sweep"][..], "sweep file"),
    ] {
        let mut args = vec!["merge"];
        args.extend_from_slice(dirs);
        args.extend_from_slice(&["--out", "merged"]);
        let out = lamina(&args, &dir);
        let err = text(&out.stderr);
        assert!(!out.status.success(), "{dirs:?} merged");
        assert!(
            err.contains(expected),
            "{dirs:?}: `{expected}` missing from {err}"
        );
        assert!(
            !dir.join("merged").exists(),
            "{dirs:?}: something was written"
        );
    }
    for bad in ["0/3", "4/3", "1/0", "two"] {
        let out = lamina(&["sweep", "truth.toml", "--shard", bad, "--dry-run"], &dir);
        assert!(!out.status.success(), "--shard {bad} accepted");
        assert!(text(&out.stderr).contains(bad), "{}", text(&out.stderr));
    }
}
