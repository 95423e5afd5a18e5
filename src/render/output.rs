//! Writing images: PNG (display-referred sRGB) and EXR (linear). Each is encoded into a new
//! temporary file beside the target, flushed to disk, and renamed over the target, so an existing
//! file is never left half-written: it is either untouched or replaced by a complete image.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, ErrorKind, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::Error;

/// An output error that names the file and, where the cause is a common one, says what to do.
fn io_error(path: &Path, dir: &Path, what: &str, e: std::io::Error) -> Error {
    let dir_name = if dir == Path::new(".") {
        "the current directory".to_owned()
    } else {
        format!("'{}'", dir.display())
    };
    let advice = match e.kind() {
        ErrorKind::NotFound if !dir.is_dir() => {
            format!(
                "the directory {dir_name} does not exist: create it, or choose another output path"
            )
        }
        ErrorKind::PermissionDenied | ErrorKind::ReadOnlyFilesystem => {
            format!("the directory {dir_name} is not writable: choose another output path")
        }
        ErrorKind::StorageFull => {
            format!("the disk holding {dir_name} is full: free some space, or choose another output path")
        }
        ErrorKind::IsADirectory => {
            "a directory of that name is in the way: choose another output path".to_owned()
        }
        _ => "check that the directory exists, is writable and has space".to_owned(),
    };
    Error::Io {
        context: format!("could not {what} '{}' ({advice})", path.display()),
        source: e,
    }
}

/// The temporary file, remembering the first error the file system gave: encoders wrap it in
/// errors of their own that lose its kind (a full disk must still be reported as one).
struct Sink {
    file: File,
    error: Option<std::io::Error>,
}

impl Sink {
    fn note<T>(&mut self, result: std::io::Result<T>) -> std::io::Result<T> {
        if let Err(e) = &result {
            if self.error.is_none() {
                self.error = Some(std::io::Error::new(e.kind(), e.to_string()));
            }
        }
        result
    }
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let r = self.file.write(buf);
        self.note(r)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        let r = self.file.flush();
        self.note(r)
    }
}

impl Seek for Sink {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        let r = self.file.seek(pos);
        self.note(r)
    }
}

/// The temporary file's name for a write of `name`: `.NAME.PID.TID.tmp`, with the process id
/// and the writing thread's number (the digits of its `ThreadId`), so that no two writers that
/// can run at the same time - other processes, or other threads of this one - share it. (With
/// the process id alone, two threads writing one target removed each other's temporary file.)
#[doc(hidden)]
pub fn temp_name(name: &std::ffi::OsStr) -> String {
    let thread: String = format!("{:?}", std::thread::current().id())
        .chars()
        .filter(char::is_ascii_digit)
        .collect();
    format!(
        ".{}.{}.{thread}.tmp",
        name.to_string_lossy(),
        std::process::id()
    )
}

/// Writes `bytes` to `path` the way images are written: through a temporary file beside it,
/// flushed to disk and renamed over it, so `path` is either untouched or complete.
pub fn write_file(path: &Path, bytes: &[u8]) -> crate::Result<()> {
    write_atomically(path, |out| {
        out.write_all(bytes).map_err(image::ImageError::IoError)
    })
}

/// Writes the image `encode` produces to `path`, through a temporary file in the same directory
/// (so the rename cannot cross file systems), flushed to disk before the rename. On any failure
/// the temporary file is removed and `path` is left as it was.
fn write_atomically(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<Sink>) -> image::ImageResult<()>,
) -> crate::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path.file_name().ok_or_else(|| {
        Error::input(format!("output path '{}' has no file name", path.display()))
    })?;
    let tmp: PathBuf = dir.join(temp_name(name));
    // create_new: never write through a file (or a link) that is already there; one left over by
    // a killed run of a process (and thread) with the same id is removed first.
    let open = || OpenOptions::new().write(true).create_new(true).open(&tmp);
    let file = match open() {
        Err(e) if e.kind() == ErrorKind::AlreadyExists && std::fs::remove_file(&tmp).is_ok() => {
            open()
        }
        other => other,
    }
    .map_err(|e| match e.kind() {
        ErrorKind::AlreadyExists => Error::Io {
            context: format!(
                "could not write '{}' (the temporary file '{}' is in the way and could not be removed: remove it)",
                path.display(),
                tmp.display()
            ),
            source: e,
        },
        _ => io_error(path, dir, "write", e),
    })?;

    let mut out = BufWriter::new(Sink { file, error: None });
    let encoded = encode(&mut out).map_err(|e| match e {
        image::ImageError::IoError(io) => io,
        other => std::io::Error::other(other),
    });
    let written = encoded
        .and_then(|()| out.flush())
        .and_then(|()| out.get_ref().file.sync_all());
    let written = written.map_err(|e| out.get_mut().error.take().unwrap_or(e));
    // Closed before the rename or the removal (the buffer is empty, or the write failed anyway).
    drop(out);
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(io_error(path, dir, "write", e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_error(path, dir, "replace", e)
    })
}

/// Writes RGBA8 sRGB pixels as a PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> crate::Result<()> {
    let img = image::RgbaImage::from_raw(width, height, rgba8.to_vec()).ok_or_else(|| {
        Error::input(format!(
            "image buffer does not hold {width}x{height} RGBA8 pixels"
        ))
    })?;
    // Fast compression with adaptive filtering: a 1920x1080 frame encodes in a fraction of the
    // default level's time, for files ~10 % larger.
    write_atomically(path, |out| {
        use image::ImageEncoder;
        image::codecs::png::PngEncoder::new_with_quality(
            out,
            image::codecs::png::CompressionType::Fast,
            image::codecs::png::FilterType::Adaptive,
        )
        .write_image(img.as_raw(), width, height, image::ExtendedColorType::Rgba8)
    })
}

/// Writes linear RGBA f32 pixels as an OpenEXR file. Refuses (with an error) to write NaN or Inf.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> crate::Result<()> {
    if let Some(i) = rgba.iter().position(|v| !v.is_finite()) {
        let px = i / 4;
        return Err(Error::device(format!(
            "the HDR image has a non-finite value at pixel ({}, {}); nothing was written to '{}'. This is a bug in weft: please report it with the scene",
            px as u32 % width.max(1),
            px as u32 / width.max(1),
            path.display()
        )));
    }
    let img = image::Rgba32FImage::from_raw(width, height, rgba.to_vec()).ok_or_else(|| {
        Error::input(format!(
            "image buffer does not hold {width}x{height} RGBA pixels"
        ))
    })?;
    write_atomically(path, |out| {
        image::DynamicImage::ImageRgba32F(img).write_to(out, image::ImageFormat::OpenExr)
    })
}
