//! Writing images: PNG (display-referred sRGB) and EXR (linear). Each is encoded into a new
//! temporary file beside the target, flushed to disk, and renamed over the target, so an existing
//! file is never left half-written: it is either untouched or replaced by a complete image.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, ErrorKind, Write};
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

/// Writes the image `encode` produces to `path`, through a temporary file in the same directory
/// (so the rename cannot cross file systems), flushed to disk before the rename. On any failure
/// the temporary file is removed and `path` is left as it was.
fn write_atomically(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<File>) -> image::ImageResult<()>,
) -> crate::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path.file_name().ok_or_else(|| {
        Error::input(format!("output path '{}' has no file name", path.display()))
    })?;
    let tmp: PathBuf = dir.join(format!(
        ".{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id()
    ));
    // create_new: never write through a file (or a link) that is already there; one left over by
    // a killed run of a process with the same id is removed first.
    let open = || OpenOptions::new().write(true).create_new(true).open(&tmp);
    let file = match open() {
        Err(e) if e.kind() == ErrorKind::AlreadyExists && std::fs::remove_file(&tmp).is_ok() => {
            open()
        }
        other => other,
    }
    .map_err(|e| io_error(path, dir, "write", e))?;

    let written = (|| {
        let mut out = BufWriter::new(file);
        encode(&mut out).map_err(|e| match e {
            image::ImageError::IoError(io) => io,
            other => std::io::Error::other(other),
        })?;
        out.flush()?;
        let file = out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()
    })();
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
    write_atomically(path, |out| img.write_to(out, image::ImageFormat::Png))
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
