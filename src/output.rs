//! Machine-readable output of `lamina eval` (DESIGN.md §5). Other tools parse it: keep the
//! field names and nesting stable.

use serde::Serialize;

use crate::model::Evaluation;

#[derive(Debug, Serialize)]
pub struct EvalReport {
    pub material: String,
    pub model: String,
    pub backend: String,
    pub samples: Vec<EvalSample>,
}

#[derive(Debug, Serialize)]
pub struct EvalSample {
    pub cos_theta: f64,
    pub reflectance: [f64; 3],
    pub transmittance: [f64; 3],
    /// GGX α of the lobe the stack transmits, as the forward pass shades it (a thin slab:
    /// `model::transmitted_alpha`); absent where nothing is transmitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transmitted_roughness: Option<f64>,
    pub lobes: Vec<EvalLobe>,
}

#[derive(Debug, Serialize)]
pub struct EvalLobe {
    pub weight: [f64; 3],
    /// GGX α of the lobe (1 for a diffuse base's lobe, which has none).
    pub roughness: f64,
    /// `true` for a diffuse base's Lambertian lobe; absent otherwise.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub diffuse: bool,
}

impl EvalSample {
    pub fn new(cos_theta: f64, evaluation: &Evaluation) -> Self {
        Self {
            cos_theta,
            reflectance: evaluation.reflectance,
            transmittance: evaluation.transmittance,
            transmitted_roughness: evaluation
                .transmittance
                .iter()
                .any(|&t| t > 0.0)
                .then_some(evaluation.transmitted_roughness),
            lobes: evaluation
                .lobes
                .iter()
                .map(|l| EvalLobe {
                    weight: l.weight,
                    roughness: l.roughness,
                    diffuse: l.diffuse,
                })
                .collect(),
        }
    }
}

impl EvalReport {
    /// A human-readable table: one block per sample, one line per lobe.
    pub fn table(&self) -> String {
        let mut out = format!(
            "material: {}   model: {}   backend: {}\n",
            self.material, self.model, self.backend
        );
        let rgb = |v: [f64; 3]| format!("{:.5} {:.5} {:.5}", v[0], v[1], v[2]);
        for s in &self.samples {
            let through = s
                .transmitted_roughness
                .map_or(String::new(), |a| format!(" through α {a:.4}"));
            out += &format!(
                "cos θ = {:.4}   R = {}   T = {}{through}\n",
                s.cos_theta,
                rgb(s.reflectance),
                rgb(s.transmittance)
            );
            for (k, l) in s.lobes.iter().enumerate() {
                let shape = if l.diffuse {
                    "diffuse (Lambertian)".to_owned()
                } else {
                    format!("α {:.4}", l.roughness)
                };
                out += &format!("    lobe {k:>2}: weight {}   {shape}\n", rgb(l.weight));
            }
        }
        out
    }
}
