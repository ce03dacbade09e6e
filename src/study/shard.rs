//! Sweeps over many machines: `lamina sweep FILE --shard K/N` runs shard K of N of every study
//! — a deterministic share of its points (every N-th from the K-th, so that each shard gets
//! some of every axis; in a study that measures image error, every point of every N-th
//! material, whose references are the costly part) with the `ggx` baselines those points
//! need, and of a reference study's materials — and writes a complete results directory that
//! says which share it holds ([`ShardMeta`] in `study.json`). `lamina merge` ([`merge`])
//! joins the N directories into the whole study's, as one run of it would have written it (the
//! runs' timings are each shard's own). Any scheduler runs the shards: a CI matrix, a Slurm
//! array, Kubernetes indexed jobs (README, "Sweeps over many machines").

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::profile::image_error::{error_map_path, FP32_MAPS};
use crate::profile::plan::Plan;
use crate::profile::results::Results;

use super::dirs::StudyDir;
use super::meta::{PointMeta, StudyMeta};
use super::Study;

/// Most shards a sweep is split into.
pub const MAX_SHARDS: usize = 4096;

/// Shard `index` (1-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let form = || format!("`{s}`: give K/N, shard K of N shards (1 ≤ K ≤ N), e.g. 2/3");
        let (k, n) = s.split_once('/').ok_or_else(form)?;
        let k: usize = k.trim().parse().map_err(|_| form())?;
        let n: usize = n.trim().parse().map_err(|_| form())?;
        if n == 0 || n > MAX_SHARDS {
            return Err(format!(
                "`{s}`: {n} shards; allowed: 1 to {MAX_SHARDS} shards"
            ));
        }
        if k == 0 || k > n {
            return Err(format!(
                "`{s}`: shard {k} of {n}; allowed: shards 1 to {n} (they count from 1)"
            ));
        }
        Ok(Self { index: k, count: n })
    }
}

impl Shard {
    /// Whether this shard runs item `i` of a study's list.
    pub fn takes(self, i: usize) -> bool {
        i % self.count == self.index - 1
    }
}

/// What a shard's `study.json` records: which shard it is, and where what it ran sits in the
/// whole study — its points' indices among the study's points, its reference comparisons'
/// among the study's (truth by truth: the named materials, then the random stacks).
#[derive(Clone, Debug, PartialEq, Eq, Deserialize, Serialize)]
pub struct ShardMeta {
    pub index: usize,
    pub count: usize,
    pub points: Vec<usize>,
    pub total_points: usize,
    pub reference: Vec<usize>,
    pub total_reference: usize,
}

/// `study` reduced to its share under `shard`: its points, the baselines they need, its
/// reference materials and random stacks.
pub fn apply(study: &mut Study, shard: Shard) {
    let total_points = study.points.len();
    let points: Vec<usize> = if study.image_error_spp.is_some() {
        // A study that measures image error renders each material's references once for all
        // its points: its shards take whole materials, every N-th, so that no two shards
        // render the same references.
        let materials = point_materials(study);
        (0..total_points)
            .filter(|&i| shard.takes(materials[i]))
            .collect()
    } else {
        (0..total_points).filter(|&i| shard.takes(i)).collect()
    };
    study.points = points.iter().map(|&i| study.points[i].clone()).collect();
    study.plan = Plan::new(study.points.iter().map(|p| p.case.clone()).collect());
    let (mut reference, mut total_reference) = (Vec::new(), 0);
    if let Some(r) = &mut study.reference {
        let named = r.cases.len();
        let per_truth = named + r.random.len();
        let kept: Vec<usize> = (0..per_truth).filter(|&j| shard.takes(j)).collect();
        r.cases = kept
            .iter()
            .filter(|&&j| j < named)
            .map(|&j| r.cases[j].clone())
            .collect();
        r.random = kept
            .iter()
            .filter(|&&j| j >= named)
            .map(|&j| r.random[j - named].clone())
            .collect();
        for t in 0..r.interfaces.len() {
            reference.extend(kept.iter().map(|&j| t * per_truth + j));
        }
        total_reference = per_truth * r.interfaces.len();
    }
    study.shard = Some(ShardMeta {
        index: shard.index,
        count: shard.count,
        points,
        total_points,
        reference,
        total_reference,
    });
}

/// Each point's material: the index of its stack's name among the study's, in the order they
/// first appear.
fn point_materials(study: &Study) -> Vec<usize> {
    let mut names: Vec<&str> = Vec::new();
    study
        .points
        .iter()
        .map(|p| {
            let name = p.case.stack.name.as_str();
            names.iter().position(|&n| n == name).unwrap_or_else(|| {
                names.push(name);
                names.len() - 1
            })
        })
        .collect()
}

