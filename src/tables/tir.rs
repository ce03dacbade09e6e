//! The TIR table (ALGORITHMS.md §6.3) behind `tir=lut32` and `tir=lut16`: for incidence cosine
//! μ, roughness α and relative IOR η < 1, the fraction of a GGX reflection lobe that total
//! internal reflection keeps inside the layer.
//!
//! n³ texels on a vertex-centred grid (texel (i, j, k) at μ = i/(n−1), α = j/(n−1),
//! η = k/(n−1)), generated on the GPU by `tir_table.comp.glsl` and kept in two 3-D images: R32F
//! (`lut32`) and R16F (`lut16`, the same values rounded to half floats). The shader samples with
//! u = (x·(n−1) + ½)/n and a trilinear filter, which lands texel centres on the grid.
//! [`trapped_fraction`](crate::model::tir::trapped_fraction) integrates the same quantity in f64.

use half::f16;

use std::path::Path;

use crate::cache;
use crate::error::Result;
use crate::gpu::{ComputeKernel, Gpu};
use crate::shader::interface::TIR_TABLE_SIZE;
use crate::shader::kernel::{KernelInterface, KernelSpec, LOCAL_SIZE_2D};
use crate::tables::{filter_axis, Texels};
use crate::variant::Tir;
use crate::vk::{
    submit_and_wait, upload_image, Access, BindingKind, Buffer, BufferDesc, DescriptorSet, Format,
    Image, ImageDesc, ImageState, ImageUsageFlags, ImageView, Resource,
};

/// The size the shaders sample ([`TIR_TABLE_SIZE`]: 64³, the size of the reference's table).
pub const DEFAULT_SIZE: u32 = TIR_TABLE_SIZE;
/// Hammersley samples per texel; the estimate is within ~2e-3 of the integral (tests/suite/tables.rs).
pub const DEFAULT_SAMPLES: u32 = 1024;
/// Sampled by the shaders, uploaded, and read back by the tests.
const TABLE_USAGE: ImageUsageFlags = ImageUsageFlags::from_raw(
    ImageUsageFlags::SAMPLED.as_raw()
        | ImageUsageFlags::TRANSFER_DST.as_raw()
        | ImageUsageFlags::TRANSFER_SRC.as_raw(),
);

/// η slices per submission: the unit of progress.
const SLICES_PER_SUBMIT: u32 = 8;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    size: u32,
    sample_count: u32,
    z0: u32,
}

/// `tir_table.comp.glsl`: one invocation per texel of `depth` η slices from `z0`.
pub const KERNEL: KernelInterface = KernelInterface {
    entry: "tir_table.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[BindingKind::StorageBuffer],
    push: crate::push_block!(Push {
        size,
        sample_count,
        z0
    }),
    local_size: [LOCAL_SIZE_2D, LOCAL_SIZE_2D],
};

pub struct TirTable {
    pub size: u32,
    pub samples: u32,
    /// The values the GPU computed, μ fastest, then α, then η.
    pub texels: Vec<f32>,
    /// R32_SFLOAT, in `FragmentRead` state.
    pub image32: Image,
    pub view32: ImageView,
    /// R16_SFLOAT, the same values rounded to half floats.
    pub image16: Image,
    pub view16: ImageView,
}

impl TirTable {
    /// The table from the disk cache when a valid one exists (`true`), else built on the GPU
    /// and stored there; `progress(done, total)` follows the build in η slices.
    pub fn load_or_build(
        gpu: &Gpu,
        size: u32,
        samples: u32,
        cache_dir: Option<&Path>,
        progress: impl FnMut(u32, u32),
    ) -> Result<(Self, bool)> {
        let key = cache_key(size, samples);
        let count = (size as usize).pow(3);
        let (texels, cached) = cache::load_or_build(cache_dir, &key, count, || {
            Ok(Self::build(gpu, size, samples, progress)?.texels)
        })?;
        Ok((Self::from_texels(gpu, size, samples, texels)?, cached))
    }

