//! The prefiltered environment and the split-sum table against CPU references.

use crate::common;

use glam::DVec3;
use lamina::tables::environment::{self, EnvDesc, Environment, Weighting};
use lamina::tables::split_sum::{self, SplitSumTable};
use lamina::variant::G2;

fn luminance(c: [f32; 4]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

#[test]
fn prefiltered_mip0_matches_source_and_mips_get_smoother() {
    let gpu = common::gpu();
    let studio = common::studio();
    let desc = EnvDesc {
        face_size: 128,
        mip_count: 6,
        samples: 64,
    };
    let mut env = Environment::build(&gpu, &studio, desc).unwrap();

    let mip0 = env.read_mip(&gpu, Weighting::Karis, 0).unwrap();
    let n = desc.face_size;
    // Per-texel bound, in units of the spread of the four texels a bilinear lookup blends:
    // the sampler's fixed-point weights (subTexelPrecisionBits) move the blend by up to
    // spread·2⁻ᵇ, and the texel coordinate, computed in f32 through atan/acos (polynomial
    // approximations on lavapipe), is off by up to 0.023 texel (measured), bounded here by 1/32.
    // The value is also rounded to half twice (upload and cube store): 2⁻¹⁰ relative.
    let weight_step = 0.5f64.powi(gpu.device.report.sub_texel_precision_bits as i32) + 1.0 / 32.0;
    let mut errors = Vec::new();
    let mut outside = 0usize;
    let mut worst_outlier = 0.0f64;
    for face in 0..6 {
        for j in 0..n {
            for i in 0..n {
                let u = (f64::from(i) + 0.5) / f64::from(n);
                let v = (f64::from(j) + 0.5) / f64::from(n);
                let d: DVec3 = environment::cube_direction(face, u, v);
                let (eu, ev) = environment::equirect_uv(d);
                let want = environment::sample_bilinear(&studio, eu, ev);
                let got = mip0[((face * n + j) * n + i) as usize];
                for ((&g, value), spread) in got.iter().zip(want.value).zip(want.spread) {
                    let err = (f64::from(g) - value).abs();
                    let bound = spread * weight_step + value.abs() * 2f64.powi(-10) + 1e-6;
                    if err > bound {
                        outside += 1;
                        worst_outlier = worst_outlier.max(err / value.abs().max(1e-3));
                    }
                    errors.push(err / (value.abs() + 1e-2));
                }
            }
        }
    }
    errors.sort_by(f64::total_cmp);
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    let p999 = errors[(errors.len() as f64 * 0.999) as usize];
    println!(
        "mip 0 vs source: mean relative error {mean:.5}, 99.9th percentile {p999:.5}, \
         {outside} of {} values outside the per-texel bound (worst by {worst_outlier:.4} relative)",
        errors.len()
    );
    // On lavapipe 19 of 294912 values (all on the ±X faces, at most 3% off, measured) exceed the
    // per-texel bound; their cause is not yet understood (recorded on issue #2), so they are
    // bounded here by count and size rather than hidden in a wider per-texel tolerance.
    assert!(
        (outside as f64) < 1e-4 * errors.len() as f64,
        "{outside} values outside the sampler-precision bound"
    );
    assert!(
        worst_outlier < 5e-2,
        "an outlier is {worst_outlier} off, relative"
    );
    assert!(mean < 2e-3, "mean relative error {mean}");

    // Both cubes: mip 0 the source's, every mip smoother than the one above; the matched
    // cube's mips below the first differ from Karis's (their weights do).
    env.build_matched(&gpu).unwrap();
    for weighting in [Weighting::Karis, Weighting::Matched] {
        let mut variances = Vec::new();
        for mip in 0..desc.mip_count {
            let texels = env.read_mip(&gpu, weighting, mip).unwrap();
            let karis = env.read_mip(&gpu, Weighting::Karis, mip).unwrap();
            assert_eq!(
                texels == karis,
                mip == 0 || weighting == Weighting::Karis,
                "{weighting:?} mip {mip}"
            );
            let lum: Vec<f64> = texels.iter().map(|&t| luminance(t)).collect();
            let mean = lum.iter().sum::<f64>() / lum.len() as f64;
            let var = lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lum.len() as f64;
            println!("{weighting:?} mip {mip}: mean luminance {mean:.4}, variance {var:.6}");
            variances.push(var);
        }
        for (m, pair) in variances.windows(2).enumerate() {
            assert!(
                pair[1] < pair[0],
                "{weighting:?}: mip {} is not smoother than mip {m}",
                m + 1
            );
        }
    }
    common::assert_validation_clean(&gpu);
}

/// One step of a half float relative to a value in [0.5, 1), the most a cube's texel may be
/// off: an image store may convert to half rounding towards zero (Vulkan's conversion rules
/// allow it; lavapipe does), so a weighted mean of equal values an f32 rounding below them
/// is stored a whole step below.
const HALF_STEP: f64 = 1.0 / 1024.0;

/// A uniform environment prefilters to itself, within the cubes' half-float step, in every
/// texel of every mip of both cubes.
#[test]
fn a_uniform_environment_prefilters_to_itself_in_both_cubes() {
    let gpu = common::gpu();
    let uniform = lamina::imageio::HdrImage {
        width: 64,
        height: 32,
        pixels: vec![[0.75, 0.75, 0.75, 1.0]; 64 * 32],
    };
    let desc = EnvDesc {
        face_size: 32,
        mip_count: 5,
        samples: 16,
    };
    let mut env = Environment::build(&gpu, &uniform, desc).unwrap();
    env.build_matched(&gpu).unwrap();
    for weighting in [Weighting::Karis, Weighting::Matched] {
        for mip in 0..desc.mip_count {
            let texels = env.read_mip(&gpu, weighting, mip).unwrap();
            let off = texels
                .iter()
                .flat_map(|t| &t[..3])
                .map(|&c| (f64::from(c) - 0.75).abs())
                .fold(0.0, f64::max);
            assert!(
                off <= HALF_STEP * 0.75,
                "{weighting:?} mip {mip}: a texel {off:e} off"
            );
        }
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn split_sum_table_matches_cpu_monte_carlo() {
    let gpu = common::gpu();
    let table = SplitSumTable::build(
        &gpu,
        G2::HeightCorrelated,
        split_sum::DEFAULT_SIZE,
        split_sum::DEFAULT_SAMPLES,
    )
    .unwrap();
    let points = [
        (0, 0),
        (1, 5),
        (5, 40),
        (13, 63),
        (20, 10),
        (31, 31),
        (40, 55),
        (50, 2),
        (63, 63),
        (63, 20),
        (10, 25),
        (58, 45),
        (7, 60),
        (25, 48),
        (45, 8),
        (60, 33),
    ];
    // 4096 Hammersley points of a bounded integrand against a 256² midpoint rule: both within
    // ~1e-3 of the integral (split_sum::DEFAULT_SAMPLES).
    let mut worst = 0.0f64;
    for (i, j) in points {
        let (mu, alpha) = table.coordinates(i, j);
        let want = split_sum::cpu_reference(mu, alpha, G2::HeightCorrelated, 256);
        let got = table.texel(i, j);
        for c in 0..2 {
            let err = (got[c] as f64 - want[c]).abs();
            worst = worst.max(err);
            assert!(
                err < 2e-3,
                "texel ({i}, {j}) μ={mu:.3} α={alpha:.4}: GPU {got:?} vs CPU {want:?}"
            );
        }
    }
    println!(
        "split-sum GPU vs CPU: max abs error {worst:.2e} over {} points",
        points.len()
    );
    common::assert_validation_clean(&gpu);
}
