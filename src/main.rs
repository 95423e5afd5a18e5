//! The `weft` command line: parses arguments, calls the library, prints.

#![deny(unsafe_code)]

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use weft::bench::median;
use weft::render::{self, DebugView, Plan, RenderOptions, Renderer};
use weft::scene::{self, Scene};
use weft::vk::{Context, ContextOptions, DeviceChoice};

mod fabric_cmd;
mod fidelity_cmd;

#[derive(Parser)]
#[command(
    name = "weft",
    version = env!("WEFT_LONG_VERSION"),
    about = "A deferred Vulkan renderer for woven fabric"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a glTF scene (or the built-in default scene) to PNG, and optionally EXR.
    Render(RenderArgs),
    /// Print what a frame of the scene needs: passes, lights, materials.
    Plan(PlanArgs),
    /// Measure what accuracy costs in time: every accuracy level and weave precision against a
    /// supersampled ground truth, growth with resolution and lights, fabric vs PBR lighting cost.
    Bench(BenchArgs),
    /// The paper's figure: the scene's fabric under Gouraud, Phong, plain Ashikhmin-Shirley and
    /// the fabric model, side by side and labelled, in one PNG.
    Compare(CompareArgs),
    /// A contact sheet: every .gltf/.glb under the given files or folders rendered with the same
    /// options (the defaults unless told), labelled with name and mean sRGB, in one PNG; prints a
    /// table of what each scene gave.
    Sheet(SheetArgs),
    /// Write a copy of a .gltf/.glb with the woven fabric (WEFT_materials_fabric) on chosen
    /// materials, a preset's parameters, the thread pitch in world units, and a sheen fallback.
    Fabric(fabric_cmd::FabricArgs),
    /// weft among the glTF renderers: render Khronos' glTF-Render-Fidelity scenarios, score them
    /// and every published engine against a path-traced reference with the comparison's metric,
    /// and write a side-by-side sheet (docs/fidelity.md).
    Fidelity(fidelity_cmd::FidelityArgs),
    /// An interactive window on the same renderer: orbit camera, live controls (docs/viewer.md).
    View(ViewArgs),
    /// Write the SPIR-V shader package: every module as .spv, manifest.json, include/, README.md.
    Shaders {
        /// Directory to write the package into (created if missing).
        #[arg(long)]
        out: PathBuf,
    },
}

