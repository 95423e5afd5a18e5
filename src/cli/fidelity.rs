//! `weft fidelity`: weft among the glTF renderers on Khronos' glTF-Render-Fidelity scenarios
//! (`weft::fidelity`, docs/fidelity.md).

use std::path::{Path, PathBuf};
use std::process::Command;

use clap::Args;

use weft::fidelity::{self, Scenario};

#[derive(Args)]
pub struct FidelityArgs {
    /// The folder that holds fidelity/ (scenarios.json, environments/, thumbnails/) and the
    /// models the scenarios name (realworld/...). Default: ../shared if it exists.
    #[arg(long)]
    pub shared: Option<PathBuf>,
    /// Where to write weft's renders, the side-by-side sheet and the table.
    #[arg(short, long, default_value = "fidelity-out")]
    pub out: PathBuf,
    /// The engine whose thumbnails are the truth.
    #[arg(long, default_value = "blender-cycles")]
    pub reference: String,
    /// Only these scenarios (names with or without the khronos- prefix), comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Render one scenario as the comparison generator calls an offline renderer: the argument
    /// is `{"scenario": {...a scenarios.json entry...}, "outputFile": "out.png"}`; the image is
    /// rendered at twice the scenario's size, as the goldens are.
    #[arg(long, conflicts_with_all = ["only"])]
    pub scenario: Option<String>,
    /// Occlusion of the environment's light in weft's renders, as `weft render --occlusion`
    /// takes it (gtao, gtao:R, gtao-nobounce, none): to see what it changes in the comparison.
    #[arg(long, default_value = "gtao", value_parser = |s: &str| weft::render::Occlusion::parse(s).map(|_| s.to_string()))]
    pub occlusion: String,
    /// How weft's renders integrate environment light, as `weft render --ibl` takes it (approx,
    /// fis:N, mc:N): what a better estimator would change in the comparison (mc:N is weft's own
    /// Monte Carlo truth).
    #[arg(long, default_value = "fis:8", value_parser = |s: &str| weft::env::IblLevel::parse(s).map(|_| s.to_string()))]
    pub ibl: String,
    /// Punctual lights in weft's renders, as `weft render --lights` takes them (auto: the file's;
    /// none): to see what the file's own lights change in the comparison.
    #[arg(long, default_value = "auto", value_parser = |s: &str| weft::env::LightsMode::parse(s).map(|_| s.to_string()))]
    pub lights: String,
}

fn shared_dir(arg: &Option<PathBuf>) -> anyhow::Result<PathBuf> {
    match arg {
        Some(d) => Ok(d.clone()),
        None => {
            let d = PathBuf::from("../shared");
            if d.join("fidelity").is_dir() {
                Ok(d)
            } else {
                anyhow::bail!(
                    "no ../shared/fidelity here: give --shared DIR, the folder that holds fidelity/ and the models (realworld/...)"
                )
            }
        }
    }
}

/// The model, or where the same sample keeps it in another of the sample repository's variants
/// (a copy may hold only glTF-Binary, say, where the scenario names glTF/).
fn model_path(named: &Path) -> PathBuf {
    if named.exists() {
        return named.to_path_buf();
    }
    let (Some(stem), Some(sample)) = (named.file_stem(), named.parent().and_then(Path::parent))
    else {
        return named.to_path_buf();
    };
    let stem = stem.to_string_lossy();
    let mut variants: Vec<PathBuf> = std::fs::read_dir(sample)
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("glTF"))
        })
        .collect();
    // glTF-Binary and glTF first (the plain variants), then the others (KTX2, Draco...).
    variants.sort_by_key(|p| {
        !matches!(
            p.file_name().and_then(|n| n.to_str()),
            Some("glTF-Binary" | "glTF")
        )
    });
    variants
        .iter()
        .flat_map(|v| {
            [
                v.join(format!("{stem}.glb")),
                v.join(format!("{stem}.gltf")),
            ]
        })
        .find(|p| p.exists())
        .unwrap_or_else(|| named.to_path_buf())
}

