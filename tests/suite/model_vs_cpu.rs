//! The GPU model against the f64 CPU oracle, with the same FGD table on both sides (the GPU's
//! split-sum texels, sampled bilinearly on the CPU), so only the model arithmetic is compared.

use crate::common;

use lamina::material::random::random_stack;
use lamina::model::hg;
use lamina::model::random::{case_seed, Rng};
use lamina::model::{
    tm2, tm6, Evaluation, LayerParams, NoTir, INDEX_MATCHED, IOR_AIR, REFLECTS_NOTHING,
};
use lamina::render::eval::{GpuEvaluator, Tolerance};
use lamina::variant::{Model, VariantKey};

/// Metals of ALGORITHMS.md §12.2 (Au, Ag, Al, Cu, Cr).
const METALS: [([f64; 3], [f64; 3]); 5] = [
    ([0.143245, 0.377423, 1.43919], [3.98479, 2.3847, 1.60434]),
    ([0.15554, 0.11678, 0.138371], [4.83139, 3.12331, 2.14745]),
    ([1.66058, 0.88143, 0.521467], [9.2282, 6.27077, 4.83803]),
    ([0.208183, 0.919438, 1.10241], [3.92198, 2.45627, 2.14157]),
    ([4.48917, 2.90664, 1.66205], [5.21625, 4.22766, 3.75206]),
];

/// A random physically sensible stack of 1..=4 layers: dielectric coats (media in 6-flux),
/// usually over a metal.
fn sensible_stack(rng: &mut Rng, model: Model) -> Vec<LayerParams> {
    let coats = (rng.unit() * 4.0) as usize;
    let mut layers: Vec<LayerParams> = (0..coats)
        .map(|_| {
            let medium = model == Model::Tm6 && rng.unit() < 0.7;
            // Drawn in this order: η, α, then the medium's depth, σs, σa and g.
            let coat = LayerParams::dielectric(rng.range(1.1, 2.2), rng.range(0.02, 0.8));
            if !medium {
                return coat;
            }
            let depth = rng.range(0.0, 1.5);
            let sigma_s = [(); 3].map(|_| rng.range(0.0, 2.0));
            let sigma_a = [(); 3].map(|_| rng.range(0.0, 1.0));
            coat.with_medium(depth, sigma_s, sigma_a, rng.range(-0.5, 0.9))
        })
        .collect();
    if layers.is_empty() || rng.unit() < 0.8 {
        let (ior, kappa) = METALS[(rng.unit() * METALS.len() as f64) as usize];
        layers.push(LayerParams::conductor(ior, kappa, rng.range(0.02, 0.8)));
    }
    layers
}

/// Relative error, with values below `floor` compared absolutely against it.
fn relative(gpu: f64, cpu: f64, floor: f64) -> f64 {
    (gpu - cpu).abs() / cpu.abs().max(floor)
}

/// Worst relative error over reflectance and lobe weights.
fn compare(gpu: &Evaluation, cpu: &Evaluation) -> f64 {
    assert_eq!(gpu.lobes.len(), cpu.lobes.len(), "lobe counts differ");
    let mut worst = 0.0f64;
    for c in 0..3 {
        worst = worst.max(relative(gpu.reflectance[c], cpu.reflectance[c], 1e-3));
        worst = worst.max(relative(gpu.transmittance[c], cpu.transmittance[c], 1e-3));
        for (g, l) in gpu.lobes.iter().zip(&cpu.lobes) {
            worst = worst.max(relative(g.weight[c], l.weight[c], 1e-3));
        }
    }
    worst
}

fn finite(e: &Evaluation) -> bool {
    e.reflectance
        .iter()
        .chain(&e.transmittance)
        .all(|v| v.is_finite())
        && e.lobes
            .iter()
            .all(|l| l.roughness.is_finite() && l.weight.iter().all(|v| v.is_finite()))
}

