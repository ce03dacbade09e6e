//! The white furnace: a material under a uniform white environment reflects exactly its
//! directional albedo (and, for a stack that transmits, shows its transmittance from behind),
//! so the image measures the energy the shading path returns per view angle.
//!
//! The GPU side renders the sphere under a constant environment of radiance 1 and averages the
//! pixels by the cosine between normal and view (computed on the CPU from the camera and the
//! sphere); the CPU side evaluates the oracle's total reflectance at the bins' mean cosines.

use glam::Vec3;

use crate::error::Result;
use crate::gpu::Gpu;
use crate::imageio::HdrImage;
use crate::model::oracle;
use crate::model::{ends_transmissive, LayerParams};
use crate::stats::MinMeanMax;
use crate::tables::environment::EnvDesc;
use crate::variant::{Model, VariantKey};

use super::renderer::Renderer;

/// Reflected energy averaged over the view cosines of one bin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FurnaceBin {
    /// Mean view cosine of the bin's samples.
    pub cos_theta: f64,
    pub energy: [f64; 3],
    /// Pixels (GPU) or evaluations (CPU) that went into the bin.
    pub samples: usize,
}

/// Minimum, mean and maximum over all bins and channels (NaN for no bins).
pub fn summary(bins: &[FurnaceBin]) -> (f64, f64, f64) {
    MinMeanMax::of(bins.iter().flat_map(|b| b.energy))
        .map_or((f64::NAN, f64::NAN, f64::NAN), |s| (s.min, s.mean, s.max))
}

/// Renders `layers` under a white environment at `size`² pixels and bins the sphere's
/// radiance by n·v into `bin_count` bins (empty bins are dropped).
pub fn gpu(
    gpu: &Gpu,
    variant: VariantKey,
    layers: &[LayerParams],
    size: u32,
    bin_count: usize,
) -> Result<Vec<FurnaceBin>> {
    let white = HdrImage {
        width: 64,
        height: 32,
        pixels: vec![[1.0; 4]; 64 * 32],
    };
    let desc = EnvDesc {
        face_size: 32,
        mip_count: 6,
        samples: 16,
    };
    let mut renderer = Renderer::new(gpu, &white, desc)?;
    let pass = renderer.prepare_uniform(variant, layers)?;
    let frame = renderer.render(&pass, layers, size, size)?;

    let camera = renderer.camera;
    // Per bin: radiance sums, cosine sum, pixel count.
    let mut sums = vec![([0.0f64; 3], 0.0f64, 0usize); bin_count];
    for y in 0..size {
        for x in 0..size {
            let dir = camera.ray(x, y, size, size);
            let Some(cos_theta) = sphere_cosine(camera.eye, dir) else {
                continue;
            };
            let bin = ((cos_theta * bin_count as f64) as usize).min(bin_count - 1);
            let p = frame.pixels[(y * size + x) as usize];
            for (sum, c) in sums[bin].0.iter_mut().zip(p) {
                *sum += f64::from(c);
            }
            sums[bin].1 += cos_theta;
            sums[bin].2 += 1;
        }
    }
    Ok(sums
        .iter()
        .filter(|(_, _, n)| *n > 0)
        .map(|(sum, cos_sum, n)| FurnaceBin {
            cos_theta: cos_sum / *n as f64,
            energy: sum.map(|s| s / *n as f64),
            samples: *n,
        })
        .collect())
}

/// n·v where the ray hits the unit sphere at the origin, for rays that stay clear of the
/// silhouette (whose pixels mix sphere and background).
pub fn sphere_cosine(eye: Vec3, dir: Vec3) -> Option<f64> {
    let (eye, dir) = (eye.as_dvec3(), dir.as_dvec3());
    let b = eye.dot(dir);
    let closest = eye - b * dir;
    if closest.length() > 0.98 {
        return None;
    }
    let t = -b - (1.0 - closest.length_squared()).sqrt();
    let normal = (eye + t * dir).normalize();
    Some(normal.dot(-dir).clamp(0.0, 1.0))
}

/// The CPU side: the oracle's total reflectance ([`oracle::evaluate`]) for `variant` at each
/// view cosine, and its transmittance where the stack transmits (the forward pass shows what
/// a thin slab transmits from behind, where the environment is white too). The `ggx` baseline
/// shades the top layer alone with one GGX lobe, so its reference is that layer through the
/// 2-flux model.
pub fn cpu(variant: VariantKey, layers: &[LayerParams], cosines: &[f64]) -> Vec<FurnaceBin> {
    let transmits = ends_transmissive(layers);
    let (variant, layers) = match variant.model {
        Model::Ggx => (
            VariantKey {
                model: Model::Tm2,
                ..variant
            },
            &layers[..1],
        ),
        _ => (variant, layers),
    };
    cosines
        .iter()
        .map(|&cos_theta| {
            let e = oracle::evaluate(variant, layers, cos_theta);
            let t = if transmits { e.transmittance } else { [0.0; 3] };
            FurnaceBin {
                cos_theta,
                energy: std::array::from_fn(|c| e.reflectance[c] + t[c]),
                samples: 1,
            }
        })
        .collect()
}
