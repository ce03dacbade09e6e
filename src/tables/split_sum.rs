//! The 2-channel split-sum table of Karis 2013 (DESIGN.md's `fgd-karis`).
//!
//! Texel (i, j) of an n×n table holds (A, B) for view cosine μ = (i + ½)/n and perceptual
//! roughness r = √α = (j + ½)/n, such that the directional albedo of a GGX lobe with Schlick
//! Fresnel is F0·A + B. Sampled with normalised coordinates (μ, √α) and a linear filter, the
//! texel centres land exactly on those values. The GPU estimate uses Hammersley points with
//! visible-normal sampling; [`cpu_reference`] integrates the same quantity in f64.

use half::f16;

use super::{filter_axis, Texels};
use crate::error::Result;
use crate::gpu::{ComputeKernel, Gpu};
use crate::model::microfacet;
use crate::shader::kernel::{KernelInterface, KernelSpec, LOCAL_SIZE_2D};
use crate::variant::G2;
use crate::vk::{
    submit_and_wait, upload_image, Access, BindingKind, Buffer, BufferDesc, DescriptorSet, Format,
    Image, ImageDesc, ImageState, ImageView, Resource,
};

pub const DEFAULT_SIZE: u32 = 64;
/// 4096 Hammersley samples per texel put the estimate within ~1e-3 of the integral.
pub const DEFAULT_SAMPLES: u32 = 4096;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    size: u32,
    sample_count: u32,
}

/// `split_sum.comp.glsl`: one invocation per texel.
pub const KERNEL: KernelInterface = KernelInterface {
    entry: "split_sum.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[BindingKind::StorageBuffer],
    push: crate::push_block!(Push { size, sample_count }),
    local_size: [LOCAL_SIZE_2D, LOCAL_SIZE_2D],
};

pub struct SplitSumTable {
    /// R16G16_SFLOAT, in `FragmentRead` state.
    pub image: Image,
    pub view: ImageView,
    pub size: u32,
    /// The f32 values the GPU computed, row-major (row = roughness).
    pub texels: Vec<[f32; 2]>,
}

impl SplitSumTable {
    /// The table from the disk cache ([`super::cache`]) when a valid one exists, else built and
    /// stored there.
    pub fn load_or_build(gpu: &Gpu, g2: G2, size: u32, samples: u32) -> Result<Self> {
        let key = crate::cache::Key {
            kind: "split-sum",
            params: vec![size, samples, crate::variant::Axis::code(g2)],
            shader_hash: crate::shader::entry_hash("split_sum.comp.glsl"),
        };
        let dir = crate::cache::tables_dir();
        let count = (size * size * 2) as usize;
        let (values, _) = crate::cache::load_or_build(dir.as_deref(), &key, count, || {
            let table = Self::build(gpu, g2, size, samples)?;
            Ok(table.texels.iter().flatten().copied().collect())
        })?;
        let texels = values.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        Self::from_texels(gpu, size, texels)
    }

    pub fn build(gpu: &Gpu, g2: G2, size: u32, samples: u32) -> Result<Self> {
        let kernel = ComputeKernel::build(gpu, &KERNEL, &[], &[], KernelSpec::for_g2(g2))?;
        let device = &gpu.device;
        let buffer = Buffer::new(
            device,
            BufferDesc::readback(u64::from(size * size) * 8),
            "split-sum texels",
        )?;
        let mut set = DescriptorSet::new(device, &kernel.set_layout, "split-sum")?;
        set.write(0, Resource::Buffer(&buffer));
        submit_and_wait(device, "split-sum table", |rec| {
            rec.begin_label("split-sum table");
            kernel.record_dispatch(
                rec,
                &[&set],
                &Push {
                    size,
                    sample_count: samples,
                },
                [size, size, 1],
            );
            rec.barrier(Access::ComputeWrite, Access::HostRead);
            rec.end_label();
            Ok(())
        })?;
        let texels: Vec<[f32; 2]> = buffer.read();
        Self::from_texels(gpu, size, texels)
    }

    /// Uploads computed texels (row-major, row = roughness) as the half-float image.
    pub fn from_texels(gpu: &Gpu, size: u32, texels: Vec<[f32; 2]>) -> Result<Self> {
        let device = &gpu.device;
        let halves: Vec<f16> = texels.iter().flatten().map(|&v| f16::from_f32(v)).collect();
        let image = Image::new(
            device,
            ImageDesc::new_2d(Format::R16G16_SFLOAT, size, size),
            "split-sum table",
        )?;
        upload_image(
            device,
            &image,
            bytemuck::cast_slice(&halves),
            ImageState::FragmentRead,
        )?;
        let view = image.view("split-sum table")?;
        Ok(Self {
            image,
            view,
            size,
            texels,
        })
    }

