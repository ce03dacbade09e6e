//! GLSL → SPIR-V with shaderc, from the sources embedded at build time.
//!
//! Entry points are `glsl/<pass>.<stage>.glsl` with stage ∈ {vert, frag, comp}; includes live
//! under `glsl/include/` and are resolved relative to the including file first, then to
//! `glsl/include/`. Host constants reach GLSL as macro definitions ([`HOST_DEFINES`]) so shaders
//! never hard-code them.

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/glsl_files.rs"));
}

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Constants shared with GLSL; the shaders read them as macros.
pub const HOST_DEFINES: &[(&str, u32)] = &[
    ("LAMINA_MAX_LAYERS_LIMIT", crate::variant::MAX_LAYERS_LIMIT),
    ("LAMINA_TIR_SIZE", super::interface::TIR_TABLE_SIZE),
    ("LAMINA_FGD_SIZE", super::interface::FGD_GRID_SIZE),
    (
        "LAMINA_TRANSPORT_POINTS",
        crate::model::transport::POINTS as u32,
    ),
    (
        "LAMINA_TRANSPORT_OFFSET",
        super::interface::TRANSPORT_OFFSET as u32,
    ),
];

#[derive(Debug, thiserror::Error)]
pub enum ShaderError {
    #[error("no GLSL entry point `{0}` under glsl/ (entry points: {1})")]
    UnknownEntry(String, String),
    #[error("`{0}` is not named <pass>.<vert|frag|comp>.glsl")]
    UnknownStage(String),
    #[error("compiling glsl/{path}:\n{log}")]
    Compile { path: String, log: String },
    #[error("shaderc could not start: {0}")]
    Init(String),
}

/// The text of an embedded GLSL file, by its path under `glsl/`.
pub fn source(path: &str) -> Option<&'static str> {
    embedded::GLSL_FILES
        .iter()
        .find(|(p, _)| *p == path)
        .map(|(_, s)| *s)
}

fn fnv1a(h: u64, bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(h, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The files `entry` compiles from: itself and every include it reaches, by resolved path,
/// sorted.
fn sources_of(entry: &str) -> Vec<(String, std::borrow::Cow<'static, str>)> {
    let mut seen: Vec<(String, std::borrow::Cow<'static, str>)> = Vec::new();
    let mut pending = vec![entry.to_owned()];
    while let Some(path) = pending.pop() {
        let Some(text) = text_of(&path) else { continue };
        if seen.iter().any(|(p, _)| *p == path) {
            continue;
        }
        for line in text.lines() {
            let requested = line
                .trim_start()
                .strip_prefix("#include")
                .and_then(|rest| rest.trim().strip_prefix('"'))
                .and_then(|rest| rest.split('"').next());
            if let Some(name) = requested.and_then(|r| resolve_include(r, &path).ok()) {
                pending.push(name.resolved_name);
            }
        }
        seen.push((path, text));
    }
    seen.sort();
    seen
}

/// FNV-1a hash of what `entry`'s SPIR-V depends on: its text, the text of every include it
/// reaches and the host constants. A table cached on disk is keyed on the hash of the kernel
/// that builds it, so editing another shader does not invalidate it.
pub fn entry_hash(entry: &str) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325;
    for (path, text) in sources_of(entry) {
        h = fnv1a(h, path.bytes().chain([0]).chain(text.bytes()).chain([0]));
    }
    for (name, value) in HOST_DEFINES {
        h = fnv1a(h, name.bytes().chain(value.to_le_bytes()));
    }
    h
}

/// Every entry point (file at the top of `glsl/`), sorted.
pub fn entry_points() -> Vec<&'static str> {
    embedded::GLSL_FILES
        .iter()
        .map(|(p, _)| *p)
        .filter(|p| !p.contains('/'))
        .collect()
}

fn stage_of(entry: &str) -> Result<shaderc::ShaderKind, ShaderError> {
    let stem = entry
        .strip_suffix(".glsl")
        .ok_or_else(|| ShaderError::UnknownStage(entry.into()))?;
    match stem.rsplit('.').next() {
        Some("vert") => Ok(shaderc::ShaderKind::Vertex),
        Some("frag") => Ok(shaderc::ShaderKind::Fragment),
        Some("comp") => Ok(shaderc::ShaderKind::Compute),
        _ => Err(ShaderError::UnknownStage(entry.into())),
    }
}

/// Lexically normalises `a/b/../c` to `a/c` (embedded paths have no symlinks).
fn normalise(path: &Path) -> Option<String> {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::Normal(p) => out.push(p),
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            Component::CurDir => {}
            _ => return None,
        }
    }
    Some(out.to_string_lossy().replace('\\', "/"))
}

