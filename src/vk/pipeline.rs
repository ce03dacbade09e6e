//! Pipeline layouts, compute and graphics pipelines, and specialization constants.
//!
//! Specialization constants come from a `#[repr(C)]` + `Pod` struct whose map entries are built
//! with `offset_of!` by [`spec_constants!`](crate::spec_constants), so the host struct is the one
//! source of truth for ids and offsets and a pipeline is created from a struct literal.
//!
//! Pipelines are created through a [`PipelineCache`] (which names their device), and each
//! records how long its creation took and whether the driver found it in that cache
//! (`VkPipelineCreationFeedback`, core in Vulkan 1.3; drivers that give no valid feedback leave
//! it unknown).

use std::sync::Arc;
use std::time::{Duration, Instant};

use ash::vk;

use super::descriptor::{DescriptorSetLayout, Stages};
use super::device::Device;
use super::error::{Check, VkError, VkResult};
use super::pipeline_cache::PipelineCache;

/// One specialization constant: its `constant_id` and where it lives in the host struct.
#[derive(Clone, Copy, Debug)]
pub struct SpecEntry {
    pub id: u32,
    pub offset: usize,
    pub size: usize,
}

/// A `#[repr(C)]` struct of 32-bit specialization constants.
pub trait SpecConstants: bytemuck::Pod {
    const ENTRIES: &'static [SpecEntry];
}

/// No specialization constants.
impl SpecConstants for () {
    const ENTRIES: &'static [SpecEntry] = &[];
}

/// Implements [`SpecConstants`] for a `#[repr(C)]` struct of `u32` fields:
/// `spec_constants!(MySpec { max_layers = 0, model = 1 });`
#[macro_export]
macro_rules! spec_constants {
    ($ty:ty { $($field:ident = $id:expr),* $(,)? }) => {
        impl $crate::vk::SpecConstants for $ty {
            const ENTRIES: &'static [$crate::vk::SpecEntry] = &[
                $($crate::vk::SpecEntry {
                    id: $id,
                    offset: ::core::mem::offset_of!($ty, $field),
                    size: 4,
                }),*
            ];
        }
    };
}

fn map_entries<S: SpecConstants>() -> Vec<vk::SpecializationMapEntry> {
    S::ENTRIES
        .iter()
        .map(|e| vk::SpecializationMapEntry {
            constant_id: e.id,
            offset: e.offset as u32,
            size: e.size,
        })
        .collect()
}

/// A shader module that lives only while a pipeline is created.
struct ShaderModule<'a> {
    device: &'a Device,
    raw: vk::ShaderModule,
}

impl<'a> ShaderModule<'a> {
    fn new(device: &'a Device, spirv: &[u32]) -> VkResult<Self> {
        let info = vk::ShaderModuleCreateInfo::default().code(spirv);
        // SAFETY: `spirv` comes from shaderc, which emits valid SPIR-V words.
        let raw = unsafe { device.raw.create_shader_module(&info, None) }
            .check("vkCreateShaderModule")?;
        Ok(Self { device, raw })
    }
}

impl Drop for ShaderModule<'_> {
    fn drop(&mut self) {
        // SAFETY: modules may be destroyed once the pipelines using them are created.
        unsafe { self.device.raw.destroy_shader_module(self.raw, None) };
    }
}

pub struct PipelineLayout {
    device: Arc<Device>,
    pub(crate) raw: vk::PipelineLayout,
    pub(crate) push_stages: vk::ShaderStageFlags,
}

impl PipelineLayout {
    /// `push_constant_bytes` = 0 means no push constants.
    pub fn new(
        device: &Arc<Device>,
        sets: &[&DescriptorSetLayout],
        push_constant_bytes: u32,
        stages: Stages,
        name: &str,
    ) -> VkResult<Self> {
        let set_layouts: Vec<_> = sets.iter().map(|s| s.raw).collect();
        let ranges = [vk::PushConstantRange {
            stage_flags: stages.raw(),
            offset: 0,
            size: push_constant_bytes,
        }];
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&set_layouts)
            .push_constant_ranges(if push_constant_bytes > 0 {
                &ranges
            } else {
                &[]
            });
        // SAFETY: valid create info on a live device.
        let raw = unsafe { device.raw.create_pipeline_layout(&info, None) }
            .check("vkCreatePipelineLayout")?;
        device.set_name(raw, name);
        Ok(Self {
            device: device.clone(),
            raw,
            push_stages: stages.raw(),
        })
    }
}

