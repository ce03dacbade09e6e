//! lamina's integration tests, in one binary: on lavapipe (or whatever Vulkan device is
//! present) with the Khronos validation layer on, every validation message a failure. One
//! binary links once, and its tests share both cores while one of them compiles shaders
//! on a single thread. `cargo test --test suite MODULE::` runs one file's tests.

mod common;

mod capture;
mod cli;
mod deferred;
mod device;
mod diffuse;
mod environment;
mod export;
mod fgd;
mod gates;
mod ibl;
mod lights;
mod model_gpu;
mod model_vs_cpu;
mod pipeline_cache;
mod reference;
mod reference_maps;
mod reflection;
mod render;
mod shard;
mod spec_array;
mod specialized;
mod structure;
mod surface;
mod sweep;
mod tables;
mod transmission;
mod viewer;