    /// Builds the table on the GPU (no cache).
    pub fn build(
        gpu: &Gpu,
        size: u32,
        samples: u32,
        mut progress: impl FnMut(u32, u32),
    ) -> Result<Self> {
        if size < 2 {
            return Err(crate::error::Error::Unsupported(format!(
                "TIR table size {size}: at least 2 texels per axis"
            )));
        }
        let kernel = ComputeKernel::build(gpu, &KERNEL, &[], &[], KernelSpec::default())?;
        let device = &gpu.device;
        let count = u64::from(size).pow(3);
        let buffer = Buffer::new(device, BufferDesc::readback(count * 4), "tir texels")?;
        let mut set = DescriptorSet::new(device, &kernel.set_layout, "tir table")?;
        set.write(0, Resource::Buffer(&buffer));
        let mut z0 = 0;
        while z0 < size {
            let depth = SLICES_PER_SUBMIT.min(size - z0);
            submit_and_wait(device, "tir table", |rec| {
                rec.begin_label("tir table");
                kernel.record_dispatch(
                    rec,
                    &[&set],
                    &Push {
                        size,
                        sample_count: samples,
                        z0,
                    },
                    [size, size, depth],
                );
                rec.barrier(Access::ComputeWrite, Access::HostRead);
                rec.end_label();
                Ok(())
            })?;
            z0 += depth;
            progress(z0, size);
        }
        let texels: Vec<f32> = buffer.read();
        Self::from_texels(gpu, size, samples, texels)
    }

    /// Uploads computed texels into the two images.
    pub fn from_texels(gpu: &Gpu, size: u32, samples: u32, texels: Vec<f32>) -> Result<Self> {
        let device = &gpu.device;
        let image32 = Image::new(
            device,
            ImageDesc::new_3d(Format::R32_SFLOAT, size, size, size).usage(TABLE_USAGE),
            "tir table lut32",
        )?;
        upload_image(
            device,
            &image32,
            bytemuck::cast_slice(&texels),
            ImageState::FragmentRead,
        )?;
        let halves: Vec<f16> = texels.iter().map(|&v| f16::from_f32(v)).collect();
        let image16 = Image::new(
            device,
            ImageDesc::new_3d(Format::R16_SFLOAT, size, size, size).usage(TABLE_USAGE),
            "tir table lut16",
        )?;
        upload_image(
            device,
            &image16,
            bytemuck::cast_slice(&halves),
            ImageState::FragmentRead,
        )?;
        Ok(Self {
            view32: image32.view("tir table lut32")?,
            view16: image16.view("tir table lut16")?,
            image32,
            image16,
            size,
            samples,
            texels,
        })
    }

    /// The table a variant samples: the real one (from the cache or built) for `lut32` and
    /// `lut16`, else a 2³ table of zeros that only fills the descriptor.
    pub fn for_variant(gpu: &Gpu, tir: Tir) -> Result<Self> {
        if matches!(tir, Tir::Lut32 | Tir::Lut16) {
            let dir = cache::tables_dir();
            Ok(Self::load_or_build(
                gpu,
                DEFAULT_SIZE,
                DEFAULT_SAMPLES,
                dir.as_deref(),
                |_, _| {},
            )?
            .0)
        } else {
            Self::from_texels(gpu, 2, 0, vec![0.0; 8])
        }
    }

    /// The image a variant samples (`lut16` the half-float one, anything else the f32 one).
    pub fn view_for(&self, tir: Tir) -> &ImageView {
        if tir == Tir::Lut16 {
            &self.view16
        } else {
            &self.view32
        }
    }

    pub fn texel(&self, i: u32, j: u32, k: u32) -> f32 {
        let n = self.size;
        self.texels[((k * n + j) * n + i) as usize]
    }

    /// (μ, α, η) at grid vertex (i, j, k).
    pub fn coordinates(&self, i: u32, j: u32, k: u32) -> (f64, f64, f64) {
        let step = 1.0 / f64::from(self.size - 1);
        (
            f64::from(i) * step,
            f64::from(j) * step,
            f64::from(k) * step,
        )
    }

    /// The CPU twin of the shader's lookup: trilinear over the texels (rounded to half floats
    /// for `half`), vertex-centred, clamped to the domain.
    pub fn sample(&self, mu: f64, alpha: f64, eta: f64, half: bool) -> f64 {
        let n = self.size as usize;
        let value = |i: usize, j: usize, k: usize| {
            let v = self.texels[(k * n + j) * n + i];
            f64::from(if half { f16::from_f32(v).to_f32() } else { v })
        };
        let axis = |x: f64| filter_axis(x, n, Texels::Vertices);
        let (i, fx) = axis(mu);
        let (j, fy) = axis(alpha);
        let (k, fz) = axis(eta);
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let plane = |k: usize| {
            lerp(
                lerp(value(i, j, k), value(i + 1, j, k), fx),
                lerp(value(i, j + 1, k), value(i + 1, j + 1, k), fx),
                fy,
            )
        };
        lerp(plane(k), plane(k + 1), fz)
    }
}

