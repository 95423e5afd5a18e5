//! weft: a deferred Vulkan renderer for woven fabric.
//!
//! Layers, bottom up: `error` (errors and load warnings), `color` (the sRGB transfer functions),
//! `parse` (values as they enter), `cache` (weft's cache on disk), `reflect` (a SPIR-V reader),
//! `vk` (every `unsafe` Vulkan call; its set layouts are reflected from the shaders), `fabric` (the
//! cloth material's parameters, weave patterns and the weave's coverage), `scene` (glTF into plain
//! data), `records` (the GPU's records, mirrored by glsl/include/frame.glsl), `reference` (the CPU
//! twin of every shader function), `env` (environment maps, their preprocessing and the f64
//! quadrature truth), `render` (the plan and the passes of a frame), `metrics` (image metrics: FLIP, RMSE, PSNR), `assets` (the woven model
//! written into glTF files), `spec` (what to render, and the one way to load it), then the commands' libraries (`package`, `batch`, `bench`, `compare`,
//! `fidelity`, `sheet`, `view`). A module uses only lower ones: tests/module_layers.rs checks it,
//! with no exception.
//!
//! `unsafe` is denied everywhere but in `vk`.
#![deny(unsafe_code)]

pub mod assets;
pub mod batch;
pub mod bench;
pub mod cache;
pub mod color;
pub mod compare;
pub mod env;
pub mod fabric;
pub mod fidelity;
pub mod metrics;
pub mod package;
pub mod parse;
pub mod records;
pub mod reference;
pub mod reflect;
pub mod render;
pub mod scene;
pub mod sheet;
pub mod spec;
pub mod view;
#[allow(unsafe_code)]
pub mod vk;

mod error;
pub use error::{catch_panic, catching_panic, Error, Warning};

pub type Result<T, E = Error> = std::result::Result<T, E>;
