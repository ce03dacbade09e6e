//! `lamina diff OLD NEW`: two sets of results side by side — between commits, drivers or
//! devices. Runs pair by (variant, material). Times are compared as ratios to each run's own
//! `ggx` baseline (milliseconds of different machines or runs do not compare; the ratio within
//! one run does), JIT instruction counts as they are (deterministic: any change is a change of
//! the code that ran). `--fail-above PCT` turns an instruction-count growth into an error, for
//! CI.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

use super::bench::{Results, Run};
use super::report::{read_json, short_variant};

/// One results.json with the name it pairs by (its directory's, for a study).
pub struct ResultSet {
    pub name: String,
    pub path: PathBuf,
    pub results: Results,
}

/// The result sets at `path`: a results.json file, a directory holding one, or a directory
/// whose sub-directories hold one each (a `lamina sweep` output), in name order.
pub fn load(path: &Path) -> Result<Vec<ResultSet>> {
    let named = |file: PathBuf, name: String| -> Result<ResultSet> {
        Ok(ResultSet {
            results: read_json(&file)?,
            path: file,
            name,
        })
    };
    let dir_name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    if path.is_file() {
        let name = path
            .parent()
            .map(dir_name)
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| dir_name(path));
        return Ok(vec![named(path.to_owned(), name)?]);
    }
    if !path.is_dir() {
        return Err(Error::Input {
            path: path.to_owned(),
            message: "no such file or directory (expected a results.json or a directory of \
                      `lamina sweep` results)"
                .into(),
        });
    }
    if path.join("results.json").is_file() {
        return Ok(vec![named(path.join("results.json"), dir_name(path))?]);
    }
    let entries = std::fs::read_dir(path).map_err(|e| Error::Input {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    let mut dirs: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("results.json").is_file())
        .collect();
    if dirs.is_empty() {
        return Err(Error::Input {
            path: path.to_owned(),
            message: "no results.json here or in its sub-directories".into(),
        });
    }
    dirs.sort();
    dirs.into_iter()
        .map(|d| named(d.join("results.json"), dir_name(&d)))
        .collect()
}

/// One run present on both sides.
pub struct Change<'a> {
    pub old: &'a Run,
    pub new: &'a Run,
}

impl Change<'_> {
    /// New ratio to the baseline over the old one.
    pub fn time(&self) -> f64 {
        self.new.ratio_to_baseline / self.old.ratio_to_baseline
    }

    /// New JIT instruction count over the old one, when both were counted.
    pub fn instructions(&self) -> Option<f64> {
        Some(self.new.instructions? as f64 / self.old.instructions? as f64)
    }
}

/// Two result sets compared.
pub struct SetDiff<'a> {
    pub old: &'a ResultSet,
    pub new: &'a ResultSet,
    pub changes: Vec<Change<'a>>,
    pub only_old: Vec<&'a Run>,
    pub only_new: Vec<&'a Run>,
}

fn pair_runs<'a>(old: &'a ResultSet, new: &'a ResultSet) -> SetDiff<'a> {
    let same = |a: &Run, b: &Run| a.variant == b.variant && a.material == b.material;
    let changes = old
        .results
        .runs
        .iter()
        .filter_map(|o| {
            let n = new.results.runs.iter().find(|n| same(o, n))?;
            Some(Change { old: o, new: n })
        })
        .collect();
    SetDiff {
        old,
        new,
        changes,
        only_old: old
            .results
            .runs
            .iter()
            .filter(|o| !new.results.runs.iter().any(|n| same(o, n)))
            .collect(),
        only_new: new
            .results
            .runs
            .iter()
            .filter(|n| !old.results.runs.iter().any(|o| same(o, n)))
            .collect(),
    }
}

