//! The shaders' interface as the compiled SPIR-V declares it, read back with a reflection
//! crate (rspirv-reflect, and the rspirv module under it for block layouts), equals what the
//! host creates pipelines from:
//! - every compute entry point has exactly one `KernelInterface`; its own set's bindings (and
//!   the shading set's, for kernels that shade) have the host's descriptor types, its push
//!   block has the host's members at the host's offsets (in order: the optimised SPIR-V keeps
//!   no names) and fits in the host's size, and its work-group size comes from the
//!   specialization constants the host sets;
//! - the graphics entry points declare the shading set (set 0) and the scene set (set 1) as
//!   `shader::interface` lays them out, and no push constants (their layout has none);
//! - the std430 Material block, the std140 TransportRatios block (the same buffer's energy
//!   ratios) and the std140 Frame block have the member offsets and array strides of
//!   `MaterialGpu`, `LayerGpu` and `FrameConstants`;
//! - every specialization constant a shader declares has an id the host's spec struct sets.
//!
//! Each entry is compiled in every define set it is built with (fp16 narrows types).
//! No device is needed.

use std::collections::BTreeMap;
use std::mem::{offset_of, size_of};

use lamina::profile::calibrate;
use lamina::render::{deferred, eval};
use lamina::shader::interface::{
    FrameConstants, LayerGpu, MaterialGpu, SCENE_BINDINGS, SCENE_SET, SHADING_BINDINGS,
    SHADING_SET, TRANSPORT_OFFSET, TRANSPORT_ROWS, TRANSPORT_SEGMENTS,
};
use lamina::shader::kernel::{self, KernelInterface, KernelSpec};
use lamina::shader::{entry_points, ShaderCompiler};
use lamina::tables::{environment, fgd, split_sum, tir};
use lamina::variant::ShadeSpec;
use lamina::vk::{BindingKind, SpecConstants};
use rspirv_reflect::rspirv::binary::{parse_words, Consumer, ParseAction};
use rspirv_reflect::rspirv::dr::{Instruction, Loader, ModuleHeader, Operand};
use rspirv_reflect::spirv::{Decoration, ExecutionMode, Op, StorageClass};
use rspirv_reflect::{DescriptorType, Reflection};

/// One compiled entry point.
struct Spirv {
    reflection: Reflection,
    /// The OpExecutionModeId instructions (LocalSizeId), kept aside by [`ModeIdLoader`].
    execution_mode_ids: Vec<Instruction>,
}

/// rspirv's module loader (0.12) refuses OpExecutionModeId ("detached instruction"), which
/// glslang emits for `local_size_x_id` when targeting SPIR-V 1.6: this consumer keeps those
/// instructions aside and hands every other one to the loader.
struct ModeIdLoader {
    loader: Loader,
    execution_mode_ids: Vec<Instruction>,
}

impl Consumer for ModeIdLoader {
    fn initialize(&mut self) -> ParseAction {
        self.loader.initialize()
    }

    fn finalize(&mut self) -> ParseAction {
        self.loader.finalize()
    }

    fn consume_header(&mut self, header: ModuleHeader) -> ParseAction {
        self.loader.consume_header(header)
    }

    fn consume_instruction(&mut self, inst: Instruction) -> ParseAction {
        if inst.class.opcode == Op::ExecutionModeId {
            self.execution_mode_ids.push(inst);
            ParseAction::Continue
        } else {
            self.loader.consume_instruction(inst)
        }
    }
}

/// A struct member: its offset and type id.
#[derive(Debug)]
struct Member {
    offset: u32,
    ty: u32,
}

impl Spirv {
    fn compile(compiler: &ShaderCompiler, entry: &str, defines: &[(&str, &str)]) -> Self {
        let words = compiler.compile(entry, defines).unwrap();
        let mut consumer = ModeIdLoader {
            loader: Loader::new(),
            execution_mode_ids: Vec::new(),
        };
        parse_words(&words, &mut consumer)
            .unwrap_or_else(|e| panic!("{entry}: SPIR-V parse failed: {e:?}"));
        Self {
            reflection: Reflection::new(consumer.loader.module()),
            execution_mode_ids: consumer.execution_mode_ids,
        }
    }

