//! The counting worker, both sides of its process boundary: `lamina count-worker` ([`worker`])
//! runs under `valgrind --tool=callgrind --instr-atstart=no`, draws each case of its job and
//! switches instrumentation on around the shaded draw's submission only, dumping the count
//! under the case's name; the parent (`run_worker`) writes the job file, starts the worker
//! at the lowest priority, follows its progress and reads the dumps back. What is counted and
//! how the workers are shared out is `super::counter`'s.

use std::ffi::CString;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::imageio::HdrImage;
use crate::material::Stack;
use crate::render::lights::Lighting;
use crate::render::scene::Scene;
use crate::render::{PassCache, Renderer, ShadedPhase};
use crate::size::Size;
use crate::tables::environment::EnvDesc;

use super::bench::place_scene;
use super::callgrind;
use super::counter::CountRequest;
use super::plan::Case;
use super::results::Counts;

/// The environment the worker prefilters: small, because the worker runs under valgrind and
/// the prefilter is not what is counted. The shaded draw's code path does not depend on the
/// cube's size (one trilinear fetch per lobe whatever the mip count).
pub const WORKER_ENV: EnvDesc = EnvDesc {
    face_size: 64,
    mip_count: 7,
    samples: 16,
};

/// Prefix of the dump names, followed by `CASE-SIZE`: the indices of the case and of the size.
const DUMP_PREFIX: &str = "lamina-case-";
/// The line the worker prints on stderr after each case, read by the parent for progress.
const PROGRESS_PREFIX: &str = "lamina-counted ";

/// Runs in `lamina count-worker`: every case drawn and counted at each of `sizes`, in that
/// order, with `scene`'s mesh.
pub fn worker(
    gpu: &Gpu,
    equirect: &HdrImage,
    cases: &[Case],
    scene: Scene,
    lighting: &Lighting,
    sizes: &[Size],
) -> Result<()> {
    if !callgrind::running() {
        return Err(Error::Unsupported(
            "count-worker only counts under `valgrind --tool=callgrind --instr-atstart=no`; \
             use `lamina bench --counter instructions` or a sweep with `counter = \"instructions\"`"
                .into(),
        ));
    }
    let mut renderer = Renderer::new(gpu, equirect, WORKER_ENV)?;
    renderer.lighting = lighting.clone();
    let keys = cases
        .iter()
        .map(|c| c.pass_key(lighting))
        .collect::<Result<Vec<_>>>()?;
    let mut passes = PassCache::new();
    for key in &keys {
        passes.get(&mut renderer, key)?;
    }
    let total = cases.len() * sizes.len();
    for (k, &Size { width, height }) in sizes.iter().enumerate() {
        place_scene(&mut renderer, scene, width, height)?;
        for (i, case) in cases.iter().enumerate() {
            let layers = case.stack.params();
            renderer.set_surface(case.stack.surface.as_ref())?;
            let pass = passes.get(&mut renderer, &keys[i])?;
            // llvmpipe compiles a fragment-shader variant at its first draw with a state (the
            // pipeline, the bound textures' formats and sizes): keep that out with a draw of
            // the same state, as small as any — its size is not part of the variant. A
            // deferred pass's kernel samples the G-buffer, whose size is the frame's, and
            // llvmpipe keys a kernel's variant on whether its images' sides are powers of two:
            // its warm-up frame has the counted size.
            let (w, h) = if pass.deferred.is_some() {
                (width, height)
            } else {
                (WARM_UP_SIDE, WARM_UP_SIDE)
            };
            renderer.render(pass, &layers, w, h)?;
            renderer.render_observed(pass, &layers, width, height, &mut |phase| match phase {
                ShadedPhase::Before => callgrind::start_instrumentation(),
                ShadedPhase::After => callgrind::stop_instrumentation(),
            })?;
            let name = CString::new(format!("{DUMP_PREFIX}{i}-{k}")).expect("no NUL in a number");
            callgrind::dump_stats_at(&name);
            eprintln!("{PROGRESS_PREFIX}{}/{total}", k * cases.len() + i + 1);
        }
    }
    Ok(())
}

/// The side of the draw before each counted one (`worker`).
const WARM_UP_SIDE: u32 = 8;

/// Writes the worker's job file (the cases' variants and stacks) into `dir`.
fn write_job(dir: &Path, cases: &[Case], lighting: Option<&str>) -> Result<PathBuf> {
    let stacks = dir.join("stacks.json");
    let job = WorkerJob {
        lighting: lighting.map(str::to_owned),
        ..WorkerJob::from_cases(cases)
    };
    let job = serde_json::to_string(&job)
        .map_err(|e| Error::Unsupported(format!("encoding the worker's job: {e}")))?;
    std::fs::write(&stacks, job).map_err(|e| io_error(&stacks, e))?;
    Ok(stacks)
}

