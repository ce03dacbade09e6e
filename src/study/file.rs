//! The sweep file format (`profiling/sweeps/*.toml`), as read: a study is a set of variants ×
//! materials measured in one interleaved bench run; a suite lists studies and overrides their
//! resolution and frame counts (`reproduce.toml`).
//!
//! ```toml
//! name = "fp16"                       # output sub-directory and report heading
//! title = "Half precision"
//! description = "…"                   # one paragraph, copied into the report
//! materials = ["varnished-gold"]      # presets or files (relative to this file)
//! base = "model=tm2"                  # variant axes every case starts from
//! scene = "fullscreen"                # what the draw shades: fullscreen (default) or sphere
//! size = "320x180"
//! frames = 10
//! warmup = 2
//! counter = "instructions"            # optional: also count instructions under callgrind
//! counter_sizes = ["48x48", "96x96"]  # the two counted resolutions (per pixel: the difference)
//! fit = "linear"                      # optional: report a least-squares line along axis 1
//! tile_width = 128                    # optional: a suite's sizes apply if their width is a multiple
//! own_counter_sizes = true            # optional: a suite's counter_sizes do not apply
//! reference_spp = 64                  # optional: each run's image against the reference image
//!                                     #   (`render::reference`, this many samples per lobe)
//! [reference]                         # optional, alone: each material's model against the
//! cosines = [1.0, 0.7, 0.4, 0.15]     #   stochastic reference (`reference::compare`), no
//! paths = 200000                      #   timing; paths per channel and view cosine
//! [[axis]]                            # cartesian product, first axis on the charts' x axis
//! name = "max_layers"
//! values = [2, 4, 8, 16]
//! [[axis]]
//! name = "fp16"
//! values = ["off", "on"]
//! [[published]]                       # the talk's figures this study is compared with
//! label = "2-flux"
//! match = "model=tm2"
//! ms = 1.433
//! ```
//!
//! Axes are the variant axes of DESIGN.md §4 plus `active_layers` (the material resized with
//! `Stack::with_active_layers`), `material` (an alternative to `materials`) and `variant`
//! (key fragments). `study::expand` checks a file completely — axes, values, sizes,
//! materials, the availability of each variant — before any GPU work.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    pub name: Option<String>,
    pub title: Option<String>,
    pub description: Option<String>,
    /// A suite: sweep files (relative to this one) run in order, with this file's `scene`,
    /// `size`, `frames`, `warmup`, `counter`, `counter_sizes` and `lights` overriding theirs.
    pub studies: Option<Vec<String>>,
    pub materials: Option<Vec<String>>,
    pub base: Option<String>,
    pub scene: Option<String>,
    /// A lighting file (relative to this one) or preset (`render::lights`): the environment's
    /// scale and the analytic lights. Absent: the environment alone.
    pub lights: Option<String>,
    /// An equirectangular OpenEXR environment map (relative to this file) that lights this
    /// study instead of the suite's (`--env`); its instructions are counted under the suite's,
    /// which costs the same.
    pub env: Option<String>,
    pub size: Option<String>,
    pub frames: Option<u32>,
    pub warmup: Option<u32>,
    pub counter: Option<String>,
    pub counter_sizes: Option<Vec<String>>,
    /// The period across the frame, in pixels, of this study's materials (masks in screen
    /// coordinates: the divergence study), so that every row holds whole periods. A suite's
    /// `size` or `counter_sizes` whose width is not a multiple of it do not apply to this
    /// study, whose own do; its own must be multiples.
    pub tile_width: Option<u32>,
    /// The study counts at its own `counter_sizes` whatever a suite says: its materials' maps
    /// are in texture coordinates, which the full-screen grid stretches over the frame, so a
    /// patch spans as many pixels as the frame is wide over its scale, and where the patches
    /// are a few pixels wide nearly every block of pixels mixes two stacks; the per-pixel
    /// count between two small frames then measures those boundaries more than the stacks.
    #[serde(default)]
    pub own_counter_sizes: bool,
    /// Replaced by `counter_sizes`; read only to say so.
    pub counter_size: Option<toml::Value>,
    pub fit: Option<String>,
    #[serde(default, rename = "axis")]
    pub axes: Vec<AxisSpec>,
    #[serde(default)]
    pub published: Vec<Published>,
    #[serde(default, rename = "target")]
    pub targets: Vec<Target>,
    pub bake_error: Option<BakeErrorSpec>,
    pub reference: Option<ReferenceSpec>,
    /// Each run's image error against the reference image of its material and scene
    /// (`profile::image_error`), the reference at this many samples per lobe and pixel.
    pub reference_spp: Option<u32>,
}

