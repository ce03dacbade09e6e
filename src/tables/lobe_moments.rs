//! Where a GGX lobe looks and how wide it is: the table the matched cube's lookups read
//! (`tables::environment`, prefiltered with the lobe's own weights at a normal view). `ibl=matched`
//! reads its L² fit ([`lobe_fit`](super::lobe_fit)), stored here in spare channels; the moments
//! place `ibl=anisotropic`'s fetches and `ibl=taps`' fallback fetch.
//!
//! At a normal view the lobe the cube was prefiltered with is the lobe itself. Away from it the
//! lobe leans from the mirror direction R towards the normal N — its reflected directions are
//! cut by the horizon and weighted by G2/G1 — and spreads differently: at μ = 0.1, α = 0.2 the
//! mean of its directions is 30° from R. The split sum reads its cube at R bent by Lagarde & de
//! Rousiers' view-independent lerp (8° there). Here each (μ, α) gets the lobe's own first
//! moment, the mean m of its reflected directions under the visible-normal distribution with
//! the height-correlated G2/G1 weight: a fetch goes along m̂ (stored as the weight w of
//! normalize(mix(R, N, w)), which points there), at the mip of the α′ whose normal-view lobe
//! has the same resultant length |m| (how concentrated its directions are; the von Mises-Fisher
//! fit's statistic). One moment matched in direction and one in spread: the fetch is still
//! isotropic, so what a grazing lobe's anisotropy changes is not matched.
//!
//! `ibl=anisotropic` matches three moments more ([`lobe_moments`]): the mean squares σ²_t, σ²_y
//! of the reflected directions' components along the tangent t of m̂ in the plane of incidence
//! and across it, and the mean cube κ of the component along t, which the horizon skews. The
//! lobe is wider along t (at α = 0.2 about twice the mean square from μ = 0.2 on). Two
//! fetches, each from the mip of the α″ whose normal-view lobe has mean square σ²_y per
//! tangent axis ([`normal_view_variance`]), at m̂ + up·t and m̂ − down·t with weights
//! down/(up + down) and up/(up + down) ([`two_points`]), hold σ²_y across the plane, and along
//! it the mean square up·down + σ²_y = σ²_t and the mean cube κ. At a normal view
//! up = down = 0 and α″ = α: one lobe, the cube's own.
//!
//! Each (√μ, √α) = (i, j)/(n − 1) holds (w, √α′, √α″, up, down): texel (i, j) of the
//! 2n × n RGBA32F image the first four, texel (n + i, j) the fifth (vertex-centred, so a
//! lookup never blends the halves; [`lobe_albedo`](super::lobe_albedo)'s layout with √μ for μ:
//! the lean changes fastest at grazing). Built on the CPU over a grid of the visible-normal
//! sampler's variables ([`lobe_moments`]); cached on disk like the other tables.

use glam::DVec3;

use crate::error::Result;
use crate::gpu::Gpu;
use crate::model::microfacet::{reflect, sample_vndf, smith_lambda};
use crate::shader::interface::LOBE_MOMENTS_SIZE;
use crate::vk::{upload_image, Format, Image, ImageDesc, ImageState, ImageView};

use super::lobe_albedo::MIN_MU;
use super::lobe_fit::{fit, warped, Kernels};
use super::{filter_axis, Texels};

/// Texels per side ([`LOBE_MOMENTS_SIZE`], which the shaders read too).
pub const SIZE: u32 = LOBE_MOMENTS_SIZE;

/// Side of the visible-normal grid each texel's moments are taken over.
const GRID: u32 = 192;

/// Points of the 1-D quadrature of the normal-view lobe's resultant length.
const SPREAD_POINTS: u32 = 8192;

/// Samples of the normal-view resultant length, uniform in √α, that α′ is read from.
const SPREAD_SAMPLES: usize = 256;

/// Bumped when the quadrature or the layout changes, so cached tables are rebuilt.
const VERSION: u32 = 5;

/// Values per (μ, α): (w, √α′, √α″, up, down, w°, √α°).
const VALUES: usize = 7;

