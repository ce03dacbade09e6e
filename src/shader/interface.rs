//! The host side of the GLSL interface: the structs mirrored in `glsl/include/shared/` (size
//! and offsets asserted here, and compared with the compiled blocks by tests/suite/reflection.rs) and
//! the descriptor sets declared in `glsl/include/bindings/`, with the layout of the shading set
//! that every entry point evaluating the model binds as set 0.

use std::mem::{offset_of, size_of};
use std::sync::Arc;

use crate::material::surface::SurfaceMaps;
use crate::model::transport::{self, Correction};
use crate::model::LayerParams;
use crate::vk::{
    upload_image, BindingKind, Buffer, BufferUsageFlags, DescriptorSet, DescriptorSetLayout,
    Device, Format, Image, ImageDesc, ImageState, ImageView, Resource, Sampler, SamplerDesc,
    Stages, VkResult,
};

use crate::variant::MAX_LAYERS_LIMIT;

/// Per-frame constants (`shared/frame.glsl`, std140).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameConstants {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    /// xyz: world-space eye.
    pub camera_pos: [f32; 4],
    /// x: mip count of the prefiltered environment.
    pub params: [f32; 4],
    /// The environment's irradiance in order-2 spherical harmonics
    /// (`tables::irradiance::irradiance_sh`).
    pub irradiance: [[f32; 4]; 9],
}

const _: () = assert!(size_of::<FrameConstants>() == 160 + 9 * 16);
const _: () = assert!(offset_of!(FrameConstants, irradiance) == 160);
const _: () = assert!(offset_of!(FrameConstants, inv_view_proj) == 64);
const _: () = assert!(offset_of!(FrameConstants, camera_pos) == 128);
const _: () = assert!(offset_of!(FrameConstants, params) == 144);

/// One layer (`shared/material.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LayerGpu {
    pub ior: [f32; 4],
    pub kappa: [f32; 4],
    pub sigma_s: [f32; 4],
    pub sigma_a: [f32; 4],
    /// x: GGX α of the top interface, y: medium depth, z: HG g.
    pub params: [f32; 4],
    /// w = 1: a diffuse base of albedo rgb (`model::diffuse`).
    pub diffuse: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MaterialGpu {
    /// x: layer count.
    pub info: [u32; 4],
    pub layers: [LayerGpu; MAX_LAYERS_LIMIT as usize],
    /// Per layer, the maps of its varying fields ([`SurfaceMaps`]'s codes: x: η, κ, σs, σa;
    /// y: α, depth, g, coverage; z: diffuse albedo, a byte each); zeros for a uniform stack.
    pub maps: [[u32; 4]; MAX_LAYERS_LIMIT as usize],
    /// `transport=corrected`: per layer, then for the transmittance, the energy ratios
    /// ([`Correction`]) over each of the [`TRANSPORT_SEGMENTS`] intervals between the
    /// tabulated view cosines, as half floats (`packHalf2x16` pairs): x = (r₀, g₀), y = (b₀, Δr),
    /// z = (Δg, Δb), the ratio at the interval's lower cosine and its change to the upper one
    /// (w unused); ratio 1 (the paper's energies) otherwise. The shaders read this array
    /// through a uniform-buffer view of the same buffer (`glsl/include/bindings/shading.glsl`).
    pub transport: [[u32; 4]; TRANSPORT_ROWS * TRANSPORT_SEGMENTS],
}

/// Rows of [`MaterialGpu::transport`]: one per layer and the transmittance's.
pub const TRANSPORT_ROWS: usize = MAX_LAYERS_LIMIT as usize + 1;

/// Intervals per row of [`MaterialGpu::transport`]: between consecutive tabulated cosines.
pub const TRANSPORT_SEGMENTS: usize = transport::POINTS - 1;

/// Where [`MaterialGpu::transport`] starts in the material's buffer: the uniform-buffer view
/// declares its array at this offset (`LAMINA_TRANSPORT_OFFSET`).
pub const TRANSPORT_OFFSET: usize = offset_of!(MaterialGpu, transport);

/// One interval of a ratio curve as the shaders read it (see [`MaterialGpu::transport`]). A
/// half float's relative step (2⁻¹¹) is far below the model's error; the CPU twins keep f64
/// ratios, and the GPU meets them within 1e-3 (tests/suite/model_vs_cpu.rs).
fn transport_segment(lo: [f64; 3], hi: [f64; 3]) -> [u32; 4] {
    let half = |v: f64| half::f16::from_f64(v).to_bits() as u32;
    let pair = |a: f64, b: f64| half(a) | (half(b) << 16);
    let d: [f64; 3] = std::array::from_fn(|c| hi[c] - lo[c]);
    [pair(lo[0], lo[1]), pair(lo[2], d[0]), pair(d[1], d[2]), 0]
}

