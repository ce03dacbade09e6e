//! `lamina reference`: the stochastic reference of a material (total R and T with standard
//! errors, the BRDF in the plane of incidence and over the hemisphere), on every core, with a
//! progress bar; Ctrl-C stops it without writing anything.

use std::path::PathBuf;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use lamina::imageio::write_file_atomically;
use lamina::material::Stack;
use lamina::reference::flows::Side;
use lamina::reference::walk::Walker;
use lamina::reference::{self, Reference, Settings};
use lamina::variant::{Axis, Interfaces, Model, G2};
use serde::Serialize;

use super::args::CosinesArg;
use super::stop_on_interrupt;

#[derive(clap::Args)]
pub struct ReferenceArgs {
    /// Material file or preset name (see assets/materials/).
    #[arg(long, value_name = "FILE|PRESET")]
    material: String,
    #[command(flatten)]
    cos: CosinesArg,
    /// Light paths per channel and view cosine (standard errors fall as 1/√N).
    #[arg(long, value_name = "N", default_value_t = 1_000_000)]
    paths: u64,
    /// Seed of the paths: the same seed gives the same numbers on any number of threads.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Masking form of the interfaces' reflections (the model's FGD's; the variant axis g2);
    /// `--interfaces multiple` takes only `height-correlated`, the microsurface's own.
    #[arg(long, value_name = "FORM", default_value = "height-correlated")]
    g2: String,
    /// How rough interfaces scatter: `single` (the microfacet BSDF's one event; masking loses
    /// energy) or `multiple` (the walk on the microsurface, which conserves it).
    #[arg(long, value_name = "MODE", default_value = "single")]
    interfaces: String,
    /// Also print, per boundary, side and crossing order (1, 2, 3+), the energy arriving,
    /// sent back, passed and lost (always in the JSON).
    #[arg(long)]
    tally: bool,
    /// Print the JSON (with the slice and hemisphere bins) instead of a table.
    #[arg(long)]
    json: bool,
    /// Also write the JSON to this file (atomically: all of it or nothing).
    #[arg(long, value_name = "FILE.json")]
    out: Option<PathBuf>,
}

/// The JSON `--json` prints and `--out` writes.
#[derive(Serialize)]
struct ReferenceReport<'a> {
    material: &'a str,
    model: String,
    g2: String,
    interfaces: String,
    /// Each boundary in words, by the index the samples' flows use.
    boundaries: Vec<String>,
    paths: u64,
    seed: u64,
    /// Centres of the plane-of-incidence bins, signed θ_o in degrees (positive: mirror side).
    slice_theta_deg: Vec<f64>,
    slice_azimuth_half_width_deg: f64,
    hemisphere_rings: usize,
    hemisphere_sectors: usize,
    samples: &'a [Reference],
}

pub fn run(args: &ReferenceArgs) -> Result<()> {
    let stack = Stack::resolve(&args.material)?;
    stack.require_uniform("`lamina reference`")?;
    let cosines = args.cos.checked()?;
    let settings = settings(args, stack.model)?;
    let (g2, interfaces) = (settings.g2, settings.interfaces);
    let layers = stack.params();
    let walker = Walker::new(&layers, settings.media, g2, interfaces);
    let boundaries: Vec<String> = (0..=layers.len()).map(|b| walker.describe(b)).collect();
    let bar = ProgressBar::new(args.paths * cosines.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix:>12} [{bar:30}] {human_pos}/{human_len} paths per channel ({elapsed}, ETA {eta})",
        )
        .expect("a valid template")
        .progress_chars("=> "),
    );
    bar.set_prefix("reference");
    let stop = stop_on_interrupt();
    let mut samples = Vec::with_capacity(cosines.len());
    for (j, &mu) in cosines.iter().enumerate() {
        let before = j as u64 * args.paths;
        let mut progress = |paths: u64| bar.set_position(before + paths);
        let result = reference::simulate(&layers, &settings, mu, &mut progress, stop)?;
        let Some(result) = result else {
            bar.abandon();
            anyhow::bail!(
                "interrupted after {} of {} paths per channel; nothing was written",
                bar.position(),
                bar.length().unwrap_or(0)
            );
        };
        samples.push(result);
    }
    bar.finish_and_clear();
    let report = ReferenceReport {
        material: &stack.name,
        model: stack.model.to_string(),
        g2: g2.to_string(),
        interfaces: interfaces.to_string(),
        boundaries: boundaries.clone(),
        paths: args.paths,
        seed: args.seed,
        slice_theta_deg: (0..reference::SLICE_BINS)
            .map(|i| {
                let (a, b) = reference::slice_bin_edges(i);
                (0.5 * (a + b)).to_degrees()
            })
            .collect(),
        slice_azimuth_half_width_deg: reference::SLICE_HALF_WIDTH_DEG,
        hemisphere_rings: reference::HEMISPHERE_RINGS,
        hemisphere_sectors: reference::HEMISPHERE_SECTORS,
        samples: &samples,
    };
    let json = serde_json::to_string_pretty(&report)?;
    if let Some(path) = &args.out {
        write_file_atomically(path, format!("{json}\n"))?;
    }
    if args.json {
        println!("{json}");
    } else {
        print!("{}", table(&stack.name, interfaces, &samples));
        if args.tally {
            print!("{}", flows_table(&boundaries, &samples));
        }
    }
    Ok(())
}

