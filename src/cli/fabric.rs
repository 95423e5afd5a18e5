//! `weft fabric`: the command line of `weft::assets` (docs/fabric-on-assets.md).

use std::path::{Path, PathBuf};

use clap::Args;

use weft::assets::{self, Colour, MaterialRef, Overrides, Request, Source};
use weft::fabric::draft::Draft;
use weft::fabric::{presets, ThreadTexture, WeavePattern};

#[derive(Args)]
pub struct FabricArgs {
    /// The .gltf or .glb file to start from.
    #[arg(required_unless_present = "list_presets")]
    pub input: Option<PathBuf>,
    /// Where to write the copy (same kind as the input: .gltf or .glb). A .gltf's external
    /// buffers and images are copied beside it when it goes to another folder.
    #[arg(short, long, required_unless_present = "list_presets")]
    pub output: Option<PathBuf>,
    /// Materials to weave: names or indices, comma-separated (or the flag repeated).
    #[arg(long, value_delimiter = ',', required_unless_present = "list_presets")]
    pub material: Vec<String>,
    /// The fabric: a preset (--list-presets) or from-sheen (map the material's KHR_materials_sheen).
    #[arg(long, required_unless_present = "list_presets")]
    pub preset: Option<String>,
    /// Print the presets with their parameters and sources, and exit.
    #[arg(long)]
    pub list_presets: bool,
    /// Thread pitch (centre to centre) in world units: 0.8mm, 0.1cm, 0.0008m, 0.03in.
    #[arg(long)]
    pub pitch: Option<String>,
    /// Weave pattern instead of the preset's: plain, twill, satin, or rows like "-|/|-".
    #[arg(long)]
    pub pattern: Option<String>,
    /// A weaving draft (WIF, the Weaving Information File of weaving programs): its weave instead
    /// of the preset's pattern, and its thread colours, thread by thread where a warp or weft
    /// changes colour (stripes, checks, tartans), unless --rd, --rd-warp or --rd-weft say
    /// otherwise.
    #[arg(long, conflicts_with = "pattern")]
    pub draft: Option<PathBuf>,
    /// Gap between threads as a fraction of the pitch, 0..1.
    #[arg(long)]
    pub gap: Option<f64>,
    /// Thread colour (both threads), linear R,G,B or one number, or `base` (the material's
    /// baseColorFactor).
    #[arg(long)]
    pub rd: Option<String>,
    /// Warp thread colour, as --rd.
    #[arg(long)]
    pub rd_warp: Option<String>,
    /// Weft thread colour, as --rd.
    #[arg(long)]
    pub rd_weft: Option<String>,
    /// Ashikhmin-Shirley exponent along a thread.
    #[arg(long)]
    pub e_along: Option<f32>,
    /// Ashikhmin-Shirley exponent across a thread.
    #[arg(long)]
    pub e_across: Option<f32>,
    /// Schlick reflectance at normal incidence.
    #[arg(long)]
    pub rs: Option<f32>,
    /// How dark the thread shadow is, 0..1.
    #[arg(long)]
    pub shadow_strength: Option<f32>,
    /// Fraction of a thread's length that is shadowed, 0..1.
    #[arg(long)]
    pub shadow_width: Option<f32>,
    /// Use the Ashikhmin-Shirley coupled diffuse instead of Lambert.
    #[arg(long)]
    pub coupled_diffuse: bool,
    /// The material's texture multiplied over the thread colours: base_color (the default),
    /// sheen_color or none.
    #[arg(long)]
    pub thread_texture: Option<String>,
    /// The cloth is a single sheet (a curtain, a veil): its gaps let light straight through and
    /// its threads pass the preset's thread transmittance of their diffuse light to the other
    /// side. A material with KHR_materials_diffuse_transmission is a sheet without it.
    #[arg(long)]
    pub sheet: bool,
    /// A single sheet whose threads pass this share of their diffuse light through, 0..1.
    #[arg(long)]
    pub transmission: Option<f32>,
}

fn unit_range(flag: &str, x: Option<f32>) -> anyhow::Result<Option<f32>> {
    match x {
        Some(v) if !(0.0..=1.0).contains(&v) => {
            anyhow::bail!("{flag} {v} is outside [0, 1]")
        }
        _ => Ok(x),
    }
}