/// `weft render` of `s` at `width` x `height` into `out` (a child process: one scenario's failure
/// is its own, and every scene starts from the same state a user's render does).
fn render(
    s: &Scenario,
    shared: &Path,
    width: u32,
    height: u32,
    occlusion: &str,
    ibl: &str,
    lights: &str,
    out: &Path,
) -> anyhow::Result<()> {
    let exe = std::env::current_exe()?;
    let model = model_path(&shared.join(&s.model));
    let v3 = |v: [f32; 3]| format!("{},{},{}", v[0], v[1], v[2]);
    let output = Command::new(exe)
        .arg("render")
        .arg(&model)
        .args(["--size", &format!("{width}x{height}")])
        .args(["--eye", &v3(s.eye), "--target", &v3(s.target)])
        .args(["--fov", &s.vertical_fov_deg.to_string()])
        .arg("--env")
        .arg(shared.join("fidelity").join(&s.environment))
        // The goldens put the equirect's centre at +X, weft at -Z (../shared/fidelity/README.md).
        .args(["--env-rotation", "-90"])
        .args(["--background", if s.skybox { "env" } else { "none" }])
        .args(["--tonemap", "aces"])
        .args(["--occlusion", occlusion])
        .args(["--ibl", ibl])
        .args(["--lights", lights])
        .arg("-o")
        .arg(out)
        .output()?;
    if !output.status.success() {
        anyhow::bail!(
            "weft render of scenario '{}' failed: {}",
            s.name,
            String::from_utf8_lossy(&output.stderr).trim()
        );
    }
    Ok(())
}

fn load_rgba(path: &Path) -> anyhow::Result<image::RgbaImage> {
    Ok(image::open(path)
        .map_err(|e| anyhow::anyhow!("cannot read '{}': {e}", path.display()))?
        .to_rgba8())
}

/// One scenario's outcome.
struct Row {
    name: String,
    /// The generator's scores (over each candidate's own pixels).
    scores: Scores,
    /// The same over the reference's pixels ([`fidelity::score_over_reference`]).
    object: Scores,
    /// Engines whose thumbnail covers over 5 % more pixels than the reference's (an opaque
    /// background), with the ratio.
    overcovered: Vec<(String, f64)>,
}

/// weft's score and every published engine's but the reference's, by one measure.
struct Scores {
    weft: f64,
    /// (engine, score).
    engines: Vec<(String, f64)>,
}