pub struct LobeMomentsTable {
    /// R32G32B32A32_SFLOAT, 2n × n, in `FragmentRead` state: (w, √α′, √α″, up) in the left
    /// half, (down, w°, √α°, 0) in the right.
    pub image: Image,
    pub view: ImageView,
    pub size: u32,
    /// Row-major (row = roughness): (w, √α′, √α″, up, down, w°, √α°) per (μ, α).
    pub texels: Vec<[f32; VALUES]>,
}

impl LobeMomentsTable {
    /// From the disk cache when there, else computed (several seconds) and stored.
    pub fn load_or_build(gpu: &Gpu) -> Result<Self> {
        let key = crate::cache::Key {
            kind: "lobe-moments",
            params: vec![SIZE, GRID],
            shader_hash: u64::from(VERSION),
        };
        let dir = crate::cache::tables_dir();
        let count = SIZE as usize * SIZE as usize * VALUES;
        let (flat, _) =
            crate::cache::load_or_build(dir.as_deref(), &key, count, || Ok(compute(SIZE)))?;
        let image = Image::new(
            &gpu.device,
            ImageDesc::new_2d(Format::R32G32B32A32_SFLOAT, 2 * SIZE, SIZE),
            "lobe moments table",
        )?;
        upload_image(
            &gpu.device,
            &image,
            bytemuck::cast_slice(&halves(&flat, SIZE as usize)),
            ImageState::FragmentRead,
        )?;
        let view = image.view("lobe moments table")?;
        Ok(Self {
            image,
            view,
            size: SIZE,
            texels: flat
                .chunks_exact(VALUES)
                .map(|c| [c[0], c[1], c[2], c[3], c[4], c[5], c[6]])
                .collect(),
        })
    }

    /// The CPU twin of the shaders' lookup: (w, √α′, √α″, up, down, w°, √α°), bilinear over the
    /// vertex-centred texels.
    pub fn sample(&self, mu: f64, alpha: f64) -> [f64; VALUES] {
        let n = self.size as usize;
        let texel = |i: usize, j: usize, c: usize| f64::from(self.texels[j * n + i][c]);
        let (i, fx) = filter_axis(mu.clamp(0.0, 1.0).sqrt(), n, Texels::Vertices);
        let (j, fy) = filter_axis(alpha.clamp(0.0, 1.0).sqrt(), n, Texels::Vertices);
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        std::array::from_fn(|c| {
            let bottom = lerp(texel(i, j, c), texel(i + 1, j, c), fx);
            let top = lerp(texel(i, j + 1, c), texel(i + 1, j + 1, c), fx);
            lerp(bottom, top, fy)
        })
    }
}

/// The image's RGBA texels from the flat values: per row, (w, √α′, √α″, up) at each μ, then
/// (down, w°, √α°, 0) at each μ.
fn halves(flat: &[f32], size: usize) -> Vec<f32> {
    flat.chunks_exact(VALUES * size)
        .flat_map(|row| {
            let left = row.chunks_exact(VALUES).flat_map(|v| v[..4].to_vec());
            let right = row
                .chunks_exact(VALUES)
                .flat_map(|v| [v[4], v[5], v[6], 0.0]);
            left.chain(right).collect::<Vec<_>>()
        })
        .collect()
}

/// The lobe's first moment at view cosine `mu`: the mean of its reflected directions
/// (tangent space, the view in the +x half, so R = (−√(1−μ²), 0, μ)) under the visible
/// normals, weighted by the height-correlated G2/G1. A product rule over the visible-normal
/// sampler's two variables, the radial one u₁ = 1 − (1 − s)³ for s on a midpoint grid (weight
/// 3(1 − s)²): GGX's tail, which sets how far the directions spread, gets the points.
pub fn mean_direction(mu: f64, alpha: f64) -> DVec3 {
    lobe_moments(mu, alpha).0
}