/// A fresh directory for worker `index`'s job and dumps.
pub(super) fn scratch_dir(index: usize) -> Result<PathBuf> {
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    let dir = std::env::temp_dir().join(format!(
        "lamina-count-{}-{index}-{stamp}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).map_err(|e| io_error(&dir, e))?;
    Ok(dir)
}

pub(super) fn run_worker(
    request: &CountRequest<'_>,
    dir: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<Vec<Counts>>> {
    let stacks = write_job(dir, request.cases, request.lighting)?;
    let out_file = dir.join("callgrind.out");
    let mut command = Command::new("valgrind");
    command
        .arg("--tool=callgrind")
        .arg("--instr-atstart=no")
        .arg(format!("--callgrind-out-file={}", out_file.display()))
        .arg("-q")
        .arg(request.exe)
        .args(&request.global_args)
        .arg("count-worker")
        .arg("--job")
        .arg(&stacks)
        .arg("--env")
        .arg(request.env_map)
        .arg("--scene")
        .arg(request.scene.name())
        .args(
            request
                .sizes
                .iter()
                .flat_map(|s| ["--size".to_string(), s.to_string()]),
        )
        .env("LP_NUM_THREADS", "0")
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    lowest_priority(&mut command);
    let mut child = command.spawn().map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            Error::Unsupported(
                "instruction counting needs valgrind on PATH (Debian: apt-get install valgrind; \
                 scripts/setup.sh installs it)"
                    .into(),
            )
        } else {
            Error::Unsupported(format!("starting valgrind: {e}"))
        }
    })?;
    let mut tail: Vec<String> = Vec::new();
    let total = request.cases.len() * request.sizes.len();
    progress(0, total);
    if let Some(stderr) = child.stderr.take() {
        for line in BufReader::new(stderr).lines().map_while(|l| l.ok()) {
            if let Some(done) = line
                .strip_prefix(PROGRESS_PREFIX)
                .and_then(|rest| rest.split('/').next())
                .and_then(|n| n.parse().ok())
            {
                progress(done, total);
            } else {
                tail.push(line);
                if tail.len() > 40 {
                    tail.remove(0);
                }
            }
        }
    }
    let status = child
        .wait()
        .map_err(|e| Error::Unsupported(format!("waiting for valgrind: {e}")))?;
    if !status.success() {
        return Err(Error::Unsupported(format!(
            "the instruction-counting worker failed ({status}); its last messages:\n{}",
            tail.join("\n")
        )));
    }
    read_dumps(dir, request, &tail)
}

/// The counts of the dumps the worker wrote into `dir`: `counts[case][size]`, each present or
/// an error quoting the worker's last messages (`tail`).
fn read_dumps(dir: &Path, request: &CountRequest<'_>, tail: &[String]) -> Result<Vec<Vec<Counts>>> {
    let mut counts = vec![vec![None; request.sizes.len()]; request.cases.len()];
    for entry in std::fs::read_dir(dir).map_err(|e| io_error(dir, e))? {
        let path = entry.map_err(|e| io_error(dir, e))?.path();
        let is_dump = path
            .file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.starts_with("callgrind.out"));
        if !is_dump {
            continue;
        }
        let text = std::fs::read_to_string(&path).map_err(|e| io_error(&path, e))?;
        if let Some(((case, size), count)) = parse_dump(&text) {
            if let Some(slot) = counts.get_mut(case).and_then(|c| c.get_mut(size)) {
                *slot = Some(count);
            }
        }
    }
    counts
        .into_iter()
        .enumerate()
        .map(|(i, by_size)| {
            by_size
                .into_iter()
                .enumerate()
                .map(|(k, c)| {
                    c.ok_or_else(|| {
                        Error::Unsupported(format!(
                            "callgrind wrote no count for case {i} ({}) at {}; worker \
                             messages:\n{}",
                            request.cases[i].variant,
                            request.sizes[k],
                            tail.join("\n")
                        ))
                    })
                })
                .collect()
        })
        .collect()
}

/// Starts `command` at the lowest scheduling priority (nice 19): a count does not depend on
/// when its instructions run, and a study timed beside it (`study::run`) keeps its core.
#[cfg(unix)]
fn lowest_priority(command: &mut Command) {
    use std::os::unix::process::CommandExt;
    // SAFETY: the closure runs in the child between fork and exec, where only
    // async-signal-safe calls are allowed: setpriority is one (a plain system call), and the
    // closure touches no memory of the parent. A failure leaves the child at its priority.
    unsafe {
        command.pre_exec(|| {
            libc::setpriority(libc::PRIO_PROCESS, 0, 19);
            Ok(())
        });
    }
}

#[cfg(not(unix))]
fn lowest_priority(_command: &mut Command) {}

fn io_error(path: &Path, e: std::io::Error) -> Error {
    Error::Output {
        path: path.to_owned(),
        message: e.to_string(),
    }
}

