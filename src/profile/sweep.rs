//! Sweep files (`profiling/sweeps/*.toml`): a study is a set of variants × materials measured
//! in one interleaved bench run; a suite lists studies and overrides their resolution and
//! frame counts (`reproduce.toml`).
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
//! [`Stack::with_active_layers`]) and `material` (an alternative to `materials`). Every file is
//! checked completely — axes, values, sizes, materials, the availability of each variant —
//! before any GPU work.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::image_error::ErrorMap;
use crate::error::{Error, Result};
use crate::imageio::write_file_atomically;
use crate::material::Stack;
use crate::reference::compare::MaterialReference;
use crate::render::lights::{Lighting, PRESETS};
use crate::render::scene::Scene;
use crate::size::Size;
use crate::variant::{Model, VariantKey, AXES};

use super::bench::Case;
use super::counter::{CounterSetup, CounterSizes};

/// What a study shades when its file names no `scene`: every pixel, as the talk measured.
pub const DEFAULT_SCENE: Scene = Scene::FullScreen;
/// The frame a study's file names no `size` for.
const DEFAULT_SIZE: &str = "320x180";
/// The pseudo-axes a sweep adds to the variant axes: `variant` takes key fragments
/// (`"mode=generic,max_layers=4"`), for studies whose variants are not a product of axes.
pub const EXTRA_AXES: [&str; 3] = ["active_layers", "material", "variant"];

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
}

/// A `[reference]` study, checked: the materials (each with its variant: model and masking
/// form), the view cosines, the paths and the seed.
#[derive(Clone, Debug)]
pub struct ReferenceStudy {
    pub cases: Vec<Case>,
    pub cosines: Vec<f64>,
    pub paths: u64,
    pub seed: u64,
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
/// time. The report says met, or missed and by how much; nothing fails on it.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Target {
    pub label: String,
    #[serde(rename = "match")]
    pub matches: String,
    pub against: Option<String>,
    /// A preset or material file in the sweep file; the material's name once loaded.
    pub material: String,
    pub max: f64,
}

/// `[bake_error]`: each baked material's table against the per-pixel model
/// (`render::baked::error_study`) at these table sizes, the images compared at `image_size`².
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BakeErrorSpec {
    pub sizes: Vec<u32>,
    pub image_size: Option<u32>,
}

/// The images' side when `[bake_error]` names no `image_size`.
pub const BAKE_ERROR_IMAGE_SIZE: u32 = 128;
/// The images' sides `[bake_error]` allows.
pub const BAKE_ERROR_IMAGE_SIZES: std::ops::RangeInclusive<u32> = 8..=2048;

/// One baked material's errors per table size, as `study.json` keeps them.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct MaterialBakeError {
    pub material: String,
    pub variant: String,
    pub image_size: u32,
    pub rows: Vec<BakeErrorRow>,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct BakeErrorRow {
    pub size: u32,
    pub lobe_error: f64,
    pub image_error: f64,
}

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
    pub points: Vec<Point>,
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

/// Where a study's files go under `out`: `out` itself for a lone study, `out/NAME` for each
/// study of a suite.
pub fn output_dir(out: &Path, study: &Study, suite: bool) -> PathBuf {
    if suite {
        out.join(&study.name)
    } else {
        out.to_owned()
    }
}

/// One case of a study with its value on every swept axis (in axis order).
#[derive(Clone, Debug)]
pub struct Point {
    pub case: Case,
    pub coords: Vec<String>,
}

/// What `lamina sweep FILE` runs: one study, or a suite's studies (then `true`).
pub fn load(file: &Path) -> Result<(Vec<Study>, bool)> {
    let sweep = read(file)?;
    match &sweep.studies {
        None => Ok((vec![expand(file, &sweep, &Overrides::default())?], false)),
        Some(list) => {
            if list.is_empty() {
                return Err(bad(
                    file,
                    "studies",
                    "an empty list; name at least one sweep file",
                ));
            }
            if !sweep.axes.is_empty()
                || sweep.materials.is_some()
                || sweep.base.is_some()
                || !sweep.targets.is_empty()
                || sweep.bake_error.is_some()
                || sweep.reference.is_some()
            {
                return Err(bad(
                    file,
                    "studies",
                    "a suite lists studies only; `axis`, `materials`, `base`, `target`, \
                     `bake_error` and `reference` belong in the study files",
                ));
            }
            let overrides = Overrides {
                scene: sweep.scene.clone(),
                lights: sweep.lights.as_ref().map(|l| (file.to_owned(), l.clone())),
                size: sweep.size.clone(),
                frames: sweep.frames,
                warmup: sweep.warmup,
                counter: sweep.counter.clone(),
                counter_sizes: sweep.counter_sizes.clone(),
                reference_spp: sweep.reference_spp,
            };
            let dir = file.parent().unwrap_or(Path::new("."));
            let mut studies = Vec::new();
            for entry in list {
                let path = dir.join(entry);
                let inner = read(&path)?;
                if inner.studies.is_some() {
                    return Err(bad(&path, "studies", "a suite cannot list another suite"));
                }
                let study = expand(&path, &inner, &overrides)?;
                if studies.iter().any(|s: &Study| s.name == study.name) {
                    return Err(bad(
                        file,
                        "studies",
                        &format!("two studies are named `{}`", study.name),
                    ));
                }
                studies.push(study);
            }
            Ok((studies, true))
        }
    }
}

#[derive(Default)]
struct Overrides {
    scene: Option<String>,
    /// The suite's file and its `lights`.
    lights: Option<(PathBuf, String)>,
    size: Option<String>,
    frames: Option<u32>,
    warmup: Option<u32>,
    counter: Option<String>,
    counter_sizes: Option<Vec<String>>,
    reference_spp: Option<u32>,
}

