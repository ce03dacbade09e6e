//! The FGD tables (issue #6): GPU values against the f64 references, the resampled table's
//! index arithmetic as the shader samples it, and the disk cache of the grids.

use crate::common;

use lamina::model::fgd::ExactFgd;
use lamina::model::{fresnel, Fgd as _};
use lamina::tables::belcour::Basis;
use lamina::tables::fgd::{
    self, BelcourTable, FgdImages, FgdLookup, FgdProbe, Filter, Grid, GridKind,
};
use lamina::tables::split_sum::SplitSumTable;
use lamina::variant::{Fgd, G2};

const G2_FORM: G2 = G2::HeightCorrelated;

#[test]
fn fgd_grids_match_the_f64_quadrature() {
    let gpu = common::gpu();
    // A small grid: the shader is the same at every size; the renderer's sample count.
    let grid = fgd::build_grid(
        &gpu,
        GridKind::Full4d,
        G2_FORM,
        8,
        fgd::GRID_SAMPLES,
        |_, _| {},
    )
    .unwrap();
    let exact = ExactFgd {
        g2: G2_FORM,
        resolution: 256,
    };
    // 1024 Hammersley points against a 256² midpoint rule of the same bounded integrand
    // (F·G2/G1 ≤ 1, visible-normal variables): smooth F converges to ~1e-4 on both sides; the
    // step of F at the critical angle (η < 1) leaves each ~5e-4 (measured against 4096²).
    let mut worst = 0.0f64;
    let mut points = 0;
    for (i, j, k, l) in [
        (1, 1, 2, 0),
        (2, 3, 5, 0),
        (7, 7, 1, 7),
        (3, 5, 7, 2),
        (5, 2, 3, 4),
        (7, 4, 6, 1),
        (4, 6, 4, 6),
        (1, 7, 2, 3),
        (6, 1, 1, 5),
        (2, 2, 7, 7),
        (3, 3, 3, 3),
        (5, 6, 2, 0),
        (7, 2, 5, 2),
        (4, 4, 1, 1),
        (6, 5, 6, 4),
        (1, 3, 4, 6),
    ] {
        let [mu, alpha, eta, kappa] = grid.coordinates(i, j, k, l);
        let cpu = exact.fgd(mu, alpha, eta, kappa);
        let gpu_v = f64::from(grid.texel(i, j, k, l));
        let err = (gpu_v - cpu).abs();
        assert!(
            err < 2e-3,
            "FGD({mu:.3}, {alpha:.3}, {eta:.3}, {kappa:.3}): GPU {gpu_v:.5}, f64 {cpu:.5}"
        );
        worst = worst.max(err);
        points += 1;
    }
    println!("4-D grid: {points} points, max |GPU − f64| = {worst:.2e}");

    // The η < 1 dielectric grid: at α = 0 it is Fresnel itself, total internal reflection
    // included; elsewhere within the same bound as above.
    let below = fgd::build_grid(
        &gpu,
        GridKind::DielectricBelow1,
        G2_FORM,
        8,
        fgd::GRID_SAMPLES,
        |_, _| {},
    )
    .unwrap();
    for i in 1..8 {
        for k in 1..8 {
            let [mu, _, eta, _] = below.coordinates(i, 0, k, 0);
            let want = fresnel::dielectric(mu, eta);
            let got = f64::from(below.texel(i, 0, k, 0));
            assert!((got - want).abs() < 1e-5, "μ {mu} η {eta}: {got} vs {want}");
        }
    }
    for (i, j, k) in [(2, 2, 5), (5, 3, 6), (7, 6, 4), (3, 7, 2)] {
        let [mu, alpha, eta, _] = below.coordinates(i, j, k, 0);
        let err = (f64::from(below.texel(i, j, k, 0)) - exact.fgd(mu, alpha, eta, 0.0)).abs();
        assert!(err < 2e-3, "η<1 grid at ({mu}, {alpha}, {eta}): {err}");
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn belcour_table_matches_its_f64_reference() {
    let gpu = common::gpu();
    let basis = Basis::fit();
    let table = BelcourTable::build(&gpu, G2_FORM, 16, fgd::BELCOUR_SAMPLES, Basis::fit()).unwrap();
    // 4096 samples as the renderer's table (the split-sum table's count, within ~1e-3).
    let mut points = 0;
    for i in [0, 3, 7, 11, 15] {
        for j in [0, 4, 9, 15] {
            let (mu, alpha) = table.coordinates(i, j);
            let cpu = fgd::belcour_reference(&basis, mu, alpha, G2_FORM, 256);
            let got = table.raw[(j * 16 + i) as usize];
            for k in 0..4 {
                let err = (f64::from(got[k]) - cpu[k]).abs();
                assert!(
                    err < 2e-3,
                    "L{k}({mu:.3}, {alpha:.3}): {} vs {}",
                    got[k],
                    cpu[k]
                );
            }
            points += 1;
        }
    }
    assert!(points >= 16);
    // ALGORITHMS.md §7.4's L0 = E_ss at μ = 1 (α = 0.1, 0.5, 1: 0.9883, 0.6878, 0.3069) from the
    // CPU twin, bilinear between texels.
    for (alpha, l0) in [(0.5, 0.6878), (1.0, 0.3069)] {
        let got = fgd::belcour_reference(&basis, 1.0, alpha, G2_FORM, 256)[0];
        assert!((got - l0).abs() < 2e-3, "L0(1, {alpha}) = {got}");
    }
    common::assert_validation_clean(&gpu);
}

/// Aluminium's κ (9.2, 6.3, 4.8) lies past the 4-D tables' κ ≤ 4. The shader carries FGD on
/// from the table's edge along the split sum's slope in F0, and its CPU twin does the same: both
/// come within 0.035 of the exact FGD (μ ≥ 0.2), where the edge's own value, what clamping κ
/// gave, is up to 0.22 off.
#[test]
fn beyond_the_4d_tables_kappa_fgd_goes_on_from_their_edge() {
    let gpu = common::gpu();
    let split = SplitSumTable::load_or_build(
        &gpu,
        G2_FORM,
        lamina::tables::split_sum::DEFAULT_SIZE,
        lamina::tables::split_sum::DEFAULT_SAMPLES,
    )
    .unwrap();
    let exact = ExactFgd {
        g2: G2_FORM,
        resolution: 256,
    };
    let aluminium = [(1.66058, 9.2282), (0.88143, 6.27077), (0.521467, 4.83803)];
    for mode in [Fgd::Full4d, Fgd::Resampled4d] {
        let images = FgdImages::for_variant(&gpu, mode, G2_FORM).unwrap();
        let twin = FgdLookup {
            twin: &images.twin,
            split_sum: &split,
        };
        let mut points = Vec::new();
        for (eta, kappa) in aluminium {
            for mu in [1.0, 0.5, 0.2] {
                for alpha in [0.01, 0.1, 0.3, 0.7] {
                    points.push([mu, alpha, eta, kappa]);
                }
            }
        }
        let probed: Vec<[f32; 4]> = points.iter().map(|p| p.map(|v| v as f32)).collect();
        let values = FgdProbe::new(&gpu, mode)
            .unwrap()
            .sample(&split, &images, &probed)
            .unwrap();
        let (mut worst, mut worst_edge) = (0.0f64, 0.0f64);
        for (&[mu, alpha, eta, kappa], got) in points.iter().zip(values) {
            let want = exact.fgd(mu, alpha, eta, kappa);
            let got = f64::from(got);
            let cpu = twin.fgd(mu, alpha, eta, kappa);
            assert!(
                (got - cpu).abs() < 2e-3,
                "{mode} at (μ, α, η, κ) = ({mu}, {alpha}, {eta}, {kappa}): shader {got:.4}, \
                 CPU twin {cpu:.4}"
            );
            worst = worst.max((got - want).abs());
            worst_edge = worst_edge.max((exact.fgd(mu, alpha, eta, fgd::KAPPA_MAX) - want).abs());
        }
        println!("{mode} beyond κ = 4: max |FGD − exact| {worst:.4}, the edge's {worst_edge:.4}");
        assert!(worst < 0.035, "{mode}: {worst} beyond the table");
        assert!(worst_edge > 0.15, "the edge alone is {worst_edge} off");
    }
    common::assert_validation_clean(&gpu);
}

/// Fills a 64⁴ grid with one of its coordinates.
fn coordinate_grid(axis: usize) -> Grid {
    let n = fgd::SIZE;
    let mut grid = Grid {
        dims: [n; 4],
        eta: (0.0, fgd::ETA_MAX),
        kappa: (0.0, fgd::KAPPA_MAX),
        samples: 0,
        texels: vec![0.0; (n as usize).pow(4)],
    };
    for l in 0..n {
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let v = grid.coordinates(i, j, k, l)[axis] as f32;
                    let index = grid.index(i, j, k, l);
                    grid.texels[index] = v;
                }
            }
        }
    }
    grid
}

