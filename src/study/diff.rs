//! `lamina diff OLD NEW`: two sets of results side by side — between commits, drivers or
//! devices. Runs pair by (variant, material). Times are compared as ratios to each run's own
//! `ggx` baseline (milliseconds of different machines or runs do not compare; the ratio within
//! one run does), JIT instruction counts as they are (deterministic: any change is a change of
//! the code that ran): per shaded pixel where both sides have that figure, and the whole draw's.
//! `--fail-above PCT` turns a growth of the whole draw's count — or a run or study it cannot
//! check — into an error, for CI.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

use crate::profile::results::{Results, Run};

use super::dirs::{dirs_holding, read_json};

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
    dirs_holding(path, "results.json")?
        .into_iter()
        .map(|d| named(d.join("results.json"), dir_name(&d)))
        .collect()
}

/// One run present on both sides.
pub struct Change<'a> {
    pub old: &'a Run,
    pub new: &'a Run,
}

impl Change<'_> {
    /// New ratio to the baseline over the old one; `None` when the old one is not positive.
    pub fn time(&self) -> Option<f64> {
        (self.old.ratio_to_baseline > 0.0)
            .then(|| self.new.ratio_to_baseline / self.old.ratio_to_baseline)
    }

    /// New JIT instruction count over the old one, when both were counted and the old one is
    /// not zero.
    pub fn instructions(&self) -> Option<f64> {
        let old = self.old.instructions.filter(|&n| n > 0)?;
        Some(self.new.instructions? as f64 / old as f64)
    }

    /// New JIT instructions per shaded pixel over the old ones, when both sides have them and
    /// the old figure is positive.
    pub fn instructions_per_pixel(&self) -> Option<f64> {
        let old = self.old.instructions_per_pixel.filter(|&n| n > 0.0)?;
        Some(self.new.instructions_per_pixel? / old)
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

/// Two collections of result sets compared: the pairs, and the sets on one side only.
pub struct Comparison<'a> {
    pub pairs: Vec<SetDiff<'a>>,
    pub only_old: Vec<&'a ResultSet>,
    pub only_new: Vec<&'a ResultSet>,
}

/// Pairs the sets by name; two single sets pair whatever their names. Errors when nothing
/// pairs.
pub fn diff<'a>(
    old: &'a [ResultSet],
    new: &'a [ResultSet],
    old_path: &Path,
    new_path: &Path,
) -> Result<Comparison<'a>> {
    if let ([o], [n]) = (old, new) {
        return Ok(Comparison {
            pairs: vec![pair_runs(o, n)],
            only_old: Vec::new(),
            only_new: Vec::new(),
        });
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
    Ok(Comparison {
        pairs,
        only_old: old
            .iter()
            .filter(|o| !new.iter().any(|n| n.name == o.name))
            .collect(),
        only_new: new
            .iter()
            .filter(|n| !old.iter().any(|o| o.name == n.name))
            .collect(),
    })
}

fn percent(x: f64) -> String {
    format!("{:+.1} %", (x - 1.0) * 100.0)
}

fn ratio(x: Option<f64>) -> String {
    x.map_or("–".into(), percent)
}

/// The comparison as text tables, one per pair of sets, then the sets on one side only.
pub fn render(cmp: &Comparison) -> String {
    let mut out = String::new();
    for d in &cmp.pairs {
        let (o, n) = (&d.old.results, &d.new.results);
        if d.old.name == d.new.name {
            let _ = writeln!(out, "== {}", d.new.name);
        } else {
            let _ = writeln!(out, "== {} → {}", d.old.name, d.new.name);
        }
        let _ = writeln!(
            out,
            "old: {} (rev {}, {}x{} {})\nnew: {} (rev {}, {}x{} {})",
            o.device.name,
            o.git_rev,
            o.size[0],
            o.size[1],
            o.scene,
            n.device.name,
            n.git_rev,
            n.size[0],
            n.size[1],
            n.scene
        );
        let _ = writeln!(
            out,
            "{:>8} {:>8} {:>9}  {:>10} {:>10} {:>9}  {:>14} {:>14} {:>9}  variant | material",
            "old ×ggx",
            "new ×ggx",
            "Δ time",
            "old JIT/px",
            "new JIT/px",
            "Δ /px",
            "old JIT instr.",
            "new JIT instr.",
            "Δ instr."
        );
        for c in &d.changes {
            let count = |r: &Run| r.instructions.map_or("–".into(), |n| n.to_string());
            let per_pixel = |r: &Run| {
                r.instructions_per_pixel
                    .map_or("–".into(), |n| format!("{n:.1}"))
            };
            let _ = writeln!(
                out,
                "{:>8.2} {:>8.2} {:>9}  {:>10} {:>10} {:>9}  {:>14} {:>14} {:>9}  {} | {}",
                c.old.ratio_to_baseline,
                c.new.ratio_to_baseline,
                ratio(c.time()),
                per_pixel(c.old),
                per_pixel(c.new),
                ratio(c.instructions_per_pixel()),
                count(c.old),
                count(c.new),
                ratio(c.instructions()),
                c.new.variant.short(),
                c.new.material
            );
        }
        for (side, runs) in [("old", &d.only_old), ("new", &d.only_new)] {
            for r in runs.iter() {
                let _ = writeln!(
                    out,
                    "only in {side}: {} | {}",
                    r.variant.short(),
                    r.material
                );
            }
        }
        out.push('\n');
    }
    for (side, sets) in [("old", &cmp.only_old), ("new", &cmp.only_new)] {
        for set in sets.iter() {
            let _ = writeln!(
                out,
                "only in {side}: study {} ({})",
                set.name,
                set.path.display()
            );
        }
    }
    out
}

