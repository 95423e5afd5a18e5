//! `weft view`: the interactive window.

use super::*;

#[derive(Args)]
pub(super) struct ViewArgs {
    #[command(flatten)]
    pub(super) scene: SceneArgs,
    /// Exposure in EV (stops), as for render (the panel changes it live).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--exposure", s))]
    pub(super) exposure: f32,
    /// Edge anti-aliasing, as for render: fxaa or none (ssN is for still renders).
    #[arg(long, default_value = "fxaa", value_parser = parse_aa)]
    pub(super) aa: render::Antialias,
    /// Turn on the Vulkan validation layer; any message it reports ends the viewer with an error.
    #[arg(long)]
    pub(super) validate: bool,
    /// Vulkan device: auto, cpu (lavapipe), an index, or part of a name. Also WEFT_DEVICE.
    #[arg(long)]
    pub(super) device: Option<String>,
    /// Write the window's content to this PNG after --after frames, then exit.
    #[arg(long)]
    pub(super) screenshot: Option<PathBuf>,
    /// Frames to present before --screenshot.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub(super) after: u32,
    /// Start with the panel hidden (Tab shows it): the window then shows exactly the render.
    #[arg(long)]
    pub(super) no_panel: bool,
    /// Time this many frames of the frame loop (after 3 warm-up frames), print a table, exit.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub(super) bench_frames: Option<u32>,
    /// The glTF animation to play (name or index; `weft plan` lists them): the file's first
    /// plays, looping, unless this says which. Space pauses and plays.
    #[arg(long)]
    pub(super) animation: Option<String>,
    /// Start paused at this time of the animation, in seconds (Space plays).
    #[arg(long, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--time", s))]
    pub(super) time: Option<f32>,
}

pub(super) fn run_view(args: ViewArgs) -> anyhow::Result<()> {
    let device = args
        .device
        .as_deref()
        .map(DeviceChoice::parse)
        .unwrap_or_else(DeviceChoice::from_env);
    let (scene, mut options) = load_scene_with(&args.scene, (1280, 720), &[], false)?;
    let playback =
        weft::view::playback::Playback::for_scene(&scene, args.animation.as_deref(), args.time)?;
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
        playback,
    })?;
    if let Some(r) = report {
        print!("{}", r.table());
    }
    Ok(())
}
