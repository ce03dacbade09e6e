//! Per-material pipelines shade what the generic one shades (issue 11 §5): the GPU evaluator
//! (`tm_eval.comp.glsl`, the forward pass's library) under `mode=specialized` and
//! `mode=specialized-values` against `mode=generic` (and the 6-flux walk one colour channel at a
//! time, `channels=serial`, in every mode), every preset under both models plus stacks
//! that take every structural branch (smooth interfaces, index-matched and clear interfaces,
//! TIR traps, media and none, with and without a conductor), at 256 view cosines from grazing to
//! normal; and a baked table's lobes against the model between its samples.

use crate::common;

use lamina::material::{presets, Stack};
use lamina::model::{hg, Evaluation, LayerParams};
use lamina::render::baked::{self, BakedTable};
use lamina::render::eval::GpuEvaluator;
use lamina::variant::{Mode, Model, VariantKey};

/// Relative agreement of the per-material pipelines with the generic one: they run the same
/// f32 arithmetic with branches and loads folded, so they differ by rounding only. R and T are
/// compared relative to themselves; a lobe's weight is a difference of two cumulative
/// reflectances (tm2.glsl, tm6.glsl), so its rounding is relative to the reflectance R of
/// that channel, not to the (possibly small) difference.
const RELATIVE: f64 = 1e-5;
/// Values this small are compared absolutely (a relative error of a denormal means nothing).
const FLOOR: f64 = 1e-6;

fn cosines() -> Vec<f64> {
    (0..256)
        .map(|i| 1e-4 + (1.0 - 1e-4) * f64::from(i) / 255.0)
        .collect()
}

fn layer(ior: f64, kappa: f64, roughness: f64, depth: f64) -> LayerParams {
    LayerParams::conductor(
        [ior, ior * 1.01, ior * 1.02],
        [kappa, kappa * 0.9, kappa * 0.8],
        roughness,
    )
    .with_medium(depth, [0.8, 1.2, 2.0], [0.05, 0.1, 0.3], 0.4)
}

/// Stacks that take every structural branch the specialization constants fold.
fn structural_stacks() -> Vec<(String, Vec<LayerParams>)> {
    vec![
        (
            "smooth coat over smooth gold".into(),
            vec![layer(1.5, 0.0, 0.0, 0.2), layer(0.2, 3.0, 0.0, 0.0)],
        ),
        (
            "index-matched and clear interfaces over a rough dielectric".into(),
            vec![
                layer(1.4, 0.0, 0.1, 0.3),
                layer(1.4, 0.0, 0.3, 0.0),
                layer(1.4004, 0.0, 0.2, 0.5),
                layer(1.2, 0.0, 0.05, 0.0),
            ],
        ),
        (
            "TIR trap: lighter layer under a dense one, over copper".into(),
            vec![
                layer(1.8, 0.0, 0.3, 0.1),
                layer(1.1, 0.0, 0.0, 0.4),
                layer(0.27, 2.8, 0.25, 0.0),
            ],
        ),
        (
            "dielectric slab, no base".into(),
            vec![layer(1.3, 0.0, 0.6, 1.0), layer(1.6, 0.0, 1.0, 0.0)],
        ),
    ]
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= RELATIVE * a.abs().max(b.abs()).max(FLOOR)
}

/// The first difference beyond tolerance between two evaluations, if any.
fn difference(generic: &Evaluation, other: &Evaluation) -> Option<String> {
    for c in 0..3 {
        for (what, a, b) in [
            ("R", generic.reflectance[c], other.reflectance[c]),
            ("T", generic.transmittance[c], other.transmittance[c]),
        ] {
            if !close(a, b) {
                return Some(format!("{what}[{c}]: generic {a:e}, other {b:e}"));
            }
        }
    }
    if generic.lobes.len() != other.lobes.len() {
        return Some(format!(
            "{} lobes against {}",
            generic.lobes.len(),
            other.lobes.len()
        ));
    }
    for (k, (a, b)) in generic.lobes.iter().zip(&other.lobes).enumerate() {
        for c in 0..3 {
            let scale = generic.reflectance[c].abs().max(FLOOR);
            if (a.weight[c] - b.weight[c]).abs() > RELATIVE * scale {
                return Some(format!(
                    "lobe {k} weight[{c}]: generic {:e}, other {:e}",
                    a.weight[c], b.weight[c]
                ));
            }
        }
        // A lobe's α matters where it carries light. It comes from the lobe's HG g, a
        // difference of g-weighted reflectances over the lobe's weight: rounding relative to
        // R, divided by the weight. It is compared as g (α(g) is steep near α = 1).
        let weight = (a.weight[0] + a.weight[1] + a.weight[2]) / 3.0;
        let r = (generic.reflectance[0] + generic.reflectance[1] + generic.reflectance[2]) / 3.0;
        if weight > FLOOR {
            let (ga, gb) = (hg::g_of_alpha(a.roughness), hg::g_of_alpha(b.roughness));
            if (ga - gb).abs() > RELATIVE * 2.0 * r / weight {
                return Some(format!(
                    "lobe {k} g: generic {ga:e}, other {gb:e} (α {:e}, {:e}; weight {weight:e})",
                    a.roughness, b.roughness
                ));
            }
        }
    }
    None
}

