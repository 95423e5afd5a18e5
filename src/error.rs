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
    /// A file could not be read or written: `context` says which and what to do; the OS's
    /// message is the `source` only (printing it in the message too made it appear twice in a
    /// `{:#}` chain).
    #[error("{context}")]
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

#[cfg(test)]
mod tests {
    use super::Error;
    use std::error::Error as _;

    /// The OS message is the source, not also part of the message: a chain printer (anyhow's
    /// `{:#}`, as `weft` prints errors) shows it once.
    #[test]
    fn io_errors_show_the_os_message_once() {
        let e = Error::Io {
            context: "could not write 'x.png'".into(),
            source: std::io::Error::from_raw_os_error(28),
        };
        let os = std::io::Error::from_raw_os_error(28).to_string();
        assert_eq!(e.to_string(), "could not write 'x.png'");
        assert_eq!(e.source().map(|s| s.to_string()), Some(os.clone()));
        let chain = format!("{:#}", anyhow::Error::from(e));
        assert_eq!(chain.matches(&os).count(), 1, "{chain}");
    }
}