#[test]
fn gpu_matches_cpu_oracle_on_random_cases() {
    let gpu = common::gpu();
    let keys = [
        "model=tm2",
        "model=tm2,g2=smith",
        "model=tm2,ndf=karis,max_layers=8",
        "model=tm2,g2=schlick",
        "model=tm6",
        "model=tm6,g2=smith",
        "model=tm6,ndf=karis,max_layers=8",
        "model=tm6,g2=earl",
        "model=tm2,tir=lut32",
        "model=tm2,tir=lut16,g2=smith",
        "model=tm2,tir=constant",
        "model=tm2,tir=analytic",
        "model=tm6,tir=lut32",
        "model=tm6,tir=analytic",
        "model=tm2,tir=fit",
        "model=tm6,tir=fit",
    ];
    let mut rng = Rng(0x1a3f_5c7e_9b2d_4f61);
    let mut cases = 0;
    let mut worst_overall = 0.0f64;
    for key in keys {
        let variant: VariantKey = key.parse().unwrap();
        let evaluator = GpuEvaluator::new(&gpu, variant).unwrap();
        let mut worst = 0.0f64;
        for _ in 0..25 {
            let stack = sensible_stack(&mut rng, variant.model);
            let cosines: Vec<f64> = (0..5).map(|_| rng.range(0.05, 1.0)).collect();
            let on_gpu = evaluator.evaluate(&stack, &cosines).unwrap();
            for (&mu, g) in cosines.iter().zip(&on_gpu) {
                let tir = evaluator.tir_lookup();
                let fgd = evaluator.fgd_lookup();
                let cpu = match variant.model {
                    Model::Tm6 => tm6::evaluate(&stack, mu, &fgd, tir.as_ref()),
                    _ => tm2::evaluate(&stack, mu, &fgd, tir.as_ref()),
                };
                assert!(
                    finite(g),
                    "{key}: non-finite GPU result for {stack:?} at {mu}"
                );
                assert_eq!(
                    g.lobes.len(),
                    cpu.lobes.len(),
                    "{key}: lobe counts for {stack:?} at {mu}\nGPU {g:?}\nCPU {cpu:?}"
                );
                let err = compare(g, &cpu);
                assert!(
                    err <= 1e-3,
                    "{key}: relative error {err:.2e} at μ = {mu} for {stack:?}\nGPU {g:?}\nCPU {cpu:?}"
                );
                worst = worst.max(err);
                cases += 1;
            }
        }
        println!("{key}: max relative error {worst:.2e}");
        worst_overall = worst_overall.max(worst);
    }
    println!("{cases} cases, max relative error {worst_overall:.2e} (bound 1e-3)");
    assert!(cases >= 1000);
    common::assert_validation_clean(&gpu);
}

/// The most lobes the 6-flux model emits: dielectric layers that all hold a medium, no
/// substrate (6n − 2 for n layers). The GPU's output has room for every one of them.
#[test]
fn six_flux_emits_its_largest_lobe_count_on_the_gpu() {
    let gpu = common::gpu();
    let slab = |ior: f64| {
        LayerParams::dielectric(ior, 0.2).with_medium(0.5, [0.8, 0.5, 0.3], [0.05, 0.1, 0.2], 0.3)
    };
    for n in [1usize, 3] {
        let variant: VariantKey = format!("model=tm6,max_layers={n}").parse().unwrap();
        let evaluator = GpuEvaluator::new(&gpu, variant).unwrap();
        let stack: Vec<LayerParams> = (0..n).map(|i| slab(1.3 + 0.2 * i as f64)).collect();
        let cosines = [0.2, 0.6, 1.0];
        let on_gpu = evaluator.evaluate(&stack, &cosines).unwrap();
        for (&mu, g) in cosines.iter().zip(&on_gpu) {
            let cpu = tm6::evaluate(&stack, mu, &evaluator.fgd_lookup(), &NoTir);
            assert_eq!(cpu.lobes.len(), 6 * n - 2, "CPU lobe count at μ = {mu}");
            assert_eq!(evaluator.max_lobes(n), 6 * n - 2);
            let err = compare(g, &cpu);
            assert!(
                err <= 1e-3,
                "n = {n}, μ = {mu}: {err:.2e}\nGPU {g:?}\nCPU {cpu:?}"
            );
        }
    }
    common::assert_validation_clean(&gpu);
}

