//! Preset materials: `assets/materials/<name>.toml`, found relative to the working directory
//! first (an installed copy, or edits next to the binary) and then in the source tree.

use std::path::{Path, PathBuf};

use super::MaterialError;

/// Where presets live, relative to the working directory or to the source tree.
const PRESET_DIR: &str = "assets/materials";

fn preset_dirs() -> [PathBuf; 2] {
    [
        PathBuf::from(PRESET_DIR),
        Path::new(env!("CARGO_MANIFEST_DIR")).join(PRESET_DIR),
    ]
}

/// A preset name has no path separator and no `.toml`; anything else is a path.
pub(super) fn is_preset_name(spec: &str) -> bool {
    !spec.is_empty() && !spec.contains(['/', '\\']) && !spec.ends_with(".toml")
}

/// The file of preset `name`, from the first preset directory that has it.
pub(super) fn find(name: &str) -> Result<PathBuf, MaterialError> {
    let dirs = preset_dirs();
    dirs.iter()
        .map(|dir| dir.join(format!("{name}.toml")))
        .find(|candidate| candidate.is_file())
        .ok_or_else(|| MaterialError::NotFound {
            name: name.to_owned(),
            searched: dirs
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(" and "),
        })
}

/// Preset files, sorted by name (from the first preset directory that exists).
pub fn presets() -> Vec<PathBuf> {
    let Some(dir) = preset_dirs().into_iter().find(|d| d.is_dir()) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}
