//! A sweep file checked completely and expanded into its studies, before any GPU work: the
//! study's name, how it measures (scene, lighting, sizes, frames, counter), its axes and the
//! cartesian product of their values over its materials (each case's variant checked and left
//! out where the stack does not fit), then what it compares against (the talk's figures,
//! targets, the baked-table and reference studies). Every error names the file and the field.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::material::Stack;
use crate::profile::counter::CounterSizes;
use crate::profile::plan::{Case, Plan};
use crate::render::lights::{Lighting, PRESETS};
use crate::render::scene::Scene;
use crate::size::Size;
use crate::variant::{Mode, VariantKey, AXES};

use super::file::{bad, read, BakeErrorSpec, SweepFile, Target};
use super::{Point, Study};

/// What a study shades when its file names no `scene`: every pixel, as the talk measured.
pub const DEFAULT_SCENE: Scene = Scene::FullScreen;
/// The frame a study's file names no `size` for.
const DEFAULT_SIZE: &str = "320x180";
/// The pseudo-axes a sweep adds to the variant axes: `variant` takes key fragments
/// (`"mode=generic,max_layers=4"`), for studies whose variants are not a product of axes.
pub const EXTRA_AXES: [&str; 3] = ["active_layers", "material", "variant"];
/// The images' side when `[bake_error]` names no `image_size`.
pub const BAKE_ERROR_IMAGE_SIZE: u32 = 128;
/// The images' sides `[bake_error]` allows.
pub const BAKE_ERROR_IMAGE_SIZES: std::ops::RangeInclusive<u32> = 8..=2048;

