//! `weft bench --footprint`: the weave's footprint filters against the pixel truth.

use super::*;

/// `weft bench --footprint`: per view, the default and the analytic weave with each footprint
/// filter (the bounding box, 2 x 2 and 3 x 3 parallelogram pieces), frames of one view
/// round-robin in one run, against the pixel-integrating ground truth of `truth_samples`². Returns
/// the table; writes `footprint.csv` into `out`.
pub fn footprint_bench(
    ctx: Context,
    views: &[View],
    (width, height): (u32, u32),
    truth_samples: u32,
    frames: u32,
    out: &Path,
) -> crate::Result<String> {
    use crate::render::Footprint;
    use std::fmt::Write;
    let mut renderer = Renderer::new(ctx)?;
    let footprints = [
        Footprint::Box,
        Footprint::Parallelogram(1),
        Footprint::Parallelogram(2),
        Footprint::Parallelogram(3),
    ];
    let precisions = [
        WeavePrecision::Rgba16f,
        WeavePrecision::Sat,
        WeavePrecision::Analytic,
    ];
    let mut table = String::new();
    let mut csv = String::from("view,precision,footprint,gbuffer_ms,lighting_ms,total_ms,psnr_db,flip_mean,cost_vs_box,truth_psnr_db\n");
    let _ = writeln!(
        table,
        "footprint filters at {width}x{height}, mixture, against {truth_samples}x{truth_samples} jittered point samples per pixel (errors over the fabric pixels)"
    );
    let _ = writeln!(
        table,
        "{:<10} {:<9} {:<16} {:>10} {:>11} {:>9} {:>8} {:>9} {:>8}",
        "view",
        "precision",
        "footprint",
        "gbuffer ms",
        "lighting ms",
        "total ms",
        "PSNR dB",
        "FLIP",
        "vs box"
    );
    for &view in views {
        let scene = view.scene().load()?;
        let gpu = renderer.upload(&scene)?;
        let base = RenderOptions {
            width,
            height,
            camera_override: Some(view.camera(&scene)?),
            ..crate::bench::timed_options()
        };
        let truth = pixel_truth(&mut renderer, &scene, &gpu, &base, truth_samples, || {})?;
        let mask = truth.fabric_everywhere();
        let jobs: Vec<_> = precisions
            .iter()
            .flat_map(|&p| footprints.iter().map(move |&f| (p, f)))
            .map(|(p, f)| {
                (
                    &scene,
                    &gpu,
                    RenderOptions {
                        weave_precision: p,
                        footprint: f,
                        ..base.clone()
                    },
                )
            })
            .collect();
        let measured = measure(&mut renderer, &jobs, 1, frames, |_| {})?;
        let truth_psnr = truth.noise_psnr(&mask);
        let mut box_ms = 0.0;
        for ((_, _, o), (frame, times)) in jobs.iter().zip(&measured) {
            if o.footprint == Footprint::Box {
                box_ms = times.total_ms();
            }
            let psnr = psnr_hdr_masked(&truth.frame, frame, &mask);
            let flip = flip_mean_masked(&truth.frame, frame, &mask);
            let ratio = times.total_ms() / box_ms.max(1e-9);
            let _ = writeln!(
                table,
                "{:<10} {:<9} {:<16} {:>10} {:>11} {:>9} {:>8.2} {:>9.5} {:>7.2}x",
                view.name(),
                o.weave_precision.name(),
                o.footprint.name(),
                fmt_ms(times.gbuffer_ms),
                fmt_ms(times.lighting_ms),
                fmt_ms(times.total_ms()),
                psnr,
                flip,
                ratio
            );
            let _ = writeln!(
                csv,
                "{},{},{},{:.4},{:.4},{:.4},{:.3},{:.6},{:.4},{}",
                view.name(),
                o.weave_precision.name(),
                o.footprint.name(),
                times.gbuffer_ms,
                times.lighting_ms,
                times.total_ms(),
                psnr,
                flip,
                ratio,
                truth_psnr.map(|p| format!("{p:.3}")).unwrap_or_default()
            );
        }
        let _ = writeln!(
            table,
            "{:<10} the ground truth's own PSNR: {}",
            "",
            truth_psnr
                .map(|p| format!("~{p:.1} dB"))
                .unwrap_or_else(|| "unknown".into())
        );
    }
    create_out_dir(out)?;
    write_text(&out.join("footprint.csv"), &csv)?;
    let _ = writeln!(table, "vs box: total time against the box footprint of the same view and precision (same run, frames round-robin)");
    Ok(table)
}