    fn module(&self) -> &rspirv_reflect::rspirv::dr::Module {
        &self.reflection.0
    }

    /// (set, binding) → descriptor type, of every descriptor the entry point declares.
    fn descriptors(&self) -> BTreeMap<(u32, u32), DescriptorType> {
        let sets = self.reflection.get_descriptor_sets().unwrap();
        sets.iter()
            .flat_map(|(&set, bindings)| bindings.iter().map(move |(&b, info)| ((set, b), info.ty)))
            .collect()
    }

    fn definition(&self, id: u32) -> &Instruction {
        self.module()
            .types_global_values
            .iter()
            .find(|i| i.result_id == Some(id))
            .unwrap_or_else(|| panic!("no definition of %{id}"))
    }

    /// The decorations of `id` (member decorations when `member` is given).
    fn decorations(&self, id: u32, member: Option<u32>) -> Vec<(Decoration, Option<u32>)> {
        self.module()
            .annotations
            .iter()
            .filter_map(|a| match (a.class.opcode, &a.operands[..], member) {
                (Op::Decorate, [Operand::IdRef(target), Operand::Decoration(d), rest @ ..], None)
                    if *target == id =>
                {
                    Some((*d, literal(rest)))
                }
                (
                    Op::MemberDecorate,
                    [Operand::IdRef(target), Operand::LiteralBit32(m), Operand::Decoration(d), rest @ ..],
                    Some(member),
                ) if *target == id && *m == member => Some((*d, literal(rest))),
                _ => None,
            })
            .collect()
    }

    fn decoration(&self, id: u32, member: Option<u32>, which: Decoration) -> Option<u32> {
        self.decorations(id, member)
            .into_iter()
            .find(|(d, _)| *d == which)
            .and_then(|(_, v)| v)
    }

    /// The members of the struct type `id`.
    fn members(&self, id: u32) -> Vec<Member> {
        let def = self.definition(id);
        assert_eq!(def.class.opcode, Op::TypeStruct, "%{id} is not a struct");
        def.operands
            .iter()
            .enumerate()
            .map(|(i, op)| {
                let Operand::IdRef(ty) = op else {
                    panic!("struct member operand {op:?}")
                };
                let i = i as u32;
                Member {
                    offset: self
                        .decoration(id, Some(i), Decoration::Offset)
                        .unwrap_or_else(|| panic!("%{id} member {i} has no Offset")),
                    ty: *ty,
                }
            })
            .collect()
    }

    /// The struct a variable of `class` points to, for variables picked by `pick`.
    fn variable_struct(&self, class: StorageClass, pick: impl Fn(u32) -> bool) -> Option<u32> {
        self.module()
            .types_global_values
            .iter()
            .filter(|i| i.class.opcode == Op::Variable)
            .filter(|i| i.operands.first() == Some(&Operand::StorageClass(class)))
            .find(|i| pick(i.result_id.unwrap()))
            .map(|var| {
                let pointer = self.definition(var.result_type.unwrap());
                match pointer.operands[..] {
                    [Operand::StorageClass(_), Operand::IdRef(pointee)] => pointee,
                    _ => panic!("variable type is not a pointer"),
                }
            })
    }

    fn push_struct(&self) -> Option<u32> {
        self.variable_struct(StorageClass::PushConstant, |_| true)
    }

    /// The block bound at (set, binding).
    fn block(&self, set: u32, binding: u32) -> u32 {
        [StorageClass::StorageBuffer, StorageClass::Uniform]
            .into_iter()
            .find_map(|class| {
                self.variable_struct(class, |var| {
                    self.decoration(var, None, Decoration::DescriptorSet) == Some(set)
                        && self.decoration(var, None, Decoration::Binding) == Some(binding)
                })
            })
            .unwrap_or_else(|| panic!("no block at set {set} binding {binding}"))
    }

    /// The spec ids of every specialization constant.
    fn spec_ids(&self) -> Vec<u32> {
        self.module()
            .annotations
            .iter()
            .filter_map(|a| match a.operands[..] {
                [Operand::IdRef(_), Operand::Decoration(Decoration::SpecId), Operand::LiteralBit32(id)] => {
                    Some(id)
                }
                _ => None,
            })
            .collect()
    }

