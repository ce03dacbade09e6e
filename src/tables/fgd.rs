//! The FGD tables behind the `fgd` axis's values other than `karis` (ALGORITHMS.md §6.1, §7):
//!
//! - `fgd=4d`: FGD(μ, α, η, κ) on the reference's 64⁴ vertex-centred grid over
//!   [0, 1]² × [0, 4]², stacked as one 64×64×4096 R32F 3-D image (Vulkan guarantees only
//!   2048 texels of depth; lavapipe and desktop GPUs offer 4096 or more — checked at load).
//! - `fgd=resampled4d`: the talk's D3D12 workaround, 64×64×2048: the κ axis filtered down to
//!   32 slices ([`Filter`], box by default) and stacked onto η.
//! - `fgd=belcour`: the 4-channel table of Belcour et al. 2020 with the projection folded in
//!   ([`super::belcour`]), plus a 64³ dielectric table over η ∈ [0, 1] for the interfaces the
//!   decomposition cannot represent (light leaving a denser layer: no total internal
//!   reflection in its basis, ALGORITHMS.md §7.5).
//!
//! The grids are computed on the GPU by `fgd_table.comp.glsl` and `fgd_belcour.comp.glsl`,
//! cached on disk ([`crate::cache`]), and sampled by `lib/fgd.glsl`; [`FgdProbe`] samples
//! them at arbitrary points exactly as the shaders do.

use std::path::Path;

use crate::cache;
use crate::error::{Error, Result};
use crate::gpu::{ComputeKernel, Gpu};
use crate::model::fresnel;
use crate::shader::interface::{material_buffer, InputViews, ShadingLayout, FGD_GRID_SIZE};
use crate::shader::kernel::{KernelInterface, KernelSpec, LOCAL_SIZE_1D};
pub use crate::tables::belcour::{belcour_reference, BelcourTable, BELCOUR_KERNEL};
use crate::tables::split_sum::SplitSumTable;
use crate::tables::tir::TirTable;
use crate::tables::{filter_axis, Texels};
use crate::variant::{Fgd, ShadeSpec, VariantKey, FGD_PAST_EDGE_SHIFT, G2};
use crate::vk::{
    submit_and_wait, upload_image, Access, BindingKind, Buffer, BufferDesc, BufferUsageFlags,
    DescriptorSet, Format, Image, ImageDesc, ImageState, ImageView, Resource,
};

/// Texels per axis of every FGD grid: the size the shaders sample ([`FGD_GRID_SIZE`], the
/// reference's 64).
pub const SIZE: u32 = FGD_GRID_SIZE;
/// Hammersley samples per texel of the 4-D and η < 1 grids: they resolve the step of F at
/// the critical angle (η < 1) to ~5e-4 (256 samples: 5e-3; tests/suite/fgd.rs). The build shader
/// holds at most 1024 in shared memory.
pub const GRID_SAMPLES: u32 = 1024;
/// Samples per texel of the Belcour table (64² texels: cheap).
pub const BELCOUR_SAMPLES: u32 = 4096;
/// The 4-D table's domain in η and κ.
pub const ETA_MAX: f64 = crate::shader::interface::FGD_ETA_MAX;
pub const KAPPA_MAX: f64 = crate::shader::interface::FGD_KAPPA_MAX;
/// Depth of the stacked 4-D image: `fgd=4d` needs `maxImageDimension3D` at least this.
pub const FULL_DEPTH: u32 = SIZE * SIZE;
const MAX_GRID_SAMPLES: u32 = 1024;
/// κ slices per submission: the unit of progress.
const SLICES_PER_SUBMIT: u32 = 4;

/// A vertex-centred grid over (μ, α, η, κ): μ, α ∈ [0, 1]; η and κ over their ranges.
/// Texels are μ fastest, then α, η, κ (the layout of the stacked 3-D images).
#[derive(Clone)]
pub struct Grid {
    pub dims: [u32; 4],
    pub eta: (f64, f64),
    pub kappa: (f64, f64),
    pub samples: u32,
    pub texels: Vec<f32>,
}

impl Grid {
    pub fn index(&self, i: u32, j: u32, k: u32, l: u32) -> usize {
        let [nm, na, ne, _] = self.dims;
        (((l * ne + k) * na + j) * nm + i) as usize
    }

    pub fn texel(&self, i: u32, j: u32, k: u32, l: u32) -> f32 {
        self.texels[self.index(i, j, k, l)]
    }