/// The walk's settings from the arguments, checked.
fn settings(args: &ReferenceArgs, model: Model) -> Result<Settings> {
    let g2 = G2::parse_value(&args.g2).context("--g2")?;
    let interfaces = Interfaces::parse_value(&args.interfaces).context("--interfaces")?;
    if interfaces == Interfaces::Multiple && g2 != G2::HeightCorrelated {
        anyhow::bail!(
            "--g2 {g2} with --interfaces multiple: the microsurface walk's masking is Smith's \
             height-correlated form; --g2 chooses the masking of --interfaces single"
        );
    }
    let settings = Settings {
        paths: args.paths,
        seed: args.seed,
        g2,
        interfaces,
        media: model == Model::Tm6,
    };
    settings.check()?;
    Ok(settings)
}

/// R and T per view cosine with their standard errors.
fn table(name: &str, interfaces: Interfaces, samples: &[Reference]) -> String {
    let mut out = format!("{name}: stochastic reference, interfaces={interfaces}\n");
    let rgb = |e: &reference::Estimate| {
        (0..3)
            .map(|c| format!("{:.4}±{:.4}", e.mean[c], e.std_error[c]))
            .collect::<Vec<_>>()
            .join(" ")
    };
    for s in samples {
        out.push_str(&format!(
            "cos θ {:.3} ({} paths per channel)\n  R  {}\n  T  {}\n",
            s.cos_theta,
            s.paths,
            rgb(&s.reflectance),
            rgb(&s.transmittance)
        ));
        // The slice at every fifth bin (10°), mean of RGB: the lobe's shape at a glance.
        let slice: Vec<String> = (0..reference::SLICE_BINS)
            .step_by(5)
            .map(|i| {
                let (a, b) = reference::slice_bin_edges(i);
                let f = s.slice[i].mean.iter().sum::<f64>() / 3.0;
                format!("{:+.0}° {f:.3}", (0.5 * (a + b)).to_degrees())
            })
            .collect();
        out.push_str(&format!(
            "  BRDF in the plane of incidence (1/sr, mean RGB; + mirror side): {}\n",
            slice.join(", ")
        ));
        if s.unresolved.iter().any(|&u| u > 0.0) {
            out.push_str(&format!(
                "  unresolved (paths past {} events) {:.2e} {:.2e} {:.2e}\n",
                reference::walk::MAX_EVENTS,
                s.unresolved[0],
                s.unresolved[1],
                s.unresolved[2]
            ));
        }
    }
    out
}

/// The flows per view cosine: per boundary, side and order, the energy arriving (per unit of
/// incident energy, mean of RGB) and the shares of it sent back, passed and lost.
fn flows_table(boundaries: &[String], samples: &[Reference]) -> String {
    let mean = |v: [f64; 3]| (v[0] + v[1] + v[2]) / 3.0;
    let mut out = String::from(
        "energy at each boundary per crossing order (mean RGB; shares of what arrives)\n",
    );
    for s in samples {
        out.push_str(&format!(
            "cos θ {:.3}\n  {:<36} {:<10} {:>5} {:>9} {:>10} {:>8} {:>8}\n",
            s.cos_theta, "boundary", "arrives", "order", "arriving", "sent back", "passed", "lost"
        ));
        for row in &s.flows {
            let a = mean(row.flow.arriving);
            let share = |v: [f64; 3]| 100.0 * mean(v) / a;
            let from = match row.from {
                Side::Above => "from above",
                Side::Below => "from below",
            };
            out.push_str(&format!(
                "  {:<36} {:<10} {:>5} {:>9.4} {:>9.1}% {:>7.1}% {:>7.1}%\n",
                boundaries.get(row.boundary).map_or("?", String::as_str),
                from,
                row.order,
                a,
                share(row.flow.sent_back),
                share(row.flow.passed),
                share(row.flow.lost)
            ));
        }
    }
    out
}
