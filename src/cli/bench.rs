//! `weft bench`: every table of what accuracy costs in time.

use super::*;

#[derive(Args)]
pub(super) struct BenchArgs {
    /// A short run (about 15 s on lavapipe): smaller images, fewer levels.
    #[arg(long)]
    pub(super) quick: bool,
    /// Instead: what the plan's skipping saves (each skippable effect forced on against the
    /// plan, same run) and 4 against 256 point lights of limited range.
    #[arg(long)]
    pub(super) plan: bool,
    /// Instead: the IBL levels (approx, fis:4/16/64) against a Monte Carlo ground truth, and the
    /// lighting pass with environment light against lamps only.
    #[arg(long)]
    pub(super) ibl: bool,
    /// Instead: time to the first picture: the whole `weft render` process at --size (default
    /// scene, 5 runs, median) against the warm frame of the same render (same run), and their
    /// ratio.
    #[arg(long)]
    pub(super) startup: bool,
    /// Instead: the default scene's frame (--size, default 1920x1080) as one queue submission, the
    /// normal path, against one submission per pass (what --timings and the other benches use),
    /// frames interleaved in one process (--frames, default 5).
    #[arg(long)]
    pub(super) submission: bool,
    /// Instead: temporal stability: the camera turning slowly at the mid and far views, the
    /// consecutive-frame change on fabric of every level against the supersampled ground truth's
    /// (ratio = how much more it flickers). --size (default 320x180), --frames (default 9).
    #[arg(long)]
    pub(super) temporal: bool,
    /// Degrees the camera turns between frames in --temporal.
    #[arg(long, default_value_t = 0.1, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--temporal-step", s))]
    pub(super) temporal_step: f32,
    /// The environment of the --ibl bench (default: tests/data/env/lebombo_1k.hdr of weft's
    /// source tree; the built-in studio where weft was installed without it).
    #[arg(long)]
    pub(super) ibl_env: Option<PathBuf>,
    /// Monte Carlo samples per pixel of the --ibl ground truth.
    #[arg(long, default_value_t = 2048)]
    pub(super) ibl_truth: u32,
    /// Image size of the --plan and --ibl benches.
    #[arg(long, default_value = "960x540")]
    pub(super) size: String,
    /// Where bench.csv and bench.png go.
    #[arg(long, default_value = "target/bench")]
    pub(super) out: PathBuf,
    /// Timed frames per measurement (medians of these, after warm-up).
    #[arg(long)]
    pub(super) frames: Option<u32>,
    /// Vulkan device: auto, cpu (lavapipe), an index, or part of a name. Also WEFT_DEVICE.
    #[arg(long)]
    pub(super) device: Option<String>,
    /// Only these views of the accuracy sweep (comma-separated: close-up, mid, far, grazing,
    /// cells-10px, cells-1px, cells-1px-square, cells-1.5px-square,
    /// cells-grazing).
    #[arg(long, value_delimiter = ',', value_parser = parse_bench_view)]
    pub(super) views: Option<Vec<weft::bench::View>>,
    /// Jittered point samples per pixel side of the ground truth (N x N frames per view).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=weft::bench::MAX_TRUTH_SAMPLES as i64))]
    pub(super) truth_samples: Option<u32>,
    /// Only the accuracy sweep: skip the growth over resolution and lights and the PBR ratio.
    #[arg(long)]
    pub(super) accuracy_only: bool,
    /// Instead: the footprint filters (box against parallelogram:2 and :3) per view, texture and
    /// analytic weave, timed in one run, against the pixel-integrating ground truth.
    #[arg(long)]
    pub(super) footprint: bool,
    /// Instead: what loading each of these scenes costs (the loader alone, --frames runs each,
    /// default 5, interleaved; medians and the ratio to the first scene's), with each scene's
    /// texture memory as uploaded (RGBA8 with mips, or its KTX2 files' BC7 chains).
    #[arg(long, num_args = 1.., value_name = "SCENE")]
    pub(super) load: Vec<PathBuf>,
}

pub(super) fn parse_bench_view(text: &str) -> Result<weft::bench::View, String> {
    weft::bench::View::parse(text).map_err(|e| e.to_string())
}