    /// (μ, α, η, κ) at vertex (i, j, k, l); μ = 0 is evaluated at 1e-3 by the build.
    pub fn coordinates(&self, i: u32, j: u32, k: u32, l: u32) -> [f64; 4] {
        let at = |index: u32, n: u32, (lo, hi): (f64, f64)| {
            if n > 1 {
                lo + (hi - lo) * f64::from(index) / f64::from(n - 1)
            } else {
                lo
            }
        };
        [
            at(i, self.dims[0], (0.0, 1.0)),
            at(j, self.dims[1], (0.0, 1.0)),
            at(k, self.dims[2], self.eta),
            at(l, self.dims[3], self.kappa),
        ]
    }
}

/// The kinds of grid lamina builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridKind {
    /// 64⁴ over η, κ ∈ [0, 4].
    Full4d,
    /// 64³ over η ∈ [0, 1], κ = 0 (belcour's fallback).
    DielectricBelow1,
}

impl GridKind {
    fn dims(self, n: u32) -> [u32; 4] {
        match self {
            Self::Full4d => [n; 4],
            Self::DielectricBelow1 => [n, n, n, 1],
        }
    }

    fn ranges(self) -> ((f64, f64), (f64, f64)) {
        match self {
            Self::Full4d => ((0.0, ETA_MAX), (0.0, KAPPA_MAX)),
            Self::DielectricBelow1 => ((0.0, 1.0), (0.0, 0.0)),
        }
    }

    /// Its name in messages and in the disk cache.
    pub fn name(self) -> &'static str {
        match self {
            Self::Full4d => "fgd-4d",
            Self::DielectricBelow1 => "fgd-dielectric-below-1",
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GridPush {
    dims: [u32; 4],
    range: [f32; 4],
    sample_count: u32,
    l0: u32,
}

/// `fgd_table.comp.glsl`: a work group per (μ, α, κ) draws the samples once; its invocations
/// cover η.
pub const GRID_KERNEL: KernelInterface = KernelInterface {
    entry: "fgd_table.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[BindingKind::StorageBuffer],
    push: crate::push_block!(GridPush {
        dims,
        range,
        sample_count,
        l0
    }),
    local_size: [LOCAL_SIZE_1D, 1],
};

/// The disk-cache key of a grid.
pub fn grid_cache_key(kind: GridKind, g2: G2, n: u32, samples: u32) -> cache::Key {
    cache::Key {
        kind: kind.name(),
        params: vec![n, samples, crate::variant::Axis::code(g2)],
        shader_hash: crate::shader::entry_hash("fgd_table.comp.glsl"),
    }
}

/// The grid from the disk cache when a valid one exists (`true`), else built on the GPU and
/// stored; `progress(done, total)` follows the build in κ slices.
pub fn load_or_build_grid(
    gpu: &Gpu,
    kind: GridKind,
    g2: G2,
    n: u32,
    samples: u32,
    cache_dir: Option<&Path>,
    progress: impl FnMut(u32, u32),
) -> Result<(Grid, bool)> {
    let key = grid_cache_key(kind, g2, n, samples);
    let dims = kind.dims(n);
    let (eta, kappa) = kind.ranges();
    let count = dims.iter().map(|&d| d as usize).product();
    let (texels, cached) = cache::load_or_build(cache_dir, &key, count, || {
        Ok(build_grid(gpu, kind, g2, n, samples, progress)?.texels)
    })?;
    let grid = Grid {
        dims,
        eta,
        kappa,
        samples,
        texels,
    };
    Ok((grid, cached))
}

/// Builds a grid on the GPU (no cache).
pub fn build_grid(
    gpu: &Gpu,
    kind: GridKind,
    g2: G2,
    n: u32,
    samples: u32,
    mut progress: impl FnMut(u32, u32),
) -> Result<Grid> {
    if !(2..=256).contains(&n) || !(1..=MAX_GRID_SAMPLES).contains(&samples) {
        return Err(Error::Unsupported(format!(
            "FGD grid of {n} texels per axis and {samples} samples: allowed 2..=256 texels and \
             1..={MAX_GRID_SAMPLES} samples"
        )));
    }
    let dims = kind.dims(n);
    let (eta, kappa) = kind.ranges();
    let kernel = ComputeKernel::build(gpu, &GRID_KERNEL, &[], &[], KernelSpec::for_g2(g2))?;
    let device = &gpu.device;
    let count: u64 = dims.iter().map(|&d| u64::from(d)).product();
    let buffer = Buffer::new(device, BufferDesc::readback(count * 4), "fgd grid texels")?;
    let mut set = DescriptorSet::new(device, &kernel.set_layout, "fgd grid")?;
    set.write(0, Resource::Buffer(&buffer));
    let slices = dims[3];
    let mut l0 = 0;
    while l0 < slices {
        let depth = SLICES_PER_SUBMIT.min(slices - l0);
        submit_and_wait(device, "fgd grid", |rec| {
            rec.begin_label("fgd grid");
            kernel.record_dispatch(
                rec,
                &[&set],
                &GridPush {
                    dims,
                    range: [eta.0 as f32, eta.1 as f32, kappa.0 as f32, kappa.1 as f32],
                    sample_count: samples,
                    l0,
                },
                [dims[2], dims[0], dims[1] * depth],
            );
            rec.barrier(Access::ComputeWrite, Access::HostRead);
            rec.end_label();
            Ok(())
        })?;
        l0 += depth;
        progress(l0, slices);
    }
    Ok(Grid {
        dims,
        eta,
        kappa,
        samples,
        texels: buffer.read(),
    })
}

/// How `fgd=resampled4d` brings the κ axis from n to n/2 slices. Slice m stands for the
/// original κ index 2m + ½ (so the shader's index arithmetic is the same for every filter);
/// the filters weigh the original slices 2m − 1, 2m, 2m + 1, 2m + 2 (clamped at the edges).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// ½, ½: the mean of the two slices (the talk's best).
    Box,
    /// ⅛, ⅜, ⅜, ⅛: a triangle twice as wide.
    Tent,
    /// −1/16, 9/16, 9/16, −1/16: Catmull–Rom interpolation at the midpoint.
    CatmullRom,
}

impl Filter {
    pub const ALL: [Filter; 3] = [Filter::Box, Filter::Tent, Filter::CatmullRom];