impl Drop for PipelineLayout {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: module invariant: no pending GPU work uses the layout.
        unsafe { self.device.raw.destroy_pipeline_layout(self.raw, None) };
    }
}

/// How a pipeline's creation went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PipelineCreation {
    /// Host time of the `vkCreate*Pipelines` call.
    pub duration: Duration,
    /// Whether the driver found the pipeline in the pipeline cache
    /// (`APPLICATION_PIPELINE_CACHE_HIT`); `None` where its feedback is not valid.
    pub cache_hit: Option<bool>,
}

impl PipelineCreation {
    fn new(duration: Duration, feedback: vk::PipelineCreationFeedback) -> Self {
        let flags = feedback.flags;
        Self {
            duration,
            cache_hit: flags
                .contains(vk::PipelineCreationFeedbackFlags::VALID)
                .then(|| {
                    flags
                        .contains(vk::PipelineCreationFeedbackFlags::APPLICATION_PIPELINE_CACHE_HIT)
                }),
        }
    }

    /// `hit`, `miss` or `unknown`.
    pub fn cache_outcome(&self) -> &'static str {
        match self.cache_hit {
            Some(true) => "hit",
            Some(false) => "miss",
            None => "unknown",
        }
    }
}

/// A compute or graphics pipeline, and how its creation went.
pub struct Pipeline {
    device: Arc<Device>,
    pub(crate) raw: vk::Pipeline,
    pub(crate) bind_point: vk::PipelineBindPoint,
    pub creation: PipelineCreation,
}