/// The case and size indices and the counts of one callgrind dump, when it is one of ours.
///
/// Self costs are summed per object (`ob=`): every cost line adds its last number (the `Ir`
/// event) to the current object, except the line after `calls=`, which carries the call's
/// inclusive cost. Objects are named on first use (`ob=(3) /path`) and by number after.
fn parse_dump(text: &str) -> Option<((usize, usize), Counts)> {
    let mut index = None;
    let mut names: std::collections::HashMap<&str, &str> = std::collections::HashMap::new();
    let mut current = "";
    let mut after_call = false;
    let mut counts = Counts { total: 0, jit: 0 };
    for line in text.lines() {
        if after_call {
            after_call = false;
            continue;
        }
        if let Some(desc) = line.strip_prefix("desc: Trigger: Client Request: ") {
            let (case, size) = desc.trim().strip_prefix(DUMP_PREFIX)?.split_once('-')?;
            index = Some((case.parse().ok()?, size.parse().ok()?));
        } else if let Some(spec) = line
            .strip_prefix("ob=")
            .or_else(|| line.strip_prefix("cob="))
        {
            let (id, name) = match spec.split_once(' ') {
                Some((id, name)) => (id, Some(name)),
                None => (spec, None),
            };
            if let Some(name) = name {
                names.insert(id, name);
            }
            if line.starts_with("ob=") {
                current = names.get(id).copied().unwrap_or(id);
            }
        } else if line.starts_with("calls=") {
            after_call = true;
        } else if line.starts_with(|c: char| c.is_ascii_digit() || "+-*".contains(c)) {
            let cost: u64 = line.split_whitespace().last()?.parse().ok()?;
            counts.total += cost;
            if current == "???" {
                counts.jit += cost;
            }
        }
    }
    Some((index?, counts))
}

/// The cases as the worker reads them back (JSON in the scratch directory).
#[derive(serde::Serialize, serde::Deserialize)]
pub struct WorkerJob {
    pub cases: Vec<WorkerCase>,
    /// The lighting file's text; absent: the environment alone.
    #[serde(default)]
    pub lighting: Option<String>,
}

#[derive(serde::Serialize, serde::Deserialize)]
pub struct WorkerCase {
    pub variant: String,
    pub material: String,
    /// The stack in the material file format (TOML), so the worker validates it like any file.
    pub stack_toml: String,
}

impl WorkerJob {
    /// The cases and the lighting of the job file at `path`, as the parent wrote them
    /// ([`super::counter::count_instructions`]).
    pub fn read(path: &Path) -> Result<(Vec<Case>, Lighting)> {
        let input_error = |message: String| Error::Input {
            path: path.to_owned(),
            message,
        };
        let text = std::fs::read_to_string(path)
            .map_err(|e| input_error(format!("cannot read the counter job: {e}")))?;
        let job: Self = serde_json::from_str(&text)
            .map_err(|e| input_error(format!("not a counter job ({e})")))?;
        let cases = job
            .cases
            .iter()
            .map(|c| {
                let stack = Stack::from_toml(&c.stack_toml, path)?;
                let variant = stack.variant(Some(&c.variant))?;
                Ok(Case {
                    variant,
                    stack: Stack {
                        name: c.material.clone(),
                        ..stack
                    },
                })
            })
            .collect::<Result<_>>()?;
        let lighting = match job.lighting {
            None => Lighting::default(),
            Some(text) => Lighting::parse(&text, path)?,
        };
        Ok((cases, lighting))
    }

    fn from_cases(cases: &[Case]) -> Self {
        Self {
            cases: cases
                .iter()
                .map(|c| WorkerCase {
                    variant: c.variant.to_string(),
                    material: c.stack.name.clone(),
                    stack_toml: c.stack.to_toml(),
                })
                .collect(),
            lighting: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dump_splits_jit_code_from_the_rest() {
        let text = "version: 1\ncreator: callgrind-3.19.0\npart: 2\n\
                    desc: Trigger: Client Request: lamina-case-3-1\n\
                    positions: line\nevents: Ir\nsummary: 0\n\n\
                    ob=(1) /usr/lib/libvulkan_lvp.so\nfl=(1) ???\nfn=(1) 0x10\n0 100\n\
                    cob=(2) ???\ncfn=(2) 0x20\ncalls=1 0\n0 5000\n+2 7\n\
                    ob=(2)\nfn=(2)\n0 40\n* 2\n\
                    ob=(1)\nfn=(3) 0x30\n-1 3\n";
        let (index, counts) = parse_dump(text).unwrap();
        assert_eq!(index, (3, 1));
        assert_eq!(
            counts,
            Counts {
                total: 152,
                jit: 42
            }
        );
        let exit = "desc: Trigger: Program termination\nsummary: 12\nob=(1) x\n0 12\n";
        assert_eq!(parse_dump(exit), None);
    }
}
