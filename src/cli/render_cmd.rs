//! `weft render`: one frame to PNG/EXR, or a sequence or batch share (`run_batch`).

use super::*;

#[derive(Args)]
pub(super) struct RenderArgs {
    #[command(flatten)]
    pub(super) scene: SceneArgs,
    /// Output PNG (display-referred, sRGB).
    #[arg(short, long, default_value = "weft.png")]
    pub(super) output: PathBuf,
    /// Also write the linear HDR image (before exposure and tone mapping) as OpenEXR.
    #[arg(long)]
    pub(super) exr: Option<PathBuf>,
    /// Exposure in EV (stops): the image is scaled by 2^EV before tone mapping.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--exposure", s))]
    pub(super) exposure: f32,
    /// Tone curve: pbr-neutral (Khronos PBR Neutral), aces (three.js' ACES fit with the 1/2.2
    /// display gamma of Khronos' render-fidelity goldens), agx, or none. Written into the PNG.
    #[arg(long, default_value = "pbr-neutral", value_parser = parse_tonemap)]
    pub(super) tonemap: render::ToneCurve,
    /// Anti-aliasing: fxaa (a post pass after tone mapping, glsl/fxaa.frag), none (the
    /// rasterizer's one-pixel staircases), or ssN (N x N frames at sub-pixel offsets averaged,
    /// N from 2 to 8: N² times the time, for stills; it resolves wires and detail thinner than a
    /// pixel, which FXAA cannot). Written into the PNG.
    #[arg(long, default_value = "fxaa", value_parser = parse_aa)]
    pub(super) aa: render::Antialias,
    /// Turn on the Vulkan validation layer; any message it reports fails the render.
    #[arg(long)]
    pub(super) validate: bool,
    /// Vulkan device: auto, cpu (lavapipe), an index, or part of a name. Also WEFT_DEVICE.
    #[arg(long)]
    pub(super) device: Option<String>,
    /// Print the GPU and wall time of each pass (each pass then goes to the queue on its own, for
    /// honest per-pass times: see --submit).
    #[arg(long)]
    pub(super) timings: bool,
    /// How a frame reaches the queue: frame (one submission, timestamps between the passes; the
    /// default without --timings) or pass (one submission per pass; the default with --timings).
    #[arg(long, value_parser = parse_submission)]
    pub(super) submit: Option<render::Submission>,
    /// Print what the frame ran: passes, draws, pipelines, queue submissions.
    #[arg(long)]
    pub(super) stats: bool,
    /// Render this many frames of the scene in one process (uploaded once); --timings then
    /// reports the median of the frames after the first (the first pays shader JIT compilation).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub(super) frames: u32,
    /// Try the woven fabric on a material without writing a file: MATERIAL=PRESET[@PITCH]
    /// (name or index; a preset of `weft fabric --list-presets`, or from-sheen; PRESET+sheet for
    /// a single sheet that lets light through), optionally followed by :DRAFT.wif (a weaving
    /// draft's weave and colours); repeatable.
    #[arg(long)]
    pub(super) fabric: Vec<String>,
    /// Pose the scene at this time of its animation, in seconds (clamped to the animation's
    /// keyframes); the first animation unless --animation says which.
    #[arg(long, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--time", s))]
    pub(super) time: Option<f32>,
    /// The glTF animation to pose (name or index; `weft plan` lists them), at --time (0 when left
    /// out).
    #[arg(long)]
    pub(super) animation: Option<String>,
    #[command(flatten)]
    pub(super) batch: BatchArgs,
}

