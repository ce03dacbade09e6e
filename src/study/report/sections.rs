//! The report's sections of a study beyond its runs table: its targets, the talk's figures,
//! the baked tables' errors, the image errors against the reference with the Pareto front,
//! a `[reference]` study's comparison with the stochastic reference, and fitted lines.

use std::fmt::Write as _;
use std::path::Path;

use crate::profile::image_error::{error_map_path, fp32_error_map_path};
use crate::profile::results::{ImageError, Run};
use crate::reference::compare::{MaterialReference, ReferenceRow};
use crate::render::reference::Truth;
use crate::study::charts::{pareto_front, reference_chart_stem, run_label, SIGNIFICANT_FLOORS};
use crate::study::dirs::StudyDir;
use crate::study::{Published, Target};

use super::ratios::{
    fmt_per_pixel, fmt_ratio, jit_basis, jit_ratio, linear_fit, main_ratio, per_pixel, TIME_BASIS,
};
use super::{embed_charts, relative};

/// The measured ratio of a `[[target]]`: (ratio, basis, the run, the divisor).
pub(super) fn target_ratio<'a>(
    s: &'a StudyDir,
    t: &Target,
) -> Option<(f64, &'static str, &'a Run, &'a Run)> {
    let r = &s.results;
    // The ggx baseline answers a pattern only when the pattern names it: `mode=generic,
    // max_layers=2` means the study's own generic run, not the baseline that shares its axes.
    let on = |pattern: &str, material: &str| {
        let wants_ggx = pattern.split(',').any(|p| p.trim() == "model=ggx");
        r.runs.iter().find(|run| {
            run.material == material
                && run.variant.matches(pattern)
                && (wants_ggx || !run.is_baseline())
        })
    };
    let run = on(&t.matches, &t.material)?;
    let other = t.against_material.as_deref().unwrap_or(&t.material);
    let against = match &t.against {
        Some(pattern) => on(pattern, other)?,
        None => r.baseline_of(other)?,
    };
    let (ratio, basis) = main_ratio(r, run, against);
    Some((ratio, basis, run, against))
}

/// A target's measured ratio as the report prints it, and its verdict: met, or missed and by
/// how much. A ratio of times is judged within the target's stated `tolerance` (a timing's
/// noise), and gets no verdict without one; a count is deterministic and judged as it is.
/// The printed ratio has the digits that show a miss the verdict states (1.0004× missing
/// ≤ 1.00×, not 1.00×).
pub(super) fn target_verdict(ratio: f64, basis: &str, t: &Target) -> (String, String) {
    // The fewest decimals (two at least) at which a ratio above the bound prints above it.
    let decimals = (2..=8)
        .find(|&d| ratio <= t.max || round_to(ratio, d) > round_to(t.max, d))
        .unwrap_or(8);
    let measured = format!("{ratio:.decimals$}× ({basis})");
    let tolerance = match (basis == TIME_BASIS, t.tolerance) {
        (true, None) => {
            return (
                measured,
                "no verdict: a ratio of times needs the target's `tolerance`".into(),
            )
        }
        (true, Some(tolerance)) => tolerance,
        (false, _) => 0.0,
    };
    let verdict = if ratio <= t.max {
        "met".into()
    } else if ratio <= t.max * (1.0 + tolerance) {
        format!("met within the stated {:.0} % tolerance", tolerance * 100.0)
    } else {
        let percent = (ratio / t.max - 1.0) * 100.0;
        // Below 1 %, the decimals that show the first significant digit (two at least), so a
        // narrow miss never reads as 0.00 %.
        let digits = if percent >= 1.0 {
            0
        } else {
            (-percent.log10().floor()).max(2.0) as usize
        };
        format!("missed by {percent:.digits$} %")
    };
    (measured, verdict)
}

/// `x` rounded to `decimals` decimals.
fn round_to(x: f64, decimals: usize) -> f64 {
    let scale = 10f64.powi(decimals as i32);
    (x * scale).round() / scale
}

