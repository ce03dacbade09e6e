//! SPIR-V with its specialization constants frozen to given values: the module a driver
//! compiles for one pipeline, for offline tools that take no specialization data (Radeon GPU
//! Analyzer's offline mode, spirv-cross, compiler explorers).
//!
//! The values are written into the constants' defaults here (a SPIR-V walk: `OpDecorate …
//! SpecId` names the constant, `OpSpecConstant` holds its default, `OpSpecConstantTrue/False`
//! its truth), then `spirv-opt` (Debian's `spirv-tools`) turns every specialization constant
//! into a plain one and folds what depends on them, and `spirv-val` validates the result.

use std::collections::HashMap;
use std::io::Write;
use std::process::{Command, Stdio};

const OP_DECORATE: u32 = 71;
const DECORATION_SPEC_ID: u32 = 1;
const OP_SPEC_CONSTANT_TRUE: u32 = 48;
const OP_SPEC_CONSTANT_FALSE: u32 = 49;
const OP_SPEC_CONSTANT: u32 = 50;
const OP_SPEC_CONSTANT_OP: u32 = 52;
const HEADER_WORDS: usize = 5;

/// Why a module could not be frozen.
#[derive(Debug, thiserror::Error)]
pub enum FreezeError {
    #[error("not a SPIR-V module: {0}")]
    Malformed(String),
    #[error("specialization constant {id} is {words} words wide; only 32-bit constants are set")]
    Wide { id: u32, words: usize },
    #[error(
        "{tool} (Debian: apt-get install spirv-tools; scripts/setup.sh installs it): {message}"
    )]
    Tool { tool: &'static str, message: String },
    #[error("the frozen module still holds {0} specialization constant(s)")]
    NotFrozen(usize),
}

/// The module's instructions: (start word, opcode, word count).
fn instructions(words: &[u32]) -> Result<Vec<(usize, u32, usize)>, FreezeError> {
    if words.len() < HEADER_WORDS || words[0] != 0x0723_0203 {
        return Err(FreezeError::Malformed("no SPIR-V header".into()));
    }
    let mut out = Vec::new();
    let mut at = HEADER_WORDS;
    while at < words.len() {
        let count = (words[at] >> 16) as usize;
        if count == 0 || at + count > words.len() {
            return Err(FreezeError::Malformed(format!(
                "an instruction at word {at} runs past the module"
            )));
        }
        out.push((at, words[at] & 0xffff, count));
        at += count;
    }
    Ok(out)
}

/// `words` with the default of each specialization constant named in `values` (SpecId → the
/// value's 32 bits) set to that value; constants not named keep their defaults.
pub fn set_defaults(words: &[u32], values: &HashMap<u32, u32>) -> Result<Vec<u32>, FreezeError> {
    let instructions = instructions(words)?;
    let mut spec_id = HashMap::new();
    for &(at, op, count) in &instructions {
        if op == OP_DECORATE && count >= 4 && words[at + 2] == DECORATION_SPEC_ID {
            spec_id.insert(words[at + 1], words[at + 3]);
        }
    }
    let mut out = words.to_vec();
    for &(at, op, count) in &instructions {
        let is_spec = matches!(
            op,
            OP_SPEC_CONSTANT | OP_SPEC_CONSTANT_TRUE | OP_SPEC_CONSTANT_FALSE
        );
        if !is_spec || count < 3 {
            continue;
        }
        let Some(value) = spec_id.get(&words[at + 2]).and_then(|id| values.get(id)) else {
            continue;
        };
        match op {
            OP_SPEC_CONSTANT if count == 4 => out[at + 3] = *value,
            OP_SPEC_CONSTANT => {
                return Err(FreezeError::Wide {
                    id: spec_id[&words[at + 2]],
                    words: count - 3,
                })
            }
            _ => {
                let op = if *value != 0 {
                    OP_SPEC_CONSTANT_TRUE
                } else {
                    OP_SPEC_CONSTANT_FALSE
                };
                out[at] = (words[at] & 0xffff_0000) | op;
            }
        }
    }
    Ok(out)
}

