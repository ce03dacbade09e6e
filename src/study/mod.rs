//! Studies: the documents built on `crate::profile`'s measurements. A sweep file ([`file`])
//! names a study or a suite of them; [`expand`] checks it and expands each study into its
//! cases ([`Study`]); [`run`] runs the studies' phases (timing, image errors, the baked-table
//! and reference comparisons, the instruction counts of a whole suite at once) and writes each
//! study's directory ([`write`]: results, metadata, [`charts`]); [`dirs`] reads such
//! directories back for the [`report`] and for [`diff`].
//!
//! Nothing in `profile/` imports from here: a measurement does not know the document that
//! asked for it.

pub mod charts;
pub mod diff;
pub mod dirs;
pub mod expand;
pub mod file;
pub mod meta;
mod reference;
pub mod report;
pub mod run;
pub mod shard;
pub mod write;

use std::path::{Path, PathBuf};

use crate::profile::counter::CounterSizes;
use crate::profile::plan::{Case, Plan};
use crate::render::lights::Lighting;
use crate::render::scene::Scene;

pub use expand::load;
pub use file::{Published, Target};

/// A study, checked and expanded: the cases in run order and each case's axis coordinates.
#[derive(Clone, Debug)]
pub struct Study {
    pub name: String,
    pub title: String,
    pub description: String,
    pub file: PathBuf,
    pub source_text: String,
    pub scene: Scene,
    pub lighting: Lighting,
    /// `env`: the environment map that lights this study instead of the suite's.
    pub env: Option<PathBuf>,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub warmup: u32,
    /// The counted resolutions when instruction counting is on.
    pub counter: Option<CounterSizes>,
    /// The resolutions the file (or its suite) names, used by `--counter instructions` when
    /// the file does not count by itself.
    pub counter_sizes: CounterSizes,
    pub axes: Vec<String>,
    /// The study's cases with their axis coordinates, in run order after the baselines.
    pub points: Vec<Point>,
    /// The cases as they run: the `ggx` baselines the points lack, then the points' cases.
    pub plan: Plan,
    /// Combinations left out because the stack does not fit the variant's `max_layers`.
    pub skipped: Vec<String>,
    pub published: Vec<Published>,
    pub fit: bool,
    /// `material` resolved to the material's name.
    pub targets: Vec<Target>,
    /// Table sizes and image side of the baked-table error study.
    pub bake_error: Option<(Vec<u32>, u32)>,
    /// A `[reference]` study (then `points` is empty: nothing is timed).
    pub reference: Option<ReferenceStudy>,
    /// `reference_spp`: image errors against reference images of this many samples per lobe.
    pub image_error_spp: Option<u32>,
    /// `--shard K/N`: the share of the whole study this one runs ([`shard::apply`]).
    pub shard: Option<shard::ShardMeta>,
}

impl Study {
    /// Counts instructions too (`--counter instructions`): at the study's own counter sizes
    /// when it counts already, else at [`CounterSizes::DEFAULT`].
    pub fn count_instructions(&mut self) {
        if self.reference.is_none() {
            self.counter.get_or_insert(self.counter_sizes);
        }
    }
}

/// One case of a study with its value on every swept axis (in axis order).
#[derive(Clone, Debug)]
pub struct Point {
    pub case: Case,
    pub coords: Vec<String>,
}

/// A `[reference]` study, checked: the materials (each with its variant: model and masking
/// form), the view cosines, the paths, the seed and the interface modes.
#[derive(Clone, Debug)]
pub struct ReferenceStudy {
    pub cases: Vec<Case>,
    pub cosines: Vec<f64>,
    pub paths: u64,
    pub seed: u64,
    /// The reference's interface modes, each a truth of its own.
    pub interfaces: Vec<crate::variant::Interfaces>,
    /// Random stacks within the presets' ranges, each in its own model, and their paths.
    pub random: Vec<Case>,
    pub random_paths: u64,
}

/// Where a study's files go under `out`: `out` itself for a lone study, `out/NAME` for each
/// study of a suite.
pub fn output_dir(out: &Path, study: &Study, suite: bool) -> PathBuf {
    if suite {
        out.join(&study.name)
    } else {
        out.to_owned()
    }
}