#[derive(Args)]
struct SceneArgs {
    /// A .gltf or .glb file; the built-in default scene when left out.
    scene: Option<PathBuf>,
    /// Output size, WIDTHxHEIGHT (default 1280x720; for compare, each panel's, default 480x360).
    #[arg(long, value_parser = checked_size)]
    size: Option<(u32, u32)>,
    /// Index of the scene's camera to use (default: its first camera, or automatic framing).
    #[arg(long)]
    camera: Option<usize>,
    /// Place the camera here (X,Y,Z, world space) instead of the scene's camera; needs --target.
    #[arg(long, allow_hyphen_values = true, requires = "target",
          value_parser = |s: &str| render::parse_vec3("--eye", s))]
    eye: Option<glam::Vec3>,
    /// The point the --eye camera looks at (X,Y,Z).
    #[arg(long, allow_hyphen_values = true, requires = "eye",
          value_parser = |s: &str| render::parse_vec3("--target", s))]
    target: Option<glam::Vec3>,
    /// Vertical field of view of the --eye camera, in degrees.
    #[arg(long, default_value_t = 40.0, value_parser = |s: &str| render::parse_finite("--fov", s))]
    fov: f32,
    /// How the weave becomes reflectance: nearest, filtered-params, mixture, supersampled:N.
    #[arg(long, default_value = "mixture", value_parser = Choice::new(
        render::Accuracy::parse,
        &["nearest", "filtered-params", "mixture", "supersampled:N"],
    ))]
    accuracy: render::Accuracy,
    /// Where coverages come from: sat (the weave's summed-area table: each footprint box
    /// exactly), rgba8 or rgba16f weave texture (mip chain, trilinear), or analytic (no texture).
    #[arg(long, default_value = "sat", value_parser = Choice::new(
        render::WeavePrecision::parse,
        &render::WeavePrecision::ALL.map(render::WeavePrecision::name),
    ))]
    weave_precision: render::WeavePrecision,
    /// How the weave is filtered over a pixel's footprint: parallelogram (oblique footprints cut
    /// into 2 x 2 pieces), parallelogram:N (N x N, N up to 4), or box (its bounding box: faster,
    /// blurrier where threads run oblique to the screen).
    #[arg(long, default_value = "parallelogram", value_parser = Choice::new(
        render::Footprint::parse,
        &["parallelogram", "parallelogram:N", "box"],
    ))]
    footprint: render::Footprint,
    /// Show a G-buffer target instead of the lit image: albedo, normals, tangents,
    /// roughness-metallic, coverage, thread-dir, depth.
    #[arg(long, default_value = "none", value_parser = Choice::new(
        DebugView::parse,
        &DebugView::ALL.map(DebugView::name),
    ))]
    debug_view: DebugView,
    /// How fabric is shaded: fabric (the model), or for comparison gouraud, phong,
    /// ashikhmin-shirley (one lobe, no weave).
    #[arg(long, default_value = "fabric", value_parser = Choice::new(
        render::Shading::parse,
        &render::Shading::ALL.map(render::Shading::name),
    ))]
    shading: render::Shading,
    /// Environment lighting: an equirectangular .hdr or .exr file, `studio` (the built-in
    /// procedural studio, the default) or `none` (lamps and a fixed ambient only).
    #[arg(long, default_value = "studio")]
    env: String,
    /// Turn the environment about the vertical axis, in degrees.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--env-rotation", s))]
    env_rotation: f32,
    /// Scale the environment's radiance.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--env-intensity", s))]
    env_intensity: f32,
    /// What empty pixels show: env, env:BLUR (0..1), color, color:R,G,B (linear), none
    /// (transparent).
    #[arg(long, default_value = "env")]
    background: String,
    /// How environment light is integrated: approx, fis:N (filtered importance sampling, default
    /// fis:8), mc:N (brute-force Monte Carlo, the ground truth). weft bench --ibl shows the cost
    /// and error of each.
    #[arg(long, default_value = "fis:8")]
    ibl: String,
    /// Occlusion of the environment's light: gtao (screen-space ground-truth ambient occlusion
    /// from the depth buffer, out to 0.3 of the scene's size), gtao:R (out to R world units),
    /// or none (occlusion textures only). Runs only when an environment lights the scene.
    #[arg(long, default_value = "gtao", value_parser = Choice::new(
        render::Occlusion::parse,
        &["gtao", "gtao:R", "none"],
    ))]
    occlusion: render::Occlusion,
    /// Punctual lights: auto (the file's; a default key light with a shadow and a ground when it
    /// has none and no --env FILE is given), none, file, default.
    #[arg(long, default_value = "auto")]
    lights: String,
    /// KHR_materials_variants: load the materials of this variant (`weft plan` lists them).
    #[arg(long)]
    variant: Option<String>,
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output PNG (display-referred, sRGB).
    #[arg(short, long, default_value = "weft.png")]
    output: PathBuf,
    /// Also write the linear HDR image (before exposure and tone mapping) as OpenEXR.
    #[arg(long)]
    exr: Option<PathBuf>,
    /// Exposure in EV (stops): the image is scaled by 2^EV before tone mapping.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--exposure", s))]
    exposure: f32,
    /// Tone curve: pbr-neutral (Khronos PBR Neutral), aces (three.js' ACES fit with the 1/2.2
    /// display gamma of Khronos' render-fidelity goldens), agx, or none. Written into the PNG.
    #[arg(long, default_value = "pbr-neutral", value_parser = parse_tonemap)]
    tonemap: render::ToneCurve,
    /// Anti-aliasing: fxaa (a post pass after tone mapping, glsl/fxaa.frag), none (the
    /// rasterizer's one-pixel staircases), or ssN (N x N frames at sub-pixel offsets averaged,
    /// N from 2 to 8: N² times the time, for stills; it resolves wires and detail thinner than a
    /// pixel, which FXAA cannot). Written into the PNG.
    #[arg(long, default_value = "fxaa", value_parser = parse_aa)]
    aa: render::Antialias,
    /// Turn on the Vulkan validation layer; any message it reports fails the render.
    #[arg(long)]
    validate: bool,
    /// Vulkan device: auto, cpu (lavapipe), an index, or part of a name. Also WEFT_DEVICE.
    #[arg(long)]
    device: Option<String>,
    /// Print the GPU and wall time of each pass (each pass then goes to the queue on its own, for
    /// honest per-pass times: see --submit).
    #[arg(long)]
    timings: bool,
    /// How a frame reaches the queue: frame (one submission, timestamps between the passes; the
    /// default without --timings) or pass (one submission per pass; the default with --timings).
    #[arg(long, value_parser = parse_submission)]
    submit: Option<render::Submission>,
    /// Print what the frame ran: passes, draws, pipelines, queue submissions.
    #[arg(long)]
    stats: bool,
    /// Render this many frames of the scene in one process (uploaded once); --timings then
    /// reports the median of the frames after the first (the first pays shader JIT compilation).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// Try the woven fabric on a material without writing a file: MATERIAL=PRESET[@PITCH]
    /// (name or index; a preset of `weft fabric --list-presets`, or from-sheen; PRESET+sheet for
    /// a single sheet that lets light through), optionally followed by :DRAFT.wif (a weaving
    /// draft's weave and colours); repeatable.
    #[arg(long)]
    fabric: Vec<String>,
    /// Pose the scene at this time of its animation, in seconds (clamped to the animation's
    /// keyframes); the first animation unless --animation says which.
    #[arg(long, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--time", s))]
    time: Option<f32>,
    /// The glTF animation to pose (name or index; `weft plan` lists them), at --time (0 when left
    /// out).
    #[arg(long)]
    animation: Option<String>,
    #[command(flatten)]
    batch: BatchArgs,
}