pub(super) fn targets_section(md: &mut String, s: &StudyDir) {
    let _ = writeln!(
        md,
        "Targets (a ratio bound per row; the study records them, nothing fails on them):\n"
    );
    let _ = writeln!(md, "| target | run | against | measured | bound | |");
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for t in &s.meta.targets {
        match target_ratio(s, t) {
            Some((ratio, basis, run, against)) => {
                let (measured, verdict) = target_verdict(ratio, basis, t);
                let on = match &t.against_material {
                    Some(m) => format!(" on {m}"),
                    None => String::new(),
                };
                let _ = writeln!(
                    md,
                    "| {} | `{}` on {} | `{}`{on} | {measured} | ≤ {:.2}× | {verdict} |",
                    t.label,
                    run.variant.short(),
                    t.material,
                    against.variant.short(),
                    t.max,
                );
            }
            None => {
                let _ = writeln!(
                    md,
                    "| {} | `{}` on {} | – | not measured | ≤ {:.2}× | |",
                    t.label, t.matches, t.material, t.max
                );
            }
        }
    }
    md.push('\n');
}

pub(super) fn bake_error_section(md: &mut String, s: &StudyDir, out_dir: &Path) {
    let m = &s.meta;
    let sizes: Vec<u32> = m.bake_error[0].rows.iter().map(|row| row.size).collect();
    let _ = writeln!(
        md,
        "Baked tables against the per-pixel model (`render::baked::error_study`; `lamina \
         bake-error --material M` prints one material's): per table size, the largest lobe \
         error (weight relative to the reflectance, roughness weighted by the lobe's share) \
         at view cosines between the samples, and the largest relative pixel difference of \
         the baked render from the per-pixel one at {0}x{0}. Lobes / image:\n",
        m.bake_error[0].image_size
    );
    let header: Vec<String> = sizes.iter().map(|n| n.to_string()).collect();
    let _ = writeln!(md, "| material | {} |", header.join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(sizes.len()));
    for e in &m.bake_error {
        let cells: Vec<String> = e
            .rows
            .iter()
            .map(|row| format!("{:.1e} / {:.1e}", row.lobe_error, row.image_error))
            .collect();
        let _ = writeln!(md, "| {} | {} |", e.material, cells.join(" | "));
    }
    let worst: Vec<String> = (0..sizes.len())
        .map(|i| {
            let (lobe, image) = m.bake_error.iter().fold((0.0f64, 0.0f64), |(l, im), e| {
                (l.max(e.rows[i].lobe_error), im.max(e.rows[i].image_error))
            });
            format!("{lobe:.1e} / {image:.1e}")
        })
        .collect();
    let _ = writeln!(md, "| **worst** | {} |\n", worst.join(" | "));
    embed_charts(md, s, out_dir, &["chart-bake-lobes", "chart-bake-image"]);
}

/// Each run's image against the reference image of its material and scene, its cost beside
/// it, whether it is on its material's Pareto front, its error map; the Pareto charts.
/// The image-error table's opening paragraph: what it compares, with the references' largest
/// relative noise and the cost the Pareto front weighs (`counted`: JIT instructions).
fn image_error_intro(md: &mut String, s: &StudyDir, counted: bool) {
    let noise = s
        .results
        .runs
        .iter()
        .filter_map(|run| run.reference_noise)
        .fold(0.0f64, f64::max);
    let _ = writeln!(
        md,
        "Image error against the reference image of the same material and scene (`lamina \
         render --reference`: the exact model's lobes integrated by Monte Carlo, no split sum, \
         no prefiltering, no FGD table; relative noise at most {noise:.1e}): mean FLIP (in \
         parentheses, where measured, the reference's noise floor: the FLIP between it and the \
         same reference from the next seed), RMSE and the largest relative error of the \
         radiance (`profile::image_error`). The error in two parts, where measured: \
         *lighting*, the run's image against the reference of its own lobes (the lobes the \
         variant computes, integrated exactly: what its image-based lighting and lights \
         alone cost), and *model*, that reference against the exact model's (what its lobes \
         alone cost; both references from one seed, so their noise largely cancels). The exact \
         model, against which the whole error, its floor and its map are measured too, is that \
         of the run's transport: the paper's, or under `transport=corrected` the energies of \
         the transport that follows light's angles in the run's `interfaces` mode. FLIP \
         does not add: each part is the FLIP of its two images, and the whole lies within \
         their sum. Two FLIPs differ significantly when they are at least {} noise floors \
         (the larger of the two runs') apart: the floor is then at most a quarter of any \
         difference the report resolves. A run is on the Pareto front when it is \
         significantly closer to the reference than every cheaper run of its material on the \
         front (cost: {}); a run off it has a cheaper one that is not resolvably farther. \
         Runs of another transport or `interfaces` mode are measured against their own truth \
         and form their own front.\n",
        SIGNIFICANT_FLOORS,
        if counted {
            "JIT instructions per pixel"
        } else {
            "median time"
        }
    );
}

