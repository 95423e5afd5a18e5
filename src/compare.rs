//! `weft compare`: the paper's figure. The same scene with its fabric shaded four ways, side by
//! side and labelled: Gouraud shading (paper figure 1), per-pixel Phong (figure 2a), plain
//! single-lobe Ashikhmin–Shirley (figure 2b) and the fabric model (figure 4). Everything but the
//! fabric's shading is the same in every panel: camera, lights, the other materials.

use crate::bench::plot::{text_width, Canvas};
use crate::render::{Frame, RenderOptions, Renderer, Shading};
use crate::scene::Scene;

/// Pixels between panels and around the figure.
const MARGIN: u32 = 4;

/// The composed figure, and the frame of each panel.
pub struct Figure {
    pub width: u32,
    pub height: u32,
    /// Display-referred RGBA8, sRGB-encoded, rows top to bottom.
    pub rgba: Vec<u8>,
    /// The panels in figure order (left to right), with the model each shows.
    pub panels: Vec<(Shading, Frame)>,
}

/// Font scale of the labels for panels `width` pixels wide: the longest label fills at most
/// about two thirds of a panel.
fn label_scale(width: u32) -> i32 {
    let longest = Shading::ALL
        .iter()
        .map(|s| text_width(s.label(), 1))
        .max()
        .unwrap_or(1);
    ((width as i32 * 2 / 3) / longest).clamp(1, 4)
}

/// Renders `scene` once per model of [`Shading::ALL`] with `options` (each panel is
/// `options.width` × `options.height`; `options.shading` is ignored) and lays the panels out in a
/// row, each with its label under it.
pub fn figure(
    renderer: &mut Renderer,
    scene: &Scene,
    options: &RenderOptions,
) -> crate::Result<Figure> {
    let gpu = renderer.upload(scene)?;
    let mut panels = Vec::new();
    for shading in Shading::ALL {
        let options = RenderOptions {
            shading,
            ..options.clone()
        };
        panels.push((shading, renderer.render_frame(scene, &gpu, &options)?));
    }
    Ok(compose(panels))
}

/// Lays out rendered panels (all of one size) in a row with their labels.
pub fn compose(panels: Vec<(Shading, Frame)>) -> Figure {
    let (pw, ph) = panels
        .first()
        .map(|(_, f)| (f.width, f.height))
        .unwrap_or((1, 1));
    let scale = label_scale(pw);
    let label_h = (7 * scale) as u32 + 2 * MARGIN;
    let n = panels.len() as u32;
    let width = MARGIN + n * (pw + MARGIN);
    let height = MARGIN + ph + label_h;
    let mut canvas = Canvas::new(width, height, [1.0, 1.0, 1.0]);
    for (i, (shading, frame)) in panels.iter().enumerate() {
        let x = (MARGIN + i as u32 * (pw + MARGIN)) as i32;
        canvas.image(x, MARGIN as i32, frame.width, frame.height, &frame.ldr);
        let label = shading.label();
        let tx = x + (pw as i32 - text_width(label, scale)) / 2;
        let ty = (MARGIN + ph + MARGIN) as i32;
        canvas.text(tx, ty, label, scale, [0.1, 0.1, 0.12]);
    }
    Figure {
        width,
        height,
        rgba: canvas.to_rgba8(),
        panels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_fit_their_panels() {
        for width in [128, 256, 480, 1920] {
            let scale = label_scale(width);
            for s in Shading::ALL {
                assert!(
                    text_width(s.label(), scale) <= width as i32,
                    "{} at {width}",
                    s.label()
                );
            }
        }
    }
}