/// Sequences and the batch contract (docs/batch.md). Any of --frames-range, --sweep, --task,
/// --tasks makes the render a batch task: -o (and --exr) become patterns, and the exit codes
/// below apply.
#[derive(Args)]
#[command(next_help_heading = "Sequences and batches (docs/batch.md)")]
pub(super) struct BatchArgs {
    /// Render frames FIRST..LAST (both included) in one process, the scene uploaded once; frame
    /// f is posed at f / --fps seconds. -o is then a pattern: %04d is the frame number.
    #[arg(long, value_name = "FIRST..LAST", conflicts_with = "frames",
          value_parser = |s: &str| weft::batch::FrameRange::parse(s))]
    pub(super) frames_range: Option<weft::batch::FrameRange>,
    /// Frames per second of the sequence (the time of frame f is f / FPS).
    #[arg(long, default_value_t = 24.0, value_parser = |s: &str| render::parse_finite("--fps", s))]
    pub(super) fps: f32,
    /// Turn the camera about the vertical axis through the scene's centre, in degrees per second.
    #[arg(
        long,
        value_name = "DEGREES_PER_SECOND",
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_parser = |s: &str| render::parse_finite("--orbit", s)
    )]
    pub(super) orbit: f32,
    /// Move the camera along its view direction, in world units per second (negative: away).
    #[arg(
        long,
        value_name = "UNITS_PER_SECOND",
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_parser = |s: &str| render::parse_finite("--dolly", s)
    )]
    pub(super) dolly: f32,
    /// Skip frames whose outputs are all there (the PNG, and the EXR with --exr), complete and
    /// of the frame's size.
    #[arg(long)]
    pub(super) resume: bool,
    /// This task's index, from 0 (overrides the engines' variables: SLURM_ARRAY_TASK_ID,
    /// JOB_COMPLETION_INDEX, AWS_BATCH_JOB_ARRAY_INDEX, WEFT_TASK).
    #[arg(long, value_name = "I")]
    pub(super) task: Option<u32>,
    /// How many tasks share the jobs (else from SLURM_ARRAY_TASK_COUNT or _MIN/_MAX, or
    /// WEFT_TASKS).
    #[arg(long, value_name = "N")]
    pub(super) tasks: Option<u32>,
    /// How the jobs are dealt to tasks: contiguous (task i gets one run of frames) or strided
    /// (task i gets i, i+N, i+2N, ...).
    #[arg(long, default_value = "contiguous", value_parser = Choice::new(
        weft::batch::Split::parse, &["contiguous", "strided"]))]
    pub(super) split: weft::batch::Split,
    /// Render every frame once per value: KEY=V1,V2,... with KEY exposure, accuracy,
    /// env-intensity or env-rotation; -o must hold {sweep} (the value).
    #[arg(long, value_name = "KEY=V1,V2,...", allow_hyphen_values = true,
          value_parser = |s: &str| weft::batch::Sweep::parse(s))]
    pub(super) sweep: Option<weft::batch::Sweep>,
    /// Print one JSON line per job on stdout: frame, time, output, status, per-pass GPU and wall
    /// ms.
    #[arg(long)]
    pub(super) metrics_json: bool,
    /// After the frames, make a video of them with ffmpeg (must be on PATH; one task only, no
    /// sweep). The codec is ffmpeg's default for the extension (e.g. .mp4).
    #[arg(long, value_name = "PATH")]
    pub(super) video: Option<PathBuf>,
}

impl BatchArgs {
    pub(super) fn on(&self) -> bool {
        self.frames_range.is_some()
            || self.sweep.is_some()
            || self.task.is_some()
            || self.tasks.is_some()
    }
}

/// Whether the command line asks for a batch render (so that even a flag value clap refuses
/// exits with the batch contract's code).
pub(super) fn batch_command_line() -> bool {
    std::env::args_os().any(|a| {
        let a = a.to_string_lossy();
        a.starts_with("--frames-range") || a.starts_with("--task") || a.starts_with("--sweep")
    })
}

/// `weft render --help`'s epilogue: the batch exit codes and the engines' variables.
pub(super) fn render_after_help() -> String {
    let mut t = String::from(
        "Exit codes of a batch render (--frames-range, --sweep, --task, --tasks; a single render exits 1 on any error):\n",
    );
    for line in weft::batch::ExitClass::table().lines() {
        t.push_str(&format!("  {line}\n"));
    }
    t.push_str("Task index and count from the environment when --task is not given:\n");
    for (engine, vars) in weft::batch::TASK_ENV_VARS {
        t.push_str(&format!("  {engine}: {vars}\n"));
    }
    t
}

