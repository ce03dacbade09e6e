//! The GPU model against the f64 CPU oracle, with the same FGD table on both sides (the GPU's
//! split-sum texels, sampled bilinearly on the CPU), so only the model arithmetic is compared.

mod common;

use lamina::model::{tm2, tm6, Evaluation, LayerParams, NoTir};
use lamina::render::eval::GpuEvaluator;
use lamina::shader::{Model, VariantKey};
use lamina::tables::tir::provider;

/// xorshift64*: a tiny seeded generator, enough for test cases.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

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
fn random_stack(rng: &mut Rng, model: Model) -> Vec<LayerParams> {
    let coats = (rng.next() * 4.0) as usize;
    let mut layers: Vec<LayerParams> = (0..coats)
        .map(|_| {
            let medium = model == Model::Tm6 && rng.next() < 0.7;
            LayerParams {
                ior: [rng.range(1.1, 2.2); 3],
                kappa: [0.0; 3],
                roughness: rng.range(0.02, 0.8),
                depth: if medium { rng.range(0.0, 1.5) } else { 0.0 },
                sigma_s: if medium {
                    [
                        rng.range(0.0, 2.0),
                        rng.range(0.0, 2.0),
                        rng.range(0.0, 2.0),
                    ]
                } else {
                    [0.0; 3]
                },
                sigma_a: if medium {
                    [
                        rng.range(0.0, 1.0),
                        rng.range(0.0, 1.0),
                        rng.range(0.0, 1.0),
                    ]
                } else {
                    [0.0; 3]
                },
                g: if medium { rng.range(-0.5, 0.9) } else { 0.0 },
            }
        })
        .collect();
    if layers.is_empty() || rng.next() < 0.8 {
        let (ior, kappa) = METALS[(rng.next() * METALS.len() as f64) as usize];
        layers.push(LayerParams {
            ior,
            kappa,
            roughness: rng.range(0.02, 0.8),
            depth: 0.0,
            sigma_s: [0.0; 3],
            sigma_a: [0.0; 3],
            g: 0.0,
        });
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
    ];
    let mut rng = Rng(0x1a3f_5c7e_9b2d_4f61);
    let mut cases = 0;
    let mut worst_overall = 0.0f64;
    for key in keys {
        let variant: VariantKey = key.parse().unwrap();
        let evaluator = GpuEvaluator::new(&gpu, variant).unwrap();
        let mut worst = 0.0f64;
        for _ in 0..25 {
            let stack = random_stack(&mut rng, variant.model);
            let cosines: Vec<f64> = (0..5).map(|_| rng.range(0.05, 1.0)).collect();
            let on_gpu = evaluator.evaluate(&stack, &cosines).unwrap();
            for (&mu, g) in cosines.iter().zip(&on_gpu) {
                let tir = provider(variant.tir, &evaluator.tir);
                let cpu = match variant.model {
                    Model::Tm6 => tm6::evaluate(&stack, mu, &evaluator.table, tir.as_ref()),
                    _ => tm2::evaluate(&stack, mu, &evaluator.table, tir.as_ref()),
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
    let slab = |ior: f64| LayerParams {
        ior: [ior; 3],
        kappa: [0.0; 3],
        roughness: 0.2,
        depth: 0.5,
        sigma_s: [0.8, 0.5, 0.3],
        sigma_a: [0.05, 0.1, 0.2],
        g: 0.3,
    };
    for n in [1usize, 3] {
        let variant: VariantKey = format!("model=tm6,max_layers={n}").parse().unwrap();
        let evaluator = GpuEvaluator::new(&gpu, variant).unwrap();
        let stack: Vec<LayerParams> = (0..n).map(|i| slab(1.3 + 0.2 * i as f64)).collect();
        let cosines = [0.2, 0.6, 1.0];
        let on_gpu = evaluator.evaluate(&stack, &cosines).unwrap();
        for (&mu, g) in cosines.iter().zip(&on_gpu) {
            let cpu = tm6::evaluate(&stack, mu, &evaluator.table, &NoTir);
            assert_eq!(cpu.lobes.len(), 6 * n - 2, "CPU lobe count at μ = {mu}");
            assert_eq!(evaluator.max_lobes(), 6 * n - 2);
            let err = compare(g, &cpu);
            assert!(
                err <= 1e-3,
                "n = {n}, μ = {mu}: {err:.2e}\nGPU {g:?}\nCPU {cpu:?}"
            );
        }
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn fp16_error_is_reported_and_results_are_finite() {
    let gpu = common::gpu();
    if !gpu.device.supports_fp16() {
        println!("skipped: {} has no shaderFloat16", gpu.device.report.name);
        return;
    }
    let mut rng = Rng(0x77aa_0123_4567_89ab);
    for key in ["model=tm2,fp16=on", "model=tm6,fp16=on"] {
        let variant: VariantKey = key.parse().unwrap();
        let evaluator = GpuEvaluator::new(&gpu, variant).unwrap();
        let mut worst = 0.0f64;
        for _ in 0..20 {
            let stack = random_stack(&mut rng, variant.model);
            let cosines: Vec<f64> = (0..5).map(|_| rng.range(0.05, 1.0)).collect();
            for (&mu, g) in cosines
                .iter()
                .zip(&evaluator.evaluate(&stack, &cosines).unwrap())
            {
                assert!(finite(g), "{key}: NaN/Inf for {stack:?} at {mu}");
                let cpu = match variant.model {
                    Model::Tm6 => tm6::evaluate(&stack, mu, &evaluator.table, &NoTir),
                    _ => tm2::evaluate(&stack, mu, &evaluator.table, &NoTir),
                };
                worst = worst.max(compare(g, &cpu));
            }
        }
        println!(
            "{key}: max relative error vs the f64 oracle {worst:.2e} (reported, not asserted)"
        );
    }
    common::assert_validation_clean(&gpu);
}
