//! The scene thread: its own device renders what the UI asks for and sends the pixels back, so
//! a slow frame or a variant's compilation (seconds for a large 6-flux shader on lavapipe,
//! whose JIT runs at the first draw) never freezes the window.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, Sender};

use crate::error::Result;
use crate::gpu::Gpu;
use crate::imageio;
use crate::model::LayerParams;
use crate::render::scene::{torus, uv_sphere, Camera};
use crate::render::{PassCache, PassKey, Renderer};
use crate::tables::environment::EnvDesc;
use crate::variant::VariantKey;
use crate::vk::{DeviceSelector, InstanceDesc};

use super::panels::MeshKind;

/// The prefiltered environment of the viewer: smaller than `lamina render`'s so switching maps
/// takes a moment, not seconds.
const VIEWER_ENV: EnvDesc = EnvDesc {
    face_size: 256,
    mip_count: 8,
    samples: 32,
};

/// One frame to render.
pub struct Request {
    pub layers: Vec<LayerParams>,
    /// A spatially varying stack's maps.
    pub surface: Option<std::sync::Arc<crate::material::Surface>>,
    pub variant: VariantKey,
    pub camera: Camera,
    pub lighting: crate::render::lights::Lighting,
    pub width: u32,
    pub height: u32,
    /// A new environment map to prefilter first.
    pub environment: Option<PathBuf>,
    /// A new mesh to draw from now on.
    pub mesh: Option<MeshKind>,
}

pub enum Reply {
    /// The outcome of building a variant's pipeline.
    Compiled {
        variant: VariantKey,
        error: Option<String>,
    },
    Frame(Frame),
    /// No frame for this request: its variant failed to build or cannot hold the stack.
    Skipped,
    /// The request could not be rendered (the thread keeps serving).
    Failed(String),
}

pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
    pub shaded_ms: f64,
    pub fragment_invocations: Option<u64>,
}

/// Serves requests until the UI hangs up, one terminal reply (`Frame`, `Skipped` or `Failed`)
/// per request after coalescing; returns the validation problems its device saw.
pub fn serve(
    instance: InstanceDesc,
    selector: DeviceSelector,
    env: PathBuf,
    requests: Receiver<Request>,
    replies: Sender<Reply>,
) -> Result<u32> {
    let gpu = Gpu::new(
        InstanceDesc {
            surface: false,
            ..instance
        },
        &selector,
    )?;
    let equirect = read_env(&env)?;
    let mut renderer = Renderer::new(&gpu, &equirect, VIEWER_ENV)?;
    // One pass at a time: an edit that names another pass rebuilds it, as the UI counts.
    let mut passes = PassCache::bounded(1);
    while let Ok(mut request) = requests.recv() {
        // Only the newest frame matters; keep the scene changes of the skipped ones.
        while let Ok(newer) = requests.try_recv() {
            let environment = newer.environment.clone().or(request.environment.take());
            let mesh = newer.mesh.or(request.mesh);
            request = Request {
                environment,
                mesh,
                ..newer
            };
        }
        let reply = match step(&mut renderer, &mut passes, &request, &replies) {
            Ok(Some(frame)) => Reply::Frame(frame),
            Ok(None) => Reply::Skipped,
            Err(e) => Reply::Failed(e.to_string()),
        };
        if replies.send(reply).is_err() {
            break;
        }
    }
    drop(passes);
    drop(renderer);
    Ok(gpu.device.validation_problems())
}

fn step(
    renderer: &mut Renderer<'_>,
    passes: &mut PassCache,
    request: &Request,
    replies: &Sender<Reply>,
) -> Result<Option<Frame>> {
    if let Some(path) = &request.environment {
        renderer.set_environment(&read_env(path)?, VIEWER_ENV)?;
    }
    if let Some(kind) = request.mesh {
        let mesh = match kind {
            MeshKind::Sphere => uv_sphere(64, 128),
            MeshKind::Torus => torus(0.72, 0.32, 96, 48),
        };
        renderer.set_mesh(&mesh)?;
    }
    renderer.set_surface(request.surface.as_ref())?;
    renderer.lighting = request.lighting.clone();
    // An edit names another pass when it changes what the pass was built for: the structure
    // under `specialized`, any value under `specialized-values` and `baked`, the maps, a
    // diffuse base, the lights.
    let key = PassKey::new(
        request.variant,
        &request.layers,
        request.surface.as_deref(),
        &request.lighting,
    );
    let compiled = key
        .as_ref()
        .map_or(true, |k| passes.find(renderer, k).is_none());
    if compiled {
        let built = key.as_ref().map_err(|e| e.to_string()).and_then(|k| {
            passes
                .get(renderer, k)
                .map(|_| ())
                .map_err(|e| e.to_string())
        });
        let _ = replies.send(Reply::Compiled {
            variant: request.variant,
            error: built.err(),
        });
    }
    let Some(pass) = key.ok().and_then(|k| passes.find(renderer, &k)) else {
        return Ok(None);
    };
    if pass.key.admits(&request.layers).is_err() {
        return Ok(None);
    }
    renderer.camera = request.camera;
    if compiled {
        // llvmpipe compiles the shader at its first draw: keep that out of the history.
        renderer.render(pass, &request.layers, request.width, request.height)?;
    }
    let frame = renderer.render(pass, &request.layers, request.width, request.height)?;
    Ok(Some(Frame {
        width: frame.width,
        height: frame.height,
        pixels: frame.pixels,
        shaded_ms: frame.shaded.duration.as_ms(),
        fragment_invocations: frame.shaded.fragment_invocations,
    }))
}

fn read_env(path: &Path) -> Result<imageio::HdrImage> {
    Ok(imageio::read_exr(path)?)
}