impl Scores {
    fn best_rasterizer(&self) -> Option<(&str, f64)> {
        self.engines
            .iter()
            .filter(|(e, _)| fidelity::RASTERIZERS.contains(&e.as_str()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(e, s)| (e.as_str(), *s))
    }

    /// weft's place among the rasterizers (1 = closest), and how many there are.
    fn rank(&self) -> (usize, usize) {
        let r: Vec<f64> = self
            .engines
            .iter()
            .filter(|(e, _)| fidelity::RASTERIZERS.contains(&e.as_str()))
            .map(|(_, s)| *s)
            .collect();
        (
            1 + r.iter().filter(|s| **s < self.weft).count(),
            r.len() + 1,
        )
    }
}

pub fn run(args: FidelityArgs) -> anyhow::Result<()> {
    let shared = shared_dir(&args.shared)?;
    if let Some(json) = &args.scenario {
        let v: serde_json::Value = serde_json::from_str(json)
            .map_err(|e| anyhow::anyhow!("--scenario is not JSON: {e}"))?;
        let s = Scenario::from_json("--scenario", &v["scenario"])?;
        let out = v["outputFile"]
            .as_str()
            .ok_or_else(|| anyhow::anyhow!("--scenario has no \"outputFile\" string"))?;
        return render(
            &s,
            &shared,
            2 * s.size[0],
            2 * s.size[1],
            &args.occlusion,
            &args.ibl,
            &args.lights,
            Path::new(out),
        );
    }
    let root = shared.join("fidelity");
    let scenarios = Scenario::load_all(&root.join("scenarios.json"))?;
    let wanted = |s: &Scenario| {
        args.only.is_empty()
            || args
                .only
                .iter()
                .any(|o| o == &s.name || o == s.short_name())
    };
    let renders = args.out.join("weft");
    std::fs::create_dir_all(&renders)
        .map_err(|e| anyhow::anyhow!("cannot create '{}': {e}", renders.display()))?;
    let mut rows = Vec::new();
    let mut sheet_rows: Vec<[image::RgbaImage; 3]> = Vec::new();
    for s in scenarios.iter().filter(|s| wanted(s)) {
        let thumbs = root.join("thumbnails").join(&s.name);
        let reference_path = thumbs.join(format!("{}.webp", args.reference));
        if !reference_path.exists() {
            eprintln!("{}: no {} thumbnail, skipped", s.name, args.reference);
            continue;
        }
        let reference = load_rgba(&reference_path)?;
        let (tw, th) = reference.dimensions();
        let full = renders.join(format!("{}.png", s.short_name()));
        // At the goldens' own size (twice the scenario's: the browsers capture at device pixel
        // ratio 2), not the thumbnail's: a texture that the golden magnifies, and the site's
        // resize then averages in display space, would be minified here and mip-filtered in
        // linear light instead (TextureEncodingTest's lettering: -18.4 dB at twice the
        // thumbnail, -24.4 at the golden's size).
        if let Err(e) = render(
            s,
            &shared,
            2 * s.size[0],
            2 * s.size[1],
            &args.occlusion,
            &args.ibl,
            &args.lights,
            &full,
        ) {
            eprintln!("{e}");
            continue;
        }
        let ours = fidelity::thumbnail(&load_rgba(&full)?, tw, th)?;
        ours.save(renders.join(format!("{}.thumb.png", s.short_name())))?;
        let Some(weft_score) = fidelity::score(&reference, &ours) else {
            eprintln!("{}: weft's render has no opaque pixel", s.name);
            continue;
        };
        let mut engines = Vec::new();
        let mut object = Vec::new();
        let mut overcovered = Vec::new();
        let mut entries: Vec<PathBuf> = std::fs::read_dir(&thumbs)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "webp"))
            .collect();
        entries.sort();
        for p in entries {
            let engine = p
                .file_stem()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            if engine == args.reference {
                continue;
            }
            let thumb = load_rgba(&p)?;
            if let (Some(score), Some(inside)) = (
                fidelity::score(&reference, &thumb),
                fidelity::score_over_reference(&reference, &thumb),
            ) {
                let ratio = fidelity::coverage_ratio(&reference, &thumb);
                if ratio > 1.05 {
                    overcovered.push((engine.clone(), ratio));
                }
                engines.push((engine.clone(), score));
                object.push((engine, inside));
            }
        }
        let row = Row {
            name: s.short_name().to_string(),
            scores: Scores {
                weft: weft_score,
                engines,
            },
            object: Scores {
                weft: fidelity::score_over_reference(&reference, &ours).unwrap_or(f64::NAN),
                engines: object,
            },
            overcovered,
        };
        let best = row.scores.best_rasterizer();
        let best_img = match best {
            Some((e, _)) => load_rgba(&thumbs.join(format!("{e}.webp")))?,
            None => image::RgbaImage::new(tw, th),
        };
        sheet_rows.push([reference, ours, best_img]);
        let (rank, of) = row.scores.rank();
        println!(
            "{:<32} weft {:>6.1} dB   best rasterizer {:<20} {:>6.1}   weft {rank} of {of}",
            row.name,
            row.scores.weft,
            best.map_or("-", |b| b.0),
            best.map_or(f64::NAN, |b| b.1)
        );
        if !row.overcovered.is_empty() {
            let (rank, of) = row.object.rank();
            let best = row.object.best_rasterizer();
            println!(
                "{:<32} {}; over {}'s own pixels: weft {:.1}, best rasterizer {} {:.1}, weft {rank} of {of}",
                "",
                row.overcovered
                    .iter()
                    .map(|(e, r)| format!("{e} covers {r:.2}x the reference's pixels"))
                    .collect::<Vec<_>>()
                    .join(", "),
                args.reference,
                row.object.weft,
                best.map_or("-", |b| b.0),
                best.map_or(f64::NAN, |b| b.1)
            );
        }
        rows.push(row);
    }
    if rows.is_empty() {
        anyhow::bail!("no scenario was scored (check --shared and --only)");
    }
    // Medians over the scenarios scored, each engine over those it has.
    let medians = engine_medians(rows.iter().map(|r| &r.scores));
    println!(
        "\nmedian against {} (more negative = closer)",
        args.reference
    );
    for (e, m, n) in &medians {
        println!("  {e:<22} {m:>6.1} dB over {n} scenarios");
    }
    let object_medians = engine_medians(rows.iter().map(|r| &r.object));
    // Printed where it differs to the tenth of a dB that the table shows.
    let shown = |m: &[(String, f64, usize)]| {
        m.iter()
            .map(|(e, v, n)| format!("{e} {v:.1} {n}"))
            .collect::<Vec<_>>()
    };
    if shown(&object_medians) != shown(&medians) {
        println!(
            "\nthe same over {}'s own pixels (an opaque background not credited)",
            args.reference
        );
        for (e, m, n) in &object_medians {
            println!("  {e:<22} {m:>6.1} dB over {n} scenarios");
        }
    }
    // The table and the sheet.
    let mut md = String::from(
        "| scenario | weft | best rasterizer | weft's rank among the rasterizers | over the reference's pixels: weft, best rasterizer, rank |\n|---|---|---|---|---|\n",
    );
    for r in &rows {
        let (rank, of) = r.scores.rank();
        let best = r.scores.best_rasterizer();
        let (orank, oof) = r.object.rank();
        let obest = r.object.best_rasterizer();
        md.push_str(&format!(
            "| {} | {:.1} | {} {:.1} | {rank} of {of} | {:.1}, {} {:.1}, {orank} of {oof} |\n",
            r.name,
            r.scores.weft,
            best.map_or("-", |b| b.0),
            best.map_or(f64::NAN, |b| b.1),
            r.object.weft,
            obest.map_or("-", |b| b.0),
            obest.map_or(f64::NAN, |b| b.1)
        ));
    }
    md.push_str(&format!("\nMedians against {}:\n\n", args.reference));
    for (e, m, n) in &medians {
        md.push_str(&format!("- {e}: {m:.1} dB ({n} scenarios)\n"));
    }
    std::fs::write(args.out.join("fidelity.md"), md)?;
    write_sheet(&sheet_rows, &args.out.join("sheet.png"))?;
    println!(
        "\nwrote {} (per scenario: {} | weft | the closest rasterizer, over white) and {}",
        args.out.join("sheet.png").display(),
        args.reference,
        args.out.join("fidelity.md").display()
    );
    Ok(())
}