fn bad(file: &Path, field: &str, message: &str) -> Error {
    Error::Input {
        path: file.to_owned(),
        message: format!("`{field}`: {message}"),
    }
}

fn read(file: &Path) -> Result<SweepFile> {
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

/// `counter_sizes`: two `WxH` sizes, the smaller first ([`CounterSizes`]).
fn parse_counter_sizes(file: &Path, sizes: &[String]) -> Result<CounterSizes> {
    let field = "counter_sizes";
    let [small, large] = sizes else {
        return Err(bad(
            file,
            field,
            &format!(
                "{} size(s); give two, the smaller first, e.g. [\"48x48\", \"96x96\"]",
                sizes.len()
            ),
        ));
    };
    CounterSizes::new(
        parse_size(file, field, small)?,
        parse_size(file, field, large)?,
    )
    .map_err(|e| bad(file, field, &e))
}

/// `size` and `counter_sizes`: `WxH` within [`Size`]'s limit.
fn parse_size(file: &Path, field: &str, text: &str) -> Result<Size> {
    text.parse().map_err(|_| {
        bad(
            file,
            field,
            &format!(
                "`{text}`: expected WxH with both sides in 1..={}",
                Size::MAX_SIDE
            ),
        )
    })
}

fn value_text(value: &toml::Value) -> Option<String> {
    match value {
        toml::Value::String(s) => Some(s.clone()),
        toml::Value::Integer(n) => Some(n.to_string()),
        toml::Value::Boolean(b) => Some(if *b { "on" } else { "off" }.to_string()),
        _ => None,
    }
}

fn expand(file: &Path, sweep: &SweepFile, over: &Overrides) -> Result<Study> {
    let source_text = std::fs::read_to_string(file).map_err(|e| Error::Input {
        path: file.to_owned(),
        message: e.to_string(),
    })?;
    let name = match &sweep.name {
        Some(n) => n.clone(),
        None => file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "sweep".into()),
    };
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(bad(
            file,
            "name",
            &format!("`{name}`: use letters, digits, `-` and `_` (it names a directory)"),
        ));
    }
    let tile = match sweep.tile_width {
        Some(0) => {
            return Err(bad(
                file,
                "tile_width",
                "0: give a period of 1 pixel or more",
            ))
        }
        Some(tile) => tile,
        None => 1,
    };
    let fits = |size: &Size| size.width % tile == 0;
    let own_size = parse_size(file, "size", sweep.size.as_deref().unwrap_or(DEFAULT_SIZE))?;
    if !fits(&own_size) {
        return Err(bad(
            file,
            "size",
            &format!("{own_size}: its width is not a multiple of the study's tile_width {tile}"),
        ));
    }
    let suite_size = match &over.size {
        Some(text) => Some(parse_size(file, "size", text)?),
        None => None,
    };
    let Size { width, height } = suite_size.filter(fits).unwrap_or(own_size);
    let scene = match over.scene.as_ref().or(sweep.scene.as_ref()) {
        None => DEFAULT_SCENE,
        Some(text) => text.parse().map_err(|e: String| bad(file, "scene", &e))?,
    };
    let lights = over
        .lights
        .clone()
        .or_else(|| sweep.lights.as_ref().map(|l| (file.to_owned(), l.clone())));
    let lighting = match lights {
        None => Lighting::default(),
        Some((owner, spec)) => {
            let spec = if PRESETS.contains(&spec.as_str()) || Path::new(&spec).is_absolute() {
                spec
            } else {
                let dir = owner.parent().unwrap_or(Path::new("."));
                dir.join(&spec).to_string_lossy().into_owned()
            };
            Lighting::load(&spec).map_err(|e| bad(&owner, "lights", &e.to_string()))?
        }
    };
    let frames = over.frames.or(sweep.frames).unwrap_or(10);
    if frames == 0 {
        return Err(bad(
            file,
            "frames",
            "0: at least one measured frame is needed",
        ));
    }
    let warmup = over.warmup.or(sweep.warmup).unwrap_or(2);
    let own_counter_sizes = match &sweep.counter_sizes {
        Some(sizes) => parse_counter_sizes(file, sizes)?,
        None => CounterSizes::DEFAULT,
    };
    if !(fits(&own_counter_sizes.small) && fits(&own_counter_sizes.large)) {
        return Err(bad(
            file,
            "counter_sizes",
            &format!(
                "{} and {}: their widths must be multiples of the study's tile_width {tile}",
                own_counter_sizes.small, own_counter_sizes.large
            ),
        ));
    }
    let suite_counter_sizes = match &over.counter_sizes {
        Some(sizes) => Some(parse_counter_sizes(file, sizes)?),
        None => None,
    };
    let counter_sizes = suite_counter_sizes
        .filter(|sizes| fits(&sizes.small) && fits(&sizes.large))
        .unwrap_or(own_counter_sizes);
    let counter = match over.counter.as_deref().or(sweep.counter.as_deref()) {
        None | Some("none") => None,
        Some("instructions") => Some(counter_sizes),
        Some(other) => {
            return Err(bad(
                file,
                "counter",
                &format!("`{other}`: allowed: instructions, none"),
            ))
        }
    };
    let fit = match sweep.fit.as_deref() {
        None => false,
        Some("linear") => true,
        Some(other) => return Err(bad(file, "fit", &format!("`{other}`: allowed: linear"))),
    };

    let mut axes: Vec<(String, Vec<String>)> = Vec::new();
    for (i, axis) in sweep.axes.iter().enumerate() {
        let field = format!("axis[{i}]");
        if !AXES.contains(&axis.name.as_str()) && !EXTRA_AXES.contains(&axis.name.as_str()) {
            return Err(bad(
                file,
                &format!("{field}.name"),
                &format!(
                    "unknown axis `{}`; allowed: {}, {}",
                    axis.name,
                    AXES.join(", "),
                    EXTRA_AXES.join(", ")
                ),
            ));
        }
        if axes.iter().any(|(n, _)| *n == axis.name) {
            return Err(bad(
                file,
                &format!("{field}.name"),
                &format!("axis `{}` is given twice", axis.name),
            ));
        }
        if axis.values.is_empty() {
            return Err(bad(
                file,
                &format!("{field}.values"),
                &format!(
                    "axis `{}` has no values: the product would be empty",
                    axis.name
                ),
            ));
        }
        let values = axis
            .values
            .iter()
            .map(|v| {
                value_text(v).ok_or_else(|| {
                    bad(
                        file,
                        &format!("{field}.values"),
                        &format!("`{v}`: values are strings, integers or booleans"),
                    )
                })
            })
            .collect::<Result<Vec<_>>>()?;
        axes.push((axis.name.clone(), values));
    }
    if axes.iter().any(|(n, _)| n == "material") && sweep.materials.is_some() {
        return Err(bad(
            file,
            "materials",
            "give the materials either as `materials` or as a `material` axis, not both",
        ));
    }
    let materials = sweep
        .materials
        .clone()
        .unwrap_or_else(|| vec!["varnished-gold".into()]);
    if materials.is_empty() {
        return Err(bad(
            file,
            "materials",
            "an empty list: the product would be empty",
        ));
    }
    let dir = file.parent().unwrap_or(Path::new("."));
    let resolve = |spec: &str| -> Result<Stack> {
        let local = dir.join(spec);
        let stack = if spec.ends_with(".toml") && local.exists() {
            Stack::load(&local)
        } else {
            Stack::resolve(spec)
        };
        stack.map_err(|e| Error::Input {
            path: file.to_owned(),
            message: format!("material `{spec}`: {e}"),
        })
    };
    let base_text = sweep.base.clone().unwrap_or_default();

    // The cartesian product, first axis slowest, materials (when not an axis) outermost.
    let mut combos: Vec<Vec<String>> = vec![Vec::new()];
    for (_, values) in &axes {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push(v.clone());
                    c
                })
            })
            .collect();
    }
    let material_list: Vec<Option<String>> = if axes.iter().any(|(n, _)| n == "material") {
        vec![None]
    } else {
        materials.iter().cloned().map(Some).collect()
    };
    let mut points = Vec::new();
    let mut skipped = Vec::new();
    for material in &material_list {
        for coords in &combos {
            let mut spec = material.clone();
            let mut active = None;
            let mut key_text = base_text.clone();
            for ((axis, _), value) in axes.iter().zip(coords) {
                match axis.as_str() {
                    "material" => spec = Some(value.clone()),
                    "active_layers" => {
                        active = Some(
                            value
                                .parse::<usize>()
                                .ok()
                                .filter(|n| (1..=16).contains(n))
                                .ok_or_else(|| {
                                    bad(
                                        file,
                                        "axis.values",
                                        &format!(
                                        "active_layers `{value}`: allowed: an integer in 1..=16"
                                    ),
                                    )
                                })?,
                        )
                    }
                    _ => {
                        if !key_text.is_empty() {
                            key_text.push(',');
                        }
                        if axis == "variant" {
                            key_text += value;
                        } else {
                            key_text += &format!("{axis}={value}");
                        }
                    }
                }
            }
            let spec = spec.expect("a material comes from `materials` or the material axis");
            let mut stack = resolve(&spec)?;
            if let Some(n) = active {
                stack = stack.with_active_layers(n).map_err(|e| Error::Input {
                    path: file.to_owned(),
                    message: e.to_string(),
                })?;
            }
            let variant = VariantKey::parse_over(&key_text, stack.base_variant()).map_err(|e| {
                Error::Input {
                    path: file.to_owned(),
                    message: format!("variant `{key_text}`: {e}"),
                }
            })?;
            // A per-material pipeline has the stack's own array size.
            if !variant.mode.per_material() && stack.layers.len() > variant.max_layers as usize {
                skipped.push(format!("{} with {variant}", stack.name));
                continue;
            }
            points.push(Point {
                case: Case { variant, stack },
                coords: coords.clone(),
            });
        }
    }
    let reference = sweep
        .reference
        .as_ref()
        .map(|spec| check_reference(file, sweep, spec, &mut points))
        .transpose()?;
    let counter = if reference.is_some() { None } else { counter };
    let image_error_spp = match over.reference_spp.or(sweep.reference_spp) {
        Some(spp) if spp == 0 || spp > crate::render::reference::MAX_SPP => {
            return Err(bad(
                file,
                "reference_spp",
                &format!(
                    "{spp}: allowed: 1 to {} samples per lobe and pixel",
                    crate::render::reference::MAX_SPP
                ),
            ))
        }
        spp => spp.filter(|_| reference.is_none()),
    };
    if points.is_empty() && reference.is_none() {
        return Err(bad(
            file,
            "axis",
            "the product is empty: every combination was skipped because the stack has more \
             layers than `max_layers`",
        ));
    }
    for (i, p) in sweep.published.iter().enumerate() {
        if !(p.ms.is_finite() && p.ms > 0.0) {
            return Err(bad(
                file,
                &format!("published[{i}].ms"),
                &format!("{}: allowed: a positive number of milliseconds", p.ms),
            ));
        }
        VariantKey::parse_over(&p.matches, VariantKey::default())
            .map_err(|e| bad(file, &format!("published[{i}].match"), &e.to_string()))?;
    }
    let targets = sweep
        .targets
        .iter()
        .enumerate()
        .map(|(i, t)| check_target(file, i, t, &points, &resolve))
        .collect::<Result<Vec<_>>>()?;
    let bake_error = sweep
        .bake_error
        .as_ref()
        .map(|spec| check_bake_error(file, spec, &points))
        .transpose()?;
    Ok(Study {
        title: sweep.title.clone().unwrap_or_else(|| name.clone()),
        name,
        description: sweep.description.clone().unwrap_or_default(),
        file: file.to_owned(),
        source_text,
        scene,
        lighting,
        width,
        height,
        frames,
        warmup,
        counter,
        counter_sizes,
        axes: axes.into_iter().map(|(n, _)| n).collect(),
        points,
        skipped,
        published: sweep.published.clone(),
        fit,
        targets,
        bake_error,
        reference,
        image_error_spp,
    })
}