/// How many specialization constants `words` holds, of any kind (`OpSpecConstantTrue` to
/// `OpSpecConstantOp`, composites included).
pub fn spec_constant_count(words: &[u32]) -> Result<usize, FreezeError> {
    Ok(instructions(words)?
        .iter()
        .filter(|&&(_, op, _)| (OP_SPEC_CONSTANT_TRUE..=OP_SPEC_CONSTANT_OP).contains(&op))
        .count())
}

/// `words` with the constants of `values` set ([`set_defaults`]), every specialization
/// constant frozen and folded by `spirv-opt`, validated by `spirv-val` (Vulkan 1.3 rules).
pub fn freeze(words: &[u32], values: &HashMap<u32, u32>) -> Result<Vec<u32>, FreezeError> {
    let set = set_defaults(words, values)?;
    let frozen = run_tool(
        "spirv-opt",
        &[
            "--freeze-spec-const",
            "--fold-spec-const-op-composite",
            "--eliminate-dead-const",
            "--target-env=vulkan1.3",
            "-",
            "-o",
            "-",
        ],
        &set,
    )?;
    let frozen: Vec<u32> = bytemuck::pod_collect_to_vec(&frozen);
    run_tool(
        "spirv-val",
        &["--target-env", "vulkan1.3", "-"],
        bytemuck::cast_slice(&frozen),
    )?;
    let left = spec_constant_count(&frozen)?;
    if left > 0 {
        return Err(FreezeError::NotFrozen(left));
    }
    Ok(frozen)
}

/// Runs `tool args` with `input` on its standard input; its standard output.
fn run_tool(tool: &'static str, args: &[&str], input: &[u32]) -> Result<Vec<u8>, FreezeError> {
    let fail = |message: String| FreezeError::Tool { tool, message };
    let mut child = Command::new(tool)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| fail(format!("cannot start it: {e}")))?;
    let mut stdin = child.stdin.take().expect("stdin was piped");
    let bytes: Vec<u8> = bytemuck::cast_slice(input).to_vec();
    let writer = std::thread::spawn(move || stdin.write_all(&bytes));
    let out = child
        .wait_with_output()
        .map_err(|e| fail(format!("waiting for it: {e}")))?;
    writer
        .join()
        .expect("the writer only writes")
        .map_err(|e| fail(format!("writing the module to it: {e}")))?;
    if !out.status.success() {
        return Err(fail(format!(
            "failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    Ok(out.stdout)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::ShaderCompiler;
    use crate::variant::VariantKey;
    use crate::vk::SpecConstants;

    fn forward_fragment() -> Vec<u32> {
        let variant = VariantKey::default();
        ShaderCompiler::with_disk_cache(None)
            .unwrap()
            .compile("forward.frag.glsl", &variant.defines())
            .unwrap()
            .to_vec()
    }

    #[test]
    fn a_frozen_forward_shader_validates_and_holds_no_specialization_constant() {
        let words = forward_fragment();
        assert!(spec_constant_count(&words).unwrap() > 0);
        let spec = VariantKey::default().spec();
        let bytes = bytemuck::bytes_of(&spec);
        let values: HashMap<u32, u32> = crate::variant::ShadeSpec::ENTRIES
            .iter()
            .map(|e| {
                let word = u32::from_ne_bytes(bytes[e.offset..e.offset + 4].try_into().unwrap());
                (e.id, word)
            })
            .collect();
        let frozen = freeze(&words, &values).unwrap();
        assert_eq!(spec_constant_count(&frozen).unwrap(), 0);
    }

    #[test]
    fn defaults_take_the_given_values() {
        let words = forward_fragment();
        // max_layers (SpecId 1) set to 7: its OpSpecConstant's literal reads 7 afterwards.
        let set = set_defaults(&words, &HashMap::from([(1, 7)])).unwrap();
        let found = instructions(&set)
            .unwrap()
            .into_iter()
            .any(|(at, op, count)| {
                op == OP_SPEC_CONSTANT && count == 4 && set[at + 3] == 7 && words[at + 3] != 7
            });
        assert!(found, "no constant took the value 7");
        assert!(matches!(
            set_defaults(&[1, 2, 3], &HashMap::new()),
            Err(FreezeError::Malformed(_))
        ));
    }
}