    fn weights(self) -> [f64; 4] {
        match self {
            Self::Box => [0.0, 0.5, 0.5, 0.0],
            Self::Tent => [0.125, 0.375, 0.375, 0.125],
            Self::CatmullRom => [-0.0625, 0.5625, 0.5625, -0.0625],
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Box => "box",
            Self::Tent => "tent",
            Self::CatmullRom => "catmull-rom",
        }
    }
}

/// The resampled table of a 4-D grid: n/2 κ slices, texels laid out as the grid's.
pub fn resample(grid: &Grid, filter: Filter) -> Vec<f32> {
    let [nm, na, ne, nk] = grid.dims;
    let slice = (nm * na * ne) as usize;
    let w = filter.weights();
    let mut out = vec![0.0f32; slice * (nk / 2) as usize];
    for m in 0..nk / 2 {
        let sources: Vec<usize> = (0..4)
            .map(|t| (2 * m as i64 - 1 + t).clamp(0, i64::from(nk) - 1) as usize)
            .collect();
        let dst = &mut out[m as usize * slice..(m as usize + 1) * slice];
        for (x, d) in dst.iter_mut().enumerate() {
            let v: f64 = (0..4)
                .map(|t| w[t] * f64::from(grid.texels[sources[t] * slice + x]))
                .sum();
            *d = v as f32;
        }
    }
    out
}

/// The CPU twin of the shader's κ lookup in a resampled table, at the grid's own η and
/// (μ, α) vertices: the value `fgd=resampled4d` returns at κ = `kappa`.
pub fn resampled_at(grid: &Grid, resampled: &[f32], i: u32, j: u32, k: u32, kappa: f64) -> f64 {
    let [_, _, _, nk] = grid.dims;
    let slices = f64::from(nk / 2);
    let fk = (kappa / grid.kappa.1).clamp(0.0, 1.0) * f64::from(nk - 1);
    let g = (0.5 * (fk - 0.5)).clamp(0.0, slices - 1.0);
    let s0 = g.floor().min(slices - 2.0);
    let at = |s: f64| f64::from(resampled[grid.index(i, j, k, s as u32)]);
    at(s0) + (at(s0 + 1.0) - at(s0)) * (g - s0)
}

/// The images one `fgd` value samples: binding 5 (`fgd_table`, 3-D) and binding 6
/// (`fgd_belcour`, 2-D). Values that do not sample one get a tiny zero image there.
pub struct FgdImages {
    pub fgd: Fgd,
    pub volume: Image,
    pub volume_view: ImageView,
    pub plane: Image,
    pub plane_view: ImageView,
    /// The same tables on the CPU, looked up as the shader does.
    pub twin: FgdTwin,
}

const TABLE_USAGE: crate::vk::ImageUsageFlags = crate::vk::ImageUsageFlags::from_raw(
    crate::vk::ImageUsageFlags::SAMPLED.as_raw()
        | crate::vk::ImageUsageFlags::TRANSFER_DST.as_raw(),
);

impl FgdImages {
    /// The tables of `fgd` for the G2 form `g2`, from the disk cache or built.
    pub fn for_variant(gpu: &Gpu, fgd: Fgd, g2: G2) -> Result<Self> {
        let dir = cache::tables_dir();
        match fgd {
            Fgd::Karis => Self::new(gpu, FgdTwin::Karis, [2, 2, 2], &[0.0; 8], 1, &[[0.0; 4]]),
            Fgd::Belcour => {
                let (below, _) = load_or_build_grid(
                    gpu,
                    GridKind::DielectricBelow1,
                    g2,
                    SIZE,
                    GRID_SAMPLES,
                    dir.as_deref(),
                    |_, _| {},
                )?;
                let (table, _) =
                    BelcourTable::load_or_build(gpu, g2, SIZE, BELCOUR_SAMPLES, dir.as_deref())?;
                let (volume, plane) = (below.texels.clone(), table.folded());
                Self::new(
                    gpu,
                    FgdTwin::Belcour { table, below },
                    [SIZE, SIZE, SIZE],
                    &volume,
                    SIZE,
                    &plane,
                )
            }
            Fgd::Full4d | Fgd::Resampled4d => {
                let (grid, _) = load_or_build_grid(
                    gpu,
                    GridKind::Full4d,
                    g2,
                    SIZE,
                    GRID_SAMPLES,
                    dir.as_deref(),
                    |_, _| {},
                )?;
                Self::stacked(gpu, fgd, &grid, Filter::Box)
            }
        }
    }

