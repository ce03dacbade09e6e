//! The `[reference]` study of a sweep file, checked: the materials' cases, the view cosines,
//! the paths, the truths (`interfaces`) and the random stacks (`[reference.random]`). Every
//! error names the file and the field.

use std::path::Path;

use crate::error::Result;
use crate::material::random::{preset_like_stack, PresetRanges};
use crate::model::random::{case_seed, Rng};
use crate::profile::plan::Case;
use crate::variant::{Axis, Interfaces, Model};

use super::file::{bad, RandomSpec, ReferenceSpec, SweepFile};
use super::{Point, ReferenceStudy};

/// `[reference]`: alone in its study (no axes, figures, targets or bake error), view cosines
/// in (0, 1], a path count in range. Takes the study's points: their materials and variants
/// are the reference study's, and nothing is timed.
pub(super) fn check(
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
    let interfaces = reference_interfaces(file, spec.interfaces.as_deref())?;
    let (random, random_paths) = match &spec.random {
        None => (Vec::new(), spec.paths),
        Some(r) => (random_cases(file, r)?, r.paths.unwrap_or(spec.paths)),
    };
    Ok(ReferenceStudy {
        cases: points.drain(..).map(|p| p.case).collect(),
        cosines: spec.cosines.clone(),
        paths: spec.paths,
        seed: spec.seed.unwrap_or(1),
        interfaces,
        random,
        random_paths,
    })
}

/// Most random stacks a reference study draws.
const MAX_RANDOM_STACKS: usize = 1000;

/// `reference.random`: `count` stacks within the presets' ranges, alternately 2- and 6-flux,
/// named `random-NN`, each in its model's base variant.
fn random_cases(file: &Path, spec: &RandomSpec) -> Result<Vec<Case>> {
    if spec.count == 0 || spec.count > MAX_RANDOM_STACKS {
        return Err(bad(
            file,
            "reference.random.count",
            &format!("{}: allowed: 1 to {MAX_RANDOM_STACKS}", spec.count),
        ));
    }
    if let Some(paths) = spec.paths {
        if paths == 0 || paths > crate::reference::MAX_PATHS {
            return Err(bad(
                file,
                "reference.random.paths",
                &format!("{paths}: allowed: 1 to {}", crate::reference::MAX_PATHS),
            ));
        }
    }
    let ranges = PresetRanges::of_presets()?;
    let mut rng = Rng(case_seed(spec.seed, 0));
    Ok((0..spec.count)
        .map(|k| {
            let model = if k % 2 == 0 { Model::Tm2 } else { Model::Tm6 };
            let stack = preset_like_stack(&mut rng, &ranges, model, &format!("random-{k:02}"));
            let variant = stack.base_variant();
            Case { variant, stack }
        })
        .collect())
}

/// `reference.interfaces`: the truths, `single` when not given.
fn reference_interfaces(file: &Path, names: Option<&[String]>) -> Result<Vec<Interfaces>> {
    match names {
        None => Ok(vec![Interfaces::Single]),
        Some([]) => Err(bad(
            file,
            "reference.interfaces",
            &format!("empty: give one or more of {}", Interfaces::allowed()),
        )),
        Some(names) => names
            .iter()
            .map(|n| {
                Interfaces::parse_value(n)
                    .map_err(|e| bad(file, "reference.interfaces", &e.to_string()))
            })
            .collect(),
    }
}
