//! The bench's table, CSV and plot.

use super::*;

impl BenchReport {
    /// The ratio of the first PBR row that has one (the mid view when run by default).
    pub fn pbr_ratio(&self) -> Option<f64> {
        self.pbr.first().map(|r| r.ratio())
    }

    /// (slope ms per megapixel, intercept ms) of G-buffer + lighting time over resolution.
    pub fn ms_per_megapixel(&self) -> Option<(f64, f64)> {
        fit_line(
            &self
                .resolutions
                .iter()
                .map(|r| (r.megapixels(), r.times.total_ms()))
                .collect::<Vec<_>>(),
        )
    }

    /// (slope ms per light, intercept ms) of the lighting pass over the number of point lights.
    pub fn ms_per_light(&self) -> Option<(f64, f64)> {
        fit_line(
            &self
                .lights
                .iter()
                .map(|r| (r.lights as f64, r.times.lighting_ms))
                .collect::<Vec<_>>(),
        )
    }

    /// The whole report as text: machine, the accuracy table, the growth tables, the ratio.
    pub fn table(&self) -> String {
        use std::fmt::Write;
        let m = &self.machine;
        let mut t = String::new();
        let load = |l: Option<f64>| l.map(|l| format!("{l:.2}")).unwrap_or_else(|| "?".into());
        let _ = writeln!(
            t,
            "device   {} — {} (Vulkan {})",
            m.device, m.driver, m.api_version
        );
        let _ = writeln!(
            t,
            "cpu      {} x {} — load average {} at start, {} at end",
            m.cores,
            m.cpu,
            load(m.load_start),
            load(m.load_end)
        );
        let _ = writeln!(
            t,
            "times    GPU timestamps, one pass per submit, median of warm frames; validation {}",
            if m.validation { "ON (slower)" } else { "off" }
        );
        let _ = writeln!(t);
        let (w, h) = self.size;
        let _ = writeln!(
            t,
            "accuracy at {w}x{h} against the pixel-integrating ground truth, errors over the fabric pixels:"
        );
        for g in &self.ground_truth {
            let _ = writeln!(
                t,
                "  {:<10} ground truth {n}x{n} jittered point samples per pixel: gbuffer {} ms + lighting {} ms (sum of {} frames), fabric fills {:.0}% of the image, its own PSNR {}",
                g.view.name(),
                fmt_ms(g.times.gbuffer_ms),
                fmt_ms(g.times.lighting_ms),
                g.times.frames,
                g.fabric_fraction * 100.0,
                g.noise_psnr.map(|p| format!("~{p:.1} dB")).unwrap_or_else(|| "unknown".into()),
                n = g.samples,
            );
        }
        let _ = writeln!(
            t,
            "{:<10} {:<16} {:<9} {:>10} {:>11} {:>9} {:>10} {:>10} {:>8} {:>6}",
            "view",
            "level",
            "precision",
            "gbuffer ms",
            "lighting ms",
            "total ms",
            "FLIP mean",
            "HDR RMSE",
            "PSNR dB",
            "front"
        );
        for r in &self.accuracy {
            let _ = writeln!(
                t,
                "{:<10} {:<16} {:<9} {:>10} {:>11} {:>9} {:>10.5} {:>10.5} {:>8.2} {:>6}",
                r.view.name(),
                r.level.name(),
                r.precision.name(),
                fmt_ms(r.times.gbuffer_ms),
                fmt_ms(r.times.lighting_ms),
                fmt_ms(r.times.total_ms()),
                r.flip_mean,
                r.rmse,
                r.psnr,
                if r.pareto { "*" } else { "" }
            );
        }
        let _ = writeln!(t, "front: * = on the view's Pareto front (no other variant of the view is both faster and closer)");
        if !self.resolutions.is_empty() {
            let _ = writeln!(t);
            let _ = writeln!(
                t,
                "growth over resolution (mid view, mixture, rgba16f, the scene's 3 lights):"
            );
            let _ = writeln!(
                t,
                "{:<10} {:>6} {:>10} {:>11} {:>9} {:>8}",
                "size", "MP", "gbuffer ms", "lighting ms", "total ms", "ms/MP"
            );
            for r in &self.resolutions {
                let _ = writeln!(
                    t,
                    "{:<10} {:>6.2} {:>10} {:>11} {:>9} {:>8.1}",
                    format!("{}x{}", r.width, r.height),
                    r.megapixels(),
                    fmt_ms(r.times.gbuffer_ms),
                    fmt_ms(r.times.lighting_ms),
                    fmt_ms(r.times.total_ms()),
                    r.times.total_ms() / r.megapixels()
                );
            }
            if let Some((slope, intercept)) = self.ms_per_megapixel() {
                let _ = writeln!(t, "fit: {slope:.1} ms per megapixel + {intercept:.1} ms");
            }
        }
        if !self.lights.is_empty() {
            let _ = writeln!(t);
            let (lw, lh) = (self.lights[0].width, self.lights[0].height);
            let _ = writeln!(
                t,
                "growth over point lights (mid view, mixture, rgba16f, {lw}x{lh}):"
            );
            let _ = writeln!(
                t,
                "{:<7} {:>10} {:>11} {:>12}",
                "lights", "gbuffer ms", "lighting ms", "lighting/N"
            );
            for r in &self.lights {
                let _ = writeln!(
                    t,
                    "{:<7} {:>10} {:>11} {:>12}",
                    r.lights,
                    fmt_ms(r.times.gbuffer_ms),
                    fmt_ms(r.times.lighting_ms),
                    fmt_ms(r.times.lighting_ms / r.lights as f64)
                );
            }
            if let Some((slope, intercept)) = self.ms_per_light() {
                let _ = writeln!(
                    t,
                    "fit: {slope:.2} ms per light + {intercept:.1} ms (lighting pass)"
                );
            }
        }
        if !self.pbr.is_empty() {
            let _ = writeln!(t);
            let _ = writeln!(t, "fabric lighting pass against metallic-roughness on the same G-buffer (mixture, rgba16f):");
            for r in &self.pbr {
                let head = format!(
                    "{:<9} {}x{} fabric {:.0}% of the image: fabric lighting {} ms",
                    r.view.name(),
                    r.width,
                    r.height,
                    r.fabric_fraction * 100.0,
                    fmt_ms(r.fabric.lighting_ms)
                );
                let _ = writeln!(
                    t,
                    "{head}, as metallic-roughness {} ms: ratio {:.2}x (target: within 1.5x); \
                     about {:.1}x per fabric pixel",
                    fmt_ms(r.pbr.lighting_ms),
                    r.ratio(),
                    r.ratio_per_fabric_pixel()
                );
            }
        }
        let _ = writeln!(t);
        let _ = writeln!(
            t,
            "run took {:.0} s; wrote {} and {}",
            self.seconds,
            self.csv.display(),
            self.png.display()
        );
        t
    }