/// `[reference]`: alone in its study (no axes, figures, targets or bake error), view cosines
/// in (0, 1], a path count in range. Takes the study's points: their materials and variants
/// are the reference study's, and nothing is timed.
fn check_reference(
    file: &Path,
    sweep: &SweepFile,
    spec: &ReferenceSpec,
    points: &mut Vec<Point>,
) -> Result<ReferenceStudy> {
    if !sweep.axes.is_empty()
        || !sweep.published.is_empty()
        || !sweep.targets.is_empty()
        || sweep.bake_error.is_some()
    {
        return Err(bad(
            file,
            "reference",
            "a reference study compares each material's own model with the stochastic \
             reference; it takes `materials` and `base`, not `axis`, `published`, `target` \
             or `bake_error`",
        ));
    }
    if spec.cosines.is_empty() {
        return Err(bad(
            file,
            "reference.cosines",
            "empty: give view cosines in (0, 1]",
        ));
    }
    if let Some(c) = spec
        .cosines
        .iter()
        .find(|c| !(c.is_finite() && **c > 0.0 && **c <= 1.0))
    {
        return Err(bad(
            file,
            "reference.cosines",
            &format!("{c}: allowed: view cosines in (0, 1]"),
        ));
    }
    if spec.paths == 0 || spec.paths > crate::reference::MAX_PATHS {
        return Err(bad(
            file,
            "reference.paths",
            &format!(
                "{}: allowed: 1 to {} paths per channel and view cosine",
                spec.paths,
                crate::reference::MAX_PATHS
            ),
        ));
    }
    if let Some(p) = points.iter().find(|p| p.case.variant.model == Model::Ggx) {
        return Err(bad(
            file,
            "base",
            &format!(
                "{}: model=ggx is not a layered model; a reference study compares tm2 or tm6",
                p.case.variant
            ),
        ));
    }
    Ok(ReferenceStudy {
        cases: points.drain(..).map(|p| p.case).collect(),
        cosines: spec.cosines.clone(),
        paths: spec.paths,
        seed: spec.seed.unwrap_or(1),
    })
}