/// Variants that cover every value of every axis, fp16 included. The 4-D FGD tables are the
/// default G2 form's: the other forms pair with the cheaper tables (each 4-D grid is 64⁴
/// texels of 1024 samples, about 50 s on two cores of lavapipe; the GPU-vs-CPU comparison of
/// the model does not depend on which form built the table both sides read).
const VARIANTS: [&str; 28] = [
    "model=tm2,max_layers=16",
    "model=tm6,max_layers=16",
    "model=tm2,max_layers=4,fp16=on",
    "model=tm6,max_layers=4,fp16=on",
    "model=tm2,tir=constant,max_layers=8",
    "model=tm6,tir=constant,max_layers=8",
    "model=tm2,tir=analytic,fgd=belcour,g2=smith",
    "model=tm6,tir=analytic,fgd=belcour",
    "model=tm2,tir=lut32,fgd=4d",
    "model=tm6,tir=lut32,fgd=4d",
    "model=tm2,tir=lut16,fgd=resampled4d",
    "model=tm6,tir=lut16,fgd=resampled4d",
    "model=tm2,tir=lut32,g2=earl,ndf=karis",
    "model=tm6,tir=lut32,g2=earl,ndf=karis",
    "model=tm2,tir=lut32,fp16=on",
    "model=tm6,tir=lut32,fp16=on",
    "model=tm2,tir=analytic,fgd=4d,fp16=on",
    "model=tm6,tir=analytic,fgd=4d,fp16=on",
    "model=tm2,tir=constant,fgd=belcour,fp16=on,max_layers=8",
    "model=tm6,tir=constant,fgd=belcour,fp16=on,max_layers=8",
    "model=tm2,tir=lut16,fgd=resampled4d,fp16=on",
    "model=tm6,tir=lut16,fgd=resampled4d,fp16=on",
    "model=tm2,max_layers=1,g2=schlick",
    "model=tm6,max_layers=2,g2=smith",
    "model=tm2,tir=fit,fgd=4d,fp16=on",
    "model=tm6,tir=fit,g2=schlick",
    "model=tm6,channels=serial,max_layers=8",
    "model=tm6,channels=serial,tir=lut32,fp16=on",
];

#[test]
fn random_valid_stacks_match_the_oracle_in_every_2_flux_variant() {
    random_valid_stacks_match_the_oracle(Model::Tm2);
}

#[test]
fn random_valid_stacks_match_the_oracle_in_every_6_flux_variant() {
    random_valid_stacks_match_the_oracle(Model::Tm6);
}