/// The disk-cache key of a TIR table: its size, sample count and the shaders' hash.
pub fn cache_key(size: u32, samples: u32) -> cache::Key {
    cache::Key {
        kind: "tir",
        params: vec![size, samples],
        shader_hash: crate::shader::entry_hash("tir_table.comp.glsl"),
    }
}

/// `tir=lut32` / `tir=lut16` as the GPU computes them.
pub struct TableTir<'a> {
    pub table: &'a TirTable,
    pub half: bool,
}

impl crate::model::Tir for TableTir<'_> {
    fn tir(&self, mu: f64, alpha: f64, eta: f64) -> f64 {
        self.table.sample(mu, alpha, eta, self.half)
    }
}

/// The CPU provider that matches what a variant's shader computes for `tir`: the table's twin
/// for `lut32`/`lut16`, else the table-free modes of `model::tir`.
pub fn provider(tir: Tir, table: &TirTable) -> Box<dyn crate::model::Tir + '_> {
    use crate::model::tir::{AnalyticTir, ConstantTir, FitTir, CONSTANT_FRACTION};
    match tir {
        Tir::None => Box::new(crate::model::NoTir),
        Tir::Constant => Box::new(ConstantTir(CONSTANT_FRACTION)),
        Tir::Analytic => Box::new(AnalyticTir),
        Tir::Lut32 => Box::new(TableTir { table, half: false }),
        Tir::Lut16 => Box::new(TableTir { table, half: true }),
        Tir::Fit => Box::new(FitTir(crate::model::tir_fit::COEFFICIENTS)),
    }
}

/// How far an estimator is from the table over its grid.
#[derive(Clone, Copy, Debug)]
pub struct ErrorStats {
    pub mse: f64,
    pub mean_abs: f64,
    pub max_abs: f64,
    /// (μ, α, η) of the largest error.
    pub worst_at: (f64, f64, f64),
    pub points: usize,
}

impl ErrorStats {
    /// The statistics of `estimate` against reference values: `points` yields each point's
    /// (μ, α, η) and its reference value. `None` without points.
    pub fn of(
        estimate: &dyn crate::model::Tir,
        points: impl IntoIterator<Item = ((f64, f64, f64), f64)>,
    ) -> Option<Self> {
        let (mut sum2, mut sum, mut max, mut worst, mut count) =
            (0.0, 0.0, 0.0, (0.0, 0.0, 0.0), 0);
        for ((mu, alpha, eta), reference) in points {
            let e = (estimate.tir(mu, alpha, eta) - reference).abs();
            sum2 += e * e;
            sum += e;
            count += 1;
            if e > max {
                max = e;
                worst = (mu, alpha, eta);
            }
        }
        (count > 0).then(|| Self {
            mse: sum2 / count as f64,
            mean_abs: sum / count as f64,
            max_abs: max,
            worst_at: worst,
            points: count,
        })
    }
}

/// `estimate` against the table at every grid vertex with 0 < η < 1 (the domain the model
/// queries: a relative IOR is positive, and η = 1 has no TIR). The table needs at least 3
/// texels per axis, for one η slice inside (0, 1).
pub fn error_against(table: &TirTable, estimate: &dyn crate::model::Tir) -> ErrorStats {
    let n = table.size;
    let vertices =
        (1..n - 1).flat_map(|k| (0..n).flat_map(move |j| (0..n).map(move |i| (i, j, k))));
    ErrorStats::of(
        estimate,
        vertices.map(|(i, j, k)| (table.coordinates(i, j, k), f64::from(table.texel(i, j, k)))),
    )
    .expect("a studied TIR table has an η slice inside (0, 1)")
}

/// The table in the reference's file format (ALGORITHMS.md §6): three int32 sizes, three
/// (f32 min, f32 max) pairs, then the f32 values with μ fastest.
pub fn reference_file_bytes(table: &TirTable) -> Vec<u8> {
    let mut out = Vec::with_capacity(36 + table.texels.len() * 4);
    for _ in 0..3 {
        out.extend((table.size as i32).to_le_bytes());
    }
    for _ in 0..3 {
        out.extend(0.0f32.to_le_bytes());
        out.extend(1.0f32.to_le_bytes());
    }
    for v in &table.texels {
        out.extend(v.to_le_bytes());
    }
    out
}
