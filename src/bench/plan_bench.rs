//! `weft bench --plan`: what the plan's skipping saves. Each row renders one scene twice in the
//! same run, frames interleaved (so a change in the machine's load falls on both alike): as the
//! plan decides, and with the skipped effect forced on ([`Force`]). And the growth from 4 to 256
//! point lights of limited range, which per-pixel range culling keeps cheap.

use std::fmt::Write;

use crate::render::{Force, Frame, RenderOptions, Renderer};
use crate::scene::{LightKind, Scene};

/// One scene, planned against forced.
#[derive(Clone, Debug)]
pub struct SkipRow {
    pub scene: String,
    pub skipped: String,
    /// Median GPU time of the frame's passes (all but readback), ms.
    pub planned_ms: f64,
    pub forced_ms: f64,
}

/// One light count.
#[derive(Clone, Debug)]
pub struct LightsRow {
    pub lights: u32,
    pub range: f32,
    pub frame_ms: f64,
    pub lighting_ms: f64,
}

pub struct PlanReport {
    pub size: (u32, u32),
    pub frames: u32,
    pub skips: Vec<SkipRow>,
    pub lights: Vec<LightsRow>,
}

/// The summed GPU time (wall time without timestamps) of every pass but the readback.
fn frame_ms(frame: &Frame) -> f64 {
    frame
        .timings
        .iter()
        .filter(|t| t.name != "readback" && t.name != "submission")
        .map(|t| t.gpu_ms.or(t.wall_ms).unwrap_or(0.0))
        .sum()
}

/// Medians of `frames` interleaved rounds over the option sets (after one warm-up round each);
/// per set: (frame ms, lighting ms).
fn interleaved(
    renderer: &mut Renderer,
    scene: &Scene,
    sets: &[RenderOptions],
    frames: u32,
) -> crate::Result<Vec<(f64, f64)>> {
    let gpu = renderer.upload(scene)?;
    for o in sets {
        renderer.render_frame(scene, &gpu, o)?;
    }
    let mut t: Vec<(Vec<f64>, Vec<f64>)> = sets.iter().map(|_| (Vec::new(), Vec::new())).collect();
    for _ in 0..frames.max(1) {
        for (i, o) in sets.iter().enumerate() {
            let f = renderer.render_frame(scene, &gpu, o)?;
            t[i].0.push(frame_ms(&f));
            t[i].1.push(super::pass_ms(&f, "lighting"));
        }
    }
    Ok(t.into_iter()
        .map(|(f, l)| (super::median(f), super::median(l)))
        .collect())
}

/// The default scene with its steel ball made of clear, double-sided glass: a transmissive draw,
/// opaque in the transparent pass with both faces drawn (what the pass's face order is about).
pub fn default_with_glass_ball() -> Scene {
    let mut glass = crate::scene::default_scene();
    for m in &mut glass.materials {
        if m.metallic > 0.5 && m.fabric.is_none() {
            m.metallic = 0.0;
            m.roughness = 0.1;
            m.double_sided = true;
            m.transmission = Some(crate::scene::Transmission {
                factor: 1.0,
                texture: None,
                thickness: 0.0,
                thickness_texture: None,
                attenuation_color: [1.0; 3],
                attenuation_distance: None,
                dispersion: 0.0,
            });
        }
    }
    glass
}