    /// The 4-D grid as `fgd=4d` (whole) or `fgd=resampled4d` (κ filtered by `filter`).
    pub fn stacked(gpu: &Gpu, fgd: Fgd, grid: &Grid, filter: Filter) -> Result<Self> {
        let [nm, na, ne, nk] = grid.dims;
        if fgd == Fgd::Full4d {
            let limit = gpu.device.report.max_image_dimension_3d;
            if limit < ne * nk {
                return Err(Error::Unsupported(format!(
                    "fgd=4d stacks the 4-D table as a {nm}×{na}×{} 3-D image, but `{}` allows \
                     at most {limit} texels of depth (maxImageDimension3D); use \
                     fgd=resampled4d",
                    ne * nk,
                    gpu.device.report.name
                )));
            }
            let extent = [nm, na, ne * nk];
            let twin = FgdTwin::Full4d(grid.clone());
            Self::new(gpu, twin, extent, &grid.texels, 1, &[[0.0; 4]])
        } else {
            let texels = resample(grid, filter);
            let resampled = Grid {
                dims: [nm, na, ne, nk / 2],
                eta: grid.eta,
                kappa: grid.kappa,
                samples: grid.samples,
                texels: texels.clone(),
            };
            let extent = [nm, na, ne * nk / 2];
            Self::new(
                gpu,
                FgdTwin::Resampled4d(resampled),
                extent,
                &texels,
                1,
                &[[0.0; 4]],
            )
        }
    }

