//! The report's tables of a study's runs: every run with its time and counts against ggx, the
//! shading stage's statistics where the driver reports them, and — for several materials over
//! one other axis — each material's ratios side by side.

use std::fmt::Write as _;

use crate::profile::results::{Results, Run, UNSUPPORTED};

use super::super::dirs::StudyDir;
use super::super::meta::StudyMeta;
use super::ratios::{
    baseline_of, fmt_count, fmt_per_pixel, fmt_ratio, instructions_ratio, main_ratio, per_pixel,
};

/// The study's runs as a table — the baseline, then each point with its coordinates: time,
/// its ratio to ggx, and where counted the JIT instructions per pixel and per draw — and the
/// rows it shows (coordinates and run), for the tables that follow it.
pub(super) fn runs_table<'a>(
    md: &mut String,
    s: &'a StudyDir,
) -> (String, Vec<(Vec<String>, &'a Run)>) {
    let (r, m) = (&s.results, &s.meta);
    let base = r.runs.iter().find(|run| run.is_baseline());
    let counted = r.runs.iter().any(|run| run.instructions.is_some());
    let per_pixel = per_pixel(r);
    let header_axes = if m.axes.is_empty() {
        "variant".to_string()
    } else {
        m.axes.join(" | ")
    };
    let _ = writeln!(
        md,
        "| {header_axes} | material | median ms | min–max ms | ×ggx (time) |{}{}",
        if per_pixel {
            " JIT instr. per pixel | ×ggx (per pixel) |"
        } else {
            ""
        },
        if counted {
            " JIT instructions | ×ggx (JIT instr.) | all instructions |"
        } else {
            ""
        }
    );
    let columns =
        m.axes.len().max(1) + 4 + if per_pixel { 2 } else { 0 } + if counted { 3 } else { 0 };
    let _ = writeln!(md, "|{}", "---|".repeat(columns));
    let mut rows: Vec<(Vec<String>, &Run)> = Vec::new();
    if let Some(b) = base {
        let mut coords = vec!["ggx baseline".to_string()];
        coords.resize(m.axes.len().max(1), String::new());
        rows.push((coords, b));
    }
    for p in &m.points {
        let coords = if p.coords.is_empty() {
            vec![r.runs[p.run].variant.to_string()]
        } else {
            p.coords.clone()
        };
        rows.push((coords, &r.runs[p.run]));
    }
    for (coords, run) in &rows {
        let _ = write!(
            md,
            "| {} | {} | {:.3} | {:.3}–{:.3} | {:.2}× |",
            coords.join(" | "),
            run.material,
            run.median_ms,
            run.min_ms,
            run.max_ms,
            run.ratio_to_baseline
        );
        if per_pixel {
            let _ = write!(
                md,
                " {} | {} |",
                fmt_per_pixel(run.instructions_per_pixel),
                fmt_ratio(run.instructions_per_pixel_ratio)
            );
        }
        if counted {
            let _ = write!(
                md,
                " {} | {} | {} |",
                fmt_count(run.instructions),
                fmt_ratio(instructions_ratio(run, baseline_of(r, run).or(base))),
                fmt_count(run.instructions_total)
            );
        }
        md.push('\n');
    }
    md.push('\n');
    (header_axes, rows)
}

/// A study of materials over one other axis: that axis's index, the materials and the axis's
/// values, each in first-seen order.
pub(super) struct MaterialGrid<'a> {
    pub axis: usize,
    pub materials: Vec<&'a str>,
    pub columns: Vec<&'a str>,
}

/// The grid of a study whose one axis besides `material` (an axis or the `materials` list) is
/// crossed with at least two materials.
pub(super) fn material_grid<'a>(r: &'a Results, m: &'a StudyMeta) -> Option<MaterialGrid<'a>> {
    let others: Vec<usize> = (0..m.axes.len())
        .filter(|&i| m.axes[i] != "material")
        .collect();
    let [axis] = others[..] else {
        return None;
    };
    let mut materials: Vec<&str> = Vec::new();
    let mut columns: Vec<&str> = Vec::new();
    for p in &m.points {
        let material = r.runs[p.run].material.as_str();
        if !materials.contains(&material) {
            materials.push(material);
        }
        if !columns.contains(&p.coords[axis].as_str()) {
            columns.push(&p.coords[axis]);
        }
    }
    (materials.len() >= 2).then_some(MaterialGrid {
        axis,
        materials,
        columns,
    })
}

/// What the runs say of the driver's pipeline-executable statistics: unsupported, or which
/// statistics each run's results.json holds.
pub(super) fn executable_stats_line(r: &Results) -> Option<String> {
    let stats: Vec<&serde_json::Value> = r
        .runs
        .iter()
        .filter_map(|run| run.executable_stats.as_ref())
        .collect();
    if stats.is_empty() {
        return None;
    }
    if stats.iter().all(|s| s.as_str() == Some(UNSUPPORTED)) {
        return Some(format!(
            "Pipeline-executable statistics (registers, spills, code size): unsupported — {} \
             does not offer `VK_KHR_pipeline_executable_properties`.",
            r.device.name
        ));
    }
    let mut names: Vec<String> = Vec::new();
    for s in &stats {
        for exe in s.as_array().into_iter().flatten() {
            for stat in exe["statistics"].as_array().into_iter().flatten() {
                if let Some(name) = stat["name"].as_str() {
                    if !names.iter().any(|n| n == name) {
                        names.push(name.to_string());
                    }
                }
            }
        }
    }
    Some(format!(
        "Pipeline-executable statistics per run in results.json (`executable_stats`): {}.",
        names.join(", ")
    ))
}

