//! The CPU reference: every function the fabric shaders compute, in f64 (the ground truth) and in
//! f32 (the line-for-line twin of `glsl/include/fabric.glsl` and `glsl/include/weave.glsl`, with
//! the same names), plus the integrators and the GPU probe's CPU side.
//!
//! - [`brdf`]: the Ashikhmin–Shirley lobe, D, Schlick, Lambert, the coupled diffuse, the fabric
//!   mixture; [`brdf::sampling`]: importance sampling of the lobe and its pdf.
//! - [`weave`]: the weave at a point and its exact coverage of a box footprint.
//! - [`furnace`]: white-furnace albedo.
//! - [`shading`]: the CPU twin of the lighting and tonemap passes (lights, glTF PBR, ambient,
//!   the fabric branch).
//! - [`ibl_twin`]: the f32 twins of `glsl/include/ibl.glsl` and `glsl/include/cube.glsl`, the
//!   records of `glsl/ibl_probe.comp`, and the interval bound of every output under the Vulkan
//!   precision rules; the number types it is written over (`Real` at f32 and f64, and the
//!   interval arithmetic `Iv`) are in `interval.rs`, re-exported from `ibl_twin`.
//! - [`env_light`]: the f32 twins of `glsl/include/env_light.glsl` (the environment light's
//!   estimators) and `glsl/include/shadows.glsl` (PCF), over any look-up of the textures they
//!   read, and the closed-form stand-ins `glsl/env_probe.comp` gives both sides.
//! - [`probe`]: the std430 buffers of `glsl/fabric_probe.comp`, their CPU evaluation, the inputs
//!   (hard cases and random) and the GPU-vs-CPU error bound.
//!
//! The BRDF exists twice in this project: here (one source, instantiated in both precisions by a
//! macro) and in GLSL. Nothing else may carry a copy.

pub mod brdf;
pub mod env_light;
pub mod furnace;
pub mod ibl_twin;
mod interval;
pub mod lobe_albedo;
pub mod probe;
pub mod raster;
pub mod shading;

/// The weave's CPU twin lives with the material ([`crate::fabric::coverage`]).
pub use crate::fabric::coverage as weave;
pub use probe::{probe_cpu_f32, probe_cpu_f64, ProbeInput, ProbeOutput};