/// Each engine's median over the scenarios it has (weft first as scored), closest first.
fn engine_medians<'a>(rows: impl Iterator<Item = &'a Scores> + Clone) -> Vec<(String, f64, usize)> {
    let weft: Vec<f64> = rows.clone().map(|r| r.weft).collect();
    let n = weft.len();
    let mut medians = vec![("weft".to_string(), weft::bench::median(weft), n)];
    let mut engines: Vec<String> = rows
        .clone()
        .flat_map(|r| r.engines.iter().map(|(e, _)| e.clone()))
        .collect();
    engines.sort();
    engines.dedup();
    for e in engines {
        let v: Vec<f64> = rows
            .clone()
            .filter_map(|r| r.engines.iter().find(|(n, _)| *n == e).map(|(_, s)| *s))
            .collect();
        let n = v.len();
        medians.push((e, weft::bench::median(v), n));
    }
    medians.sort_by(|a, b| a.1.total_cmp(&b.1));
    medians
}

/// Rows of three thumbnails (reference, weft, best rasterizer), each scaled to 256 px wide and
/// blended over white as the metric sees them.
fn write_sheet(rows: &[[image::RgbaImage; 3]], path: &Path) -> anyhow::Result<()> {
    const W: u32 = 256;
    let scaled: Vec<Vec<image::RgbaImage>> = rows
        .iter()
        .map(|r| {
            r.iter()
                .map(|img| {
                    let (w, h) = img.dimensions();
                    let h2 = (h as u64 * W as u64 / w.max(1) as u64).max(1) as u32;
                    image::imageops::resize(img, W, h2, image::imageops::FilterType::Triangle)
                })
                .collect()
        })
        .collect();
    let height: u32 = scaled.iter().map(|r| r[0].height() + 4).sum();
    let mut sheet =
        image::RgbImage::from_pixel(3 * (W + 4), height.max(1), image::Rgb([255, 255, 255]));
    let mut y = 0;
    for r in &scaled {
        for (k, img) in r.iter().enumerate() {
            for (x, yy, p) in img.enumerate_pixels() {
                let c = fidelity::over_white(p.0).map(|v| v.round() as u8);
                if yy + y < sheet.height() {
                    sheet.put_pixel(k as u32 * (W + 4) + x, y + yy, image::Rgb(c));
                }
            }
        }
        y += r[0].height() + 4;
    }
    sheet.save(path)?;
    Ok(())
}
