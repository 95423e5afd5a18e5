//! `weft sheet`: a contact sheet of many scenes, each rendered with the same options, labelled
//! with its name and mean display value, in one PNG; scenes that fail show their error instead.

use crate::bench::plot::{text_width, Canvas};

const MARGIN: u32 = 4;

/// One cell of the sheet: a name and either a rendered RGBA8 image or the error it gave.
pub struct Cell {
    pub name: String,
    pub image: Result<Vec<u8>, String>,
}

/// Mean of the RGB channels of an RGBA8 image, in [0, 255].
pub fn mean_srgb(rgba: &[u8]) -> f64 {
    let sum: u64 = rgba
        .chunks_exact(4)
        .map(|p| p[0] as u64 + p[1] as u64 + p[2] as u64)
        .sum();
    sum as f64 / (rgba.len() / 4 * 3).max(1) as f64
}

/// Lays out `cells` (images all `w` x `h`) in rows of `columns`, each labelled under it with its
/// name and mean sRGB value (or "FAILED" on a red panel). Returns (width, height, RGBA8).
pub fn compose(cells: &[Cell], w: u32, h: u32, columns: u32) -> (u32, u32, Vec<u8>) {
    let columns = columns.clamp(1, cells.len().max(1) as u32);
    let rows = (cells.len() as u32).div_ceil(columns).max(1);
    let scale = 1;
    let label_h = 2 * (7 * scale) as u32 + 3 * MARGIN;
    let width = MARGIN + columns * (w + MARGIN);
    let height = MARGIN + rows * (h + label_h + MARGIN);
    let mut canvas = Canvas::new(width, height, [1.0, 1.0, 1.0]);
    for (k, cell) in cells.iter().enumerate() {
        let (col, row) = (k as u32 % columns, k as u32 / columns);
        let x = (MARGIN + col * (w + MARGIN)) as i32;
        let y = (MARGIN + row * (h + label_h + MARGIN)) as i32;
        let second = match &cell.image {
            Ok(rgba) => {
                canvas.image(x, y, w, h, rgba);
                format!("MEAN {:.0}", mean_srgb(rgba))
            }
            Err(_) => {
                canvas.fill_rect(x, y, x + w as i32, y + h as i32, [0.8, 0.2, 0.2]);
                "FAILED".into()
            }
        };
        // Names longer than the cell are cut.
        let mut name = cell.name.clone();
        while text_width(&name, scale) > w as i32 && !name.is_empty() {
            name.pop();
        }
        let ty = y + h as i32 + MARGIN as i32;
        canvas.text(x, ty, &name, scale, [0.1, 0.1, 0.12]);
        canvas.text(
            x,
            ty + 7 * scale + MARGIN as i32,
            &second,
            scale,
            [0.35, 0.35, 0.4],
        );
    }
    (width, height, canvas.to_rgba8())
}

/// Every `.gltf` and `.glb` under `paths` (files as given, folders searched recursively), sorted.
pub fn find_scenes(paths: &[std::path::PathBuf]) -> Vec<std::path::PathBuf> {
    fn walk(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if matches!(
                p.extension()
                    .and_then(|x| x.to_str())
                    .map(|x| x.to_ascii_lowercase())
                    .as_deref(),
                Some("gltf" | "glb")
            ) {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            walk(p, &mut out);
        } else {
            out.push(p.clone());
        }
    }
    out.sort();
    out
}