/// Random valid stacks over the whole documented parameter space (range ends, grazing
/// angles, thick media, TIR traps) in every variant of `model`, fp16 included: every GPU value
/// finite and within the documented tolerance of the f64 model run with the very same tables.
/// A model per test, so that both models' shaders compile side by side.
fn random_valid_stacks_match_the_oracle(model: Model) {
    let seed = std::env::var("LAMINA_PROPERTY_SEED")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .unwrap_or(0x6a1d_e5ee_d202_6112);
    println!("seed: {seed} (LAMINA_PROPERTY_SEED={seed} replays it)");
    let gpu = common::gpu();
    let (mut cases, mut ambiguous) = (0, 0);
    for (v, key) in VARIANTS.iter().enumerate() {
        let variant: VariantKey = key.parse().unwrap();
        if variant.model != model {
            continue;
        }
        if variant.fp16 && !gpu.device.supports_fp16() {
            println!(
                "{key}: skipped, {} has no shaderFloat16",
                gpu.device.report.name
            );
            continue;
        }
        let evaluator = GpuEvaluator::new(&gpu, variant).unwrap();
        let fgd = evaluator.fgd_lookup();
        let tir = evaluator.tir_lookup();
        let tolerance = Tolerance::of(variant);
        let (mut worst_energy, mut worst_alpha) = (0.0f64, 0.0f64);
        for k in 0..100 {
            let mut rng = Rng(case_seed(seed, v * 1000 + k));
            let (stack, mu) =
                random_stack(&mut rng, Some(variant.model), variant.max_layers as usize);
            if at_a_threshold(&stack.layers) {
                ambiguous += 1;
                continue;
            }
            let cosines = [mu, 1e-4, 1.0];
            let on_gpu = evaluator.evaluate(&stack.layers, &cosines).unwrap();
            for (&mu, g) in cosines.iter().zip(&on_gpu) {
                let cpu = match variant.model {
                    Model::Tm6 => tm6::evaluate(&stack.layers, mu, &fgd, tir.as_ref()),
                    _ => tm2::evaluate(&stack.layers, mu, &fgd, tir.as_ref()),
                };
                let context = || {
                    format!(
                        "{key}, case {k}, μ = {mu}\nGPU {g:?}\nCPU {cpu:?}\n{}",
                        stack.to_toml()
                    )
                };
                assert!(finite(g), "non-finite GPU values: {}", context());
                assert_eq!(g.lobes.len(), cpu.lobes.len(), "lobe counts: {}", context());
                let (energy, alpha) = differences(g, &cpu);
                assert!(
                    energy <= tolerance.energy && alpha <= tolerance.lobe_g,
                    "|Δ energy| {energy:.2e}, |Δg| {alpha:.2e} beyond {tolerance:?}: {}",
                    context()
                );
                worst_energy = worst_energy.max(energy);
                worst_alpha = worst_alpha.max(alpha);
                cases += 1;
            }
        }
        println!(
            "{key}: max |Δ energy| {worst_energy:.2e}, max |Δg| {worst_alpha:.2e} (bounds {:.0e}, {:.0e})",
            tolerance.energy, tolerance.lobe_g
        );
    }
    println!("{model}: {cases} cases; {ambiguous} stacks left out at a model threshold");
    // 13 variants of 100 stacks at 3 cosines each, less the stacks at a threshold.
    assert!(cases >= 1000);
    common::assert_validation_clean(&gpu);
}

/// Whether an interface's relative IOR lies within f32 rounding of one of the model's
/// thresholds ([`INDEX_MATCHED`], [`REFLECTS_NOTHING`]): there the f32 shader and the f64 model
/// may legitimately take different branches, and the model is discontinuous.
fn at_a_threshold(layers: &[LayerParams]) -> bool {
    let mut eta_above = IOR_AIR;
    for layer in layers.iter().filter(|l| !l.is_conductor()) {
        let eta_layer = layer.ior.iter().sum::<f64>() / 3.0;
        let off = (eta_layer / eta_above - 1.0).abs();
        if [INDEX_MATCHED, REFLECTS_NOTHING]
            .iter()
            .any(|t| (off - t).abs() < 1e-6)
        {
            return true;
        }
        if off >= INDEX_MATCHED {
            eta_above = eta_layer;
        }
    }
    false
}

/// Largest absolute difference of the energies (R, T, lobe weights) and of the HG g of the
/// lobes that carry at least 1 % of the light, the transmitted one included (their α as g:
/// α(g) is steep near α = 1, where a g off by 5e-4 moves α by 2.5e-3).
fn differences(gpu: &Evaluation, cpu: &Evaluation) -> (f64, f64) {
    let mut energy = 0.0f64;
    let mut alpha = 0.0f64;
    for c in 0..3 {
        energy = energy.max((gpu.reflectance[c] - cpu.reflectance[c]).abs());
        energy = energy.max((gpu.transmittance[c] - cpu.transmittance[c]).abs());
        for (g, l) in gpu.lobes.iter().zip(&cpu.lobes) {
            energy = energy.max((g.weight[c] - l.weight[c]).abs());
        }
    }
    for (g, l) in gpu.lobes.iter().zip(&cpu.lobes) {
        if l.weight.iter().sum::<f64>() / 3.0 >= 0.01 {
            let lobe_g = |alpha: f64| hg::g_of_alpha(alpha);
            alpha = alpha.max((lobe_g(g.roughness) - lobe_g(l.roughness)).abs());
        }
    }
    if cpu.transmittance.iter().sum::<f64>() / 3.0 >= 0.01 {
        let (g, l) = (gpu.transmitted_roughness, cpu.transmitted_roughness);
        alpha = alpha.max((hg::g_of_alpha(g) - hg::g_of_alpha(l)).abs());
    }
    (energy, alpha)
}

