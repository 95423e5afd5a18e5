//! `weft compare`: the paper's comparison figure.

use super::*;

#[derive(Args)]
pub(super) struct CompareArgs {
    #[command(flatten)]
    pub(super) scene: SceneArgs,
    /// Output PNG: the four panels in a row, each labelled.
    #[arg(short, long, default_value = "figure.png")]
    pub(super) output: PathBuf,
    /// Exposure in EV (stops), as for render.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = |s: &str| render::parse_finite("--exposure", s))]
    pub(super) exposure: f32,
    /// Turn on the Vulkan validation layer; any message it reports fails the run.
    #[arg(long)]
    pub(super) validate: bool,
    /// Vulkan device: auto, cpu (lavapipe), an index, or part of a name. Also WEFT_DEVICE.
    #[arg(long)]
    pub(super) device: Option<String>,
}

pub(super) fn run_compare(args: CompareArgs) -> anyhow::Result<()> {
    let (scene, mut options) = load_scene_with(&args.scene, (480, 360), &[], false)?;
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
