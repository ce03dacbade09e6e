//! The deferred path (`path=deferred`, issue 28): the mesh's draw writes a G-buffer of what
//! the forward pass's fragment shader receives (the interpolated world position and normal,
//! the texture coordinates: `gbuffer.frag.glsl`), then compute kernels shade the pixels it
//! covers with the forward pass's own shading code (`glsl/include/lib/deferred.glsl`,
//! `lib/shade.glsl`) into the render target. On a GPU whose graphics run on a few of its units
//! (the H100: 4 of 132 SMs) the compute dispatches run on all of them.
//!
//! `classify` says how pixels reach pipelines:
//! - `none`: one kernel over every pixel (`deferred.comp.glsl`), generic or specialized as
//!   `mode` says; a varying stack under `mode=specialized` whose pixels fall into several
//!   classes, each needing its own pipeline (`render::classes`), is refused by name.
//! - `tiles` and `pixels`: a classification in three small dispatches puts the items (8×8
//!   tiles, one work group each, or pixels) into bins, one per class — `bin_count.comp.glsl`
//!   finds each pixel's class by the coverage tests the forward path's stencil marks make and
//!   counts the items per bin, `bin_offsets.comp.glsl` turns the counts into list offsets and
//!   indirect dispatch sizes, `bin_scatter.comp.glsl` writes each item at its place — then
//!   each class's pipeline shades its bin by an indirect dispatch (`deferred_bins.comp.glsl`).
//!   A tile whose pixels mix classes goes to the generic pipeline fitted to the stack, the
//!   only one that shades several structures (Unity HDRP's tiled deferred does the same with
//!   its feature flags: the variant that covers every feature a tile holds). Every other stack
//!   has one class, every covered pixel, in bin 0.
//!
//! The tile is 8×8 pixels: lavapipe's SIMD width is 8 lanes of 32 bits (256-bit vectors), so a
//! tile row is one vector, and 64 invocations are two warps or one wave on the GPUs lamina
//! measures.

use ash::vk::ImageUsageFlags;

use crate::error::{Error, Result};
use crate::gpu::{ComputeKernel, Gpu};
use crate::shader::kernel::{KernelInterface, KernelSpec};
use crate::variant::{Classify, Mode, ShadeSpec, VariantKey};
use crate::vk::{
    Access, BindingKind, Buffer, BufferDesc, DescriptorSet, DescriptorSetLayout, Format, Image,
    ImageDesc, ImageState, ImageView, Pipeline, Recorder, Resource, Sampler,
};

use super::pass::{MaterialKey, PassKey};

/// The G-buffer's two attachments: (position, u) and (normal, v), in floats, so that the
/// compute kernel shades the very inputs the fragment shader would.
pub const GBUFFER_FORMAT: Format = Format::R32G32B32A32_SFLOAT;

/// The G-buffer's fragment shader.
pub const GBUFFER_ENTRY: &str = "gbuffer.frag.glsl";

/// The shading kernels' tile edge, in pixels (their work group; `classify=tiles`' tile).
pub const TILE: u32 = 8;

/// Bins: one per class of pixels, named by its marked bits (`render::classes`: at most 8
/// marks), then [`BIN_MIXED`]. Mirrors `glsl/include/lib/bins.glsl`.
pub const BIN_COUNT: u32 = 257;
/// The bin of the tiles whose pixels mix classes.
pub const BIN_MIXED: u32 = 256;
/// Words per bin's header: the dispatch's work-group counts, the item count, the offset.
pub const BIN_STRIDE: u32 = 8;

/// The shading kernels' push constants: the frame's size.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DeferredPush {
    pub width: u32,
    pub height: u32,
}

/// `bin_count.comp.glsl`'s push constants: the frame's size and the marks' material layers
/// (mark k in bits 4k…4k+3).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CountPush {
    pub width: u32,
    pub height: u32,
    pub marks: u32,
    pub mark_count: u32,
}

/// `bin_offsets.comp.glsl`'s push constants: items per work group of the shading dispatch.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct OffsetsPush {
    pub per_group: u32,
}

