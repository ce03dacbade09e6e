//! Deterministic counters: the instructions the CPU executes while lavapipe runs one shaded
//! draw, counted by `valgrind --tool=callgrind` (DESIGN.md §7). Timestamps on lavapipe are CPU
//! wall-clock and drift up to 2× between runs; instruction counts repeat to ~1e-5, so CI gates on
//! them.
//!
//! The parent ([`count_instructions`]) runs `lamina count-worker` under callgrind with
//! instrumentation off; the worker ([`super::count_worker::worker`]) builds everything natively (environment, tables,
//! pipelines), renders each case once more to let llvmpipe JIT its fragment shader, then switches
//! instrumentation on around the shaded draw's submission only and dumps the count under the
//! case's name. The parent reads the dumps back.
//!
//! A draw's count carries costs that do not grow with the pixels it shades: vertex shading,
//! triangle setup, the blocks a triangle edge crosses. The worker therefore draws every case at
//! two sizes ([`CounterSizes`]), and [`count_plans`] divides the difference of the two counts by
//! the difference of the shaded pixels: instructions per additional shaded pixel, in which the
//! fixed costs cancel (profiling/README.md).

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::Sender;

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::render::lights::Lighting;
use crate::render::scene::{Camera, Scene};
use crate::size::Size;
use crate::variant::VariantKey;

use super::count_worker::{run_worker, scratch_dir};
use super::plan::{Case, Plan};
use super::prebuild;
use super::results::{CaseCounts, CounterInfo, Counts};

/// The two resolutions every case is counted at, the smaller first (`--counter-sizes
/// 48x48,96x96`, `counter_sizes = ["48x48", "96x96"]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CounterSizes {
    pub small: Size,
    pub large: Size,
}

impl CounterSizes {
    pub const DEFAULT: Self = Self {
        small: Size {
            width: 48,
            height: 48,
        },
        large: Size {
            width: 96,
            height: 96,
        },
    };

    /// Refuses a pair whose second size has no more pixels than the first: the per-pixel
    /// count divides by the difference.
    pub fn new(small: Size, large: Size) -> std::result::Result<Self, String> {
        let (a, b) = (pixels(small), pixels(large));
        if a == b {
            return Err(format!(
                "{small} and {large} both have {a} pixels; the per-pixel count divides by the \
                 difference, give two sizes with different pixel counts"
            ));
        }
        if b < a {
            return Err(format!(
                "{small} has more pixels than {large}; give the smaller size first"
            ));
        }
        Ok(Self { small, large })
    }

    pub fn both(self) -> [Size; 2] {
        [self.small, self.large]
    }
}

fn pixels(size: Size) -> u64 {
    u64::from(size.width) * u64::from(size.height)
}

impl FromStr for CounterSizes {
    type Err = String;

    /// `WxH,WxH`, the smaller first.
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        let parts: Vec<&str> = text.split(',').collect();
        let [small, large] = parts[..] else {
            return Err(format!(
                "`{text}` is not two sizes SMALL,LARGE, e.g. 48x48,96x96"
            ));
        };
        let parse = |part: &str| part.trim().parse::<Size>().map_err(|e| e.to_string());
        Self::new(parse(small)?, parse(large)?)
    }
}

impl fmt::Display for CounterSizes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{},{}", self.small, self.large)
    }
}

/// How a run starts `lamina count-worker` under callgrind: which executable, with which global
/// arguments, on which environment map.
pub struct CounterSetup {
    pub exe: PathBuf,
    pub global_args: Vec<String>,
    pub env_map: PathBuf,
}

impl CounterSetup {
    /// The counter's device policy. Refused off a CPU device (lavapipe): the counter counts CPU
    /// instructions, which measure a shader only where the CPU runs it. The worker is this
    /// executable on the same device (by name) and environment map, and runs without the
    /// validation layer even when this run has it: the layer's hooks on the counted submission
    /// would be counted too. Its Vulkan work is the same as the (validated) timing run's.
    pub fn for_device(gpu: &Gpu, env_map: &Path) -> Result<Self> {
        let report = &gpu.device.report;
        if !report.device_type.eq_ignore_ascii_case("cpu") {
            return Err(Error::Unsupported(format!(
                "--counter instructions counts the CPU instructions lavapipe executes; the \
                 selected device `{}` is of type {} (choose lavapipe with --device llvmpipe, or \
                 drop the counter)",
                report.name, report.device_type
            )));
        }
        let exe = std::env::current_exe()
            .map_err(|e| Error::Unsupported(format!("locating the lamina executable: {e}")))?;
        Ok(Self {
            exe,
            global_args: vec!["--device".to_string(), report.name.clone()],
            env_map: env_map.to_owned(),
        })
    }
}