/// Sequences and the batch contract (docs/batch.md). Any of --frames-range, --sweep, --task,
/// --tasks makes the render a batch task: -o (and --exr) become patterns, and the exit codes
/// below apply.
#[derive(Args)]
#[command(next_help_heading = "Sequences and batches (docs/batch.md)")]
struct BatchArgs {
    /// Render frames FIRST..LAST (both included) in one process, the scene uploaded once; frame
    /// f is posed at f / --fps seconds. -o is then a pattern: %04d is the frame number.
    #[arg(long, value_name = "FIRST..LAST", conflicts_with = "frames",
          value_parser = |s: &str| weft::batch::FrameRange::parse(s))]
    frames_range: Option<weft::batch::FrameRange>,
    /// Frames per second of the sequence (the time of frame f is f / FPS).
    #[arg(long, default_value_t = 24.0, value_parser = |s: &str| render::parse_finite("--fps", s))]
    fps: f32,
    /// Turn the camera about the vertical axis through the scene's centre, in degrees per second.
    #[arg(
        long,
        value_name = "DEGREES_PER_SECOND",
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_parser = |s: &str| render::parse_finite("--orbit", s)
    )]
    orbit: f32,
    /// Move the camera along its view direction, in world units per second (negative: away).
    #[arg(
        long,
        value_name = "UNITS_PER_SECOND",
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_parser = |s: &str| render::parse_finite("--dolly", s)
    )]
    dolly: f32,
    /// Skip frames whose outputs are all there (the PNG, and the EXR with --exr), complete and
    /// of the frame's size.
    #[arg(long)]
    resume: bool,
    /// This task's index, from 0 (overrides the engines' variables: SLURM_ARRAY_TASK_ID,
    /// JOB_COMPLETION_INDEX, AWS_BATCH_JOB_ARRAY_INDEX, WEFT_TASK).
    #[arg(long, value_name = "I")]
    task: Option<u32>,
    /// How many tasks share the jobs (else from SLURM_ARRAY_TASK_COUNT or _MIN/_MAX, or
    /// WEFT_TASKS).
    #[arg(long, value_name = "N")]
    tasks: Option<u32>,
    /// How the jobs are dealt to tasks: contiguous (task i gets one run of frames) or strided
    /// (task i gets i, i+N, i+2N, ...).
    #[arg(long, default_value = "contiguous", value_parser = Choice::new(
        weft::batch::Split::parse, &["contiguous", "strided"]))]
    split: weft::batch::Split,
    /// Render every frame once per value: KEY=V1,V2,... with KEY exposure, accuracy,
    /// env-intensity or env-rotation; -o must hold {sweep} (the value).
    #[arg(long, value_name = "KEY=V1,V2,...", allow_hyphen_values = true,
          value_parser = |s: &str| weft::batch::Sweep::parse(s))]
    sweep: Option<weft::batch::Sweep>,
    /// Print one JSON line per job on stdout: frame, time, output, status, per-pass GPU and wall
    /// ms.
    #[arg(long)]
    metrics_json: bool,
    /// After the frames, make a video of them with ffmpeg (must be on PATH; one task only, no
    /// sweep). The codec is ffmpeg's default for the extension (e.g. .mp4).
    #[arg(long, value_name = "PATH")]
    video: Option<PathBuf>,
}

impl BatchArgs {
    fn on(&self) -> bool {
        self.frames_range.is_some()
            || self.sweep.is_some()
            || self.task.is_some()
            || self.tasks.is_some()
    }
}

/// Whether the command line asks for a batch render (so that even a flag value clap refuses
/// exits with the batch contract's code).
fn batch_command_line() -> bool {
    std::env::args_os().any(|a| {
        let a = a.to_string_lossy();
        a.starts_with("--frames-range") || a.starts_with("--task") || a.starts_with("--sweep")
    })
}

/// `weft render --help`'s epilogue: the batch exit codes and the engines' variables.
fn render_after_help() -> String {
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

#[derive(Args)]
struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Exposure in EV (stops), as for render (the panel changes it live).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--exposure", s))]
    exposure: f32,
    /// Edge anti-aliasing, as for render: fxaa or none (ssN is for still renders).
    #[arg(long, default_value = "fxaa", value_parser = parse_aa)]
    aa: render::Antialias,
    /// Turn on the Vulkan validation layer; any message it reports ends the viewer with an error.
    #[arg(long)]
    validate: bool,
    /// Vulkan device: auto, cpu (lavapipe), an index, or part of a name. Also WEFT_DEVICE.
    #[arg(long)]
    device: Option<String>,
    /// Write the window's content to this PNG after --after frames, then exit.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Frames to present before --screenshot.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    after: u32,
    /// Start with the panel hidden (Tab shows it): the window then shows exactly the render.
    #[arg(long)]
    no_panel: bool,
    /// Time this many frames of the frame loop (after 3 warm-up frames), print a table, exit.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    bench_frames: Option<u32>,
}

#[derive(Args)]
struct SheetArgs {
    /// .gltf/.glb files, or folders to search recursively.
    #[arg(required = true)]
    paths: Vec<PathBuf>,
    /// Output PNG.
    #[arg(short, long, default_value = "sheet.png")]
    output: PathBuf,
    /// Size of each cell, WIDTHxHEIGHT.
    #[arg(long, default_value = "256x192", value_parser = checked_size)]
    size: (u32, u32),
    /// Cells per row.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..))]
    columns: u32,
    /// Environment, as for render: a .hdr/.exr file, studio or none.
    #[arg(long, default_value = "studio")]
    env: String,
    /// Turn on the Vulkan validation layer; any message it reports fails that scene's cell.
    #[arg(long)]
    validate: bool,
    /// Vulkan device, as for render.
    #[arg(long)]
    device: Option<String>,
}

#[derive(Args)]
struct CompareArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output PNG: the four panels in a row, each labelled.
    #[arg(short, long, default_value = "figure.png")]
    output: PathBuf,
    /// Exposure in EV (stops), as for render.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--exposure", s))]
    exposure: f32,
    /// Turn on the Vulkan validation layer; any message it reports fails the run.
    #[arg(long)]
    validate: bool,
    /// Vulkan device: auto, cpu (lavapipe), an index, or part of a name. Also WEFT_DEVICE.
    #[arg(long)]
    device: Option<String>,
}

