//! The shape of the source tree (DESIGN.md §3), read from the files as text: no production file
//! under `src/` over 800 lines, no production function over 120 lines and at most 10 over 80,
//! and floors — the top-level modules import each other without a loop (so each stands above
//! all it imports; the binary's `cli` on top), the error enum aside, and `profile/`
//! (measurements) imports nothing from `study/` (the documents above them). `cargo test --test suite structure:: -- --nocapture`
//! prints the figures.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const MAX_FILE_LINES: usize = 800;
const MAX_FUNCTION_LINES: usize = 120;
const LONG_FUNCTION_LINES: usize = 80;
const MAX_LONG_FUNCTIONS: usize = 10;

/// A production source file of the library: its path under `src/`, its top-level module and
/// its lines with test code removed.
struct Source {
    path: PathBuf,
    module: String,
    lines: Vec<String>,
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The net count of `{` minus `}` on a line, outside strings and character literals.
fn brace_balance(line: &str) -> i64 {
    let (mut depth, mut in_string, mut escaped) = (0i64, false, false);
    let chars: Vec<char> = line.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if in_string {
            if escaped {
                escaped = false;
            } else if c == '\\' {
                escaped = true;
            } else if c == '"' {
                in_string = false;
            }
        } else if c == '"' {
            in_string = true;
        } else if c == '\'' && i + 2 < chars.len() && chars[i + 2] == '\'' {
            i += 2;
        } else if c == '\'' && i + 3 < chars.len() && chars[i + 1] == '\\' && chars[i + 3] == '\'' {
            i += 3;
        } else if c == '{' {
            depth += 1;
        } else if c == '}' {
            depth -= 1;
        }
        i += 1;
    }
    depth
}

/// The index of the line that closes the item starting at `start` (its braces balanced, or
/// its `;` when it has none).
fn item_end(lines: &[String], start: usize) -> usize {
    let mut depth = 0;
    let mut opened = false;
    for (i, line) in lines.iter().enumerate().skip(start) {
        let balance = brace_balance(line);
        opened |= line.contains('{');
        depth += balance;
        if opened && depth <= 0 {
            return i;
        }
        if !opened && line.trim_end().ends_with(';') {
            return i;
        }
    }
    lines.len() - 1
}

/// `text` without its `#[cfg(test)]` items: its production lines, comments included.
fn production_lines(text: &str) -> Vec<String> {
    let lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let trimmed = lines[i].trim();
        if trimmed == "#[cfg(test)]" {
            i = item_end(&lines, i + 1) + 1;
            continue;
        }
        out.push(lines[i].clone());
        i += 1;
    }
    out
}

/// The files a parent declares as `#[cfg(test)] mod name;`: test code as a whole.
fn test_only_files(files: &[PathBuf]) -> BTreeSet<PathBuf> {
    let mut out = BTreeSet::new();
    for file in files {
        let text = std::fs::read_to_string(file).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for pair in lines.windows(2) {
            if pair[0].trim() != "#[cfg(test)]" {
                continue;
            }
            let Some(name) = pair[1]
                .trim()
                .strip_prefix("mod ")
                .and_then(|rest| rest.strip_suffix(';'))
            else {
                continue;
            };
            let dir = if file
                .file_name()
                .is_some_and(|n| n == "mod.rs" || n == "lib.rs")
            {
                file.parent().unwrap().to_owned()
            } else {
                file.with_extension("")
            };
            out.insert(dir.join(format!("{name}.rs")));
            out.insert(dir.join(name).join("mod.rs"));
        }
    }
    out
}

/// The production sources under `src/`: the library's, and the binary's (`main.rs`, `cli/`),
/// whose module is `cli` — the top floor, which no library module may import.
fn sources() -> Vec<Source> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let tests = test_only_files(&files);
    files
        .into_iter()
        .filter(|f| !tests.contains(f))
        .filter_map(|path| {
            let relative = path.strip_prefix(&src).unwrap().to_owned();
            let first = relative.components().next()?.as_os_str().to_string_lossy();
            let module = match first.trim_end_matches(".rs") {
                "main" => "cli".to_owned(),
                other => other.to_owned(),
            };
            let lines = production_lines(&std::fs::read_to_string(&path).unwrap());
            Some(Source {
                path: relative,
                module,
                lines,
            })
        })
        .collect()
}

/// Every function of `source`: (name, lines).
fn functions(source: &Source) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    for (i, line) in source.lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let rest = ["pub(crate) ", "pub(super) ", "pub "]
            .iter()
            .find_map(|p| trimmed.strip_prefix(p))
            .unwrap_or(trimmed);
        let rest = rest.strip_prefix("const ").unwrap_or(rest);
        let rest = rest.strip_prefix("unsafe ").unwrap_or(rest);
        let Some(rest) = rest.strip_prefix("fn ") else {
            continue;
        };
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let end = item_end(&source.lines, i);
        out.push((name, end - i + 1));
    }
    out
}

