//! A study's charts: per x category of its first axis, the median time (min–max whiskers) and,
//! where counted, the JIT instructions per shaded pixel, one line per combination of the other
//! axes; the baked tables' errors; cost against image error with each material's Pareto
//! front; and a `[reference]` study's BRDF slices, model against reference.

use std::path::Path;

use crate::chart::{Chart, PanelChart, Series, XyChart, XySeries};
use crate::profile::results::{Results, Run};
use crate::reference::compare::{MaterialReference, ReferenceRow};
use crate::render::reference::Truth;

use super::meta::{BakeErrorRow, StudyMeta};

/// A run's cost for the Pareto charts: JIT instructions per shaded pixel where counted at two
/// sizes, else the median time.
fn run_cost(run: &Run, instructions: bool) -> Option<f64> {
    if instructions {
        run.instructions_per_pixel
    } else {
        Some(run.median_ms)
    }
}

/// How many noise floors apart two runs' FLIPs must be for the report to call them different:
/// a reference's noise floor is the FLIP between it and the same reference from the next seed,
/// so a difference within a few floors may be the reference's noise. At four, the floor
/// printed beside an error is at most a quarter of any difference the report resolves.
pub const SIGNIFICANT_FLOORS: f64 = 4.0;

/// The smallest FLIP difference between runs `a` and `b` the report calls significant
/// ([`SIGNIFICANT_FLOORS`] times the larger of their references' noise floors; 0 where
/// neither was measured, and then any difference is one).
pub fn significant_flip(a: &Run, b: &Run) -> f64 {
    let floor = |r: &Run| r.reference_flip_floor.unwrap_or(0.0);
    SIGNIFICANT_FLOORS * floor(a).max(floor(b))
}

/// The runs of `material` on its Pareto front of (FLIP, cost), cheapest first: the cheapest
/// run (the closest of equally cheap ones), then each run significantly closer to the
/// reference ([`significant_flip`]) than the last one taken before it. A run off the front
/// has a cheaper run on it that is not resolvably farther from the reference. With no noise
/// floor measured this is the classic front: no run is at most as costly and at most as
/// wrong, and better in one. Only runs measured against the same reference take part: those
/// of `material` whose transport holds `truth` exact (`render::reference::Truth::of`).
pub fn pareto_front(
    results: &Results,
    material: &str,
    truth: Truth,
    instructions: bool,
) -> Vec<usize> {
    let mut points: Vec<(usize, f64, f64)> = results
        .runs
        .iter()
        .enumerate()
        .filter(|(_, r)| r.material == material && Truth::of(r.variant) == truth)
        .filter_map(|(i, r)| Some((i, r.image_error?.flip, run_cost(r, instructions)?)))
        .collect();
    points.sort_by(|a, b| a.2.total_cmp(&b.2).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(usize, f64, f64)> = Vec::new();
    for (i, e, c) in points {
        let taken = front.last().is_none_or(|&(j, e_front, _)| {
            e < e_front && e_front - e >= significant_flip(&results.runs[i], &results.runs[j])
        });
        if taken {
            front.push((i, e, c));
        }
    }
    front.into_iter().map(|(i, _, _)| i).collect()
}

/// How a run is named on a chart or in a table: its coordinates, else the baseline, else its
/// variant.
pub fn run_label(results: &Results, meta: &StudyMeta, i: usize) -> String {
    let run = &results.runs[i];
    match meta.points.iter().find(|p| p.run == i) {
        Some(p) if !p.coords.is_empty() => p.coords.join(", "),
        _ if run.is_baseline() => "ggx baseline".to_string(),
        _ => run.variant.to_string(),
    }
}

/// Cost against image error, a panel per material: every run a point (FLIP, cost), the Pareto
/// front joined. One chart by JIT instructions per pixel where counted, one by time.
pub fn pareto_charts(results: &Results, meta: &StudyMeta) -> Vec<(&'static str, PanelChart)> {
    if !results.runs.iter().any(|r| r.image_error.is_some()) {
        return Vec::new();
    }
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
            let panels = materials
                .iter()
                .map(|material| {
                    let (series, max_flip) = pareto_series(results, meta, material, instructions);
                    XyChart {
                        title: (*material).to_owned(),
                        x_label: "mean FLIP against the reference image".into(),
                        y_label: y_label.into(),
                        x_range: (0.0, (max_flip * 1.15).max(1e-3)),
                        series,
                    }
                })
                .collect();
            let title = format!("{} — cost against image error", meta.title);
            (stem, PanelChart { title, panels })
        })
        .collect()
}