/// `deferred_bins.comp.glsl`'s push constants: the frame's size and the bin it shades.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BinPush {
    pub width: u32,
    pub height: u32,
    pub bin: u32,
}

/// `deferred.comp.glsl` (`classify=none`): the shading and scene sets, then its own — the
/// G-buffer's two attachments (sampled) and the render target (storage).
pub const KERNEL: KernelInterface = KernelInterface {
    entry: "deferred.comp.glsl",
    shades: true,
    scene: true,
    bindings: &[
        BindingKind::SampledImage,
        BindingKind::SampledImage,
        BindingKind::StorageImage,
    ],
    push: crate::push_block!(DeferredPush { width, height }),
    local_size: [TILE, TILE],
};

/// `deferred_bins.comp.glsl`: [`KERNEL`]'s bindings, then the bins and the list.
pub const BINS_KERNEL: KernelInterface = KernelInterface {
    entry: "deferred_bins.comp.glsl",
    shades: true,
    scene: true,
    bindings: &[
        BindingKind::SampledImage,
        BindingKind::SampledImage,
        BindingKind::StorageImage,
        BindingKind::StorageBuffer,
        BindingKind::StorageBuffer,
    ],
    push: crate::push_block!(BinPush { width, height, bin }),
    local_size: [TILE, TILE],
};

/// `bin_count.comp.glsl`: the shading set (the coverage maps), then the G-buffer, the bins
/// and the items' keys.
pub const COUNT_KERNEL: KernelInterface = KernelInterface {
    entry: "bin_count.comp.glsl",
    shades: true,
    scene: false,
    bindings: &[
        BindingKind::SampledImage,
        BindingKind::SampledImage,
        BindingKind::StorageBuffer,
        BindingKind::StorageBuffer,
    ],
    push: crate::push_block!(CountPush {
        width,
        height,
        marks,
        mark_count
    }),
    local_size: [TILE, TILE],
};

/// `bin_offsets.comp.glsl`: the bins, one invocation.
pub const OFFSETS_KERNEL: KernelInterface = KernelInterface {
    entry: "bin_offsets.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[BindingKind::StorageBuffer],
    push: crate::push_block!(OffsetsPush { per_group }),
    local_size: [1, 1],
};

/// `bin_scatter.comp.glsl`: the bins, the keys and the list.
pub const SCATTER_KERNEL: KernelInterface = KernelInterface {
    entry: "bin_scatter.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[
        BindingKind::StorageBuffer,
        BindingKind::StorageBuffer,
        BindingKind::StorageBuffer,
    ],
    push: crate::push_block!(DeferredPush { width, height }),
    local_size: [TILE, TILE],
};

/// A deferred pass's pipelines: the G-buffer's draw and the shading.
pub struct DeferredPipelines {
    /// Draws the mesh into the G-buffer (`forward.vert.glsl`, `gbuffer.frag.glsl`); built
    /// by the caller, who owns the graphics layout.
    pub gbuffer: Pipeline,
    pub shading: Shading,
}

/// How a deferred pass shades (its `classify`).
pub enum Shading {
    /// One kernel over every pixel.
    Grid(ComputeKernel),
    Binned(Box<Binned>),
}

/// A classified deferred pass: the classification's kernels and one shading kernel per bin.
pub struct Binned {
    /// Items are 8×8 tiles (else pixels).
    tiles: bool,
    /// The marks' material layers, 4 bits each, and their count.
    marks: u32,
    mark_count: u32,
    count: ComputeKernel,
    offsets: ComputeKernel,
    scatter: ComputeKernel,
    /// Each bin that may hold items, and the kernel that shades it: a routed stack's classes
    /// the most layers first (then, for tiles, the mixed bin's generic kernel); else bin 0.
    bins: Vec<(u32, ComputeKernel)>,
}

