//! `lamina report DIR…`: profiling/REPORT.md from committed sweep results — per study our
//! table and chart beside the talk's published figures, compared as ratios (absolute times of
//! different machines do not compare; ratios within one run do), and a reading of them: which
//! figures agree, and the device effects the data itself shows (lavapipe's draw-time shader
//! rebuild, its fp16 emulation).
//!
//! Instruction counts are compared per shaded pixel (the marginal count between the two
//! counter sizes, free of per-draw costs) where a study has them; the whole draw's count is the
//! secondary column, and the only one of studies counted at a single size.

use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};

use crate::error::{Error, Result};
use crate::variant::VariantKey;

use super::bench::{Results, Run};
use super::stats::MinMeanMax;
use super::sweep::{key_matches, reference_chart_stem, Published, StudyMeta, Target};

/// One study's directory, read back.
pub struct StudyDir {
    pub dir: PathBuf,
    pub results: Results,
    pub meta: StudyMeta,
}

pub(super) fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Input {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    serde_json::from_str(&text).map_err(|e| Error::Input {
        path: path.to_owned(),
        message: format!("not a lamina result file: {e}"),
    })
}

/// `root` itself when it holds `file`, else its sub-directories that hold one, in name order;
/// an error naming `root` when there is none.
pub(super) fn dirs_holding(root: &Path, file: &str) -> Result<Vec<PathBuf>> {
    if root.join(file).is_file() {
        return Ok(vec![root.to_owned()]);
    }
    let entries = std::fs::read_dir(root).map_err(|e| Error::Input {
        path: root.to_owned(),
        message: format!("not a results directory: {e}"),
    })?;
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join(file).is_file())
        .collect();
    if found.is_empty() {
        return Err(Error::Input {
            path: root.to_owned(),
            message: format!(
                "no {file} here or in its sub-directories; run `lamina sweep FILE --out DIR` first"
            ),
        });
    }
    found.sort();
    Ok(found)
}

/// The study directories under `roots`: a root holding `study.json` is one; otherwise its
/// sub-directories that hold one, in name order.
pub fn collect(roots: &[PathBuf]) -> Result<Vec<StudyDir>> {
    let mut dirs = Vec::new();
    for root in roots {
        dirs.extend(dirs_holding(root, "study.json")?);
    }
    dirs.into_iter()
        .map(|dir| {
            let results: Results = read_json(&dir.join("results.json"))?;
            let meta: StudyMeta = read_json(&dir.join("study.json"))?;
            if let Some(p) = meta.points.iter().find(|p| p.run >= results.runs.len()) {
                return Err(Error::Input {
                    path: dir.join("study.json"),
                    message: format!(
                        "`points` names run {} but results.json has {} run(s): the two files \
                         are not from the same sweep",
                        p.run,
                        results.runs.len()
                    ),
                });
            }
            Ok(StudyDir { dir, results, meta })
        })
        .collect()
}

/// `path` relative to the directory `from` (both made absolute first), `/`-separated for
/// Markdown links.
fn relative(path: &Path, from: &Path) -> String {
    let abs = |p: &Path| -> Vec<String> {
        std::path::absolute(p)
            .unwrap_or_else(|_| p.to_owned())
            .components()
            .filter(|c| !matches!(c, Component::CurDir))
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect()
    };
    let (p, f) = (abs(path), abs(from));
    let common = p.iter().zip(&f).take_while(|(a, b)| a == b).count();
    let mut parts: Vec<String> = vec!["..".into(); f.len() - common];
    parts.extend(p[common..].iter().cloned());
    if parts.is_empty() {
        ".".into()
    } else {
        parts.join("/")
    }
}

/// Least-squares line y = a + b·x and its R².
pub fn linear_fit(points: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = points.iter().map(|p| (p.1 - my).powi(2)).sum();
    if sxx == 0.0 {
        return None;
    }
    let b = sxy / sxx;
    let r2 = if syy == 0.0 {
        1.0
    } else {
        sxy * sxy / (sxx * syy)
    };
    Some((my - b * mx, b, r2))
}

fn fmt_count(n: Option<u64>) -> String {
    n.map(|n| format!("{:.3} M", n as f64 / 1e6))
        .unwrap_or_else(|| "–".into())
}

fn fmt_ratio(r: Option<f64>) -> String {
    r.map(|r| format!("{r:.2}×")).unwrap_or_else(|| "–".into())
}

fn instructions_ratio(run: &Run, base: Option<&Run>) -> Option<f64> {
    Some(run.instructions? as f64 / base?.instructions? as f64)
}

/// The ggx baseline `run` is divided by: the one on its material, else the study's first.
fn baseline_of<'a>(r: &'a Results, run: &Run) -> Option<&'a Run> {
    r.baseline_of(&run.material)
        .or_else(|| r.runs.iter().find(|b| b.variant.starts_with("model=ggx")))
}

/// `a` over `b` on the study's main basis: JIT instructions per pixel, else per draw, else
/// median time; with the basis's name.
fn main_ratio(r: &Results, a: &Run, b: &Run) -> (f64, &'static str) {
    match jit_ratio(a, b) {
        Some(x) => (x, jit_basis(r)),
        None => (a.median_ms / b.median_ms, "median time"),
    }
}

fn fmt_per_pixel(n: Option<f64>) -> String {
    n.map(|n| format!("{n:.1}")).unwrap_or_else(|| "–".into())
}

/// Whether the study's runs carry instructions per shaded pixel (counted at two sizes).
fn per_pixel(r: &Results) -> bool {
    r.runs
        .iter()
        .any(|run| run.instructions_per_pixel.is_some())
}

