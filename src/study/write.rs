//! A study's directory: `results.json`, `results.csv`, `study.json`, `sweep.toml` (the file as
//! run), its charts and its error maps, each written atomically.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::imageio::{write_file_atomically, write_png};
use crate::profile::image_error::{error_map_path, ErrorMap};
use crate::profile::results::Results;

use super::charts::{
    charts_of, pareto_charts, reference_chart, reference_chart_stem, reference_distribution_chart,
};
use super::meta::StudyMeta;

/// Writes the study's files into `dir` (`sweep_text`: the study's file as run); returns the
/// chart paths (PNG).
pub fn write(
    dir: &Path,
    sweep_text: &str,
    results: &Results,
    meta: &StudyMeta,
    error_maps: &[(usize, ErrorMap)],
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Output {
        path: dir.to_owned(),
        message: e.to_string(),
    })?;
    let results_json = serde_json::to_string_pretty(results).expect("results serialise");
    let meta_json = serde_json::to_string_pretty(meta).expect("study metadata serialises");
    write_file_atomically(&dir.join("results.json"), &results_json)?;
    write_file_atomically(&dir.join("results.csv"), results.csv())?;
    write_file_atomically(&dir.join("study.json"), &meta_json)?;
    write_file_atomically(&dir.join("sweep.toml"), sweep_text)?;
    let mut charts = Vec::new();
    for (stem, chart) in charts_of(results, meta) {
        let path = dir.join(stem);
        chart.write(&path)?;
        charts.push(path.with_extension("png"));
    }
    for e in &meta.reference {
        if let Some(toml) = &e.random_stack {
            // A random stack: its TOML (once), no slice chart of its own.
            let path = dir
                .join("random-stacks")
                .join(format!("{}.toml", e.material));
            if !path.exists() {
                write_file_atomically(&path, toml)?;
            }
            continue;
        }
        let path = dir.join(reference_chart_stem(&e.material, &e.interfaces));
        reference_chart(e).write(&path)?;
        charts.push(path.with_extension("png"));
    }
    if meta.reference.iter().any(|e| e.random_stack.is_some()) {
        let path = dir.join("reference-distribution");
        reference_distribution_chart(&meta.reference).write(&path)?;
        charts.push(path.with_extension("png"));
    }
    for (run, map) in error_maps {
        let path = dir.join(error_map_path(*run));
        write_png(&path, map.width as usize, map.height as usize, &map.rgba())?;
    }
    for (stem, chart) in pareto_charts(results, meta) {
        let path = dir.join(stem);
        chart.write(&path)?;
        charts.push(path.with_extension("png"));
    }
    Ok(charts)
}