impl DeferredPipelines {
    /// The shading of `key` (whose `spec` the caller made) over the `shading` and `scene`
    /// set layouts, writing a target of `target_format`, beside the G-buffer's pipeline.
    pub fn new(
        gpu: &Gpu,
        gbuffer: Pipeline,
        shared: [&DescriptorSetLayout; 2],
        key: &PassKey,
        spec: ShadeSpec,
        defines: &[(&'static str, &'static str)],
        target_format: Format,
    ) -> Result<Self> {
        let mut defines = defines.to_vec();
        if target_format == Format::R32G32B32A32_SFLOAT {
            defines.push(("LAMINA_TARGET_RGBA32F", "1"));
        }
        let tiles = match key.variant.classify {
            Classify::None => {
                let spec = grid_spec(key, spec)?;
                let kernel = ComputeKernel::build(gpu, &KERNEL, &defines, &shared, spec)?;
                return Ok(Self {
                    gbuffer,
                    shading: Shading::Grid(kernel),
                });
            }
            Classify::Tiles => true,
            Classify::Pixels => false,
        };
        if tiles {
            defines.push(("LAMINA_BIN_TILES", "1"));
        }
        let specs = bin_specs(key, spec, tiles);
        let (marks, mark_count) = match &key.material {
            MaterialKey::Classes(routing) => (
                routing
                    .marks
                    .iter()
                    .enumerate()
                    .map(|(k, &layer)| (layer as u32) << (4 * k))
                    .sum(),
                routing.marks.len() as u32,
            ),
            _ => (0, 0),
        };
        let bins = specs
            .into_iter()
            .map(|(bin, spec)| {
                ComputeKernel::build(gpu, &BINS_KERNEL, &defines, &shared, spec).map(|k| (bin, k))
            })
            .collect::<Result<Vec<_>>>()?;
        let table = KernelSpec::default();
        Ok(Self {
            gbuffer,
            shading: Shading::Binned(Box::new(Binned {
                tiles,
                marks,
                mark_count,
                count: ComputeKernel::build(gpu, &COUNT_KERNEL, &defines, &shared[..1], spec)?,
                offsets: ComputeKernel::build(gpu, &OFFSETS_KERNEL, &[], &[], table)?,
                scatter: ComputeKernel::build(gpu, &SCATTER_KERNEL, &[], &[], table)?,
                bins,
            })),
        })
    }

    /// The pipeline the bench reports: the only shading kernel, or the first bin's (a routed
    /// stack's class with the most layers).
    pub fn main_pipeline(&self) -> &Pipeline {
        match &self.shading {
            Shading::Grid(kernel) => &kernel.pipeline,
            Shading::Binned(binned) => &binned.bins[0].1.pipeline,
        }
    }

    /// Every pipeline, the G-buffer's first.
    pub fn pipelines(&self) -> Vec<&Pipeline> {
        let mut out = vec![&self.gbuffer];
        match &self.shading {
            Shading::Grid(kernel) => out.push(&kernel.pipeline),
            Shading::Binned(b) => {
                out.extend([&b.count, &b.offsets, &b.scatter].map(|k| &k.pipeline));
                out.extend(b.bins.iter().map(|(_, k)| &k.pipeline));
            }
        }
        out
    }
}

/// The constants of `classify=none`'s one kernel over every pixel: the pass's own `spec`, or
/// for a routed stack whose coverage leaves one class everywhere that class's; a routed stack
/// of several classes, each needing its own pipeline, is refused by name.
pub fn grid_spec(key: &PassKey, spec: ShadeSpec) -> Result<ShadeSpec> {
    match &key.material {
        MaterialKey::Classes(routing) => match routing.classes.as_slice() {
            [one] => Ok(key.class_spec(one)),
            classes => Err(Error::Unsupported(format!(
                "variant {}: the stack's pixels fall into {} classes, each shaded by its own \
                 pipeline, which classify=none does not tell apart; classify them \
                 (classify=pixels or classify=tiles), or shade the stack with path=forward, \
                 or under mode=generic",
                key.variant,
                classes.len()
            ))),
        },
        _ => Ok(spec),
    }
}

