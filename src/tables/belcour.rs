//! The preintegrable Fresnel decomposition of Belcour, Bati & Barla 2020 (ALGORITHMS.md §7):
//! F(μ; η, κ) ≈ c0 + c1·b1(μ) + c2·b2(μ) + c3·b3(μ), so that FGD ≈ Σ c_k L_k(μ, α) with
//! L_k the split-sum integrals of the basis functions (`fgd_belcour.comp.glsl`).
//!
//! The basis is data-driven. lamina fits its own, the way the paper describes (§7.1), on a
//! deterministic training set: [`TRAINING_DIELECTRICS`] dielectrics with η uniform on
//! [1.01, 3] and, for the 1 % of conductors, Gulbrandsen's edge-tint-1 conductors of
//! reflectivity 0.5, 0.7 and 0.9. b1 is the first right-singular vector of the curves
//! (F − F0)/(1 − F0); b2 and b3 the first two of the residual (F − F0)/(1 − F0) − b1; each is
//! normalised to max |·| = 1 with that extreme positive. Singular vectors come from power
//! iteration on XᵀX. The projection interpolates F at μ = 1, [`CT1`] and [`CT2`] (the paper's
//! nodes, kept so the shader's constants do not depend on the fit).

use std::path::Path;

use crate::cache;
use crate::error::{Error, Result};
use crate::gpu::{ComputeKernel, Gpu};
use crate::model::{fresnel, microfacet};
use crate::shader::kernel::{KernelInterface, KernelSpec, LOCAL_SIZE_2D};
use crate::variant::G2;
use crate::vk::{
    submit_and_wait, Access, BindingKind, Buffer, BufferDesc, BufferUsageFlags, DescriptorSet,
    Resource,
};

use super::{filter_axis, Texels};

/// Basis samples, uniform in μ ∈ [0, 1] (as the paper's notebook).
pub const POINTS: usize = 1000;
/// The projection's nodes: where b2 peaks and b3 bottoms out in the paper's basis.
pub const CT1: f64 = crate::shader::interface::BELCOUR_CT1;
pub const CT2: f64 = crate::shader::interface::BELCOUR_CT2;
/// Dielectric curves of the training set (99 % of it).
pub const TRAINING_DIELECTRICS: usize = 297;
/// Gulbrandsen reflectivities of the conductor curves (edge tint 1).
const TRAINING_CONDUCTORS: [f64; 3] = [0.5, 0.7, 0.9];

#[derive(Clone)]
pub struct Basis {
    /// b1, b2, b3 at μ = i/(POINTS − 1).
    pub values: [Vec<f64>; 3],
    /// b1 at (CT1, CT2).
    pub b1_at_nodes: [f64; 2],
    /// Inverse of [[b2(ct1), b2(ct2)], [b3(ct1), b3(ct2)]]: [c2, c3] = [ΔF(ct1), ΔF(ct2)]·A.
    pub a: [[f64; 2]; 2],
}

impl Basis {
    /// Fits the basis on the training set (a few milliseconds in release builds).
    pub fn fit() -> Self {
        let mu: Vec<f64> = (0..POINTS)
            .map(|i| i as f64 / (POINTS - 1) as f64)
            .collect();
        let mut curves: Vec<Vec<f64>> = (0..TRAINING_DIELECTRICS)
            .map(|m| {
                let eta = 1.01 + (3.0 - 1.01) * m as f64 / (TRAINING_DIELECTRICS - 1) as f64;
                normalised_curve(&mu, eta, 0.0)
            })
            .collect();
        for r in TRAINING_CONDUCTORS {
            let (eta, kappa) = gulbrandsen_edge_tint_one(r);
            curves.push(normalised_curve(&mu, eta, kappa));
        }
        let b1 = normalise_max(top_singular_vectors(&curves, 1).remove(0));
        let residual: Vec<Vec<f64>> = curves
            .iter()
            .map(|c| c.iter().zip(&b1).map(|(x, b)| x - b).collect())
            .collect();
        let mut rest = top_singular_vectors(&residual, 2).into_iter();
        let b2 = normalise_max(rest.next().expect("two vectors"));
        let b3 = normalise_max(rest.next().expect("two vectors"));
        let mut basis = Self {
            values: [b1, b2, b3],
            b1_at_nodes: [0.0; 2],
            a: [[0.0; 2]; 2],
        };
        basis.b1_at_nodes = [basis.at(1, CT1), basis.at(1, CT2)];
        let (p, q, r, s) = (
            basis.at(2, CT1),
            basis.at(2, CT2),
            basis.at(3, CT1),
            basis.at(3, CT2),
        );
        let det = p * s - q * r;
        basis.a = [[s / det, -q / det], [-r / det, p / det]];
        basis
    }

