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
        ErrorKind::InvalidFilename => {
            "the file system refuses the name (too long, or a character it does not allow): choose a shorter or plainer name".to_owned()
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
    // A long target name is cut (and a hash of the whole added, so that two targets alike in
    // their first bytes, a frame's PNG and EXR, still get two names): a target name of up to
    // NAME_MAX bytes gets a temporary name the file system takes too.
    let name = name.to_string_lossy();
    let shown = if name.len() <= TEMP_NAME_PREFIX {
        name.into_owned()
    } else {
        let mut cut = TEMP_NAME_PREFIX - 10;
        while !name.is_char_boundary(cut) {
            cut -= 1;
        }
        // FNV-1a.
        let hash = name.bytes().fold(0x811c_9dc5u32, |h, b| {
            (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
        });
        format!("{}~{hash:08x}", &name[..cut])
    };
    format!(".{shown}.{}.{thread}.tmp", std::process::id())
}

/// The longest file name (in bytes) the file systems weft writes to take: 255 on Linux (ext4,
/// XFS, Btrfs, tmpfs, NFS), macOS and Windows.
pub const NAME_MAX: usize = 255;
/// The longest path (in bytes) Linux takes in a system call.
pub const PATH_MAX: usize = 4095;
/// How much of the target's name a temporary file's name keeps (`.` + this + `.PID.TID.tmp`,
/// at most 2 + 10 + 20 + 4 more bytes, stays under [`NAME_MAX`]).
const TEMP_NAME_PREFIX: usize = 200;

/// Writes `bytes` to `path` the way images are written: through a temporary file beside it,
/// flushed to disk and renamed over it, so `path` is either untouched or complete.
pub fn write_file(path: &Path, bytes: &[u8]) -> crate::Result<()> {
    stage(path, |out| {
        out.write_all(bytes).map_err(image::ImageError::IoError)
    })?
    .commit()
}

/// A file encoded into its temporary file beside the target and flushed to disk, not yet in
/// place: [`Staged::commit`] renames it over the target; dropped uncommitted (an error, or a
/// panic, before the commit) it removes the temporary file, so nothing of it is left.
#[must_use = "a staged file is removed unless committed"]
pub struct Staged {
    tmp: PathBuf,
    path: PathBuf,
    dir: PathBuf,
    committed: bool,
}

impl Staged {
    /// Renames the temporary file over the target.
    pub fn commit(mut self) -> crate::Result<()> {
        self.committed = true;
        std::fs::rename(&self.tmp, &self.path).map_err(|e| {
            let _ = std::fs::remove_file(&self.tmp);
            io_error(&self.path, &self.dir, "replace", e)
        })
    }

    /// The target path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Puts several staged files in place, all or none: if one rename fails, the files already
/// renamed by this call are removed again (what they replaced is gone either way), so a failed
/// frame leaves none of its outputs. Pass the file that marks the whole as done (the PNG that
/// `--resume` looks for) last.
pub fn commit_all(staged: Vec<Staged>) -> crate::Result<()> {
    let mut placed: Vec<PathBuf> = Vec::new();
    let mut staged = staged.into_iter();
    while let Some(s) = staged.next() {
        let path = s.path.clone();
        if let Err(e) = s.commit() {
            for p in &placed {
                let _ = std::fs::remove_file(p);
            }
            // The rest drop here, removing their temporary files.
            drop(staged);
            return Err(e);
        }
        placed.push(path);
    }
    Ok(())
}

/// Encodes what `encode` produces into a new temporary file in `path`'s directory (so the rename
/// cannot cross file systems), flushed to disk. On any failure the temporary file is removed and
/// `path` is left as it was.
fn stage(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<Sink>) -> image::ImageResult<()>,
) -> crate::Result<Staged> {
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
    // From here on the guard removes the temporary file on every way out but the commit.
    let staged = Staged {
        tmp,
        path: path.to_path_buf(),
        dir: dir.to_path_buf(),
        committed: false,
    };

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
    written.map_err(|e| io_error(path, dir, "write", e))?;
    Ok(staged)
}

/// Refuses a pixel buffer that is not exactly `width` x `height` texels of `channels` values
/// (the encoders panic on a longer one).
fn check_len(
    what: &str,
    width: u32,
    height: u32,
    channels: usize,
    len: usize,
) -> crate::Result<()> {
    let expect = width as usize * height as usize * channels;
    if width == 0 || height == 0 || len != expect {
        return Err(Error::device(format!(
            "the {what} image buffer holds {len} values, not the {expect} of a {width}x{height} image; this is a bug in weft: please report it"
        )));
    }
    Ok(())
}

/// Writes RGBA8 sRGB pixels as a PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> crate::Result<()> {
    stage_png(path, width, height, rgba8)?.commit()
}

