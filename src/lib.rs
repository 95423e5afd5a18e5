//! weft: a deferred Vulkan renderer for woven fabric.
//!
//! Layers, bottom up: `parse` (values as they enter), `cache` (weft's cache on disk), `reflect` (a
//! SPIR-V reader), `vk` (every `unsafe` Vulkan call; its set layouts are reflected from the
//! shaders), `fabric` (the cloth material's parameters and weave patterns), `scene` (glTF into plain data), `reference` (the CPU
//! twin of every shader function), `env` (environment maps and their preprocessing), `render` (the
//! plan and the passes of a frame), then the commands' libraries (`package`, `batch`, `bench`,
//! `compare`, `fidelity`, `sheet`, `view`). A module uses only lower ones; tests/module_layers.rs
//! checks it and names the four uses that still go up.
//!
//! `unsafe` is denied everywhere but in `vk`.
#![deny(unsafe_code)]

pub mod batch;
pub mod bench;
pub mod cache;
pub mod compare;
pub mod env;
pub mod fabric;
pub mod fidelity;
pub mod package;
pub mod parse;
pub mod reference;
pub mod reflect;
pub mod render;
pub mod scene;
pub mod sheet;
pub mod view;
#[allow(unsafe_code)]
pub mod vk;

mod error;
pub use error::{catch_panic, catching_panic, Error};

pub type Result<T, E = Error> = std::result::Result<T, E>;
