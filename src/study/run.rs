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
use crate::profile::calibrate::{calibrate, CalibrationSetup};
use crate::profile::counter::{self, CounterSetup, Pool};
use crate::profile::image_error::{self, ErrorMaps, References};
use crate::profile::prebuild;
use crate::profile::results::{CaseCounts, CounterInfo, Results};
use crate::reference::compare::MaterialReference;
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
                image_error::measure(gpu, equirect, &config, (spp, 0), references, progress)?;
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

/// What the counter measured of one study: where it counted, and one count per case of its
/// plan.
pub type StudyCounts = (CounterInfo, Vec<CaseCounts>);

/// Counts the instructions of every study that asks for them, in one pool of workers per
/// scene, environment, counter sizes and lighting (so a suite starts its workers and compiles each shader
/// under valgrind once, not once per study), the pools' workers in one queue: per study, its
/// counts, or `None` when it does not count. Needs only the studies' plans, so it may run
/// beside their timing.
pub fn count(
    studies: &[Study],
    setup: &CounterSetup,
    progress: impl FnMut(usize, usize),
) -> Result<Vec<Option<StudyCounts>>> {
    // One pool of workers per scene, environment, counted sizes and lighting: a worker draws
    // one of each. A study's own environment is counted under it: what `ibl=lamps` compiles
    // depends on the map's lamps.
    let mut pools: Vec<(Pool<'_>, Vec<usize>)> = Vec::new();
    for (i, s) in studies.iter().enumerate() {
        let Some(sizes) = s.counter else { continue };
        let env = s.env.as_deref();
        let same = |p: &Pool<'_>| {
            p.scene == s.scene && p.env == env && p.sizes == sizes && *p.lighting == s.lighting
        };
        match pools.iter_mut().find(|(p, _)| same(p)) {
            Some((pool, members)) => {
                pool.plans.push(&s.plan);
                members.push(i);
            }
            None => pools.push((
                Pool {
                    plans: vec![&s.plan],
                    scene: s.scene,
                    env,
                    lighting: &s.lighting,
                    sizes,
                },
                vec![i],
            )),
        }
    }
    let (pools, members): (Vec<Pool<'_>>, Vec<Vec<usize>>) = pools.into_iter().unzip();
    let counts = counter::count_pools(&pools, setup, progress)?;
    let mut out = vec![None; studies.len()];
    for ((info, per_plan), members) in counts.into_iter().zip(members) {
        for (i, plan_counts) in members.into_iter().zip(per_plan) {
            out[i] = Some((info.clone(), plan_counts));
        }
    }
    Ok(out)
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
    let cosines = spec.cosines.len() as u64;
    let per_truth = cosines
        * (spec.paths * spec.cases.len() as u64 + spec.random_paths * spec.random.len() as u64);
    let total = per_truth * spec.interfaces.len() as u64;
    let never = AtomicBool::new(false);
    let mut out =
        Vec::with_capacity((spec.cases.len() + spec.random.len()) * spec.interfaces.len());
    let mut before = 0;
    for &interfaces in &spec.interfaces {
        let named = spec.cases.iter().map(|c| (c, spec.paths, false));
        let random = spec.random.iter().map(|c| (c, spec.random_paths, true));
        for (case, paths, is_random) in named.chain(random) {
            let mut compared = crate::reference::compare::compare(
                &case.stack.name,
                &case.stack.params(),
                case.variant,
                interfaces,
                &spec.cosines,
                (paths, spec.seed),
                &mut |p| progress("reference paths", (before + p) as usize, total as usize),
                &never,
            )?
            .expect("a reference study is never stopped");
            if is_random {
                compared.random_stack = Some(case.stack.to_toml());
            }
            before += paths * cosines;
            out.push(compared);
        }
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
    Timed { study: &'a Study, took: Duration },
    /// Every study is timed; the instruction counts, begun beside the timing, go on.
    Counting,
    /// The counts are done, `took` after they began.
    Counted { took: Duration },
    /// The study's directory was written, with this many charts.
    Written {
        study: &'a Study,
        results: &'a Results,
        dir: &'a Path,
        charts: usize,
    },
}

/// Runs `studies`: the tables prebuilt where that helps (`profile::prebuild`), every study
/// timed and, beside the timing, all the counts in one pool of workers (each worker starts
/// once and compiles each shader under valgrind once for the whole suite; niced, so the timed
/// thread keeps its core), then each study's directory written; returns the directories.
/// Fails at the first validation message.
pub fn run_suite(
    run: &SuiteRun<'_>,
    studies: &[Study],
    on: &mut dyn FnMut(Event<'_>),
) -> Result<Vec<PathBuf>> {
    let gpu = run.gpu;
    if prebuild::worthwhile(gpu) {
        on(Event::Prebuilt(prebuild_tables(run, studies)));
    }
    // The counts need only the plans: they run beside the timing, their workers niced so that
    // the timed thread keeps its core (`profile::counter`), and both cores after it.
    let (timed, counts) = std::thread::scope(|scope| -> Result<_> {
        let (progress_tx, progress_rx) = std::sync::mpsc::channel();
        let started = Instant::now();
        let counting = run.counter.map(|setup| {
            scope.spawn(move || {
                count(studies, setup, |done, total| {
                    let _ = progress_tx.send((done, total));
                })
            })
        });
        let timed = time_all(run, studies, on)?;
        let Some(counting) = counting else {
            return Ok((timed, Vec::new()));
        };
        on(Event::Counting);
        for (done, total) in progress_rx {
            on(Event::Progress {
                what: "counted",
                done,
                total,
            });
        }
        let counts = counting.join().expect("the counting thread only returns")?;
        on(Event::Counted {
            took: started.elapsed(),
        });
        Ok((timed, counts))
    })?;
    // On a GPU, the calibration pair once for the suite: each timed study's report says what
    // a fragment timing stands for on the device (lavapipe's two paths are the same CPU).
    let on_gpu = !gpu.device.report.device_type.eq_ignore_ascii_case("cpu");
    let calibration = if on_gpu && studies.iter().any(|s| s.reference.is_none()) {
        Some(calibrate(gpu, CalibrationSetup::default())?)
    } else {
        None
    };
    let mut written = Vec::with_capacity(studies.len());
    for (i, (study, timed)) in studies.iter().zip(timed).enumerate() {
        let mut timed = timed;
        if let Some(Some((info, counts))) = counts.get(i) {
            timed.results.record_counts(info.clone(), counts);
        }
        if study.reference.is_none() {
            timed.results.calibration.clone_from(&calibration);
        }
        let error_maps = std::mem::take(&mut timed.error_maps);
        let (results, meta) = finish(study, timed, run.counter.is_some());
        let dir = output_dir(run.out, study, run.suite);
        let charts = super::write::write(&dir, &study.source_text, &results, &meta, &error_maps)?;
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

/// Every study's timing phase ([`time`]), in order, the reference images shared; fails at
/// the first validation message.
fn time_all(
    run: &SuiteRun<'_>,
    studies: &[Study],
    on: &mut dyn FnMut(Event<'_>),
) -> Result<Vec<Timed>> {
    let mut timed = Vec::with_capacity(studies.len());
    let mut references = References::default();
    for (index, study) in studies.iter().enumerate() {
        on(Event::Timing {
            index,
            count: studies.len(),
            study,
        });
        let started = Instant::now();
        let mut progress = |what: &str, done, total| on(Event::Progress { what, done, total });
        timed.push(match &study.env {
            // Its own environment, and its own references.
            Some(path) => {
                let equirect = crate::imageio::read_exr(path)
                    .map_err(|e| Error::Unsupported(format!("study `{}`: env: {e}", study.name)))?;
                let mut own = References::default();
                let mut t = time(run.gpu, &equirect, study, &mut own, &mut progress)?;
                t.results.environment = path.file_name().map(|n| n.to_string_lossy().into_owned());
                t
            }
            None => time(run.gpu, run.equirect, study, &mut references, &mut progress)?,
        });
        check_validation(run.gpu)?;
        on(Event::Timed {
            study,
            took: started.elapsed(),
        });
    }
    Ok(timed)
}

/// The tables of every study's variants, built by the table worker on every core.
fn prebuild_tables(run: &SuiteRun<'_>, studies: &[Study]) -> std::result::Result<Duration, Error> {
    let variants = prebuild::table_variants(
        studies
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.case.variant)),
    );
    // A reference study alone shades nothing: there is nothing to build.
    if variants.is_empty() {
        return Ok(Duration::ZERO);
    }
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
