//! `lamina eval`: a material's model at view cosines — total R, T and the lobes — from the CPU
//! oracle or the GPU's own code, as a table or the JSON of DESIGN.md §5.

use anyhow::Result;
use lamina::material::resolve_with_variant;
use lamina::model::oracle;
use lamina::output::{EvalReport, EvalSample};
use lamina::render::eval::GpuEvaluator;
use lamina::render::oracle::VariantOracle;

use super::args::CosinesArg;
use super::{check_validation, GlobalArgs};

/// Where the model is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Backend {
    /// The f64 model with every axis of the variant it can honour: the FGD source and the TIR
    /// correction through the CPU twins of the tables the GPU samples (refuses fp16=on).
    Cpu,
    /// The shader library on the device (tm_eval.comp).
    Gpu,
    /// The f64 model itself: FGD integrated exactly, no TIR correction (the reference the
    /// tables approximate; the white furnace's oracle).
    Exact,
}

#[derive(clap::Args)]
pub struct EvalArgs {
    /// Material file or preset name (see assets/materials/).
    #[arg(long, value_name = "FILE|PRESET")]
    material: String,
    #[command(flatten)]
    cos: CosinesArg,
    #[arg(long, value_enum, default_value_t = Backend::Gpu)]
    backend: Backend,
    /// Shader variant; axes not given come from the defaults and the material's model.
    #[arg(long, value_name = "KEY")]
    variant: Option<String>,
    /// Print the JSON of DESIGN.md §5 instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn run(global: &GlobalArgs, args: &EvalArgs) -> Result<()> {
    let (stack, variant) = resolve_with_variant(&args.material, args.variant.as_deref())?;
    stack.require_uniform("`lamina eval`")?;
    let cosines = args.cos.checked()?;
    let layers = stack.params();
    let (backend, results) = match args.backend {
        Backend::Cpu => {
            oracle::check_cpu_variant(variant)?;
            let gpu = global.open_gpu()?;
            let results = VariantOracle::new(&gpu, variant)?.evaluate(&layers, cosines)?;
            check_validation(&gpu)?;
            ("cpu", results)
        }
        Backend::Exact => (
            "exact",
            cosines
                .iter()
                .map(|&c| oracle::evaluate(variant, &layers, c))
                .collect::<Vec<_>>(),
        ),
        Backend::Gpu => {
            let gpu = global.open_gpu()?;
            let evaluator = GpuEvaluator::new(&gpu, variant)?;
            let results = evaluator.evaluate(&layers, cosines)?;
            check_validation(&gpu)?;
            ("gpu", results)
        }
    };
    let report = EvalReport {
        material: stack.name.clone(),
        model: variant.model.to_string(),
        backend: backend.into(),
        samples: cosines
            .iter()
            .zip(&results)
            .map(|(&c, e)| EvalSample::new(c, e))
            .collect(),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.table());
    }
    Ok(())
}