pub(super) fn image_error_section(md: &mut String, s: &StudyDir, out_dir: &Path) {
    let (r, m) = (&s.results, &s.meta);
    let counted = r
        .runs
        .iter()
        .any(|run| run.instructions_per_pixel.is_some());
    image_error_intro(md, s, counted);
    let _ = writeln!(
        md,
        "| run | material | FLIP | lighting | model | RMSE | max rel. error | {} | Pareto | error map |",
        if counted {
            "JIT instr. per pixel"
        } else {
            "median ms"
        }
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|");
    let mut dominated = Vec::new();
    for (i, run) in r.runs.iter().enumerate() {
        let Some(e) = run.image_error else {
            continue;
        };
        let name = run_label(r, m, i);
        let cost = if counted {
            fmt_per_pixel(run.instructions_per_pixel)
        } else {
            format!("{:.3}", run.median_ms)
        };
        let front = pareto_front(r, &run.material, Truth::of(run.variant), counted).contains(&i);
        if !front {
            dominated.push(format!("{name} ({})", run.material));
        }
        let map = s.dir.join(error_map_path(i));
        let floor = run
            .reference_flip_floor
            .map_or(String::new(), |f| format!(" ({f:.4})"));
        let part =
            |p: Option<ImageError>| p.map_or("–".to_string(), |p| format!("{:.4}", p.flip));
        let _ = writeln!(
            md,
            "| {name} | {} | {:.4}{floor} | {} | {} | {:.2e} | {:.1} % | {cost} | {} | [map]({}) |",
            run.material,
            e.flip,
            part(run.lighting_error),
            part(run.model_error),
            e.rmse,
            100.0 * e.max_relative,
            if front { "yes" } else { "dominated" },
            relative(&map, out_dir)
        );
    }
    md.push('\n');
    if !dominated.is_empty() {
        let _ = writeln!(
            md,
            "Dominated (a cheaper run of the material on the front is not significantly \
             farther from the reference): {}.\n",
            dominated.join("; ")
        );
    }
    fp16_table(md, s, out_dir);
    embed_charts(
        md,
        s,
        out_dir,
        &["chart-pareto-instructions", "chart-pareto-time"],
    );
}

/// Each half-precision run against the same variant in single precision: what fp16 alone
/// changes.
fn fp16_table(md: &mut String, s: &StudyDir, out_dir: &Path) {
    let r = &s.results;
    let halves: Vec<(usize, &Run)> = r
        .runs
        .iter()
        .enumerate()
        .filter(|(_, run)| run.image_error_vs_fp32.is_some())
        .collect();
    if halves.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "Half precision against the same variant in single precision (what fp16 alone \
         changes):\n\n| variant | material | FLIP vs fp32 | RMSE vs fp32 | FLIP vs reference | \
         error map vs fp32 |\n|---|---|---|---|---|---|"
    );
    for (i, run) in halves {
        let (e, against) = (
            run.image_error_vs_fp32.expect("filtered"),
            run.image_error.map_or(f64::NAN, |e| e.flip),
        );
        let map = s.dir.join(fp32_error_map_path(i));
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} | {:.2e} | {against:.4} | [map]({}) |",
            run.variant,
            run.material,
            e.flip,
            e.rmse,
            relative(&map, out_dir)
        );
    }
    md.push('\n');
}