/// The lobe's first moment ([`mean_direction`]) and its moments about the mean's direction
/// m̂, under the same weights: the mean squares of the reflected directions' components along
/// the tangent t of m̂ in the plane of incidence (t leans towards the normal) and across it
/// (the y axis), and the mean cube of the component along t (the horizon skews it).
pub fn lobe_moments(mu: f64, alpha: f64) -> (DVec3, [f64; 3]) {
    let v = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let masked = 1.0 + smith_lambda(mu, alpha);
    let samples = || {
        (0..GRID).flat_map(move |a| {
            let (u1, jacobian) = warped(a, GRID);
            (0..GRID).filter_map(move |b| {
                let u2 = (f64::from(b) + 0.5) / f64::from(GRID);
                let l = reflect(v, sample_vndf(v, (u1, u2), alpha));
                (l.z > 0.0).then(|| (jacobian * masked / (masked + smith_lambda(l.z, alpha)), l))
            })
        })
    };
    let (sum, total) = samples().fold((DVec3::ZERO, 0.0), |(s, t), (w, l)| (s + w * l, t + w));
    if total <= 0.0 {
        return (
            DVec3::new(-(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu),
            [0.0; 3],
        );
    }
    let m = sum / total;
    let n = m.normalize();
    let t = DVec3::new(n.z, 0.0, -n.x);
    let [along, across, skew] = samples().fold([0.0; 3], |[a, c, k], (w, l)| {
        let x = l.dot(t);
        [a + w * x * x, c + w * l.y * l.y, k + w * x * x * x]
    });
    (m, [along / total, across / total, skew / total])
}

/// Two points, at +up with weight down/(up + down) and at −down with the rest, whose mean is
/// 0, mean square `variance` and mean cube `skew`: up·down = variance, up − down =
/// skew/variance.
fn two_points(variance: f64, skew: f64) -> (f64, f64) {
    if variance <= 1e-12 {
        return (0.0, 0.0);
    }
    let s = skew / variance;
    let r = (s * s + 4.0 * variance).sqrt();
    ((r + s) / 2.0, (r - s) / 2.0)
}

/// The weight w of normalize(mix(R, N, w)) that points along the lobe's mean direction `m`
/// ([`mean_direction`]) at view cosine `mu`.
pub fn mean_lean(mu: f64, m: DVec3) -> f64 {
    let r = DVec3::new(-(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    mix_weight(mu.acos(), m.normalize().dot(r).clamp(-1.0, 1.0).acos())
}

/// The weight w of normalize(mix(R, N, w)) that points `lean` radians from R towards N, R
/// at `theta` radians from N.
pub(super) fn mix_weight(theta: f64, lean: f64) -> f64 {
    if theta <= 1e-9 {
        return 0.0;
    }
    let t = lean.min(theta).tan();
    (t / (theta.sin() + t * (1.0 - theta.cos()))).clamp(0.0, 1.0)
}

/// The mean of `f(cos θ_l)` over the normal-view lobe of roughness α > 0's reflected
/// directions, weighted by G2/G1 = 1/(1 + Λ(l)). Visible normals at a normal view are
/// D(h)·cos θ_h, whose CDF in u gives tan²θ_h = α²u/(1 − u); l makes 2θ_h with N and falls below
/// the horizon past θ_h = π/4, u = 1/(1 + α²). A midpoint rule in u over [0, that] is smooth in
/// α, where the 2-D grid's cut at the horizon moves in steps.
fn normal_view_mean(alpha: f64, f: impl Fn(f64) -> f64) -> f64 {
    let a2 = alpha * alpha;
    let end = 1.0 / (1.0 + a2);
    let (mut sum, mut total) = (0.0, 0.0);
    for k in 0..SPREAD_POINTS {
        let u = end * (f64::from(k) + 0.5) / f64::from(SPREAD_POINTS);
        let tan2 = a2 * u / (1.0 - u);
        let cos_l = (1.0 - tan2) / (1.0 + tan2);
        let w = 1.0 / (1.0 + smith_lambda(cos_l, alpha));
        sum += w * f(cos_l);
        total += w;
    }
    sum / total
}

/// The resultant length of the normal-view lobe of roughness α: the mean cosine of its
/// reflected directions to N ([`normal_view_mean`]).
pub fn normal_view_spread(alpha: f64) -> f64 {
    if alpha <= 0.0 {
        return 1.0;
    }
    normal_view_mean(alpha, |cos_l| cos_l)
}

/// The mean square of one tangent component of the normal-view lobe of roughness α's
/// reflected directions: (1 − cos²θ_l)/2 averaged ([`normal_view_mean`]).
pub fn normal_view_variance(alpha: f64) -> f64 {
    if alpha <= 0.0 {
        return 0.0;
    }
    normal_view_mean(alpha, |cos_l| 0.5 * (1.0 - cos_l * cos_l))
}

/// √α whose normal-view lobe's tangent component has mean square `c`, read from `variance`
/// (at √α uniform on [0, 1], increasing): the ends clamp.
fn variance_root_alpha(variance: &[f64], c: f64) -> f64 {
    let n = variance.len();
    if c <= variance[0] {
        return 0.0;
    }
    for k in 1..n {
        if c <= variance[k] {
            let t = (c - variance[k - 1]) / (variance[k] - variance[k - 1]);
            return (k as f64 - 1.0 + t) / (n - 1) as f64;
        }
    }
    1.0
}

/// √α′ whose normal-view lobe has resultant length `c`, read from `spread` (lengths at √α
/// uniform on [0, 1], decreasing): the ends clamp.
pub(super) fn matched_root_alpha(spread: &[f64], c: f64) -> f64 {
    let n = spread.len();
    if c >= spread[0] {
        return 0.0;
    }
    for k in 1..n {
        if c >= spread[k] {
            let t = (spread[k - 1] - c) / (spread[k - 1] - spread[k]);
            return (k as f64 - 1.0 + t) / (n - 1) as f64;
        }
    }
    1.0
}

/// The normal-view resultant lengths [`matched_root_alpha`] reads.
pub(super) fn spread_samples() -> Vec<f64> {
    samples(normal_view_spread)
}

/// `statistic` (of α) at √α uniform on [0, 1].
fn samples(statistic: fn(f64) -> f64) -> Vec<f64> {
    (0..SPREAD_SAMPLES)
        .map(|k| {
            let r = k as f64 / (SPREAD_SAMPLES - 1) as f64;
            statistic(r * r)
        })
        .collect()
}

/// The values, flat (w, √α′, √α″, up, down, w°, √α°) per (μ, α), rows split between the
/// machine's cores.
fn compute(size: u32) -> Vec<f32> {
    use rayon::prelude::*;
    let spread = spread_samples();
    let kernels = Kernels::default();
    let variance = samples(normal_view_variance);
    (0..size * size)
        .into_par_iter()
        .flat_map_iter(|t| {
            let (i, j) = (t % size, t / size);
            let root_mu = f64::from(i) / f64::from(size - 1);
            let mu = (root_mu * root_mu).max(MIN_MU);
            let root_alpha = f64::from(j) / f64::from(size - 1);
            if j == 0 {
                return [0.0; VALUES];
            }
            let (m, [along, across, skew]) = lobe_moments(mu, root_alpha * root_alpha);
            let w = mean_lean(mu, m);
            let root = matched_root_alpha(&spread, m.length());
            let minor = variance_root_alpha(&variance, along.min(across));
            let (up, down) = two_points((along - across).max(0.0), skew);
            let (fit_w, fit_root) = fit(mu, root_alpha * root_alpha, &kernels);
            [w, root, minor, up, down, fit_w, fit_root].map(|x| x as f32)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_normal_view_keeps_the_mirror_direction_and_its_own_roughness() {
        let spread = samples(normal_view_spread);
        assert!(spread.windows(2).all(|p| p[1] < p[0]), "{spread:?}");
        // The 2-D rule's length at a normal view inverts to the α it was taken at.
        for alpha in [0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0] {
            let m = mean_direction(1.0, alpha);
            assert!(m.x.abs() < 1e-9 && m.y.abs() < 1e-9, "{alpha}: {m}");
            let root = matched_root_alpha(&spread, m.length());
            assert!((root - alpha.sqrt()).abs() < 2e-4, "{alpha}: √α′ {root}");
        }
    }

    #[test]
    fn the_second_moments_at_a_normal_view_are_the_lobes_own() {
        let variance = samples(normal_view_variance);
        assert!(variance.windows(2).all(|p| p[1] > p[0]));
        for alpha in [0.02, 0.05, 0.1, 0.2, 0.5] {
            let (_, [along, across, _]) = lobe_moments(1.0, alpha);
            assert!(
                (along - across).abs() < 1e-3 * across,
                "{alpha}: {along} {across}"
            );
            let root = variance_root_alpha(&variance, along.min(across));
            assert!((root - alpha.sqrt()).abs() < 2e-3, "{alpha}: √α″ {root}");
        }
    }

    #[test]
    fn a_grazing_lobe_is_narrower_across_the_plane_of_incidence() {
        // α 0.2: at μ 0.9 nearly round; towards grazing the lobe spreads along the plane of
        // incidence about twice as much as across it (its mean squares), until the horizon
        // cuts the spread along it.
        let ratios: Vec<f64> = [0.9, 0.5, 0.2, 0.05]
            .map(|mu| {
                let (_, [along, across, _]) = lobe_moments(mu, 0.2);
                along / across
            })
            .to_vec();
        assert!(ratios[0] > 1.0 && ratios[0] < 1.2, "{ratios:?}");
        assert!(ratios[1] > 1.6 && ratios[2] > ratios[1], "{ratios:?}");
        assert!(
            ratios[2..].iter().all(|r| (r - 2.0).abs() < 0.2),
            "{ratios:?}"
        );
    }

    #[test]
    fn the_two_points_hold_the_spread_and_the_skew_they_are_given() {
        for (variance, skew) in [(0.01, 0.0), (0.01, 4e-4), (0.002, -1e-4), (0.05, 0.02)] {
            let (up, down) = two_points(variance, skew);
            let q = down / (up + down);
            let moment = |k: i32| q * up.powi(k) + (1.0 - q) * (-down).powi(k);
            assert!(moment(1).abs() < 1e-12, "{variance} {skew}");
            assert!((moment(2) - variance).abs() < 1e-12, "{variance} {skew}");
            assert!((moment(3) - skew).abs() < 1e-12, "{variance} {skew}");
        }
        // A grazing lobe's skew: the horizon cuts the side towards it, so the longer arm
        // points away from the horizon, towards the normal.
        let (_, [along, across, skew]) = lobe_moments(0.05, 0.2);
        let (up, down) = two_points(along - across, skew);
        assert!(skew > 0.0 && up > down, "skew {skew}: up {up}, down {down}");
    }

    #[test]
    fn a_grazing_lobe_leans_towards_the_normal_and_the_weight_points_there() {
        // α 0.2 at μ 0.1: the mean direction is about 30° from R, far beyond the split sum's
        // lerp (8°).
        let mu: f64 = 0.1;
        let m = mean_direction(mu, 0.2).normalize();
        let r = DVec3::new(-(1.0 - mu * mu).sqrt(), 0.0, mu);
        let lean = m.dot(r).acos().to_degrees();
        assert!((lean - 30.0).abs() < 1.0, "lean {lean}°");
        // Lagarde & de Rousiers' lerp(N, R, (1 − α)(√(1 − α) + α)), the split sum's direction.
        let f = 0.8 * (0.8f64.sqrt() + 0.2);
        let lagarde = (f * r + (1.0 - f) * DVec3::Z)
            .normalize()
            .dot(r)
            .acos()
            .to_degrees();
        assert!((lagarde - 8.0).abs() < 0.5, "Lagarde's lean {lagarde}°");
        let theta = mu.acos();
        let w = mix_weight(theta, lean.to_radians());
        let bent = ((1.0 - w) * r + w * DVec3::Z).normalize();
        assert!(bent.dot(m) > 1.0 - 1e-9, "w {w}: {bent} against {m}");
        // Leaning grows as the view grazes.
        let leans: Vec<f64> = [0.9, 0.5, 0.2, 0.05]
            .map(|mu: f64| {
                let r = DVec3::new(-(1.0 - mu * mu).sqrt(), 0.0, mu);
                mean_direction(mu, 0.2).normalize().dot(r).acos()
            })
            .to_vec();
        assert!(leans.windows(2).all(|p| p[1] > p[0]), "{leans:?}");
    }
}
