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

thread_local! {
    static CATCHING: std::cell::Cell<u32> = const { std::cell::Cell::new(0) };
}

/// Runs `f`, turning a panic in it (a dependency's, on input that slipped past weft's checks)
/// into `Err` with the panic's message. While `f` runs, [`catching_panic`] is true on this
/// thread, so a panic hook can stay quiet about a panic that becomes an error (the `weft`
/// binary's does: the user sees the error naming the file, not panic text and a backtrace).
pub fn catch_panic<T>(f: impl FnOnce() -> T) -> std::result::Result<T, String> {
    struct Depth;
    impl Drop for Depth {
        fn drop(&mut self) {
            CATCHING.with(|c| c.set(c.get() - 1));
        }
    }
    CATCHING.with(|c| c.set(c.get() + 1));
    let _depth = Depth;
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|panic| {
        panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no details".into())
    })
}

/// Whether this thread is inside [`catch_panic`]: a panic now becomes an error, not a crash.
pub fn catching_panic() -> bool {
    CATCHING.with(|c| c.get() > 0)
}

/// Non-fatal problems found while loading: the scene still renders, and the CLI prints these.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning(pub String);

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::Error;

    #[test]
    fn caught_panics_become_their_message() {
        assert!(!super::catching_panic());
        let r: Result<(), String> = super::catch_panic(|| {
            assert!(super::catching_panic());
            panic!("inside {}", "a dependency")
        });
        assert_eq!(r, Err("inside a dependency".to_string()));
        assert!(
            !super::catching_panic(),
            "the flag is cleared after a panic too"
        );
        assert_eq!(super::catch_panic(|| 7), Ok(7));
    }
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
