//! `lamina eval`: a material's model at view cosines — total R, T and the lobes — from the CPU
//! oracle or the GPU's own code, as a table or the JSON of DESIGN.md §5.

use anyhow::Result;
use lamina::material::resolve_with_variant;
use lamina::oracle;
use lamina::output::{EvalReport, EvalSample};
use lamina::render::eval::GpuEvaluator;

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
    /// View cosines, comma-separated, each in (0, 1].
    #[arg(
        long = "cos",
        value_name = "LIST",
        value_delimiter = ',',
        required = true
    )]
    cosines: Vec<f64>,
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
    if let Some(c) = args
        .cosines
        .iter()
        .find(|c| !(c.is_finite() && **c > 0.0 && **c <= 1.0))
    {
        anyhow::bail!("--cos: {c} is not a view cosine; each must be in (0, 1]");
    }
    let layers = stack.params();
    let (backend, results) = match args.backend {
        Backend::Cpu => {
            oracle::check_cpu_variant(variant)?;
            let gpu = global.open_gpu()?;
            let results =
                oracle::VariantOracle::new(&gpu, variant)?.evaluate(&layers, &args.cosines)?;
            check_validation(&gpu)?;
            ("cpu", results)
        }
        Backend::Exact => (
            "exact",
            args.cosines
                .iter()
                .map(|&c| oracle::evaluate(variant, &layers, c))
                .collect::<Vec<_>>(),
        ),
        Backend::Gpu => {
            let gpu = global.open_gpu()?;
            let evaluator = GpuEvaluator::new(&gpu, variant)?;
            let results = evaluator.evaluate(&layers, &args.cosines)?;
            check_validation(&gpu)?;
            ("gpu", results)
        }
    };
    let report = EvalReport {
        material: stack.name.clone(),
        model: variant.model.to_string(),
        backend: backend.into(),
        samples: args
            .cosines
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