/// Each bin a classified pass shades and its pipeline's constants: a routed stack's classes
/// (and for tiles the mixed bin, shaded by the generic pipeline holding every layer), or bin
/// 0 with the pass's own `spec`.
pub fn bin_specs(key: &PassKey, spec: ShadeSpec, tiles: bool) -> Vec<(u32, ShadeSpec)> {
    let MaterialKey::Classes(routing) = &key.material else {
        return vec![(0, spec)];
    };
    let mut specs: Vec<(u32, ShadeSpec)> = routing
        .classes
        .iter()
        .map(|class| (class.bits, key.class_spec(class)))
        .collect();
    if tiles {
        let generic = PassKey {
            variant: VariantKey {
                mode: Mode::Generic,
                max_layers: routing.layer_count as u32,
                ..key.variant
            },
            material: MaterialKey::Any,
            ..key.clone()
        };
        specs.push((BIN_MIXED, generic.spec(None)));
    }
    specs
}

/// A deferred frame's resources: the G-buffer's attachments, and the shading's sets over them,
/// the render target and (classified) the bins, the items' keys and the list.
pub struct DeferredFrame {
    pub images: [Image; 2],
    pub views: [ImageView; 2],
    sets: FrameSets,
}

enum FrameSets {
    Grid(DescriptorSet),
    Binned(Box<BinnedSets>),
}

struct BinnedSets {
    bins: Buffer,
    count: DescriptorSet,
    offsets: DescriptorSet,
    scatter: DescriptorSet,
    shade: DescriptorSet,
    _buffers: [Buffer; 2],
}

impl DeferredFrame {
    pub fn new(
        gpu: &Gpu,
        pipelines: &DeferredPipelines,
        target_view: &ImageView,
        sampler: &Sampler,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let device = &gpu.device;
        let desc = ImageDesc::new_2d(GBUFFER_FORMAT, width, height)
            .usage(ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::SAMPLED);
        let images = [
            Image::new(device, desc, "g-buffer position")?,
            Image::new(device, desc, "g-buffer normal")?,
        ];
        let views = [
            images[0].view("g-buffer position")?,
            images[1].view("g-buffer normal")?,
        ];
        let gbuffer = |set: &mut DescriptorSet| {
            set.write(0, Resource::Sampled(&views[0], sampler))
                .write(1, Resource::Sampled(&views[1], sampler));
        };
        let sets = match &pipelines.shading {
            Shading::Grid(kernel) => {
                let mut set = DescriptorSet::new(device, &kernel.set_layout, "g-buffer")?;
                gbuffer(&mut set);
                set.write(2, Resource::Storage(target_view));
                FrameSets::Grid(set)
            }
            Shading::Binned(binned) => {
                let [w, h] = binned.grid(width, height);
                let items = u64::from(w) * u64::from(h);
                let header = u64::from(BIN_COUNT * BIN_STRIDE) * 4;
                let bins = Buffer::new(device, BufferDesc::indirect(header), "bins")?;
                let keys = Buffer::new(device, BufferDesc::storage(items * 8), "bin keys")?;
                let list = Buffer::new(device, BufferDesc::storage(items * 4), "bin list")?;
                let mut count = DescriptorSet::new(device, &binned.count.set_layout, "bin count")?;
                gbuffer(&mut count);
                count
                    .write(2, Resource::Buffer(&bins))
                    .write(3, Resource::Buffer(&keys));
                let mut offsets =
                    DescriptorSet::new(device, &binned.offsets.set_layout, "bin offsets")?;
                offsets.write(0, Resource::Buffer(&bins));
                let mut scatter =
                    DescriptorSet::new(device, &binned.scatter.set_layout, "bin scatter")?;
                scatter
                    .write(0, Resource::Buffer(&bins))
                    .write(1, Resource::Buffer(&keys))
                    .write(2, Resource::Buffer(&list));
                let layout = &binned.bins[0].1.set_layout;
                let mut shade = DescriptorSet::new(device, layout, "bin shading")?;
                gbuffer(&mut shade);
                shade
                    .write(2, Resource::Storage(target_view))
                    .write(3, Resource::Buffer(&bins))
                    .write(4, Resource::Buffer(&list));
                FrameSets::Binned(Box::new(BinnedSets {
                    bins,
                    count,
                    offsets,
                    scatter,
                    shade,
                    _buffers: [keys, list],
                }))
            }
        };
        Ok(Self {
            images,
            views,
            sets,
        })
    }

