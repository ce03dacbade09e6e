//! Passes and the frame that runs them: the sky, the shaded sphere, readback; one key per
//! pass and one cache of them ([`pass`]).

pub mod baked;
pub mod classes;
pub mod deferred;
pub mod eval;
pub mod forward;
pub mod furnace;
pub mod inputs;
pub mod lights;
pub mod oracle;
pub mod pass;
pub mod reference;
pub mod renderer;
pub mod scene;
pub mod sheet;
pub mod sky;
pub mod surface;

pub use pass::{PassCache, PassKey};
pub use renderer::{RenderedFrame, Renderer, ShadedPhase, TargetFormat};