/// `target[i]`: finite positive bound, key fragments that parse, a material that resolves, and
/// runs of the study for it to compare.
fn check_target(
    file: &Path,
    i: usize,
    t: &Target,
    points: &[Point],
    resolve: &dyn Fn(&str) -> Result<Stack>,
) -> Result<Target> {
    let field = |f: &str| format!("target[{i}].{f}");
    if !(t.max.is_finite() && t.max > 0.0) {
        return Err(bad(
            file,
            &field("max"),
            &format!("{}: allowed: a positive ratio", t.max),
        ));
    }
    let material = resolve(&t.material)?.name;
    let on_material: Vec<&Point> = points
        .iter()
        .filter(|p| p.case.stack.name == material)
        .collect();
    let patterns = [
        Some(("match", &t.matches)),
        t.against.as_ref().map(|a| ("against", a)),
    ];
    for (name, pattern) in patterns.into_iter().flatten() {
        VariantKey::parse_over(pattern, VariantKey::default())
            .map_err(|e| bad(file, &field(name), &e.to_string()))?;
        let found = on_material
            .iter()
            .any(|p| key_matches(&p.case.variant.to_string(), pattern));
        if !found {
            return Err(bad(
                file,
                &field(name),
                &format!("`{pattern}`: no run of the study on {material} has these axis values"),
            ));
        }
    }
    Ok(Target {
        material,
        ..t.clone()
    })
}

/// `[bake_error]`: table sizes in the baked table's range, increasing; an image side in range;
/// and a `mode=baked` run to measure.
fn check_bake_error(
    file: &Path,
    spec: &BakeErrorSpec,
    points: &[Point],
) -> Result<(Vec<u32>, u32)> {
    let range = crate::render::baked::SIZE_RANGE;
    if spec.sizes.is_empty() {
        return Err(bad(
            file,
            "bake_error.sizes",
            "an empty list; give table sizes",
        ));
    }
    if let Some(s) = spec.sizes.iter().find(|s| !range.contains(s)) {
        return Err(bad(
            file,
            "bake_error.sizes",
            &format!("{s}: allowed: {}..={}", range.start(), range.end()),
        ));
    }
    if spec.sizes.windows(2).any(|w| w[0] >= w[1]) {
        return Err(bad(
            file,
            "bake_error.sizes",
            "give the sizes in increasing order, each once",
        ));
    }
    let image_size = spec.image_size.unwrap_or(BAKE_ERROR_IMAGE_SIZE);
    if !BAKE_ERROR_IMAGE_SIZES.contains(&image_size) {
        return Err(bad(
            file,
            "bake_error.image_size",
            &format!(
                "{image_size}: allowed: {}..={}",
                BAKE_ERROR_IMAGE_SIZES.start(),
                BAKE_ERROR_IMAGE_SIZES.end()
            ),
        ));
    }
    if !points
        .iter()
        .any(|p| p.case.variant.mode == crate::variant::Mode::Baked)
    {
        return Err(bad(
            file,
            "bake_error",
            "the study has no mode=baked run whose table to measure",
        ));
    }
    Ok((spec.sizes.clone(), image_size))
}