#[derive(Args)]
struct BenchArgs {
    /// A short run (about 15 s on lavapipe): smaller images, fewer levels.
    #[arg(long)]
    quick: bool,
    /// Instead: what the plan's skipping saves (each skippable effect forced on against the
    /// plan, same run) and 4 against 256 point lights of limited range.
    #[arg(long)]
    plan: bool,
    /// Instead: the IBL levels (approx, fis:4/16/64) against a Monte Carlo ground truth, and the
    /// lighting pass with environment light against lamps only.
    #[arg(long)]
    ibl: bool,
    /// Instead: time to the first picture: the whole `weft render` process at --size (default
    /// scene, 5 runs, median) against the warm frame of the same render (same run), and their
    /// ratio.
    #[arg(long)]
    startup: bool,
    /// Instead: the default scene's frame (--size, default 1920x1080) as one queue submission, the
    /// normal path, against one submission per pass (what --timings and the other benches use),
    /// frames interleaved in one process (--frames, default 5).
    #[arg(long)]
    submission: bool,
    /// Instead: temporal stability: the camera turning slowly at the mid and far views, the
    /// consecutive-frame change on fabric of every level against the supersampled ground truth's
    /// (ratio = how much more it flickers). --size (default 320x180), --frames (default 9).
    #[arg(long)]
    temporal: bool,
    /// Degrees the camera turns between frames in --temporal.
    #[arg(long, default_value_t = 0.1, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--temporal-step", s))]
    temporal_step: f32,
    /// The environment of the --ibl bench (default: the repository's tests/data/env/lebombo_1k.hdr).
    #[arg(long)]
    ibl_env: Option<PathBuf>,
    /// Monte Carlo samples per pixel of the --ibl ground truth.
    #[arg(long, default_value_t = 2048)]
    ibl_truth: u32,
    /// Image size of the --plan and --ibl benches.
    #[arg(long, default_value = "960x540")]
    size: String,
    /// Where bench.csv and bench.png go.
    #[arg(long, default_value = "target/bench")]
    out: PathBuf,
    /// Timed frames per measurement (medians of these, after warm-up).
    #[arg(long)]
    frames: Option<u32>,
    /// Vulkan device: auto, cpu (lavapipe), an index, or part of a name. Also WEFT_DEVICE.
    #[arg(long)]
    device: Option<String>,
    /// Only these views of the accuracy sweep (comma-separated: close-up, mid, far, grazing,
    /// cells-10px, cells-1px, cells-1px-square, cells-1.5px-square,
    /// cells-grazing).
    #[arg(long, value_delimiter = ',', value_parser = parse_bench_view)]
    views: Option<Vec<weft::bench::View>>,
    /// Jittered point samples per pixel side of the ground truth (N x N frames per view).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=weft::bench::MAX_TRUTH_SAMPLES as i64))]
    truth_samples: Option<u32>,
    /// Only the accuracy sweep: skip the growth over resolution and lights and the PBR ratio.
    #[arg(long)]
    accuracy_only: bool,
    /// Instead: the footprint filters (box against parallelogram:2 and :3) per view, texture and
    /// analytic weave, timed in one run, against the pixel-integrating ground truth.
    #[arg(long)]
    footprint: bool,
    /// Instead: what loading each of these scenes costs (the loader alone, --frames runs each,
    /// default 5, interleaved; medians and the ratio to the first scene's), with each scene's
    /// texture memory as uploaded (RGBA8 with mips, or its KTX2 files' BC7 chains).
    #[arg(long, num_args = 1.., value_name = "SCENE")]
    load: Vec<PathBuf>,
}

fn parse_bench_view(text: &str) -> Result<weft::bench::View, String> {
    weft::bench::View::parse(text).map_err(|e| e.to_string())
}

#[derive(Args)]
struct PlanArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Print the plan as JSON.
    #[arg(long)]
    json: bool,
    /// Anti-aliasing, as for render (its default: fxaa; ssN: the plan of each of its N² frames).
    #[arg(long, default_value = "fxaa", value_parser = parse_aa)]
    aa: render::Antialias,
    /// The woven fabric tried on a material, as for render: MATERIAL=PRESET[+sheet][@PITCH][:DRAFT.wif];
    /// repeatable.
    #[arg(long)]
    fabric: Vec<String>,
}