pub fn run(renderer: &mut Renderer, size: (u32, u32), frames: u32) -> crate::Result<PlanReport> {
    let base = RenderOptions {
        width: size.0,
        height: size.1,
        ..crate::bench::timed_options()
    };
    // In the binary: `weft bench` works wherever weft is installed, not only in its source tree.
    let shadows = crate::scene::load_slice(
        include_bytes!("../../assets/scenes/shadows.glb"),
        "assets/scenes/shadows.glb (built in)",
        None,
    )?;
    let mut no_receivers = shadows.clone();
    for d in &mut no_receivers.draws {
        d.receive_shadows = false;
    }
    let mut directional_only = crate::scene::default_scene();
    directional_only
        .lights
        .retain(|l| l.kind == LightKind::Directional);
    let default = crate::scene::default_scene();
    let local = super::with_local_point_lights(&default, 256, 0.6);

    let glass = default_with_glass_ball();
    // As `weft render` lights it (the studio at fis:8): where the other kinds' code would cost
    // most.
    let studio = RenderOptions {
        environment: Some(crate::env::EnvLighting::new(std::sync::Arc::new(
            crate::env::Environment::studio(),
        ))),
        ..base.clone()
    };
    // FXAA as `weft render` runs it (its edge search only on the blocks with an edge), and the
    // occlusion pass as it runs under the studio (its estimates and blur where a surface is).
    let fxaa = RenderOptions {
        antialias: crate::render::Antialias::Fxaa,
        ..base.clone()
    };
    let gtao = RenderOptions {
        occlusion: crate::render::Occlusion::DEFAULT,
        ..studio.clone()
    };
    // The frame `weft render` renders by default (the studio, GTAO, FXAA, no HDR read back):
    // its lighting pass applies the tone curve, and the tonemap pass does not run.
    let render_default = RenderOptions {
        antialias: crate::render::Antialias::Fxaa,
        read_hdr: false,
        ..gtao.clone()
    };
    let cases: [(&str, &str, &Scene, &RenderOptions, Force); 10] = [
        (
            "default, as weft render renders it",
            "tonemap pass (the curve in the lighting pass)",
            &default,
            &render_default,
            Force {
                tonemap_pass: true,
                ..Force::NONE
            },
        ),
        (
            "default, studio environment",
            "other kinds' code, unused texture slots",
            &default,
            &studio,
            Force {
                material_kinds: true,
                ..Force::NONE
            },
        ),
        (
            "default, --aa fxaa",
            "FXAA's edge search off the edges",
            &default,
            &fxaa,
            Force {
                fxaa_everywhere: true,
                ..Force::NONE
            },
        ),
        (
            "default, studio, --occlusion gtao",
            "occlusion estimates where nothing is",
            &default,
            &gtao,
            Force {
                occlusion_everywhere: true,
                ..Force::NONE
            },
        ),
        (
            "default",
            "hidden G-buffer fragments (depth pre-pass)",
            &default,
            &base,
            Force {
                no_depth_prepass: true,
                ..Force::NONE
            },
        ),
        (
            "default, steel ball as 2-sided glass",
            "glass back faces behind its front faces",
            &glass,
            &base,
            Force {
                back_faces_first: true,
                ..Force::NONE
            },
        ),
        (
            "shadows.glb, nothing receives",
            "shadow pass (2 maps) and shadow sampling",
            &no_receivers,
            &base,
            Force {
                shadows: true,
                ..Force::NONE
            },
        ),
        (
            "default, directional lights only",
            "point and spot light code",
            &directional_only,
            &base,
            Force {
                light_types: true,
                ..Force::NONE
            },
        ),
        (
            "default + 256 point lights, range 0.6",
            "lights out of range, per pixel",
            &local,
            &base,
            Force {
                no_range_culling: true,
                ..Force::NONE
            },
        ),
        (
            "default (no light asks for shadows)",
            "all of the above",
            &default,
            &base,
            Force::ALL,
        ),
    ];
    let mut skips = Vec::new();
    for (name, skipped, scene, options, force) in cases {
        let forced = RenderOptions {
            force,
            ..options.clone()
        };
        let m = interleaved(renderer, scene, &[options.clone(), forced], frames)?;
        skips.push(SkipRow {
            scene: name.into(),
            skipped: skipped.into(),
            planned_ms: m[0].0,
            forced_ms: m[1].0,
        });
    }

    let mut lights = Vec::new();
    for n in [4, 256] {
        let scene = super::with_local_point_lights(&default, n, 0.6);
        let m = interleaved(renderer, &scene, std::slice::from_ref(&base), frames)?;
        lights.push(LightsRow {
            lights: n,
            range: 0.6,
            frame_ms: m[0].0,
            lighting_ms: m[0].1,
        });
    }
    Ok(PlanReport {
        size,
        frames,
        skips,
        lights,
    })
}

impl PlanReport {
    pub fn table(&self) -> String {
        let mut t = String::new();
        let (w, h) = self.size;
        let _ = writeln!(
            t,
            "what the plan skips, {w}x{h}, medians of {} interleaved frames (GPU ms, all passes):",
            self.frames
        );
        let _ = writeln!(
            t,
            "{:<40} {:<44} {:>10} {:>10} {:>8}",
            "scene", "skipped by the plan", "planned", "forced", "saved"
        );
        for r in &self.skips {
            let _ = writeln!(
                t,
                "{:<40} {:<44} {:>10.2} {:>10.2} {:>7.0}%",
                r.scene,
                r.skipped,
                r.planned_ms,
                r.forced_ms,
                100.0 * (1.0 - r.planned_ms / r.forced_ms.max(1e-9))
            );
        }
        let _ = writeln!(t);
        let _ = writeln!(
            t,
            "point lights of limited range over the default scene, {w}x{h}:"
        );
        let _ = writeln!(
            t,
            "{:<8} {:>8} {:>10} {:>12} {:>14}",
            "lights", "range", "frame ms", "lighting ms", "frame / 4 lights"
        );
        let first = self.lights.first().map(|r| r.frame_ms).unwrap_or(1.0);
        for r in &self.lights {
            let _ = writeln!(
                t,
                "{:<8} {:>8.1} {:>10.2} {:>12.2} {:>13.2}x",
                r.lights,
                r.range,
                r.frame_ms,
                r.lighting_ms,
                r.frame_ms / first.max(1e-9)
            );
        }
        t
    }
}