/// Whether a run's variant key has every axis value `pattern` names (`model=tm6,fp16=on`).
pub fn key_matches(variant: &str, pattern: &str) -> bool {
    let pairs: Vec<&str> = variant.split(',').map(str::trim).collect();
    pattern
        .split(',')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .all(|want| pairs.contains(&want))
}

/// What a study's directory holds besides `results.json`: read by `lamina report`.
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
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct PointMeta {
    pub run: usize,
    pub coords: Vec<String>,
}

/// Runs one study: timings interleaved on `gpu`, the baked tables' errors, then (when asked)
/// instruction counts.
pub fn run(
    gpu: &crate::gpu::Gpu,
    equirect: &crate::imageio::HdrImage,
    study: &Study,
    counter: Option<&CounterSetup>,
    mut progress: impl FnMut(&str, usize, usize),
) -> Result<(super::bench::Results, StudyMeta)> {
    let mut timed = [time(gpu, equirect, study, &mut progress)?];
    if let Some(setup) = counter {
        count(
            std::slice::from_ref(study),
            &mut timed,
            setup,
            |done, total| progress("counted", done, total),
        )?;
    }
    let [timed] = timed;
    Ok(finish(study, timed, counter.is_some()))
}

/// A study timed and its baked tables measured; its instructions not counted yet.
pub struct Timed {
    pub results: super::bench::Results,
    /// The runs' cases in order (the added ggx baselines, then the study's points).
    pub cases: Vec<Case>,
    pub bake_error: Vec<MaterialBakeError>,
    pub reference: Vec<MaterialReference>,
    /// `reference_spp`: each run's FLIP error map, by run index (the image errors themselves
    /// are in the results' runs).
    pub error_maps: Vec<(usize, ErrorMap)>,
}

/// The first part of [`run`]: the timings, interleaved on `gpu`, and the bake-error study.
pub fn time(
    gpu: &crate::gpu::Gpu,
    equirect: &crate::imageio::HdrImage,
    study: &Study,
    progress: &mut impl FnMut(&str, usize, usize),
) -> Result<Timed> {
    let config = super::bench::BenchConfig {
        cases: study.points.iter().map(|p| p.case.clone()).collect(),
        scene: study.scene,
        width: study.width,
        height: study.height,
        frames: study.frames,
        warmup: study.warmup,
        lighting: study.lighting.clone(),
    };
    let cases = config.with_baselines();
    let results = super::bench::run(gpu, equirect, &config, |done, total| {
        progress("frames", done as usize, total as usize)
    })?;
    let bake_error = match &study.bake_error {
        Some((sizes, image_size)) => {
            bake_errors(gpu, equirect, study, sizes, *image_size, progress)?
        }
        None => Vec::new(),
    };
    let reference = match &study.reference {
        Some(spec) => reference_comparisons(spec, progress)?,
        None => Vec::new(),
    };
    let mut results = results;
    let error_maps = match study.image_error_spp {
        Some(spp) => super::image_error::measure(
            gpu,
            equirect,
            &config,
            &cases,
            spp,
            &mut results,
            progress,
        )?,
        None => Vec::new(),
    };
    Ok(Timed {
        results,
        cases,
        bake_error,
        reference,
        error_maps,
    })
}

/// Counts the instructions of every timed study that asks for them, in one pool of workers
/// per scene, counter sizes and lighting (so a suite starts its workers and compiles each shader under
/// valgrind once, not once per study). `studies[i]` was timed into `timed[i]`.
pub fn count(
    studies: &[Study],
    timed: &mut [Timed],
    setup: &CounterSetup,
    mut progress: impl FnMut(usize, usize),
) -> Result<()> {
    // One pool of workers per scene, counted sizes and lighting: a worker draws one of each.
    let mut keys: Vec<(Scene, CounterSizes, Option<String>)> = Vec::new();
    for (s, t) in studies.iter().zip(timed.iter()) {
        if let Some(sizes) = s.counter {
            let key = (s.scene, sizes, t.results.lighting.clone());
            if !keys.contains(&key) {
                keys.push(key);
            }
        }
    }
    let total: usize = studies
        .iter()
        .zip(timed.iter())
        .filter(|(s, _)| s.counter.is_some())
        .map(|(_, t)| t.cases.len() * 2)
        .sum();
    let mut before = 0;
    for (scene, sizes, lighting) in keys {
        let mut batches: Vec<(&mut super::bench::Results, &[Case])> = studies
            .iter()
            .zip(timed.iter_mut())
            .filter(|(s, t)| {
                s.scene == scene && s.counter == Some(sizes) && t.results.lighting == lighting
            })
            .map(|(_, t)| (&mut t.results, t.cases.as_slice()))
            .collect();
        let here: usize = batches.iter().map(|(_, c)| c.len() * 2).sum();
        super::counter::add_counts_to_all(&mut batches, setup, sizes, |done, _| {
            progress(before + done, total)
        })?;
        before += here;
    }
    Ok(())
}

/// The last part of [`run`]: the study's metadata beside its results (counted when `counted`
/// and the study asks for counts).
pub fn finish(study: &Study, timed: Timed, counted: bool) -> (super::bench::Results, StudyMeta) {
    let Timed {
        results,
        cases,
        bake_error,
        reference,
        error_maps: _,
    } = timed;
    let baselines = cases.len() - study.points.len();
    let counted = study.counter.filter(|_| counted);
    let meta = StudyMeta {
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
    };
    (results, meta)
}