/// `transport=corrected` on the GPU against its CPU twin (the same ratios, built from the same
/// tables' twins, applied to the f64 model): both models, both interface modes, generic and
/// specialized, over coated, transmissive, diffuse-based and 6-flux presets, from normal to
/// grazing view.
#[test]
fn the_corrected_transport_matches_its_cpu_twin() {
    use lamina::material::Stack;
    use lamina::model::oracle::evaluate_variant;

    let gpu = common::gpu();
    let cases: [(&str, &[&str]); 4] = [
        (
            "model=tm2,max_layers=5,transport=corrected",
            &["varnished-gold", "five-layers", "glazed-ceramic"],
        ),
        (
            "model=tm2,mode=specialized,transport=corrected,interfaces=multiple",
            &["lacquered-copper"],
        ),
        (
            "model=tm6,transport=corrected",
            &["dusty-varnish", "absorbing-film"],
        ),
        (
            "model=tm6,tir=lut32,mode=specialized,transport=corrected",
            &["patina-bronze"],
        ),
    ];
    let cosines = [1.0, 0.7, 0.4, 0.15, 0.03];
    for (key, materials) in cases {
        let variant: VariantKey = key.parse().unwrap();
        for material in materials {
            let layers = Stack::resolve(material).unwrap().params();
            let evaluator = GpuEvaluator::new(&gpu, variant).unwrap();
            let on_gpu = evaluator.evaluate(&layers, &cosines).unwrap();
            let fgd = evaluator.fgd_lookup();
            let tir = evaluator.tir_lookup();
            let on_cpu = evaluate_variant(variant, &layers, &cosines, &fgd, tir.as_ref());
            let paper = evaluate_variant(
                VariantKey {
                    transport: lamina::variant::Transport::Paper,
                    interfaces: lamina::variant::Interfaces::Single,
                    ..variant
                },
                &layers,
                &cosines,
                &fgd,
                tir.as_ref(),
            );
            for ((g, c), (p, mu)) in on_gpu.iter().zip(&on_cpu).zip(paper.iter().zip(cosines)) {
                assert!(finite(g), "{key} {material} μ {mu}: {g:?}");
                let err = compare(g, c);
                assert!(
                    err <= 1e-3,
                    "{key} {material} μ {mu}: relative error {err:.2e}\nGPU {g:?}\nCPU {c:?}"
                );
                // The top's Fresnel lobe: the same lobe, interface and albedo.
                match (g.top_fresnel, c.top_fresnel) {
                    (Some(a), Some(b)) => assert!(
                        a.lobe == b.lobe
                            && (a.eta - b.eta).abs() < 1e-5
                            && (a.albedo - b.albedo).abs() <= 1e-3 * b.albedo.max(1e-2),
                        "{key} {material} μ {mu}: the top's Fresnel lobe {a:?} vs {b:?}"
                    ),
                    (None, None) => {}
                    other => panic!("{key} {material} μ {mu}: the top's Fresnel lobe {other:?}"),
                }
                // The transport changes the energies (coated stacks: by more than the bound).
                if material != &"glazed-ceramic" {
                    assert!(
                        compare(c, p) > 1e-3,
                        "{key} {material} μ {mu}: same as paper"
                    );
                }
            }
        }
    }
    common::assert_validation_clean(&gpu);
}