pub(super) fn run_render(args: RenderArgs) -> anyhow::Result<()> {
    if args.batch.on() {
        return run_batch(args);
    }
    let device = args
        .device
        .as_deref()
        .map(DeviceChoice::parse)
        .unwrap_or_else(DeviceChoice::from_env);
    // The device and the fixed pipelines on a thread of their own while the scene and the
    // environment load on this one: both are CPU work before the first frame.
    let validate = args.validate;
    let gpu = std::thread::spawn(move || -> weft::Result<(Renderer, f64)> {
        let start = std::time::Instant::now();
        let ctx = Context::new(&ContextOptions { validate, device })?;
        let renderer = Renderer::new(ctx)?;
        Ok((renderer, start.elapsed().as_secs_f64() * 1e3))
    });
    let load_start = std::time::Instant::now();
    let loaded = load_scene_with(&args.scene, (1280, 720), &args.fabric, false).and_then(
        |(mut scene, options)| {
            pose_scene(&mut scene, args.animation.as_deref(), args.time)?;
            Ok((scene, options))
        },
    );
    let load_ms = load_start.elapsed().as_secs_f64() * 1e3;
    let gpu = gpu
        .join()
        .map_err(|_| anyhow::anyhow!("the Vulkan set-up thread panicked"))?;
    // A bad scene or flag is the error to report even when there is no driver too.
    let (scene, mut options) = loaded?;
    let mut outputs = vec![render::OutputPath::new("-o", &args.output)];
    outputs.extend(args.exr.iter().map(|e| render::OutputPath::new("--exr", e)));
    check_outputs(&inputs_of(&args.scene, &scene), &outputs)?;
    let (mut renderer, setup_ms) = gpu?;
    options.exposure = args.exposure;
    options.tonemap = args.tonemap;
    options.antialias = args.aa;
    options.read_hdr = args.exr.is_some();
    options.submission = args.submit.unwrap_or(if args.timings {
        render::Submission::PerPass
    } else {
        render::Submission::Frame
    });
    options.validate()?;
    let info = renderer.context().info().clone();
    eprintln!(
        "device: {} ({}, {} {})",
        info.name, info.device_type, info.driver_name, info.driver_info
    );
    let (frame, render_ms) =
        weft::metrics::render_warm(&mut renderer, &scene, &options, args.frames)?;
    // Both outputs or neither (as a batch frame): encoded first, then renamed into place.
    let write_start = std::time::Instant::now();
    render::write_frame(
        &args.output,
        args.exr.as_deref(),
        frame.width,
        frame.height,
        &frame.ldr,
        &frame.hdr,
        &options,
    )?;
    let write_ms = write_start.elapsed().as_secs_f64() * 1e3;
    eprintln!(
        "wrote {} ({}x{})",
        args.output.display(),
        frame.width,
        frame.height
    );
    if let Some(exr) = &args.exr {
        eprintln!("wrote {}", exr.display());
    }
    if args.timings {
        if args.frames > 1 {
            println!(
                "median of {} warm frames (after the first)",
                args.frames - 1
            );
        } else {
            println!("one cold frame (includes shader JIT); --frames 10 gives warm medians");
        }
        if options.supersample() > 1 {
            println!(
                "each pass's time is the sum over the {} frames of --aa {}",
                options.supersample().pow(2),
                options.antialias.name()
            );
        }
        match options.submission {
            render::Submission::PerPass => {
                println!("one queue submission per pass, each timed alone (--submit frame: one per frame)")
            }
            render::Submission::Frame => println!(
                "one queue submission per frame; a pass's gpu ms is between the timestamps around it, where passes may overlap (--submit pass times each alone)"
            ),
        }
        println!("{:<12} {:>10} {:>10}", "pass", "gpu ms", "wall ms");
        println!("{:<12} {:>10} {:>10.2}", "load", "-", load_ms);
        println!(
            "{:<12} {:>10} {:>10.2}   (device and fixed pipelines, alongside load)",
            "setup", "-", setup_ms
        );
        for t in &frame.timings {
            let gpu = t
                .gpu_ms
                .map(|g| format!("{g:.2}"))
                .unwrap_or_else(|| "-".into());
            let wall = t
                .wall_ms
                .map(|w| format!("{w:.2}"))
                .unwrap_or_else(|| "-".into());
            let note = if (t.name == "environment" && frame.stats.environment_from_disk)
                || (t.name == "world light" && frame.stats.world_light_from_disk)
            {
                "   (from weft's cache on disk)"
            } else if t.name == "world rays" {
                "   (on a thread beside the pipelines)"
            } else {
                ""
            };
            println!("{:<12} {:>10} {:>10}{note}", t.name, gpu, wall);
        }
        println!("{:<12} {:>10} {:>10.2}", "frame", "-", render_ms);
        println!(
            "{:<12} {:>10} {:>10.2}   (the PNG{} encoded and written)",
            "write",
            "-",
            write_ms,
            if args.exr.is_some() {
                " and the EXR"
            } else {
                ""
            }
        );
    }
    if args.stats {
        println!("passes     {}", frame.stats.passes.join(" -> "));
        println!(
            "draws      {} ({} triangles)",
            frame.stats.draws, frame.stats.triangles
        );
        println!("pipelines  {}", frame.stats.pipelines.join(", "));
        let (specialized, reused) = weft::vk::specialize::counts();
        println!(
            "modules    {specialized} specialised before the driver by spirv-opt ({reused} of them from weft's cache; a CPU device's large modules only)"
        );
        println!(
            "submits    {} queue submission(s) ({})",
            frame.stats.submissions,
            options.submission.name()
        );
        println!(
            "weave      {} distinct weave(s); {} weave-pass dispatch(es) (mip chains, built for the first frame that reads them; 0 when only summed-area tables were read)",
            frame.stats.weave_textures, frame.stats.weave_dispatches
        );
        println!(
            "shadows    {} map(s), {} caster draw(s)",
            frame.stats.shadow_maps, frame.stats.shadow_draws
        );
        println!(
            "lights     lists per 16 x 16-pixel tile{}",
            match frame.stats.light_slices {
                1 => String::new(),
                n => format!(" and {n} slices of view distance"),
            }
        );
    }
    Ok(())
}