impl Pipeline {
    pub fn compute<S: SpecConstants>(
        cache: &PipelineCache,
        layout: &PipelineLayout,
        spirv: &[u32],
        spec: &S,
        name: &str,
    ) -> VkResult<Self> {
        let device = &cache.device;
        let module = ShaderModule::new(device, spirv)?;
        let entries = map_entries::<S>();
        let spec_info = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(bytemuck::bytes_of(spec));
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module.raw)
            .name(c"main")
            .specialization_info(&spec_info);
        Self::create(
            device,
            vk::PipelineBindPoint::COMPUTE,
            name,
            "vkCreateComputePipelines",
            |feedback| {
                let info = vk::ComputePipelineCreateInfo::default()
                    .stage(stage)
                    .layout(layout.raw)
                    .flags(capture_flags(device))
                    .push_next(feedback);
                // SAFETY: all pointers borrow locals that outlive the call; the cache is
                // internally synchronized.
                unsafe {
                    device
                        .raw
                        .create_compute_pipelines(cache.raw, &[info], None)
                }
                .map(|pipelines| pipelines[0])
                .map_err(|(_, result)| result)
            },
        )
    }

    pub fn graphics<S: SpecConstants>(
        cache: &PipelineCache,
        layout: &PipelineLayout,
        desc: &GraphicsDesc<'_>,
        spec: &S,
        name: &str,
    ) -> VkResult<Self> {
        let device = &cache.device;
        let vertex = ShaderModule::new(device, desc.vertex)?;
        let fragment = ShaderModule::new(device, desc.fragment)?;
        let entries = map_entries::<S>();
        let spec_info = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(bytemuck::bytes_of(spec));
        let stages = [
            (vk::ShaderStageFlags::VERTEX, &vertex),
            (vk::ShaderStageFlags::FRAGMENT, &fragment),
        ]
        .map(|(stage, module)| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(stage)
                .module(module.raw)
                .name(c"main")
                .specialization_info(&spec_info)
        });
        let vertex_input = VertexInput::new(desc);
        let vertex_state = vertex_input.info();
        let blend_attachments = desc.blend_attachments();
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        let dynamic =
            vk::PipelineDynamicStateCreateInfo::default().dynamic_states(desc.dynamic_states());
        let mut rendering =
            vk::PipelineRenderingCreateInfo::default().color_attachment_formats(desc.color_formats);
        if desc.stencil.is_some() {
            rendering = rendering.stencil_attachment_format(super::STENCIL_FORMAT);
        }
        let depth_stencil = desc.stencil.map(StencilUse::state);
        let fixed = FixedFunction::new(desc.cull_back);
        Self::create(
            device,
            vk::PipelineBindPoint::GRAPHICS,
            name,
            "vkCreateGraphicsPipelines",
            |feedback| {
                let mut info = vk::GraphicsPipelineCreateInfo::default()
                    .stages(&stages)
                    .vertex_input_state(&vertex_state)
                    .input_assembly_state(&fixed.input_assembly)
                    .viewport_state(&fixed.viewport)
                    .rasterization_state(&fixed.raster)
                    .multisample_state(&fixed.multisample)
                    .color_blend_state(&blend)
                    .dynamic_state(&dynamic)
                    .layout(layout.raw)
                    .flags(capture_flags(device))
                    .push_next(&mut rendering)
                    .push_next(feedback);
                if let Some(state) = depth_stencil.as_ref() {
                    info = info.depth_stencil_state(state);
                }
                // SAFETY: all pointers borrow locals that outlive the call; the cache is
                // internally synchronized.
                unsafe {
                    device
                        .raw
                        .create_graphics_pipelines(cache.raw, &[info], None)
                }
                .map(|pipelines| pipelines[0])
                .map_err(|(_, result)| result)
            },
        )
    }

    /// The one place a pipeline comes to be: `create` makes it with the creation feedback
    /// chained onto its create info; here it is timed, named and wrapped.
    fn create(
        device: &Arc<Device>,
        bind_point: vk::PipelineBindPoint,
        name: &str,
        call: &'static str,
        create: impl FnOnce(
            &mut vk::PipelineCreationFeedbackCreateInfo<'_>,
        ) -> Result<vk::Pipeline, vk::Result>,
    ) -> VkResult<Self> {
        let mut feedback = vk::PipelineCreationFeedback::default();
        let start = Instant::now();
        let raw = {
            let mut feedback_info = vk::PipelineCreationFeedbackCreateInfo::default()
                .pipeline_creation_feedback(&mut feedback);
            create(&mut feedback_info).map_err(|result| VkError::Vk { call, result })?
        };
        let creation = PipelineCreation::new(start.elapsed(), feedback);
        device.set_name(raw, name);
        Ok(Self {
            device: device.clone(),
            raw,
            bind_point,
            creation,
        })
    }
}

/// A graphics pipeline's vertex input: one interleaved buffer of `desc.vertex_stride` bytes per
/// vertex with its attributes, or none (a stride of 0: the vertex shader makes its vertices).
struct VertexInput {
    bindings: [vk::VertexInputBindingDescription; 1],
    attributes: Vec<vk::VertexInputAttributeDescription>,
}

impl VertexInput {
    fn new(desc: &GraphicsDesc<'_>) -> Self {
        Self {
            bindings: [vk::VertexInputBindingDescription {
                binding: 0,
                stride: desc.vertex_stride,
                input_rate: vk::VertexInputRate::VERTEX,
            }],
            attributes: desc
                .attributes
                .iter()
                .map(
                    |&(location, format, offset)| vk::VertexInputAttributeDescription {
                        location,
                        binding: 0,
                        format,
                        offset,
                    },
                )
                .collect(),
        }
    }

    fn info(&self) -> vk::PipelineVertexInputStateCreateInfo<'_> {
        if self.bindings[0].stride > 0 {
            vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(&self.bindings)
                .vertex_attribute_descriptions(&self.attributes)
        } else {
            vk::PipelineVertexInputStateCreateInfo::default()
        }
    }
}