/// A `[reference]` study: each material's model against the stochastic reference, per
/// truth (the reference's interface mode): the relative errors per view cosine of the paper's
/// transport and the corrected one, and the slice charts.
pub(super) fn reference_section(md: &mut String, s: &StudyDir, out_dir: &Path) {
    let m = &s.meta;
    let paths = m.reference[0].paths;
    let _ = writeln!(
        md,
        "The transfer-matrix model in f64 (FGD integrated exactly, the TIR correction from the \
         exact trapped fraction, the variant's masking form) against the stochastic reference \
         (`lamina reference`, {paths} paths per channel and view cosine) in each interface \
         mode it was run in: `single` (single-scattering interfaces, which lose what masking \
         removes) and `multiple` (the microsurface walk, which conserves it). `paper` is the \
         model as published (the same against both truths); `corrected` is \
         `transport=corrected` in the truth's interface mode (`model::transport`: each \
         layer's energy from the discrete-ordinates transport, the lobes' shapes the \
         paper's). Per point: the total reflectance R (mean of the channels, ± the \
         reference's standard error), each model's relative error (the corrected model's \
         worst channel beside it), the paper's without its TIR correction, and the relative \
         L1 error of the BRDF in the plane of incidence (in parentheses: the part the \
         reference's noise explains). `reference::compare` defines each figure.\n"
    );
    let mut truths: Vec<&str> = Vec::new();
    for e in &m.reference {
        if !truths.contains(&e.interfaces.as_str()) {
            truths.push(&e.interfaces);
        }
    }
    for truth in &truths {
        reference_table(md, s, truth);
    }
    random_stacks_table(md, s, &truths, out_dir);
    transmittance_table(md, &m.reference, &truths);
    for e in m.reference.iter().filter(|e| e.random_stack.is_none()) {
        let png = s.dir.join(format!(
            "{}.png",
            reference_chart_stem(&e.material, &e.interfaces)
        ));
        if png.is_file() {
            let _ = writeln!(
                md,
                "![{} — {}, interfaces={}]({})\n",
                m.title,
                e.material,
                e.interfaces,
                relative(&png, out_dir)
            );
        }
    }
}

/// The random stacks' errors per truth and transport: median, 90th percentile and largest
/// |ΔR|/R (mean of the channels), the points within 5 %, the worst channels within 10 %, and
/// the distribution chart.
fn random_stacks_table(md: &mut String, s: &StudyDir, truths: &[&str], out_dir: &Path) {
    let random: Vec<_> = s
        .meta
        .reference
        .iter()
        .filter(|e| e.random_stack.is_some())
        .collect();
    if random.is_empty() {
        return;
    }
    let stacks = random.iter().filter(|e| e.interfaces == truths[0]).count();
    let _ = writeln!(
        md,
        "#### Random stacks\n\n{stacks} stacks drawn within the presets' ranges \
         (`material::random::preset_like_stack`, written out under `random-stacks/`), \
         alternately 2- and 6-flux, {} paths per channel and view cosine.\n",
        random[0].paths
    );
    let _ = writeln!(
        md,
        "| truth | transport | points | median | 90th percentile | largest | within 5 % | \
         worst channel within 10 % |\n|---|---|---|---|---|---|---|---|"
    );
    for truth in truths {
        let rows: Vec<_> = random
            .iter()
            .filter(|e| e.interfaces == *truth)
            .flat_map(|e| &e.rows)
            .collect();
        for transport in ["paper", "corrected"] {
            let of = |r: &ReferenceRow| match transport {
                "paper" => (r.relative_error(), r.worst_channel(r.model)),
                _ => (
                    r.relative_error_corrected(),
                    r.worst_channel(r.model_corrected),
                ),
            };
            let mut errors: Vec<f64> = rows.iter().map(|r| of(r).0.abs()).collect();
            errors.sort_by(f64::total_cmp);
            let at = |q: f64| errors[((q * (errors.len() - 1) as f64).round()) as usize];
            let within = errors.iter().filter(|e| **e <= 0.05).count();
            let channels = rows.iter().filter(|r| of(r).1.abs() <= 0.10).count();
            let _ = writeln!(
                md,
                "| {truth} | {transport} | {} | {:.1} % | {:.1} % | {:.1} % | {within} | {channels} |",
                errors.len(),
                100.0 * at(0.5),
                100.0 * at(0.9),
                100.0 * at(1.0)
            );
        }
    }
    md.push('\n');
    let png = s.dir.join("reference-distribution.png");
    if png.is_file() {
        let _ = writeln!(
            md,
            "![Random stacks: the error's distribution]({})\n",
            relative(&png, out_dir)
        );
    }
}