    /// One row per measurement; `section` says which table it belongs to.
    pub fn csv_text(&self) -> String {
        let mut t = CSV_COLUMNS.join(",");
        t.push('\n');
        let (w, h) = self.size;
        let base = |section: &str,
                    view: View,
                    level: String,
                    precision: WeavePrecision,
                    size: (u32, u32),
                    lights: usize| {
            let mut r = CsvRow::default();
            r.set("section", section);
            r.set("view", view.name());
            r.set("level", level);
            r.set("precision", precision.name());
            r.set("width", size.0);
            r.set("height", size.1);
            r.set("lights", lights);
            r
        };
        let times = |r: &mut CsvRow, p: &PassTimes| {
            r.set("frames", p.frames);
            r.set("gbuffer_ms", format!("{:.4}", p.gbuffer_ms));
            r.set("lighting_ms", format!("{:.4}", p.lighting_ms));
            r.set("total_ms", format!("{:.4}", p.total_ms()));
        };
        let scene_lights = 3; // the default scene's key, fill and rim lights
        for g in &self.ground_truth {
            let mut r = base(
                "ground-truth",
                g.view,
                format!("pixel:{}", g.samples),
                WeavePrecision::Analytic,
                (w, h),
                scene_lights,
            );
            times(&mut r, &g.times);
            r.set("fabric_fraction", format!("{:.4}", g.fabric_fraction));
            if let Some(p) = g.noise_psnr {
                r.set("psnr_db", format!("{p:.3}"));
            }
            r.push(&mut t);
        }
        for a in &self.accuracy {
            let mut r = base(
                "accuracy",
                a.view,
                a.level.name(),
                a.precision,
                (w, h),
                scene_lights,
            );
            times(&mut r, &a.times);
            r.set("flip_mean", format!("{:.6}", a.flip_mean));
            r.set("rmse_hdr", format!("{:.6}", a.rmse));
            r.set("psnr_db", format!("{:.3}", a.psnr));
            r.set("pareto", a.pareto as u8);
            r.push(&mut t);
        }
        let default = (Accuracy::Mixture, WeavePrecision::default());
        for g in &self.resolutions {
            let mut r = base(
                "resolution",
                View::Mid,
                default.0.name(),
                default.1,
                (g.width, g.height),
                scene_lights,
            );
            times(&mut r, &g.times);
            r.set(
                "ms_per_mp",
                format!("{:.4}", g.times.total_ms() / g.megapixels()),
            );
            r.push(&mut t);
        }
        for g in &self.lights {
            let mut r = base(
                "lights",
                View::Mid,
                default.0.name(),
                default.1,
                (g.width, g.height),
                g.lights as usize,
            );
            times(&mut r, &g.times);
            r.set(
                "ms_per_light",
                format!("{:.4}", g.times.lighting_ms / g.lights as f64),
            );
            r.push(&mut t);
        }
        for p in &self.pbr {
            for (section, pt) in [
                ("pbr-fabric", &p.fabric),
                ("pbr-metallic-roughness", &p.pbr),
            ] {
                let mut r = base(
                    section,
                    p.view,
                    default.0.name(),
                    default.1,
                    (p.width, p.height),
                    scene_lights,
                );
                times(&mut r, pt);
                r.set("fabric_fraction", format!("{:.4}", p.fabric_fraction));
                r.set("ratio", format!("{:.4}", p.ratio()));
                r.set(
                    "ratio_per_fabric_pixel",
                    format!("{:.4}", p.ratio_per_fabric_pixel()),
                );
                r.push(&mut t);
            }
        }
        if let Some((slope, intercept)) = self.ms_per_megapixel() {
            let mut r = base(
                "fit-resolution",
                View::Mid,
                default.0.name(),
                default.1,
                (0, 0),
                scene_lights,
            );
            r.set("width", "");
            r.set("height", "");
            r.set("ms_per_mp", format!("{slope:.4}"));
            r.set("total_ms", format!("{intercept:.4}"));
            r.push(&mut t);
        }
        if let Some((slope, intercept)) = self.ms_per_light() {
            let (lw, lh) = self
                .lights
                .first()
                .map(|l| (l.width, l.height))
                .unwrap_or((0, 0));
            let mut r = base(
                "fit-lights",
                View::Mid,
                default.0.name(),
                default.1,
                (lw, lh),
                0,
            );
            r.set("lights", "");
            r.set("ms_per_light", format!("{slope:.4}"));
            r.set("lighting_ms", format!("{intercept:.4}"));
            r.push(&mut t);
        }
        t
    }
}