/// Counts the instructions of every case of `plans` at both `sizes`, in one pool of workers
/// (a suite's studies: each worker starts once and compiles each shader once), with `scene`'s
/// mesh under `lighting`: where the counts were taken, and per plan one [`CaseCounts`] per
/// case, in plan order ([`count_pools`] with one pool).
pub fn count_plans(
    plans: &[&Plan],
    setup: &CounterSetup,
    scene: Scene,
    lighting: &Lighting,
    sizes: CounterSizes,
    progress: impl FnMut(usize, usize),
) -> Result<PoolCounts> {
    let pool = Pool {
        plans: plans.to_vec(),
        scene,
        env: None,
        lighting,
        sizes,
    };
    let mut counts = count_pools(std::slice::from_ref(&pool), setup, progress)?;
    Ok(counts.remove(0))
}

/// Plans counted with one scene, environment, lighting and pair of sizes: a worker draws one of
/// each.
pub struct Pool<'a> {
    pub plans: Vec<&'a Plan>,
    pub scene: Scene,
    /// The environment map the worker lights with; `None`: the setup's.
    pub env: Option<&'a Path>,
    pub lighting: &'a Lighting,
    pub sizes: CounterSizes,
}

/// What a pool's counts are: where they were taken, and per plan one [`CaseCounts`] per case,
/// in plan order.
pub type PoolCounts = (CounterInfo, Vec<Vec<CaseCounts>>);

/// Counts every case of every pool at the pool's two sizes, the workers of all pools in one
/// queue ([`count_requests`]): per pool, the whole-draw counts at each size and the JIT
/// instructions per shaded pixel (the difference of the two counts over the difference of the
/// pixels the scene shades, [`Scene::shaded_pixels`]).
pub fn count_pools(
    pools: &[Pool<'_>],
    setup: &CounterSetup,
    progress: impl FnMut(usize, usize),
) -> Result<Vec<PoolCounts>> {
    // The renderers of the bench and of the worker look through the default camera.
    let camera = Camera::default();
    let mut shaded = Vec::with_capacity(pools.len());
    for pool in pools {
        let [small, large] = pool
            .sizes
            .both()
            .map(|s| pool.scene.shaded_pixels(&camera, s.width, s.height));
        if large <= small {
            return Err(Error::Unsupported(format!(
                "the {} scene shades {small} pixels at {} and {large} at {}: no per-pixel \
                 difference to count; give a larger second counter size",
                pool.scene, pool.sizes.small, pool.sizes.large
            )));
        }
        shaded.push([small, large]);
    }
    let cases: Vec<Vec<Case>> = pools
        .iter()
        .map(|p| {
            p.plans
                .iter()
                .flat_map(|plan| plan.cases().iter().cloned())
                .collect()
        })
        .collect();
    let lighting: Vec<Option<String>> = pools
        .iter()
        .map(|p| (*p.lighting != Lighting::default()).then(|| p.lighting.to_toml()))
        .collect();
    let sizes: Vec<[Size; 2]> = pools.iter().map(|p| p.sizes.both()).collect();
    let requests: Vec<CountRequest<'_>> = (0..pools.len())
        .map(|i| CountRequest {
            exe: &setup.exe,
            global_args: setup.global_args.clone(),
            env_map: pools[i].env.unwrap_or(&setup.env_map),
            cases: &cases[i],
            scene: pools[i].scene,
            lighting: lighting[i].as_deref(),
            sizes: &sizes[i],
        })
        .collect();
    let counts = count_requests(&requests, progress)?;
    Ok(pools
        .iter()
        .zip(shaded)
        .zip(counts)
        .map(|((pool, shaded), counts)| per_plan(pool, shaded, counts))
        .collect())
}

/// A pool's counts (`counts[case][size]`, its plans' cases in order) split per plan, with the
/// instructions per added shaded pixel.
fn per_plan(pool: &Pool<'_>, shaded_pixels: [u64; 2], counts: Vec<Vec<Counts>>) -> PoolCounts {
    let added_pixels = (shaded_pixels[1] - shaded_pixels[0]) as f64;
    let mut counts = counts.into_iter().map(|count| {
        let [small, large] = count[..] else {
            unreachable!("count_requests answers one count per size");
        };
        CaseCounts {
            small,
            large,
            per_pixel: (large.jit as f64 - small.jit as f64) / added_pixels,
        }
    });
    let per_plan = pool
        .plans
        .iter()
        .map(|plan| counts.by_ref().take(plan.cases().len()).collect())
        .collect();
    let info = CounterInfo {
        sizes: pool.sizes.both().map(|s| [s.width, s.height]),
        shaded_pixels,
    };
    (info, per_plan)
}

/// What the parent needs to start the worker.
pub struct CountRequest<'a> {
    /// The `lamina` executable (the worker is its hidden `count-worker` subcommand).
    pub exe: &'a Path,
    /// Arguments placed before the subcommand (`--device …`).
    pub global_args: Vec<String>,
    pub env_map: &'a Path,
    pub cases: &'a [Case],
    pub scene: Scene,
    /// The lighting file's text (`Lighting::to_toml`); `None`: the environment alone.
    pub lighting: Option<&'a str>,
    /// The resolutions each case is drawn and counted at, in order.
    pub sizes: &'a [Size],
}