/// What `lamina sweep FILE` runs: one study, or a suite's studies (then `true`).
pub fn load(file: &Path) -> Result<(Vec<Study>, bool)> {
    let sweep = read(file)?;
    let Some(list) = &sweep.studies else {
        return Ok((vec![expand(file, &sweep, &Overrides::default())?], false));
    };
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
    let mut studies: Vec<Study> = Vec::new();
    for entry in list {
        let path = dir.join(entry);
        let inner = read(&path)?;
        if inner.studies.is_some() {
            return Err(bad(&path, "studies", "a suite cannot list another suite"));
        }
        let study = expand(&path, &inner, &overrides)?;
        if studies.iter().any(|s| s.name == study.name) {
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

/// What a suite sets for all its studies.
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

/// How a study measures: what it draws, at which size, how often, and whether it counts.
struct Measuring {
    scene: Scene,
    lighting: Lighting,
    size: Size,
    frames: u32,
    warmup: u32,
    counter: Option<CounterSizes>,
    counter_sizes: CounterSizes,
}

fn expand(file: &Path, sweep: &SweepFile, over: &Overrides) -> Result<Study> {
    let source_text = std::fs::read_to_string(file).map_err(|e| Error::Input {
        path: file.to_owned(),
        message: e.to_string(),
    })?;
    let name = study_name(file, sweep)?;
    let measuring = measuring(file, sweep, over)?;
    let fit = match sweep.fit.as_deref() {
        None => false,
        Some("linear") => true,
        Some(other) => return Err(bad(file, "fit", &format!("`{other}`: allowed: linear"))),
    };
    let axes = axes(file, sweep)?;
    let resolve = |spec: &str| resolve_material(file, spec);
    let (mut points, skipped) = product(file, sweep, &axes, &resolve)?;
    let reference = sweep
        .reference
        .as_ref()
        .map(|spec| super::reference::check(file, sweep, spec, &mut points))
        .transpose()?;
    let counter = measuring.counter.filter(|_| reference.is_none());
    let image_error_spp = check_reference_spp(file, over.reference_spp.or(sweep.reference_spp))?
        .filter(|_| reference.is_none());
    if points.is_empty() && reference.is_none() {
        return Err(bad(
            file,
            "axis",
            "the product is empty: every combination was skipped because the stack has more \
             layers than `max_layers`",
        ));
    }
    // What a pass would refuse at run time (a per-material mode on a stack with maps …),
    // refused now, before any GPU work.
    for p in &points {
        p.case
            .pass_key(&measuring.lighting)
            .map_err(|e| bad(file, "materials", &format!("`{}`: {e}", p.case.stack.name)))?;
    }
    check_published(file, sweep)?;
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
    sweep.check_names_something(file)?;
    Ok(Study {
        title: sweep.title.clone().unwrap_or_else(|| name.clone()),
        name,
        description: sweep.description.clone().unwrap_or_default(),
        file: file.to_owned(),
        source_text,
        scene: measuring.scene,
        lighting: measuring.lighting,
        env: environment(file, sweep)?,
        width: measuring.size.width,
        height: measuring.size.height,
        frames: measuring.frames,
        warmup: measuring.warmup,
        counter,
        counter_sizes: measuring.counter_sizes,
        axes: axes.into_iter().map(|(n, _)| n).collect(),
        plan: Plan::new(points.iter().map(|p| p.case.clone()).collect()),
        points,
        skipped,
        published: sweep.published.clone(),
        fit,
        targets,
        bake_error,
        reference,
        image_error_spp,
        shard: None,
    })
}

/// The study's name: `name`, else the file's stem; it names a directory.
fn study_name(file: &Path, sweep: &SweepFile) -> Result<String> {
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
    Ok(name)
}

/// The scene, lighting, size, frames and counter of a study, a suite's settings over its own:
/// a suite's sizes only where their widths hold whole `tile_width` periods.
fn measuring(file: &Path, sweep: &SweepFile, over: &Overrides) -> Result<Measuring> {
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
    let fits = |size: &Size| size.width.is_multiple_of(tile);
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
    let scene = match over.scene.as_ref().or(sweep.scene.as_ref()) {
        None => DEFAULT_SCENE,
        Some(text) => text.parse().map_err(|e: String| bad(file, "scene", &e))?,
    };
    let lighting = lighting(file, sweep, over)?;
    let frames = over.frames.or(sweep.frames).unwrap_or(10);
    if frames == 0 {
        return Err(bad(
            file,
            "frames",
            "0: at least one measured frame is needed",
        ));
    }
    let (counter, counter_sizes) = counter(file, sweep, over, tile)?;
    Ok(Measuring {
        scene,
        lighting,
        size: suite_size.filter(fits).unwrap_or(own_size),
        frames,
        warmup: over.warmup.or(sweep.warmup).unwrap_or(2),
        counter,
        counter_sizes,
    })
}

/// The suite's `lights`, else the study's, relative to the file that names them.
/// `env`, relative to the study's file; an error names the file when it is not there.
fn environment(file: &Path, sweep: &SweepFile) -> Result<Option<PathBuf>> {
    let Some(env) = &sweep.env else {
        return Ok(None);
    };
    let path = file.parent().unwrap_or(Path::new(".")).join(env);
    if !path.is_file() {
        return Err(bad(
            file,
            "env",
            &format!(
                "`{}` is not a file (an OpenEXR environment map)",
                path.display()
            ),
        ));
    }
    Ok(Some(path))
}

fn lighting(file: &Path, sweep: &SweepFile, over: &Overrides) -> Result<Lighting> {
    let lights = over
        .lights
        .clone()
        .or_else(|| sweep.lights.as_ref().map(|l| (file.to_owned(), l.clone())));
    let Some((owner, spec)) = lights else {
        return Ok(Lighting::default());
    };
    let spec = if PRESETS.contains(&spec.as_str()) || Path::new(&spec).is_absolute() {
        spec
    } else {
        let dir = owner.parent().unwrap_or(Path::new("."));
        dir.join(&spec).to_string_lossy().into_owned()
    };
    Lighting::load(&spec).map_err(|e| bad(&owner, "lights", &e.to_string()))
}

/// Whether the study counts instructions (at which sizes), and the sizes it counts at when
/// asked to: the suite's where their widths hold whole `tile` periods and the study does not
/// keep its own (`own_counter_sizes`), else its own.
fn counter(
    file: &Path,
    sweep: &SweepFile,
    over: &Overrides,
    tile: u32,
) -> Result<(Option<CounterSizes>, CounterSizes)> {
    let fits = |sizes: &CounterSizes| {
        sizes.small.width.is_multiple_of(tile) && sizes.large.width.is_multiple_of(tile)
    };
    let own = match &sweep.counter_sizes {
        Some(sizes) => parse_counter_sizes(file, sizes)?,
        None => CounterSizes::DEFAULT,
    };
    if !fits(&own) {
        return Err(bad(
            file,
            "counter_sizes",
            &format!(
                "{} and {}: their widths must be multiples of the study's tile_width {tile}",
                own.small, own.large
            ),
        ));
    }
    let suite = match &over.counter_sizes {
        Some(sizes) if !sweep.own_counter_sizes => Some(parse_counter_sizes(file, sizes)?),
        _ => None,
    };
    let sizes = suite.filter(fits).unwrap_or(own);
    let counter = match over.counter.as_deref().or(sweep.counter.as_deref()) {
        None | Some("none") => None,
        Some("instructions") => Some(sizes),
        Some(other) => {
            return Err(bad(
                file,
                "counter",
                &format!("`{other}`: allowed: instructions, none"),
            ))
        }
    };
    Ok((counter, sizes))
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

/// The study's axes and their values as text, checked: known names, each once, not empty.
fn axes(file: &Path, sweep: &SweepFile) -> Result<Vec<(String, Vec<String>)>> {
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
    Ok(axes)
}

/// A material of the sweep file: a file relative to it, else a preset or a path.
fn resolve_material(file: &Path, spec: &str) -> Result<Stack> {
    let dir = file.parent().unwrap_or(Path::new("."));
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
}

/// The cartesian product of the axes' values (first axis slowest) over the materials (when
/// not an axis: outermost), each a case with its coordinates; and the combinations left out
/// because the stack does not fit the variant's `max_layers`.
fn product(
    file: &Path,
    sweep: &SweepFile,
    axes: &[(String, Vec<String>)],
    resolve: &dyn Fn(&str) -> Result<Stack>,
) -> Result<(Vec<Point>, Vec<String>)> {
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
    let mut combos: Vec<Vec<String>> = vec![Vec::new()];
    for (_, values) in axes {
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
        materials.into_iter().map(Some).collect()
    };
    let base = sweep.base.clone().unwrap_or_default();
    let mut points = Vec::new();
    let mut skipped = Vec::new();
    for material in &material_list {
        for coords in &combos {
            let case = case_at(file, &base, material.as_deref(), axes, coords, resolve)?;
            // A per-material pipeline has the stack's own array size.
            let fits = case.variant.mode.per_material()
                || case.stack.layers.len() <= case.variant.max_layers as usize;
            if fits {
                points.push(Point {
                    case,
                    coords: coords.clone(),
                });
            } else {
                skipped.push(format!("{} with {}", case.stack.name, case.variant));
            }
        }
    }
    Ok((points, skipped))
}

/// The case at `coords`: the material (`material`, or the material axis's value) resized to
/// the `active_layers` axis's count, in the variant `base` with the other axes' values.
fn case_at(
    file: &Path,
    base: &str,
    material: Option<&str>,
    axes: &[(String, Vec<String>)],
    coords: &[String],
    resolve: &dyn Fn(&str) -> Result<Stack>,
) -> Result<Case> {
    let mut spec = material.map(str::to_owned);
    let mut active = None;
    let mut key_text = base.to_owned();
    for ((axis, _), value) in axes.iter().zip(coords) {
        match axis.as_str() {
            "material" => spec = Some(value.clone()),
            "active_layers" => {
                let count = value
                    .parse::<usize>()
                    .ok()
                    .filter(|n| (1..=16).contains(n))
                    .ok_or_else(|| {
                        bad(
                            file,
                            "axis.values",
                            &format!("active_layers `{value}`: allowed: an integer in 1..=16"),
                        )
                    })?;
                active = Some(count);
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
    let variant =
        VariantKey::parse_over(&key_text, stack.base_variant()).map_err(|e| Error::Input {
            path: file.to_owned(),
            message: format!("variant `{key_text}`: {e}"),
        })?;
    Ok(Case { variant, stack })
}

/// `reference_spp`: a sample count in range.
fn check_reference_spp(file: &Path, spp: Option<u32>) -> Result<Option<u32>> {
    match spp {
        Some(spp) if spp == 0 || spp > crate::render::reference::MAX_SPP => Err(bad(
            file,
            "reference_spp",
            &format!(
                "{spp}: allowed: 1 to {} samples per lobe and pixel",
                crate::render::reference::MAX_SPP
            ),
        )),
        spp => Ok(spp),
    }
}

/// `published[i]`: a positive time and a `match` that parses.
fn check_published(file: &Path, sweep: &SweepFile) -> Result<()> {
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
    Ok(())
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
    if let Some(tolerance) = t.tolerance {
        if !(tolerance.is_finite() && (0.0..1.0).contains(&tolerance)) {
            return Err(bad(
                file,
                &field("tolerance"),
                &format!("{tolerance}: allowed: a fraction in [0, 1), e.g. 0.02 for 2 %"),
            ));
        }
    }
    let material = resolve(&t.material)?.name;
    let against_material = match &t.against_material {
        Some(m) => Some(resolve(m)?.name),
        None => None,
    };
    let patterns = [
        Some(("match", &t.matches, &material)),
        t.against.as_ref().map(|a| {
            let on = against_material.as_ref().unwrap_or(&material);
            ("against", a, on)
        }),
    ];
    for (name, pattern, material) in patterns.into_iter().flatten() {
        VariantKey::parse_over(pattern, VariantKey::default())
            .map_err(|e| bad(file, &field(name), &e.to_string()))?;
        let found = points
            .iter()
            .filter(|p| p.case.stack.name == *material)
            .any(|p| p.case.variant.matches(pattern));
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
        against_material,
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
    if !points.iter().any(|p| p.case.variant.mode == Mode::Baked) {
        return Err(bad(
            file,
            "bake_error",
            "the study has no mode=baked run whose table to measure",
        ));
    }
    Ok((spec.sizes.clone(), image_size))
}
