//! Materials: for now the single GGX layer the baseline shades; the transfer-matrix stack and
//! its TOML format extend this (DESIGN.md §6).

/// One interface: complex IOR per RGB channel (relative to air) and GGX roughness α.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer {
    pub ior: [f32; 3],
    pub kappa: [f32; 3],
    pub roughness: f32,
}

impl Default for Layer {
    /// Gold (RGB n, k from ALGORITHMS.md §12.2) at α = 0.2.
    fn default() -> Self {
        Self {
            ior: [0.143245, 0.377423, 1.43919],
            kappa: [3.98479, 2.3847, 1.60434],
            roughness: 0.2,
        }
    }
}

impl Layer {
    /// Normal-incidence reflectance ((η − 1)² + κ²) / ((η + 1)² + κ²) per channel, in f64.
    pub fn f0(&self) -> [f64; 3] {
        std::array::from_fn(|c| {
            let (n, k) = (f64::from(self.ior[c]), f64::from(self.kappa[c]));
            ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gold_f0_matches_the_table() {
        // ALGORITHMS.md §12.2: Au F0 = 0.9667, 0.8009, 0.3246.
        let f0 = Layer::default().f0();
        for (got, want) in f0.iter().zip([0.9667, 0.8009, 0.3246]) {
            assert!((got - want).abs() < 1e-4, "{f0:?}");
        }
    }
}