/// The graphics pipelines' dynamic state: the viewport and scissor, set at each draw.
const DYNAMIC_STATES: [vk::DynamicState; 2] =
    [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];

/// [`DYNAMIC_STATES`] and the stencil's reference and masks.
const DYNAMIC_STATES_STENCIL: [vk::DynamicState; 5] = [
    vk::DynamicState::VIEWPORT,
    vk::DynamicState::SCISSOR,
    vk::DynamicState::STENCIL_REFERENCE,
    vk::DynamicState::STENCIL_COMPARE_MASK,
    vk::DynamicState::STENCIL_WRITE_MASK,
];

/// The fixed-function state every graphics pipeline shares: triangle lists, one dynamic
/// viewport, filled counter-clockwise triangles (culled from the back when asked), one sample.
struct FixedFunction {
    input_assembly: vk::PipelineInputAssemblyStateCreateInfo<'static>,
    viewport: vk::PipelineViewportStateCreateInfo<'static>,
    raster: vk::PipelineRasterizationStateCreateInfo<'static>,
    multisample: vk::PipelineMultisampleStateCreateInfo<'static>,
}

impl FixedFunction {
    fn new(cull_back: bool) -> Self {
        Self {
            input_assembly: vk::PipelineInputAssemblyStateCreateInfo::default()
                .topology(vk::PrimitiveTopology::TRIANGLE_LIST),
            viewport: vk::PipelineViewportStateCreateInfo::default()
                .viewport_count(1)
                .scissor_count(1),
            raster: vk::PipelineRasterizationStateCreateInfo::default()
                .polygon_mode(vk::PolygonMode::FILL)
                .cull_mode(if cull_back {
                    vk::CullModeFlags::BACK
                } else {
                    vk::CullModeFlags::NONE
                })
                .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
                .line_width(1.0),
            multisample: vk::PipelineMultisampleStateCreateInfo::default()
                .rasterization_samples(vk::SampleCountFlags::TYPE_1),
        }
    }
}

/// One compiled executable of a pipeline (a shader stage, as the driver split it) and the
/// statistics the driver reports for it (`VK_KHR_pipeline_executable_properties`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct ExecutableStats {
    pub name: String,
    pub description: String,
    pub subgroup_size: u32,
    pub statistics: Vec<ExecutableStat>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct ExecutableStat {
    pub name: String,
    pub description: String,
    pub value: serde_json::Value,
}