/// `a`'s JIT instructions over `b`'s: per shaded pixel when both have that figure, else the
/// whole draws' counts.
fn jit_ratio(a: &Run, b: &Run) -> Option<f64> {
    match (a.instructions_per_pixel, b.instructions_per_pixel) {
        (Some(x), Some(y)) if y > 0.0 => Some(x / y),
        _ => Some(a.instructions? as f64 / b.instructions? as f64),
    }
}

/// How [`jit_ratio`] compared the study's runs, for prose.
fn jit_basis(r: &Results) -> &'static str {
    if per_pixel(r) {
        "JIT instructions per pixel"
    } else {
        "JIT instructions"
    }
}

/// Collects the studies under `roots` ([`collect`]) and writes their report to `out`
/// atomically; returns how many studies it holds.
pub fn write(roots: &[PathBuf], out: &Path) -> Result<usize> {
    let studies = collect(roots)?;
    crate::imageio::write_file_atomically(out, render(&studies, out))?;
    Ok(studies.len())
}

/// The report's Markdown; `out` is where it will be written (links are relative to it).
pub fn render(studies: &[StudyDir], out: &Path) -> String {
    let out_dir = out.parent().unwrap_or(Path::new("."));
    let mut md = String::new();
    md += "# lamina profiling report\n\n";
    md += "Generated by `lamina report` from the committed sweep results listed under each study; \
           do not edit by hand. Method: profiling/README.md. Each study is one run: its variants' \
           pipelines are built up front, frames interleave the variants round-robin, warm-up frames \
           are dropped, the shaded draw is timed by timestamps (median of the measured frames) and, \
           where counted, its instructions are counted under callgrind (lavapipe, \
           `LP_NUM_THREADS=0`, deterministic) at two sizes: the main figure is the instructions per \
           shaded pixel (the difference of the two counts over the added pixels, so what a draw \
           costs whatever its size cancels), the whole draw's count at the smaller size is \
           secondary. Ratios divide by the `ggx` baseline, or by the first published figure's \
           run, measured in the same run.\n\n";
    let mut devices = Vec::new();
    if studies.iter().any(|s| is_llvmpipe(&s.results)) {
        devices.push(
            "On lavapipe the \"GPU\" is the CPU: timestamps are wall-clock time of llvmpipe's JIT \
             code (noisy, up to 2× between runs), and fp16 is emulated (it costs more, where a \
             GPU saves registers).",
        );
    }
    if studies.iter().any(|s| !is_llvmpipe(&s.results)) {
        devices.push(
            "On a GPU nothing is counted (callgrind sees llvmpipe's code only): the fragment \
             stage's pipeline-executable statistics, where the driver reports them (registers, \
             local memory, code size), stand beside the times.",
        );
    }
    devices.push(
        "The talk's figures come from an RX 6700 XT (D3D12, RGP); compare their ratios, not \
         their milliseconds.",
    );
    md += &devices.join(" ");
    md += "\n\n";
    let mut index = String::new();
    for s in studies {
        let _ = writeln!(
            index,
            "- [{}](#{}) — {}",
            s.meta.title,
            anchor(&s.meta.title),
            s.results.device.name
        );
    }
    md += "## Studies\n\n";
    md += &index;
    md += "\n";
    summary_section(&mut md, studies);
    targets_summary(&mut md, studies);
    for s in studies {
        study_section(&mut md, s, out_dir);
    }
    md
}

/// Every published comparison of every study in one table, so the headline ratios read at a
/// glance; each study's section has the details.
fn summary_section(md: &mut String, studies: &[StudyDir]) {
    let rows: Vec<(&StudyDir, Comparison)> = studies
        .iter()
        .flat_map(|s| comparisons(s).into_iter().skip(1).map(move |c| (s, c)))
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "## Summary: ours against the talk\n\n\
         Ratios to each study's first published figure (agreeing: within {:.0} % of the \
         talk's); JIT instructions per shaded pixel where the study counted two sizes, else of \
         the whole draw.\n",
        AGREEMENT * 100.0
    );
    let _ = writeln!(
        md,
        "| study | figure | against | talk | ours, time | ours, JIT instructions |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for (s, c) in rows {
        let _ = writeln!(
            md,
            "| [{}](#{}) | {} | {} | {:.2}× | {} | {} |",
            s.meta.title,
            anchor(&s.meta.title),
            c.figure.label,
            c.reference.label,
            c.talk,
            verdict(c.time, c.talk),
            if c.instructions.is_some() {
                verdict(c.instructions, c.talk)
            } else {
                "–".into()
            }
        );
    }
    md.push('\n');
}

/// Every study's `[[target]]`s in one table: what was asked, what was measured.
fn targets_summary(md: &mut String, studies: &[StudyDir]) {
    let rows: Vec<(&StudyDir, &Target)> = studies
        .iter()
        .flat_map(|s| s.meta.targets.iter().map(move |t| (s, t)))
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "## Summary: targets\n\nThe ratio bounds the study files set (`[[target]]`), \
         measured; each study's section has the runs.\n"
    );
    let _ = writeln!(md, "| study | target | material | measured | bound | |");
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for (s, t) in rows {
        let (measured, verdict) = match target_ratio(s, t) {
            Some((ratio, basis, _, _)) => (
                format!("{ratio:.2}× ({basis})"),
                target_verdict(ratio, t.max),
            ),
            None => ("not measured".into(), String::new()),
        };
        let _ = writeln!(
            md,
            "| [{}](#{}) | {} | {} | {measured} | ≤ {:.2}× | {verdict} |",
            s.meta.title,
            anchor(&s.meta.title),
            t.label,
            t.material,
            t.max
        );
    }
    md.push('\n');
}

fn anchor(title: &str) -> String {
    title
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            'a'..='z' | '0'..='9' | '-' | '_' => Some(c),
            ' ' => Some('-'),
            _ => None,
        })
        .collect()
}

