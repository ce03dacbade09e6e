//! What a study's directory holds besides `results.json`: `study.json`, the study's metadata —
//! its title and description, its axes and each run's coordinates on them, the talk's figures
//! and the targets it compares with, and the results of its comparisons that are not runs (the
//! baked tables' errors, the model against the stochastic reference). Read by `lamina report`.

use serde::{Deserialize, Serialize};

use crate::reference::compare::MaterialReference;
use crate::variant::VariantKey;

use super::shard::ShardMeta;
use super::{Published, Study, Target};

/// A study's `study.json`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct StudyMeta {
    pub name: String,
    pub title: String,
    pub description: String,
    pub sweep_file: String,
    pub axes: Vec<String>,
    /// `runs[run]` of results.json has these axis values; runs not listed are baselines.
    pub points: Vec<PointMeta>,
    pub skipped: Vec<String>,
    pub published: Vec<Published>,
    pub fit: bool,
    /// The smaller counted size: that of the whole-draw counts.
    pub counter_size: Option<[u32; 2]>,
    /// Both counted sizes, the smaller first; absent from studies counted at one size.
    #[serde(default)]
    pub counter_sizes: Option<[[u32; 2]; 2]>,
    #[serde(default)]
    pub targets: Vec<Target>,
    #[serde(default)]
    pub bake_error: Vec<MaterialBakeError>,
    /// A `[reference]` study's comparisons, one per material.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reference: Vec<MaterialReference>,
    /// A shard's place in the whole study (`lamina sweep --shard`); absent from a whole run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<ShardMeta>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct PointMeta {
    pub run: usize,
    pub coords: Vec<String>,
}

/// One baked material's errors per table size, as `study.json` keeps them.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct MaterialBakeError {
    pub material: String,
    pub variant: VariantKey,
    pub image_size: u32,
    pub rows: Vec<BakeErrorRow>,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct BakeErrorRow {
    pub size: u32,
    pub lobe_error: f64,
    pub image_error: f64,
}

impl StudyMeta {
    /// The metadata of `study`, whose runs follow its plan (`counted`: its instructions were
    /// counted at its counter sizes), with its comparisons that are not runs.
    pub fn of(
        study: &Study,
        counted: bool,
        bake_error: Vec<MaterialBakeError>,
        reference: Vec<MaterialReference>,
    ) -> Self {
        let baselines = study.plan.added_baselines();
        let counted = study.counter.filter(|_| counted);
        StudyMeta {
            name: study.name.clone(),
            title: study.title.clone(),
            description: study.description.clone(),
            sweep_file: study.file.display().to_string(),
            axes: study.axes.clone(),
            points: study
                .points
                .iter()
                .enumerate()
                .map(|(i, p)| PointMeta {
                    run: baselines + i,
                    coords: p.coords.clone(),
                })
                .collect(),
            skipped: study.skipped.clone(),
            published: study.published.clone(),
            fit: study.fit,
            counter_size: counted.map(|c| [c.small.width, c.small.height]),
            counter_sizes: counted.map(|c| c.both().map(|s| [s.width, s.height])),
            targets: study.targets.clone(),
            bake_error,
            reference,
            shard: study.shard.clone(),
        }
    }
}