fn overrides(args: &FabricArgs) -> anyhow::Result<Overrides> {
    let colour = |flag: &str, v: &Option<String>| -> anyhow::Result<Option<Colour>> {
        Ok(match v {
            Some(t) => Some(Colour::parse(flag, t)?),
            None => None,
        })
    };
    let pattern = match &args.pattern {
        None => None,
        Some(p) => Some(match WeavePattern::by_name(p) {
            Some(p) => p,
            None => {
                let rows: Vec<&str> = p.split('/').collect();
                WeavePattern::from_rows(&rows).map_err(|e| {
                    anyhow::anyhow!(
                        "--pattern '{p}' is neither plain, twill, satin nor rows like \"-|/|-\" ('-' weft up, '|' warp up, rows separated by '/'): {e}"
                    )
                })?
            }
        }),
    };
    if let Some(g) = args.gap {
        if !(0.0..=1.0).contains(&g) {
            anyhow::bail!("--gap {g} is outside [0, 1] (a fraction of the thread pitch)");
        }
    }
    for (flag, e) in [("--e-along", args.e_along), ("--e-across", args.e_across)] {
        if let Some(e) = e {
            if !(0.0..=1e6).contains(&e) {
                anyhow::bail!("{flag} {e} is outside [0, 1e6]");
            }
        }
    }
    let mut o = Overrides {
        pitch_m: args
            .pitch
            .as_deref()
            .map(assets::parse_length)
            .transpose()?,
        pattern,
        gap_fraction: args.gap,
        e_along: args.e_along,
        e_across: args.e_across,
        rs: unit_range("--rs", args.rs)?,
        shadow_strength: unit_range("--shadow-strength", args.shadow_strength)?,
        shadow_width: unit_range("--shadow-width", args.shadow_width)?,
        rd: colour("--rd", &args.rd)?,
        rd_warp: colour("--rd-warp", &args.rd_warp)?,
        rd_weft: colour("--rd-weft", &args.rd_weft)?,
        coupled_diffuse: args.coupled_diffuse.then_some(true),
        thread_texture: match &args.thread_texture {
            None => None,
            Some(t) => Some(ThreadTexture::by_name(t).ok_or_else(|| {
                anyhow::anyhow!(
                    "--thread-texture '{t}' is not one of {:?} (the material's texture multiplied over the thread colours)",
                    ThreadTexture::NAMES
                )
            })?),
        },
        warp_colours: None,
        weft_colours: None,
        sheet: args.sheet.then_some(true),
        transmission: unit_range("--transmission", args.transmission)?,
    };
    if let Some(path) = &args.draft {
        let d = Draft::load(path)?;
        eprintln!(
            "draft {}: {} warp threads x {} picks, weave repeat {} x {} cells ({}; '-' weft up, '|' warp up, pick 1 first)",
            path.display(),
            d.threads,
            d.picks,
            d.pattern.cols(),
            d.pattern.rows(),
            d.pattern.to_rows().join("/")
        );
        for w in o.apply_draft(&d) {
            eprintln!("warning: {w}");
        }
    }
    Ok(o)
}

fn list_presets() {
    for p in presets::PRESETS {
        println!("{:<16} {}", p.name, p.summary);
        println!(
            "{:<16} pattern {}, pitch {}, gap {:.0}% of the pitch, e_along {}, e_across {}, rs {}, shadow {} x {}",
            "",
            p.pattern,
            assets::format_length(p.pitch_m),
            p.gap_fraction * 100.0,
            p.e_along,
            p.e_across,
            p.rs,
            p.shadow_strength,
            p.shadow_width
        );
        println!(
            "{:<16} rd_warp {:?}, rd_weft {:?} (linear)",
            "", p.rd_warp, p.rd_weft
        );
        println!("{:<16} sources: {}", "", p.sources);
    }
    println!(
        "{:<16} the material's own KHR_materials_sheen and base colour, mapped (docs/fabric-on-assets.md)",
        "from-sheen"
    );
}

fn kind(path: &Path) -> Option<&'static str> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("gltf") => Some("gltf"),
        Some("glb") => Some("glb"),
        _ => None,
    }
}

pub fn run(args: FabricArgs) -> anyhow::Result<()> {
    if args.list_presets {
        list_presets();
        return Ok(());
    }
    let (Some(input), Some(output), Some(preset)) = (&args.input, &args.output, &args.preset)
    else {
        anyhow::bail!("weft fabric needs IN, -o OUT, --material and --preset (or --list-presets)");
    };
    let source = Source::parse(preset)?;
    let materials: Vec<MaterialRef> = args
        .material
        .iter()
        .map(|m| m.trim())
        .filter(|m| !m.is_empty())
        .map(MaterialRef::parse)
        .collect();
    if materials.is_empty() {
        anyhow::bail!("--material needs at least one material name or index");
    }
    let request = Request {
        materials,
        source,
        overrides: overrides(&args)?,
    };
    let bytes = std::fs::read(input)
        .map_err(|e| anyhow::anyhow!("cannot read '{}': {e}", input.display()))?;
    let in_kind = if bytes.starts_with(b"glTF") {
        "glb"
    } else {
        "gltf"
    };
    match kind(output) {
        Some(k) if k == in_kind => {}
        Some(k) => anyhow::bail!(
            "the input is a .{in_kind} and the output '{}' a .{k}; weft fabric writes the same kind it reads (name the output .{in_kind})",
            output.display()
        ),
        None => anyhow::bail!(
            "the output '{}' should end in .{in_kind} (the input's kind)",
            output.display()
        ),
    }
    let in_dir = match input.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let out_dir = match output.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    // The output against what is read (the input and the files it refers to), as for render.
    let mut inputs = vec![input.clone()];
    if in_kind == "gltf" {
        if let Ok(doc) = serde_json::from_slice::<serde_json::Value>(&bytes) {
            inputs.extend(assets::external_files(&doc).iter().map(|f| in_dir.join(f)));
        }
    }
    std::fs::create_dir_all(&out_dir)
        .map_err(|e| anyhow::anyhow!("cannot create '{}': {e}", out_dir.display()))?;
    weft::render::check_outputs(
        &inputs.iter().map(PathBuf::as_path).collect::<Vec<_>>(),
        &[weft::render::OutputPath::new("-o", output)],
    )?;
    let source_name = input.display().to_string();
    let (out_bytes, applied) = assets::transform(
        &bytes,
        &source_name,
        Some(&in_dir),
        std::slice::from_ref(&request),
    )?;
    let copied = if in_kind == "gltf" {
        let doc: serde_json::Value = serde_json::from_slice(&out_bytes)?;
        assets::copy_external_files(&doc, &in_dir, &out_dir)?
    } else {
        Vec::new()
    };
    std::fs::write(output, &out_bytes)
        .map_err(|e| anyhow::anyhow!("cannot write '{}': {e}", output.display()))?;
    for a in &applied {
        print!("{a}");
    }
    if !copied.is_empty() {
        println!(
            "copied {} external file(s) beside the output so its references resolve: {}",
            copied.len(),
            copied
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    println!("wrote {}", output.display());
    Ok(())
}