fn study_section(md: &mut String, s: &StudyDir, out_dir: &Path) {
    let r = &s.results;
    let m = &s.meta;
    let _ = writeln!(md, "## {}\n", m.title);
    if !m.description.is_empty() {
        let _ = writeln!(md, "{}\n", m.description.trim());
    }
    let _ = writeln!(
        md,
        "Device: **{}** ({}, Vulkan {}); {} scene, {}x{}, {} measured frames per variant{}{}; \
         rev `{}`; sweep `{}`; results `{}`.\n",
        r.device.name,
        r.device.driver,
        r.device.api_version,
        r.scene,
        r.size[0],
        r.size[1],
        r.runs.first().map_or(0, |run| run.frames),
        r.counter
            .as_ref()
            .map(|c| {
                let [[a, b], [w, h]] = c.sizes;
                format!(
                    "; instructions counted at {a}x{b} and {w}x{h} ({} and {} shaded pixels)",
                    c.shaded_pixels[0], c.shaded_pixels[1]
                )
            })
            .unwrap_or_default(),
        if is_llvmpipe(r) {
            format!(
                "; LP_NUM_THREADS={}",
                r.lp_num_threads.as_deref().unwrap_or("unset")
            )
        } else {
            String::new()
        },
        r.git_rev,
        m.sweep_file,
        relative(&s.dir, out_dir),
    );
    let _ = writeln!(md, "Command: `{}`\n", r.command);
    if !m.reference.is_empty() {
        reference_section(md, s, out_dir);
        return;
    }
    if let Some(line) = executable_stats_line(r) {
        let _ = writeln!(md, "{line}\n");
    }
    let base = r
        .runs
        .iter()
        .find(|run| run.variant.starts_with("model=ggx"));
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
            vec![r.runs[p.run].variant.clone()]
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
    executable_stats_table(md, &header_axes, &rows);
    pivot_section(md, s);
    embed_charts(md, s, out_dir, &["chart-time", "chart-instructions"]);
    if !m.published.is_empty() {
        published_section(md, s);
    }
    if !m.targets.is_empty() {
        targets_section(md, s);
    }
    if !m.bake_error.is_empty() {
        bake_error_section(md, s, out_dir);
    }
    if m.fit {
        fit_section(md, s);
    }
    if r.runs.iter().any(|run| run.image_error.is_some()) {
        image_error_section(md, s, out_dir);
    }
    let reading = reading(s);
    if !reading.is_empty() {
        let _ = writeln!(md, "Reading:\n");
        for line in reading {
            let _ = writeln!(md, "- {line}");
        }
        md.push('\n');
    }
    if !m.skipped.is_empty() {
        let _ = writeln!(
            md,
            "Skipped (stack deeper than `max_layers`): {}.\n",
            m.skipped.join("; ")
        );
    }
}

/// A study of materials over one other axis: that axis's index, the materials and the axis's
/// values, each in first-seen order.
struct MaterialGrid<'a> {
    axis: usize,
    materials: Vec<&'a str>,
    columns: Vec<&'a str>,
}

