//! `lamina sweep`: a study file or a suite (`lamina::study`) — its cases listed, run
//! interleaved, written as results, charts and a report.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use indicatif::ProgressBar;
use lamina::imageio;
use lamina::profile::counter::CounterSetup;
use lamina::study::run::{run_suite, Event, SuiteRun};
use lamina::study::{self, report, shard};

use super::args::{CounterArg, EnvArg};
use super::{asset_path, progress_bar, studies, GlobalArgs};

#[derive(clap::Args)]
pub struct SweepArgs {
    /// A study or a suite (`studies = [...]`), e.g. profiling/sweeps/reproduce.toml.
    file: PathBuf,
    /// Output directory: results of one study go here, a suite's in one sub-directory per study.
    #[arg(long, value_name = "DIR", default_value = "out/sweep")]
    out: PathBuf,
    /// Count instructions too (overrides the sweep file's `counter`).
    #[arg(long, value_enum)]
    counter: Option<CounterArg>,
    /// Run only these studies of a suite (repeatable; names as the suite's plan lists them).
    #[arg(long, value_name = "NAME")]
    study: Vec<String>,
    #[command(flatten)]
    env: EnvArg,
    /// Check and expand the file, print the cases, and stop before any GPU work.
    #[arg(long)]
    dry_run: bool,
    /// Run shard K of N (1 ≤ K ≤ N): every N-th point of each study from the K-th, the ggx
    /// baselines they need, every N-th reference material; the output is a complete results
    /// directory that `lamina merge` joins with the other shards'.
    #[arg(long, value_name = "K/N")]
    shard: Option<shard::Shard>,
}

pub fn run(global: &GlobalArgs, args: &SweepArgs) -> Result<()> {
    let (mut list, suite) = study::load(&args.file)?;
    if !args.study.is_empty() {
        select_studies(&args.file, &mut list, &args.study)?;
    }
    if let Some(s) = args.shard {
        list.iter_mut().for_each(|study| shard::apply(study, s));
    }
    match args.counter {
        Some(CounterArg::Instructions) => {
            list.iter_mut().for_each(study::Study::count_instructions)
        }
        Some(CounterArg::None) => list.iter_mut().for_each(|s| s.counter = None),
        None => {}
    }
    // Lighting arguments replace every study's `lights`.
    if args.env.lights.given() {
        let lighting = args.env.lights.lighting()?;
        list.iter_mut().for_each(|s| s.lighting = lighting.clone());
    }
    let dir_of = |s: &study::Study| study::output_dir(&args.out, s, suite);
    print_plan(args, &list, &dir_of);
    if args.dry_run {
        for s in &list {
            println!("{}:", s.name);
            if let Some(r) = &s.reference {
                for c in &r.cases {
                    println!("  reference | {} | {}", c.variant, c.stack.name);
                }
            }
            for p in &s.points {
                println!("  {} | {}", p.case.variant, p.case.stack.name);
            }
        }
        return Ok(());
    }
    let env_path = asset_path(&args.env.env);
    let equirect = imageio::read_exr(&env_path).context("reading the environment map")?;
    let gpu = global.open_gpu()?;
    let setup = if list.iter().any(|s| s.counter.is_some()) {
        Some(CounterSetup::for_device(&gpu, &env_path)?)
    } else {
        None
    };
    let started = std::time::Instant::now();
    let mut bar = Follow::new();
    let written = run_suite(
        &SuiteRun {
            gpu: &gpu,
            equirect: &equirect,
            counter: setup.as_ref(),
            validation: global.validation,
            out: &args.out,
            suite,
        },
        &list,
        &mut |event| show(event, &mut bar),
    )?;
    let report_path = args.out.join("REPORT.md");
    report::write(&written, &report_path)?;
    println!(
        "\n{} in {:.0} s; report: {}",
        studies(list.len()),
        started.elapsed().as_secs_f64(),
        report_path.display()
    );
    Ok(())
}

/// How far the running phase is: a progress bar on a terminal; elsewhere (a CI log, a batch
/// job's file) a line on stderr when a step begins and at most every [`PLAIN_EVERY`] within
/// it, so a long phase never runs silent.
struct Follow {
    bar: Option<ProgressBar>,
    plain: bool,
    /// The phase's name, and the step and time of the last line printed.
    phase: String,
    last: Option<(String, Instant)>,
}

/// How often a plain progress line repeats within one step.
const PLAIN_EVERY: Duration = Duration::from_secs(60);

impl Follow {
    fn new() -> Self {
        Self {
            bar: None,
            plain: !std::io::stderr().is_terminal(),
            phase: String::new(),
            last: None,
        }
    }