fn refuse(path: &Path, message: String) -> Error {
    Error::Input {
        path: path.to_owned(),
        message,
    }
}

/// One study merged from its shards: its results, its metadata, the sweep file as run, and
/// each merged run's error maps (`error-maps/` files of the shard that ran it: the source
/// path and the path in the merged study's directory).
pub struct Merged {
    pub name: String,
    pub results: Results,
    pub meta: StudyMeta,
    pub sweep_text: String,
    pub error_maps: Vec<(PathBuf, String)>,
}

/// Joins the shard directories `dirs` (every study of a sharded sweep, each shard's) into
/// one study each, in the order the studies first appear. Refuses by name: a directory that
/// is not a shard, shards of different revisions, devices, sweep files or shard counts, a
/// shard given twice, a missing shard.
pub fn merge(dirs: Vec<StudyDir>) -> Result<Vec<Merged>> {
    let mut studies: Vec<(String, Vec<StudyDir>)> = Vec::new();
    for d in dirs {
        if d.meta.shard.is_none() {
            return Err(refuse(
                &d.dir.join("study.json"),
                "not a shard: it was not run with `lamina sweep --shard K/N`".into(),
            ));
        }
        match studies.iter_mut().find(|(name, _)| *name == d.meta.name) {
            Some((_, shards)) => shards.push(d),
            None => studies.push((d.meta.name.clone(), vec![d])),
        }
    }
    studies
        .into_iter()
        .map(|(name, shards)| merge_study(name, shards))
        .collect()
}

fn merge_study(name: String, shards: Vec<StudyDir>) -> Result<Merged> {
    let first = &shards[0];
    let first_shard = first.meta.shard.as_ref().expect("checked by merge");
    let sweep_text = read_sweep(first)?;
    let mut by_index: BTreeMap<usize, &StudyDir> = BTreeMap::new();
    for d in &shards {
        let s = d.meta.shard.as_ref().expect("checked by merge");
        let here = d.dir.join("study.json");
        let differs = |what: &str, a: &str, b: &str| {
            refuse(
                &here,
                format!(
                    "study `{name}`: {what} `{b}` differs from `{a}` of {}; merge shards of \
                     one sweep only",
                    first.dir.display()
                ),
            )
        };
        if d.results.git_rev != first.results.git_rev {
            return Err(differs(
                "revision",
                &first.results.git_rev,
                &d.results.git_rev,
            ));
        }
        let device = |r: &Results| format!("{} ({})", r.device.name, r.device.driver);
        if device(&d.results) != device(&first.results) {
            return Err(differs(
                "device",
                &device(&first.results),
                &device(&d.results),
            ));
        }
        if read_sweep(d)? != sweep_text || d.meta.sweep_file != first.meta.sweep_file {
            return Err(differs(
                "sweep file",
                &first.meta.sweep_file,
                &d.meta.sweep_file,
            ));
        }
        if s.count != first_shard.count {
            return Err(differs(
                "shard count",
                &first_shard.count.to_string(),
                &s.count.to_string(),
            ));
        }
        if let Some(other) = by_index.insert(s.index, d) {
            return Err(refuse(
                &here,
                format!(
                    "study `{name}`: shard {}/{} given twice (also {})",
                    s.index,
                    s.count,
                    other.dir.display()
                ),
            ));
        }
    }
    if let Some(missing) = (1..=first_shard.count).find(|k| !by_index.contains_key(k)) {
        return Err(refuse(
            &first.dir,
            format!(
                "study `{name}`: shard {missing}/{} is missing; give every shard's directory",
                first_shard.count
            ),
        ));
    }
    let ordered: Vec<&StudyDir> = by_index.into_values().collect();
    Ok(join(name, sweep_text, &ordered))
}

fn read_sweep(d: &StudyDir) -> Result<String> {
    let path = d.dir.join("sweep.toml");
    std::fs::read_to_string(&path).map_err(|e| refuse(&path, e.to_string()))
}