/// [`write_png`] up to the rename: the PNG complete in its temporary file.
pub fn stage_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> crate::Result<Staged> {
    stage_png_with_text(path, width, height, rgba8, &[])
}

/// [`stage_png`] with PNG text chunks (tEXt, Latin-1 keys and values: what the image is, e.g.
/// the tone curve and exposure a render used).
pub fn stage_png_with_text(
    path: &Path,
    width: u32,
    height: u32,
    rgba8: &[u8],
    text: &[(String, String)],
) -> crate::Result<Staged> {
    check_len("RGBA8", width, height, 4, rgba8.len())?;
    if !text.is_empty() {
        return stage(path, |out| {
            let to_io = |e: png::EncodingError| {
                image::ImageError::IoError(std::io::Error::other(e.to_string()))
            };
            let mut encoder = png::Encoder::new(out, width, height);
            encoder.set_color(png::ColorType::Rgba);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_compression(png::Compression::Fast);
            encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
            for (k, v) in text {
                encoder
                    .add_text_chunk(k.clone(), v.clone())
                    .map_err(to_io)?;
            }
            let mut writer = encoder.write_header().map_err(to_io)?;
            writer.write_image_data(rgba8).map_err(to_io)?;
            writer.finish().map_err(to_io)
        });
    }
    // Fast compression with adaptive filtering: a 1920x1080 frame encodes in a fraction of the
    // default level's time, for files ~10 % larger.
    stage(path, |out| {
        use image::ImageEncoder;
        image::codecs::png::PngEncoder::new_with_quality(
            out,
            image::codecs::png::CompressionType::Fast,
            image::codecs::png::FilterType::Adaptive,
        )
        .write_image(rgba8, width, height, image::ExtendedColorType::Rgba8)
    })
}

/// Writes linear RGBA f32 pixels as an OpenEXR file. Refuses (with an error) to write NaN or Inf.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> crate::Result<()> {
    stage_exr(path, width, height, rgba)?.commit()
}

/// [`write_exr`] up to the rename.
pub fn stage_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> crate::Result<Staged> {
    check_len("RGBA f32", width, height, 4, rgba.len())?;
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
    stage(path, |out| {
        image::DynamicImage::ImageRgba32F(img).write_to(out, image::ImageFormat::OpenExr)
    })
}

/// Writes a frame's image and, when asked, its HDR image, all or nothing: both are encoded and
/// flushed to temporary files first, then renamed, the PNG last (what `--resume` looks for). A
/// failure at any step leaves neither (a single render and a batch frame alike).
/// The PNG records how it was made in text chunks: `Software` (weft and its version) and
/// `weft:display` (the tone curve and exposure that turned the linear image into these pixels).
pub fn write_frame(
    png: &Path,
    exr: Option<&Path>,
    width: u32,
    height: u32,
    ldr: &[u8],
    hdr: &[f32],
    options: &super::RenderOptions,
) -> crate::Result<()> {
    let mut staged = Vec::new();
    if let Some(exr) = exr {
        staged.push(stage_exr(exr, width, height, hdr)?);
    }
    let text = [
        (
            "Software".to_string(),
            format!("weft {}", env!("CARGO_PKG_VERSION")),
        ),
        ("weft:display".to_string(), display_note(options)),
    ];
    staged.push(stage_png_with_text(png, width, height, ldr, &text)?);
    commit_all(staged)
}

/// `tonemap NAME, exposure E EV`, then `, aa fxaa` with edge anti-aliasing (debug views:
/// `debug view NAME, no tone curve`).
pub fn display_note(options: &super::RenderOptions) -> String {
    if options.debug_view != super::DebugView::None {
        format!("debug view {}, no tone curve", options.debug_view.name())
    } else {
        let aa = match options.antialias {
            super::Antialias::None => String::new(),
            a => format!(", aa {}", a.name()),
        };
        format!(
            "tonemap {}, exposure {} EV{aa}",
            options.tonemap.name(),
            options.exposure
        )
    }
}

/// A file a command is about to write, and how the user named it, for messages (`-o`,
/// `--exr`, `-o of frame 12`).
#[derive(Clone, Debug)]
pub struct OutputPath {
    pub flag: String,
    pub path: PathBuf,
}

impl OutputPath {
    pub fn new(flag: impl Into<String>, path: impl Into<PathBuf>) -> OutputPath {
        OutputPath {
            flag: flag.into(),
            path: path.into(),
        }
    }
}