    fn begin(&mut self, phase: String) {
        self.bar = Some(progress_bar(&phase));
        self.phase = phase;
        self.last = None;
    }

    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }

    fn progress(&mut self, what: &str, done: usize, total: usize) {
        if let Some(bar) = &self.bar {
            bar.set_message(what.to_owned());
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        }
        if !self.plain {
            return;
        }
        let due = match &self.last {
            Some((step, at)) => step != what || at.elapsed() >= PLAIN_EVERY,
            None => true,
        };
        if due {
            let took = self.bar.as_ref().map_or(0, |b| b.elapsed().as_secs());
            eprintln!("  {}: {what} {done}/{total} ({took} s)", self.phase);
            self.last = Some((what.to_owned(), Instant::now()));
        }
    }
}

/// Prints what the suite's run does: its progress per phase ([`Follow`]), a line per phase
/// done, each study's table once written.
fn show(event: Event<'_>, bar: &mut Follow) {
    match event {
        Event::Prebuilt(Ok(took)) => println!(
            "  built or loaded the tables on every core in {:.1} s",
            took.as_secs_f64()
        ),
        Event::Prebuilt(Err(e)) => {
            eprintln!("warning: {e}; the studies build their tables themselves")
        }
        Event::Timing {
            index,
            count,
            study,
        } => bar.begin(format!("[{}/{}] {}", index + 1, count, study.name)),
        Event::Progress { what, done, total } => bar.progress(what, done, total),
        Event::Timed { study, took } => {
            bar.finish();
            println!("  timed {} in {:.1} s", study.name, took.as_secs_f64());
        }
        Event::Counting => bar.begin("instructions (callgrind)".to_owned()),
        Event::Counted { took } => {
            bar.finish();
            println!(
                "  counted instructions in {:.1} s (begun beside the timing)",
                took.as_secs_f64()
            );
        }
        Event::Written {
            study,
            results,
            dir,
            charts,
        } => {
            println!("\n== {} ({})", study.title, study.name);
            print!("{}", results.table());
            println!(
                "wrote {}/results.json, results.csv, {charts} chart(s)",
                dir.display()
            );
        }
    }
}

/// Keeps the studies `names` asks for, in the suite's order; a name the suite lacks is an
/// error that lists the suite's studies.
fn select_studies(file: &Path, list: &mut Vec<study::Study>, names: &[String]) -> Result<()> {
    if let Some(missing) = names.iter().find(|n| !list.iter().any(|s| &s.name == *n)) {
        let known: Vec<&str> = list.iter().map(|s| s.name.as_str()).collect();
        anyhow::bail!(
            "--study {missing}: {} has no such study (it has: {})",
            file.display(),
            known.join(", ")
        );
    }
    list.retain(|s| names.contains(&s.name));
    Ok(())
}

/// The studies and their cases, before anything runs.
fn print_plan(args: &SweepArgs, list: &[study::Study], dir_of: &dyn Fn(&study::Study) -> PathBuf) {
    let cases: usize = list.iter().map(|s| s.points.len()).sum();
    let share = args.shard.map_or(String::new(), |s| {
        format!(" in shard {}/{}", s.index, s.count)
    });
    println!(
        "{}: {}, {cases} case(s){share} (+ ggx baselines)",
        args.file.display(),
        studies(list.len())
    );
    for s in list {
        if let Some(r) = &s.reference {
            let random = if r.random.is_empty() {
                String::new()
            } else {
                format!(
                    " and {} random stack(s) ({} paths)",
                    r.random.len(),
                    r.random_paths
                )
            };
            let truths: Vec<String> = r.interfaces.iter().map(|i| i.to_string()).collect();
            println!(
                "  {:<22} {} material(s){random} against the stochastic reference ({}) at {} \
                 view cosine(s), {} paths per channel  -> {}",
                s.name,
                r.cases.len(),
                truths.join(", "),
                r.cosines.len(),
                r.paths,
                dir_of(s).display()
            );
            continue;
        }
        println!(
            "  {:<22} {:>3} case(s) at {}x{} {}, {}+{} frames{}{}  -> {}",
            s.name,
            s.points.len(),
            s.width,
            s.height,
            s.scene,
            s.warmup,
            s.frames,
            s.counter
                .map(|c| format!(", instructions at {} and {}", c.small, c.large))
                .unwrap_or_default(),
            if s.skipped.is_empty() {
                String::new()
            } else {
                format!(", {} skipped (stack > max_layers)", s.skipped.len())
            },
            dir_of(s).display()
        );
    }
}