/// The transmissive stacks' T (presets and random, every point that transmits 1e-3 or more):
/// per truth and transport, the median and largest |ΔT|/T and the points within 5 %.
fn transmittance_table(md: &mut String, compared: &[MaterialReference], truths: &[&str]) {
    let transmits = compared
        .iter()
        .flat_map(|e| &e.rows)
        .any(|r| r.transmittance_error(false).is_some());
    if !transmits {
        return;
    }
    let _ = writeln!(
        md,
        "Transmittance, where a stack transmits (T ≥ 1e-3, presets and random stacks):\n\n\
         | truth | transport | points | median | largest | within 5 % |\n|---|---|---|---|---|---|"
    );
    for truth in truths {
        for (transport, corrected) in [("paper", false), ("corrected", true)] {
            let mut errors: Vec<f64> = compared
                .iter()
                .filter(|e| e.interfaces == *truth)
                .flat_map(|e| &e.rows)
                .filter_map(|r| r.transmittance_error(corrected))
                .map(f64::abs)
                .collect();
            if errors.is_empty() {
                continue;
            }
            errors.sort_by(f64::total_cmp);
            let within = errors.iter().filter(|e| **e <= 0.05).count();
            let _ = writeln!(
                md,
                "| {truth} | {transport} | {} | {:.1} % | {:.1} % | {within} |",
                errors.len(),
                100.0 * errors[errors.len() / 2],
                100.0 * errors[errors.len() - 1]
            );
        }
    }
    md.push('\n');
}

