//! Running studies: a study's phases — its plan timed interleaved, its image errors, its
//! baked-table and reference comparisons ([`time`]), its instruction counts ([`count`], a
//! whole suite's in one pool of workers), its metadata ([`finish`]) — and a suite's run from
//! the first table to the report ([`run_suite`]), telling its caller what happens through
//! [`Event`]s.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio::HdrImage;
use crate::profile::bench::{self, BenchConfig};
use crate::profile::counter::{self, CounterSetup, CounterSizes};
use crate::profile::image_error::{self, ErrorMaps, References};
use crate::profile::plan::Plan;
use crate::profile::prebuild;
use crate::profile::results::Results;
use crate::reference::compare::MaterialReference;
use crate::render::lights::Lighting;
use crate::render::scene::Scene;
use crate::tables::environment::EnvDesc;
use crate::variant::Mode;

use super::meta::{BakeErrorRow, MaterialBakeError, StudyMeta};
use super::{output_dir, Point, ReferenceStudy, Study};

/// A study timed, its image errors and comparisons measured; its instructions not counted yet.
pub struct Timed {
    pub results: Results,
    pub bake_error: Vec<MaterialBakeError>,
    pub reference: Vec<MaterialReference>,
    /// `reference_spp`: each run's FLIP error map, by run index (the image errors themselves
    /// are in the results' runs).
    pub error_maps: ErrorMaps,
}

/// The first phase of a study: its plan timed interleaved on `gpu`, then the baked-table
/// error study, the reference comparisons and the image errors it asks for (against the
/// reference images in `references`, rendered there when missing); `progress(what, done,
/// total)` follows each.
pub fn time(
    gpu: &Gpu,
    equirect: &HdrImage,
    study: &Study,
    references: &mut References,
    progress: &mut impl FnMut(&str, usize, usize),
) -> Result<Timed> {
    let config = BenchConfig {
        plan: study.plan.clone(),
        scene: study.scene,
        width: study.width,
        height: study.height,
        frames: study.frames,
        warmup: study.warmup,
        lighting: study.lighting.clone(),
    };
    let mut results = bench::run(gpu, equirect, &config, |done, total| {
        progress("frames", done as usize, total as usize)
    })?;
    let bake_error = match &study.bake_error {
        Some((sizes, image_size)) => {
            bake_errors(gpu, equirect, study, sizes, *image_size, progress)?
        }
        None => Vec::new(),
    };
    let reference = match &study.reference {
        Some(spec) => reference_comparisons(spec, progress)?,
        None => Vec::new(),
    };
    let error_maps = match study.image_error_spp {
        Some(spp) => {
            let (errors, maps) =
                image_error::measure(gpu, equirect, &config, spp, references, progress)?;
            results.record_image_errors(&errors);
            maps
        }
        None => Vec::new(),
    };
    Ok(Timed {
        results,
        bake_error,
        reference,
        error_maps,
    })
}

/// Counts the instructions of every timed study that asks for them, in one pool of workers
/// per scene, counter sizes and lighting (so a suite starts its workers and compiles each
/// shader under valgrind once, not once per study). `studies[i]` was timed into `timed[i]`.
pub fn count(
    studies: &[Study],
    timed: &mut [Timed],
    setup: &CounterSetup,
    mut progress: impl FnMut(usize, usize),
) -> Result<()> {
    // One pool of workers per scene, counted sizes and lighting: a worker draws one of each.
    let mut groups: Vec<(Scene, CounterSizes, &Lighting)> = Vec::new();
    for s in studies {
        if let Some(sizes) = s.counter {
            let group = (s.scene, sizes, &s.lighting);
            if !groups.contains(&group) {
                groups.push(group);
            }
        }
    }
    let total: usize = studies
        .iter()
        .filter(|s| s.counter.is_some())
        .map(|s| s.plan.cases().len() * 2)
        .sum();
    let mut before = 0;
    for (scene, sizes, lighting) in groups {
        let members: Vec<usize> = (0..studies.len())
            .filter(|&i| {
                let s = &studies[i];
                s.scene == scene && s.counter == Some(sizes) && s.lighting == *lighting
            })
            .collect();
        let plans: Vec<&Plan> = members.iter().map(|&i| &studies[i].plan).collect();
        let here: usize = plans.iter().map(|p| p.cases().len() * 2).sum();
        let (info, counts) =
            counter::count_plans(&plans, setup, scene, lighting, sizes, |done, _| {
                progress(before + done, total)
            })?;
        for (&i, counts) in members.iter().zip(&counts) {
            timed[i].results.record_counts(info.clone(), counts);
        }
        before += here;
    }
    Ok(())
}

