//! lamina's on-disk cache, `$LAMINA_CACHE` (default `~/.cache/lamina`): the generated tables in
//! `tables/` (this module's files), the compiled shaders in `spirv/`
//! (`shader::ShaderCompiler`) and the pipeline caches in `pipelines/` (`pipeline_cache`), with
//! the checksum every one of them is verified by.
//!
//! Tables: one file per table keyed by its kind, parameters and the hash of
//! the kernel that builds it (its source and includes, `shader::entry_hash`: editing another
//! shader leaves it valid). A file is trusted only when its header matches the key exactly and its
//! length and checksum match its data; anything else (truncated, edited, from another shader
//! version) is ignored and rebuilt, and storing a table removes its other versions.

use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"LAMTAB01";

/// What identifies a cached table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Key {
    pub kind: &'static str,
    /// Size, sample count and anything else the values depend on.
    pub params: Vec<u32>,
    pub shader_hash: u64,
}

impl Key {
    fn file_name(&self) -> String {
        let params: Vec<String> = self.params.iter().map(u32::to_string).collect();
        format!(
            "{}-{}-{:016x}.bin",
            self.kind,
            params.join("x"),
            self.shader_hash
        )
    }

    fn header(&self, count: usize) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend((self.kind.len() as u32).to_le_bytes());
        out.extend(self.kind.as_bytes());
        out.extend((self.params.len() as u32).to_le_bytes());
        for p in &self.params {
            out.extend(p.to_le_bytes());
        }
        out.extend(self.shader_hash.to_le_bytes());
        out.extend((count as u64).to_le_bytes());
        out
    }
}

/// lamina's cache root, `$LAMINA_CACHE` (default `~/.cache/lamina`): the tables live in
/// `tables/` under it, the pipeline caches in `pipelines/` (`crate::pipeline_cache`), the
/// compiled shaders in `spirv/` (`crate::shader::ShaderCompiler`). `None` when
/// neither `LAMINA_CACHE` nor `HOME` is set.
pub fn root() -> Option<PathBuf> {
    std::env::var_os("LAMINA_CACHE")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/lamina")))
}

/// The tables' directory, `tables/` under [`root`]; `None` when neither `LAMINA_CACHE` nor
/// `HOME` is set.
pub fn tables_dir() -> Option<PathBuf> {
    Some(root()?.join("tables"))
}

