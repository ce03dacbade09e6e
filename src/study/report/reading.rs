//! The report's reading of a study, one statement per line: each published figure against
//! ours, and the effects the results themselves show — how whole-draw counts dilute per-pixel
//! ratios, what divergence costs against coherent shading, how the columns of a material grid
//! compare, lavapipe's draw-time rebuilds and its fp16 emulation.

use std::fmt::Write as _;

use crate::profile::results::{ActiveLayers, Results, Run};
use crate::stats::MinMeanMax;
use crate::study::dirs::StudyDir;
use crate::variant::VariantKey;

use super::ratios::{
    baseline_of, fmt_count, instructions_ratio, is_llvmpipe, jit_basis, jit_ratio, main_ratio,
    per_pixel, spread, verdict, REBUILD_OVERHEAD,
};
use super::runs::{material_grid, MaterialGrid};
use super::sections::{comparisons, published_run};

/// The study's reading, one statement per line: each published figure against ours (agreeing
/// when within `AGREEMENT`), then the effects of the device that the results themselves
/// show. Empty when there is nothing to say.
pub(super) fn reading(s: &StudyDir) -> Vec<String> {
    let r = &s.results;
    let mut lines = Vec::new();
    for c in comparisons(s).iter().skip(1) {
        let mut line = format!(
            "{} against {}: the talk {:.2}×; ours by time {}",
            c.figure.label,
            c.reference.label,
            c.talk,
            verdict(c.time, c.talk)
        );
        if c.instructions.is_some() {
            let _ = write!(
                line,
                ", by {} {}",
                jit_basis(r),
                verdict(c.instructions, c.talk)
            );
        }
        line.push('.');
        lines.push(line);
    }

    lines.extend(dilution(r));
    lines.extend(divergence(r));
    lines.extend(columns_reading(s));

    lines.extend(rebuild_reading(s));
    if is_llvmpipe(r) {
        lines.extend(fp16_reading(r));
    }
    lines
}

/// lavapipe's draw-time rebuild: runs with far more instructions outside the JIT code than
/// the ggx baseline of the same material (no verdict without that baseline).
fn rebuild_reading(s: &StudyDir) -> Option<String> {
    let (r, m) = (&s.results, &s.meta);
    let overhead = |run: &Run| Some(run.instructions_total?.saturating_sub(run.instructions?));
    let rebuild = |run: &Run| -> Option<(u64, u64)> {
        if run.is_baseline() {
            return None;
        }
        let base = r.baseline_of(&run.material)?;
        let (o, b) = (overhead(run)?, overhead(base)?);
        // A rebuild happens at every draw, so it shows at both counted sizes; a one-off
        // excess at one size (driver work at a draw, seen since the material left the uniform
        // buffer) is not one.
        let large = |run: &Run| {
            Some(
                run.instructions_total_large?
                    .saturating_sub(run.instructions_large?),
            )
        };
        let at_large = match (large(run), large(base)) {
            (Some(o), Some(b)) => b > 0 && o as f64 > REBUILD_OVERHEAD * b as f64,
            _ => true,
        };
        (b > 0 && o as f64 > REBUILD_OVERHEAD * b as f64 && at_large).then_some((o, b))
    };
    let rebuilt: Vec<String> = r
        .runs
        .iter()
        .filter_map(|run| {
            let (o, b) = rebuild(run)?;
            Some(format!(
                "`{}` on {} ({} outside the JIT code, ggx {})",
                run.variant.short(),
                run.material,
                fmt_count(Some(o)),
                fmt_count(Some(b))
            ))
        })
        .collect();
    if rebuilt.is_empty() {
        return None;
    }
    let published_hit = m
        .published
        .iter()
        .filter_map(|p| published_run(s, &p.matches))
        .any(|run| rebuild(run).is_some());
    Some(format!(
        "lavapipe rebuilds the shader at every draw for {}: their times include the rebuild \
         and their JIT counts are of a shader specialised to the material \
         (profiling/README.md), so neither compares with runs that are not rebuilt{}.",
        rebuilt.join("; "),
        if published_hit {
            "; a published figure's run is among them"
        } else {
            ""
        }
    ))
}