/// One truth's table and its reading.
fn reference_table(md: &mut String, s: &StudyDir, truth: &str) {
    let _ = writeln!(md, "#### Against the `interfaces={truth}` reference\n");
    let _ = writeln!(
        md,
        "| material | model | cos θ | reference R | paper R | paper error | without TIR | \
         corrected R | corrected error (worst channel) | slice error paper / corrected (noise) | \
         corrected, lobes below the top leaving through it |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|");
    let mean = |v: [f64; 3]| (v[0] + v[1] + v[2]) / 3.0;
    let (mut paper10, mut paper5, mut corrected5, mut worst10, mut n) = (0, 0, 0, 0, 0);
    let mut worst: Option<(f64, &str, f64)> = None;
    let mut slices = Slices::default();
    let named = s.meta.reference.iter().filter(|e| e.random_stack.is_none());
    for e in named.filter(|e| e.interfaces == truth) {
        for row in &e.rows {
            let (slice, noise) = row.slice_error();
            let (slice_c, _) = row.slice_error_of(&row.slice_corrected);
            let (error, corrected) = (row.relative_error(), row.relative_error_corrected());
            let channel = row.worst_channel(row.model_corrected);
            let _ = writeln!(
                md,
                "| {} | {} | {:.2} | {:.4} ± {:.4} | {:.4} | {:+.1} % | {:+.1} % | {:.4} | \
                 {:+.1} % ({:+.1} %) | {:.1} % / {:.1} % ({:.1} %) | {:.1} % |",
                e.material,
                e.model,
                row.cos_theta,
                mean(row.reference.mean),
                mean(row.reference.std_error) / 3f64.sqrt(),
                mean(row.model),
                100.0 * error,
                100.0 * row.relative_error_no_tir(),
                mean(row.model_corrected),
                100.0 * corrected,
                100.0 * channel,
                100.0 * slice,
                100.0 * slice_c,
                100.0 * noise,
                100.0 * row.slice_exit
            );
            n += 1;
            paper10 += usize::from(error.abs() < 0.1);
            paper5 += usize::from(error.abs() <= 0.05);
            corrected5 += usize::from(corrected.abs() <= 0.05);
            worst10 += usize::from(channel.abs() <= 0.1);
            if worst.is_none_or(|w| corrected.abs() > w.0.abs()) {
                worst = Some((corrected, &e.material, row.cos_theta));
            }
            // The coated stacks' slices: more than one layer.
            if e.layers > 1 {
                slices.paper.push(slice);
                slices.corrected.push(slice_c);
                slices.exit.push(row.slice_exit);
            }
        }
    }
    md.push('\n');
    if let Some((error, material, mu)) = worst {
        let _ = writeln!(
            md,
            "Reading: the paper's total reflectance is within 10 % of this reference at \
             {paper10} of {n} (material, view) points and within 5 % at {paper5}; the \
             corrected model is within 5 % at {corrected5} of {n}, its worst channel within \
             10 % at {worst10}, its largest error {:+.1} % ({material}, cos θ = {mu:.2}). {}\n",
            100.0 * error,
            slice_reading(slices)
        );
    }
}

/// The coated stacks' slice errors per point: the paper's, the corrected model's, and the
/// corrected model's with the lobes below the top leaving through it as the walk's do.
#[derive(Default)]
struct Slices {
    paper: Vec<f64>,
    corrected: Vec<f64>,
    exit: Vec<f64>,
}

/// [`Slices`] in words.
fn slice_reading(s: Slices) -> String {
    if s.paper.is_empty() {
        return String::new();
    }
    let lower = s
        .paper
        .iter()
        .zip(&s.corrected)
        .filter(|(p, c)| c < p)
        .count();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        100.0 * v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    let mut text = format!(
        "Median slice error of the coated stacks: paper {:.2} %, corrected {:.2} % (corrected \
         lower at {lower} of {} points: it scales the paper's lobes and shades the top \
         interface's with its Fresnel factor F(v·h)).",
        median(s.paper.clone()),
        median(s.corrected.clone()),
        s.paper.len()
    );
    if s.exit.iter().any(|&e| e > 0.0) {
        text += &format!(
            " With the lobes below the top leaving through it as the walk's do, each times the \
             top's transmittance towards the light and renormalised to its energy \
             (`reference::slice`, a diagnosis: lamina does not shade them so), {:.2} %.",
            median(s.exit.clone())
        );
    }
    text
}

/// The run a published figure's `match` pattern names: the first study point that matches,
/// else the first run.
pub(super) fn published_run<'a>(s: &'a StudyDir, pattern: &str) -> Option<&'a Run> {
    let r = &s.results;
    s.meta
        .points
        .iter()
        .map(|p| &r.runs[p.run])
        .chain(r.runs.iter())
        .find(|run| run.variant.matches(pattern))
}

/// One published figure set against ours: ratios to the study's first published figure, the
/// talk's and ours from the same run.
pub(super) struct Comparison<'a> {
    pub figure: &'a Published,
    /// The study's first published figure, which the ratios divide by.
    pub reference: &'a Published,
    pub run: Option<&'a Run>,
    pub talk: f64,
    pub time: Option<f64>,
    pub instructions: Option<f64>,
}