/// The top-level modules `source` names as `crate::module` (`lamina::module` in the binary;
/// re-exports at the crate root resolved to their module), the error enum left out.
fn imports(source: &Source, modules: &BTreeSet<String>) -> BTreeSet<String> {
    // The binary names the library as `lamina`.
    let root = if source.module == "cli" {
        "lamina::"
    } else {
        "crate::"
    };
    let mut out = BTreeSet::new();
    for line in source
        .lines
        .iter()
        .filter(|l| !l.trim_start().starts_with("//"))
    {
        let mut rest = line.as_str();
        while let Some(at) = rest.find(root) {
            rest = &rest[at + root.len()..];
            let names: Vec<String> = if let Some(group) = rest.strip_prefix('{') {
                let close = group.find('}').unwrap_or(group.len());
                group[..close]
                    .split(',')
                    .map(|n| n.trim().split("::").next().unwrap_or("").to_owned())
                    .collect()
            } else {
                vec![rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect()]
            };
            for name in names {
                let module = match name.as_str() {
                    "Gpu" => "gpu".to_owned(),
                    "Size" => "size".to_owned(),
                    _ => name,
                };
                if module != source.module && module != "error" && modules.contains(&module) {
                    out.insert(module);
                }
            }
        }
    }
    out
}

#[test]
fn files_and_functions_stay_short() {
    let sources = sources();
    let mut long = Vec::new();
    let mut too_long_files = Vec::new();
    for source in &sources {
        if source.lines.len() > MAX_FILE_LINES {
            too_long_files.push(format!(
                "{} ({} lines)",
                source.path.display(),
                source.lines.len()
            ));
        }
        for (name, lines) in functions(source) {
            if lines > LONG_FUNCTION_LINES {
                long.push((lines, format!("{}: {name}", source.path.display())));
            }
        }
    }
    long.sort_by(|a, b| b.cmp(a));
    println!(
        "{} production files; the longest: {}",
        sources.len(),
        sources
            .iter()
            .map(|s| (s.lines.len(), s.path.display().to_string()))
            .max()
            .map(|(n, p)| format!("{p} ({n} lines)"))
            .unwrap_or_default()
    );
    println!("functions over {LONG_FUNCTION_LINES} lines: {}", long.len());
    for (lines, name) in &long {
        println!("  {lines:>4}  {name}");
    }
    assert!(
        too_long_files.is_empty(),
        "files over {MAX_FILE_LINES} production lines: {too_long_files:?}"
    );
    let over: Vec<_> = long
        .iter()
        .filter(|(n, _)| *n > MAX_FUNCTION_LINES)
        .collect();
    assert!(
        over.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines: {over:?}"
    );
    assert!(
        long.len() <= MAX_LONG_FUNCTIONS,
        "{} functions over {LONG_FUNCTION_LINES} lines (at most {MAX_LONG_FUNCTIONS})",
        long.len()
    );
}

#[test]
fn modules_stand_on_floors_and_measurements_know_no_documents() {
    // The crate root (`lib.rs`) only declares and re-exports the modules.
    let sources: Vec<Source> = sources()
        .into_iter()
        .filter(|s| s.module != "lib")
        .collect();
    let modules: BTreeSet<String> = sources.iter().map(|s| s.module.clone()).collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for source in &sources {
        graph
            .entry(source.module.clone())
            .or_default()
            .extend(imports(source, &modules));
    }
    let into_study: Vec<_> = sources
        .iter()
        .filter(|s| s.module == "profile" && imports(s, &modules).contains("study"))
        .map(|s| s.path.display().to_string())
        .collect();
    assert!(
        into_study.is_empty(),
        "profile/ imports study/: {into_study:?}"
    );
    // Floors: the ground holds what imports nothing; each floor above, what imports only
    // floors below it. A module left over stands in a loop.
    let mut floors: Vec<Vec<String>> = Vec::new();
    let mut placed: BTreeSet<String> = BTreeSet::new();
    while placed.len() < graph.len() {
        let floor: Vec<String> = graph
            .iter()
            .filter(|(m, deps)| !placed.contains(*m) && deps.iter().all(|d| placed.contains(d)))
            .map(|(m, _)| m.clone())
            .collect();
        if floor.is_empty() {
            let loop_members: Vec<_> = graph
                .iter()
                .filter(|(m, _)| !placed.contains(*m))
                .map(|(m, deps)| {
                    let up: Vec<_> = deps.iter().filter(|d| !placed.contains(*d)).collect();
                    format!("{m} -> {up:?}")
                })
                .collect();
            panic!("modules that import each other in a loop: {loop_members:#?}");
        }
        placed.extend(floor.iter().cloned());
        floors.push(floor);
    }
    for (i, floor) in floors.iter().enumerate() {
        println!("floor {}: {}", i + 1, floor.join(", "));
    }
}