pub(super) fn run_bench(args: BenchArgs) -> anyhow::Result<()> {
    if !args.load.is_empty() {
        let runs = args.frames.unwrap_or(5);
        let rows = weft::bench::load::run(&args.load, runs)?;
        println!("{}", weft::bench::load::table(&rows, runs));
        return Ok(());
    }
    if args.startup {
        return run_startup_bench(&args);
    }
    if args.submission {
        return run_submission_bench(&args);
    }
    if args.temporal {
        let mut config = if args.quick {
            weft::bench::temporal::TemporalConfig::quick()
        } else {
            weft::bench::temporal::TemporalConfig::default()
        };
        if args.size != "960x540" {
            config.size = checked_size(&args.size)?;
        }
        if let Some(f) = args.frames {
            config.frames = f;
        }
        config.degrees_per_frame = args.temporal_step;
        config.out = args.out.clone();
        config.check()?;
        let ctx = open_device(args.device.as_deref(), false)?;
        let mut renderer = Renderer::new(ctx)?;
        let report = weft::bench::temporal::run(&mut renderer, &config)?;
        println!("{}", report.table());
        println!(
            "wrote {} and {}",
            config.out.join("temporal.csv").display(),
            config.out.join("bench-temporal.png").display()
        );
        return Ok(());
    }
    if args.ibl {
        let size = checked_size(&args.size)?;
        weft::env::IblLevel::parse(&format!("mc:{}", args.ibl_truth))?;
        // The default is Lebombo (a real HDR map with a sun) from weft's source tree, 1.4 MiB and
        // not built in; where weft was installed without its sources, the built-in studio.
        let source_tree =
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/env/lebombo_1k.hdr");
        let env = match args
            .ibl_env
            .as_ref()
            .or(source_tree.exists().then_some(&source_tree))
        {
            Some(path) => {
                eprintln!("environment: {}", path.display());
                std::sync::Arc::new(weft::env::Environment::load(path)?)
            }
            None => {
                eprintln!(
                    "environment: the built-in studio (weft's tests/data/env/lebombo_1k.hdr is not at {}; --ibl-env FILE.hdr chooses one)",
                    source_tree.display()
                );
                weft::spec::studio()
            }
        };
        let ctx = open_device(args.device.as_deref(), false)?;
        let mut renderer = Renderer::new(ctx)?;
        let report = weft::bench::ibl_bench::run(
            &mut renderer,
            env,
            size,
            args.frames.unwrap_or(5),
            args.ibl_truth,
        )?;
        println!("{}", report.table());
        std::fs::create_dir_all(&args.out)
            .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", args.out.display()))?;
        let (w, h, rgba) = report.plot();
        let png = args.out.join("bench-ibl.png");
        render::write_png(&png, w, h, &rgba)?;
        eprintln!("wrote {}", png.display());
        return Ok(());
    }
    if args.plan {
        let size = checked_size(&args.size)?;
        let ctx = open_device(args.device.as_deref(), false)?;
        let mut renderer = Renderer::new(ctx)?;
        let report = weft::bench::plan_bench::run(&mut renderer, size, args.frames.unwrap_or(7))?;
        println!("{}", report.table());
        return Ok(());
    }
    if args.footprint {
        let ctx = open_device(args.device.as_deref(), false)?;
        let views = args.views.unwrap_or_else(|| {
            vec![
                weft::bench::View::Cells10,
                weft::bench::View::Cells1,
                weft::bench::View::Cells1Square,
                weft::bench::View::Cells15Square,
                weft::bench::View::CellsGrazing,
                weft::bench::View::Far,
            ]
        });
        let report = weft::bench::footprint_bench(
            ctx,
            &views,
            (640, 360),
            args.truth_samples.unwrap_or(16),
            args.frames.unwrap_or(5),
            &args.out,
        )?;
        println!("{}", report);
        return Ok(());
    }
    let mut config = if args.quick {
        weft::bench::BenchConfig::quick()
    } else {
        weft::bench::BenchConfig::default()
    };
    config.out = args.out;
    if let Some(f) = args.frames {
        config.frames = f;
    }
    if let Some(v) = args.views {
        config.views = v;
    }
    if let Some(n) = args.truth_samples {
        config.truth_samples = n;
    }
    if args.accuracy_only {
        config.resolutions.clear();
        config.light_counts.clear();
        config.pbr_size = None;
    }
    let device = args
        .device
        .as_deref()
        .map(DeviceChoice::parse)
        .unwrap_or_else(DeviceChoice::from_env);
    let ctx = Context::new(&ContextOptions {
        validate: false,
        device,
    })?;
    let report = weft::bench::run(ctx, &config)?;
    println!("{}", report.table());
    println!(
        "wrote {} and {}",
        config.out.join("bench.csv").display(),
        config.out.join("bench.png").display()
    );
    Ok(())
}