/// The columns of bench.csv. In the `fit-*` rows, `ms_per_mp` / `ms_per_light` is the fitted slope
/// and `total_ms` / `lighting_ms` the intercept.
pub const CSV_COLUMNS: [&str; 20] = [
    "section",
    "view",
    "level",
    "precision",
    "width",
    "height",
    "lights",
    "frames",
    "gbuffer_ms",
    "lighting_ms",
    "total_ms",
    "flip_mean",
    "rmse_hdr",
    "psnr_db",
    "ms_per_mp",
    "ms_per_light",
    "fabric_fraction",
    "ratio",
    "ratio_per_fabric_pixel",
    "pareto",
];

/// One CSV line, filled by column name; unset columns stay empty.
#[derive(Default)]
pub(crate) struct CsvRow(Vec<(usize, String)>);

impl CsvRow {
    fn set(&mut self, column: &str, value: impl ToString) {
        let i = CSV_COLUMNS
            .iter()
            .position(|c| *c == column)
            .expect("a column of CSV_COLUMNS");
        self.0.retain(|(j, _)| *j != i);
        self.0.push((i, value.to_string()));
    }

    fn push(&self, out: &mut String) {
        let mut fields = vec![String::new(); CSV_COLUMNS.len()];
        for (i, v) in &self.0 {
            fields[*i] = v.clone();
        }
        out.push_str(&fields.join(","));
        out.push('\n');
    }
}