/// fp16 on llvmpipe is emulated: each fp16=on run against its fp16=off twin.
fn fp16_reading(r: &Results) -> Option<String> {
    let mut time = Vec::new();
    let mut instr = Vec::new();
    for on in r.runs.iter().filter(|run| run.variant.fp16) {
        let twin = VariantKey {
            fp16: false,
            ..on.variant
        };
        let Some(off) = r
            .runs
            .iter()
            .find(|run| run.variant == twin && run.material == on.material)
        else {
            continue;
        };
        time.push(on.median_ms / off.median_ms);
        instr.extend(jit_ratio(on, off));
    }
    if time.is_empty() {
        return None;
    }
    let range = |v: &[f64]| {
        let MinMeanMax {
            min: lo, max: hi, ..
        } = MinMeanMax::of(v.iter().copied()).expect("a non-empty list");
        if (hi - lo).abs() < 0.005 {
            format!("{lo:.2}×")
        } else {
            format!("{lo:.2}–{hi:.2}×")
        }
    };
    let mut line = format!(
        "fp16 is emulated by llvmpipe (32-bit arithmetic plus conversions): `fp16=on` runs at \
         {} its `fp16=off` twin's time",
        range(&time)
    );
    if !instr.is_empty() {
        let _ = write!(line, ", {} in {}", range(&instr), jit_basis(r));
    }
    line += "; a GPU with native half floats saves registers and scratch with it instead.";
    Some(line)
}

/// How much whole-draw counts understate the per-pixel ratios to ggx: the per-draw costs
/// (vertex work, triangle setup, partly covered blocks) are the same for every variant and
/// weigh most at small sizes.
fn dilution(r: &Results) -> Option<String> {
    let counter = r.counter.as_ref()?;
    let mut shares: Vec<f64> = r
        .runs
        .iter()
        .filter(|run| !run.is_baseline())
        .filter_map(|run| {
            let base = baseline_of(r, run)?;
            let whole = instructions_ratio(run, Some(base))?;
            Some(whole / run.instructions_per_pixel_ratio?)
        })
        .collect();
    if shares.is_empty() {
        return None;
    }
    let [w, h] = counter.sizes[0];
    let text = spread(&mut shares);
    let median = shares[shares.len() / 2];
    Some(if median < 0.95 {
        format!(
            "Whole-draw counts dilute the ratios: a run's whole-draw ×ggx at {w}x{h} is {text} \
             of its per-pixel ×ggx, because what every draw costs whatever it shades (vertex \
             work, triangle setup, partly covered blocks) is the same for both variants."
        )
    } else {
        format!(
            "A run's whole-draw ×ggx at {w}x{h} is {text} of its per-pixel ×ggx: on the {} \
             scene the per-draw costs are small next to the shading.",
            r.scene
        )
    })
}

/// The cost of a layer count that varies per pixel (the divergence study): the runs whose
/// pixels all run the same count draw the coherent cost line (piecewise linear in the count);
/// every run whose count varies is read against that line at its mean count — the excess is
/// what divergence costs — and against the line at its busiest pixel's count, which a SIMD
/// group holding that pixel runs whatever its other lanes need. Empty without at least two
/// coherent counts and one varying run.
pub(super) fn divergence(r: &Results) -> Vec<String> {
    // Each variant (the forward and the deferred path) against its own coherent runs.
    let mut variants: Vec<VariantKey> = Vec::new();
    for run in r.runs.iter().filter(|run| !run.is_baseline()) {
        if run.active_layers.is_some() && !variants.contains(&run.variant) {
            variants.push(run.variant);
        }
    }
    let several = variants.len() > 1;
    let mut lines: Vec<String> = variants
        .into_iter()
        .flat_map(|v| divergence_of(r, v, several))
        .collect();
    if lines.is_empty() {
        return lines;
    }
    if let Some(lanes) = r.device.subgroup_size {
        let simd = if is_llvmpipe(r) {
            format!(
                "lavapipe runs {lanes} pixels in lockstep (its subgroup size: one SIMD vector \
                 of 32-bit lanes, part of the 4x4 pixel block it rasterises, or of a compute \
                 kernel's work group)"
            )
        } else {
            format!(
                "{} runs {lanes} lanes in lockstep (its subgroup size)",
                r.device.name
            )
        };
        lines.push(format!(
            "{simd}: a group in which any pixel runs more layers runs them for all its pixels, \
             so a mask coherent over groups of that size costs what its mean costs, and a finer \
             one what its busiest pixels cost."
        ));
    }
    lines
}

