//! `lamina export`: the forward pass of one variant and material as SPIR-V with its
//! specialization constants frozen to the pass's values (`lamina::shader::freeze`), one module
//! per entry point, and `spec.json` with the values: input for offline compilers and shader
//! analysers that take no specialization data.

use std::collections::HashMap;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use lamina::imageio::write_file_atomically;
use lamina::material::resolve_with_variant;
use lamina::profile::plan::Case;
use lamina::render::forward;
use lamina::render::lights::Lighting;
use lamina::shader::freeze::freeze;
use lamina::shader::ShaderCompiler;
use lamina::variant::{Mode, ShadeSpec};
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
    let spec = key.spec(None);
    let compiler = ShaderCompiler::new()?;
    let constants = constants(&spec);
    let values: HashMap<u32, u32> = constants.iter().map(|c| (c.id, c.bits)).collect();
    let mut modules = Vec::new();
    for entry in forward::ENTRIES {
        let words = compiler.compile(entry, &variant.defines())?;
        let frozen = freeze(&words, &values).with_context(|| format!("freezing {entry}"))?;
        let file = format!("{}.spv", entry.trim_end_matches(".glsl"));
        let bytes: &[u8] = bytemuck::cast_slice(&frozen);
        write_file_atomically(&args.out.join(&file), bytes)?;
        modules.push(Module {
            entry: entry.to_string(),
            file,
            bytes: bytes.len(),
        });
    }
    let spec_file = SpecFile {
        variant: variant.to_string(),
        material,
        modules,
        constants,
    };
    let json = serde_json::to_string_pretty(&spec_file)?;
    write_file_atomically(&args.out.join("spec.json"), json)?;
    for m in &spec_file.modules {
        println!(
            "wrote {} ({} bytes)",
            args.out.join(&m.file).display(),
            m.bytes
        );
    }
    println!("wrote {}", args.out.join("spec.json").display());
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
