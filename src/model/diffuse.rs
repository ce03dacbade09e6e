//! A Lambertian base of albedo ρ under the stack (issue 12): the light the stack transmits
//! down reaches the base, which reflects the fraction ρ of it into a uniformly diffuse
//! (cosine-distributed) flux; that flux climbs the stack, which lets out T′_d of it and sends
//! R′_d back down to the base, and so on. Summing the internal reflection series,
//!
//!   w_d = T(μ) · ρ · T′_d / (1 − ρ·R′_d)     (written as ρ·T′_d / (q_d + R′_d·(1 − ρ)) with the
//!                                             stack's q = 1 − R′ carried without cancellation)
//!
//! where T(μ) is the stack's transmittance for the view's mean direction (the model's own) and
//! (R′_d, T′_d) are the stack's reflectance and transmittance for diffuse light arriving from
//! below, composed by the same adding equations over each interface's cosine-weighted
//! hemispherical Fresnel averages. With one smooth coat of index n this is the classic closed
//! form of a smooth dielectric over a Lambertian surface (Kubelka's internal reflection series;
//! d'Eon, "A Hitchhiker's Guide to Multiple Scattering", 2016, §"Coated diffuse"; Weidlich &
//! Wilkie, "Arbitrarily layered micro-facet surfaces", 2007):
//!
//!   R(μ) = F(μ) + (1 − F(μ)) · ρ · (1 − F̄_i) / (1 − ρ·F̄_i),   F̄_i = 1 − (1 − F̄_e)/n²,
//!
//! F̄_e the hemispherical average from outside, F̄_i from inside (total internal reflection
//! included, by reciprocity). The tests hold the model to it.
//!
//! Approximations, stated: the diffuse flux sees every interface as smooth (the hemispherical
//! average of a rough interface's albedo differs by a few percent at most: roughness moves
//! energy between angles, the average over all of them changes little); a 6-flux medium is
//! crossed by diffuse light as by collimated light at μ = 1/2 (the cosine-weighted mean of
//! the path length 1/μ is 2); and the light leaving the stack is shaded as a Lambertian lobe
//! (`LOBE_DIFFUSE`), its angular narrowing by refraction ignored. Energy is conserved exactly:
//! a white base under a lossless stack gives R + w_d = R + T = 1.

use super::adding::{avg, map3, Component, Rgb, Slab};
use super::{fresnel, medium, LayerParams, INDEX_MATCHED, IOR_AIR};

/// Gauss–Legendre points of the hemispherical averages (the integrand is smooth from the
/// rarer side, so 16 points are exact to f64 rounding for η up to 400; the tests check).
pub const HEMISPHERE_POINTS: usize = 16;

/// The `n`-point Gauss–Legendre rule on [0, 1]: (node, weight) pairs, by Newton's method on
/// the Legendre polynomial P_n.
pub fn gauss_legendre_unit(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            // Tricomi's initial guess for the i-th root of P_n on [-1, 1].
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut derivative = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                derivative = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let step = p1 / derivative;
                x -= step;
                if step.abs() < 1e-16 {
                    break;
                }
            }
            let weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
            (0.5 * (x + 1.0), 0.5 * weight)
        })
        .collect()
}

/// The cosine-weighted hemispherical average 2∫₀¹ F(μ, η) μ dμ of the dielectric Fresnel
/// reflectance for diffuse light arriving at an interface of relative IOR η = n_t/n_i. From
/// the denser side (η < 1) by reciprocity, F̄(η) = 1 − η²·(1 − F̄(1/η)): the light that gets
/// out is the light that would get in, scaled by the ratio of the hemispheres' étendues,
/// total internal reflection included.
pub fn fresnel_hemispherical(eta: f64) -> f64 {
    if eta < 1.0 {
        return 1.0 - eta * eta * (1.0 - fresnel_hemispherical(1.0 / eta));
    }
    // With μ = s², 2μ dμ = 4s³ ds: the nodes crowd towards grazing incidence, where F climbs
    // to 1 over a range of μ that shrinks with η − 1.
    gauss_legendre_unit(HEMISPHERE_POINTS)
        .iter()
        .map(|&(s, w)| w * 4.0 * s * s * s * fresnel::dielectric(s * s, eta))
        .sum()
}

/// The layers above a diffuse base as diffuse light sees them: (R, T) from above and
/// (R′, T′, q) from below, by the adding equations over each dielectric interface's
/// hemispherical averages and, in 6-flux, each medium crossed at μ = 1/2.
pub(crate) fn slab(above: &[LayerParams], media: bool) -> Slab {
    let mut s = Slab::empty();
    let mut eta_above = IOR_AIR;
    for layer in above {
        let eta = avg(layer.ior) / eta_above;
        if (eta - 1.0).abs() >= INDEX_MATCHED {
            let (down, up) = (fresnel_hemispherical(eta), fresnel_hemispherical(1.0 / eta));
            s = s.over(&Component::lossless(down, 1.0 - down, up, 1.0 - up));
            eta_above = avg(layer.ior);
        }
        if media && layer.depth > 0.0 {
            // t_ff holds the unscattered transmission too (tm6's Component6::medium).
            let m = medium::medium_factors(layer, 0.5);
            s = s.over(&Component::symmetric(m.r_fb, m.t_ff));
        }
    }
    s
}

