//! `weft bench` on a tiny configuration, with validation on: the CSV and the plot are written and
//! the table has a row for every measurement. No timing assertions: machines are noisy.

mod common;

use weft::bench::{self, BenchConfig, View};
use weft::render::{Accuracy, WeavePrecision};

#[test]
fn tiny_bench_writes_every_row_the_csv_and_the_plot() {
    let out = tempfile::tempdir().expect("a temporary directory");
    let config = BenchConfig {
        views: vec![View::Mid, View::Far],
        variants: vec![
            (Accuracy::Nearest, WeavePrecision::Rgba8),
            (Accuracy::Mixture, WeavePrecision::Rgba16f),
            (Accuracy::Mixture, WeavePrecision::Analytic),
            (Accuracy::Supersampled(2), WeavePrecision::Analytic),
        ],
        truth_samples: 2,
        size: (96, 54),
        frames: 1,
        warmup: 0,
        large_frames: 1,
        resolutions: vec![(64, 36), (96, 54)],
        light_counts: vec![1, 3],
        lights_size: (64, 36),
        pbr_size: Some((64, 36)),
        pbr_views: vec![View::CloseUp],
        out: out.path().join("bench"),
        progress: false,
    };
    let report = bench::run(common::context(), &config).expect("the bench runs");

    assert_eq!(report.ground_truth.len(), 2);
    assert_eq!(report.accuracy.len(), 2 * 4);
    assert_eq!(report.resolutions.len(), 2);
    assert_eq!(report.lights.len(), 2);
    assert_eq!(report.pbr.len(), 1);
    for r in &report.accuracy {
        assert!(
            r.flip_mean.is_finite() && (0.0..=1.0).contains(&r.flip_mean),
            "{r:?}"
        );
        assert!(r.rmse.is_finite() && r.rmse >= 0.0, "{r:?}");
        assert!(
            r.times.gbuffer_ms >= 0.0 && r.times.lighting_ms >= 0.0,
            "{r:?}"
        );
    }
    // The default scene's cloth is on screen in every view.
    for g in &report.ground_truth {
        assert!(g.fabric_fraction > 0.0 && g.fabric_fraction < 1.0, "{g:?}");
    }

    let table = report.table();
    for r in &report.accuracy {
        let row = format!(
            "{:<10} {:<16} {:<9}",
            r.view.name(),
            r.level.name(),
            r.precision.name()
        );
        assert!(
            table.lines().any(|l| l.starts_with(&row)),
            "no table row for {row:?} in\n{table}"
        );
    }
    for size in ["64x36", "96x54"] {
        assert!(
            table.lines().any(|l| l.starts_with(size)),
            "no resolution row {size} in\n{table}"
        );
    }
    for n in ["1 ", "3 "] {
        assert!(
            table.lines().any(|l| l.starts_with(n)),
            "no light-count row {n:?} in\n{table}"
        );
    }
    assert!(
        table.contains("ms per megapixel") && table.contains("ms per light"),
        "{table}"
    );
    assert!(
        table.contains("close-up") && table.contains("fabric lighting"),
        "{table}"
    );

    let csv = std::fs::read_to_string(&report.csv).expect("bench.csv is written");
    let lines: Vec<&str> = csv.lines().collect();
    let columns = lines[0].split(',').count();
    for l in &lines {
        assert_eq!(l.split(',').count(), columns, "ragged CSV line {l:?}");
    }
    let count = |section: &str| {
        lines
            .iter()
            .filter(|l| l.split(',').next() == Some(section))
            .count()
    };
    assert_eq!(count("ground-truth"), 2);
    assert_eq!(count("accuracy"), 8);
    assert_eq!(count("resolution"), 2);
    assert_eq!(count("lights"), 2);
    assert_eq!(count("pbr-fabric"), 1);
    assert_eq!(count("fit-resolution"), 1);
    assert_eq!(count("fit-lights"), 1);

    let png = image::open(&report.png)
        .expect("bench.png is a readable image")
        .to_rgb8();
    assert!(png.width() >= 640 && png.height() >= 400);
    // Something was drawn in the plot area: not all of it is the white background.
    let drawn = png.pixels().filter(|p| p.0 != [255, 255, 255]).count();
    assert!(
        drawn > (png.width() * png.height()) as usize / 50,
        "the plot is nearly empty"
    );
}