/// The files the compiler writes from Rust tables, under `glsl/include/generated/`: the codes
/// of every variant axis value and the model's constants, and the `specialized-values`
/// constants of every layer, so GLSL never copies them by hand.
const GENERATED_CODES: &str = "include/generated/codes.glsl";
const GENERATED_LAYER_VALUES: &str = "include/generated/layer_values.glsl";

/// The numeric parameters of every layer as specialization constants
/// (`LAYER<i>_<FIELD>`, ids from `variant::VALUE_ID_BASE`), and `tm_layer_values(i)`, the
/// layer they make: what `mode=specialized-values` reads instead of the material buffer. Then
/// the environment's lamps (`IBL_LAMP_<v>`, ids from `variant::LAMP_ID_BASE`) and
/// `ibl_lamp(i)`, their i-th vector: what `ibl=lamps` lights with (`tables::lamps`). On
/// lavapipe a constant costs nothing to read, where each vector of a uniform buffer costs
/// about 25 instructions a pixel.
fn layer_values_glsl() -> String {
    use crate::variant::{
        LAMP_ID_BASE, LAMP_VALUES, LAYER_VALUES, MAX_LAYERS_LIMIT, VALUES_PER_LAYER, VALUE_ID_BASE,
    };
    let mut out = String::from(
        "// Written by src/shader/compiler.rs from src/variant.rs (LAYER_VALUES). Needs\n\
         // shared/material.glsl's LayerGpu.\n\
         #ifndef LAMINA_GENERATED_LAYER_VALUES\n#define LAMINA_GENERATED_LAYER_VALUES\n",
    );
    for layer in 0..MAX_LAYERS_LIMIT {
        for (field, name) in LAYER_VALUES.iter().enumerate() {
            let id = VALUE_ID_BASE + VALUES_PER_LAYER * layer + field as u32;
            out.push_str(&format!(
                "layout(constant_id = {id}) const float LAYER{layer}_{name} = 0.0;\n"
            ));
        }
    }
    out.push_str("LayerGpu tm_layer_values(uint i) {\n    switch (i) {\n");
    for layer in 0..MAX_LAYERS_LIMIT {
        let v = |names: [&str; 3]| names.map(|n| format!("LAYER{layer}_{n}")).join(", ");
        out.push_str(&format!(
            "    case {layer}u: return LayerGpu(vec4({}, 0.0), vec4({}, 0.0), vec4({}, 0.0), \
             vec4({}, 0.0), vec4(LAYER{layer}_ALPHA, LAYER{layer}_DEPTH, LAYER{layer}_G, 0.0), \
             vec4(0.0));\n",
            v(["IOR_R", "IOR_G", "IOR_B"]),
            v(["KAPPA_R", "KAPPA_G", "KAPPA_B"]),
            v(["SIGMA_S_R", "SIGMA_S_G", "SIGMA_S_B"]),
            v(["SIGMA_A_R", "SIGMA_A_G", "SIGMA_A_B"]),
        ));
    }
    out.push_str("    }\n    return material.layers[i];\n}\n");
    for v in 0..LAMP_VALUES {
        let id = LAMP_ID_BASE + v as u32;
        out.push_str(&format!(
            "layout(constant_id = {id}) const float IBL_LAMP_{v} = 0.0;\n"
        ));
    }
    out.push_str("vec4 ibl_lamp(uint i) {\n    switch (i) {\n");
    for i in 0..LAMP_VALUES / 4 {
        let v = (0..4)
            .map(|c| format!("IBL_LAMP_{}", 4 * i + c))
            .collect::<Vec<_>>();
        out.push_str(&format!("    case {i}u: return vec4({});\n", v.join(", ")));
    }
    out.push_str("    }\n    return vec4(0.0);\n}\n#endif\n");
    out
}