/// A `[reference]` study: each material's model against the stochastic reference, on every
/// core.
fn reference_comparisons(
    spec: &ReferenceStudy,
    progress: &mut impl FnMut(&str, usize, usize),
) -> Result<Vec<MaterialReference>> {
    let per_material = spec.paths * spec.cosines.len() as u64;
    let total = per_material * spec.cases.len() as u64;
    let never = std::sync::atomic::AtomicBool::new(false);
    let mut out = Vec::with_capacity(spec.cases.len());
    for (i, case) in spec.cases.iter().enumerate() {
        let before = i as u64 * per_material;
        let compared = crate::reference::compare::compare(
            &case.stack.name,
            &case.stack.params(),
            case.variant,
            &spec.cosines,
            (spec.paths, spec.seed),
            &mut |paths| progress("reference paths", (before + paths) as usize, total as usize),
            &never,
        )?
        .expect("a reference study is never stopped");
        out.push(compared);
    }
    Ok(out)
}

/// The baked-table error study of every material the study bakes (its first `mode=baked` run
/// per material).
fn bake_errors(
    gpu: &crate::gpu::Gpu,
    equirect: &crate::imageio::HdrImage,
    study: &Study,
    sizes: &[u32],
    image_size: u32,
    progress: &mut impl FnMut(&str, usize, usize),
) -> Result<Vec<MaterialBakeError>> {
    let mut baked: Vec<&Point> = Vec::new();
    for p in &study.points {
        if p.case.variant.mode == crate::variant::Mode::Baked
            && !baked.iter().any(|b| b.case.stack.name == p.case.stack.name)
        {
            baked.push(p);
        }
    }
    let mut out = Vec::with_capacity(baked.len());
    for (i, p) in baked.iter().enumerate() {
        progress("bake error", i, baked.len());
        let errors = crate::render::baked::error_study(
            gpu,
            equirect,
            crate::tables::environment::EnvDesc::default(),
            p.case.variant,
            &p.case.stack.params(),
            sizes,
            image_size,
        )?;
        out.push(MaterialBakeError {
            material: p.case.stack.name.clone(),
            variant: p.case.variant.to_string(),
            image_size,
            rows: errors
                .iter()
                .map(|e| BakeErrorRow {
                    size: e.size,
                    lobe_error: e.lobe_error,
                    image_error: e.image_error,
                })
                .collect(),
        });
    }
    progress("bake error", baked.len(), baked.len());
    Ok(out)
}

/// Writes `results.json`, `results.csv`, `study.json`, `sweep.toml` (the file as run) and the
/// charts into `dir`; returns the chart paths (PNG).
pub fn write(
    dir: &Path,
    study: &Study,
    results: &super::bench::Results,
    meta: &StudyMeta,
    error_maps: &[(usize, ErrorMap)],
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Output {
        path: dir.to_owned(),
        message: e.to_string(),
    })?;
    let results_json = serde_json::to_string_pretty(results).expect("results serialise");
    let meta_json = serde_json::to_string_pretty(meta).expect("study metadata serialises");
    write_file_atomically(&dir.join("results.json"), &results_json)?;
    write_file_atomically(&dir.join("results.csv"), results.csv())?;
    write_file_atomically(&dir.join("study.json"), &meta_json)?;
    write_file_atomically(&dir.join("sweep.toml"), &study.source_text)?;
    let mut charts = Vec::new();
    for (stem, chart) in charts_of(results, meta) {
        let path = dir.join(stem);
        chart.write(&path)?;
        charts.push(path.with_extension("png"));
    }
    for e in &meta.reference {
        let path = dir.join(reference_chart_stem(&e.material));
        reference_chart(e).write(&path)?;
        charts.push(path.with_extension("png"));
    }
    for (run, map) in error_maps {
        let path = dir.join(super::image_error::error_map_path(*run));
        crate::imageio::write_png(&path, map.width as usize, map.height as usize, &map.rgba())?;
    }
    for (stem, chart) in pareto_charts(results, meta) {
        let path = dir.join(stem);
        chart.write(&path)?;
        charts.push(path.with_extension("png"));
    }
    Ok(charts)
}

/// A run's cost for the Pareto charts: JIT instructions per shaded pixel where counted at two
/// sizes, else the median time.
fn run_cost(run: &super::bench::Run, instructions: bool) -> Option<f64> {
    if instructions {
        run.instructions_per_pixel
    } else {
        Some(run.median_ms)
    }
}

/// The runs of `material` on its Pareto front of (FLIP, cost): no other run of the material
/// is at most as costly and at most as wrong, and better in one.
pub fn pareto_front(
    results: &super::bench::Results,
    material: &str,
    instructions: bool,
) -> Vec<usize> {
    let points: Vec<(usize, f64, f64)> = results
        .runs
        .iter()
        .enumerate()
        .filter(|(_, r)| r.material == material)
        .filter_map(|(i, r)| Some((i, r.image_error?.flip, run_cost(r, instructions)?)))
        .collect();
    points
        .iter()
        .filter(|&&(_, e, c)| {
            !points
                .iter()
                .any(|&(_, e2, c2)| e2 <= e && c2 <= c && (e2 < e || c2 < c))
        })
        .map(|&(i, _, _)| i)
        .collect()
}