#[test]
fn stacked_tables_read_back_their_coordinates_at_texel_centres() {
    let gpu = common::gpu();
    let split = SplitSumTable::load_or_build(&gpu, G2_FORM, 8, 16).unwrap();
    // The sampler's weights are exact to 2^-subTexelPrecisionBits; a lookup that lands on a
    // texel centre can leak at most that much of a neighbour, and the neighbour of the last η
    // texel of a stacked slice is the first of the next slice.
    let leak = 0.5f64.powi(gpu.device.report.sub_texel_precision_bits as i32);
    let n = fgd::SIZE;
    let step = 4.0 / f64::from(n - 1);
    for mode in [Fgd::Full4d, Fgd::Resampled4d] {
        let probe = FgdProbe::new(&gpu, mode).unwrap();
        for (axis, name) in [(0, "μ"), (1, "α"), (2, "η"), (3, "κ")] {
            let grid = coordinate_grid(axis);
            let images = FgdImages::stacked(&gpu, mode, &grid, Filter::Box).unwrap();
            let mut points = Vec::new();
            let mut expected = Vec::new();
            for k in [0, 1, 31, 62, 63] {
                for s in 0..n {
                    for (i, j) in [(1, 0), (17, 40), (63, 63)] {
                        let mut at = grid.coordinates(i, j, k, s);
                        let mut want = at[axis];
                        if mode == Fgd::Resampled4d {
                            // Slice m of the resampled table stands at κ index 2m + ½.
                            if s >= n / 2 {
                                continue;
                            }
                            at[3] = (2.0 * f64::from(s) + 0.5) * step;
                            if axis == 3 {
                                want = at[3];
                            }
                        }
                        points.push(at.map(|v| v as f32));
                        expected.push(want);
                    }
                }
            }
            let values = probe.sample(&split, &images, &points).unwrap();
            // Largest jump between stacked neighbours: the axis's range at slice boundaries.
            let jump = if axis == 2 { fgd::ETA_MAX } else { step };
            for ((p, want), got) in points.iter().zip(&expected).zip(&values) {
                let err = (f64::from(*got) - want).abs();
                assert!(
                    err <= leak * jump + 1e-5,
                    "{mode}: {name} at (μ, α, η, κ) = {p:?} reads {got}, expected {want}"
                );
            }
        }
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn grids_are_cached_by_their_parameters() {
    let gpu = common::gpu();
    let dir = common::scratch_dir("fgd-cache");
    let build = |n, samples| {
        fgd::load_or_build_grid(
            &gpu,
            GridKind::DielectricBelow1,
            G2_FORM,
            n,
            samples,
            Some(&dir),
            |_, _| {},
        )
        .unwrap()
    };
    let (first, cached) = build(4, 16);
    assert!(!cached);
    let (again, cached) = build(4, 16);
    assert!(cached);
    assert_eq!(first.texels, again.texels);
    assert!(!build(4, 32).1, "another sample count is another table");
    assert!(!build(5, 16).1, "another size is another table");
    let key = fgd::grid_cache_key(GridKind::DielectricBelow1, G2_FORM, 4, 16);
    let path = lamina::cache::path_of(&dir, &key);
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() - 5]).unwrap();
    assert!(!build(4, 16).1, "a truncated file is rebuilt");
    common::assert_validation_clean(&gpu);
}
