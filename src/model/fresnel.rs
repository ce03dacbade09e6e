//! Exact Fresnel reflectance (ALGORITHMS.md §10.5), unpolarised, relative IORs.

/// Dielectric interface of relative IOR η = n_t/n_i at incidence cosine `c`; 1 under total
/// internal reflection and for η = 0 (nothing to transmit into).
/// Normal-incidence reflectance of relative complex IOR η + iκ (`f0_channel` in
/// `glsl/include/lib/fresnel.glsl`): ((η − 1)² + κ²) / ((η + 1)² + κ²).
pub fn f0(eta: f64, kappa: f64) -> f64 {
    ((eta - 1.0).powi(2) + kappa * kappa) / ((eta + 1.0).powi(2) + kappa * kappa)
}

pub fn dielectric(c: f64, eta: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    let ct2 = 1.0 - (1.0 - c * c) / (eta * eta).max(1e-12);
    if ct2 <= 0.0 || eta <= 0.0 {
        return 1.0;
    }
    let ct = ct2.sqrt();
    let rs = (c - eta * ct) / (c + eta * ct);
    let rp = (eta * c - ct) / (eta * c + ct);
    0.5 * (rs * rs + rp * rp)
}

/// Conductor of relative complex IOR η + iκ at incidence cosine `c`.
pub fn conductor(c: f64, eta: f64, kappa: f64) -> f64 {
    if kappa <= 0.0 {
        return dielectric(c, eta);
    }
    let c = c.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t0 = eta * eta - kappa * kappa - s2;
    let a2b2 = (t0 * t0 + 4.0 * eta * eta * kappa * kappa).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let rs = (a2b2 + c2 - 2.0 * a * c) / (a2b2 + c2 + 2.0 * a * c);
    let rp =
        rs * (c2 * a2b2 + s2 * s2 - 2.0 * a * c * s2) / (c2 * a2b2 + s2 * s2 + 2.0 * a * c * s2);
    0.5 * (rs + rp)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cos_deg(d: f64) -> f64 {
        d.to_radians().cos()
    }

    /// ALGORITHMS.md §12.1.
    #[test]
    fn dielectric_matches_the_table() {
        let rows = [
            (1.5, [0.04000, 0.04152, 0.05024, 0.08919, 0.25306, 0.61280]),
            (1.33, [0.02006, 0.02111, 0.02752, 0.05913, 0.21143, 0.58273]),
            (2.42, [0.17239, 0.17388, 0.18152, 0.21160, 0.33063, 0.62162]),
        ];
        for (eta, values) in rows {
            for (deg, want) in [0.0, 30.0, 45.0, 60.0, 75.0, 85.0].iter().zip(values) {
                let got = dielectric(cos_deg(*deg), eta);
                assert!((got - want).abs() < 1e-5, "η {eta} at {deg}°: {got}");
            }
        }
        assert!((dielectric(cos_deg(30.0), 1.0 / 1.5) - 0.05519).abs() < 1e-5);
        assert_eq!(dielectric(cos_deg(45.0), 1.0 / 1.5), 1.0);
    }

    /// ALGORITHMS.md §12.2, gold.
    #[test]
    fn conductor_matches_the_table() {
        let eta = [0.143245, 0.377423, 1.43919];
        let kappa = [3.98479, 2.3847, 1.60434];
        let f60 = [0.9622, 0.8034, 0.3717];
        let f80 = [0.9632, 0.8749, 0.5922];
        for c in 0..3 {
            assert!((conductor(cos_deg(60.0), eta[c], kappa[c]) - f60[c]).abs() < 1e-4);
            assert!((conductor(cos_deg(80.0), eta[c], kappa[c]) - f80[c]).abs() < 1e-4);
        }
    }
}
