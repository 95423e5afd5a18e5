//! The `weft` command line: parses arguments, calls the library, prints. One file per
//! subcommand; what they share (the scene flags, value parsers, the device) is here.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use weft::bench::median;
use weft::render::{self, DebugView, Plan, RenderOptions, Renderer};
use weft::scene::Scene;
use weft::spec::{EnvSource, Loaded, SceneSpec};
use weft::vk::{Context, ContextOptions, DeviceChoice};

mod bench;
mod cache;
mod compare;
mod fabric;
mod fidelity;
mod plan;
mod render_cmd;
mod sheet;
mod view;

use bench::{run_bench, BenchArgs};
use compare::{run_compare, CompareArgs};
use plan::{run_plan, PlanArgs};
use render_cmd::{batch_command_line, render_after_help, run_render, RenderArgs};
use sheet::{run_sheet, SheetArgs};
use view::{run_view, ViewArgs};

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
    Fabric(fabric::FabricArgs),
    /// weft among the glTF renderers: render Khronos' glTF-Render-Fidelity scenarios, score them
    /// and every published engine against a path-traced reference with the comparison's metric,
    /// and write a side-by-side sheet (docs/fidelity.md).
    Fidelity(fidelity::FidelityArgs),
    /// An interactive window on the same renderer: orbit camera, live controls (docs/viewer.md).
    View(ViewArgs),
    /// What weft's cache on disk holds (compiled pipelines and shaders, preprocessed environments,
    /// baked world light) and its size limit; `--clear` empties it.
    Cache(cache::CacheArgs),
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
    /// At fis, the radius within which the cloth's pixels pool their environment samples where
    /// the surface agrees: 1 (default, 3x3 pixels), 2 (5x5: closer to the truth close up, slower),
    /// 0 (each pixel alone, the fastest). weft bench --ibl shows the cost and error of each.
    #[arg(long, default_value_t = weft::env::DEFAULT_POOL)]
    ibl_pool: u32,
    /// Occlusion of the environment's light: gtao (screen-space ground-truth ambient occlusion
    /// from the depth buffer, out to 0.3 of the scene's size; the light bounced between
    /// occluders from a fit, and the occluders' own light the screen shows where it is more;
    /// and, for a static scene, the world light: what each vertex sees of the whole scene,
    /// baked by rays on the CPU, for the occluders the screen does not show; where every
    /// receiving triangle is small beside the radius, the world's alone: `weft plan` says which),
    /// gtao:R (out to R
    /// world units), gtao-screen[:R] (the screen's alone, no world light), gtao-nobounce[:R] (the
    /// fit alone), or none (occlusion textures only). Runs only when an environment lights the
    /// scene.
    #[arg(long, default_value = "gtao", value_parser = Choice::new(
        render::Occlusion::parse,
        &["gtao", "gtao:R", "gtao-screen", "gtao-screen:R", "gtao-nobounce", "gtao-nobounce:R", "none"],
    ))]
    occlusion: render::Occlusion,
    /// Punctual lights: auto (the file's; a default key light with a shadow and a ground when it
    /// has none and no --env FILE is given), none, file, default.
    #[arg(long, default_value = "auto")]
    lights: String,
    /// KHR_materials_variants: load the materials of this variant (`weft plan` lists them).
    #[arg(long)]
    variant: Option<String>,
    /// Which of the file's scenes to draw, by index or name (default: the file's `scene`, else
    /// its first; `weft plan` lists them).
    #[arg(long, value_name = "N|NAME")]
    gltf_scene: Option<String>,
}

impl SceneArgs {
    /// The flags as the library's [`SceneSpec`]. The flags that take a word are read here, so a
    /// typo fails before any loading.
    fn spec(&self, fabric: &[String]) -> anyhow::Result<SceneSpec> {
        Ok(SceneSpec {
            scene: self.scene.clone(),
            variant: self.variant.clone(),
            gltf_scene: self.gltf_scene.clone(),
            fabric: fabric.to_vec(),
            size: self.size,
            camera: self.camera,
            look_at: self.eye.zip(self.target),
            fov_degrees: self.fov,
            accuracy: self.accuracy,
            weave_precision: self.weave_precision,
            footprint: self.footprint,
            debug_view: self.debug_view,
            shading: self.shading,
            env: EnvSource::parse(&self.env),
            env_rotation: self.env_rotation,
            env_intensity: self.env_intensity,
            background: weft::env::Background::parse(&self.background)?,
            ibl: weft::env::IblLevel::parse(&self.ibl)?,
            ibl_pool: self.ibl_pool,
            occlusion: self.occlusion,
            lights: weft::env::LightsMode::parse(&self.lights)?,
        })
    }
}

/// [`SceneSpec::load`] for the command line: a progress line for a large file, what `--fabric`
/// applied and, unless `quiet`, the loader's warnings on stderr.
fn load_spec(spec: &SceneSpec, default_size: (u32, u32), quiet: bool) -> anyhow::Result<Loaded> {
    // A progress line for loads a user waits on (tangent generation and texture decoding of a
    // large file take seconds).
    let bytes = spec
        .scene
        .as_ref()
        .and_then(|p| std::fs::metadata(p).ok())
        .map_or(0, |m| m.len());
    let big = bytes > 32 << 20 && !quiet;
    let t = std::time::Instant::now();
    if let (true, Some(path)) = (big, &spec.scene) {
        eprintln!("loading {} ({} MiB)...", path.display(), bytes >> 20);
    }
    let loaded = spec.load(default_size)?;
    if let (true, Some(path)) = (big, &spec.scene) {
        eprintln!(
            "loaded {} in {:.1} s",
            path.display(),
            t.elapsed().as_secs_f64()
        );
    }
    for a in &loaded.applied {
        eprint!("fabric: {a}");
    }
    if !quiet {
        for w in &loaded.scene.warnings {
            eprintln!("warning: {w}");
        }
    }
    Ok(loaded)
}

/// The scene and options of `args` (and `--fabric` requests) at `args`' size or `default_size`.
fn load_scene_with(
    args: &SceneArgs,
    default_size: (u32, u32),
    fabric: &[String],
    quiet: bool,
) -> anyhow::Result<(Scene, RenderOptions)> {
    let loaded = load_spec(&args.spec(fabric)?, default_size, quiet)?;
    Ok((loaded.scene, loaded.options))
}

/// The files a command reads, which none of its outputs may be ([`SceneSpec::inputs`]).
fn inputs_of(args: &SceneArgs, scene: &Scene) -> Vec<PathBuf> {
    SceneSpec {
        scene: args.scene.clone(),
        env: EnvSource::parse(&args.env),
        ..SceneSpec::default()
    }
    .inputs(scene)
}

pub fn main() -> ExitCode {
    // A panic the library catches and turns into an error (weft::catch_panic: a dependency's,
    // on input that slipped past weft's checks) is reported as that error, naming the file;
    // its panic text and backtrace would only bury it. Any other panic is a bug: shown as is.
    // A reader that stops early (`weft fabric --list-presets | head -1`) closes the pipe under
    // the standard library's print!, which panics: weft ends quietly and successfully there, as
    // command-line tools do (ripgrep's choice), instead of printing a backtrace.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let text = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.starts_with("failed printing to stdout") && text.contains("Broken pipe") {
            std::process::exit(0);
        }
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
        Command::Fabric(args) => fabric::run(args),
        Command::Fidelity(args) => fidelity::run(args),
        Command::View(args) => run_view(args),
        Command::Cache(args) => cache::run(args),
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
