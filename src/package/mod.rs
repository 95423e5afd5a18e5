//! The SPIR-V shader package: every module compiled from `glsl/` as `<name>.spv`, a
//! `manifest.json` that says how to bind and call each one, the shared GLSL under `include/`, and
//! a `README.md` for the engine developer. Another Vulkan program can use it without weft's Rust
//! code (`tests/package_consumer.rs` does exactly that).
//!
//! The manifest is reflected from the SPIR-V words ([`spirv`]), never typed by hand; only the
//! prose is: what each module is for ([`MODULE_NOTES`]), what each binding holds (the comment at
//! its GLSL declaration: [`binding_comment`]) and what each specialization constant means
//! ([`SPEC_MEANINGS`]). The package tests fail when a module, binding or constant lacks its
//! prose, or prose names one that is gone.
//!
//! The output is reproducible: modules sorted by name, JSON keys sorted, no timestamps, so two
//! writes of the same build are byte-identical.

mod binding;
mod manifest;
mod prose;
mod readme;
mod write;

/// The SPIR-V reader (`crate::reflect`), under the name the package has always given it.
pub use crate::reflect as spirv;

pub use binding::binding_comment;
pub use manifest::{
    manifest, reflect_module, sha256_hex, stage_name, stage_vk_bit, BindingEntry, FileEntry,
    Manifest, ModuleEntry, SpecEntry,
};
pub use prose::{module_notes, MODULE_NOTES, SPEC_MEANINGS, SPEC_MEANINGS_OF};
pub use spirv::{
    Access, DescriptorKind, InterfaceVariable, PushConstantRange, SpecConstant, SpecValue,
    WorkgroupSize,
};
pub use write::write_package;

/// Version of the package layout and of manifest.json's schema; bumped when either changes in a
/// way a consumer would notice.
pub const FORMAT_VERSION: u32 = 1;

/// The manifest's file name inside the package.
pub const MANIFEST_FILE: &str = "manifest.json";

/// The shared GLSL, as shipped under `include/`: what an engine's own shaders can `#include` to
/// read weft's G-buffer or evaluate the fabric BRDF.
pub const INCLUDES: &[(&str, &str)] = &[
    ("cube.glsl", include_str!("../../glsl/include/cube.glsl")),
    (
        "env_cubes.glsl",
        include_str!("../../glsl/include/env_cubes.glsl"),
    ),
    (
        "env_light.glsl",
        include_str!("../../glsl/include/env_light.glsl"),
    ),
    (
        "fabric.glsl",
        include_str!("../../glsl/include/fabric.glsl"),
    ),
    ("frame.glsl", include_str!("../../glsl/include/frame.glsl")),
    ("fxaa.glsl", include_str!("../../glsl/include/fxaa.glsl")),
    (
        "forward_main.glsl",
        include_str!("../../glsl/include/forward_main.glsl"),
    ),
    (
        "gbuffer_main.glsl",
        include_str!("../../glsl/include/gbuffer_main.glsl"),
    ),
    ("ibl.glsl", include_str!("../../glsl/include/ibl.glsl")),
    (
        "lighting_main.glsl",
        include_str!("../../glsl/include/lighting_main.glsl"),
    ),
    (
        "lights.glsl",
        include_str!("../../glsl/include/lights.glsl"),
    ),
    (
        "occlusion.glsl",
        include_str!("../../glsl/include/occlusion.glsl"),
    ),
    ("pbr.glsl", include_str!("../../glsl/include/pbr.glsl")),
    ("pool.glsl", include_str!("../../glsl/include/pool.glsl")),
    ("shade.glsl", include_str!("../../glsl/include/shade.glsl")),
    (
        "shadows.glsl",
        include_str!("../../glsl/include/shadows.glsl"),
    ),
    (
        "surface.glsl",
        include_str!("../../glsl/include/surface.glsl"),
    ),
    (
        "tonemap.glsl",
        include_str!("../../glsl/include/tonemap.glsl"),
    ),
    ("weave.glsl", include_str!("../../glsl/include/weave.glsl")),
];
