//! Writing images: PNG (display-referred sRGB) and EXR (linear). Each is written to a temporary
//! file beside the target and renamed over it, so an existing file is never left half-written.

use std::path::Path;

use crate::Error;

fn io_error(path: &Path, what: &str, e: impl std::fmt::Display) -> Error {
    Error::Io {
        context: format!("could not {what} '{}' (check that the directory exists, is writable and has space)", path.display()),
        source: std::io::Error::other(e.to_string()),
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<(), String>) -> crate::Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().ok_or_else(|| Error::input(format!("output path '{}' has no file name", path.display())))?;
    let tmp = dir.join(format!(".{}.{}.tmp", name.to_string_lossy(), std::process::id()));
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(io_error(path, "write", e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_error(path, "replace", e)
    })
}

/// Writes RGBA8 sRGB pixels as a PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> crate::Result<()> {
    let img = image::RgbaImage::from_raw(width, height, rgba8.to_vec())
        .ok_or_else(|| Error::input(format!("image buffer does not hold {width}x{height} RGBA8 pixels")))?;
    write_atomically(path, |tmp| img.save_with_format(tmp, image::ImageFormat::Png).map_err(|e| e.to_string()))
}

/// Writes linear RGBA f32 pixels as an OpenEXR file. Refuses (with an error) to write NaN or Inf.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> crate::Result<()> {
    if let Some(i) = rgba.iter().position(|v| !v.is_finite()) {
        let px = i / 4;
        return Err(Error::device(format!(
            "the HDR image has a non-finite value at pixel ({}, {}); nothing was written to '{}'. This is a bug in weft: please report it with the scene",
            px as u32 % width,
            px as u32 / width,
            path.display()
        )));
    }
    let img = image::Rgba32FImage::from_raw(width, height, rgba.to_vec())
        .ok_or_else(|| Error::input(format!("image buffer does not hold {width}x{height} RGBA pixels")))?;
    write_atomically(path, |tmp| {
        image::DynamicImage::ImageRgba32F(img).save_with_format(tmp, image::ImageFormat::OpenExr).map_err(|e| e.to_string())
    })
}