/// [`divergence`] for the runs of `variant` (named in each line when `named`).
fn divergence_of(r: &Results, variant: VariantKey, named: bool) -> Vec<String> {
    let runs: Vec<(&Run, ActiveLayers)> = r
        .runs
        .iter()
        .filter(|run| run.variant == variant)
        .filter_map(|run| Some((run, run.active_layers?)))
        .collect();
    let mut coherent: Vec<(f64, &Run)> = runs
        .iter()
        .filter(|(_, a)| a.min == a.max)
        .map(|&(run, a)| (a.mean, run))
        .collect();
    coherent.sort_by(|a, b| a.0.total_cmp(&b.0));
    coherent.dedup_by(|a, b| a.0 == b.0);
    let varying: Vec<_> = runs.iter().filter(|(_, a)| a.min < a.max).collect();
    if coherent.len() < 2 || varying.is_empty() {
        return Vec::new();
    }
    // The coherent cost at `layers` by `cost`, interpolated between the coherent runs.
    let line = |layers: f64, cost: &dyn Fn(&Run) -> Option<f64>| -> Option<f64> {
        let i = coherent.windows(2).position(|w| layers <= w[1].0)?;
        let ((x0, a), (x1, b)) = (coherent[i], coherent[i + 1]);
        if layers < x0 {
            return None;
        }
        let (y0, y1) = (cost(a)?, cost(b)?);
        Some(y0 + (y1 - y0) * (layers - x0) / (x1 - x0))
    };
    let time = |run: &Run| Some(run.median_ms);
    let jit = |run: &Run| run.instructions_per_pixel;
    let per = |run: &Run, a: &ActiveLayers, cost: &dyn Fn(&Run) -> Option<f64>| {
        let at_mean = line(a.mean, cost)?;
        let at_max = line(f64::from(a.max), cost)?;
        let value = cost(run)?;
        Some((
            value / at_mean - 1.0,
            (value - at_mean) / (at_max - at_mean),
        ))
    };
    let pct = |x: f64| format!("{:+.0} %", 100.0 * x);
    let mut lines = Vec::new();
    for (run, a) in varying {
        let mut parts = Vec::new();
        if let Some((excess, share)) = per(run, a, &jit) {
            parts.push(format!(
                "JIT instructions per pixel {} ({:.0} % of the way to its busiest pixel's)",
                pct(excess),
                100.0 * share
            ));
        }
        if let Some((excess, share)) = per(run, a, &time) {
            parts.push(format!(
                "time {} ({:.0} % of the way)",
                pct(excess),
                100.0 * share
            ));
        }
        if parts.is_empty() {
            continue;
        }
        let name = if named {
            format!("{} ({})", run.material, run.variant.short())
        } else {
            run.material.clone()
        };
        lines.push(format!(
            "{name}: {} to {} layers per pixel, {:.2} on average; against coherent shading of \
             {:.2} layers (interpolated between the runs whose pixels all run one count): {}.",
            a.min,
            a.max,
            a.mean,
            a.mean,
            parts.join("; ")
        ));
    }
    lines
}

/// For a study of several materials over one other axis: each column's ratio to ggx over
/// the materials, and how the costliest column compares with each per-material mode.
fn columns_reading(s: &StudyDir) -> Vec<String> {
    let (r, m) = (&s.results, &s.meta);
    let Some(MaterialGrid {
        axis,
        materials: names,
        columns,
    }) = material_grid(r, m)
    else {
        return Vec::new();
    };
    let materials = |column: &str| -> Vec<&Run> {
        m.points
            .iter()
            .filter(|p| p.coords[axis] == column)
            .map(|p| &r.runs[p.run])
            .collect()
    };
    let count = names.len();
    let to_ggx = |run: &Run| Some(main_ratio(r, run, baseline_of(r, run)?).0);
    let mut lines = Vec::new();
    let mut medians = Vec::new();
    let mut parts = Vec::new();
    for column in &columns {
        let mut ratios: Vec<f64> = materials(column).into_iter().filter_map(to_ggx).collect();
        if ratios.is_empty() {
            continue;
        }
        parts.push(format!("`{column}` {}", spread(&mut ratios)));
        medians.push((*column, ratios[ratios.len() / 2]));
    }
    let basis = if per_pixel(r) || r.runs.iter().any(|run| run.instructions.is_some()) {
        jit_basis(r)
    } else {
        "median time"
    };
    lines.push(format!(
        "× the material's ggx baseline ({basis}) over the {count} materials: {}.",
        parts.join("; ")
    ));
    let Some(&(costliest, _)) = medians.iter().max_by(|a, b| a.1.total_cmp(&b.1)) else {
        return lines;
    };
    let mut factors = Vec::new();
    for column in columns.iter().filter(|c| **c != costliest) {
        let per_material = materials(column)
            .first()
            .is_some_and(|run| run.variant.mode.per_material());
        if !per_material {
            continue;
        }
        let mut ratios: Vec<f64> = materials(column)
            .into_iter()
            .filter_map(|run| {
                let top = materials(costliest)
                    .into_iter()
                    .find(|c| c.material == run.material)?;
                Some(main_ratio(r, top, run).0)
            })
            .collect();
        if !ratios.is_empty() {
            factors.push(format!("{} `{column}`", spread(&mut ratios)));
        }
    }
    if !factors.is_empty() {
        lines.push(format!(
            "`{costliest}` costs {} on the same material.",
            factors.join(", ")
        ));
    }
    lines
}