fn c_text(raw: &[std::ffi::c_char]) -> String {
    let bytes: Vec<u8> = raw
        .iter()
        .take_while(|&&c| c != 0)
        .map(|&c| c as u8)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

impl Pipeline {
    /// The driver's per-executable statistics (registers, scratch, instruction counts …);
    /// `None` where the device does not offer `VK_KHR_pipeline_executable_properties`.
    pub fn executable_statistics(&self) -> VkResult<Option<Vec<ExecutableStats>>> {
        let Some(ext) = &self.device.exec_props else {
            return Ok(None);
        };
        let info = vk::PipelineInfoKHR::default().pipeline(self.raw);
        // SAFETY: the pipeline is alive and was created with CAPTURE_STATISTICS (capture_flags),
        // the extension's feature is enabled on this device.
        let executables = unsafe { ext.get_pipeline_executable_properties(&info) }
            .check("vkGetPipelineExecutablePropertiesKHR")?;
        let mut out = Vec::with_capacity(executables.len());
        for (index, exe) in executables.iter().enumerate() {
            let info = vk::PipelineExecutableInfoKHR::default()
                .pipeline(self.raw)
                .executable_index(index as u32);
            // SAFETY: as above; the index is below the count the driver returned.
            let stats = unsafe { ext.get_pipeline_executable_statistics(&info) }
                .check("vkGetPipelineExecutableStatisticsKHR")?;
            let statistics = stats
                .iter()
                .map(|s| {
                    // SAFETY: the union member read is the one `format` names.
                    let value = unsafe {
                        match s.format {
                            vk::PipelineExecutableStatisticFormatKHR::BOOL32 => {
                                serde_json::Value::from(s.value.b32 != 0)
                            }
                            vk::PipelineExecutableStatisticFormatKHR::INT64 => {
                                serde_json::Value::from(s.value.i64)
                            }
                            vk::PipelineExecutableStatisticFormatKHR::UINT64 => {
                                serde_json::Value::from(s.value.u64)
                            }
                            _ => serde_json::Value::from(s.value.f64),
                        }
                    };
                    ExecutableStat {
                        name: c_text(&s.name),
                        description: c_text(&s.description),
                        value,
                    }
                })
                .collect();
            out.push(ExecutableStats {
                name: c_text(&exe.name),
                description: c_text(&exe.description),
                subgroup_size: exe.subgroup_size,
                statistics,
            });
        }
        Ok(Some(out))
    }
}

/// Ask the driver to keep executable statistics where it can report them.
fn capture_flags(device: &Device) -> vk::PipelineCreateFlags {
    if device.exec_props.is_some() {
        vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR
    } else {
        vk::PipelineCreateFlags::empty()
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // SAFETY: module invariant: no pending GPU work uses the pipeline.
        unsafe { self.device.raw.destroy_pipeline(self.raw, None) };
    }
}

/// Fixed-function state of lamina's graphics pipelines: one colour attachment, no blending,
/// dynamic viewport and scissor.
pub struct GraphicsDesc<'a> {
    pub vertex: &'a [u32],
    pub fragment: &'a [u32],
    /// 0: no vertex buffer (positions generated from the vertex index).
    pub vertex_stride: u32,
    /// (location, format, byte offset) of each attribute.
    pub attributes: &'a [(u32, vk::Format, u32)],
    /// One per colour attachment, in location order.
    pub color_formats: &'a [vk::Format],
    pub cull_back: bool,
    /// What the pipeline does with a stencil attachment (`STENCIL_FORMAT`) of its rendering
    /// scope; `None`: the scope has none.
    pub stencil: Option<StencilUse>,
}

impl GraphicsDesc<'_> {
    /// One blend state per colour attachment: written, unblended (a stencil mark writes no
    /// colour).
    fn blend_attachments(&self) -> Vec<vk::PipelineColorBlendAttachmentState> {
        let writes = if self.stencil == Some(StencilUse::Mark) {
            vk::ColorComponentFlags::empty()
        } else {
            vk::ColorComponentFlags::RGBA
        };
        self.color_formats
            .iter()
            .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(writes))
            .collect()
    }

    /// The dynamic states: the viewport and scissor, and with a stencil its reference and
    /// masks.
    fn dynamic_states(&self) -> &'static [vk::DynamicState] {
        if self.stencil.is_some() {
            &DYNAMIC_STATES_STENCIL
        } else {
            &DYNAMIC_STATES
        }
    }
}

/// A graphics pipeline's part in routing pixels by the stencil: the reference value and the
/// masks are dynamic (`Recorder::set_stencil`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StencilUse {
    /// Writes the reference's bits (under the write mask) wherever its fragment survives, and
    /// no colour.
    Mark,
    /// Shades only the pixels whose compared stencil bits equal the reference.
    Equal,
}

impl StencilUse {
    fn state(self) -> vk::PipelineDepthStencilStateCreateInfo<'static> {
        let (compare, pass) = match self {
            Self::Mark => (vk::CompareOp::ALWAYS, vk::StencilOp::REPLACE),
            Self::Equal => (vk::CompareOp::EQUAL, vk::StencilOp::KEEP),
        };
        let face = vk::StencilOpState::default()
            .fail_op(vk::StencilOp::KEEP)
            .pass_op(pass)
            .depth_fail_op(vk::StencilOp::KEEP)
            .compare_op(compare);
        vk::PipelineDepthStencilStateCreateInfo::default()
            .stencil_test_enable(true)
            .front(face)
            .back(face)
    }
}