    /// b_k(μ) for k = 1, 2, 3, linear between samples (b_0 = 1).
    pub fn at(&self, k: usize, mu: f64) -> f64 {
        if k == 0 {
            return 1.0;
        }
        let v = &self.values[k - 1];
        let f = mu.clamp(0.0, 1.0) * (POINTS - 1) as f64;
        let i = (f as usize).min(POINTS - 2);
        v[i] + (v[i + 1] - v[i]) * (f - i as f64)
    }

    /// The coefficients c0..c3 of F(·; η, κ) (the paper's projection).
    pub fn coefficients(&self, eta: f64, kappa: f64) -> [f64; 4] {
        let c0 = fresnel::conductor(1.0, eta, kappa);
        let c1 = 1.0 - c0;
        let d = [
            fresnel::conductor(CT1, eta, kappa) - c0 - c1 * self.b1_at_nodes[0],
            fresnel::conductor(CT2, eta, kappa) - c0 - c1 * self.b1_at_nodes[1],
        ];
        let c2 = d[0] * self.a[0][0] + d[1] * self.a[1][0];
        let c3 = d[0] * self.a[0][1] + d[1] * self.a[1][1];
        [c0, c1, c2, c3]
    }

    /// The reconstruction Σ c_k b_k(μ) of F itself.
    pub fn fresnel(&self, mu: f64, eta: f64, kappa: f64) -> f64 {
        let c = self.coefficients(eta, kappa);
        (0..4).map(|k| c[k] * self.at(k, mu)).sum()
    }

    /// FGD ≈ Σ c_k L_k from the four integrals L_k of one texel.
    pub fn reconstruct(&self, l: [f64; 4], eta: f64, kappa: f64) -> f64 {
        let c = self.coefficients(eta, kappa);
        (0..4).map(|k| c[k] * l[k]).sum()
    }

    /// The integrals with the projection folded in, so that FGD = F(1)·P0 + P1 + F(CT1)·P2 +
    /// F(CT2)·P3 (what the shader evaluates; algebraically equal to [`Basis::reconstruct`]).
    pub fn fold(&self, l: [f64; 4]) -> [f64; 4] {
        let m = [
            self.a[0][0] * l[2] + self.a[0][1] * l[3],
            self.a[1][0] * l[2] + self.a[1][1] * l[3],
        ];
        let [b0, b1] = self.b1_at_nodes;
        [
            l[0] - l[1] - (1.0 - b0) * m[0] - (1.0 - b1) * m[1],
            l[1] - b0 * m[0] - b1 * m[1],
            m[0],
            m[1],
        ]
    }

    /// b1, b2, b3 as f32, one after the other (the build shader's basis buffer).
    pub fn to_f32(&self) -> Vec<f32> {
        self.values.iter().flatten().map(|&v| v as f32).collect()
    }
}

/// (F − F0)/(1 − F0) over `mu`.
fn normalised_curve(mu: &[f64], eta: f64, kappa: f64) -> Vec<f64> {
    let f0 = fresnel::conductor(1.0, eta, kappa);
    mu.iter()
        .map(|&m| (fresnel::conductor(m, eta, kappa) - f0) / (1.0 - f0))
        .collect()
}

/// Gulbrandsen 2014 with edge tint g = 1: the complex IOR of normal reflectivity r.
fn gulbrandsen_edge_tint_one(r: f64) -> (f64, f64) {
    let n = (1.0 - r) / (1.0 + r);
    let k2 = (r * (n + 1.0).powi(2) - (n - 1.0).powi(2)) / (1.0 - r);
    (n, k2.max(0.0).sqrt())
}