/// FNV-1a over `bytes`: catches a file edited or damaged after it was written.
pub fn checksum(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The cached values of `key` in `dir`, if a valid file for exactly `count` values exists.
pub fn load(dir: &Path, key: &Key, count: usize) -> Option<Vec<f32>> {
    let path = dir.join(key.file_name());
    let bytes = std::fs::read(path).ok()?;
    let header = key.header(count);
    let data_len = count * 4;
    if bytes.len() != header.len() + data_len + 8 || bytes[..header.len()] != header[..] {
        return None;
    }
    let data = &bytes[header.len()..header.len() + data_len];
    let stored = u64::from_le_bytes(bytes[header.len() + data_len..].try_into().ok()?);
    if stored != checksum(data) {
        return None;
    }
    Some(
        data.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect(),
    )
}

/// The values of `key`: from `dir` when a valid file for `count` values is there (`true`),
/// else made by `build` and stored there (`false`). One builder at a time: a thread or
/// process that finds the table missing while another builds it waits for that build
/// (an exclusive lock on `KEY.lock` beside the file) and loads its result. Without a `dir`,
/// `build` runs.
pub fn load_or_build(
    dir: Option<&Path>,
    key: &Key,
    count: usize,
    build: impl FnOnce() -> crate::error::Result<Vec<f32>>,
) -> crate::error::Result<(Vec<f32>, bool)> {
    let Some(dir) = dir else {
        return Ok((build()?, false));
    };
    if let Some(values) = load(dir, key, count) {
        return Ok((values, true));
    }
    // A lock that cannot be taken (no directory, a read-only one) only loses the sharing.
    let _lock = build_lock(dir, key);
    if let Some(values) = load(dir, key, count) {
        return Ok((values, true));
    }
    let values = build()?;
    // A cache that cannot be written costs a rebuild next time, nothing more.
    let _ = store(dir, key, &values);
    Ok((values, false))
}

/// An exclusive lock on `key`'s lock file in `dir`, held until dropped; `None` where it
/// cannot be made.
fn build_lock(dir: &Path, key: &Key) -> Option<std::fs::File> {
    std::fs::create_dir_all(dir).ok()?;
    let mut name = key.file_name();
    name.push_str(".lock");
    let file = std::fs::File::create(dir.join(name)).ok()?;
    file.lock().ok()?;
    Some(file)
}

/// Stores `values` under `key` (atomically); a failure to write only costs a rebuild later,
/// so it is reported to the caller and may be ignored.
pub fn store(dir: &Path, key: &Key, values: &[f32]) -> crate::error::Result<PathBuf> {
    std::fs::create_dir_all(dir).map_err(|e| crate::error::Error::Output {
        path: dir.to_owned(),
        message: e.to_string(),
    })?;
    let path = dir.join(key.file_name());
    let mut bytes = key.header(values.len());
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let sum = checksum(&data);
    bytes.extend(&data);
    bytes.extend(sum.to_le_bytes());
    crate::imageio::write_file_atomically(&path, &bytes)?;
    remove_stale(dir, key);
    Ok(path)
}

/// Deletes the files of `key`'s kind and parameters built by other versions of its kernel: a
/// shader edit would otherwise leave a 64 MB FGD table behind each time.
fn remove_stale(dir: &Path, key: &Key) {
    let current = key.file_name();
    let prefix = &current[..current.len() - "0123456789abcdef.bin".len()];
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        // Other versions' tables and the lock files of their builds.
        let hash = name.strip_prefix(prefix).and_then(|rest| {
            rest.strip_suffix(".bin")
                .or_else(|| rest.strip_suffix(".bin.lock"))
        });
        if !name.starts_with(&current)
            && hash.is_some_and(|h| h.len() == 16 && h.bytes().all(|b| b.is_ascii_hexdigit()))
        {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// The file a key is cached in under `dir`.
pub fn path_of(dir: &Path, key: &Key) -> PathBuf {
    dir.join(key.file_name())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn storing_a_table_removes_its_other_versions_only() {
        let dir = std::env::temp_dir().join(format!("lamina-cache-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let key = |params: Vec<u32>, shader_hash| Key {
            kind: "tir",
            params,
            shader_hash,
        };
        store(&dir, &key(vec![8, 64], 1), &[1.0]).unwrap();
        store(&dir, &key(vec![8, 32], 1), &[2.0]).unwrap();
        store(&dir, &key(vec![8, 64], 2), &[3.0]).unwrap();
        assert!(
            load(&dir, &key(vec![8, 64], 1), 1).is_none(),
            "the old version is gone"
        );
        assert_eq!(load(&dir, &key(vec![8, 64], 2), 1), Some(vec![3.0]));
        assert_eq!(
            load(&dir, &key(vec![8, 32], 1), 1),
            Some(vec![2.0]),
            "other parameters stay"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Two builders of one missing table: the second waits for the first's build and loads it.
    #[test]
    fn a_table_is_built_once_by_concurrent_builders() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let dir = std::env::temp_dir().join(format!("lamina-cache-lock-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let key = Key {
            kind: "locked",
            params: vec![4],
            shader_hash: 7,
        };
        let builds = AtomicUsize::new(0);
        let outcomes: Vec<(Vec<f32>, bool)> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..2)
                .map(|_| {
                    scope.spawn(|| {
                        load_or_build(Some(&dir), &key, 4, || {
                            builds.fetch_add(1, Ordering::SeqCst);
                            std::thread::sleep(std::time::Duration::from_millis(200));
                            Ok(vec![1.0, 2.0, 3.0, 4.0])
                        })
                        .unwrap()
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert_eq!(builds.load(Ordering::SeqCst), 1, "built twice");
        assert!(outcomes.iter().all(|(v, _)| *v == [1.0, 2.0, 3.0, 4.0]));
        assert_eq!(outcomes.iter().filter(|(_, cached)| *cached).count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