const _: () = assert!(size_of::<LayerGpu>() == 96);
const _: () = assert!(offset_of!(LayerGpu, params) == 64);
const _: () = assert!(
    size_of::<MaterialGpu>()
        == 16 + 112 * MAX_LAYERS_LIMIT as usize + 16 * TRANSPORT_ROWS * TRANSPORT_SEGMENTS
);
// The uniform-buffer view covers the whole buffer: within every device's uniform range.
const _: () = assert!(size_of::<MaterialGpu>() <= 16384);
const _: () = assert!(offset_of!(MaterialGpu, layers) == 16);
const _: () = assert!(offset_of!(MaterialGpu, maps) == 16 + 96 * MAX_LAYERS_LIMIT as usize);

impl MaterialGpu {
    /// Packs `layers` (top first); at most [`MAX_LAYERS_LIMIT`] layers, which the material
    /// module's validation guarantees (a caller bug otherwise).
    pub fn new(layers: &[LayerParams]) -> Self {
        assert!(
            layers.len() <= MAX_LAYERS_LIMIT as usize,
            "stack exceeds the buffer"
        );
        let rgb = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32, 0.0];
        let mut gpu = Self {
            info: [layers.len() as u32, 0, 0, 0],
            layers: [LayerGpu::default(); MAX_LAYERS_LIMIT as usize],
            maps: [[0; 4]; MAX_LAYERS_LIMIT as usize],
            transport: [transport_segment([1.0; 3], [1.0; 3]); TRANSPORT_ROWS * TRANSPORT_SEGMENTS],
        };
        for (dst, src) in gpu.layers.iter_mut().zip(layers) {
            *dst = LayerGpu {
                ior: rgb(src.ior),
                kappa: rgb(src.kappa),
                sigma_s: rgb(src.sigma_s),
                sigma_a: rgb(src.sigma_a),
                params: [src.roughness as f32, src.depth as f32, src.g as f32, 0.0],
                diffuse: match src.diffuse {
                    Some(rho) => [rho[0] as f32, rho[1] as f32, rho[2] as f32, 1.0],
                    None => [0.0; 4],
                },
            };
        }
        gpu
    }

    /// With the energy ratios of `transport=corrected`.
    pub fn with_transport(mut self, correction: &Correction) -> Self {
        let rows = correction
            .layers
            .iter()
            .take(MAX_LAYERS_LIMIT as usize)
            .enumerate()
            .chain([(MAX_LAYERS_LIMIT as usize, &correction.transmittance)]);
        for (row, curve) in rows {
            for (k, pair) in curve.windows(2).enumerate() {
                self.transport[row * TRANSPORT_SEGMENTS + k] = transport_segment(pair[0], pair[1]);
            }
        }
        self
    }

    /// With the map codes of a spatially varying stack (one per layer, top first).
    pub fn with_maps(mut self, maps: &SurfaceMaps) -> Self {
        for (dst, code) in self.maps.iter_mut().zip(&maps.codes) {
            *dst = [code[0], code[1], code[2], 0];
        }
        self
    }
}

/// One binding of a descriptor set: its number, kind and GLSL name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    pub binding: u32,
    pub kind: BindingKind,
    pub name: &'static str,
}

/// The descriptor set index of the shading inputs in every pipeline that shades.
pub const SHADING_SET: u32 = 0;

/// Texels per axis of the TIR table the shading set binds (`LAMINA_TIR_SIZE`, read by
/// `glsl/include/lib/tir.glsl` to place texel centres): 64³, the size of the reference's
/// table. The host builds the `lut32`/`lut16` table at this size (`tables::tir`).
pub const TIR_TABLE_SIZE: u32 = 64;

/// Texels per axis of every FGD grid the shading set binds (`LAMINA_FGD_SIZE`, read by
/// `glsl/include/lib/fgd.glsl`): the reference's 64. The host builds the grids at this size
/// (`tables::fgd`).
pub const FGD_GRID_SIZE: u32 = 64;

/// Texels per side of the white lobe's albedo table the lights read (`LOBE_ALBEDO_SIZE`, read
/// by `glsl/include/lib/light.glsl`): the split-sum table's. The host builds it at this size
/// (`tables::lobe_albedo`).
pub const LOBE_ALBEDO_SIZE: u32 = 64;

/// Texels per side of the lobe-moments table `ibl=matched` reads (`LOBE_MOMENTS_SIZE`, read by
/// `glsl/include/lib/ibl.glsl`). The host builds it at this size (`tables::lobe_moments`).
pub const LOBE_MOMENTS_SIZE: u32 = 32;