/// The last phase: the study's results and its metadata (counted when `counted` and the
/// study asks for counts).
pub fn finish(study: &Study, timed: Timed, counted: bool) -> (Results, StudyMeta) {
    let meta = StudyMeta::of(study, counted, timed.bake_error, timed.reference);
    (timed.results, meta)
}

/// A `[reference]` study: each material's model against the stochastic reference, on every
/// core.
fn reference_comparisons(
    spec: &ReferenceStudy,
    progress: &mut impl FnMut(&str, usize, usize),
) -> Result<Vec<MaterialReference>> {
    let per_material = spec.paths * spec.cosines.len() as u64;
    let total = per_material * spec.cases.len() as u64;
    let never = AtomicBool::new(false);
    let mut out = Vec::with_capacity(spec.cases.len());
    for (i, case) in spec.cases.iter().enumerate() {
        let before = i as u64 * per_material;
        let compared = crate::reference::compare::compare(
            &case.stack.name,
            &case.stack.params(),
            case.variant,
            &spec.cosines,
            (spec.paths, spec.seed),
            &mut |paths| progress("reference paths", (before + paths) as usize, total as usize),
            &never,
        )?
        .expect("a reference study is never stopped");
        out.push(compared);
    }
    Ok(out)
}

/// The baked-table error study of every material the study bakes (its first `mode=baked` run
/// per material).
fn bake_errors(
    gpu: &Gpu,
    equirect: &HdrImage,
    study: &Study,
    sizes: &[u32],
    image_size: u32,
    progress: &mut impl FnMut(&str, usize, usize),
) -> Result<Vec<MaterialBakeError>> {
    let mut baked: Vec<&Point> = Vec::new();
    for p in &study.points {
        if p.case.variant.mode == Mode::Baked
            && !baked.iter().any(|b| b.case.stack.name == p.case.stack.name)
        {
            baked.push(p);
        }
    }
    let mut out = Vec::with_capacity(baked.len());
    for (i, p) in baked.iter().enumerate() {
        progress("bake error", i, baked.len());
        let errors = crate::render::baked::error_study(
            gpu,
            equirect,
            EnvDesc::default(),
            p.case.variant,
            &p.case.stack.params(),
            sizes,
            image_size,
        )?;
        out.push(MaterialBakeError {
            material: p.case.stack.name.clone(),
            variant: p.case.variant,
            image_size,
            rows: errors
                .iter()
                .map(|e| BakeErrorRow {
                    size: e.size,
                    lobe_error: e.lobe_error,
                    image_error: e.image_error,
                })
                .collect(),
        });
    }
    progress("bake error", baked.len(), baked.len());
    Ok(out)
}

/// How a suite runs: on which device and environment, counted how (when any study counts),
/// written where.
pub struct SuiteRun<'a> {
    pub gpu: &'a Gpu,
    pub equirect: &'a HdrImage,
    /// The instruction counter's worker (`CounterSetup::for_device`), when a study counts.
    pub counter: Option<&'a CounterSetup>,
    /// Whether the run has the validation layer on (its table worker gets it too).
    pub validation: bool,
    /// The output directory: a lone study's files, or one sub-directory per study of a suite.
    pub out: &'a Path,
    pub suite: bool,
}

