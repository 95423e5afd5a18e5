//! Shared by the GPU tests: a context on lavapipe (or WEFT_DEVICE) with validation always on.
#![allow(dead_code)]

use weft::vk::{Context, ContextOptions, DeviceChoice};

pub fn context() -> Context {
    let device = match std::env::var("WEFT_DEVICE") {
        Ok(v) => DeviceChoice::parse(&v),
        Err(_) => DeviceChoice::Cpu,
    };
    Context::new(&ContextOptions {
        validate: true,
        device,
    })
    .expect("a Vulkan device with the validation layer (run tools/setup)")
}

/// Mean of the RGB channels of an RGBA8 image, in [0, 255].
pub fn mean_rgb(rgba: &[u8]) -> f64 {
    let sum: u64 = rgba
        .chunks_exact(4)
        .map(|p| p[0] as u64 + p[1] as u64 + p[2] as u64)
        .sum();
    sum as f64 / (rgba.len() / 4 * 3) as f64
}