/// A material's point per run with an image error and its joined Pareto front (one per
/// truth), costed by instructions or time; and its largest FLIP.
fn pareto_series(
    results: &Results,
    meta: &StudyMeta,
    material: &str,
    instructions: bool,
) -> (Vec<XySeries>, f64) {
    let mut series = Vec::new();
    let mut max_flip = 0.0f64;
    for (i, r) in results.runs.iter().enumerate() {
        let (Some(e), Some(cost)) = (r.image_error, run_cost(r, instructions)) else {
            continue;
        };
        if r.material != material {
            continue;
        }
        max_flip = max_flip.max(e.flip);
        series.push(XySeries {
            label: run_label(results, meta, i),
            points: vec![(e.flip, cost, 0.0, 0.0)],
            line: false,
            colour: series.len(),
        });
    }
    let mut truths: Vec<Truth> = Vec::new();
    for r in results.runs.iter().filter(|r| r.material == material) {
        if r.image_error.is_some() && !truths.contains(&Truth::of(r.variant)) {
            truths.push(Truth::of(r.variant));
        }
    }
    for truth in truths {
        let mut front: Vec<(f64, f64)> = pareto_front(results, material, truth, instructions)
            .into_iter()
            .filter_map(|i| {
                let r = &results.runs[i];
                Some((r.image_error?.flip, run_cost(r, instructions)?))
            })
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        let label = match truth {
            Truth::Paper => "Pareto front".to_owned(),
            other => format!("Pareto front (against {other})"),
        };
        series.push(XySeries {
            label,
            points: front.iter().map(|&(x, y)| (x, y, 0.0, 0.0)).collect(),
            line: true,
            colour: series.len(),
        });
    }
    (series, max_flip)
}

/// The file stem of a material's chart in a `[reference]` study: `reference-` and the name's
/// letters and digits, the rest as `-`; `-multiple` after it against the multiple-scattering
/// truth.
pub fn reference_chart_stem(material: &str, interfaces: &str) -> String {
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
    if interfaces == "single" {
        format!("reference-{name}")
    } else {
        format!("reference-{name}-{interfaces}")
    }
}

