//! `lamina export`: the forward pass of one variant and material as SPIR-V with its
//! specialization constants frozen to the pass's values (`lamina::shader::freeze`), one module
//! per entry point, and `spec.json` with the values: input for offline compilers and shader
//! analysers that take no specialization data. A varying stack under `mode=specialized`
//! draws several pipelines (`render::classes`): each gets its own sub-directory of the same
//! layout, `mark-layer-N/` for a stencil mark and `class-BB/` for a class of pixels. On the
//! deferred path the shading kernels are exported: the one over every pixel, or a classified
//! pass's kernel per class (`class-BB/`) and, classified by tile, the generic one its mixed
//! tiles take (`mixed/`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use lamina::imageio::write_file_atomically;
use lamina::material::resolve_with_variant;
use lamina::profile::plan::Case;
use lamina::render::classes::Class;
use lamina::render::lights::Lighting;
use lamina::render::pass::{MaterialKey, PassKey};
use lamina::render::{deferred, forward};
use lamina::shader::freeze::freeze;
use lamina::shader::kernel::WorkGroupSpec;
use lamina::shader::ShaderCompiler;
use lamina::variant::{Classify, Mode, ShadePath, ShadeSpec};
use lamina::vk::SpecConstants;

#[derive(clap::Args)]
pub struct ExportArgs {
    /// Shader variant; axes not given come from the defaults and the material's model.
    #[arg(long, value_name = "KEY")]
    variant: Option<String>,
    /// Material file or preset name (see assets/materials/).
    #[arg(long, value_name = "FILE|PRESET")]
    material: String,
    /// Directory for the modules (`forward.vert.spv`, `forward.frag.spv`) and `spec.json`.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// `spec.json`: what the modules were frozen from.
#[derive(serde::Serialize)]
struct SpecFile {
    variant: String,
    material: String,
    /// A routed pass's draw: what it is (a stencil mark, or a class and its layers).
    #[serde(skip_serializing_if = "Option::is_none")]
    draw: Option<String>,
    /// The modules written, by entry point.
    modules: Vec<Module>,
    /// Every specialization constant: its SpecId and the 32 bits it was frozen to (the
    /// layers' values are floats; `float` gives them as such).
    constants: Vec<Constant>,
}

#[derive(serde::Serialize)]
struct Module {
    entry: String,
    file: String,
    bytes: usize,
}

#[derive(serde::Serialize)]
struct Constant {
    id: u32,
    bits: u32,
    #[serde(skip_serializing_if = "Option::is_none")]
    float: Option<f32>,
}

pub fn run(args: &ExportArgs) -> Result<()> {
    let (stack, variant) = resolve_with_variant(&args.material, args.variant.as_deref())?;
    if variant.mode == Mode::Baked {
        bail!(
            "mode=baked is not exported: a baked pass's constants come from its table, baked on \
             a device; `lamina export` takes mode=generic, specialized and specialized-values"
        );
    }
    let material = stack.name.clone();
    let key = Case { variant, stack }.pass_key(&Lighting::default())?;
    let draws = if variant.path == ShadePath::Deferred {
        deferred_draws(&key, &args.out)?
    } else {
        forward_draws(&key, &args.out)
    };
    let mut defines = variant.defines();
    if variant.path == ShadePath::Deferred && variant.classify == Classify::Tiles {
        defines.push(("LAMINA_BIN_TILES", "1"));
    }
    let compiler = ShaderCompiler::new()?;
    for (dir, draw, entries, spec) in draws {
        let file = SpecFile {
            variant: variant.to_string(),
            material: material.clone(),
            draw,
            modules: Vec::new(),
            constants: constants(&spec),
        };
        export_draw(&compiler, &dir, &entries, file, &defines)?;
    }
    Ok(())
}

/// One pipeline to export: its directory, what it draws (a routed or classified pass's
/// part), its entry points and its constants.
type Draw = (PathBuf, Option<String>, Vec<&'static str>, ShadeSpec);

/// The forward pass's draws: one, or a routed pass's stencil marks and classes.
fn forward_draws(key: &PassKey, out: &Path) -> Vec<Draw> {
    let vertex = forward::ENTRIES[0];
    match &key.material {
        MaterialKey::Classes(routing) => {
            let marks = routing.marks.iter().map(|&layer| {
                (
                    out.join(format!("mark-layer-{}", layer + 1)),
                    Some(format!("stencil mark of layer {}'s coverage", layer + 1)),
                    vec![vertex, forward::MARK_ENTRY],
                    key.mark_spec(layer),
                )
            });
            let classes = routing.classes.iter().map(|class| {
                (
                    out.join(format!("class-{:02x}", class.bits)),
                    Some(class_text(class)),
                    forward::ENTRIES.to_vec(),
                    key.class_spec(class),
                )
            });
            marks.chain(classes).collect()
        }
        _ => vec![(
            out.to_owned(),
            None,
            forward::ENTRIES.to_vec(),
            key.spec(None),
        )],
    }
}

/// The deferred path's shading kernels (the G-buffer's draw and the classification shade
/// nothing): the kernel over every pixel, or one per bin of a classified pass, a routed
/// stack's classes in `class-BB/` and the tiles that mix them in `mixed/`.
fn deferred_draws(key: &PassKey, out: &Path) -> Result<Vec<Draw>> {
    let variant = key.variant;
    let local = |spec: ShadeSpec| spec.with_local_size([deferred::TILE, deferred::TILE]);
    let classes = match &key.material {
        MaterialKey::Classes(routing) => routing.classes.as_slice(),
        _ => &[],
    };
    if variant.classify == Classify::None {
        let spec = deferred::grid_spec(key, key.spec(None))?;
        return Ok(vec![(
            out.to_owned(),
            None,
            vec![deferred::KERNEL.entry],
            local(spec),
        )]);
    }
    let bins = deferred::bin_specs(key, key.spec(None), variant.classify == Classify::Tiles);
    if classes.is_empty() {
        let (_, spec) = bins[0];
        return Ok(vec![(
            out.to_owned(),
            None,
            vec![deferred::BINS_KERNEL.entry],
            local(spec),
        )]);
    }
    Ok(bins
        .into_iter()
        .map(|(bin, spec)| {
            let (dir, text) = match classes.iter().find(|c| c.bits == bin) {
                Some(class) => (format!("class-{bin:02x}"), class_text(class)),
                None => (
                    "mixed".to_string(),
                    "the tiles whose pixels mix classes: the generic pipeline".to_string(),
                ),
            };
            (
                out.join(dir),
                Some(text),
                vec![deferred::BINS_KERNEL.entry],
                local(spec),
            )
        })
        .collect())
}

/// A class of pixels as `spec.json` names it: its bits and its layers.
fn class_text(class: &Class) -> String {
    let layers: Vec<String> = class.layers.iter().map(|m| (m + 1).to_string()).collect();
    format!("class {:#04x}: layers [{}]", class.bits, layers.join(", "))
}

/// Writes `entries` frozen to `file`'s constants into `dir`, then `file` (with the modules)
/// as `spec.json`.
fn export_draw(
    compiler: &ShaderCompiler,
    dir: &Path,
    entries: &[&str],
    mut file: SpecFile,
    defines: &[(&str, &str)],
) -> Result<()> {
    let values: HashMap<u32, u32> = file.constants.iter().map(|c| (c.id, c.bits)).collect();
    for entry in entries {
        let words = compiler.compile(entry, defines)?;
        let frozen = freeze(&words, &values).with_context(|| format!("freezing {entry}"))?;
        let name = format!("{}.spv", entry.trim_end_matches(".glsl"));
        let bytes: &[u8] = bytemuck::cast_slice(&frozen);
        write_file_atomically(&dir.join(&name), bytes)?;
        println!(
            "wrote {} ({} bytes)",
            dir.join(&name).display(),
            bytes.len()
        );
        file.modules.push(Module {
            entry: entry.to_string(),
            file: name,
            bytes: bytes.len(),
        });
    }
    let json = serde_json::to_string_pretty(&file)?;
    write_file_atomically(&dir.join("spec.json"), json)?;
    println!("wrote {}", dir.join("spec.json").display());
    Ok(())
}

/// Every specialization constant of the shading pass with its value in `spec` (the ids are
/// `ShadeSpec`'s, named in `glsl/include/shared/variant.glsl`).
fn constants(spec: &ShadeSpec) -> Vec<Constant> {
    let bytes = bytemuck::bytes_of(spec);
    let values_at = std::mem::offset_of!(ShadeSpec, values);
    ShadeSpec::ENTRIES
        .iter()
        .map(|e| {
            let word: [u8; 4] = bytes[e.offset..e.offset + 4]
                .try_into()
                .expect("every entry is four bytes");
            let bits = u32::from_ne_bytes(word);
            Constant {
                id: e.id,
                bits,
                float: (e.offset >= values_at).then(|| f32::from_bits(bits)),
            }
        })
        .collect()
}
