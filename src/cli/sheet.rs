//! `weft sheet`: a contact sheet of many files rendered alike.

use super::*;

#[derive(Args)]
pub(super) struct SheetArgs {
    /// .gltf/.glb files, or folders to search recursively.
    #[arg(required = true)]
    pub(super) paths: Vec<PathBuf>,
    /// Output PNG.
    #[arg(short, long, default_value = "sheet.png")]
    pub(super) output: PathBuf,
    /// Size of each cell, WIDTHxHEIGHT.
    #[arg(long, default_value = "256x192", value_parser = checked_size)]
    pub(super) size: (u32, u32),
    /// Cells per row.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..))]
    pub(super) columns: u32,
    /// Environment, as for render: a .hdr/.exr file, studio or none.
    #[arg(long, default_value = "studio")]
    pub(super) env: String,
    /// Turn on the Vulkan validation layer; any message it reports fails that scene's cell.
    #[arg(long)]
    pub(super) validate: bool,
    /// Vulkan device, as for render.
    #[arg(long)]
    pub(super) device: Option<String>,
}

pub(super) fn run_sheet(args: SheetArgs) -> anyhow::Result<()> {
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
        let spec = SceneSpec {
            scene: Some(file.clone()),
            size: Some(args.size),
            env: EnvSource::parse(&args.env),
            ..SceneSpec::default()
        };
        let result = spec
            .load(args.size)
            .map_err(anyhow::Error::from)
            .and_then(|loaded| {
                let frame = renderer.render(&loaded.scene, &loaded.options)?;
                Ok((loaded.scene, frame))
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