/// Every published figure of the study with its ratios (the first one's are 1).
pub(super) fn comparisons(s: &StudyDir) -> Vec<Comparison<'_>> {
    let Some(reference) = s.meta.published.first() else {
        return Vec::new();
    };
    let reference_run = published_run(s, &reference.matches);
    s.meta
        .published
        .iter()
        .map(|figure| {
            let run = published_run(s, &figure.matches);
            let pair = run.zip(reference_run);
            Comparison {
                figure,
                reference,
                run,
                talk: figure.ms / reference.ms,
                time: pair.map(|(a, b)| a.median_ms / b.median_ms),
                instructions: pair.and_then(|(a, b)| jit_ratio(a, b)),
            }
        })
        .collect()
}

pub(super) fn published_section(md: &mut String, s: &StudyDir) {
    let _ = writeln!(
        md,
        "Against the talk (ratios to **{}**, the first figure; ours from the same run):\n",
        s.meta.published[0].label
    );
    let _ = writeln!(
        md,
        "| figure | talk ms | talk ratio | our run | ours, time ratio | ours, {} ratio |",
        jit_basis(&s.results)
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for c in comparisons(s) {
        let _ = writeln!(
            md,
            "| {}{} | {:.3} | {:.2}× | {} | {} | {} |",
            c.figure.label,
            c.figure
                .source
                .as_deref()
                .map(|s| format!(" ({s})"))
                .unwrap_or_default(),
            c.figure.ms,
            c.talk,
            if c.run.is_some() {
                format!("`{}`", c.figure.matches)
            } else {
                "not measured".into()
            },
            fmt_ratio(c.time),
            fmt_ratio(c.instructions)
        );
    }
    md.push('\n');
}

/// A least-squares line along the first axis per series, by time and by instructions.
pub(super) fn fit_section(md: &mut String, s: &StudyDir) {
    let r = &s.results;
    let m = &s.meta;
    let Some(x_axis) = m.axes.first() else {
        return;
    };
    // Per series label: (x, median ms, instructions) points; instructions per shaded pixel
    // where counted at two sizes, else the whole draw's.
    let per_pixel = per_pixel(r);
    type FitPoint = (f64, f64, Option<f64>);
    let mut series: Vec<(String, Vec<FitPoint>)> = Vec::new();
    for p in &m.points {
        let Some(x) = p.coords.first().and_then(|v| v.parse::<f64>().ok()) else {
            continue;
        };
        let label = p.coords[1..].join(", ");
        let run = &r.runs[p.run];
        let instructions = if per_pixel {
            run.instructions_per_pixel
        } else {
            run.instructions.map(|n| n as f64)
        };
        let point = (x, run.median_ms, instructions);
        match series.iter_mut().find(|(l, _)| *l == label) {
            Some((_, points)) => points.push(point),
            None => series.push((label, vec![point])),
        }
    }
    let _ = writeln!(md, "Least-squares line along `{x_axis}` (y = a + b·x):\n");
    let _ = writeln!(
        md,
        "| series | time: b (ms per step) | a (ms) | R² | {}: b per step | R² |",
        if per_pixel {
            "instructions per pixel"
        } else {
            "instructions"
        }
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    let slope = |b: f64| {
        if per_pixel {
            format!("{b:.2}")
        } else {
            format!("{:.3} M", b / 1e6)
        }
    };
    for (label, points) in &series {
        let time: Vec<(f64, f64)> = points.iter().map(|p| (p.0, p.1)).collect();
        let instr: Vec<(f64, f64)> = points.iter().filter_map(|p| Some((p.0, p.2?))).collect();
        let t = linear_fit(&time);
        let i = linear_fit(&instr);
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} |",
            if label.is_empty() { "all" } else { label },
            t.map_or("–".into(), |f| format!("{:.4}", f.1)),
            t.map_or("–".into(), |f| format!("{:.4}", f.0)),
            t.map_or("–".into(), |f| format!("{:.4}", f.2)),
            i.map_or("–".into(), |f| slope(f.1)),
            i.map_or("–".into(), |f| format!("{:.5}", f.2)),
        );
    }
    md.push('\n');
}