    /// The texel at view-cosine index `i` and roughness index `j`.
    pub fn texel(&self, i: u32, j: u32) -> [f32; 2] {
        self.texels[(j * self.size + i) as usize]
    }

    /// (μ, α) at the centre of texel (i, j).
    pub fn coordinates(&self, i: u32, j: u32) -> (f64, f64) {
        let mu = (f64::from(i) + 0.5) / f64::from(self.size);
        let r = (f64::from(j) + 0.5) / f64::from(self.size);
        (mu, r * r)
    }
}

/// The CPU twin of the GPU lookup `texture(split_sum, vec2(μ, √α))`: bilinear over the same
/// half-float texels, texel centres at (i + ½)/n, clamped at the edges.
impl SplitSumTable {
    pub fn sample(&self, mu: f64, alpha: f64) -> [f64; 2] {
        let n = self.size as usize;
        let texel = |i: usize, j: usize| {
            let t = self.texels[j * n + i];
            [
                f64::from(f16::from_f32(t[0]).to_f32()),
                f64::from(f16::from_f32(t[1]).to_f32()),
            ]
        };
        let (i, fx) = filter_axis(mu, n, Texels::Centred);
        let (j, fy) = filter_axis(alpha.clamp(0.0, 1.0).sqrt(), n, Texels::Centred);
        let lerp =
            |a: [f64; 2], b: [f64; 2], t: f64| [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
        let bottom = lerp(texel(i, j), texel(i + 1, j), fx);
        let top = lerp(texel(i, j + 1), texel(i + 1, j + 1), fx);
        lerp(bottom, top, fy)
    }
}

/// `fgd=karis` as the GPU computes it: F0(η, κ)·A + B from the table.
impl crate::model::Fgd for SplitSumTable {
    fn fgd(&self, mu: f64, alpha: f64, eta: f64, kappa: f64) -> f64 {
        let [a, b] = self.sample(mu, alpha);
        crate::model::fresnel::f0(eta, kappa) * a + b
    }
}

/// (A, B) at view cosine `mu` and GGX `alpha` by an `n`×`n` stratified midpoint rule over the
/// visible-normal distribution, in f64: the oracle for the GPU table.
pub fn cpu_reference(mu: f64, alpha: f64, g2: G2, n: u32) -> [f64; 2] {
    let g1_v = microfacet::masking_g1(g2, mu, alpha);
    let mut sum = [0.0f64; 2];
    microfacet::for_each_vndf_sample(mu, alpha, n, |v, h, l| {
        let w = microfacet::masking_shadowing(g2, mu, l.z, alpha) / g1_v;
        let fc = (1.0 - v.dot(h).clamp(0.0, 1.0)).powi(5);
        sum[0] += (1.0 - fc) * w;
        sum[1] += fc * w;
    });
    let count = f64::from(n * n);
    [sum[0] / count, sum[1] / count]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ALGORITHMS.md §12.4, height-correlated Smith, at perceptual roughness r (α = r²).
    #[test]
    fn cpu_reference_matches_published_values() {
        let cases = [
            (0.25, 0.5, [0.9557, 0.0326]),
            (0.25, 0.1, [0.5044, 0.3916]),
            (0.5, 1.0, [0.9158, 0.0]),
            (0.5, 0.5, [0.8349, 0.0223]),
            (0.5, 0.1, [0.7527, 0.1397]),
            (1.0, 0.5, [0.4477, 0.0030]),
            (1.0, 0.1, [0.7364, 0.0239]),
        ];
        for (r, mu, expected) in cases {
            let got = cpu_reference(mu, r * r, G2::HeightCorrelated, 400);
            for c in 0..2 {
                assert!(
                    (got[c] - expected[c]).abs() < 1.5e-3,
                    "r {r} mu {mu}: {got:?} vs {expected:?}"
                );
            }
        }
    }

    #[test]
    fn separable_smith_matches_published_values() {
        let got = cpu_reference(0.5, 0.25, G2::Smith, 400);
        assert!(
            (got[0] - 0.8329).abs() < 1.5e-3 && (got[1] - 0.0222).abs() < 1.5e-3,
            "{got:?}"
        );
    }
}
