//! Study directories read back: a `lamina sweep` output holds one directory per study (or is
//! one), each with `results.json` and `study.json`; `lamina report` and `lamina diff` read
//! them here.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::profile::results::Results;

use super::meta::StudyMeta;

/// One study's directory, read back.
pub struct StudyDir {
    pub dir: PathBuf,
    pub results: Results,
    pub meta: StudyMeta,
}

/// A result file of a study directory, parsed.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
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
pub fn dirs_holding(root: &Path, file: &str) -> Result<Vec<PathBuf>> {
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