/// A material's BRDF in the plane of incidence, per view cosine: the model's curve and the
/// reference's bins (± 2 standard errors), the channels' mean.
pub fn reference_chart(e: &MaterialReference) -> XyChart {
    let mean = |v: [f64; 3]| (v[0] + v[1] + v[2]) / 3.0;
    let centre = |i: usize| {
        let (a, b) = crate::reference::slice_bin_edges(i);
        (0.5 * (a + b)).to_degrees()
    };
    let mut series = Vec::new();
    for (j, row) in e.rows.iter().enumerate() {
        series.push(XySeries {
            label: format!("paper, cos θ = {:.2}", row.cos_theta),
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
        if !row.slice_corrected.is_empty() {
            series.push(XySeries {
                label: format!("corrected, cos θ = {:.2}", row.cos_theta),
                points: row
                    .slice_corrected
                    .iter()
                    .enumerate()
                    .map(|(i, v)| (centre(i), mean(*v), 0.0, 0.0))
                    .collect(),
                line: true,
                colour: j + e.rows.len(),
            });
        }
    }
    XyChart {
        title: format!(
            "{} ({}) — BRDF in the plane of incidence, interfaces={}",
            e.material, e.model, e.interfaces
        ),
        x_label: "θ_o (degrees; positive: mirror side)".into(),
        y_label: "BRDF (1/sr), mean of RGB".into(),
        x_range: (-90.0, 90.0),
        series,
    }
}

/// The reference study's random stacks: per truth and transport, the fraction of (stack, view)
/// points whose |ΔR|/R (mean of the channels) is at most x — the error's distribution.
pub fn reference_distribution_chart(compared: &[MaterialReference]) -> XyChart {
    let mut series = Vec::new();
    let mut truths: Vec<&str> = Vec::new();
    for e in compared {
        if !truths.contains(&e.interfaces.as_str()) {
            truths.push(&e.interfaces);
        }
    }
    for (t, truth) in truths.iter().enumerate() {
        let rows = || {
            compared
                .iter()
                .filter(|e| e.random_stack.is_some() && e.interfaces == *truth)
                .flat_map(|e| &e.rows)
        };
        for (k, (transport, error)) in [
            (
                "paper",
                &(|r: &ReferenceRow| r.relative_error()) as &dyn Fn(&ReferenceRow) -> f64,
            ),
            ("corrected", &|r: &ReferenceRow| {
                r.relative_error_corrected()
            }),
        ]
        .into_iter()
        .enumerate()
        {
            let mut errors: Vec<f64> = rows().map(|r| 100.0 * error(r).abs()).collect();
            errors.sort_by(f64::total_cmp);
            let n = errors.len().max(1) as f64;
            series.push(XySeries {
                label: format!("{transport}, interfaces={truth}"),
                points: errors
                    .iter()
                    .enumerate()
                    .map(|(i, &x)| (x, (i + 1) as f64 / n, 0.0, 0.0))
                    .collect(),
                line: true,
                colour: 2 * t + k,
            });
        }
    }
    let largest = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .fold(5.0f64, f64::max);
    XyChart {
        title: "Random stacks: the model's error against the reference".into(),
        x_label: "|ΔR| / R (%, mean of RGB)".into(),
        y_label: "fraction of (stack, view) points".into(),
        x_range: (0.0, largest.min(100.0)),
        series,
    }
}

/// A value read off a run with its whiskers: (value, low, high).
type RunValue = dyn Fn(&Run) -> Option<(f64, f64, f64)>;

/// The study's runs laid out for category charts: the x categories (the first axis's values),
/// the series labels (the other axes' values), and each point's (category, series, run).
struct Layout {
    x_axis: String,
    categories: Vec<String>,
    labels: Vec<String>,
    placed: Vec<(usize, usize, usize)>,
}

impl Layout {
    fn of(results: &Results, meta: &StudyMeta) -> Self {
        let x_axis = meta
            .axes
            .first()
            .cloned()
            .unwrap_or_else(|| "variant".into());
        let mut materials: Vec<&str> = Vec::new();
        for p in &meta.points {
            let name = results.runs[p.run].material.as_str();
            if !materials.contains(&name) {
                materials.push(name);
            }
        }
        let material_is_swept = meta
            .axes
            .iter()
            .any(|a| a == "material" || a == "active_layers");
        let mut layout = Self {
            x_axis,
            categories: Vec::new(),
            labels: Vec::new(),
            placed: Vec::new(),
        };
        for p in &meta.points {
            let mut category = p.coords.first().cloned().unwrap_or_else(|| "base".into());
            // A material file on the x axis reads as its stem (`divergence/noise.toml` → noise).
            if layout.x_axis == "material" && category.ends_with(".toml") {
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
            if materials.len() > 1 && !material_is_swept {
                label_parts.insert(0, results.runs[p.run].material.clone());
            }
            let label = if label_parts.is_empty() {
                "median".to_string()
            } else {
                label_parts.join(", ")
            };
            let ci = index_of(&mut layout.categories, category);
            let si = index_of(&mut layout.labels, label);
            layout.placed.push((ci, si, p.run));
        }
        layout
    }

    /// One series per label, of `value` read off each placed run.
    fn series(&self, results: &Results, value: &RunValue) -> Vec<Series> {
        self.labels
            .iter()
            .enumerate()
            .map(|(si, label)| Series {
                label: label.clone(),
                points: self
                    .placed
                    .iter()
                    .filter(|p| p.1 == si)
                    .filter_map(|&(ci, _, run)| {
                        value(&results.runs[run]).map(|(v, lo, hi)| (ci, v, lo, hi))
                    })
                    .collect(),
            })
            .collect()
    }
}

/// The index of `item` in `list`, pushed at the end when new.
fn index_of(list: &mut Vec<String>, item: String) -> usize {
    match list.iter().position(|c| *c == item) {
        Some(i) => i,
        None => {
            list.push(item);
            list.len() - 1
        }
    }
}

/// A counted value: no whiskers.
fn point(x: f64) -> (f64, f64, f64) {
    (x, x, x)
}

/// The study's charts: median time (min–max whiskers) per x category, one line per
/// combination of the other axes; the instruction counts when measured; the baked tables'
/// errors.
pub fn charts_of(results: &Results, meta: &StudyMeta) -> Vec<(&'static str, Chart)> {
    if meta.points.is_empty() {
        // A `[reference]` study times nothing.
        return Vec::new();
    }
    let layout = Layout::of(results, meta);
    let baseline = results.runs.iter().find(|r| r.is_baseline());
    let device = &results.device.name;
    let mut charts = vec![(
        "chart-time",
        Chart {
            title: format!(
                "{} — shaded draw, {}x{} {} ({device})",
                meta.title, results.size[0], results.size[1], results.scene
            ),
            x_label: layout.x_axis.clone(),
            y_label: "GPU time, ms (median; whiskers min–max)".into(),
            categories: layout.categories.clone(),
            series: layout.series(results, &|r| Some((r.median_ms, r.min_ms, r.max_ms))),
            reference: baseline.map(|b| ("ggx baseline".to_string(), b.median_ms)),
        },
    )];
    charts.extend(instructions_chart(results, meta, &layout, baseline));
    charts.extend(bake_charts(meta));
    charts
}

/// JIT instructions per shaded pixel where counted at two sizes, else (studies counted at one
/// size, before the per-pixel count) the whole draw's; none when not counted.
fn instructions_chart(
    results: &Results,
    meta: &StudyMeta,
    layout: &Layout,
    baseline: Option<&Run>,
) -> Option<(&'static str, Chart)> {
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
        return Some((
            "chart-instructions",
            Chart {
                title: format!(
                    "{} — JIT instructions per shaded pixel, {}{sizes}",
                    meta.title, results.scene
                ),
                x_label: layout.x_axis.clone(),
                y_label: "JIT instructions per added pixel (callgrind, LP_NUM_THREADS=0)".into(),
                categories: layout.categories.clone(),
                series: layout.series(results, &|r| r.instructions_per_pixel.map(point)),
                reference: baseline
                    .and_then(|b| b.instructions_per_pixel)
                    .map(|n| ("ggx baseline".to_string(), n)),
            },
        ));
    }
    if !results.runs.iter().any(|r| r.instructions.is_some()) {
        return None;
    }
    let size = meta
        .counter_size
        .map(|[w, h]| format!("{w}x{h}"))
        .unwrap_or_default();
    Some((
        "chart-instructions",
        Chart {
            title: format!(
                "{} — JIT instructions of the shaded draw, {size}",
                meta.title
            ),
            x_label: layout.x_axis.clone(),
            y_label: "JIT instructions (callgrind, LP_NUM_THREADS=0)".into(),
            categories: layout.categories.clone(),
            series: layout.series(results, &|r| r.instructions.map(|n| point(n as f64))),
            reference: baseline
                .and_then(|b| b.instructions)
                .map(|n| ("ggx baseline".to_string(), n as f64)),
        },
    ))
}

/// The baked tables' largest lobe and image errors per table size, one line per material.
fn bake_charts(meta: &StudyMeta) -> Vec<(&'static str, Chart)> {
    let Some(first) = meta.bake_error.first() else {
        return Vec::new();
    };
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
    vec![
        (
            "chart-bake-lobes",
            Chart {
                title: format!("{} — baked lobes against the model", meta.title),
                x_label: "table size (samples per lobe)".into(),
                y_label: "largest lobe error, relative to R".into(),
                categories: categories.clone(),
                series: series(|r| r.lobe_error),
                reference: bound.clone(),
            },
        ),
        (
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
        ),
    ]
}