/// The shards (complete, in shard order) joined as the whole study's run lays them out: each
/// material's baseline, then every point in the whole study's order.
fn join(name: String, sweep_text: String, shards: &[&StudyDir]) -> Merged {
    let first = shards[0];
    let total = first.meta.shard.as_ref().map_or(0, |s| s.total_points);
    let mut points: Vec<Option<(PointMeta, &StudyDir)>> = vec![None; total];
    for d in shards {
        let s = d.meta.shard.as_ref().expect("a shard");
        for (p, &whole) in d.meta.points.iter().zip(&s.points) {
            points[whole] = Some((p.clone(), d));
        }
    }
    let points: Vec<(PointMeta, &StudyDir)> = points.into_iter().flatten().collect();
    // Each material's baseline as the whole run has it: from the shard that ran the material's
    // first point (where it was planned from that point, as the whole plan's was), in the
    // order the materials first appear.
    let mut runs: Vec<crate::profile::results::Run> = Vec::new();
    let mut maps = Vec::new();
    fn run_of<'a>((p, d): &(PointMeta, &'a StudyDir)) -> &'a crate::profile::results::Run {
        &d.results.runs[p.run]
    }
    for point in &points {
        let d = point.1;
        let material = &run_of(point).material;
        // A study whose points include a material's ggx run has no baseline added for it.
        let given = points
            .iter()
            .any(|q| run_of(q).material == *material && run_of(q).is_baseline());
        if given || runs.iter().any(|b| b.material == *material) {
            continue;
        }
        let baseline = d.results.runs.iter().enumerate().find(|(r, run)| {
            run.is_baseline()
                && run.material == *material
                && !d.meta.points.iter().any(|q| q.run == *r)
        });
        if let Some((r, run)) = baseline {
            maps.push((d.dir.clone(), r, runs.len()));
            runs.push(run.clone());
        }
    }
    let mut point_meta = Vec::with_capacity(points.len());
    for (p, d) in points {
        maps.push((d.dir.clone(), p.run, runs.len()));
        point_meta.push(PointMeta {
            run: runs.len(),
            coords: p.coords,
        });
        runs.push(d.results.runs[p.run].clone());
    }
    let meta = merged_meta(shards, point_meta);
    let mut results = first.results.clone();
    results.runs = runs;
    results.command = shards
        .iter()
        .map(|d| d.results.command.as_str())
        .collect::<Vec<_>>()
        .join(" ; ");
    // A run's error map, and its map against fp32 where it has one.
    let error_maps = maps
        .into_iter()
        .flat_map(|(dir, from, to)| {
            [(from, to), (FP32_MAPS + from, FP32_MAPS + to)]
                .map(|(a, b)| (dir.join(error_map_path(a)), error_map_path(b)))
        })
        .filter(|(source, _)| source.is_file())
        .collect();
    Merged {
        name,
        results,
        meta,
        sweep_text,
        error_maps,
    }
}

/// The whole study's metadata from its shards' (complete, in shard order), its points
/// `points`: the reference comparisons in the whole study's order, the skipped combinations
/// and the baked-table errors once each.
fn merged_meta(shards: &[&StudyDir], points: Vec<PointMeta>) -> StudyMeta {
    let first = shards[0];
    let total_reference = first.meta.shard.as_ref().map_or(0, |s| s.total_reference);
    let mut reference = vec![None; total_reference];
    for d in shards {
        let s = d.meta.shard.as_ref().expect("a shard");
        for (r, &whole) in d.meta.reference.iter().zip(&s.reference) {
            reference[whole] = Some(r.clone());
        }
    }
    let mut meta = first.meta.clone();
    meta.points = points;
    meta.reference = reference.into_iter().flatten().collect();
    meta.skipped = Vec::new();
    meta.bake_error = Vec::new();
    for d in shards {
        for s in &d.meta.skipped {
            if !meta.skipped.contains(s) {
                meta.skipped.push(s.clone());
            }
        }
        for b in &d.meta.bake_error {
            if !meta.bake_error.iter().any(|m| m.material == b.material) {
                meta.bake_error.push(b.clone());
            }
        }
    }
    meta.shard = None;
    meta
}

/// Joins the shard directories under `roots` (each a sharded sweep's output: a study's
/// directory or a suite's parent) and writes the merged studies under `out` — a lone study's
/// files into `out`, a suite's each into `out/NAME` — then `out/REPORT.md`. Everything is read
/// and checked before anything is written. Returns the merged directories.
pub fn merge_dirs(roots: &[PathBuf], out: &Path) -> Result<Vec<PathBuf>> {
    let suite = roots.iter().any(|r| !r.join("study.json").is_file());
    let merged = merge(super::dirs::collect(roots)?)?;
    let mut written = Vec::with_capacity(merged.len());
    for m in &merged {
        let dir = if suite {
            out.join(&m.name)
        } else {
            out.to_owned()
        };
        super::write::write(&dir, &m.sweep_text, &m.results, &m.meta, &[])?;
        for (source, path) in &m.error_maps {
            let target = dir.join(path);
            let bytes = std::fs::read(source).map_err(|e| refuse(source, e.to_string()))?;
            if let Some(parent) = target.parent() {
                std::fs::create_dir_all(parent).map_err(|e| Error::Output {
                    path: parent.to_owned(),
                    message: e.to_string(),
                })?;
            }
            crate::imageio::write_file_atomically(&target, bytes)?;
        }
        written.push(dir);
    }
    super::report::write(
        std::slice::from_ref(&out.to_path_buf()),
        &out.join("REPORT.md"),
    )?;
    Ok(written)
}
