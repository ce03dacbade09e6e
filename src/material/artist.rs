//! The artist form of a conductor: reflectivity F0 and edge tint (Gulbrandsen 2014,
//! "Artist Friendly Metallic Fresnel", JCGT 3(4)), as ALGORITHMS.md §10.5 gives it.

/// (n, κ) of one channel from reflectivity `r` ∈ [0, 1) and edge tint `g` ∈ [0, 1]:
/// n = g(1−r)/(1+r) + (1−g)(1+√r)/(1−√r), κ² = (r(1+n)² − (n−1)²)/(1−r).
/// F0(n, κ) = r holds exactly. κ² within rounding of zero (the dielectric case, e.g. r = 0.04
/// with g = 0) is snapped to 0, so such a layer stays a dielectric rather than becoming a
/// conductor with κ ≈ 1e-9.
pub fn gulbrandsen(r: f64, g: f64) -> (f64, f64) {
    let sqrt_r = r.sqrt();
    let n = g * (1.0 - r) / (1.0 + r) + (1.0 - g) * (1.0 + sqrt_r) / (1.0 - sqrt_r);
    let k2 = (r * (1.0 + n).powi(2) - (n - 1.0).powi(2)) / (1.0 - r);
    let k2 = if k2 < 1e-12 * (1.0 + n).powi(2) {
        0.0
    } else {
        k2
    };
    (n, k2.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f0(n: f64, k: f64) -> f64 {
        ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)
    }

    /// ALGORITHMS.md §12.2 Gulbrandsen checks.
    #[test]
    fn matches_published_values_and_reproduces_f0() {
        for (r, g, n, k) in [
            (0.04, 0.0, 1.5, 0.0),
            (0.5, 0.5, 3.08088, 2.82727),
            (0.9, 0.9, 3.84474, 11.41569),
        ] {
            let (got_n, got_k) = gulbrandsen(r, g);
            assert!((got_n - n).abs() < 1e-4, "n({r}, {g}) = {got_n}");
            assert!((got_k - k).abs() < 1e-4, "κ({r}, {g}) = {got_k}");
            assert!((f0(got_n, got_k) - r).abs() < 1e-9);
        }
    }
}