/// Whether an executable is the stage named `long` (`fragment`, `compute`) or `short` (`FS`,
/// `CS`), as drivers spell it.
fn is_stage(executable: &serde_json::Value, long: &str, short: &str) -> bool {
    ["name", "description"].iter().any(|k| {
        executable[k]
            .as_str()
            .is_some_and(|t| t.to_ascii_lowercase().contains(long) || t == short)
    })
}

/// The shading stage's statistics of a run, by name, where the driver reports them: the
/// fragment executable's, or a compute pipeline's (the deferred path's shading kernel).
fn shading_stats(run: &Run) -> Option<Vec<(String, serde_json::Value)>> {
    let executables = run.executable_stats.as_ref()?.as_array()?;
    let exe = executables
        .iter()
        .find(|e| is_stage(e, "fragment", "FS"))
        .or_else(|| executables.iter().find(|e| is_stage(e, "compute", "CS")))?;
    Some(
        exe["statistics"]
            .as_array()?
            .iter()
            .filter_map(|s| Some((s["name"].as_str()?.to_string(), s["value"].clone())))
            .collect(),
    )
}

/// A bit that one driver sets in every value of a statistic (NVIDIA reports `Local Memory
/// Size` as 2^36 plus the bytes, the ggx shader's included): stripped, and said so.
pub(super) const FLAG_BIT: u64 = 1 << 36;

/// The table's rows again, with the shading stage's pipeline-executable statistics (registers,
/// code size, local memory …) where the driver reports them: the statistics that differ between
/// the rows as columns, the others in one line below.
pub(super) fn executable_stats_table(
    md: &mut String,
    header_axes: &str,
    rows: &[(Vec<String>, &Run)],
) {
    let stats: Vec<Option<Vec<(String, serde_json::Value)>>> =
        rows.iter().map(|(_, run)| shading_stats(run)).collect();
    if stats.iter().all(Option::is_none) {
        return;
    }
    let mut names: Vec<String> = Vec::new();
    for (name, _) in stats.iter().flatten().flatten() {
        if !names.contains(name) {
            names.push(name.clone());
        }
    }
    let value = |row: usize, name: &str| -> Option<&serde_json::Value> {
        stats[row]
            .as_ref()?
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    };
    let flagged: Vec<bool> = names
        .iter()
        .map(|name| {
            let values: Vec<u64> = (0..rows.len())
                .filter_map(|i| value(i, name)?.as_u64())
                .collect();
            !values.is_empty()
                && values
                    .iter()
                    .all(|v| v & FLAG_BIT != 0 && *v < 2 * FLAG_BIT)
        })
        .collect();
    let shown = |i: usize, k: usize| -> String {
        match value(i, &names[k]) {
            None => "–".to_string(),
            Some(v) => match v.as_u64() {
                Some(n) if flagged[k] => (n - FLAG_BIT).to_string(),
                _ => v.to_string(),
            },
        }
    };
    let (varying, constant): (Vec<usize>, Vec<usize>) =
        (0..names.len()).partition(|&k| (1..rows.len()).any(|i| shown(i, k) != shown(0, k)));
    let _ = writeln!(
        md,
        "Shading stage (the fragment shader; on the deferred path the shading kernel), as the \
         driver compiled it (`VK_KHR_pipeline_executable_properties`):\n"
    );
    let _ = write!(md, "| {header_axes} | material |");
    for &k in &varying {
        let _ = write!(md, " {} |", names[k]);
    }
    let _ = writeln!(
        md,
        "\n|{}",
        "---|".repeat(varying.len() + header_axes.split(" | ").count() + 1)
    );
    for (i, (coords, run)) in rows.iter().enumerate() {
        let _ = write!(md, "| {} | {} |", coords.join(" | "), run.material);
        for &k in &varying {
            let _ = write!(md, " {} |", shown(i, k));
        }
        md.push('\n');
    }
    md.push('\n');
    let mut notes: Vec<String> = constant
        .iter()
        .map(|&k| format!("{} {}", names[k], shown(0, k)))
        .collect();
    notes.extend((0..names.len()).filter(|&k| flagged[k]).map(|k| {
        format!(
            "{} is shown without bit 36, which every value has set",
            names[k]
        )
    }));
    if !notes.is_empty() {
        let _ = writeln!(md, "In every row: {}.\n", notes.join("; "));
    }
}

/// Studies of several materials over one other axis: each material's ratios to its ggx
/// baseline side by side (material rows, the axis's values as columns).
pub(super) fn pivot_section(md: &mut String, s: &StudyDir) {
    let (r, m) = (&s.results, &s.meta);
    let Some(MaterialGrid {
        axis,
        materials,
        columns,
    }) = material_grid(r, m)
    else {
        return;
    };
    let basis = if per_pixel(r) {
        "JIT instructions per shaded pixel"
    } else if r.runs.iter().any(|run| run.instructions.is_some()) {
        "JIT instructions of the draw"
    } else {
        "median time"
    };
    let _ = writeln!(
        md,
        "By material ({basis}, × the material's ggx baseline; the model is the material's own \
         unless the {} says otherwise):\n",
        m.axes[axis]
    );
    let _ = writeln!(md, "| material | {} |", columns.join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(columns.len()));
    for material in materials {
        let mut line = format!("| {material} |");
        for column in &columns {
            let cell = m
                .points
                .iter()
                .map(|p| (p, &r.runs[p.run]))
                .find(|(p, run)| run.material == material && p.coords[axis] == *column)
                .and_then(|(_, run)| Some(main_ratio(r, run, baseline_of(r, run)?).0));
            let _ = write!(line, " {} |", fmt_ratio(cell));
        }
        let _ = writeln!(md, "{line}");
    }
    md.push('\n');
}