    /// The spec ids the work-group size is made of: the LocalSizeId operands (SPIR-V 1.6), or
    /// the constituents of the WorkgroupSize built-in.
    fn local_size_spec_ids(&self) -> Vec<Option<u32>> {
        let spec_of = |id: u32| self.decoration(id, None, Decoration::SpecId);
        let by_id = self.execution_mode_ids.iter().find_map(|m| match &m.operands[..] {
            [Operand::IdRef(_), Operand::ExecutionMode(ExecutionMode::LocalSizeId), ids @ ..] => {
                Some(
                    ids.iter()
                        .map(|op| match op {
                            Operand::IdRef(id) => spec_of(*id),
                            _ => None,
                        })
                        .collect(),
                )
            }
            _ => None,
        });
        by_id.unwrap_or_else(|| {
            let builtin = self.module().types_global_values.iter().find(|i| {
                i.class.opcode == Op::SpecConstantComposite
                    && self
                        .decorations(i.result_id.unwrap(), None)
                        .iter()
                        .any(|(d, v)| *d == Decoration::BuiltIn && *v == Some(25))
            });
            builtin
                .map(|c| {
                    c.operands
                        .iter()
                        .map(|op| match op {
                            Operand::IdRef(id) => spec_of(*id),
                            _ => None,
                        })
                        .collect()
                })
                .unwrap_or_default()
        })
    }
}

/// The literal after a decoration, if any.
fn literal(rest: &[Operand]) -> Option<u32> {
    match rest {
        [Operand::LiteralBit32(v), ..] => Some(*v),
        [Operand::BuiltIn(b), ..] => Some(*b as u32),
        _ => None,
    }
}

/// Every compute kernel the library builds, by its interface.
fn kernels() -> Vec<KernelInterface> {
    vec![
        environment::CONVERT_KERNEL,
        environment::PREFILTER_KERNEL,
        split_sum::KERNEL,
        tir::KERNEL,
        fgd::GRID_KERNEL,
        fgd::BELCOUR_KERNEL,
        fgd::PROBE_KERNEL,
        eval::KERNEL,
        deferred::KERNEL,
        deferred::BINS_KERNEL,
        deferred::COUNT_KERNEL,
        deferred::OFFSETS_KERNEL,
        deferred::SCATTER_KERNEL,
        kernel::SPEC_ARRAY,
        calibrate::KERNEL,
    ]
}

/// The define sets an entry point is compiled with: the shading passes also in fp16.
fn define_sets(entry: &str) -> Vec<Vec<(&'static str, &'static str)>> {
    let shades = [
        "forward.frag.glsl",
        "tm_eval.comp.glsl",
        "deferred.comp.glsl",
    ];
    if entry == "forward.frag.glsl" {
        vec![
            vec![],
            vec![("LAMINA_FP16", "1")],
            vec![("LAMINA_REFERENCE", "1")],
            vec![
                ("LAMINA_REFERENCE", "1"),
                ("LAMINA_REFERENCE_EVALUATED", "1"),
            ],
        ]
    } else if entry == "deferred.comp.glsl" {
        vec![
            vec![],
            vec![("LAMINA_FP16", "1")],
            vec![("LAMINA_TARGET_RGBA32F", "1")],
        ]
    } else if entry == "deferred_bins.comp.glsl" {
        vec![
            vec![],
            vec![("LAMINA_FP16", "1")],
            vec![("LAMINA_TARGET_RGBA32F", "1"), ("LAMINA_BIN_TILES", "1")],
        ]
    } else if entry == "bin_count.comp.glsl" {
        vec![vec![], vec![("LAMINA_BIN_TILES", "1")]]
    } else if shades.contains(&entry) {
        vec![vec![], vec![("LAMINA_FP16", "1")]]
    } else {
        vec![vec![]]
    }
}