/// What fails a `--fail-above percent` gate: every paired run whose JIT instruction count grew
/// by more than `percent` %, and whatever the gate cannot check — a run counted before and not
/// now, a run or a study of the old results missing from the new.
pub fn gate(cmp: &Comparison, percent: f64) -> Vec<String> {
    let mut problems = Vec::new();
    for d in &cmp.pairs {
        for c in &d.changes {
            let name = format!("{} | {}", c.new.variant, c.new.material);
            match (c.old.instructions, c.new.instructions) {
                (Some(a), Some(b)) if b as f64 > a as f64 * (1.0 + percent / 100.0) => {
                    problems.push(format!("{name}: {a} → {b} JIT instructions"));
                }
                (Some(_), None) => problems.push(format!("{name}: counted before, not now")),
                _ => {}
            }
        }
        for r in &d.only_old {
            problems.push(format!(
                "{} | {}: missing from {}",
                r.variant,
                r.material,
                d.new.path.display()
            ));
        }
    }
    for set in &cmp.only_old {
        problems.push(format!("study {}: missing from the new results", set.name));
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::results::DeviceInfo;

    fn run(variant: &str, material: &str, ratio: f64, jit: Option<u64>) -> Run {
        Run {
            variant: variant.parse().unwrap(),
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
            pipeline_cache_hit: None,
            spirv_bytes: 0,
            instructions: jit,
            instructions_total: None,
            instructions_large: None,
            instructions_total_large: None,
            instructions_per_pixel: jit.map(|n| n as f64 / 1000.0),
            instructions_per_pixel_ratio: None,
            executable_stats: None,
            active_layers: None,
            image_error: None,
            reference_noise: None,
            reference_flip_floor: None,
            image_error_vs_fp32: None,
            lighting_error: None,
            model_error: None,
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
                    subgroup_size: None,
                },
                git_rev: name.into(),
                command: String::new(),
                size: [8, 8],
                lp_num_threads: None,
                scene: crate::render::scene::Scene::FullScreen,
                counter: None,
                lighting: None,
                environment: None,
                calibration: None,
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
        let cmp = diff(&old, &new, Path::new("a"), Path::new("b")).unwrap();
        assert_eq!(cmp.pairs.len(), 1);
        let d = &cmp.pairs[0];
        assert_eq!(d.changes.len(), 2);
        assert!((d.changes[0].time().unwrap() - 0.5).abs() < 1e-12);
        assert!((d.changes[0].instructions().unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(d.only_old.len(), 1);
        assert_eq!(d.only_new.len(), 1);
        let text = render(&cmp);
        assert!(text.contains("-50.0 %"), "{text}");
        assert!(text.contains("+5.0 %"), "{text}");
        // Per pixel: 30000.0 → 15000.0 for tm6, 3000.0 → 3150.0 for tm2.
        assert!(text.contains("30000.0    15000.0"), "{text}");
        assert!(
            (d.changes[1].instructions_per_pixel().unwrap() - 1.05).abs() < 1e-12,
            "{text}"
        );
        assert!(
            text.contains("only in old: model=tm2,max_layers=2 | copper"),
            "{text}"
        );
        assert!(
            text.contains("only in new: model=tm2,max_layers=2 | silver"),
            "{text}"
        );
        // tm2 on gold grew by 5 %: a failure at 2 %, not at 10 %; tm2 on copper is missing
        // from the new results at any threshold.
        let at_2 = gate(&cmp, 2.0);
        assert_eq!(at_2.len(), 2, "{at_2:?}");
        assert!(at_2[0].contains("3000000 → 3150000"), "{at_2:?}");
        let at_10 = gate(&cmp, 10.0);
        assert_eq!(at_10.len(), 1, "{at_10:?}");
        assert!(at_10[0].contains("copper: missing from flux"), "{at_10:?}");
    }

    #[test]
    fn lost_counts_and_zero_baselines_are_not_passed_silently() {
        let tm2 = "model=tm2,max_layers=4,fp16=off,tir=none,fgd=karis,g2=height-correlated,ndf=ggx";
        let old = [set("a", vec![run(tm2, "gold", 0.0, Some(0))])];
        let new = [set("b", vec![run(tm2, "gold", 4.0, None)])];
        let cmp = diff(&old, &new, Path::new("a"), Path::new("b")).unwrap();
        let c = &cmp.pairs[0].changes[0];
        assert!(c.time().is_none() && c.instructions().is_none());
        let text = render(&cmp);
        assert!(text.contains("== a → b"), "{text}");
        assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
        let problems = gate(&cmp, 0.0);
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert!(
            problems[0].contains("counted before, not now"),
            "{problems:?}"
        );
    }

    #[test]
    fn sets_pair_by_name_and_nothing_in_common_is_an_error() {
        let old = [set("fp16", vec![]), set("tir", vec![])];
        let new = [set("tir", vec![]), set("growth", vec![])];
        let cmp = diff(&old, &new, Path::new("a"), Path::new("b")).unwrap();
        assert_eq!(cmp.pairs.len(), 1);
        assert_eq!(cmp.pairs[0].new.name, "tir");
        let text = render(&cmp);
        assert!(text.contains("only in old: study fp16"), "{text}");
        assert!(text.contains("only in new: study growth"), "{text}");
        assert_eq!(
            gate(&cmp, 0.0),
            vec!["study fp16: missing from the new results"]
        );
        let new = [set("growth", vec![]), set("g2", vec![])];
        let err = diff(&old, &new, Path::new("a"), Path::new("b"))
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("no study in common with a"), "{err}");
        assert!(err.contains("fp16, tir"), "{err}");
    }
}
