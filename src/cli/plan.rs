//! `weft plan`: what a frame of the scene needs.

use super::*;

#[derive(Args)]
pub(super) struct PlanArgs {
    #[command(flatten)]
    pub(super) scene: SceneArgs,
    /// Print the plan as JSON.
    #[arg(long)]
    pub(super) json: bool,
    /// Anti-aliasing, as for render (its default: fxaa; ssN: the plan of each of its N² frames).
    #[arg(long, default_value = "fxaa", value_parser = parse_aa)]
    pub(super) aa: render::Antialias,
    /// The tone curve, as for render (the plan says which one the tonemap pass compiles in).
    #[arg(long, default_value = "pbr-neutral", value_parser = parse_tonemap)]
    pub(super) tonemap: render::ToneCurve,
    /// The woven fabric tried on a material, as for render: MATERIAL=PRESET[+sheet][@PITCH][:DRAFT.wif];
    /// repeatable.
    #[arg(long)]
    pub(super) fabric: Vec<String>,
}

pub(super) fn run_plan(args: PlanArgs) -> anyhow::Result<()> {
    let (scene, mut options) = load_scene_with(&args.scene, (1280, 720), &args.fabric, false)?;
    options.antialias = args.aa;
    options.tonemap = args.tonemap;
    // As `weft render` plans a frame without `--exr`: no HDR image read back.
    options.read_hdr = false;
    let plan = Plan::new(&scene, &options);
    if args.json {
        let mut json = serde_json::to_value(&plan)?;
        json["animations"] = scene
            .animations()
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let [nodes, materials, lights, cameras] = scene.animation_drives(i);
                serde_json::json!({"name": a.name, "duration": a.duration,
                    "drives": {"nodes": nodes, "materials": materials, "lights": lights, "cameras": cameras}})
            })
            .collect();
        json["light_types_mask"] = plan.light_types_mask().into();
        println!("{}", serde_json::to_string_pretty(&json)?);
    } else {
        println!("scene       {}", scene.source);
        println!("{plan}");
        for (i, a) in scene.animations().iter().enumerate() {
            let drives: Vec<String> = scene
                .animation_drives(i)
                .iter()
                .zip(["node", "material", "light", "camera"])
                .filter(|(n, _)| **n > 0)
                .map(|(n, what)| format!("{n} {what}{}", if *n == 1 { "" } else { "s" }))
                .collect();
            println!(
                "{}{i}: '{}', {:.3} s{}",
                if i == 0 {
                    "animations  "
                } else {
                    "            "
                },
                a.name,
                a.duration,
                if drives.is_empty() {
                    String::new()
                } else {
                    format!(", drives {}", drives.join(", "))
                }
            );
        }
    }
    Ok(())
}