/// The energy w_d the base of albedo `rho` sends back out through `above` (its diffuse
/// `slab`), given the stack's transmittance `t_view` towards the base.
pub(crate) fn lobe_weight(t_view: Rgb, rho: Rgb, diffuse: &Slab) -> Rgb {
    map3(|c| {
        let den = diffuse.q[c] + diffuse.rp[c] * (1.0 - rho[c]);
        if den > 0.0 {
            t_view[c] * rho[c] * diffuse.tp[c] / den
        } else {
            0.0
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::fgd::ExactFgd;
    use crate::model::tm2::tests::coat;
    use crate::model::{tm2, tm6, NoTir};
    use crate::variant::G2;

    fn base(rho: [f64; 3]) -> LayerParams {
        LayerParams::diffuse_base(rho)
    }

    fn reflectance(model6: bool, stack: &[LayerParams], mu: f64) -> [f64; 3] {
        let fgd = ExactFgd::new(G2::HeightCorrelated);
        if model6 {
            tm6::evaluate(stack, mu, &fgd, &NoTir).reflectance
        } else {
            tm2::evaluate(stack, mu, &fgd, &NoTir).reflectance
        }
    }

    /// 2∫F μ dμ by a fine midpoint rule, from the rarer side.
    fn average_by_midpoints(eta: f64) -> f64 {
        let n = 200_000;
        (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                2.0 * mu * fresnel::dielectric(mu, eta) / n as f64
            })
            .sum()
    }

    /// The closed form of a smooth dielectric of index n over a Lambertian albedo ρ, with its
    /// hemispherical averages by the fine midpoint rule (independent of the model's rule).
    fn closed_form(n: f64, rho: f64, mu: f64) -> f64 {
        let f = fresnel::dielectric(mu, n);
        let inside = 1.0 - (1.0 - average_by_midpoints(n)) / (n * n);
        f + (1.0 - f) * rho * (1.0 - inside) / (1.0 - rho * inside)
    }

    #[test]
    fn a_smooth_coat_over_a_lambertian_base_is_the_closed_form() {
        let mut worst = 0.0f64;
        for n in [1.33, 1.5, 2.0] {
            for rho in [0.0, 0.2, 0.8, 1.0] {
                let stack = [coat(n, 0.0), base([rho; 3])];
                for mu in [1e-4, 0.05, 0.3, 0.7, 1.0] {
                    let want = closed_form(n, rho, mu);
                    for model6 in [false, true] {
                        let got = reflectance(model6, &stack, mu)[0];
                        worst = worst.max((got - want).abs());
                        assert!(
                            (got - want).abs() < 1e-3,
                            "n {n}, ρ {rho}, μ {mu}, tm{}: {got} vs {want}",
                            if model6 { 6 } else { 2 }
                        );
                    }
                }
            }
        }
        println!("smooth coat over a Lambertian base: largest difference {worst:.1e}");
    }

    #[test]
    fn a_white_base_under_lossless_coats_reflects_at_most_one() {
        let coats = [
            vec![coat(1.5, 0.1)],
            vec![coat(1.5, 0.05), coat(1.3, 0.3), coat(2.0, 0.6)],
            vec![coat(1.2, 0.0), coat(1.0, 0.2), coat(1.8, 1.0)],
            vec![coat(1.5, 0.2).with_medium(2.0, [3.0, 1.0, 0.5], [0.0; 3], 0.4)],
        ];
        let mut lowest = 1.0f64;
        for stack in coats {
            let mut stack = stack.clone();
            stack.push(base([1.0; 3]));
            for model6 in [false, true] {
                for k in 0..=50 {
                    let mu = (k as f64 / 50.0).max(1e-4);
                    for r in reflectance(model6, &stack, mu) {
                        assert!(r <= 1.0 + 1e-9, "{stack:?} at μ {mu}: {r}");
                        lowest = lowest.min(r);
                    }
                }
            }
        }
        // Lossless interfaces pass every bit of energy to the white base and back: the furnace
        // is exactly 1 where nothing absorbs (the scattering medium's σa floor of 1e-7 aside).
        assert!(
            lowest > 1.0 - 1e-3,
            "a lossless stack over a white base lost energy: {lowest}"
        );
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let rule = gauss_legendre_unit(HEMISPHERE_POINTS);
        for degree in 0..2 * HEMISPHERE_POINTS as i32 {
            let sum: f64 = rule.iter().map(|&(x, w)| w * x.powi(degree)).sum();
            let exact = 1.0 / f64::from(degree + 1);
            assert!(
                (sum - exact).abs() < 1e-13,
                "degree {degree}: {sum} vs {exact}"
            );
        }
    }

    #[test]
    fn hemispherical_fresnel_matches_the_integral_and_reciprocity() {
        for eta in [1.0001, 1.01, 1.1, 1.33, 1.5, 2.0, 3.0, 10.0, 400.0] {
            let fine = average_by_midpoints(eta);
            let got = fresnel_hemispherical(eta);
            assert!((got - fine).abs() < 2e-6, "η {eta}: {got} vs {fine}");
        }
        // The classic value of water and glass from outside: 0.066 and 0.092.
        assert!((fresnel_hemispherical(1.33) - 0.0660).abs() < 5e-4);
        assert!((fresnel_hemispherical(1.5) - 0.0918).abs() < 5e-4);
        // From inside glass: 1 − (1 − 0.0918)/2.25 = 0.596.
        assert!((fresnel_hemispherical(1.0 / 1.5) - 0.5964).abs() < 5e-4);
        // η = 1 reflects nothing; the Fresnel terms keep rounding residues of 1 − (1 − μ²).
        assert!(fresnel_hemispherical(1.0) < 1e-15);
    }
}