/// The directory entry `path` names: its directory made canonical (links and `..` resolved),
/// then its file name. What a rename over `path` replaces. None when the directory does not
/// exist.
fn entry(path: &Path) -> Option<PathBuf> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    Some(dir.canonicalize().ok()?.join(path.file_name()?))
}

/// Checks every file a command is about to write, before any work is done (a render, a batch, a
/// sheet, `weft fabric` alike): each must be writable by name (a file name of at most
/// [`NAME_MAX`] bytes, a path of at most [`PATH_MAX`], in a directory that exists, not itself
/// a directory), none may be one of `inputs` (the scene file, its buffers and images, the
/// environment map: writing one would destroy what the command reads), and no two may be the
/// same file (one would silently replace the other). Paths are compared by the directory entry
/// they name, so `./s.gltf`, `dir/../s.gltf` and a link to the directory all count as one.
/// Every failure is bad input ([`Error::Input`]) naming the flag and the path.
pub fn check_outputs(inputs: &[&Path], outputs: &[OutputPath]) -> crate::Result<()> {
    use std::collections::HashMap;
    use std::os::unix::ffi::OsStrExt;
    // An input is the file itself (links followed) and the entry it was named by.
    let mut read: Vec<(PathBuf, &Path)> = Vec::new();
    for &input in inputs {
        read.extend(input.canonicalize().ok().map(|c| (c, input)));
        read.extend(entry(input).map(|e| (e, input)));
    }
    let mut dirs: HashMap<&Path, Option<PathBuf>> = HashMap::new();
    let mut seen: HashMap<PathBuf, usize> = HashMap::new();
    for (i, out) in outputs.iter().enumerate() {
        let (flag, path) = (&out.flag, out.path.as_path());
        let shown = path.display();
        let bytes = path.as_os_str().as_bytes();
        let name = match path.file_name() {
            Some(n) if !bytes.ends_with(b"/") => n,
            _ => {
                return Err(Error::input(format!(
                    "{flag} '{shown}' names no file (it is empty, or ends in '/' or '..'): give it a file name"
                )))
            }
        };
        if name.len() > NAME_MAX {
            return Err(Error::input(format!(
                "{flag} '{shown}': its file name is {} bytes long, and file systems take at most {NAME_MAX}: choose a shorter name",
                name.len()
            )));
        }
        if bytes.len() > PATH_MAX {
            return Err(Error::input(format!(
                "{flag} '{}...': the path is {} bytes long, more than the {PATH_MAX} the system takes: choose a shorter one",
                String::from_utf8_lossy(&bytes[..64]),
                bytes.len()
            )));
        }
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let canonical = dirs
            .entry(dir)
            .or_insert_with(|| dir.canonicalize().ok().filter(|d| d.is_dir()));
        let Some(canonical) = canonical else {
            let dir_name = if dir == Path::new(".") {
                "the current directory".to_owned()
            } else {
                format!("'{}'", dir.display())
            };
            let why = if dir.exists() {
                format!("{dir_name} is not a directory: choose another output path")
            } else {
                format!("the directory {dir_name} does not exist: create it, or choose another output path")
            };
            return Err(Error::input(format!(
                "could not write '{shown}' ({flag}; {why})"
            )));
        };
        let id = canonical.join(name);
        if id.is_dir() {
            return Err(Error::input(format!(
                "{flag} '{shown}' is a directory: name a file in it (e.g. '{}')",
                path.join("out.png").display()
            )));
        }
        if let Some((_, input)) = read.iter().find(|(r, _)| *r == id) {
            return Err(Error::input(format!(
                "{flag} '{shown}' is '{}', a file this command reads: writing it would destroy it; choose another output path",
                input.display()
            )));
        }
        if let Some(&j) = seen.get(&id) {
            let other = &outputs[j];
            return Err(Error::input(format!(
                "{flag} '{shown}' and {} '{}' are the same file, so one would replace the other: give each output a path of its own",
                other.flag,
                other.path.display()
            )));
        }
        seen.insert(id, i);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporary_names_stay_short_and_distinct() {
        let a = format!("{}.png", "x".repeat(246));
        let b = format!("{}.exr", "x".repeat(246));
        let (ta, tb) = (temp_name(a.as_ref()), temp_name(b.as_ref()));
        assert!(
            ta.len() <= NAME_MAX && tb.len() <= NAME_MAX,
            "{} {}",
            ta.len(),
            tb.len()
        );
        assert_ne!(ta, tb);
        // Short names are kept whole, as docs/batch.md describes them.
        assert!(temp_name("f_0001.png".as_ref()).starts_with(".f_0001.png."));
        // A multi-byte character at the cut is not split.
        let c = "é".repeat(127);
        assert!(temp_name(c.as_ref()).len() <= NAME_MAX);
    }
}