/// `[reference]`: the study compares each material's model with the stochastic reference
/// (`reference::compare`) at these view cosines instead of timing anything.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    pub cosines: Vec<f64>,
    /// Paths per channel and view cosine.
    pub paths: u64,
    pub seed: Option<u64>,
    /// The truths to compare with: the reference's interface modes (default `["single"]`).
    pub interfaces: Option<Vec<String>>,
    /// Random stacks within the presets' ranges, compared beside the materials.
    pub random: Option<RandomSpec>,
}

/// `[reference.random]`: how many random stacks (`material::random::preset_like_stack`), from
/// which seed, with how many paths per channel and view cosine (the study's by default).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RandomSpec {
    pub count: usize,
    pub seed: u64,
    pub paths: Option<u64>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AxisSpec {
    pub name: String,
    pub values: Vec<toml::Value>,
}

/// One published figure and the runs it is compared with.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Published {
    pub label: String,
    /// Axis values a run must have (`model=tm6,fp16=on`); the first matching run is used.
    #[serde(rename = "match")]
    pub matches: String,
    pub ms: f64,
    /// Where the figure comes from, printed beside it.
    pub source: Option<String>,
}

/// A ratio a study's runs are held to (`[[target]]`): the run matching `match` on `material`
/// over the run matching `against` on the same material (its ggx baseline when absent), in
/// JIT instructions per shaded pixel where counted at two sizes, else the whole draw's, else
/// time. The report says met, or missed and by how much (a ratio of times within the stated
/// `tolerance`); nothing fails on it.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Target {
    pub label: String,
    #[serde(rename = "match")]
    pub matches: String,
    pub against: Option<String>,
    /// A preset or material file in the sweep file; the material's name once loaded.
    pub material: String,
    /// The material of the `against` run, where it is another (the divergence study: a mask
    /// against the coherent stack of its mean layer count); as `material`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub against_material: Option<String>,
    pub max: f64,
    /// How far a ratio of median times may exceed `max` and still meet it, as a fraction: a
    /// timing's noise, which the study states (a ratio of times gets no verdict without it).
    /// Counts are deterministic and ignore it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
}

/// `[bake_error]`: each baked material's table against the per-pixel model
/// (`render::baked::error_study`) at these table sizes, the images compared at `image_size`².
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BakeErrorSpec {
    pub sizes: Vec<u32>,
    pub image_size: Option<u32>,
}

/// Reads and parses the sweep file `file` (its own fields only: `study::expand` checks them).
pub fn read(file: &Path) -> Result<SweepFile> {
    let text = std::fs::read_to_string(file).map_err(|e| Error::Input {
        path: file.to_owned(),
        message: format!("cannot read the sweep file: {e}"),
    })?;
    let sweep: SweepFile = toml::from_str(&text).map_err(|e| Error::Input {
        path: file.to_owned(),
        message: e.to_string(),
    })?;
    if sweep.counter_size.is_some() {
        return Err(bad(
            file,
            "counter_size",
            "replaced by `counter_sizes = [\"48x48\", \"96x96\"]`: instructions are counted at \
             two sizes, and their difference over the added pixels is the per-pixel count",
        ));
    }
    Ok(sweep)
}

impl SweepFile {
    /// Refuses a file that names neither studies nor anything a study measures: an empty
    /// file would otherwise run a study of defaults.
    pub fn check_names_something(&self, file: &Path) -> Result<()> {
        if !self.names_nothing() {
            return Ok(());
        }
        Err(Error::Input {
            path: file.to_owned(),
            message: "the file names nothing to measure: a study gives `materials`, `base` or \
                      an `[[axis]]` (or a `[reference]` study), a suite its `studies`"
                .into(),
        })
    }

    fn names_nothing(&self) -> bool {
        self.studies.is_none()
            && self.materials.is_none()
            && self.base.is_none()
            && self.axes.is_empty()
            && self.reference.is_none()
            && self.bake_error.is_none()
    }
}

/// An error naming `file` and its field `field`.
pub fn bad(file: &Path, field: &str, message: &str) -> Error {
    Error::Input {
        path: file.to_owned(),
        message: format!("`{field}`: {message}"),
    }
}