/// Counts the instructions of each case's shaded draw at each size: `counts[case][size]`;
/// `progress(done, total)` follows the workers. Every case gets a count at every size or the
/// whole call fails ([`count_requests`] with one request).
pub fn count_instructions(
    request: &CountRequest<'_>,
    progress: impl FnMut(usize, usize),
) -> Result<Vec<Vec<Counts>>> {
    let mut counts = count_requests(std::slice::from_ref(request), progress)?;
    Ok(counts.remove(0))
}

/// Counts every request's cases: per request, `counts[case][size]`; `progress(done, total)`
/// follows the workers over all requests.
///
/// The cases' tables and SPIR-V are built first natively (`prebuild`): under valgrind each
/// worker would build them some fifty times slower. Each request's cases are then shared out
/// over one worker per core (each worker runs llvmpipe on one thread, `LP_NUM_THREADS=0`):
/// most of a worker's time is llvmpipe compiling shaders under valgrind, which the count
/// leaves out, so the cases of one shader go to one worker (`shader_groups`). The workers of
/// all requests wait in one queue, the largest first, and one runs per core: a core a request's
/// first worker leaves goes to the next worker in the queue, not idle until its other workers
/// end. A count does not depend on the worker that takes it (the gate test counts one case
/// twice).
pub fn count_requests(
    requests: &[CountRequest<'_>],
    progress: impl FnMut(usize, usize),
) -> Result<Vec<Vec<Vec<Counts>>>> {
    let Some(first) = requests.first() else {
        return Ok(Vec::new());
    };
    let mut variants: Vec<VariantKey> = Vec::new();
    for case in requests.iter().flat_map(|r| r.cases) {
        if !variants.contains(&case.variant) {
            variants.push(case.variant);
        }
    }
    prebuild::run(first.exe, &first.global_args, &variants)?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut jobs: Vec<Job> = Vec::new();
    for (r, request) in requests.iter().enumerate() {
        let workers = cores.min(request.cases.len()).max(1);
        for share in shader_groups(request.cases, workers) {
            jobs.push(Job {
                request: r,
                cases: share.iter().map(|&i| request.cases[i].clone()).collect(),
                indices: share,
            });
        }
    }
    jobs.sort_by_key(|job| std::cmp::Reverse(job.indices.len()));
    let outcomes = run_jobs(requests, &jobs, cores, progress);
    let mut counts: Vec<Vec<Vec<Counts>>> = requests
        .iter()
        .map(|r| vec![Vec::new(); r.cases.len()])
        .collect();
    for (job, outcome) in jobs.iter().zip(outcomes) {
        for (&i, count) in job.indices.iter().zip(outcome?) {
            counts[job.request][i] = count;
        }
    }
    Ok(counts)
}

/// One worker's share of a request: the cases (of whole shaders) and their indices in it.
struct Job {
    request: usize,
    indices: Vec<usize>,
    cases: Vec<Case>,
}

/// Runs `jobs` in order, at most `runners` workers at a time; per job its counts, or the error
/// that stopped it (after a failure no new worker starts: the jobs not begun answer that a
/// worker before them failed).
fn run_jobs(
    requests: &[CountRequest<'_>],
    jobs: &[Job],
    runners: usize,
    mut progress: impl FnMut(usize, usize),
) -> Vec<Result<Vec<Vec<Counts>>>> {
    let total: usize = jobs
        .iter()
        .map(|job| job.indices.len() * requests[job.request].sizes.len())
        .sum();
    let next = AtomicUsize::new(0);
    let (tx, rx) = std::sync::mpsc::channel::<(usize, usize)>();
    let mut outcomes: Vec<Option<Result<Vec<Vec<Counts>>>>> = Vec::new();
    outcomes.resize_with(jobs.len(), || None);
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..runners.clamp(1, jobs.len().max(1)))
            .map(|_| {
                let (tx, next) = (tx.clone(), &next);
                scope.spawn(move || {
                    let mut mine = Vec::new();
                    loop {
                        let j = next.fetch_add(1, Ordering::SeqCst);
                        let Some(job) = jobs.get(j) else { break };
                        let outcome = run_job(&requests[job.request], job, j, &tx);
                        if outcome.is_err() {
                            next.store(jobs.len(), Ordering::SeqCst);
                        }
                        mine.push((j, outcome));
                    }
                    mine
                })
            })
            .collect();
        drop(tx);
        let mut done = vec![0; jobs.len()];
        progress(0, total);
        for (j, n) in rx {
            done[j] = n;
            progress(done.iter().sum(), total);
        }
        for h in handles {
            for (j, outcome) in h.join().expect("a counter thread only returns") {
                outcomes[j] = Some(outcome);
            }
        }
    });
    outcomes
        .into_iter()
        .map(|o| {
            o.unwrap_or_else(|| {
                Err(Error::Unsupported(
                    "not counted: a counting worker before it failed".into(),
                ))
            })
        })
        .collect()
}