fn same_kind(host: BindingKind, shader: DescriptorType) -> bool {
    shader
        == match host {
            BindingKind::UniformBuffer => DescriptorType::UNIFORM_BUFFER,
            BindingKind::StorageBuffer => DescriptorType::STORAGE_BUFFER,
            BindingKind::SampledImage => DescriptorType::COMBINED_IMAGE_SAMPLER,
            BindingKind::StorageImage => DescriptorType::STORAGE_IMAGE,
        }
}

/// Every descriptor the shader declares is in the host's layout with the same type, and every
/// (set, binding) in `required` is declared (the optimizer drops what a stage never reads, so
/// a shared set may be declared in part).
fn check_sets(
    entry: &str,
    spirv: &Spirv,
    host: &BTreeMap<u32, Vec<BindingKind>>,
    required: &[(u32, u32)],
) {
    let declared = spirv.descriptors();
    for (&(set, binding), &ty) in &declared {
        let kind = host
            .get(&set)
            .and_then(|kinds| kinds.get(binding as usize))
            .unwrap_or_else(|| {
                panic!("{entry}: set {set} binding {binding} ({ty:?}) is not in the host's layout")
            });
        assert!(
            same_kind(*kind, ty),
            "{entry}: set {set} binding {binding}: shader {ty:?}, host {kind:?}"
        );
    }
    for &(set, binding) in required {
        assert!(
            declared.contains_key(&(set, binding)),
            "{entry}: the host binds set {set} binding {binding}, the shader declares none"
        );
    }
}

fn kinds_in_order(bindings: &[lamina::shader::interface::Binding]) -> Vec<BindingKind> {
    bindings
        .iter()
        .enumerate()
        .map(|(i, b)| {
            assert_eq!(b.binding, i as u32, "bindings listed in binding order");
            b.kind
        })
        .collect()
}

fn ids_of<S: SpecConstants>() -> Vec<u32> {
    S::ENTRIES.iter().map(|e| e.id).collect()
}

#[test]
fn every_compute_kernel_matches_its_interface() {
    let compiler = ShaderCompiler::new().unwrap();
    let kernels = kernels();
    let computes: Vec<_> = entry_points()
        .into_iter()
        .filter(|e| e.ends_with(".comp.glsl"))
        .collect();
    for entry in &computes {
        let n = kernels.iter().filter(|k| k.entry == *entry).count();
        assert_eq!(n, 1, "{entry}: {n} KernelInterfaces (one expected)");
    }
    for k in &kernels {
        assert!(computes.contains(&k.entry), "{}: no such entry", k.entry);
        let mut sets = BTreeMap::new();
        if k.shades {
            sets.insert(SHADING_SET, kinds_in_order(&SHADING_BINDINGS));
        }
        if k.scene {
            sets.insert(SCENE_SET, kinds_in_order(&SCENE_BINDINGS));
        }
        sets.insert(k.own_set(), k.bindings.to_vec());
        // The kernels that shade (and the MAX_LAYERS array test) read ShadeSpec, whose id 6
        // is the work-group width; the table kernels read KernelSpec (ids 0, 1: x, y).
        let (spec, local_size_ids) = if k.shades || k.entry == kernel::SPEC_ARRAY.entry {
            (ids_of::<ShadeSpec>(), vec![Some(6), None, None])
        } else {
            (ids_of::<KernelSpec>(), vec![Some(0), Some(1), None])
        };
        for defines in define_sets(k.entry) {
            let spirv = Spirv::compile(&compiler, k.entry, &defines);
            let entry = format!("{} {defines:?}", k.entry);
            let own = k.own_set();
            let required: Vec<(u32, u32)> =
                (0..sets[&own].len() as u32).map(|b| (own, b)).collect();
            check_sets(&entry, &spirv, &sets, &required);

            match spirv.push_struct() {
                None => assert_eq!(k.push.size, 0, "{entry}: host pushes, shader reads none"),
                Some(block) => {
                    let members = spirv.members(block);
                    assert_eq!(
                        members.len(),
                        k.push.members.len(),
                        "{entry}: push members {members:?} vs host {:?}",
                        k.push.members
                    );
                    for (shader, host) in members.iter().zip(k.push.members) {
                        assert_eq!(
                            shader.offset, host.offset,
                            "{entry}: push member {}",
                            host.name
                        );
                    }
                    let range = spirv.reflection.get_push_constant_range().unwrap().unwrap();
                    assert!(
                        range.size <= k.push.size,
                        "{entry}: shader push block is {} bytes, host pushes {}",
                        range.size,
                        k.push.size
                    );
                }
            }

            for id in spirv.spec_ids() {
                assert!(
                    spec.contains(&id),
                    "{entry}: spec constant {id} is not set by the host (it sets {spec:?})"
                );
            }
            assert_eq!(
                spirv.local_size_spec_ids(),
                local_size_ids,
                "{entry}: the spec ids of the work-group size"
            );
        }
    }
}