/// `ibl=lamps`' placement of its fetch (`IBL_LAMPS_LEAN` and `IBL_LAMPS_ROOT` in
/// generated/codes.glsl; `tables::lobe_fit::polynomial`, whose test refits them): the lean
/// of the lobe's mean direction w = √α · (c₀ + c₁√α + c₂√μ + c₃√μ√α + c₄μ + c₅α), which
/// vanishes with α as a mirror lobe's does.
pub const LAMPS_LEAN_COEFFICIENTS: [f64; 6] = [
    0.8757772565057736,
    0.7859649637438431,
    -1.6345867800348723,
    2.0472257127886824,
    -0.23321979315146743,
    -0.833911983208834,
];

/// `ibl=lamps`' √α′ (the L² fit's) = √α · (c₀ + c₁√α + c₂√μ + c₃√μ√α + c₄μ + c₅μ√α),
/// c₀ + c₂ + c₄ ≈ 1 at a normal view.
pub const LAMPS_ROOT_COEFFICIENTS: [f64; 6] = [
    0.3628165938178354,
    0.9318763117408332,
    -0.2504194411432038,
    -0.21272428241138913,
    0.9743564066807135,
    -0.8888523152061817,
];

/// The 4-D FGD table's domain in η and κ: [0, 4] each (ALGORITHMS.md §6.1); beyond it, the
/// value at its edge carried on (`tables::fgd::beyond_the_table`). `FGD_ETA_MAX` and `FGD_KAPPA_MAX` in `glsl/include/lib/fgd.glsl`.
pub const FGD_ETA_MAX: f64 = 4.0;
pub const FGD_KAPPA_MAX: f64 = 4.0;

/// The view cosines where the Belcour projection interpolates F exactly (ALGORITHMS.md §7.2):
/// where b2 peaks and b3 bottoms out in the paper's basis (`tables::belcour`, and
/// `BELCOUR_CT1`, `BELCOUR_CT2` in `glsl/include/lib/fgd.glsl`).
pub const BELCOUR_CT1: f64 = 128.0 / 999.0;
pub const BELCOUR_CT2: f64 = 432.0 / 999.0;

/// The shading set's bindings, as `glsl/include/bindings/shading.glsl` declares them. The
/// material is a storage buffer, not a uniform buffer: lavapipe inlines uniform-buffer values
/// that feed loop bounds into the shader and recompiles it at draw time (Mesa's
/// `lvp_inline_uniforms`), which turned the generic pass into a per-material one behind the
/// benchmarks' back and took minutes of LLVM time for some variants. Storage-buffer loads are
/// never inlined. Binding 5 holds a `mode=baked` material's lobe table (`render::baked`; a
/// placeholder for every other pass). Binding 6 holds the white GGX lobe's directional albedo
/// that the analytic lights normalise each lobe by (`model::light`). Binding 7 holds the maps of
/// a spatially varying stack (`material::surface`), a 2-D array sampled with repeat; a 1×1
/// placeholder for uniform stacks. Binding 8 is the material's buffer again, as a uniform
/// buffer, through which the shaders read `transport=corrected`'s ratios
/// ([`MaterialGpu::transport`]): each pixel reads them at its own view cosine, an offset
/// lavapipe's inliner never takes (it inlines only constant offsets that feed control flow),
/// and llvmpipe loads a uniform buffer at such offsets in a fraction of a storage buffer's
/// instructions (README, "A corrected transport": the counts and the command).
pub const SHADING_BINDINGS: [Binding; 9] = [
    Binding {
        binding: 0,
        kind: BindingKind::StorageBuffer,
        name: "Material",
    },
    Binding {
        binding: 1,
        kind: BindingKind::SampledImage,
        name: "split_sum",
    },
    Binding {
        binding: 2,
        kind: BindingKind::SampledImage,
        name: "tir_table",
    },
    Binding {
        binding: 3,
        kind: BindingKind::SampledImage,
        name: "fgd_table",
    },
    Binding {
        binding: 4,
        kind: BindingKind::SampledImage,
        name: "fgd_belcour",
    },
    Binding {
        binding: 5,
        kind: BindingKind::SampledImage,
        name: "baked_lobes",
    },
    Binding {
        binding: 6,
        kind: BindingKind::SampledImage,
        name: "lobe_albedo",
    },
    Binding {
        binding: 7,
        kind: BindingKind::SampledImage,
        name: "layer_maps",
    },
    Binding {
        binding: 8,
        kind: BindingKind::UniformBuffer,
        name: "Transport",
    },
];

