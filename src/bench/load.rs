//! `weft bench --load SCENE...`: what reading each scene costs (the loader alone: container,
//! decompression of geometry, decoding and transcoding of textures), the runs interleaved across
//! the scenes so that machine load falls on all of them alike, with each scene's texture memory as
//! uploaded (RGBA8 with built mips, or its files' BC7 mip chains on a device that samples BC7).

use std::path::PathBuf;
use std::time::Instant;

/// One scene's figures.
pub struct LoadRow {
    pub path: PathBuf,
    pub median_ms: f64,
    pub textures: usize,
    pub bc7_textures: usize,
    /// Device bytes of the textures, RGBA8 with full mip chains.
    pub rgba8_bytes: u64,
    /// Device bytes where the BC7 chains are uploaded as BC7.
    pub bc7_device_bytes: u64,
}

/// Loads each of `paths` `runs` times, round-robin; the median per scene.
pub fn run(paths: &[PathBuf], runs: u32) -> crate::Result<Vec<LoadRow>> {
    let mut times = vec![Vec::new(); paths.len()];
    let mut rows = Vec::new();
    for run in 0..runs.max(1) {
        for (i, path) in paths.iter().enumerate() {
            let start = Instant::now();
            let scene = crate::scene::load(path)?;
            times[i].push(start.elapsed().as_secs_f64() * 1e3);
            if run == 0 {
                let chain = |w: u32, h: u32, bytes: &dyn Fn(u32, u32) -> u64| -> u64 {
                    let levels = 32 - w.max(h).max(1).leading_zeros();
                    (0..levels)
                        .map(|l| bytes((w >> l).max(1), (h >> l).max(1)))
                        .sum()
                };
                let rgba8 = |w: u32, h: u32| u64::from(w) * u64::from(h) * 4;
                let mut row = LoadRow {
                    path: path.clone(),
                    median_ms: 0.0,
                    textures: scene.textures.len(),
                    bc7_textures: 0,
                    rgba8_bytes: 0,
                    bc7_device_bytes: 0,
                };
                for t in &scene.textures {
                    let full = chain(t.width, t.height, &rgba8);
                    row.rgba8_bytes += full;
                    row.bc7_device_bytes += match &t.bc7 {
                        Some(levels) => {
                            row.bc7_textures += 1;
                            levels.iter().map(|l| l.len() as u64).sum()
                        }
                        None => full,
                    };
                }
                rows.push(row);
            }
        }
    }
    for (row, t) in rows.iter_mut().zip(times) {
        row.median_ms = super::median(t);
    }
    Ok(rows)
}

/// The table: per scene the median load, its ratio to the first scene's, and texture memory.
pub fn table(rows: &[LoadRow], runs: u32) -> String {
    let mut out = format!(
        "load: the loader alone, median of {runs} runs interleaved across the scenes (ratio to the first scene's)\n\n\
         | scene | load ms | ratio | textures | BC7 chains | texture MiB as RGBA8 + mips | on a BC7 device |\n\
         |---|---|---|---|---|---|---|\n"
    );
    let first = rows.first().map_or(1.0, |r| r.median_ms.max(1e-9));
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    for r in rows {
        out += &format!(
            "| {} | {:.1} | {:.2} | {} | {} | {:.1} | {:.1} |\n",
            r.path.display(),
            r.median_ms,
            r.median_ms / first,
            r.textures,
            r.bc7_textures,
            mib(r.rgba8_bytes),
            mib(r.bc7_device_bytes)
        );
    }
    out
}