    /// Records the shading of the G-buffer (drawn, in `ComputeRead`) into `target` (a colour
    /// attachment, and left one) with the `shared` shading and scene sets bound.
    pub fn record_shading(
        &self,
        rec: &mut Recorder<'_>,
        pipelines: &DeferredPipelines,
        shared: [&DescriptorSet; 2],
        target: &Image,
        [width, height]: [u32; 2],
    ) {
        let to_compute = |rec: &mut Recorder<'_>| {
            rec.transition(
                target,
                0..1,
                ImageState::ColorAttachment,
                ImageState::ComputeWrite,
            )
        };
        let frame = DeferredPush { width, height };
        match (&pipelines.shading, &self.sets) {
            (Shading::Grid(kernel), FrameSets::Grid(set)) => {
                to_compute(rec);
                let sets = [shared[0], shared[1], set];
                kernel.record_dispatch(rec, &sets, &frame, [width, height, 1]);
            }
            (Shading::Binned(binned), FrameSets::Binned(sets)) => {
                let BinnedSets {
                    bins,
                    count,
                    offsets,
                    scatter,
                    shade,
                    ..
                } = &**sets;
                let [w, h] = binned.grid(width, height);
                rec.fill_buffer(bins, bins.size(), 0);
                rec.barrier(Access::TransferWrite, Access::ComputeReadWrite);
                let push = CountPush {
                    width,
                    height,
                    marks: binned.marks,
                    mark_count: binned.mark_count,
                };
                binned
                    .count
                    .record_dispatch(rec, &[shared[0], count], &push, [width, height, 1]);
                rec.barrier(Access::ComputeWrite, Access::ComputeReadWrite);
                let per_group = if binned.tiles { 1 } else { TILE * TILE };
                let push = OffsetsPush { per_group };
                binned
                    .offsets
                    .record_dispatch(rec, &[offsets], &push, [1; 3]);
                rec.barrier(Access::ComputeWrite, Access::ComputeRead);
                let grid = DeferredPush {
                    width: w,
                    height: h,
                };
                binned
                    .scatter
                    .record_dispatch(rec, &[scatter], &grid, [w, h, 1]);
                rec.barrier(Access::ComputeWrite, Access::ComputeRead);
                rec.barrier(Access::ComputeWrite, Access::IndirectRead);
                to_compute(rec);
                for (i, (bin, kernel)) in binned.bins.iter().enumerate() {
                    if i > 0 {
                        // The bins write disjoint pixels of one image; the validation layer
                        // tracks the image whole.
                        rec.transition(
                            target,
                            0..1,
                            ImageState::ComputeWrite,
                            ImageState::ComputeWrite,
                        );
                    }
                    let push = BinPush {
                        width,
                        height,
                        bin: *bin,
                    };
                    let offset = u64::from(bin * BIN_STRIDE) * 4;
                    let sets = [shared[0], shared[1], shade];
                    kernel.record_dispatch_indirect(rec, &sets, &push, bins, offset);
                }
            }
            _ => unreachable!("a frame's sets are made for its pass's shading"),
        }
        rec.transition(
            target,
            0..1,
            ImageState::ComputeWrite,
            ImageState::ColorAttachment,
        );
    }
}

impl Binned {
    /// The grid of items over a frame of `width`×`height`: tiles or pixels.
    fn grid(&self, width: u32, height: u32) -> [u32; 2] {
        if self.tiles {
            [width.div_ceil(TILE), height.div_ceil(TILE)]
        } else {
            [width, height]
        }
    }
}