/// Runs one job's worker (`index` names its scratch directory and its progress messages).
fn run_job(
    request: &CountRequest<'_>,
    job: &Job,
    index: usize,
    tx: &Sender<(usize, usize)>,
) -> Result<Vec<Vec<Counts>>> {
    let part = CountRequest {
        exe: request.exe,
        global_args: request.global_args.clone(),
        env_map: request.env_map,
        cases: &job.cases,
        scene: request.scene,
        lighting: request.lighting,
        sizes: request.sizes,
    };
    let dir = scratch_dir(index)?;
    let result = run_worker(&part, &dir, &mut |done, _| {
        let _ = tx.send((index, done));
    });
    // The dumps are read (or the run failed); nothing in the directory is kept.
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// The indices of `cases` shared out over `workers`: the cases of one shader together — one
/// pass's specialization constants and defines, so that `mode=specialized` at two
/// `max_layers` (one pipeline's code) compiles once, in one worker — the largest groups first,
/// each to the worker with the fewest cases so far. The same shader compiled in two workers
/// can differ by a few executed instructions (seen: 3 of 4.26 M), so the equal counts the
/// gates expect of one shader come from one worker.
fn shader_groups(cases: &[Case], workers: usize) -> Vec<Vec<usize>> {
    let shader = |c: &Case| match c.pass_key(&Lighting::default()) {
        Ok(key) => {
            let spec = key.spec(None);
            format!("{:?}|{:?}", c.variant.defines(), bytemuck::bytes_of(&spec))
        }
        Err(_) => c.variant.to_string(),
    };
    let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, case) in cases.iter().enumerate() {
        let key = shader(case);
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, members)) => members.push(i),
            None => groups.push((key, vec![i])),
        }
    }
    groups.sort_by_key(|(_, members)| std::cmp::Reverse(members.len()));
    let mut shares: Vec<Vec<usize>> = vec![Vec::new(); workers.max(1)];
    for (_, members) in groups {
        let emptiest = (0..shares.len())
            .min_by_key(|&w| shares[w].len())
            .expect("at least one worker");
        shares[emptiest].extend(members);
    }
    shares.retain(|s| !s.is_empty());
    shares
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counter_sizes_parse_and_bad_pairs_are_named() {
        let sizes: CounterSizes = "48x48, 96x96".parse().unwrap();
        assert_eq!(sizes, CounterSizes::DEFAULT);
        assert_eq!(sizes.to_string(), "48x48,96x96");
        assert_eq!(
            "16x16,32x9".parse::<CounterSizes>().unwrap().large.height,
            9
        );
        for (text, words) in [
            ("48x48,48x48", vec!["2304 pixels", "different pixel counts"]),
            ("32x64,64x32", vec!["both have 2048 pixels"]),
            ("96x96,48x48", vec!["smaller size first"]),
            ("48x48", vec!["SMALL,LARGE", "`48x48`"]),
            ("16x16,32x32,64x64", vec!["SMALL,LARGE"]),
            ("0x16,32x32", vec!["width", "1..=16384"]),
            ("16x16,32x99999", vec!["height", "1..=16384"]),
        ] {
            let e = text.parse::<CounterSizes>().unwrap_err();
            for w in words {
                assert!(e.contains(w), "{text}: `{w}` missing from {e}");
            }
        }
    }
}