/// `weft bench --startup`: the whole process against its warm frame, with empty caches (weft's
/// and the driver's, each run's own) and with the caches the run before it left.
pub(super) fn run_startup_bench(args: &BenchArgs) -> anyhow::Result<()> {
    let size = if args.size == "960x540" {
        "1920x1080".to_string()
    } else {
        args.size.clone()
    };
    let runs = args.frames.unwrap_or(5).max(1);
    let exe = std::env::current_exe()?;
    let dir = std::env::temp_dir().join(format!("weft-startup-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let out = dir.join("startup.png");
    let caches = dir.join("caches");
    let mut device = Vec::new();
    if let Some(d) = &args.device {
        device = vec!["--device".to_string(), d.clone()];
    }
    // weft's cache (pipelines, the studio's preprocessing) and Mesa's shader cache (lavapipe's
    // compiled shaders; RADV and other Mesa drivers keep theirs there too) in `caches`.
    let run_with = |extra: &[&str], weft_cache: bool| -> anyhow::Result<f64> {
        let t = std::time::Instant::now();
        let o = std::process::Command::new(&exe)
            .args(["render", "--size", &size, "-o"])
            .arg(&out)
            .args(&device)
            .args(extra)
            .env(
                "WEFT_CACHE_DIR",
                if weft_cache {
                    caches.join("weft")
                } else {
                    "off".into()
                },
            )
            .env("MESA_SHADER_CACHE_DIR", caches.join("mesa"))
            .output()?;
        if !o.status.success() {
            anyhow::bail!("weft render failed: {}", String::from_utf8_lossy(&o.stderr));
        }
        Ok(t.elapsed().as_secs_f64() * 1e3)
    };
    let run = |extra: &[&str]| run_with(extra, true);
    let (mut first, mut second, mut no_weft) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..runs {
        let _ = std::fs::remove_dir_all(&caches);
        // Mesa makes its cache's last directory only.
        std::fs::create_dir_all(caches.join("mesa"))?;
        first.push(run(&[])?);
        // The two second runs in turn first (the run right after the first meets a driver
        // cache still settling).
        if k % 2 == 0 {
            second.push(run(&[])?);
            no_weft.push(run_with(&[], false)?);
        } else {
            no_weft.push(run_with(&[], false)?);
            second.push(run(&[])?);
        }
    }
    // The warm frame of the same render, in this process (`weft render --frames 6 --timings`
    // computes it the same way: metrics::render_warm, the median of the 5 frames after the first).
    let warm = {
        let Loaded {
            scene, mut options, ..
        } = SceneSpec::default().load(checked_size(&size)?)?;
        options.antialias = render::Antialias::Fxaa;
        options.submission = render::Submission::Frame;
        options.read_hdr = false;
        let mut renderer = Renderer::new(open_device(args.device.as_deref(), false)?)?;
        weft::metrics::render_warm(&mut renderer, &scene, &options, 6)?.1
    };
    let _ = std::fs::remove_dir_all(&dir);
    let (first, second, no_weft) = (median(first), median(second), median(no_weft));
    println!(
        "time to the first picture: weft render --size {size} (default scene), {runs} pairs of runs"
    );
    println!("{:<44} {:>10} {:>8}", "", "ms", "/ warm");
    println!(
        "{:<44} {:>10.1} {:>8.2}",
        "first run, empty caches (median)",
        first,
        first / warm
    );
    println!(
        "{:<44} {:>10.1} {:>8.2}",
        "second run, the first's caches (median)",
        second,
        second / warm
    );
    println!(
        "{:<44} {:>10.1} {:>8.2}",
        "second run without weft's cache (median)",
        no_weft,
        no_weft / warm
    );
    println!(
        "{:<44} {:>10.1} {:>8.2}",
        "warm frame (median of 5)", warm, 1.0
    );
    println!("caches: weft's (WEFT_CACHE_DIR: pipelines, the studio's preprocessing) and Mesa's shaders (MESA_SHADER_CACHE_DIR)");
    Ok(())
}

/// `weft bench --submission`: the default render's frame submitted whole against pass by pass.
pub(super) fn run_submission_bench(args: &BenchArgs) -> anyhow::Result<()> {
    let size = if args.size == "960x540" {
        "1920x1080".to_string()
    } else {
        args.size.clone()
    };
    let frames = args.frames.unwrap_or(5).max(1);
    // The scene and options `weft render` starts from (the default scene, the studio).
    let Loaded {
        scene, mut options, ..
    } = SceneSpec::default().load(checked_size(&size)?)?;
    options.read_hdr = false;
    options.antialias = render::Antialias::Fxaa;
    let ctx = open_device(args.device.as_deref(), false)?;
    let mut renderer = Renderer::new(ctx)?;
    let gpu = renderer.upload(&scene)?;
    let rows = weft::bench::submission::run(&mut renderer, &scene, &gpu, &options, frames)?;
    print!(
        "{}",
        weft::bench::submission::table(&rows, options.width, options.height, frames)
    );
    Ok(())
}
