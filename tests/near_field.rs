//! The near field against a ground truth that integrates the pixel (issue 15): the CPU reference
//! rasterizer (src/reference/raster.rs, f64 weave, the shading twin) renders the two-colour weave
//! of `assets/scenes/closeup.glb` at 8 x 8 samples per pixel with the weave exactly at each sample
//! point and box-filters them down; the GPU renders the same camera at each weave precision and
//! footprint filter. PSNR of the linear HDR over the pixels that are surface at every sample (the
//! truth antialiases silhouettes, which no filter here is about). Validation on.
//!
//! The views are the bench's oblique close-ups (`weft bench --footprint`): the camera 50° from the
//! patch's normal and rolled 30°, so footprints are parallelograms oblique to the weave, at a cell
//! of ~5 px (cells-10px at this 256 x 144 size) and ~0.5 px (cells-1px).

mod common;

use weft::bench::View;
use weft::reference::raster::{self, RasterOptions};
use weft::render::{Footprint, RenderOptions, Renderer, WeavePrecision};

const WIDTH: u32 = 256;
const HEIGHT: u32 = 144;
const SAMPLES: u32 = 16;

/// PSNR over the pixels the truth covers at every sample (`weft::bench::psnr_linear`, the bench's).
fn psnr(truth: &raster::RasterImage, hdr: &[f32]) -> f64 {
    assert!(truth.covered.iter().any(|c| *c), "no covered pixels");
    weft::bench::psnr_linear(&truth.hdr, hdr, &truth.covered)
}

#[test]
fn oblique_close_ups_against_the_pixel_integral() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let mut report = Vec::new();
    for view in [View::Cells10, View::Cells1] {
        let scene = view.scene().load().expect("the bench's weave scene");
        let camera = view.camera(&scene).expect("camera");
        let start = std::time::Instant::now();
        let truth = raster::render_pixel_integrated(
            &scene,
            &RasterOptions {
                width: WIDTH,
                height: HEIGHT,
                camera: camera.clone(),
                exposure: 0.0,
                subdivisions: 0,
                pieces: 0,
                shading: Default::default(),
            },
            SAMPLES,
        )
        .expect("CPU pixel truth");
        println!(
            "{}: CPU truth {SAMPLES}x{SAMPLES} in {:.1} s, {:.0} % of pixels covered",
            view.name(),
            start.elapsed().as_secs_f64(),
            100.0 * truth.covered.iter().filter(|c| **c).count() as f64
                / truth.covered.len() as f64
        );
        let gpu = renderer.upload(&scene).expect("upload");
        for precision in [WeavePrecision::Rgba16f, WeavePrecision::Analytic] {
            for footprint in [Footprint::Box, Footprint::default()] {
                let options = RenderOptions {
                    width: WIDTH,
                    height: HEIGHT,
                    camera_override: Some(camera.clone()),
                    weave_precision: precision,
                    footprint,
                    ..Default::default()
                };
                let frame = renderer
                    .render_frame(&scene, &gpu, &options)
                    .expect("render");
                let p = psnr(&truth, &frame.hdr);
                println!(
                    "  {:<8} {:<16} PSNR {p:.2} dB",
                    precision.name(),
                    footprint.name()
                );
                report.push((view, precision, footprint, p));
            }
        }
    }
    let get = |v: View, p: WeavePrecision, f: Footprint| {
        report
            .iter()
            .find(|r| r.0 == v && r.1 == p && r.2 == f)
            .expect("measured")
            .3
    };
    let par = Footprint::default();
    for view in [View::Cells10, View::Cells1] {
        // The targets: the default path (mixture, RGBA16F texture, parallelogram) at least
        // 40 dB, mixture with the analytic weave at least 45 dB, at every scale.
        let d = get(view, WeavePrecision::Rgba16f, par);
        let a = get(view, WeavePrecision::Analytic, par);
        assert!(d >= 40.0, "{}: default path {d:.2} dB < 40", view.name());
        assert!(a >= 45.0, "{}: analytic {a:.2} dB < 45", view.name());
        // And the parallelogram is what earns it: each beats the bounding box it replaced.
        for p in [WeavePrecision::Rgba16f, WeavePrecision::Analytic] {
            let b = get(view, p, Footprint::Box);
            let q = get(view, p, par);
            assert!(
                q > b,
                "{} {}: parallelogram {q:.2} dB not above the box's {b:.2}",
                view.name(),
                p.name()
            );
        }
    }
}
