//! Embeds every file under `glsl/` into the binary, so lamina compiles its shaders at run time
//! from one source (no SPIR-V is committed) and the binary runs from any directory.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect(&path, out);
        } else if path.extension().is_some_and(|e| e == "glsl") {
            out.push(path);
        }
    }
}

fn main() {
    // Read when the script runs, not when it was compiled: one compiled script can serve two
    // checkouts that share a target directory.
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let root = Path::new(&manifest).join("glsl");
    println!("cargo:rerun-if-changed=glsl");
    let mut files = Vec::new();
    collect(&root, &mut files);
    let mut code = String::from("pub static GLSL_FILES: &[(&str, &str)] = &[\n");
    for path in &files {
        let rel = path.strip_prefix(&root).expect("under glsl/");
        let rel = rel.to_string_lossy().replace('\\', "/");
        writeln!(
            code,
            "    ({rel:?}, include_str!({:?})),",
            path.display().to_string()
        )
        .expect("write to String");
    }
    code.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR")).join("glsl_files.rs");
    std::fs::write(out, code).expect("write glsl_files.rs");
}