#[test]
fn specialized_pipelines_evaluate_what_the_generic_one_does() {
    let gpu = common::gpu();
    // Every preset specializes; `specialized-values` refuses a diffuse base (its constants
    // hold no albedo: tests/suite/diffuse.rs), so those stacks go through `specialized` only.
    let mut stacks: Vec<(String, Vec<LayerParams>)> = presets()
        .iter()
        .map(|p| {
            let s = Stack::load(p).unwrap();
            (s.name.clone(), s.params())
        })
        .collect();
    assert!(
        stacks
            .iter()
            .any(|(_, layers)| layers.iter().any(LayerParams::is_diffuse)),
        "no preset with a diffuse base"
    );
    assert!(stacks.len() >= 9, "the presets are missing");
    stacks.extend(structural_stacks());
    let cosines = cosines();
    let mut compared = 0;
    for model in [Model::Tm2, Model::Tm6] {
        let generic = GpuEvaluator::new(
            &gpu,
            VariantKey {
                model,
                max_layers: 16,
                ..VariantKey::default()
            },
        )
        .unwrap();
        // The 6-flux walk one channel at a time (`channels=serial`) runs the same arithmetic
        // per channel, in every mode.
        let serial: &[&str] = if model == Model::Tm6 {
            &[
                "mode=specialized,channels=serial",
                "mode=specialized-values,channels=serial",
                "max_layers=16,channels=serial",
            ]
        } else {
            &[]
        };
        for key in ["mode=specialized", "mode=specialized-values"]
            .iter()
            .chain(serial)
        {
            let variant = VariantKey::parse_over(
                key,
                VariantKey {
                    model,
                    ..VariantKey::default()
                },
            )
            .unwrap();
            let specialized = GpuEvaluator::new(&gpu, variant).unwrap();
            for (name, layers) in &stacks {
                if variant.mode == Mode::SpecializedValues
                    && layers.iter().any(LayerParams::is_diffuse)
                {
                    continue;
                }
                let a = generic.evaluate(layers, &cosines).unwrap();
                let b = specialized.evaluate(layers, &cosines).unwrap();
                for ((mu, a), b) in cosines.iter().zip(&a).zip(&b) {
                    if let Some(d) = difference(a, b) {
                        panic!("{name}, {variant}, cos θ = {mu}: {d}");
                    }
                    compared += 1;
                }
            }
        }
    }
    println!("{compared} evaluations agree within {RELATIVE:e} relative");
    common::assert_validation_clean(&gpu);
}

/// A baked table's lobes between its samples against the model there, per table size
/// (`baked::max_lobe_error`): the largest table is closer than the smallest, and the default
/// size is within 1e-3 on every preset. Between, the error need not fall at every step: it
/// comes from kinks of the model near grazing, whose place within a table interval varies.
#[test]
fn baked_lobes_follow_the_model_between_samples() {
    let gpu = common::gpu();
    let probes = baked::probe_cosines();
    for path in presets() {
        let stack = Stack::load(&path).unwrap();
        let layers = stack.params();
        let variant = VariantKey {
            model: stack.model,
            ..VariantKey::default()
        };
        let evaluator = baked::evaluator_for(&gpu, variant, layers.len()).unwrap();
        let exact = evaluator.evaluate(&layers, &probes).unwrap();
        let mut errors = Vec::new();
        for size in baked::STUDY_SIZES {
            let table = BakedTable::build(&evaluator, &layers, size).unwrap();
            let error = baked::max_lobe_error(&table, &probes, &exact);
            println!(
                "{:<18} size {size:>3}: max lobe error {error:.2e}",
                stack.name
            );
            errors.push(error);
            if size == baked::DEFAULT_SIZE {
                assert!(
                    error <= 1e-3,
                    "{}: the default size {size} is {error:e} off",
                    stack.name
                );
            }
        }
        let last = errors.len() - 1;
        assert!(
            errors[last] < errors[0],
            "{}: {} samples ({:e}) no closer than {} ({:e})",
            stack.name,
            baked::STUDY_SIZES[last],
            errors[last],
            baked::STUDY_SIZES[0],
            errors[0]
        );
    }
    common::assert_validation_clean(&gpu);
}