fn codes_glsl() -> String {
    use crate::variant::{Axis, Fgd, Ibl, Mode, Model, Ndf, Tir, Transport, G2};
    fn axis<A: Axis>(out: &mut String) {
        for &(spelling, value) in A::VALUES {
            let name = format!("{}_{}", A::NAME, spelling)
                .to_uppercase()
                .replace('-', "_");
            out.push_str(&format!("#define {name} {}u\n", value.code()));
        }
    }
    let mut out = String::from(
        "// Written by src/shader/compiler.rs from the Rust value tables (src/variant.rs), the\n\
         // model's constants (model, model::hg, model::tir, model::tir_fit) and the tables'\n\
         // (shader::interface). Do not copy these by hand.\n\
         #ifndef LAMINA_GENERATED_CODES\n#define LAMINA_GENERATED_CODES\n",
    );
    axis::<Model>(&mut out);
    axis::<Tir>(&mut out);
    axis::<Fgd>(&mut out);
    axis::<G2>(&mut out);
    axis::<Ndf>(&mut out);
    axis::<Mode>(&mut out);
    axis::<Transport>(&mut out);
    axis::<Ibl>(&mut out);
    for (name, value) in [
        ("TM6_LOBES_PER_LAYER", crate::model::TM6_LOBES_PER_LAYER),
        ("TM6_LOBES_LESS", crate::model::TM6_LOBES_LESS),
    ] {
        out.push_str(&format!("#define {name} {value}u\n"));
    }
    out.push_str(&format!(
        "#define IBL_LAMP_COUNT {}u\n",
        crate::variant::LAMP_SLOTS
    ));
    for (name, value) in [
        ("TM_INDEX_MATCHED", crate::model::INDEX_MATCHED),
        ("TM_REFLECTS_NOTHING", crate::model::REFLECTS_NOTHING),
        ("HG_RATIO_FLOOR", crate::model::hg::RATIO_FLOOR),
        ("HG_MIN_ALPHA", crate::model::hg::MIN_ALPHA),
        ("LIGHT_MIN_ALPHA", crate::model::light::MIN_ALPHA),
        ("LIGHT_MIN_ALPHA_FP16", crate::model::light::MIN_ALPHA_FP16),
        (
            "LOBE_ALBEDO_SIZE",
            f64::from(super::interface::LOBE_ALBEDO_SIZE),
        ),
        (
            "LOBE_MOMENTS_SIZE",
            f64::from(super::interface::LOBE_MOMENTS_SIZE),
        ),
        ("FGD_ETA_MAX", super::interface::FGD_ETA_MAX),
        ("FGD_KAPPA_MAX", super::interface::FGD_KAPPA_MAX),
        ("BELCOUR_CT1", super::interface::BELCOUR_CT1),
        ("BELCOUR_CT2", super::interface::BELCOUR_CT2),
        (
            "TIR_CONSTANT_FRACTION",
            crate::model::tir::CONSTANT_FRACTION,
        ),
        ("TIR_FIT_MIN_SCALE", crate::model::tir::FIT_MIN_SCALE),
        ("TIR_FIT_X_MIN", crate::model::tir::fit_roughness(0.0)),
        ("TIR_FIT_X_MAX", crate::model::tir::fit_roughness(1.0)),
    ] {
        out.push_str(&format!("#define {name} {value:e}\n"));
    }
    out.push_str(&arrays_glsl());
    out.push_str("#endif\n");
    out
}

