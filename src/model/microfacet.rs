//! GGX microfacet terms in f64 (ALGORITHMS.md §10): the CPU side of
//! `glsl/include/lib/microfacet.glsl` and `sampling.glsl`, used as the oracle for tables.

use glam::DVec3;

use crate::variant::G2;

/// GGX D(h) = α² / (π (cos²θ_h (α² − 1) + 1)²).
pub fn ggx_d(cos_h: f64, alpha: f64) -> f64 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = cos_h * cos_h * (a2 - 1.0) + 1.0;
    a2 / (std::f64::consts::PI * d * d)
}

/// Karis 2013's arrangement of the same D (one multiply fewer, different rounding): the CPU
/// twin of `ggx_d_karis` in `glsl/include/lib/microfacet.glsl` (`ndf=karis`).
pub fn ggx_d_karis(cos_h: f64, alpha: f64) -> f64 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = (cos_h * a2 - cos_h) * cos_h + 1.0;
    a2 / (std::f64::consts::PI * d * d)
}

/// Smith Λ for GGX: (−1 + √(1 + α² tan²θ)) / 2.
pub fn smith_lambda(cos_t: f64, alpha: f64) -> f64 {
    let c2 = (cos_t * cos_t).max(1e-300);
    let tan2 = ((1.0 - c2) / c2).max(0.0);
    0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
}

/// Schlick-Smith G1 with k = α/2 (Karis 2013, IBL constant).
pub fn schlick_g1(cos_t: f64, alpha: f64) -> f64 {
    let k = 0.5 * alpha;
    cos_t / (cos_t * (1.0 - k) + k)
}

/// The masking term that goes with a G2 form (Smith's G1, or Schlick's for `schlick`).
pub fn masking_g1(g2: G2, cos_t: f64, alpha: f64) -> f64 {
    match g2 {
        G2::Schlick => schlick_g1(cos_t, alpha),
        _ => 1.0 / (1.0 + smith_lambda(cos_t, alpha)),
    }
}

/// Masking-shadowing G2 for upper-hemisphere cosines (Heitz 2014; Hammon 2017 for `earl`).
pub fn masking_shadowing(g2: G2, cos_i: f64, cos_o: f64, alpha: f64) -> f64 {
    match g2 {
        G2::HeightCorrelated => {
            1.0 / (1.0 + smith_lambda(cos_i, alpha) + smith_lambda(cos_o, alpha))
        }
        G2::Smith => masking_g1(g2, cos_i, alpha) * masking_g1(g2, cos_o, alpha),
        G2::Schlick => schlick_g1(cos_i, alpha) * schlick_g1(cos_o, alpha),
        G2::Earl => {
            let two = 2.0 * cos_i * cos_o;
            two / (two + (cos_i + cos_o - two) * alpha)
        }
    }
}

/// Visible-normal sample (Heitz 2018) for view `v` (tangent space, v.z > 0), u ∈ [0,1)².
pub fn sample_vndf(v: DVec3, u: (f64, f64), alpha: f64) -> DVec3 {
    let vh = DVec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        DVec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        DVec3::X
    };
    let t2 = vh.cross(t1);
    let r = u.0.sqrt();
    let phi = 2.0 * std::f64::consts::PI * u.1;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// Calls `f(v, h, l)` over an `n`×`n` midpoint grid of the visible-normal sampler's two
/// uniform variables, for the view v = (√(1−μ²), 0, μ): h ~ D_v(h), l = reflect(v, h), and
/// only where l is above the surface. The mean of a weight w over the grid (the sum divided
/// by n²) estimates ∫ w(l) G1(v) D(h) / (4μ) dω_l, the reflected directions' pdf; the CPU
/// references of the tables are such means (w = F·G2/G1 gives FGD).
pub fn for_each_vndf_sample(mu: f64, alpha: f64, n: u32, mut f: impl FnMut(DVec3, DVec3, DVec3)) {
    let v = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    for_each_visible_normal(v, alpha, n, |h| {
        let l = reflect(v, h);
        if l.z > 0.0 {
            f(v, h, l);
        }
    });
}

/// Calls `f(h)` for each point of an `n`×`n` midpoint grid of the visible-normal sampler's two
/// uniform variables for the view `v` (v.z > 0): h ~ D_v(h), each point of weight 1/n².
pub fn for_each_visible_normal(v: DVec3, alpha: f64, n: u32, mut f: impl FnMut(DVec3)) {
    for a in 0..n {
        for b in 0..n {
            let u = (
                (f64::from(a) + 0.5) / f64::from(n),
                (f64::from(b) + 0.5) / f64::from(n),
            );
            f(sample_vndf(v, u, alpha));
        }
    }
}

/// Mirror of `-v` about `h`: the reflected direction.
pub fn reflect(v: DVec3, h: DVec3) -> DVec3 {
    2.0 * v.dot(h) * h - v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ D(h) cos θ_h dω = 1 for any α (normalisation of the NDF), by midpoint quadrature.
    #[test]
    fn ndf_is_normalised() {
        for alpha in [0.1, 0.3, 0.7, 1.0] {
            let n = 4000;
            let mut sum = 0.0;
            for i in 0..n {
                let theta = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
                let c = theta.cos();
                sum += ggx_d(c, alpha) * c * theta.sin();
            }
            sum *= 2.0 * std::f64::consts::PI * std::f64::consts::FRAC_PI_2 / n as f64;
            assert!((sum - 1.0).abs() < 1e-3, "alpha {alpha}: {sum}");
        }
    }

    #[test]
    fn karis_form_is_the_same_distribution() {
        for alpha in [0.05, 0.3, 1.0] {
            for i in 0..=20 {
                let c = f64::from(i) / 20.0;
                let (a, b) = (ggx_d(c, alpha), ggx_d_karis(c, alpha));
                assert!(
                    (a - b).abs() <= 1e-12 * a.max(1.0),
                    "α {alpha} cos {c}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn g2_forms_agree_at_normal_incidence() {
        // Λ(normal) = 0, so the Smith forms coincide there (ALGORITHMS.md §13.2.6).
        for alpha in [0.1, 0.5, 1.0] {
            let hc = masking_shadowing(G2::HeightCorrelated, 1.0, 0.6, alpha);
            let sep = masking_shadowing(G2::Smith, 1.0, 0.6, alpha);
            assert!((hc - sep).abs() < 1e-12);
        }
    }

    #[test]
    fn vndf_samples_are_unit_and_visible() {
        let v = DVec3::new(0.8, 0.0, 0.6);
        for i in 0..64 {
            let u = ((i as f64 + 0.5) / 64.0, ((i * 37) % 64) as f64 / 64.0);
            let h = sample_vndf(v, u, 0.4);
            assert!((h.length() - 1.0).abs() < 1e-12);
            assert!(h.z >= 0.0 && v.dot(h) >= -1e-12);
        }
    }
}