fn main() -> ExitCode {
    // A panic the library catches and turns into an error (weft::catch_panic: a dependency's,
    // on input that slipped past weft's checks) is reported as that error, naming the file;
    // its panic text and backtrace would only bury it. Any other panic is a bug: shown as is.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !weft::catching_panic() {
            default_hook(info);
        }
    }));
    // A bad flag value is bad input like a bad scene: exit 1 with clap's one-line message (the
    // library's own, naming the choices). Other usage errors, --help and --version as clap has
    // them.
    // A batch render's bad input exits 2 (weft::batch::ExitClass), clap's usage errors too.
    let batch = batch_command_line();
    let command = <Cli as clap::CommandFactory>::command()
        .mut_subcommand("render", |c| c.after_help(render_after_help()));
    let cli = match command
        .try_get_matches()
        .and_then(|m| <Cli as clap::FromArgMatches>::from_arg_matches(&m))
    {
        Ok(cli) => cli,
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::ValueValidation | clap::error::ErrorKind::InvalidValue
            ) =>
        {
            let _ = e.print();
            return if batch {
                ExitCode::from(weft::batch::ExitClass::BadInput.code())
            } else {
                ExitCode::FAILURE
            };
        }
        Err(e) => e.exit(),
    };
    let batch = matches!(&cli.command, Command::Render(r) if r.batch.on());
    let result = match cli.command {
        Command::Render(args) => run_render(args),
        Command::Plan(args) => run_plan(args),
        Command::Shaders { out } => run_shaders(&out),
        Command::Bench(args) => run_bench(args),
        Command::Compare(args) => run_compare(args),
        Command::Sheet(args) => run_sheet(args),
        Command::Fabric(args) => fabric_cmd::run(args),
        Command::Fidelity(args) => fidelity_cmd::run(args),
        Command::View(args) => run_view(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if batch => {
            let class = weft::batch::ExitClass::of(&e);
            eprintln!("error: {e:#}");
            eprintln!("(exit {}: {class:?}; see weft render --help)", class.code());
            ExitCode::from(class.code())
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn load_scene(args: &SceneArgs) -> anyhow::Result<(Scene, RenderOptions)> {
    load_scene_sized(args, "1280x720")
}

/// As [`load_scene`], with `weft render --fabric` applied.
fn load_scene_fabric(
    args: &SceneArgs,
    fabric: &[String],
) -> anyhow::Result<(Scene, RenderOptions)> {
    load_scene_impl(args, "1280x720", true, fabric)
}

/// The built-in studio, generated once per process (`weft sheet` lights every file with it).
fn studio() -> std::sync::Arc<weft::env::Environment> {
    static STUDIO: std::sync::OnceLock<std::sync::Arc<weft::env::Environment>> =
        std::sync::OnceLock::new();
    STUDIO
        .get_or_init(|| std::sync::Arc::new(weft::env::Environment::studio()))
        .clone()
}

/// As [`load_scene_sized`] at 1280x720, without printing the loader's warnings (they stay in
/// `scene.warnings`).
fn load_scene_quiet(args: &SceneArgs) -> anyhow::Result<(Scene, RenderOptions)> {
    load_scene_impl(args, "1280x720", false, &[])
}

fn load_scene_sized(
    args: &SceneArgs,
    default_size: &str,
) -> anyhow::Result<(Scene, RenderOptions)> {
    load_scene_impl(args, default_size, true, &[])
}

fn load_scene_impl(
    args: &SceneArgs,
    default_size: &str,
    print_warnings: bool,
    fabric: &[String],
) -> anyhow::Result<(Scene, RenderOptions)> {
    // Flags first: a typo fails before any loading.
    let lights = weft::env::LightsMode::parse(&args.lights)?;
    let background = weft::env::Background::parse(&args.background)?;
    let level = weft::env::IblLevel::parse(&args.ibl)?;
    let load_options = scene::LoadOptions {
        variant: args.variant.clone(),
    };
    let mut scene = match &args.scene {
        Some(path) => {
            // A progress line for loads a user waits on (tangent generation and texture decoding
            // of a large file take seconds).
            let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            let big = bytes > 32 << 20 && print_warnings;
            let t = std::time::Instant::now();
            if big {
                eprintln!("loading {} ({} MiB)...", path.display(), bytes >> 20);
            }
            let scene = if fabric.is_empty() {
                scene::load_with(path, &load_options)?
            } else {
                fabric_cmd::load(Some(path), fabric, &load_options)?
            };
            if big {
                eprintln!(
                    "loaded {} in {:.1} s",
                    path.display(),
                    t.elapsed().as_secs_f64()
                );
            }
            scene
        }
        None if !fabric.is_empty() => fabric_cmd::load(None, fabric, &load_options)?,
        None if args.variant.is_some() => scene::load_slice_with(
            scene::DEFAULT_SCENE_GLB,
            "built-in default scene",
            None,
            &load_options,
        )?,
        None => scene::default_scene(),
    };
    let (env, own_env) = match args.env.as_str() {
        "none" => (None, false),
        "studio" => (Some(studio()), false),
        path => {
            let env = weft::env::Environment::load(std::path::Path::new(path))?;
            scene
                .warnings
                .extend(env.warnings.iter().cloned().map(scene::Warning));
            (Some(std::sync::Arc::new(env)), true)
        }
    };
    let environment = env.map(|e| {
        let mut l = weft::env::EnvLighting::new(e);
        l.rotation = args.env_rotation;
        l.intensity = args.env_intensity;
        l.background = background;
        l.level = level;
        l
    });
    if let Some(e) = &environment {
        e.validate()?;
    }
    weft::env::stage(&mut scene, lights, args.env_rotation, own_env);
    if print_warnings {
        for w in &scene.warnings {
            eprintln!("warning: {w}");
        }
    }
    let (width, height) = match args.size {
        Some(size) => size,
        None => render::parse_size(default_size)?,
    };
    let mut options = RenderOptions {
        width,
        height,
        camera: args.camera,
        debug_view: args.debug_view,
        accuracy: args.accuracy,
        weave_precision: args.weave_precision,
        footprint: args.footprint,
        shading: args.shading,
        environment,
        occlusion: args.occlusion,
        ..Default::default()
    };
    options.validate()?;
    if let (Some(eye), Some(target)) = (args.eye, args.target) {
        options.camera_override = Some(scene.look_at_camera(eye, target, args.fov.to_radians())?);
    }
    // Fails early, before any GPU work, if --camera names no camera.
    scene.camera(options.camera)?;
    Ok((scene, options))
}

/// The files a command reads, which none of its outputs may be: the scene file, the buffers
/// and images it refers to, and the environment map.
fn inputs_of(args: &SceneArgs, scene: &Scene) -> Vec<PathBuf> {
    let mut inputs: Vec<PathBuf> = args.scene.iter().cloned().collect();
    inputs.extend(scene.files.iter().cloned());
    if !matches!(args.env.as_str(), "none" | "studio") {
        inputs.push(PathBuf::from(&args.env));
    }
    inputs
}

/// [`render::check_outputs`] with this command's inputs.
fn check_outputs(inputs: &[PathBuf], outputs: &[render::OutputPath]) -> anyhow::Result<()> {
    let inputs: Vec<&std::path::Path> = inputs.iter().map(PathBuf::as_path).collect();
    Ok(render::check_outputs(&inputs, outputs)?)
}

/// Poses `scene` for `--animation` / `--time` (nothing when both are left out).
fn pose_scene(scene: &mut Scene, animation: Option<&str>, time: Option<f32>) -> anyhow::Result<()> {
    if animation.is_none() && time.is_none() {
        return Ok(());
    }
    let index = match animation {
        Some(a) => scene.find_animation(a)?,
        None if scene.animations().is_empty() => {
            return Err(weft::Error::input(format!(
                "--time was given but {} has no animations; leave --time out",
                scene.source
            ))
            .into())
        }
        None => 0,
    };
    scene.pose(index, time.unwrap_or(0.0))?;
    Ok(())
}

fn run_view(args: ViewArgs) -> anyhow::Result<()> {
    let device = args
        .device
        .as_deref()
        .map(DeviceChoice::parse)
        .unwrap_or_else(DeviceChoice::from_env);
    let (scene, mut options) = load_scene(&args.scene)?;
    options.exposure = args.exposure;
    options.antialias = args.aa;
    options.validate()?;
    if let render::Antialias::Supersample(n) = args.aa {
        anyhow::bail!(
            "weft view --aa ss{n}: supersampling renders {} frames per image, which is for still renders (weft render --aa ss{n}); the live view takes --aa fxaa or none",
            n * n
        );
    }
    if let Some(shot) = &args.screenshot {
        check_outputs(
            &inputs_of(&args.scene, &scene),
            &[render::OutputPath::new("--screenshot", shot)],
        )?;
    }
    let source = match &args.scene.scene {
        Some(p) => weft::view::SceneSource::File(p.clone()),
        None => weft::view::SceneSource::Builtin,
    };
    let lights = weft::env::LightsMode::parse(&args.scene.lights)?;
    let env_file =
        (!matches!(args.scene.env.as_str(), "none" | "studio")).then(|| args.scene.env.clone());
    let report = weft::view::run(weft::view::ViewOptions {
        scene,
        source,
        lights,
        env_file,
        options,
        context: ContextOptions {
            validate: args.validate,
            device,
        },
        screenshot: args.screenshot.map(|p| (p, args.after)),
        panel: !args.no_panel,
        bench_frames: args.bench_frames,
    })?;
    if let Some(r) = report {
        print!("{}", r.table());
    }
    Ok(())
}

fn run_render(args: RenderArgs) -> anyhow::Result<()> {
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
    let loaded = load_scene_fabric(&args.scene, &args.fabric).and_then(|(mut scene, options)| {
        pose_scene(&mut scene, args.animation.as_deref(), args.time)?;
        Ok((scene, options))
    });
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
    let start = std::time::Instant::now();
    let gpu_scene = renderer.upload(&scene)?;
    let mut frame = renderer.render_frame(&scene, &gpu_scene, &options)?;
    let mut render_ms = vec![start.elapsed().as_secs_f64() * 1e3];
    let mut history = vec![frame.timings.clone()];
    for _ in 1..args.frames {
        let t = std::time::Instant::now();
        frame = renderer.render_frame(&scene, &gpu_scene, &options)?;
        render_ms.push(t.elapsed().as_secs_f64() * 1e3);
        history.push(frame.timings.clone());
    }
    if args.frames > 1 {
        // Warm frames only.
        history.remove(0);
        render_ms.remove(0);
        for (i, t) in frame.timings.iter_mut().enumerate() {
            t.wall_ms = t
                .wall_ms
                .map(|_| median(history.iter().filter_map(|h| h[i].wall_ms).collect()));
            t.gpu_ms = t
                .gpu_ms
                .map(|_| median(history.iter().filter_map(|h| h[i].gpu_ms).collect()));
        }
    }
    let render_ms = median(render_ms);
    // Both outputs or neither (as a batch frame): encoded first, then renamed into place.
    render::write_frame(
        &args.output,
        args.exr.as_deref(),
        frame.width,
        frame.height,
        &frame.ldr,
        &frame.hdr,
        &options,
    )?;
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
            let note = if t.name == "environment" && frame.stats.environment_from_disk {
                "   (from weft's cache on disk)"
            } else {
                ""
            };
            println!("{:<12} {:>10} {:>10}{note}", t.name, gpu, wall);
        }
        println!("{:<12} {:>10} {:>10.2}", "frame", "-", render_ms);
    }
    if args.stats {
        println!("passes     {}", frame.stats.passes.join(" -> "));
        println!(
            "draws      {} ({} triangles)",
            frame.stats.draws, frame.stats.triangles
        );
        println!("pipelines  {}", frame.stats.pipelines.join(", "));
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
    }
    Ok(())
}

/// `weft render --frames-range / --sweep / --task`: this task's share of the jobs, in one
/// process (weft::batch::sequence). Every flag is checked before a device is opened.
fn run_batch(args: RenderArgs) -> anyhow::Result<()> {
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
    let loaded = load_scene_fabric(&args.scene, &args.fabric);
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

fn run_sheet(args: SheetArgs) -> anyhow::Result<()> {
    let (w, h) = args.size;
    let files = weft::sheet::find_scenes(&args.paths);
    if files.is_empty() {
        anyhow::bail!(
            "no .gltf or .glb files under {}: give scene files or folders that hold some",
            args.paths
                .iter()
                .map(|p| format!("'{}'", p.display()))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    check_outputs(&files, &[render::OutputPath::new("-o", &args.output)])?;
    let ctx = open_device(args.device.as_deref(), args.validate)?;
    let mut renderer = Renderer::new(ctx)?;
    let mut cells = Vec::new();
    println!("| scene | triangles | mean sRGB | ms | warnings | result |");
    println!("|---|---|---|---|---|---|");
    for file in &files {
        let name = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let start = std::time::Instant::now();
        let scene_args = SceneArgs {
            scene: Some(file.clone()),
            size: Some(args.size),
            camera: None,
            eye: None,
            target: None,
            fov: 40.0,
            accuracy: render::Accuracy::default(),
            weave_precision: render::WeavePrecision::default(),
            footprint: render::Footprint::default(),
            debug_view: DebugView::None,
            shading: render::Shading::default(),
            env: args.env.clone(),
            env_rotation: 0.0,
            env_intensity: 1.0,
            background: "env".into(),
            ibl: weft::env::DEFAULT_IBL.name(),
            occlusion: render::Occlusion::Gtao { radius: None },
            lights: "auto".into(),
            variant: None,
        };
        let result = load_scene_quiet(&scene_args).and_then(|(scene, options)| {
            let frame = renderer.render(&scene, &options)?;
            Ok((scene, frame))
        });
        let ms = start.elapsed().as_secs_f64() * 1e3;
        match result {
            Ok((scene, frame)) => {
                let mean = weft::sheet::mean_srgb(&frame.ldr);
                println!(
                    "| {name} | {} | {mean:.0} | {ms:.0} | {} | ok |",
                    frame.stats.triangles,
                    scene.warnings.len()
                );
                cells.push(weft::sheet::Cell {
                    name,
                    image: Ok(frame.ldr),
                });
            }
            Err(e) => {
                let msg = format!("{e:#}");
                println!(
                    "| {name} | - | - | {ms:.0} | - | {} |",
                    msg.replace('|', "/")
                );
                cells.push(weft::sheet::Cell {
                    name,
                    image: Err(msg),
                });
            }
        }
    }
    let (sw, sh, rgba) = weft::sheet::compose(&cells, w, h, args.columns);
    render::write_png(&args.output, sw, sh, &rgba)?;
    eprintln!("wrote {} ({} scenes)", args.output.display(), cells.len());
    Ok(())
}

/// `weft bench --startup`: the whole process against its warm frame, with empty caches (weft's
/// and the driver's, each run's own) and with the caches the run before it left.
fn run_startup_bench(args: &BenchArgs) -> anyhow::Result<()> {
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
    let run_with = |extra: &[&str], weft_cache: bool| -> anyhow::Result<(f64, String)> {
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
        Ok((
            t.elapsed().as_secs_f64() * 1e3,
            String::from_utf8_lossy(&o.stdout).into_owned(),
        ))
    };
    let run = |extra: &[&str]| run_with(extra, true);
    let (mut first, mut second, mut no_weft) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..runs {
        let _ = std::fs::remove_dir_all(&caches);
        // Mesa makes its cache's last directory only.
        std::fs::create_dir_all(caches.join("mesa"))?;
        first.push(run(&[])?.0);
        // The two second runs in turn first (the run right after the first meets a driver
        // cache still settling).
        if k % 2 == 0 {
            second.push(run(&[])?.0);
            no_weft.push(run_with(&[], false)?.0);
        } else {
            no_weft.push(run_with(&[], false)?.0);
            second.push(run(&[])?.0);
        }
    }
    // The warm frame: `--frames 6 --timings` prints the median of the 5 frames after the first.
    let (_, text) = run(&["--frames", "6", "--timings", "--submit", "frame"])?;
    let warm = text
        .lines()
        .find_map(|l| {
            l.strip_prefix("frame")
                .map(|r| r.trim().rsplit(' ').next().unwrap_or("").to_string())
        })
        .and_then(|v| v.parse::<f64>().ok())
        .ok_or_else(|| anyhow::anyhow!("no frame time in weft render --timings output:\n{text}"))?;
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
fn run_submission_bench(args: &BenchArgs) -> anyhow::Result<()> {
    /// The scene and options `weft render` starts from (the default scene, the studio).
    #[derive(Parser)]
    struct Defaults {
        #[command(flatten)]
        scene: SceneArgs,
    }
    let size = if args.size == "960x540" {
        "1920x1080".to_string()
    } else {
        args.size.clone()
    };
    let frames = args.frames.unwrap_or(5).max(1);
    let defaults = Defaults::try_parse_from(["weft", "--size", size.as_str()])?;
    let (scene, mut options) = load_scene_quiet(&defaults.scene)?;
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

/// A command-line value parsed by the library's own parser (its message, on a bad value, names
/// the choices), whose choices `--help` lists.
#[derive(Clone)]
struct Choice<T> {
    parse: fn(&str) -> weft::Result<T>,
    names: Vec<&'static str>,
}

impl<T> Choice<T> {
    fn new(parse: fn(&str) -> weft::Result<T>, names: &[&'static str]) -> Self {
        Choice {
            parse,
            names: names.to_vec(),
        }
    }
}

impl<T: Clone + Send + Sync + 'static> clap::builder::TypedValueParser for Choice<T> {
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<T, clap::Error> {
        self.parse.parse_ref(cmd, arg, value)
    }

    fn possible_values(
        &self,
    ) -> Option<Box<dyn Iterator<Item = clap::builder::PossibleValue> + '_>> {
        Some(Box::new(
            self.names
                .iter()
                .map(|n| clap::builder::PossibleValue::new(*n)),
        ))
    }
}

fn open_device(device: Option<&str>, validate: bool) -> anyhow::Result<Context> {
    let device = device
        .map(DeviceChoice::parse)
        .unwrap_or_else(DeviceChoice::from_env);
    let ctx = Context::new(&ContextOptions { validate, device })?;
    let info = ctx.info().clone();
    eprintln!(
        "device: {} ({}, {} {})",
        info.name, info.device_type, info.driver_name, info.driver_info
    );
    Ok(ctx)
}

fn run_compare(args: CompareArgs) -> anyhow::Result<()> {
    let (scene, mut options) = load_scene_sized(&args.scene, "480x360")?;
    options.exposure = args.exposure;
    options.validate()?;
    check_outputs(
        &inputs_of(&args.scene, &scene),
        &[render::OutputPath::new("-o", &args.output)],
    )?;
    let ctx = open_device(args.device.as_deref(), args.validate)?;
    let mut renderer = Renderer::new(ctx)?;
    let figure = weft::compare::figure(&mut renderer, &scene, &options)?;
    render::write_png(&args.output, figure.width, figure.height, &figure.rgba)?;
    eprintln!(
        "wrote {} ({}x{}: {})",
        args.output.display(),
        figure.width,
        figure.height,
        figure
            .panels
            .iter()
            .map(|(s, _)| s.label())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

/// `WIDTHxHEIGHT`, parsed and within what the renderer accepts.
fn checked_size(text: &str) -> anyhow::Result<(u32, u32)> {
    let size = render::parse_size(text)?;
    RenderOptions {
        width: size.0,
        height: size.1,
        ..Default::default()
    }
    .validate()?;
    Ok(size)
}

fn run_bench(args: BenchArgs) -> anyhow::Result<()> {
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
        let env = match args.ibl_env.clone() {
            Some(e) => e,
            None => {
                // The default is a file of weft's source tree (1.4 MiB, not built in): say so
                // where weft was installed without it.
                let default =
                    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/env/lebombo_1k.hdr");
                if !default.exists() {
                    anyhow::bail!(
                        "weft bench --ibl needs an environment map: give --ibl-env FILE.hdr (the default, tests/data/env/lebombo_1k.hdr of weft's source tree, is not at {})",
                        default.display()
                    );
                }
                default
            }
        };
        let ctx = open_device(args.device.as_deref(), false)?;
        let mut renderer = Renderer::new(ctx)?;
        let report = weft::bench::ibl_bench::run(
            &mut renderer,
            &env,
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

/// Writes the SPIR-V shader package (see weft::package).
fn run_shaders(out: &std::path::Path) -> anyhow::Result<()> {
    let manifest = weft::package::write_package(out)?;
    let bytes: u64 = manifest.modules.iter().map(|m| m.size).sum();
    println!(
        "wrote {} modules ({bytes} bytes of SPIR-V) to {}",
        manifest.modules.len(),
        out.display()
    );
    Ok(())
}

fn run_plan(args: PlanArgs) -> anyhow::Result<()> {
    let (scene, mut options) = load_scene_fabric(&args.scene, &args.fabric)?;
    options.antialias = args.aa;
    let plan = Plan::new(&scene, &options);
    if args.json {
        let mut json = serde_json::to_value(&plan)?;
        json["animations"] = scene
            .animations()
            .iter()
            .map(|a| serde_json::json!({"name": a.name, "duration": a.duration}))
            .collect();
        json["light_types_mask"] = plan.light_types_mask().into();
        println!("{}", serde_json::to_string_pretty(&json)?);
    } else {
        println!("scene       {}", scene.source);
        println!("{plan}");
        for (i, a) in scene.animations().iter().enumerate() {
            println!(
                "{}{i}: '{}', {:.3} s",
                if i == 0 {
                    "animations  "
                } else {
                    "            "
                },
                a.name,
                a.duration
            );
        }
    }
    Ok(())
}

fn parse_submission(text: &str) -> Result<render::Submission, String> {
    render::Submission::by_name(text)
        .ok_or_else(|| format!("unknown submission '{text}': choose frame or pass"))
}

fn parse_aa(text: &str) -> Result<render::Antialias, String> {
    render::Antialias::by_name(text)
        .ok_or_else(|| {
            format!(
                "unknown anti-aliasing '{text}': choose fxaa, none or ssN (N x N supersampled frames, N from 2 to {})",
                render::Antialias::MAX_SUPERSAMPLE
            )
        })
}

fn parse_tonemap(text: &str) -> Result<render::ToneCurve, String> {
    render::ToneCurve::by_name(text).ok_or_else(|| {
        format!("unknown tone curve '{text}': choose pbr-neutral, aces, agx or none")
    })
}