/// Cost against image error, per material: every run a point (FLIP, cost), the Pareto front
/// joined. One chart by JIT instructions per pixel where counted, one by time.
fn pareto_charts(
    results: &super::bench::Results,
    meta: &StudyMeta,
) -> Vec<(&'static str, super::chart::XyChart)> {
    use super::chart::{XyChart, XySeries};
    if !results.runs.iter().any(|r| r.image_error.is_some()) {
        return Vec::new();
    }
    let label = |i: usize| {
        let run = &results.runs[i];
        match meta.points.iter().find(|p| p.run == i) {
            Some(p) if !p.coords.is_empty() => {
                format!("{} ({})", p.coords.join(", "), run.material)
            }
            _ if run.variant.starts_with("model=ggx") => format!("ggx baseline ({})", run.material),
            _ => format!("{} ({})", run.variant, run.material),
        }
    };
    let mut materials: Vec<&str> = Vec::new();
    for r in &results.runs {
        if r.image_error.is_some() && !materials.contains(&r.material.as_str()) {
            materials.push(&r.material);
        }
    }
    let counted = results
        .runs
        .iter()
        .any(|r| r.instructions_per_pixel.is_some());
    let kinds: &[(&'static str, bool, &str)] = if counted {
        &[
            (
                "chart-pareto-instructions",
                true,
                "JIT instructions per shaded pixel",
            ),
            ("chart-pareto-time", false, "median time (ms)"),
        ]
    } else {
        &[("chart-pareto-time", false, "median time (ms)")]
    };
    kinds
        .iter()
        .map(|&(stem, instructions, y_label)| {
            let mut series = Vec::new();
            let mut colour = 0;
            let mut max_flip = 0.0f64;
            for material in &materials {
                for (i, r) in results.runs.iter().enumerate() {
                    let (Some(e), Some(cost)) = (r.image_error, run_cost(r, instructions)) else {
                        continue;
                    };
                    if r.material != *material {
                        continue;
                    }
                    max_flip = max_flip.max(e.flip);
                    series.push(XySeries {
                        label: label(i),
                        points: vec![(e.flip, cost, 0.0, 0.0)],
                        line: false,
                        colour,
                    });
                    colour += 1;
                }
                let mut front: Vec<(f64, f64)> = pareto_front(results, material, instructions)
                    .into_iter()
                    .filter_map(|i| {
                        let r = &results.runs[i];
                        Some((r.image_error?.flip, run_cost(r, instructions)?))
                    })
                    .collect();
                front.sort_by(|a, b| a.0.total_cmp(&b.0));
                series.push(XySeries {
                    label: format!("Pareto front ({material})"),
                    points: front.iter().map(|&(x, y)| (x, y, 0.0, 0.0)).collect(),
                    line: true,
                    colour,
                });
                colour += 1;
            }
            (
                stem,
                XyChart {
                    title: format!("{} — cost against image error", meta.title),
                    x_label: "mean FLIP against the reference image".into(),
                    y_label: y_label.into(),
                    x_range: (0.0, (max_flip * 1.15).max(1e-3)),
                    series,
                },
            )
        })
        .collect()
}

/// The file stem of a material's chart in a `[reference]` study: `reference-` and the name's
/// letters and digits, the rest as `-`.
pub fn reference_chart_stem(material: &str) -> String {
    let name: String = material
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect();
    format!("reference-{name}")
}

/// A material's BRDF in the plane of incidence, per view cosine: the model's curve and the
/// reference's bins (± 2 standard errors), the channels' mean.
fn reference_chart(e: &MaterialReference) -> super::chart::XyChart {
    use super::chart::{XyChart, XySeries};
    let mean = |v: [f64; 3]| (v[0] + v[1] + v[2]) / 3.0;
    let centre = |i: usize| {
        let (a, b) = crate::reference::slice_bin_edges(i);
        (0.5 * (a + b)).to_degrees()
    };
    let mut series = Vec::new();
    for (j, row) in e.rows.iter().enumerate() {
        series.push(XySeries {
            label: format!("model, cos θ = {:.2}", row.cos_theta),
            points: row
                .slice_model
                .iter()
                .enumerate()
                .map(|(i, v)| (centre(i), mean(*v), 0.0, 0.0))
                .collect(),
            line: true,
            colour: j,
        });
        series.push(XySeries {
            label: format!("reference, cos θ = {:.2}", row.cos_theta),
            points: row
                .slice_reference
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    let (m, se) = (mean(r.mean), mean(r.std_error) / 3f64.sqrt());
                    (centre(i), m, m - 2.0 * se, m + 2.0 * se)
                })
                .collect(),
            line: false,
            colour: j,
        });
    }
    XyChart {
        title: format!(
            "{} ({}) — BRDF in the plane of incidence",
            e.material, e.model
        ),
        x_label: "θ_o (degrees; positive: mirror side)".into(),
        y_label: "BRDF (1/sr), mean of RGB".into(),
        x_range: (-90.0, 90.0),
        series,
    }
}

/// A value read off a run with its whiskers: (value, low, high).
type RunValue = dyn Fn(&super::bench::Run) -> Option<(f64, f64, f64)>;