    /// Uploads a 3-D R32F volume and a 2-D RGBA32F plane.
    pub fn new(
        gpu: &Gpu,
        twin: FgdTwin,
        volume_extent: [u32; 3],
        volume: &[f32],
        plane_size: u32,
        plane: &[[f32; 4]],
    ) -> Result<Self> {
        let device = &gpu.device;
        let [w, h, d] = volume_extent;
        let volume_image = Image::new(
            device,
            ImageDesc::new_3d(Format::R32_SFLOAT, w, h, d).usage(TABLE_USAGE),
            "fgd volume",
        )?;
        upload_image(
            device,
            &volume_image,
            bytemuck::cast_slice(volume),
            ImageState::FragmentRead,
        )?;
        let plane_image = Image::new(
            device,
            ImageDesc::new_2d(Format::R32G32B32A32_SFLOAT, plane_size, plane_size)
                .usage(TABLE_USAGE),
            "fgd plane",
        )?;
        upload_image(
            device,
            &plane_image,
            bytemuck::cast_slice(plane),
            ImageState::FragmentRead,
        )?;
        Ok(Self {
            fgd: twin.fgd(),
            volume_view: volume_image.view("fgd volume")?,
            plane_view: plane_image.view("fgd plane")?,
            volume: volume_image,
            plane: plane_image,
            twin,
        })
    }
}

/// The CPU twin of what an `fgd` value's shader samples: the very texels, looked up as
/// `lib/fgd.glsl` does (vertex-centred multilinear in μ, α, η; the κ slices lerped). With
/// [`FgdLookup`] the f64 model runs with the GPU's own FGD, so that GPU-vs-CPU differences are
/// the model arithmetic's (the hardware's 8-bit filter weights aside).
pub enum FgdTwin {
    /// `karis` reads the split-sum table, which is its own twin ([`SplitSumTable`]).
    Karis,
    Full4d(Grid),
    /// The κ axis filtered down to n/2 slices.
    Resampled4d(Grid),
    /// The four folded integrals, and the η < 1 dielectric grid.
    Belcour {
        table: BelcourTable,
        below: Grid,
    },
}

impl FgdTwin {
    pub fn fgd(&self) -> Fgd {
        match self {
            Self::Karis => Fgd::Karis,
            Self::Full4d(_) => Fgd::Full4d,
            Self::Resampled4d(_) => Fgd::Resampled4d,
            Self::Belcour { .. } => Fgd::Belcour,
        }
    }
}

/// The sampler's weights on a vertex-centred axis of `n` points: (index, weight).
fn vertex_axis(x: f64, n: u32) -> (u32, f64) {
    let (i, w) = filter_axis(x, n as usize, Texels::Vertices);
    (i as u32, w)
}

impl Grid {
    /// Trilinear in (μ, α, η) at fractional vertex coordinates within κ slice `l`.
    fn trilinear(
        &self,
        (i, fi): (u32, f64),
        (j, fj): (u32, f64),
        (k, fk): (u32, f64),
        l: u32,
    ) -> f64 {
        let v = |di: u32, dj: u32, dk: u32| f64::from(self.texel(i + di, j + dj, k + dk, l));
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let plane = |dk: u32| {
            lerp(
                lerp(v(0, 0, dk), v(1, 0, dk), fi),
                lerp(v(0, 1, dk), v(1, 1, dk), fi),
                fj,
            )
        };
        lerp(plane(0), plane(1), fk)
    }
}

/// What the 4-D tables add to the value at their domain's edge for an (η, κ) beyond it (0
/// within): the split sum's slope of FGD in F0, A(μ, α), times the rise of F0 from the edge.
/// Exact at normal incidence; for aluminium's κ (9.2, 6.3, 4.8) within 0.033 of the exact
/// FGD at μ ≥ 0.2 (0.034 resampled), where clamping κ to the edge is 0.22 off
/// (`tests/suite/fgd.rs`).
/// `fgd_stacked` in `glsl/include/lib/fgd.glsl`.
pub fn beyond_the_table(
    split_sum: &SplitSumTable,
    mu: f64,
    alpha: f64,
    eta: f64,
    kappa: f64,
) -> f64 {
    if eta <= ETA_MAX && kappa <= KAPPA_MAX {
        return 0.0;
    }
    let edge = fresnel::f0(eta.min(ETA_MAX), kappa.min(KAPPA_MAX));
    split_sum.sample(mu, alpha)[0] * (fresnel::f0(eta, kappa) - edge)
}

/// [`FgdTwin`] (with the split-sum table for `karis`) as an FGD provider of the f64 model.
pub struct FgdLookup<'a> {
    pub twin: &'a FgdTwin,
    pub split_sum: &'a SplitSumTable,
}