#[test]
fn graphics_passes_declare_the_shading_and_scene_sets() {
    let compiler = ShaderCompiler::new().unwrap();
    let sets = BTreeMap::from([
        (SHADING_SET, kinds_in_order(&SHADING_BINDINGS)),
        (SCENE_SET, kinds_in_order(&SCENE_BINDINGS)),
    ]);
    let graphics: Vec<_> = entry_points()
        .into_iter()
        .filter(|e| !e.ends_with(".comp.glsl"))
        .collect();
    assert!(graphics.contains(&"forward.frag.glsl") && graphics.contains(&"sky.frag.glsl"));
    let shade_ids = ids_of::<ShadeSpec>();
    for entry in graphics {
        for defines in define_sets(entry) {
            let spirv = Spirv::compile(&compiler, entry, &defines);
            let name = format!("{entry} {defines:?}");
            // Each stage declares part of the pipeline layout, as the host lays it out; the
            // fragment pass that shades declares both sets whole but the environment's
            // sampling (scene binding 3), which only the reference pass reads (then with the
            // scene set and the lobe table, shading binding 5; or, evaluating its lobes per
            // pixel, with the whole shading set but the lobe table). A reference integrates a
            // diffuse lobe itself, so it leaves out the lamps' irradiance (scene binding 6).
            let all = |set: u32| (0..sets[&set].len() as u32).map(move |b| (set, b));
            let required: Vec<(u32, u32)> = if entry != "forward.frag.glsl" {
                Vec::new()
            } else if defines.contains(&("LAMINA_REFERENCE_EVALUATED", "1")) {
                all(SCENE_SET)
                    .filter(|&(_, b)| b != 6)
                    .chain(all(SHADING_SET).filter(|&(_, b)| b != 5))
                    .collect()
            } else if defines.contains(&("LAMINA_REFERENCE", "1")) {
                all(SCENE_SET)
                    .filter(|&(_, b)| b != 6)
                    .chain([(SHADING_SET, 5)])
                    .collect()
            } else {
                all(SHADING_SET)
                    .chain(all(SCENE_SET).filter(|&(_, b)| b != 3))
                    .collect()
            };
            check_sets(&name, &spirv, &sets, &required);
            // Only the calibration draw pushes constants, laid out as the host pushes them.
            match spirv.push_struct() {
                None => assert_ne!(entry, calibrate::ENTRIES[1], "{name}: no push constants"),
                Some(block) => {
                    assert_eq!(entry, calibrate::ENTRIES[1], "{name}: push constants");
                    let offsets: Vec<u32> = spirv.members(block).iter().map(|m| m.offset).collect();
                    let host: Vec<u32> = calibrate::FRAGMENT_PUSH
                        .members
                        .iter()
                        .map(|m| m.offset)
                        .collect();
                    assert_eq!(offsets, host, "{name}: push members");
                }
            }
            for id in spirv.spec_ids() {
                assert!(shade_ids.contains(&id), "{name}: spec constant {id} unset");
            }
        }
    }
}

fn offsets(spirv: &Spirv, id: u32) -> Vec<u32> {
    spirv.members(id).iter().map(|m| m.offset).collect()
}

/// The struct a block wraps (`Material { MaterialGpu material; }`).
fn wrapped(spirv: &Spirv, block: u32) -> u32 {
    let members = spirv.members(block);
    assert_eq!(members.len(), 1, "one wrapped struct");
    assert_eq!(members[0].offset, 0);
    members[0].ty
}

