//! The directional albedo E(μ, α) of a white GGX lobe, per G2 form: what the analytic lights
//! divide each lobe by so that its light response integrates to the lobe's weight
//! (`model::light`). Texel (i, j) of the n×n R32F image holds E at μ = i/(n − 1) and
//! √α = j/(n − 1) (vertex-centred: the range ends α = 1 and μ = 1 are texels, not clamped to
//! the nearest centre, which cost a rough lobe 0.8 % of its light), read in `lib/light.glsl`
//! at (x(n − 1) + ½)/n. Column 0 holds μ = [`MIN_MU`], the shaders' floor of the view cosine.
//!
//! Built on the CPU with the oracle's own quadrature (`model::light::lobe_albedo`, ~1e-5),
//! not on the GPU with the split-sum kernel's visible-normal samples: the A + B of that table
//! is off by up to ~4e-3 at small α, where a few samples stand for the lobe's tail beyond the
//! horizon — more than the lights' furnace allows (1e-3). Cached on disk like the other tables.

use crate::error::Result;
use crate::gpu::Gpu;
use crate::model::light;
use crate::shader::interface::LOBE_ALBEDO_SIZE;
use crate::variant::G2;
use crate::vk::{upload_image, Format, Image, ImageDesc, ImageState, ImageView};

use super::{filter_axis, Texels};

/// Texels per side ([`LOBE_ALBEDO_SIZE`], which the shaders read too).
pub const SIZE: u32 = LOBE_ALBEDO_SIZE;

/// Bumped when the quadrature or the layout changes, so cached tables are rebuilt.
const VERSION: u32 = 2;

/// The smallest view cosine tabulated: the shaders clamp n·v to it.
pub const MIN_MU: f64 = 1e-4;

pub struct LobeAlbedoTable {
    /// R32_SFLOAT, in `FragmentRead` state.
    pub image: Image,
    pub view: ImageView,
    pub size: u32,
    /// Row-major, row = roughness.
    pub texels: Vec<f32>,
}

impl LobeAlbedoTable {
    /// From the disk cache when there, else computed (a few seconds) and stored.
    pub fn load_or_build(gpu: &Gpu, g2: G2) -> Result<Self> {
        let key = crate::cache::Key {
            kind: "lobe-albedo",
            params: vec![SIZE, crate::variant::Axis::code(g2)],
            shader_hash: u64::from(VERSION),
        };
        let dir = crate::cache::tables_dir();
        let count = (SIZE * SIZE) as usize;
        let (texels, _) =
            crate::cache::load_or_build(dir.as_deref(), &key, count, || Ok(compute(g2, SIZE)))?;
        let image = Image::new(
            &gpu.device,
            ImageDesc::new_2d(Format::R32_SFLOAT, SIZE, SIZE),
            "lobe albedo table",
        )?;
        upload_image(
            &gpu.device,
            &image,
            bytemuck::cast_slice(&texels),
            ImageState::FragmentRead,
        )?;
        let view = image.view("lobe albedo table")?;
        Ok(Self {
            image,
            view,
            size: SIZE,
            texels,
        })
    }

    /// The CPU twin of the shaders' lookup: bilinear over the vertex-centred texels.
    pub fn sample(&self, mu: f64, alpha: f64) -> f64 {
        let n = self.size as usize;
        let texel = |i: usize, j: usize| f64::from(self.texels[j * n + i]);
        let (i, fx) = filter_axis(mu, n, Texels::Vertices);
        let (j, fy) = filter_axis(alpha.clamp(0.0, 1.0).sqrt(), n, Texels::Vertices);
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let bottom = lerp(texel(i, j), texel(i + 1, j), fx);
        let top = lerp(texel(i, j + 1), texel(i + 1, j + 1), fx);
        lerp(bottom, top, fy)
    }
}

/// The texels, rows split between the machine's cores.
fn compute(g2: G2, size: u32) -> Vec<f32> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as u32;
    let rows: Vec<Vec<f32>> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..cores)
            .map(|worker| {
                scope.spawn(move || {
                    (worker..size)
                        .step_by(cores as usize)
                        .map(|j| {
                            let r = f64::from(j) / f64::from(size - 1);
                            (0..size)
                                .map(|i| {
                                    let mu = (f64::from(i) / f64::from(size - 1)).max(MIN_MU);
                                    light::lobe_albedo(g2, mu, r * r) as f32
                                })
                                .collect::<Vec<f32>>()
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        let mut rows = vec![Vec::new(); size as usize];
        for (worker, handle) in workers.into_iter().enumerate() {
            let done = handle.join().expect("a lobe-albedo worker panicked");
            for (k, row) in done.into_iter().enumerate() {
                rows[worker + k * cores as usize] = row;
            }
        }
        rows
    });
    rows.concat()
}