/// The views and buffer one shading set binds.
pub struct InputViews<'a> {
    pub material: &'a Buffer,
    pub split_sum: &'a ImageView,
    pub tir: &'a ImageView,
    pub fgd_volume: &'a ImageView,
    pub fgd_plane: &'a ImageView,
    /// `mode=baked`: the lobe table (`render::baked::BakedTexture`); any 2-D view otherwise.
    pub baked: &'a ImageView,
    /// The white GGX lobe's albedo E(μ, √α) (`tables::lobe_albedo`).
    pub lobe_albedo: &'a ImageView,
    /// A spatially varying stack's maps; the layout's placeholder when `None`.
    pub layer_maps: Option<&'a ImageView>,
}

/// The shading set's layout (what a pipeline that shades lists as set 0) and the sampler its
/// tables are read with.
pub struct ShadingLayout {
    pub set_layout: DescriptorSetLayout,
    sampler: Sampler,
    /// The surface maps' sampler: bilinear, repeating.
    repeat: Sampler,
    /// One zero texel bound as `layer_maps` for uniform stacks.
    no_maps: (Image, ImageView),
}

impl ShadingLayout {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let kinds = SHADING_BINDINGS.map(|b| b.kind);
        let image = Image::new(
            device,
            ImageDesc::new_2d_array(Format::R32G32B32A32_SFLOAT, 1, 1, 1),
            "no layer maps",
        )?;
        upload_image(device, &image, &[0; 16], ImageState::FragmentRead)?;
        let view = image.view("no layer maps")?;
        Ok(Self {
            set_layout: DescriptorSetLayout::new(device, &kinds, Stages::All, "shading inputs")?,
            sampler: Sampler::new(device, SamplerDesc::linear_clamp(), "shading tables")?,
            repeat: Sampler::new(device, SamplerDesc::linear_repeat(), "layer maps")?,
            no_maps: (image, view),
        })
    }

    /// A shading set binding `views`.
    pub fn bind(
        &self,
        device: &Arc<Device>,
        views: &InputViews<'_>,
        name: &str,
    ) -> VkResult<DescriptorSet> {
        let mut set = DescriptorSet::new(device, &self.set_layout, name)?;
        let sampled = |view| Resource::Sampled(view, &self.sampler);
        set.write(0, Resource::Buffer(views.material))
            .write(1, sampled(views.split_sum))
            .write(2, sampled(views.tir))
            .write(3, sampled(views.fgd_volume))
            .write(4, sampled(views.fgd_plane))
            .write(5, sampled(views.baked))
            .write(6, sampled(views.lobe_albedo))
            .write(
                7,
                Resource::Sampled(views.layer_maps.unwrap_or(&self.no_maps.1), &self.repeat),
            )
            .write(8, Resource::Buffer(views.material));
        Ok(set)
    }
}

/// A layer stack, with its maps' codes if it varies and its energy ratios under
/// `transport=corrected`, in the storage buffer the shading set binds.
pub fn material_buffer(
    device: &Arc<Device>,
    layers: &[LayerParams],
    maps: Option<&SurfaceMaps>,
    correction: Option<&Correction>,
    name: &str,
) -> VkResult<Buffer> {
    let mut material = MaterialGpu::new(layers);
    if let Some(maps) = maps {
        material = material.with_maps(maps);
    }
    if let Some(correction) = correction {
        material = material.with_transport(correction);
    }
    Buffer::with_data(
        device,
        BufferUsageFlags::STORAGE_BUFFER | BufferUsageFlags::UNIFORM_BUFFER,
        &[material],
        name,
    )
}

/// The descriptor set index of the scene's own inputs (the forward and sky passes).
pub const SCENE_SET: u32 = 1;

/// The scene set's bindings, as `glsl/include/bindings/scene.glsl` declares them.
pub const SCENE_BINDINGS: [Binding; 7] = [
    Binding {
        binding: 0,
        kind: BindingKind::UniformBuffer,
        name: "Frame",
    },
    Binding {
        binding: 1,
        kind: BindingKind::SampledImage,
        name: "prefiltered",
    },
    Binding {
        binding: 2,
        kind: BindingKind::StorageBuffer,
        name: "Lights",
    },
    Binding {
        binding: 3,
        kind: BindingKind::StorageBuffer,
        name: "EnvironmentSampling",
    },
    Binding {
        binding: 4,
        kind: BindingKind::SampledImage,
        name: "matched",
    },
    Binding {
        binding: 5,
        kind: BindingKind::SampledImage,
        name: "lobe_moments",
    },
    Binding {
        binding: 6,
        kind: BindingKind::SampledImage,
        name: "lamps_irradiance",
    },
];

/// One analytic light (`shared/light.glsl`, std430).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightGpu {
    /// w = 0: xyz is the unit direction towards a directional light; w = 1: a point's position.
    pub position: [f32; 4],
    /// rgb: colour × intensity; w: angular radius in radians.
    pub radiance: [f32; 4],
}

const _: () = assert!(size_of::<LightGpu>() == 32);
const _: () = assert!(offset_of!(LightGpu, radiance) == 16);
