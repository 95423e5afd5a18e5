//! The near field against a ground truth that integrates the pixel (issue 15): the CPU reference
//! rasterizer (src/reference/raster.rs, f64 weave, the shading twin) renders the two-colour weave
//! of `assets/scenes/closeup.glb` at 8 x 8 samples per pixel with the weave exactly at each sample
//! point and box-filters them down; the GPU renders the same camera at each weave precision and
//! footprint filter. PSNR of the linear HDR over the pixels that are surface at every sample (the
//! truth antialiases silhouettes, which no filter here is about). Validation on.
//!
//! The views are the bench's oblique close-ups (`weft bench --footprint`): the camera 50° from the
//! patch's normal and rolled 30°, so footprints are parallelograms oblique to the weave, at a cell
//! of ~5 px (cells-10px at this 256 x 144 size) and ~0.5 px (cells-1px); and (issue 31) the fine
//! weave square-on at one and 1.5 pixels per cell and at 80° from its normal. Measured at
//! 2026-12-03 (mixture, parallelogram:2; PSNR dB): rgba16f 54.7 / 47.9 / 33.7 / 34.4 / 35.7,
//! the summed-area table (the default) 57.7 / 45.8 / 46.4 / 46.1 / 41.2, analytic 57.0 / 45.8 /
//! 46.4 / 46.2 / 41.4 (cells-10px, cells-1px, 1 px square, 1.5 px square, grazing).

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

/// The views measured: the bench's oblique close-ups as they are at this size (a cell ~5 px and
/// ~0.5 px), and the fine weave square-on at one and 1.5 pixels per cell and at 80° from its
/// normal (cells about one pixel across), their fields of view narrowed so that a cell keeps
/// the pixels it has at the bench's 360 rows ([`View::camera_for_rows`]).
const VIEWS: [View; 5] = [
    View::Cells10,
    View::Cells1,
    View::Cells1Square,
    View::Cells15Square,
    View::CellsGrazing,
];

#[test]
fn near_field_views_against_the_pixel_integral() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let mut report = Vec::new();
    for view in VIEWS {
        let scene = view.scene().load().expect("the bench's weave scene");
        let camera = match view {
            View::Cells10 | View::Cells1 => view.camera(&scene),
            _ => view.camera_for_rows(&scene, HEIGHT),
        }
        .expect("camera");
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
        let base = RenderOptions {
            width: WIDTH,
            height: HEIGHT,
            camera_override: Some(camera.clone()),
            ..Default::default()
        };
        for precision in [
            WeavePrecision::Rgba16f,
            WeavePrecision::Sat,
            WeavePrecision::Analytic,
        ] {
            for footprint in [Footprint::Box, Footprint::default()] {
                let options = RenderOptions {
                    weave_precision: precision,
                    footprint,
                    ..base.clone()
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
        // The summed-area table read texel by texel (devices that cannot filter RGBA32F) is
        // the same table: the same image to rounding.
        let filtered = renderer.render_frame(&scene, &gpu, &base).expect("render");
        let fetched = renderer
            .render_frame(
                &scene,
                &gpu,
                &RenderOptions {
                    force: weft::render::Force {
                        sat_fetch: true,
                        ..weft::render::Force::NONE
                    },
                    ..base.clone()
                },
            )
            .expect("render");
        let mask = vec![true; (WIDTH * HEIGHT) as usize];
        let same = weft::bench::psnr_linear(&filtered.hdr, &fetched.hdr, &mask);
        println!("  sat filtered against fetched: PSNR {same:.1} dB");
        assert!(
            same >= 70.0,
            "{}: the fetched table differs from the filtered one ({same:.1} dB)",
            view.name()
        );
    }
    let get = |v: View, p: WeavePrecision, f: Footprint| {
        report
            .iter()
            .find(|r| r.0 == v && r.1 == p && r.2 == f)
            .expect("measured")
            .3
    };
    let par = Footprint::default();
    assert_eq!(WeavePrecision::default(), WeavePrecision::Sat);
    for view in VIEWS {
        // Issue 31's target: the default path (mixture, the summed-area table, parallelogram)
        // at least 40 dB on every view; the analytic weave, which it approximates to the
        // texture's resolution, at least as far.
        let d = get(view, WeavePrecision::Sat, par);
        let a = get(view, WeavePrecision::Analytic, par);
        assert!(d >= 40.0, "{}: default path {d:.2} dB < 40", view.name());
        assert!(a >= 40.0, "{}: analytic {a:.2} dB < 40", view.name());
    }
    for view in [View::Cells10, View::Cells1] {
        // Oblique: the parallelogram is what earns it: each beats the bounding box it replaced.
        for p in WeavePrecision::ALL
            .into_iter()
            .filter(|p| *p != WeavePrecision::Rgba8)
        {
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