#[test]
fn presets_are_consistent() {
    for config in [BenchConfig::default(), BenchConfig::quick()] {
        assert!(!config.views.is_empty() && !config.variants.is_empty());
        assert!(config.frames >= 1 && config.light_counts.iter().all(|&n| n >= 1));
        assert!(config.truth_samples >= 6);
    }
    let full = BenchConfig::default();
    assert_eq!(full.views, View::ALL.to_vec());
    // nearest, filtered-params and mixture at every precision; supersampled:2/4/8 analytic only.
    assert_eq!(full.variants, bench::default_variants());
    assert_eq!(full.variants.len(), 3 * WeavePrecision::ALL.len() + 3);
    for level in bench::LEVELS {
        assert!(
            full.variants.iter().any(|v| v.0 == level),
            "{level:?} missing"
        );
    }
    assert!(full.resolutions.contains(&(3840, 2160)));
    assert_eq!(full.light_counts, vec![1, 4, 16, 64]);
    assert_eq!(full.pbr_size, Some((1920, 1080)));
}

#[test]
fn views_are_deterministic_and_distinct() {
    // Each view's camera on its own scene; two views of one scene never share a camera (the two
    // close-up weaves share theirs: they differ in the weave's pitch).
    let cams: Vec<_> = View::ALL
        .iter()
        .map(|v| {
            let scene = v.scene().load().expect("the view's scene");
            (v.scene(), v.camera(&scene).expect("a camera"), scene)
        })
        .collect();
    for (i, (kind, a, scene)) in cams.iter().enumerate() {
        let again = View::ALL[i].camera(scene).unwrap();
        assert_eq!(a.view, again.view);
        for (other, b, _) in &cams[i + 1..] {
            if other == kind {
                assert_ne!(a.view, b.view);
            }
        }
    }
    let scene = weft::scene::default_scene();
    for v in View::ALL {
        assert_eq!(View::parse(v.name()).unwrap(), v);
    }
    let lit = bench::with_point_lights(&scene, 16);
    assert_eq!(lit.lights.len(), 16);
    assert!(lit
        .lights
        .iter()
        .all(|l| l.range.is_some() && l.position.is_finite()));
}

/// The equal-error interpolation of `weft bench --ibl`: log-log between the measured points.
#[test]
fn equal_error_samples_interpolate_in_log_log() {
    use weft::bench::ibl_bench::equal_error_samples;
    // The error halves for every 4x the samples (Monte Carlo's 1/sqrt(N)).
    let curve = [(4, 0.2), (16, 0.1), (64, 0.05)];
    let n = equal_error_samples(&curve, 0.1).unwrap();
    assert!((n - 16.0).abs() < 1e-9, "{n}");
    let n = equal_error_samples(&curve, 0.1 / 2f64.sqrt()).unwrap();
    assert!((n - 32.0).abs() < 1e-9, "{n}");
    // Outside the measured range: no answer (the table says on which side).
    assert_eq!(equal_error_samples(&curve, 0.3), None);
    assert_eq!(equal_error_samples(&curve, 0.01), None);
}

/// `weft bench --load`: one row per scene with its medians, ratio and texture memory; the KTX2
/// scene's figures reflect its files (ETC1S without mips: no BC7 chain, RGBA8 memory).
#[test]
fn load_bench_prints_a_row_per_scene() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/compressed");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_weft"))
        .args(["bench", "--frames", "1", "--load"])
        .arg(data.join("avocado_small.glb"))
        .arg(data.join("avocado_etc1s.glb"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Vec<&str> = text.lines().filter(|l| l.contains("avocado_")).collect();
    assert_eq!(rows.len(), 2, "{text}");
    // avocado_small: 3 textures of 64 x 64, RGBA8 with mips: 3 x 21,844 bytes = 0.06 MiB.
    for row in &rows {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(
            cells[3],
            if row.contains("small") {
                "1.00"
            } else {
                cells[3]
            },
            "{row}"
        );
        assert_eq!(cells[4], "3", "{row}");
        assert_eq!(cells[5], "0", "{row}");
        assert_eq!((cells[6], cells[7]), ("0.1", "0.1"), "{row}");
        assert!(cells[2].parse::<f64>().unwrap() > 0.0, "{row}");
    }
}