/// The study's charts: median time (min–max whiskers) per x category, one line per
/// combination of the other axes; and the instruction counts when measured.
pub fn charts_of(
    results: &super::bench::Results,
    meta: &StudyMeta,
) -> Vec<(&'static str, super::chart::Chart)> {
    use super::chart::{Chart, Series};
    if meta.points.is_empty() {
        // A `[reference]` study times nothing.
        return Vec::new();
    }
    let x_axis = meta
        .axes
        .first()
        .cloned()
        .unwrap_or_else(|| "variant".into());
    let mut categories: Vec<String> = Vec::new();
    let mut labels: Vec<String> = Vec::new();
    let materials: Vec<&str> = {
        let mut m: Vec<&str> = Vec::new();
        for p in &meta.points {
            let name = results.runs[p.run].material.as_str();
            if !m.contains(&name) {
                m.push(name);
            }
        }
        m
    };
    let mut placed = Vec::new();
    for p in &meta.points {
        let mut category = p.coords.first().cloned().unwrap_or_else(|| "base".into());
        // A material file on the x axis reads as its stem (`divergence/noise.toml` → noise).
        if x_axis == "material" && category.ends_with(".toml") {
            if let Some(stem) = Path::new(&category).file_stem() {
                category = stem.to_string_lossy().into_owned();
            }
        }
        let mut label_parts: Vec<String> = meta
            .axes
            .iter()
            .zip(&p.coords)
            .skip(1)
            .filter(|(axis, _)| axis.as_str() != "material")
            .map(|(axis, v)| format!("{axis}={v}"))
            .collect();
        let material_is_swept = meta
            .axes
            .iter()
            .any(|a| a == "material" || a == "active_layers");
        if materials.len() > 1 && !material_is_swept {
            label_parts.insert(0, results.runs[p.run].material.clone());
        }
        let label = if label_parts.is_empty() {
            "median".to_string()
        } else {
            label_parts.join(", ")
        };
        let ci = match categories.iter().position(|c| *c == category) {
            Some(i) => i,
            None => {
                categories.push(category);
                categories.len() - 1
            }
        };
        let si = match labels.iter().position(|l| *l == label) {
            Some(i) => i,
            None => {
                labels.push(label);
                labels.len() - 1
            }
        };
        placed.push((ci, si, p.run));
    }
    let baseline = results
        .runs
        .iter()
        .find(|r| r.variant.starts_with("model=ggx"));
    let build = |value: &RunValue| {
        labels
            .iter()
            .enumerate()
            .map(|(si, label)| Series {
                label: label.clone(),
                points: placed
                    .iter()
                    .filter(|p| p.1 == si)
                    .filter_map(|&(ci, _, run)| {
                        value(&results.runs[run]).map(|(v, lo, hi)| (ci, v, lo, hi))
                    })
                    .collect(),
            })
            .collect::<Vec<_>>()
    };
    let device = &results.device.name;
    let mut charts = vec![(
        "chart-time",
        Chart {
            title: format!(
                "{} — shaded draw, {}x{} {} ({device})",
                meta.title, results.size[0], results.size[1], results.scene
            ),
            x_label: x_axis.clone(),
            y_label: "GPU time, ms (median; whiskers min–max)".into(),
            categories: categories.clone(),
            series: build(&|r| Some((r.median_ms, r.min_ms, r.max_ms))),
            reference: baseline.map(|b| ("ggx baseline".to_string(), b.median_ms)),
        },
    )];
    /// A counted value: no whiskers.
    fn point(x: f64) -> (f64, f64, f64) {
        (x, x, x)
    }
    if results
        .runs
        .iter()
        .any(|r| r.instructions_per_pixel.is_some())
    {
        let sizes = results
            .counter
            .as_ref()
            .map(|c| {
                let [[a, b], [c, d]] = c.sizes;
                format!(", {a}x{b} → {c}x{d}")
            })
            .unwrap_or_default();
        charts.push((
            "chart-instructions",
            Chart {
                title: format!(
                    "{} — JIT instructions per shaded pixel, {}{sizes}",
                    meta.title, results.scene
                ),
                x_label: x_axis,
                y_label: "JIT instructions per added pixel (callgrind, LP_NUM_THREADS=0)".into(),
                categories,
                series: build(&|r| r.instructions_per_pixel.map(point)),
                reference: baseline
                    .and_then(|b| b.instructions_per_pixel)
                    .map(|n| ("ggx baseline".to_string(), n)),
            },
        ));
    } else if results.runs.iter().any(|r| r.instructions.is_some()) {
        // Counted at one size, before the per-pixel count: the whole draw's.
        let size = meta
            .counter_size
            .map(|[w, h]| format!("{w}x{h}"))
            .unwrap_or_default();
        charts.push((
            "chart-instructions",
            Chart {
                title: format!(
                    "{} — JIT instructions of the shaded draw, {size}",
                    meta.title
                ),
                x_label: x_axis,
                y_label: "JIT instructions (callgrind, LP_NUM_THREADS=0)".into(),
                categories,
                series: build(&|r| r.instructions.map(|n| point(n as f64))),
                reference: baseline
                    .and_then(|b| b.instructions)
                    .map(|n| ("ggx baseline".to_string(), n as f64)),
            },
        ));
    }
    if let Some(first) = meta.bake_error.first() {
        let categories: Vec<String> = first.rows.iter().map(|r| r.size.to_string()).collect();
        let series = |value: fn(&BakeErrorRow) -> f64| {
            meta.bake_error
                .iter()
                .map(|e| Series {
                    label: e.material.clone(),
                    points: e
                        .rows
                        .iter()
                        .enumerate()
                        .map(|(i, row)| (i, value(row), value(row), value(row)))
                        .collect(),
                })
                .collect()
        };
        let bound = Some(("1e-3".to_string(), 1e-3));
        charts.push((
            "chart-bake-lobes",
            Chart {
                title: format!("{} — baked lobes against the model", meta.title),
                x_label: "table size (samples per lobe)".into(),
                y_label: "largest lobe error, relative to R".into(),
                categories: categories.clone(),
                series: series(|r| r.lobe_error),
                reference: bound.clone(),
            },
        ));
        charts.push((
            "chart-bake-image",
            Chart {
                title: format!(
                    "{} — baked render against the per-pixel one, {}x{}",
                    meta.title, first.image_size, first.image_size
                ),
                x_label: "table size (samples per lobe)".into(),
                y_label: "largest relative pixel difference".into(),
                categories,
                series: series(|r| r.image_error),
                reference: bound,
            },
        ));
    }
    charts
}
