//! The crate's error type: what went wrong, in words a user can act on.

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad user input: a scene file, a parameter, a command-line value. The message names what,
    /// where and how to fix it.
    #[error("{0}")]
    Input(String),
    /// No usable Vulkan driver or device.
    #[error("{0}")]
    NoVulkan(String),
    /// The device cannot do what was asked (image too large, out of memory, missing feature).
    #[error("{0}")]
    Device(String),
    /// A Vulkan call failed where it should not.
    #[error("Vulkan error in {what}: {result}")]
    Vulkan {
        what: &'static str,
        result: ash::vk::Result,
    },
    /// The validation layer reported errors or warnings (only when validation is on).
    #[error("Vulkan validation reported {} message(s):\n{}", .0.len(), .0.join("\n"))]
    Validation(Vec<String>),
    #[error("{context}: {source}")]
    Io {
        context: String,
        source: std::io::Error,
    },
}

impl Error {
    pub fn input(msg: impl Into<String>) -> Self {
        Error::Input(msg.into())
    }
    pub fn device(msg: impl Into<String>) -> Self {
        Error::Device(msg.into())
    }
}