/// Pairs the sets by name; two single sets pair whatever their names. Errors when nothing
/// pairs.
pub fn diff<'a>(
    old: &'a [ResultSet],
    new: &'a [ResultSet],
    old_path: &Path,
    new_path: &Path,
) -> Result<Vec<SetDiff<'a>>> {
    if let ([o], [n]) = (old, new) {
        return Ok(vec![pair_runs(o, n)]);
    }
    let pairs: Vec<SetDiff> = old
        .iter()
        .filter_map(|o| {
            new.iter()
                .find(|n| n.name == o.name)
                .map(|n| pair_runs(o, n))
        })
        .collect();
    if pairs.is_empty() {
        let names = |sets: &[ResultSet]| {
            sets.iter()
                .map(|s| s.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        return Err(Error::Input {
            path: new_path.to_owned(),
            message: format!(
                "no study in common with {}: it has {}; this has {}",
                old_path.display(),
                names(old),
                names(new)
            ),
        });
    }
    Ok(pairs)
}

fn percent(x: f64) -> String {
    format!("{:+.1} %", (x - 1.0) * 100.0)
}

/// The comparison as text tables, one per pair of sets.
pub fn render(diffs: &[SetDiff]) -> String {
    let mut out = String::new();
    for d in diffs {
        let (o, n) = (&d.old.results, &d.new.results);
        let _ = writeln!(out, "== {}", d.new.name);
        let _ = writeln!(
            out,
            "old: {} (rev {}, {}x{})\nnew: {} (rev {}, {}x{})",
            o.device.name,
            o.git_rev,
            o.size[0],
            o.size[1],
            n.device.name,
            n.git_rev,
            n.size[0],
            n.size[1]
        );
        let _ = writeln!(
            out,
            "{:>8} {:>8} {:>9}  {:>14} {:>14} {:>9}  variant | material",
            "old ×ggx", "new ×ggx", "Δ time", "old JIT instr.", "new JIT instr.", "Δ instr."
        );
        for c in &d.changes {
            let count = |r: &Run| r.instructions.map_or("–".into(), |n| n.to_string());
            let _ = writeln!(
                out,
                "{:>8.2} {:>8.2} {:>9}  {:>14} {:>14} {:>9}  {} | {}",
                c.old.ratio_to_baseline,
                c.new.ratio_to_baseline,
                percent(c.time()),
                count(c.old),
                count(c.new),
                c.instructions().map_or("–".into(), percent),
                short_variant(&c.new.variant),
                c.new.material
            );
        }
        for (side, runs) in [("old", &d.only_old), ("new", &d.only_new)] {
            for r in runs.iter() {
                let _ = writeln!(
                    out,
                    "only in {side}: {} | {}",
                    short_variant(&r.variant),
                    r.material
                );
            }
        }
        out.push('\n');
    }
    out
}

/// The paired runs whose JIT instruction count grew by more than `percent` %.
pub fn regressions<'a>(diffs: &'a [SetDiff], percent: f64) -> Vec<&'a Change<'a>> {
    diffs
        .iter()
        .flat_map(|d| d.changes.iter())
        .filter(|c| c.instructions().is_some_and(|x| x > 1.0 + percent / 100.0))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::bench::DeviceInfo;

    fn run(variant: &str, material: &str, ratio: f64, jit: Option<u64>) -> Run {
        Run {
            variant: variant.into(),
            material: material.into(),
            frames: 3,
            min_ms: ratio,
            median_ms: ratio,
            mean_ms: ratio,
            max_ms: ratio,
            stdev_ms: 0.0,
            ratio_to_baseline: ratio,
            fragment_invocations: None,
            pipeline_ms: 0.0,
            spirv_bytes: 0,
            instructions: jit,
            instructions_total: None,
            executable_stats: None,
        }
    }

    fn set(name: &str, runs: Vec<Run>) -> ResultSet {
        ResultSet {
            name: name.into(),
            path: PathBuf::from(name),
            results: Results {
                device: DeviceInfo {
                    name: "llvmpipe".into(),
                    driver: "Mesa".into(),
                    api_version: "1.3".into(),
                    vendor_id: 0x10005,
                },
                git_rev: name.into(),
                command: String::new(),
                size: [8, 8],
                lp_num_threads: None,
                runs,
            },
        }
    }

    #[test]
    fn runs_pair_by_variant_and_material_and_growth_is_a_regression() {
        let tm6 = "model=tm6,max_layers=2,fp16=off,tir=none,fgd=karis,g2=height-correlated,ndf=ggx";
        let tm2 = "model=tm2,max_layers=2,fp16=off,tir=none,fgd=karis,g2=height-correlated,ndf=ggx";
        let old = [set(
            "flux",
            vec![
                run(tm6, "gold", 20.0, Some(30_000_000)),
                run(tm2, "gold", 4.0, Some(3_000_000)),
                run(tm2, "copper", 4.0, Some(3_000_000)),
            ],
        )];
        let new = [set(
            "flux",
            vec![
                run(tm6, "gold", 10.0, Some(15_000_000)),
                run(tm2, "gold", 4.4, Some(3_150_000)),
                run(tm2, "silver", 4.0, None),
            ],
        )];
        let diffs = diff(&old, &new, Path::new("a"), Path::new("b")).unwrap();
        assert_eq!(diffs.len(), 1);
        let d = &diffs[0];
        assert_eq!(d.changes.len(), 2);
        assert!((d.changes[0].time() - 0.5).abs() < 1e-12);
        assert!((d.changes[0].instructions().unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(d.only_old.len(), 1);
        assert_eq!(d.only_new.len(), 1);
        let text = render(&diffs);
        assert!(text.contains("-50.0 %"), "{text}");
        assert!(text.contains("+5.0 %"), "{text}");
        assert!(
            text.contains("only in old: model=tm2,max_layers=2 | copper"),
            "{text}"
        );
        assert!(
            text.contains("only in new: model=tm2,max_layers=2 | silver"),
            "{text}"
        );
        // tm2 on gold grew by 5 %: a regression above 2 %, not above 10 %.
        assert_eq!(regressions(&diffs, 2.0).len(), 1);
        assert!(regressions(&diffs, 10.0).is_empty());
    }

    #[test]
    fn sets_pair_by_name_and_nothing_in_common_is_an_error() {
        let old = [set("fp16", vec![]), set("tir", vec![])];
        let new = [set("tir", vec![]), set("growth", vec![])];
        let diffs = diff(&old, &new, Path::new("a"), Path::new("b")).unwrap();
        assert_eq!(diffs.len(), 1);
        assert_eq!(diffs[0].new.name, "tir");
        let new = [set("growth", vec![]), set("g2", vec![])];
        let err = diff(&old, &new, Path::new("a"), Path::new("b"))
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("no study in common with a"), "{err}");
        assert!(err.contains("fp16, tir"), "{err}");
    }
}