/// The first `count` right-singular vectors of the matrix whose rows are `rows`, by power
/// iteration on XᵀX with deflation (Gram–Schmidt against the vectors found before).
fn top_singular_vectors(rows: &[Vec<f64>], count: usize) -> Vec<Vec<f64>> {
    let width = rows[0].len();
    let mut found: Vec<Vec<f64>> = Vec::new();
    for _ in 0..count {
        let mut v: Vec<f64> = (0..width).map(|i| 1.0 + (i % 7) as f64 * 0.01).collect();
        for _ in 0..2000 {
            let xv: Vec<f64> = rows.iter().map(|r| dot(r, &v)).collect();
            let mut next = vec![0.0; width];
            for (r, s) in rows.iter().zip(&xv) {
                for (n, x) in next.iter_mut().zip(r) {
                    *n += s * x;
                }
            }
            for f in &found {
                let p = dot(&next, f);
                for (n, x) in next.iter_mut().zip(f) {
                    *n -= p * x;
                }
            }
            let norm = dot(&next, &next).sqrt();
            next.iter_mut().for_each(|x| *x /= norm);
            let change: f64 = next.iter().zip(&v).map(|(a, b)| (a - b).abs()).sum();
            v = next;
            if change < 1e-13 {
                break;
            }
        }
        found.push(v);
    }
    found
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Scales `v` so its largest magnitude is +1.
fn normalise_max(v: Vec<f64>) -> Vec<f64> {
    let extreme = v
        .iter()
        .copied()
        .fold(0.0f64, |m, x| if x.abs() > m.abs() { x } else { m });
    v.into_iter().map(|x| x / extreme).collect()
}

/// The Belcour table: the four integrals L_k per texel (`raw`) and the basis they came from.
pub struct BelcourTable {
    pub size: u32,
    pub samples: u32,
    pub basis: Basis,
    /// L0..L3 at μ = (i + ½)/n, √α = (j + ½)/n, row-major (row = √α).
    pub raw: Vec<[f32; 4]>,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BelcourPush {
    size: u32,
    sample_count: u32,
    basis_points: u32,
}

/// `fgd_belcour.comp.glsl`: one invocation per (μ, α) texel.
pub const BELCOUR_KERNEL: KernelInterface = KernelInterface {
    entry: "fgd_belcour.comp.glsl",
    shades: false,
    scene: false,
    bindings: &[BindingKind::StorageBuffer, BindingKind::StorageBuffer],
    push: crate::push_block!(BelcourPush {
        size,
        sample_count,
        basis_points
    }),
    local_size: [LOCAL_SIZE_2D, LOCAL_SIZE_2D],
};

impl BelcourTable {
    /// From the disk cache when valid, else built on the GPU and stored.
    pub fn load_or_build(
        gpu: &Gpu,
        g2: G2,
        size: u32,
        samples: u32,
        cache_dir: Option<&Path>,
    ) -> Result<(Self, bool)> {
        let key = cache::Key {
            kind: "fgd-belcour",
            params: vec![size, samples, crate::variant::Axis::code(g2)],
            shader_hash: crate::shader::entry_hash("fgd_belcour.comp.glsl"),
        };
        let basis = Basis::fit();
        let count = (size * size * 4) as usize;
        let (values, cached) = cache::load_or_build(cache_dir, &key, count, || {
            let table = Self::build(gpu, g2, size, samples, basis.clone())?;
            Ok(table.raw.iter().flatten().copied().collect())
        })?;
        let raw = values
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect();
        Ok((
            Self {
                size,
                samples,
                basis,
                raw,
            },
            cached,
        ))
    }

    pub fn build(gpu: &Gpu, g2: G2, size: u32, samples: u32, basis: Basis) -> Result<Self> {
        if !(2..=1024).contains(&size) || samples == 0 {
            return Err(Error::Unsupported(format!(
                "Belcour table of {size} texels and {samples} samples: allowed 2..=1024 \
                 texels and at least 1 sample"
            )));
        }
        let kernel = ComputeKernel::build(gpu, &BELCOUR_KERNEL, &[], &[], KernelSpec::for_g2(g2))?;
        let device = &gpu.device;
        let out = Buffer::new(
            device,
            BufferDesc::readback(u64::from(size * size) * 16),
            "belcour texels",
        )?;
        let basis_buffer = Buffer::with_data(
            device,
            BufferUsageFlags::STORAGE_BUFFER,
            &basis.to_f32(),
            "belcour basis",
        )?;
        let mut set = DescriptorSet::new(device, &kernel.set_layout, "belcour table")?;
        set.write(0, Resource::Buffer(&out))
            .write(1, Resource::Buffer(&basis_buffer));
        submit_and_wait(device, "belcour table", |rec| {
            kernel.record_dispatch(
                rec,
                &[&set],
                &BelcourPush {
                    size,
                    sample_count: samples,
                    basis_points: super::belcour::POINTS as u32,
                },
                [size, size, 1],
            );
            rec.barrier(Access::ComputeWrite, Access::HostRead);
            Ok(())
        })?;
        Ok(Self {
            size,
            samples,
            basis,
            raw: out.read(),
        })
    }

    /// (μ, α) of texel (i, j).
    pub fn coordinates(&self, i: u32, j: u32) -> (f64, f64) {
        let n = f64::from(self.size);
        let r = (f64::from(j) + 0.5) / n;
        ((f64::from(i) + 0.5) / n, r * r)
    }

    /// The CPU twin of the shader's lookup of the raw integrals: bilinear at (μ, √α) over the
    /// texel centres, clamped at the edges.
    pub fn sample(&self, mu: f64, alpha: f64) -> [f64; 4] {
        let n = self.size as usize;
        let (i, fx) = filter_axis(mu, n, Texels::Centred);
        let (j, fy) = filter_axis(alpha.max(0.0).sqrt(), n, Texels::Centred);
        let texel = |i: usize, j: usize| self.raw[j * n + i].map(f64::from);
        let lerp = |a: [f64; 4], b: [f64; 4], t: f64| {
            let mut out = a;
            for k in 0..4 {
                out[k] += (b[k] - a[k]) * t;
            }
            out
        };
        lerp(
            lerp(texel(i, j), texel(i + 1, j), fx),
            lerp(texel(i, j + 1), texel(i + 1, j + 1), fx),
            fy,
        )
    }

    /// The texels with the projection folded in (what the shader samples).
    pub fn folded(&self) -> Vec<[f32; 4]> {
        self.raw
            .iter()
            .map(|l| {
                let p = self.basis.fold(l.map(f64::from));
                p.map(|v| v as f32)
            })
            .collect()
    }
}

/// L_k(μ, α) for k = 0..3 in f64 by an `n`×`n` midpoint rule over the visible-normal
/// sampler's uniform variables: the oracle of the Belcour table.
pub fn belcour_reference(basis: &Basis, mu: f64, alpha: f64, g2: G2, n: u32) -> [f64; 4] {
    let g1_v = microfacet::masking_g1(g2, mu, alpha);
    let mut sum = [0.0f64; 4];
    microfacet::for_each_vndf_sample(mu, alpha, n, |v, h, l| {
        let w = microfacet::masking_shadowing(g2, mu, l.z, alpha) / g1_v;
        let c = v.dot(h);
        for (k, s) in sum.iter_mut().enumerate() {
            *s += w * basis.at(k, c);
        }
    });
    sum.map(|s| s / f64::from(n * n))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fit lands near the paper's basis (ALGORITHMS.md §7.1 samples): same shapes, a few
    /// hundredths apart where the training sets differ.
    #[test]
    fn fitted_basis_resembles_the_papers() {
        let basis = Basis::fit();
        let published = [
            (0.1, [0.5088, 0.9770, 0.8370]),
            (0.3, [0.1551, 0.7021, -0.4562]),
            (0.5, [0.0484, 0.3374, -0.6085]),
            (0.7, [0.0122, 0.1211, -0.3236]),
        ];
        for (mu, want) in published {
            for (k, want) in want.iter().enumerate() {
                let got = basis.at(k + 1, mu);
                assert!(
                    (got - want).abs() < 0.06,
                    "b{}({mu}) = {got:.4}, paper {want}",
                    k + 1
                );
            }
        }
        assert_eq!(basis.at(1, 0.0), 1.0);
        assert!(basis.at(1, 1.0).abs() < 1e-9 && basis.at(2, 1.0).abs() < 1e-9);
    }

    /// The reconstruction interpolates F at the three nodes and fits it closely between them
    /// (ALGORITHMS.md §7.3: glass 1.5 within 0.004, gold within 0.0035).
    #[test]
    fn projection_reconstructs_fresnel() {
        let basis = Basis::fit();
        let gold = [(0.143245, 3.98479), (0.377423, 2.3847), (1.43919, 1.60434)];
        for (eta, kappa) in [(1.5, 0.0), (1.33, 0.0)].into_iter().chain(gold) {
            for node in [1.0, CT1, CT2] {
                let err =
                    (basis.fresnel(node, eta, kappa) - fresnel::conductor(node, eta, kappa)).abs();
                assert!(err < 1e-9, "η {eta} κ {kappa} at node {node}: {err}");
            }
            let worst = (0..=200)
                .map(|i| {
                    let mu = f64::from(i) / 200.0;
                    (basis.fresnel(mu, eta, kappa) - fresnel::conductor(mu, eta, kappa)).abs()
                })
                .fold(0.0, f64::max);
            assert!(worst < 0.01, "η {eta} κ {kappa}: max |ΔF| {worst}");
        }
    }

    #[test]
    fn folded_table_equals_the_projection() {
        let basis = Basis::fit();
        let l = [0.7, 0.05, 0.2, -0.3];
        for (eta, kappa) in [(1.5, 0.0), (0.2, 3.9), (2.4, 0.0)] {
            let p = basis.fold(l);
            let folded = fresnel::conductor(1.0, eta, kappa) * p[0]
                + p[1]
                + fresnel::conductor(CT1, eta, kappa) * p[2]
                + fresnel::conductor(CT2, eta, kappa) * p[3];
            assert!((folded - basis.reconstruct(l, eta, kappa)).abs() < 1e-12);
        }
    }
}
