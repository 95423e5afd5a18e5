//! The `weft` binary as the command-line tests run it.

use std::process::Command;

/// The `weft` binary cargo built for these tests.
pub const WEFT: &str = env!("CARGO_BIN_EXE_weft");

/// The device the binary is told to use: WEFT_DEVICE, or lavapipe ("cpu") where it is unset.
pub fn device() -> String {
    std::env::var("WEFT_DEVICE").unwrap_or_else(|_| "cpu".into())
}

/// `weft` on [`device`].
pub fn weft() -> Command {
    let mut c = Command::new(WEFT);
    c.env("WEFT_DEVICE", device());
    c
}

/// `weft` with no Vulkan driver to find: a command that gets as far as opening a device fails
/// with "No Vulkan driver", so one refused before any device work still says why, and one that
/// fails otherwise never touched the GPU.
pub fn weft_without_gpu() -> Command {
    without_gpu(weft())
}

/// `c` with no Vulkan driver to find ([`weft_without_gpu`]).
pub fn without_gpu(mut c: Command) -> Command {
    c.env("VK_ICD_FILENAMES", "/nonexistent")
        .env("VK_DRIVER_FILES", "/nonexistent");
    c
}