/// What [`run_suite`] is doing, for its caller to show.
pub enum Event<'a> {
    /// The tables were built (or loaded) on every core first, in this time; or that failed,
    /// and the studies build their tables themselves.
    Prebuilt(std::result::Result<Duration, Error>),
    /// Study `index` (of `count`) starts its timing phase.
    Timing {
        index: usize,
        count: usize,
        study: &'a Study,
    },
    /// Progress within a phase: `what` is being done, `done` of `total`.
    Progress {
        what: &'a str,
        done: usize,
        total: usize,
    },
    /// The study was timed (its image errors and comparisons measured too).
    Timed {
        study: &'a Study,
        took: Duration,
    },
    /// The instruction counts of every study that counts begin.
    Counting,
    Counted {
        took: Duration,
    },
    /// The study's directory was written, with this many charts.
    Written {
        study: &'a Study,
        results: &'a Results,
        dir: &'a Path,
        charts: usize,
    },
}

/// Runs `studies`: the tables prebuilt where that helps (`profile::prebuild`), every study
/// timed, then all the counts in one pool of workers (each worker starts once and compiles
/// each shader under valgrind once for the whole suite), then each study's directory written;
/// returns the directories. Fails at the first validation message.
pub fn run_suite(
    run: &SuiteRun<'_>,
    studies: &[Study],
    on: &mut dyn FnMut(Event<'_>),
) -> Result<Vec<PathBuf>> {
    let gpu = run.gpu;
    if prebuild::worthwhile(gpu) {
        on(Event::Prebuilt(prebuild_tables(run, studies)));
    }
    let mut timed = Vec::with_capacity(studies.len());
    let mut references = References::default();
    for (index, study) in studies.iter().enumerate() {
        on(Event::Timing {
            index,
            count: studies.len(),
            study,
        });
        let started = Instant::now();
        timed.push(time(
            gpu,
            run.equirect,
            study,
            &mut references,
            &mut |what, done, total| on(Event::Progress { what, done, total }),
        )?);
        check_validation(gpu)?;
        on(Event::Timed {
            study,
            took: started.elapsed(),
        });
    }
    if let Some(setup) = run.counter {
        on(Event::Counting);
        let started = Instant::now();
        count(studies, &mut timed, setup, |done, total| {
            on(Event::Progress {
                what: "counted",
                done,
                total,
            })
        })?;
        on(Event::Counted {
            took: started.elapsed(),
        });
    }
    let mut written = Vec::with_capacity(studies.len());
    for (study, timed) in studies.iter().zip(timed) {
        let mut timed = timed;
        let error_maps = std::mem::take(&mut timed.error_maps);
        let (results, meta) = finish(study, timed, run.counter.is_some());
        let dir = output_dir(run.out, study, run.suite);
        let charts = super::write::write(&dir, study, &results, &meta, &error_maps)?;
        on(Event::Written {
            study,
            results: &results,
            dir: &dir,
            charts: charts.len(),
        });
        written.push(dir);
    }
    Ok(written)
}

/// The tables of every study's variants, built by the table worker on every core.
fn prebuild_tables(run: &SuiteRun<'_>, studies: &[Study]) -> std::result::Result<Duration, Error> {
    let variants = prebuild::table_variants(
        studies
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.case.variant)),
    );
    let exe = std::env::current_exe()
        .map_err(|e| Error::Unsupported(format!("locating the lamina executable: {e}")))?;
    let mut worker_args = vec!["--device".to_owned(), run.gpu.device.report.name.clone()];
    if run.validation {
        worker_args.push("--validation".to_owned());
    }
    prebuild::run(&exe, &worker_args, &variants)
}

/// Fails when the validation layer reported anything so far.
fn check_validation(gpu: &Gpu) -> Result<()> {
    match gpu.device.validation_problems() {
        0 => Ok(()),
        problems => Err(Error::Unsupported(format!(
            "the validation layer reported {problems} problem(s); see the messages above"
        ))),
    }
}