impl crate::model::Fgd for FgdLookup<'_> {
    fn fgd(&self, mu: f64, alpha: f64, eta: f64, kappa: f64) -> f64 {
        match self.twin {
            FgdTwin::Karis => self.split_sum.fgd(mu, alpha, eta, kappa),
            FgdTwin::Full4d(grid) | FgdTwin::Resampled4d(grid) => {
                let n = grid.dims[0];
                let (m, a) = (vertex_axis(mu, n), vertex_axis(alpha, n));
                let e = vertex_axis(eta / ETA_MAX, n);
                let fk = (kappa / KAPPA_MAX).clamp(0.0, 1.0) * f64::from(n - 1);
                let slices = grid.dims[3];
                let g = if slices == n {
                    fk
                } else {
                    (0.5 * (fk - 0.5)).clamp(0.0, f64::from(slices - 1))
                };
                let s0 = (g.floor() as u32).min(slices - 2);
                let lo = grid.trilinear(m, a, e, s0);
                let hi = grid.trilinear(m, a, e, s0 + 1);
                let value = lo + (hi - lo) * (g - f64::from(s0));
                value + beyond_the_table(self.split_sum, mu, alpha, eta, kappa)
            }
            FgdTwin::Belcour { table, below } => {
                if kappa <= 0.0 && eta < 1.0 {
                    let n = below.dims[0];
                    let at = |x: f64| vertex_axis(x, n);
                    return below.trilinear(at(mu), at(alpha), at(eta), 0);
                }
                let p = table.basis.fold(table.sample(mu, alpha));
                fresnel::f0(eta, kappa) * p[0]
                    + p[1]
                    + fresnel::conductor(super::belcour::CT1, eta, kappa) * p[2]
                    + fresnel::conductor(super::belcour::CT2, eta, kappa) * p[3]
            }
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ProbePush {
    count: u32,
}

/// `fgd_probe.comp.glsl`: one invocation per point, after the shading set.
pub const PROBE_KERNEL: KernelInterface = KernelInterface {
    entry: "fgd_probe.comp.glsl",
    shades: true,
    scene: false,
    bindings: &[BindingKind::StorageBuffer, BindingKind::StorageBuffer],
    push: crate::push_block!(ProbePush { count }),
    local_size: [LOCAL_SIZE_1D, 1],
};

/// Samples FGD at given (μ, α, η, κ) points with the shaders' own code (`fgd_probe.comp.glsl`),
/// through the shading set as every pass that shades binds it (an empty stack, no TIR table).
pub struct FgdProbe<'g> {
    gpu: &'g Gpu,
    layout: ShadingLayout,
    kernel: ComputeKernel,
    material: Buffer,
    tir_unused: TirTable,
}

impl<'g> FgdProbe<'g> {
    pub fn new(gpu: &'g Gpu, fgd: Fgd) -> Result<Self> {
        let variant = VariantKey {
            fgd,
            ..VariantKey::default()
        };
        let layout = ShadingLayout::new(&gpu.device)?;
        let kernel = ComputeKernel::build(
            gpu,
            &PROBE_KERNEL,
            &[],
            &[&layout.set_layout],
            ShadeSpec {
                // With the code past the 4-D table's edge: the probe measures every point.
                fgd: variant.spec().fgd | 1 << FGD_PAST_EDGE_SHIFT,
                ..variant.spec()
            },
        )?;
        Ok(Self {
            gpu,
            layout,
            kernel,
            material: material_buffer(&gpu.device, &[], None, None, "fgd probe material")?,
            tir_unused: TirTable::for_variant(gpu, crate::variant::Tir::None)?,
        })
    }

    /// FGD at each point (μ, α, η, κ).
    pub fn sample(
        &self,
        split_sum: &SplitSumTable,
        images: &FgdImages,
        points: &[[f32; 4]],
    ) -> Result<Vec<f32>> {
        if points.is_empty() {
            return Ok(Vec::new());
        }
        let device = &self.gpu.device;
        let input = Buffer::with_data(
            device,
            BufferUsageFlags::STORAGE_BUFFER,
            points,
            "fgd probe points",
        )?;
        let output = Buffer::new(
            device,
            BufferDesc::readback(points.len() as u64 * 4),
            "fgd probe values",
        )?;
        let views = InputViews {
            material: &self.material,
            split_sum: &split_sum.view,
            tir: self.tir_unused.view_for(crate::variant::Tir::None),
            fgd_volume: &images.volume_view,
            fgd_plane: &images.plane_view,
            baked: &split_sum.view,
            // The probe lights nothing: any 2-D view fills the lights' binding.
            lobe_albedo: &split_sum.view,
            layer_maps: None,
        };
        let shading = self.layout.bind(device, &views, "fgd probe shading")?;
        let mut set = DescriptorSet::new(device, &self.kernel.set_layout, "fgd probe")?;
        set.write(0, Resource::Buffer(&input))
            .write(1, Resource::Buffer(&output));
        let count = points.len() as u32;
        submit_and_wait(device, "fgd probe", |rec| {
            self.kernel.record_dispatch(
                rec,
                &[&shading, &set],
                &ProbePush { count },
                [count, 1, 1],
            );
            rec.barrier(Access::ComputeWrite, Access::HostRead);
            Ok(())
        })?;
        Ok(output.read())
    }
}
