//! Henyey–Greenstein lobe algebra of the transfer-matrix model (ALGORITHMS.md §3): a lobe's
//! spread is its HG asymmetry g, and paths compose by multiplying g's. The CPU twin of
//! `glsl/include/lib/hg.glsl`.

/// GGX α → HG g (the paper's Eq. 15), exact inverse of [`alpha_of_g`] on α ∈ [0, 1].
pub fn g_of_alpha(alpha: f64) -> f64 {
    let a = alpha.clamp(0.0, 1.0);
    (-0.085 + 1.085 / (1.0 + (a / 0.5).powf(1.3))).clamp(0.0, 1.0)
}

/// The smallest α [`alpha_of_g`] gives (the shaders' `HG_MIN_ALPHA`).
pub const MIN_ALPHA: f64 = 1e-4;

/// HG g → (2α)^1.3, the paper's Eq. 15 solved for it without the root: one division, where
/// α costs a pow. Unclamped: 0 at g = 1, 2.81 at g ≤ 0.2 (α = 1.11).
pub fn alpha_power_of_g(g: f64) -> f64 {
    1.085 / (g.clamp(-1.0, 1.0).max(0.2) + 0.085) - 1.0
}

/// HG g → GGX α; any g below 0.2284 maps to α = 1.
pub fn alpha_of_g(g: f64) -> f64 {
    (0.5 * alpha_power_of_g(g).powf(1.0 / 1.3)).clamp(MIN_ALPHA, 1.0)
}

/// Lobe refraction through relative IOR η (the paper's Eq. 17–18).
pub fn refract(g: f64, eta: f64) -> f64 {
    (1.0 - (1.0 - g * g) * eta.powf(0.75))
        .max(0.0)
        .sqrt()
        .min(1.0)
}

/// Denominators below which a ratio of g's is taken as 0 ([`safe_ratio`]).
pub const RATIO_FLOOR: f64 = 1e-7;

/// `num / den`, or 0 where |den| ≤ [`RATIO_FLOOR`]. The first-order transmitted-asymmetry
/// factors (§4.4) are ratios of cumulative g's, and a lobe's g is a ratio of g-weighted energy
/// to energy: undefined where the lobe has collapsed (g → 0) or carries no energy. The
/// reference guards with > 0, which f32 and f64 pass at different depths of that collapse (a
/// g of 1e-50 is 0 in f32), so the GPU and the oracle took different branches there.
pub fn safe_ratio(num: f64, den: f64) -> f64 {
    if den.abs() > RATIO_FLOOR {
        num / den
    } else {
        0.0
    }
}

/// Fraction of an HG phase function in the backward hemisphere (polynomial fit, §3.5).
pub fn lh_norm(g: f64) -> f64 {
    let b = (0.5039 - 0.8254 * g.abs() + 0.3226 * g * g).clamp(0.0, 0.5);
    if g < 0.0 {
        1.0 - b
    } else {
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alpha_g_mapping_matches_published_values_and_round_trips() {
        for (alpha, g) in [
            (0.0, 1.0),
            (0.1, 0.8808),
            (0.3, 0.6313),
            (0.5, 0.4575),
            (1.0, 0.2284),
        ] {
            assert!((g_of_alpha(alpha) - g).abs() < 1e-4, "g({alpha})");
        }
        for (g, alpha) in [(0.99, 0.0137), (0.9, 0.0861), (0.6, 0.3306), (0.1, 1.0)] {
            assert!((alpha_of_g(g) - alpha).abs() < 1e-4, "α({g})");
        }
        for i in 1..=100 {
            let a = f64::from(i) / 100.0;
            assert!(
                (alpha_of_g(g_of_alpha(a)) - a).abs() < 1e-9,
                "round trip at {a}"
            );
        }
    }

    #[test]
    fn refraction_and_backward_fraction_match_published_values() {
        assert!((refract(0.9, 1.0 / 1.5) - 0.9273).abs() < 1e-4);
        assert!((refract(0.9, 1.5) - 0.8617).abs() < 1e-4);
        assert!((refract(0.6, 1.5) - 0.3641).abs() < 1e-4);
        assert_eq!(refract(0.5, 1.5), 0.0);
        assert_eq!(refract(1.0, 1.0), 1.0);
        // Fit vs the exact B(g) of §3.5.
        for (g, exact) in [(0.3, 0.2860), (0.5, 0.1708), (0.7, 0.0841), (0.9, 0.0229)] {
            assert!((lh_norm(g) - exact).abs() < 2e-3, "B({g}) = {}", lh_norm(g));
        }
        assert!((lh_norm(-0.5) - (1.0 - lh_norm(0.5))).abs() < 1e-12);
    }
}