/// (element type, stride, length) of an array type.
fn array(spirv: &Spirv, id: u32) -> (u32, u32, u32) {
    let def = spirv.definition(id);
    assert_eq!(
        def.class.opcode,
        Op::TypeArray,
        "%{id} is not a sized array"
    );
    let [Operand::IdRef(element), Operand::IdRef(length)] = def.operands[..] else {
        panic!("array operands {:?}", def.operands)
    };
    let length = match spirv.definition(length).operands[..] {
        [Operand::LiteralBit32(n)] => n,
        ref other => panic!("array length {other:?}"),
    };
    let stride = spirv
        .decoration(id, None, Decoration::ArrayStride)
        .expect("ArrayStride");
    (element, stride, length)
}

#[test]
fn material_and_frame_blocks_have_the_host_layout() {
    let compiler = ShaderCompiler::new().unwrap();
    let at = |o: usize| o as u32;
    // The reference pass reads no material (its lobes come from a table).
    let shading = define_sets("forward.frag.glsl")
        .into_iter()
        .filter(|d| !d.contains(&("LAMINA_REFERENCE", "1")));
    for defines in shading {
        let spirv = Spirv::compile(&compiler, "forward.frag.glsl", &defines);

        let material = wrapped(&spirv, spirv.block(SHADING_SET, 0));
        assert_eq!(
            offsets(&spirv, material),
            [
                at(offset_of!(MaterialGpu, info)),
                at(offset_of!(MaterialGpu, layers)),
                at(offset_of!(MaterialGpu, maps)),
            ]
        );
        let (layer, stride, length) = array(&spirv, spirv.members(material)[1].ty);
        assert_eq!(stride, at(size_of::<LayerGpu>()), "layer stride");
        assert_eq!(
            (offset_of!(MaterialGpu, layers) + length as usize * size_of::<LayerGpu>()),
            offset_of!(MaterialGpu, maps),
            "layer count"
        );
        let (_, stride, maps) = array(&spirv, spirv.members(material)[2].ty);
        assert_eq!(
            (stride, maps),
            (16, length),
            "one uvec4 of map codes per layer"
        );
        assert_eq!(
            offset_of!(MaterialGpu, maps) + maps as usize * 16,
            offset_of!(MaterialGpu, transport),
            "map codes"
        );
        // The energy ratios, through the uniform-buffer view of the same buffer.
        let ratios_block = spirv.members(spirv.block(SHADING_SET, 8));
        assert_eq!(ratios_block.len(), 1, "one array of energy ratios");
        assert_eq!(ratios_block[0].offset, at(TRANSPORT_OFFSET));
        let (_, stride, ratios) = array(&spirv, ratios_block[0].ty);
        assert_eq!(
            (stride, ratios as usize),
            (16, TRANSPORT_ROWS * TRANSPORT_SEGMENTS),
            "one uvec4 of energy ratios per row and interval"
        );
        assert_eq!(
            TRANSPORT_OFFSET + ratios as usize * 16,
            size_of::<MaterialGpu>(),
            "energy ratios"
        );
        assert_eq!(
            offsets(&spirv, layer),
            [
                at(offset_of!(LayerGpu, ior)),
                at(offset_of!(LayerGpu, kappa)),
                at(offset_of!(LayerGpu, sigma_s)),
                at(offset_of!(LayerGpu, sigma_a)),
                at(offset_of!(LayerGpu, params)),
                at(offset_of!(LayerGpu, diffuse)),
            ]
        );

        let frame = wrapped(&spirv, spirv.block(SCENE_SET, 0));
        assert_eq!(
            offsets(&spirv, frame),
            [
                at(offset_of!(FrameConstants, view_proj)),
                at(offset_of!(FrameConstants, inv_view_proj)),
                at(offset_of!(FrameConstants, camera_pos)),
                at(offset_of!(FrameConstants, params)),
                at(offset_of!(FrameConstants, irradiance)),
            ]
        );
        for matrix in 0..2 {
            assert_eq!(
                spirv.decoration(frame, Some(matrix), Decoration::MatrixStride),
                Some(16),
                "Frame member {matrix}: column-major vec4 columns"
            );
        }
    }
}