/// The constant arrays of `codes.glsl`: `tir=fit`'s coefficients (model::tir_fit, written by
/// `lamina tables tir-fit`), `ibl=lamps`' polynomial placement of its fetch
/// (tables::lobe_fit::polynomial) and the Gauss–Legendre rule of the hemispherical Fresnel
/// averages (model::diffuse), over s = √μ on [0, 1].
fn arrays_glsl() -> String {
    let mut out = String::new();
    let arrays: [(&str, &[f64]); 3] = [
        ("TIR_FIT_COEFFICIENTS", &crate::model::tir_fit::COEFFICIENTS),
        ("IBL_LAMPS_LEAN", &super::interface::LAMPS_LEAN_COEFFICIENTS),
        ("IBL_LAMPS_ROOT", &super::interface::LAMPS_ROOT_COEFFICIENTS),
    ];
    for (name, values) in arrays {
        let n = values.len();
        let list: Vec<String> = values.iter().map(|c| format!("{c:e}")).collect();
        out.push_str(&format!(
            "const float {name}[{n}] = float[{n}]({});\n",
            list.join(", ")
        ));
    }
    let rule = crate::model::diffuse::gauss_legendre_unit(crate::model::diffuse::HEMISPHERE_POINTS);
    let list = |f: &dyn Fn(&(f64, f64)) -> f64| {
        rule.iter()
            .map(|p| format!("{:e}", f(p)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let n = rule.len();
    out.push_str(&format!("#define HEMISPHERE_POINTS {n}\n"));
    out.push_str(&format!(
        "const float HEMISPHERE_MU[{n}] = float[{n}]({});\n",
        list(&|p| p.0)
    ));
    out.push_str(&format!(
        "const float HEMISPHERE_W[{n}] = float[{n}]({});\n",
        list(&|p| p.1)
    ));
    out
}

/// The text of a file under `glsl/`: embedded, or generated.
fn text_of(path: &str) -> Option<std::borrow::Cow<'static, str>> {
    if path == GENERATED_CODES {
        return Some(codes_glsl().into());
    }
    if path == GENERATED_LAYER_VALUES {
        return Some(layer_values_glsl().into());
    }
    source(path).map(std::borrow::Cow::Borrowed)
}

fn resolve_include(requested: &str, requester: &str) -> Result<shaderc::ResolvedInclude, String> {
    let requester_dir = Path::new(requester).parent().unwrap_or(Path::new(""));
    let candidates = [
        normalise(&requester_dir.join(requested)),
        normalise(&Path::new("include").join(requested)),
    ];
    for name in candidates.into_iter().flatten() {
        if let Some(content) = text_of(&name) {
            return Ok(shaderc::ResolvedInclude {
                resolved_name: name,
                content: content.into_owned(),
            });
        }
    }
    Err(format!(
        "cannot find include `{requested}` (from {requester}) under glsl/ or glsl/include/"
    ))
}

/// Compiles entry points; one shaderc compiler per instance, which remembers the SPIR-V of
/// every entry point and set of defines it compiled, in memory and on disk
/// (`$LAMINA_CACHE/spirv/`): a variant's pipelines differ in their specialization constants,
/// not their SPIR-V, and shaderc takes about a second over the forward shader natively and
/// several under valgrind, where the counting workers run — they read what the timing run
/// compiled.
pub struct ShaderCompiler {
    compiler: shaderc::Compiler,
    compiled: Mutex<HashMap<String, Arc<[u32]>>>,
    disk: Option<PathBuf>,
}

impl ShaderCompiler {
    /// A compiler with the disk cache under lamina's cache root (none when it has no root).
    pub fn new() -> Result<Self, ShaderError> {
        Self::with_disk_cache(crate::cache::root().map(|r| r.join("spirv")))
    }

    /// A compiler keeping its SPIR-V in `disk` too (`None`: in memory only).
    pub fn with_disk_cache(disk: Option<PathBuf>) -> Result<Self, ShaderError> {
        let compiler = shaderc::Compiler::new().map_err(|e| ShaderError::Init(e.to_string()))?;
        Ok(Self {
            compiler,
            compiled: Mutex::new(HashMap::new()),
            disk,
        })
    }

    /// Compiles `entry` (a path under `glsl/`) with extra `defines` (name, value), or returns
    /// what an earlier call with the same arguments compiled.
    pub fn compile(
        &self,
        entry: &str,
        defines: &[(&str, &str)],
    ) -> Result<Arc<[u32]>, ShaderError> {
        let key = defines.iter().fold(entry.to_owned(), |k, (name, value)| {
            format!("{k}\0{name}={value}")
        });
        // A poisoned lock only means another thread panicked mid-insert of a complete value.
        let lock = || self.compiled.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(words) = lock().get(&key) {
            return Ok(Arc::clone(words));
        }
        let text = source(entry)
            .ok_or_else(|| ShaderError::UnknownEntry(entry.into(), entry_points().join(", ")))?;
        let file = self
            .disk
            .as_deref()
            .map(|dir| SpirvFile::new(dir, entry, defines));
        let words: Arc<[u32]> = match file.as_ref().and_then(SpirvFile::load) {
            Some(words) => words.into(),
            None => {
                let words = self.compile_source(entry, text, defines)?;
                if let Some(file) = &file {
                    // A cache that cannot be written costs a compile next time, nothing more.
                    file.store(&words);
                }
                words.into()
            }
        };
        lock().insert(key, Arc::clone(&words));
        Ok(words)
    }

    /// Compiles `text` as if it were the entry point `name` (which gives the stage).
    pub fn compile_source(
        &self,
        name: &str,
        text: &str,
        defines: &[(&str, &str)],
    ) -> Result<Vec<u32>, ShaderError> {
        let entry = name;
        let kind = stage_of(entry)?;
        let mut options =
            shaderc::CompileOptions::new().map_err(|e| ShaderError::Init(e.to_string()))?;
        options.set_target_env(
            shaderc::TargetEnv::Vulkan,
            shaderc::EnvVersion::Vulkan1_3 as u32,
        );
        options.set_optimization_level(shaderc::OptimizationLevel::Performance);
        options.set_include_callback(|requested, _kind, requester, _depth| {
            resolve_include(requested, requester)
        });
        for (name, value) in HOST_DEFINES {
            options.add_macro_definition(name, Some(&value.to_string()));
        }
        for (name, value) in defines {
            options.add_macro_definition(name, Some(value));
        }
        let artifact = self
            .compiler
            .compile_into_spirv(text, kind, entry, "main", Some(&options))
            .map_err(|e| ShaderError::Compile {
                path: entry.into(),
                log: e.to_string(),
            })?;
        Ok(artifact.as_binary().to_vec())
    }
}

/// One entry point's SPIR-V on disk: `<entry>-<defines>-<sources>.spv`, the last two FNV-1a
/// hashes (of the defines; of the entry's text, its includes and the host constants,
/// [`entry_hash`]). The file holds a magic number, the word count, the words and a checksum;
/// anything else reads as absent. Storing removes the entry's files for other sources.
struct SpirvFile {
    dir: PathBuf,
    prefix: String,
    name: String,
}

const SPIRV_MAGIC: &[u8; 8] = b"LAMSPV01";

impl SpirvFile {
    fn new(dir: &Path, entry: &str, defines: &[(&str, &str)]) -> Self {
        let defines_hash = defines.iter().fold(0xcbf2_9ce4_8422_2325, |h, (n, v)| {
            fnv1a(h, n.bytes().chain([0]).chain(v.bytes()).chain([0]))
        });
        let stem = entry.strip_suffix(".glsl").unwrap_or(entry);
        let prefix = format!("{stem}-{defines_hash:016x}-");
        let name = format!("{prefix}{:016x}.spv", entry_hash(entry));
        Self {
            dir: dir.to_owned(),
            prefix,
            name,
        }
    }

    fn load(&self) -> Option<Vec<u32>> {
        let bytes = std::fs::read(self.dir.join(&self.name)).ok()?;
        let body = bytes.strip_prefix(SPIRV_MAGIC)?;
        let (count, rest) = body.split_first_chunk::<8>()?;
        let count = usize::try_from(u64::from_le_bytes(*count)).ok()?;
        let (data, sum) = rest.split_at_checked(count.checked_mul(4)?)?;
        if sum != crate::cache::checksum(data).to_le_bytes() {
            return None;
        }
        let words: Vec<u32> = data
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        (words.first() == Some(&0x0723_0203)).then_some(words)
    }

    fn store(&self, words: &[u32]) {
        if std::fs::create_dir_all(&self.dir).is_err() {
            return;
        }
        let data: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        let mut bytes = SPIRV_MAGIC.to_vec();
        bytes.extend((words.len() as u64).to_le_bytes());
        bytes.extend(&data);
        bytes.extend(crate::cache::checksum(&data).to_le_bytes());
        let path = self.dir.join(&self.name);
        let written = crate::imageio::write_file_atomically(&path, &bytes);
        if written.is_err() {
            return;
        }
        let Ok(entries) = std::fs::read_dir(&self.dir) else {
            return;
        };
        for entry in entries.flatten() {
            let file = entry.file_name().to_string_lossy().into_owned();
            if file != self.name && file.starts_with(&self.prefix) && file.ends_with(".spv") {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_entry_is_compiled_once_per_set_of_defines() {
        let shaders = ShaderCompiler::new().unwrap();
        let plain = shaders.compile("tir_table.comp.glsl", &[]).unwrap();
        let again = shaders.compile("tir_table.comp.glsl", &[]).unwrap();
        assert!(Arc::ptr_eq(&plain, &again));
        let defined = shaders
            .compile("tir_table.comp.glsl", &[("LAMINA_FP16", "1")])
            .unwrap();
        assert!(!Arc::ptr_eq(&plain, &defined));
        assert_eq!(plain[0], 0x0723_0203, "SPIR-V magic");
        assert!(matches!(
            shaders.compile("nope.comp.glsl", &[]),
            Err(ShaderError::UnknownEntry(..))
        ));
    }

    #[test]
    fn spirv_is_kept_on_disk_and_damaged_files_are_compiled_again() {
        let dir = std::env::temp_dir().join(format!("lamina-spirv-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let entry = "tir_table.comp.glsl";
        let defines = [("LAMINA_FP16", "1")];
        let first = ShaderCompiler::with_disk_cache(Some(dir.clone())).unwrap();
        let compiled = first.compile(entry, &defines).unwrap();
        let file = SpirvFile::new(&dir, entry, &defines);
        assert_eq!(
            file.load().as_deref(),
            Some(&compiled[..]),
            "stored as compiled"
        );
        // Another compiler reads the file instead of compiling: planted words come back.
        let planted = [0x0723_0203, 1, 2, 3];
        file.store(&planted);
        let second = ShaderCompiler::with_disk_cache(Some(dir.clone())).unwrap();
        assert_eq!(&second.compile(entry, &defines).unwrap()[..], &planted[..]);
        // Other defines are another file.
        assert_ne!(&second.compile(entry, &[]).unwrap()[..], &planted[..]);
        // A truncated file reads as absent: compiled again and rewritten whole.
        let path = dir.join(&file.name);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 3]).unwrap();
        let third = ShaderCompiler::with_disk_cache(Some(dir.clone())).unwrap();
        assert_eq!(third.compile(entry, &defines).unwrap(), compiled);
        assert_eq!(file.load().as_deref(), Some(&compiled[..]));
        // A file of the same entry and defines from other sources is removed on store.
        let stale = dir.join(format!("{}0000000000000000.spv", file.prefix));
        std::fs::write(&stale, b"old").unwrap();
        file.store(&compiled);
        assert!(!stale.exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn includes_resolve_relative_then_rooted() {
        let r = resolve_include("lib/math.glsl", "tonemap.comp.glsl").unwrap();
        assert_eq!(r.resolved_name, "include/lib/math.glsl");
        let r = resolve_include("../shared/frame.glsl", "include/lib/ibl.glsl").unwrap();
        assert_eq!(r.resolved_name, "include/shared/frame.glsl");
        let e = resolve_include("lib/nope.glsl", "x.comp.glsl").unwrap_err();
        assert!(e.contains("lib/nope.glsl"), "{e}");
    }

    #[test]
    fn an_entry_hash_covers_its_includes_only() {
        let files: Vec<String> = sources_of("tir_table.comp.glsl")
            .into_iter()
            .map(|(p, _)| p)
            .collect();
        assert!(
            files.contains(&"tir_table.comp.glsl".to_owned()),
            "{files:?}"
        );
        assert!(
            files.contains(&"include/lib/sampling.glsl".to_owned()),
            "{files:?}"
        );
        assert!(
            !files
                .iter()
                .any(|f| f.contains("tm2") || f.contains("forward")),
            "{files:?}"
        );
        assert_ne!(
            entry_hash("tir_table.comp.glsl"),
            entry_hash("split_sum.comp.glsl")
        );
    }

    #[test]
    fn generated_codes_follow_the_value_tables() {
        let text = codes_glsl();
        for line in [
            "#define MODEL_TM6 2u",
            "#define TIR_LUT16 4u",
            "#define TIR_FIT 5u",
            "#define FGD_RESAMPLED4D 3u",
            "#define G2_HEIGHT_CORRELATED 0u",
            "#define NDF_KARIS 1u",
            "#define TM_INDEX_MATCHED 1e-5",
        ] {
            assert!(
                text.lines().any(|l| l == line),
                "{line} missing from:\n{text}"
            );
        }
        let r = resolve_include("../generated/codes.glsl", "include/shared/variant.glsl").unwrap();
        assert_eq!(r.resolved_name, GENERATED_CODES);
        assert!(sources_of("forward.frag.glsl")
            .iter()
            .any(|(p, _)| p == GENERATED_CODES));
    }

    #[test]
    fn compile_errors_name_file_and_line() {
        let c = ShaderCompiler::new().unwrap();
        let err = c.compile("does-not-exist.comp.glsl", &[]).unwrap_err();
        assert!(matches!(err, ShaderError::UnknownEntry(..)));
        let broken =
            "#version 460\n#include \"lib/math.glsl\"\nvoid main() { undefined_thing(); }\n";
        let err = c
            .compile_source("broken.comp.glsl", broken, &[])
            .unwrap_err();
        let text = err.to_string();
        assert!(text.contains("broken.comp.glsl:3:"), "{text}");
        assert!(text.contains("undefined_thing"), "{text}");
    }
}