/// `weft render --frames-range / --sweep / --task`: this task's share of the jobs, in one
/// process (weft::batch::sequence). Every flag is checked before a device is opened.
pub(super) fn run_batch(args: RenderArgs) -> anyhow::Result<()> {
    use weft::batch::{sequence, FrameRange, OutputPattern, TaskSpec};
    let b = &args.batch;
    let task = TaskSpec::resolve(b.task, b.tasks, |k| std::env::var(k).ok())?;
    let range = b.frames_range.unwrap_or(FrameRange { first: 0, last: 0 });
    let mut spec = sequence::SequenceSpec {
        range,
        fps: b.fps,
        motion: Default::default(),
        animation: None,
        sweep: b.sweep.clone(),
        task,
        split: b.split,
        output: OutputPattern::parse(&args.output)?,
        exr: args.exr.as_deref().map(OutputPattern::parse).transpose()?,
        resume: b.resume,
    };
    spec.check()?;
    sequence::CameraMotion::check_speeds(b.orbit, b.dolly)?;
    if let Some(t) = args.time {
        anyhow::bail!(weft::Error::input(format!(
            "--time {t} poses a still; in a sequence frame f is posed at f / --fps seconds: leave --time out (choose the frames with --frames-range)"
        )));
    }
    if let Some(video) = &b.video {
        if task.count > 1 || spec.sweep.as_ref().is_some_and(|s| s.values.len() > 1) {
            anyhow::bail!(weft::Error::input(format!(
                "--video '{}' needs every frame in this process: leave it out with --tasks or a --sweep, and run ffmpeg once all tasks are done (docs/batch.md)",
                video.display()
            )));
        }
        if !sequence::on_path("ffmpeg") {
            anyhow::bail!(weft::Error::input(format!(
                "--video '{}' needs ffmpeg on PATH, and there is none: install it (e.g. apt-get install ffmpeg) or leave --video out",
                video.display()
            )));
        }
    }
    let jobs = spec.my_jobs();
    if jobs.is_empty() {
        eprintln!(
            "task {} of {} ({}): no jobs in this share of {} job(s); nothing to do",
            task.index,
            task.count,
            task.source,
            weft::batch::jobs(range, spec.sweep.as_ref()).len()
        );
        return Ok(());
    }
    let device = args
        .device
        .as_deref()
        .map(DeviceChoice::parse)
        .unwrap_or_else(DeviceChoice::from_env);
    let validate = args.validate;
    let gpu = std::thread::spawn(move || -> weft::Result<Renderer> {
        Renderer::new(Context::new(&ContextOptions { validate, device })?)
    });
    let loaded = load_scene_with(&args.scene, (1280, 720), &args.fabric, false);
    let gpu = gpu
        .join()
        .map_err(|_| anyhow::anyhow!("the Vulkan set-up thread panicked"))?;
    let (mut scene, mut options) = loaded?;
    options.exposure = args.exposure;
    options.tonemap = args.tonemap;
    options.antialias = args.aa;
    options.validate()?;
    // Every output of this task's jobs, against the inputs and each other (before the device's
    // error, so that bad output paths are bad input on a node without a driver too).
    check_outputs(&inputs_of(&args.scene, &scene), &spec.outputs())?;
    spec.motion = sequence::CameraMotion::centered(&scene, b.orbit, b.dolly)?;
    // The animation played: --animation's, else the file's first (a still scene has none).
    spec.animation = match args.animation.as_deref() {
        Some(a) => Some(scene.find_animation(a)?),
        None => (!scene.animations().is_empty()).then_some(0),
    };
    let mut renderer = gpu?;
    let info = renderer.context().info().clone();
    eprintln!(
        "device: {} ({}, {} {})",
        info.name, info.device_type, info.driver_name, info.driver_info
    );
    eprintln!(
        "task {} of {} ({}, {}): {} job(s), frames {}..{} at {} fps{}",
        task.index,
        task.count,
        task.source,
        spec.split.name(),
        jobs.len(),
        range.first,
        range.last,
        spec.fps,
        match spec.animation {
            Some(i) => format!(
                ", animation {i} '{}' ({:.3} s)",
                scene.animations()[i].name,
                scene.animations()[i].duration
            ),
            None => String::new(),
        }
    );
    let mut gpu_scene = renderer.upload(&scene)?;
    let metrics = b.metrics_json;
    let reports = sequence::run(
        &mut renderer,
        &mut scene,
        &mut gpu_scene,
        &options,
        &spec,
        |r| {
            if r.skipped {
                eprintln!(
                    "frame {} already there: {}",
                    r.job.frame,
                    r.output.display()
                );
            } else {
                eprintln!(
                    "frame {} (t = {:.3} s) {:.0} ms: wrote {}",
                    r.job.frame,
                    r.time,
                    r.render_ms + r.write_ms,
                    r.output.display()
                );
            }
            if metrics {
                use std::io::Write;
                let mut out = std::io::stdout().lock();
                let _ = writeln!(out, "{}", r.json(&spec));
                let _ = out.flush();
            }
        },
    )?;
    let rendered = reports.iter().filter(|r| !r.skipped).count();
    eprintln!(
        "done: {rendered} rendered, {} already there",
        reports.len() - rendered
    );
    if let Some(video) = &b.video {
        let status = sequence::video_command(&spec, video)
            .status()
            .map_err(|e| anyhow::anyhow!("could not run ffmpeg: {e}"))?;
        if !status.success() {
            anyhow::bail!(
                "ffmpeg failed ({status}) making '{}' from '{}'",
                video.display(),
                spec.output.as_str()
            );
        }
        eprintln!("wrote {}", video.display());
    }
    Ok(())
}