/// The grid of a study whose one axis besides `material` (an axis or the `materials` list) is
/// crossed with at least two materials.
fn material_grid<'a>(r: &'a Results, m: &'a StudyMeta) -> Option<MaterialGrid<'a>> {
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
fn executable_stats_line(r: &Results) -> Option<String> {
    let stats: Vec<&serde_json::Value> = r
        .runs
        .iter()
        .filter_map(|run| run.executable_stats.as_ref())
        .collect();
    if stats.is_empty() {
        return None;
    }
    if stats
        .iter()
        .all(|s| s.as_str() == Some(super::bench::UNSUPPORTED))
    {
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

/// The fragment stage's name among a pipeline's executables, as drivers spell it.
fn is_fragment(executable: &serde_json::Value) -> bool {
    ["name", "description"].iter().any(|k| {
        executable[k]
            .as_str()
            .is_some_and(|t| t.to_ascii_lowercase().contains("fragment") || t == "FS")
    })
}

/// The fragment executable's statistics of a run, by name, where the driver reports them.
fn fragment_stats(run: &Run) -> Option<Vec<(String, serde_json::Value)>> {
    let exe = run
        .executable_stats
        .as_ref()?
        .as_array()?
        .iter()
        .find(|e| is_fragment(e))?;
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
const FLAG_BIT: u64 = 1 << 36;

/// The table's rows again, with the fragment stage's pipeline-executable statistics (registers,
/// code size, local memory …) where the driver reports them: the statistics that differ between
/// the rows as columns, the others in one line below.
fn executable_stats_table(md: &mut String, header_axes: &str, rows: &[(Vec<String>, &Run)]) {
    let stats: Vec<Option<Vec<(String, serde_json::Value)>>> =
        rows.iter().map(|(_, run)| fragment_stats(run)).collect();
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
        "Fragment stage, as the driver compiled it (`VK_KHR_pipeline_executable_properties`):\n"
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
fn pivot_section(md: &mut String, s: &StudyDir) {
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

/// The measured ratio of a `[[target]]`: (ratio, basis, the run, the divisor).
fn target_ratio<'a>(s: &'a StudyDir, t: &Target) -> Option<(f64, &'static str, &'a Run, &'a Run)> {
    let r = &s.results;
    let on = |pattern: &str| {
        r.runs
            .iter()
            .find(|run| run.material == t.material && key_matches(&run.variant, pattern))
    };
    let run = on(&t.matches)?;
    let against = match &t.against {
        Some(pattern) => on(pattern)?,
        None => r.baseline_of(&t.material)?,
    };
    let (ratio, basis) = main_ratio(r, run, against);
    Some((ratio, basis, run, against))
}

/// Whether `ratio` meets a bound of `max`, and by how much it misses.
fn target_verdict(ratio: f64, max: f64) -> String {
    if ratio <= max {
        "met".into()
    } else {
        let percent = (ratio / max - 1.0) * 100.0;
        if percent < 1.0 {
            format!("missed by {percent:.2} %")
        } else {
            format!("missed by {percent:.0} %")
        }
    }
}

fn targets_section(md: &mut String, s: &StudyDir) {
    let _ = writeln!(
        md,
        "Targets (a ratio bound per row; the study records them, nothing fails on them):\n"
    );
    let _ = writeln!(md, "| target | run | against | measured | bound | |");
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for t in &s.meta.targets {
        match target_ratio(s, t) {
            Some((ratio, basis, run, against)) => {
                let _ = writeln!(
                    md,
                    "| {} | `{}` on {} | `{}` | {ratio:.2}× ({basis}) | ≤ {:.2}× | {} |",
                    t.label,
                    short_variant(&run.variant),
                    t.material,
                    short_variant(&against.variant),
                    t.max,
                    target_verdict(ratio, t.max)
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

fn bake_error_section(md: &mut String, s: &StudyDir, out_dir: &Path) {
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
fn image_error_section(md: &mut String, s: &StudyDir, out_dir: &Path) {
    let (r, m) = (&s.results, &s.meta);
    let counted = r
        .runs
        .iter()
        .any(|run| run.instructions_per_pixel.is_some());
    let noise = r
        .runs
        .iter()
        .filter_map(|run| run.reference_noise)
        .fold(0.0f64, f64::max);
    let _ = writeln!(
        md,
        "Image error against the reference image of the same material and scene (`lamina \
         render --reference`: the exact model's lobes integrated by Monte Carlo, no split sum, \
         no prefiltering, no FGD table; relative noise at most {noise:.1e}): mean FLIP, RMSE and \
         the largest relative error of the radiance (`profile::image_error`). A run is on the \
         Pareto front when no run of its material is both cheaper ({}) and closer.\n",
        if counted {
            "JIT instructions per pixel"
        } else {
            "median time"
        }
    );
    let _ = writeln!(
        md,
        "| run | material | FLIP | RMSE | max rel. error | {} | Pareto | error map |",
        if counted {
            "JIT instr. per pixel"
        } else {
            "median ms"
        }
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    let mut dominated = Vec::new();
    for (i, run) in r.runs.iter().enumerate() {
        let Some(e) = run.image_error else {
            continue;
        };
        let name = match m.points.iter().find(|p| p.run == i) {
            Some(p) if !p.coords.is_empty() => p.coords.join(", "),
            _ if run.variant.starts_with("model=ggx") => "ggx baseline".to_string(),
            _ => run.variant.clone(),
        };
        let cost = if counted {
            fmt_per_pixel(run.instructions_per_pixel)
        } else {
            format!("{:.3}", run.median_ms)
        };
        let front = super::sweep::pareto_front(r, &run.material, counted).contains(&i);
        if !front {
            dominated.push(format!("{name} ({})", run.material));
        }
        let map = s.dir.join(super::image_error::error_map_path(i));
        let _ = writeln!(
            md,
            "| {name} | {} | {:.4} | {:.2e} | {:.1} % | {cost} | {} | [map]({}) |",
            run.material,
            e.flip,
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
            "Dominated (another run of the material is cheaper and closer to the reference): \
             {}.\n",
            dominated.join("; ")
        );
    }
    let halves: Vec<(usize, &Run)> = r
        .runs
        .iter()
        .enumerate()
        .filter(|(_, run)| run.image_error_vs_fp32.is_some())
        .collect();
    if !halves.is_empty() {
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
            let map = s.dir.join(super::image_error::fp32_error_map_path(i));
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
    embed_charts(
        md,
        s,
        out_dir,
        &["chart-pareto-instructions", "chart-pareto-time"],
    );
}

/// The study's charts `names` (PNG stems) that exist, as images linked from the report.
fn embed_charts(md: &mut String, s: &StudyDir, out_dir: &Path, names: &[&str]) {
    for chart in names {
        let png = s.dir.join(format!("{chart}.png"));
        if png.is_file() {
            let _ = writeln!(
                md,
                "![{} — {chart}]({})\n",
                s.meta.title,
                relative(&png, out_dir)
            );
        }
    }
}

/// A `[reference]` study: each material's model against the stochastic reference, the
/// relative errors per view cosine, and the slice charts.
fn reference_section(md: &mut String, s: &StudyDir, out_dir: &Path) {
    let m = &s.meta;
    let paths = m.reference[0].paths;
    let _ = writeln!(
        md,
        "The transfer-matrix model in f64 (FGD integrated exactly, the TIR correction from the \
         exact trapped fraction, the variant's masking form) against the stochastic reference \
         (`lamina reference`, {paths} paths per channel and view cosine): the total \
         reflectance R (mean of the channels, ± the reference's standard error), the model's \
         relative error with and without its TIR correction, and the relative L1 error of the \
         BRDF in the plane of incidence (in parentheses: the part the reference's noise \
         explains). `reference::compare` defines each figure.\n"
    );
    let _ = writeln!(
        md,
        "| material | model | cos θ | reference R | model R | error | without TIR | slice error (noise) |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    let mean = |v: [f64; 3]| (v[0] + v[1] + v[2]) / 3.0;
    let (mut within, mut within_no_tir, mut n) = (0, 0, 0);
    let mut worst: Option<(f64, &str, f64)> = None;
    for e in &m.reference {
        for row in &e.rows {
            let (slice, noise) = row.slice_error();
            let error = row.relative_error();
            let _ = writeln!(
                md,
                "| {} | {} | {:.2} | {:.4} ± {:.4} | {:.4} | {:+.1} % | {:+.1} % | {:.1} % ({:.1} %) |",
                e.material,
                e.model,
                row.cos_theta,
                mean(row.reference.mean),
                mean(row.reference.std_error) / 3f64.sqrt(),
                mean(row.model),
                100.0 * error,
                100.0 * row.relative_error_no_tir(),
                100.0 * slice,
                100.0 * noise
            );
            n += 1;
            within += usize::from(error.abs() < 0.1);
            within_no_tir += usize::from(row.relative_error_no_tir().abs() < 0.1);
            if worst.map_or(true, |w| error.abs() > w.0.abs()) {
                worst = Some((error, &e.material, row.cos_theta));
            }
        }
    }
    md.push('\n');
    if let Some((error, material, mu)) = worst {
        let _ = writeln!(
            md,
            "Reading: the model's total reflectance is within 10 % of the reference at {within} \
             of {n} (material, view) points with its TIR correction and at {within_no_tir} \
             without it; the largest error is {:+.1} % ({material}, cos θ = {mu:.2}).\n",
            100.0 * error
        );
    }
    for e in &m.reference {
        let png = s
            .dir
            .join(format!("{}.png", reference_chart_stem(&e.material)));
        if png.is_file() {
            let _ = writeln!(
                md,
                "![{} — {}]({})\n",
                m.title,
                e.material,
                relative(&png, out_dir)
            );
        }
    }
}

/// The run a published figure's `match` pattern names: the first study point that matches,
/// else the first run.
fn published_run<'a>(s: &'a StudyDir, pattern: &str) -> Option<&'a Run> {
    let r = &s.results;
    s.meta
        .points
        .iter()
        .map(|p| &r.runs[p.run])
        .chain(r.runs.iter())
        .find(|run| key_matches(&run.variant, pattern))
}

/// One published figure set against ours: ratios to the study's first published figure, the
/// talk's and ours from the same run.
struct Comparison<'a> {
    figure: &'a Published,
    /// The study's first published figure, which the ratios divide by.
    reference: &'a Published,
    run: Option<&'a Run>,
    talk: f64,
    time: Option<f64>,
    instructions: Option<f64>,
}

/// Every published figure of the study with its ratios (the first one's are 1).
fn comparisons(s: &StudyDir) -> Vec<Comparison<'_>> {
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

fn published_section(md: &mut String, s: &StudyDir) {
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

/// A ratio of ours within this fraction of the talk's agrees with it.
const AGREEMENT: f64 = 0.15;
/// A run executing more than this many times the baseline's instructions outside the JIT code
/// is one lavapipe rebuilds at every draw (profiling/README.md).
const REBUILD_OVERHEAD: f64 = 3.0;

fn verdict(ours: Option<f64>, talk: f64) -> String {
    match ours {
        None => "not measured".into(),
        Some(x) if (x / talk - 1.0).abs() <= AGREEMENT => format!("{x:.2}×, agrees"),
        Some(x) => format!("{x:.2}×, {:.2}× the talk's", x / talk),
    }
}

fn is_llvmpipe(r: &super::bench::Results) -> bool {
    r.device.name.contains("llvmpipe") || r.device.driver.contains("llvmpipe")
}

/// The study's reading, one statement per line: each published figure against ours (agreeing
/// when within [`AGREEMENT`]), then the effects of the device that the results themselves
/// show. Empty when there is nothing to say.
fn reading(s: &StudyDir) -> Vec<String> {
    let r = &s.results;
    let m = &s.meta;
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

    // lavapipe's draw-time rebuild: far more instructions outside the JIT code than the ggx
    // baseline of the same material (no verdict without that baseline).
    let overhead = |run: &Run| Some(run.instructions_total?.saturating_sub(run.instructions?));
    let rebuild = |run: &Run| -> Option<(u64, u64)> {
        if run.variant.starts_with("model=ggx") {
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
                short_variant(&run.variant),
                run.material,
                fmt_count(Some(o)),
                fmt_count(Some(b))
            ))
        })
        .collect();
    if !rebuilt.is_empty() {
        let published_hit = m
            .published
            .iter()
            .filter_map(|p| published_run(s, &p.matches))
            .any(|run| rebuild(run).is_some());
        lines.push(format!(
            "lavapipe rebuilds the shader at every draw for {}: their times include the \
             rebuild and their JIT counts are of a shader specialised to the material \
             (profiling/README.md), so neither compares with runs that are not rebuilt{}.",
            rebuilt.join("; "),
            if published_hit {
                "; a published figure's run is among them"
            } else {
                ""
            }
        ));
    }

    // fp16 on llvmpipe is emulated: each fp16=on run against its fp16=off twin.
    if is_llvmpipe(r) {
        let mut time = Vec::new();
        let mut instr = Vec::new();
        for on in r.runs.iter().filter(|run| run.variant.contains("fp16=on")) {
            let twin = on.variant.replace("fp16=on", "fp16=off");
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
        if !time.is_empty() {
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
                "fp16 is emulated by llvmpipe (32-bit arithmetic plus conversions): `fp16=on` \
                 runs at {} its `fp16=off` twin's time",
                range(&time)
            );
            if !instr.is_empty() {
                let _ = write!(line, ", {} in {}", range(&instr), jit_basis(r));
            }
            line += "; a GPU with native half floats saves registers and scratch with it instead.";
            lines.push(line);
        }
    }
    lines
}

/// `lo–hi× (median m×)` of a non-empty list of ratios.
fn spread(values: &mut [f64]) -> String {
    values.sort_by(f64::total_cmp);
    let (lo, hi) = (values[0], values[values.len() - 1]);
    let median = values[values.len() / 2];
    if (hi - lo).abs() < 0.005 {
        format!("{lo:.2}×")
    } else {
        format!("{lo:.2}–{hi:.2}× (median {median:.2}×)")
    }
}

/// How much whole-draw counts understate the per-pixel ratios to ggx: the per-draw costs
/// (vertex work, triangle setup, partly covered blocks) are the same for every variant and
/// weigh most at small sizes.
fn dilution(r: &Results) -> Option<String> {
    let counter = r.counter.as_ref()?;
    let mut shares: Vec<f64> = r
        .runs
        .iter()
        .filter(|run| !run.variant.starts_with("model=ggx"))
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
fn divergence(r: &Results) -> Vec<String> {
    let runs: Vec<(&Run, super::bench::ActiveLayers)> = r
        .runs
        .iter()
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
    let per = |run: &Run, a: &super::bench::ActiveLayers, cost: &dyn Fn(&Run) -> Option<f64>| {
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
        lines.push(format!(
            "{}: {} to {} layers per pixel, {:.2} on average; against coherent shading of \
             {:.2} layers (interpolated between the runs whose pixels all run one count): {}.",
            run.material,
            a.min,
            a.max,
            a.mean,
            a.mean,
            parts.join("; ")
        ));
    }
    if let Some(lanes) = r.device.subgroup_size {
        let simd = if is_llvmpipe(r) {
            format!(
                "lavapipe runs {lanes} pixels in lockstep (its subgroup size: one SIMD vector \
                 of 32-bit lanes, part of the 4x4 pixel block it rasterises)"
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
            .and_then(|run| run.variant.parse::<VariantKey>().ok())
            .is_some_and(|k| k.mode.per_material());
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

/// A variant key for prose: model and max_layers, then only the axes off their defaults.
pub(super) fn short_variant(key: &str) -> String {
    let defaults = VariantKey::default().to_string();
    let defaults: Vec<&str> = defaults.split(',').skip(2).collect();
    key.split(',')
        .filter(|part| !defaults.contains(part))
        .collect::<Vec<_>>()
        .join(",")
}

fn fit_section(md: &mut String, s: &StudyDir) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_is_fitted_exactly() {
        let (a, b, r2) = linear_fit(&[(1.0, 3.0), (2.0, 5.0), (4.0, 9.0)]).unwrap();
        assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12 && (r2 - 1.0).abs() < 1e-12);
        assert!(linear_fit(&[(1.0, 2.0)]).is_none());
        let (_, _, r2) = linear_fit(&[(0.0, 0.0), (1.0, 1.0), (2.0, 0.0)]).unwrap();
        assert!(r2 < 0.5);
    }

    fn run(variant: &str, ms: f64, jit: u64, total: u64) -> Run {
        Run {
            variant: variant.into(),
            material: "gold".into(),
            frames: 3,
            min_ms: ms,
            median_ms: ms,
            mean_ms: ms,
            max_ms: ms,
            stdev_ms: 0.0,
            ratio_to_baseline: 1.0,
            fragment_invocations: None,
            pipeline_ms: 0.0,
            pipeline_cache_hit: None,
            spirv_bytes: 0,
            instructions: Some(jit),
            instructions_total: Some(total),
            instructions_large: None,
            instructions_total_large: None,
            instructions_per_pixel: None,
            instructions_per_pixel_ratio: None,
            executable_stats: None,
            active_layers: None,
            image_error: None,
            reference_noise: None,
            image_error_vs_fp32: None,
        }
    }

    fn published(label: &str, matches: &str, ms: f64) -> crate::profile::sweep::Published {
        crate::profile::sweep::Published {
            label: label.into(),
            matches: matches.into(),
            ms,
            source: None,
        }
    }

    #[test]
    fn the_reading_names_agreement_rebuilds_and_fp16_emulation() {
        let key = |k: &str| k.parse::<VariantKey>().unwrap().to_string();
        let tm2 = key("model=tm2,max_layers=2");
        let study = StudyDir {
            dir: PathBuf::from("x"),
            results: Results {
                device: super::super::bench::DeviceInfo {
                    name: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
                    driver: "llvmpipe Mesa".into(),
                    api_version: "1.3".into(),
                    vendor_id: 0x10005,
                    subgroup_size: None,
                },
                git_rev: "0".into(),
                command: "c".into(),
                size: [8, 8],
                lp_num_threads: Some("0".into()),
                scene: crate::render::scene::Scene::Sphere,
                counter: None,
                lighting: None,
                runs: vec![
                    run(&key("model=ggx"), 1.0, 2_000_000, 8_000_000),
                    // 34 M outside the JIT code against the baseline's 6 M: rebuilt.
                    run(&tm2, 4.0, 3_000_000, 37_000_000),
                    run(
                        &key("model=tm2,max_layers=2,fp16=on"),
                        6.0,
                        3_600_000,
                        43_000_000,
                    ),
                    run(&key("model=tm6,max_layers=2"), 20.0, 15_000_000, 21_000_000),
                    run(&key("model=tm2,max_layers=4"), 4.4, 6_000_000, 12_000_000),
                ],
            },
            meta: StudyMeta {
                name: "n".into(),
                title: "t".into(),
                description: String::new(),
                sweep_file: "s".into(),
                axes: Vec::new(),
                points: Vec::new(),
                skipped: Vec::new(),
                published: vec![
                    published("2-flux", "model=tm2,max_layers=2,fp16=off", 1.0),
                    published("6-flux", "model=tm6", 16.24),
                    published("wide array", "model=tm2,max_layers=4", 1.05),
                ],
                fit: false,
                counter_size: None,
                counter_sizes: None,
                targets: Vec::new(),
                bake_error: Vec::new(),
                reference: Vec::new(),
            },
        };
        let lines = reading(&study);
        assert_eq!(lines.len(), 4, "{lines:#?}");
        assert_eq!(
            lines[0],
            "6-flux against 2-flux: the talk 16.24×; ours by time 5.00×, 0.31× the talk's, \
             by JIT instructions 5.00×, 0.31× the talk's."
        );
        assert_eq!(
            lines[1],
            "wide array against 2-flux: the talk 1.05×; ours by time 1.10×, agrees, \
             by JIT instructions 2.00×, 1.90× the talk's."
        );
        assert!(
            lines[2].contains("`model=tm2,max_layers=2` on gold (34.000 M"),
            "{}",
            lines[2]
        );
        assert!(
            lines[2].contains("`model=tm2,max_layers=2,fp16=on` on gold"),
            "{}",
            lines[2]
        );
        assert!(!lines[2].contains("tm6"), "{}", lines[2]);
        assert!(lines[2].contains("a published figure's run is among them"));
        assert!(
            lines[3].contains("runs at 1.50× its `fp16=off` twin's time, 1.20× in JIT"),
            "{}",
            lines[3]
        );
        let md = render(std::slice::from_ref(&study), Path::new("REPORT.md"));
        assert!(
            md.contains(
                "| [t](#t) | 6-flux | 2-flux | 16.24× | 5.00×, 0.31× the talk's | \
                 5.00×, 0.31× the talk's |"
            ),
            "{md}"
        );
        assert!(md.contains("- wide array against 2-flux"), "{md}");
    }

    #[test]
    fn per_pixel_counts_are_the_main_figure() {
        let key = |k: &str| k.parse::<VariantKey>().unwrap().to_string();
        let counted = |variant: &str, jit: u64, per_pixel: f64, ratio: f64| Run {
            instructions_large: Some(jit * 3),
            instructions_total_large: Some(jit * 4),
            instructions_per_pixel: Some(per_pixel),
            instructions_per_pixel_ratio: Some(ratio),
            ..run(&key(variant), 1.0, jit, jit * 2)
        };
        let study = StudyDir {
            dir: PathBuf::from("x"),
            results: Results {
                device: super::super::bench::DeviceInfo {
                    name: "llvmpipe".into(),
                    driver: "llvmpipe Mesa".into(),
                    api_version: "1.3".into(),
                    vendor_id: 0x10005,
                    subgroup_size: None,
                },
                git_rev: "0".into(),
                command: "c".into(),
                size: [8, 8],
                lp_num_threads: Some("0".into()),
                scene: crate::render::scene::Scene::FullScreen,
                counter: Some(super::super::bench::CounterInfo {
                    sizes: [[48, 48], [96, 96]],
                    shaded_pixels: [2304, 9216],
                }),
                lighting: None,
                runs: vec![
                    counted("model=ggx", 1_000_000, 300.0, 1.0),
                    counted("model=tm2,max_layers=4", 5_000_000, 2400.0, 8.0),
                ],
            },
            meta: StudyMeta {
                name: "n".into(),
                title: "t".into(),
                description: String::new(),
                sweep_file: "s".into(),
                axes: vec!["model".into()],
                points: vec![super::super::sweep::PointMeta {
                    run: 1,
                    coords: vec!["tm2".into()],
                }],
                skipped: Vec::new(),
                published: vec![
                    published("ggx", "model=ggx", 1.0),
                    published("2-flux", "model=tm2", 8.0),
                ],
                fit: false,
                counter_size: Some([48, 48]),
                counter_sizes: Some([[48, 48], [96, 96]]),
                targets: Vec::new(),
                bake_error: Vec::new(),
                reference: Vec::new(),
            },
        };
        let md = render(std::slice::from_ref(&study), Path::new("REPORT.md"));
        assert!(
            md.contains("fullscreen scene, 8x8") && md.contains("at 48x48 and 96x96"),
            "{md}"
        );
        assert!(
            md.contains(
                "| model | material | median ms | min–max ms | ×ggx (time) | JIT instr. per \
                 pixel | ×ggx (per pixel) | JIT instructions | ×ggx (JIT instr.) | all \
                 instructions |"
            ),
            "{md}"
        );
        assert!(
            md.contains("| tm2 | gold | 1.000 | 1.000–1.000 | 1.00× | 2400.0 | 8.00× | 5.000 M | 5.00× | 10.000 M |"),
            "{md}"
        );
        assert!(
            md.contains("2-flux against ggx: the talk 8.00×; ours by time 1.00×, 0.12× the talk's, by JIT instructions per pixel 8.00×, agrees."),
            "{md}"
        );
    }

    /// A study of two materials over the mode: the pivot, the targets (met and missed, by how
    /// much), the per-mode reading, the dilution line and the bake-error table.
    #[test]
    fn targets_pivot_dilution_and_bake_error_are_reported() {
        let key = |k: &str| k.parse::<VariantKey>().unwrap().to_string();
        let counted = |variant: &str, material: &str, jit: u64, per_pixel: f64, ratio: f64| Run {
            material: material.into(),
            instructions_per_pixel: Some(per_pixel),
            instructions_per_pixel_ratio: Some(ratio),
            ..run(&key(variant), 1.0, jit, jit * 2)
        };
        let generic = "model=tm2,max_layers=16";
        let baked = "model=tm2,mode=baked";
        let runs = vec![
            counted("model=ggx", "gold", 1_000_000, 300.0, 1.0),
            counted("model=ggx", "copper", 1_000_000, 300.0, 1.0),
            counted(generic, "gold", 4_000_000, 3000.0, 10.0),
            counted(baked, "gold", 1_100_000, 360.0, 1.2),
            counted(generic, "copper", 3_000_000, 1800.0, 6.0),
            counted(baked, "copper", 1_500_000, 480.0, 1.6),
        ];
        let point = |run: usize, v: &str| super::super::sweep::PointMeta {
            run,
            coords: vec![v.into()],
        };
        let target = |label: &str, material: &str| Target {
            label: label.into(),
            matches: "mode=baked".into(),
            against: None,
            material: material.into(),
            max: 1.5,
        };
        let study = StudyDir {
            dir: PathBuf::from("x"),
            results: Results {
                device: super::super::bench::DeviceInfo {
                    name: "llvmpipe".into(),
                    driver: "llvmpipe Mesa".into(),
                    api_version: "1.3".into(),
                    vendor_id: 0x10005,
                    subgroup_size: None,
                },
                git_rev: "0".into(),
                command: "c".into(),
                size: [8, 8],
                lp_num_threads: Some("0".into()),
                scene: crate::render::scene::Scene::Sphere,
                counter: Some(super::super::bench::CounterInfo {
                    sizes: [[24, 24], [48, 48]],
                    shaded_pixels: [300, 1200],
                }),
                lighting: None,
                runs,
            },
            meta: StudyMeta {
                name: "n".into(),
                title: "t".into(),
                description: String::new(),
                sweep_file: "s".into(),
                axes: vec!["variant".into()],
                points: vec![
                    point(2, "generic"),
                    point(3, "baked"),
                    point(4, "generic"),
                    point(5, "baked"),
                ],
                skipped: Vec::new(),
                published: Vec::new(),
                fit: false,
                counter_size: Some([24, 24]),
                counter_sizes: Some([[24, 24], [48, 48]]),
                targets: vec![
                    target("baked on gold", "gold"),
                    target("baked on copper", "copper"),
                ],
                bake_error: vec![super::super::sweep::MaterialBakeError {
                    material: "gold".into(),
                    variant: key(baked),
                    image_size: 64,
                    rows: vec![
                        super::super::sweep::BakeErrorRow {
                            size: 32,
                            lobe_error: 5e-3,
                            image_error: 2e-2,
                        },
                        super::super::sweep::BakeErrorRow {
                            size: 256,
                            lobe_error: 3e-4,
                            image_error: 8e-4,
                        },
                    ],
                }],
                reference: Vec::new(),
            },
        };
        let md = render(std::slice::from_ref(&study), Path::new("REPORT.md"));
        for expected in [
            "| material | generic | baked |",
            "| gold | 10.00× | 1.20× |",
            "| copper | 6.00× | 1.60× |",
            "| baked on gold | `model=tm2,max_layers=4,mode=baked` on gold | `model=ggx,max_layers=4` | 1.20× (JIT instructions per pixel) | ≤ 1.50× | met |",
            "| 1.60× (JIT instructions per pixel) | ≤ 1.50× | missed by 7 % |",
            "`generic` 6.00–10.00× (median 10.00×); `baked` 1.20–1.60× (median 1.60×)",
            "`generic` costs 3.75–8.33× (median 8.33×) `baked` on the same material.",
            "Whole-draw counts dilute the ratios: a run's whole-draw ×ggx at 24x24 is 0.40–0.94× (median 0.92×) of its per-pixel ×ggx",
            "| gold | 5.0e-3 / 2.0e-2 | 3.0e-4 / 8.0e-4 |",
            "| **worst** | 5.0e-3 / 2.0e-2 | 3.0e-4 / 8.0e-4 |",
            "## Summary: targets",
        ] {
            assert!(md.contains(expected), "`{expected}` missing from\n{md}");
        }
    }

    #[test]
    fn links_are_relative_to_the_report() {
        assert_eq!(
            relative(
                Path::new("profiling/results/lavapipe/fp16/chart-time.png"),
                Path::new("profiling")
            ),
            "results/lavapipe/fp16/chart-time.png"
        );
        assert_eq!(
            relative(Path::new("a/b.png"), Path::new("c/d")),
            "../../a/b.png"
        );
    }

    #[test]
    fn the_stats_table_shows_what_differs_and_strips_the_flag_bit() {
        let stats = |regs: u64, local: u64| {
            serde_json::json!([
                {"name": "VS", "description": "vertex", "statistics": [
                    {"name": "Register Count", "value": 9}]},
                {"name": "FS", "description": "fragment", "statistics": [
                    {"name": "Register Count", "value": regs},
                    {"name": "Local Memory Size", "value": FLAG_BIT + local},
                    {"name": "Binary Size", "value": 4096}]},
            ])
        };
        let mut a = run("model=tm2,max_layers=4", 1.0, 1, 1);
        a.executable_stats = Some(stats(115, 896));
        let mut b = run("model=tm2,max_layers=8", 2.0, 1, 1);
        b.executable_stats = Some(stats(115, 1792));
        let rows = vec![(vec!["4".to_string()], &a), (vec!["8".to_string()], &b)];
        let mut md = String::new();
        executable_stats_table(&mut md, "max_layers", &rows);
        assert!(
            md.contains("| max_layers | material | Local Memory Size |"),
            "{md}"
        );
        assert!(
            md.contains("| 4 | gold | 896 |") && md.contains("| 8 | gold | 1792 |"),
            "{md}"
        );
        assert!(
            md.contains("Register Count 115") && md.contains("Binary Size 4096"),
            "{md}"
        );
        assert!(md.contains("without bit 36"), "{md}");

        let mut none = String::new();
        let plain = run("model=ggx", 1.0, 1, 1);
        executable_stats_table(&mut none, "model", &[(vec!["ggx".to_string()], &plain)]);
        assert!(none.is_empty());
    }

    #[test]
    fn a_narrow_miss_is_not_rounded_to_zero() {
        assert_eq!(target_verdict(1.0004, 1.0), "missed by 0.04 %");
        assert_eq!(target_verdict(1.07, 1.0), "missed by 7 %");
        assert_eq!(target_verdict(1.0, 1.0), "met");
    }
}
