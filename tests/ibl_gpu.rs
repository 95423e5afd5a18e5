//! Environment lighting on lavapipe (validation on), against the CPU ground truth of
//! `weft::env::quadrature` (quadrature over every pixel of the map, f64, none of the GPU's
//! approximations):
//! - white furnace: a uniform environment of radiance 1 on white dielectrics, white metals and
//!   the fabric, at every IBL level;
//! - a real HDR (Poly Haven "Lebombo", CC0, tests/data/env/) on the glTF spheres and the default
//!   cloth: relative error and FLIP per IBL level;
//! - the environment's rotation turns the lighting (and nothing else).

mod common;

use std::sync::Arc;

use glam::Mat4;
use weft::env::quadrature::EnvQuadrature;
use weft::env::{EnvLighting, Environment, IblLevel};
use weft::reference::shading::Surface;
use weft::render::gpu::FrameData;
use weft::render::{GBufferReadback, RenderOptions, Renderer};
use weft::scene::{self, Scene};

const W: u32 = 96;
const H: u32 = 54;

fn lebombo() -> Environment {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/env/lebombo_1k.hdr");
    Environment::load(&path).expect("tests/data/env/lebombo_1k.hdr")
}

fn spheres() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/spheres.glb");
    let mut s = scene::load(&path).expect("spheres scene");
    s.lights.clear();
    s
}

fn cloth() -> Scene {
    let mut s = scene::default_scene();
    s.lights.clear();
    s
}

fn options(env: &Arc<Environment>, level: IblLevel, rotation: f32) -> RenderOptions {
    let mut e = EnvLighting::new(env.clone());
    e.level = level;
    e.rotation = rotation;
    RenderOptions {
        width: W,
        height: H,
        environment: Some(e),
        ..Default::default()
    }
}

/// The surface at each covered pixel of the G-buffer (index, surface), and the eye.
fn surfaces(
    g: &GBufferReadback,
    scene: &Scene,
    o: &RenderOptions,
) -> (Vec<(usize, Surface)>, [f32; 3]) {
    let camera = scene.camera(o.camera).unwrap();
    let frame = FrameData::new(&camera, o.width, o.height);
    let inv = Mat4::from_cols_array_2d(&frame.inv_view_proj);
    let mut out = Vec::new();
    for i in 0..(W * H) as usize {
        if let Some(mut s) = common::gbuffer_surface(g, scene, inv, (W, H), i) {
            // Environment light only: the reference adds no emission.
            s.emissive = [0.0; 3];
            out.push((i, s));
        }
    }
    (out, [frame.eye[0], frame.eye[1], frame.eye[2]])
}

fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

#[test]
fn white_furnace() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let env = Arc::new(Environment::uniform([1.0; 3]));
    let q = EnvQuadrature::new(&env, 0.0, 1.0, 1);
    // Spheres with every material white: dielectric (front row) and metal with F0 = 1 (back).
    let mut scene = spheres();
    for m in scene.materials.iter_mut().skip(1) {
        m.base_color = [1.0; 4];
    }
    let cloth = cloth();
    for level in [
        IblLevel::Approx,
        IblLevel::Fis(16),
        IblLevel::MonteCarlo(64),
    ] {
        let o = options(&env, level, 0.0);
        let frame = renderer.render(&scene, &o).expect("render");
        let g = renderer.read_gbuffer().unwrap();
        let (surf, eye) = surfaces(&g, &scene, &o);
        let (mut worst_dielectric, mut metal_lo, mut metal_hi) = (0f64, f64::MAX, 0f64);
        let (mut metal_sum, mut metal_ref, mut metal_err, mut metal_n) = (0f64, 0f64, 0f64, 0);
        let (mut dielectric_err, mut dielectric_n) = (0f64, 0usize);
        for (i, s) in &surf {
            let material = g.surface[i * 4 + 1].round() as usize;
            if material == 0 {
                continue; // the floor
            }
            let out = frame.hdr[i * 4 + 1] as f64;
            if s.metallic < 0.5 {
                worst_dielectric = worst_dielectric.max((out - 1.0).abs());
                dielectric_err += (out - 1.0).abs();
                dielectric_n += 1;
            } else {
                metal_lo = metal_lo.min(out);
                metal_hi = metal_hi.max(out);
                if s.roughness > 0.2 {
                    let want = q.reflected(s, eye)[1];
                    metal_sum += out;
                    metal_ref += want;
                    metal_err += (out - want).abs();
                    metal_n += 1;
                }
            }
        }
        let metal_rel = metal_err / metal_ref;
        println!(
            "{}: white dielectric max |L - 1| = {worst_dielectric:.4}, mean {:.4}; white metal L in [{metal_lo:.3}, {metal_hi:.3}], mean {:.3} (CPU {:.3}, mean |GPU - CPU|/CPU {metal_rel:.4}, roughness > 0.2)",
            level.name(),
            dielectric_err / dielectric_n as f64,
            metal_sum / metal_n as f64,
            metal_ref / metal_n as f64
        );
        // Dielectric: the split sum gives diffuse·(1 - F0·A - B) + F0·A + B with white diffuse
        // and a uniform environment, exactly 1, up to f16 storage of the cubes, the DFG table and
        // the HDR target (2^-11 each). Monte Carlo with 64 samples is noisy per pixel (GGX
        // samples of a rough lobe weigh up to several times 1): its mean error over the spheres
        // is bounded instead (measured in the note; 0.03 is about 3x it).
        if level == IblLevel::MonteCarlo(64) {
            let mean = dielectric_err / dielectric_n as f64;
            assert!(mean <= 0.03, "{}: mean {mean}", level.name());
        } else {
            assert!(
                worst_dielectric <= 0.01,
                "{}: {worst_dielectric}",
                level.name()
            );
        }
        // Metal F0 = 1: the single-scattering albedo of GGX is A + B, 1 when smooth and down to
        // ~0.6 when rough at grazing view (issue 28: the glTF default material, a rough white
        // metal, was 0.88 EV darker than a path tracer); the energy compensation
        // 1 + F0·(1/Ess - 1) restores the multiply scattered light, so a white metal reflects 1
        // at every roughness and angle. The split sum is exact then but for f16 storage (the
        // same table gives Ess and A + B); measured within 0.003 of 1 at every pixel of every
        // roughness, bound 0.01. Monte Carlo with 64 GGX samples is noisy where the lobe is
        // wide (a few %): its mean over the metals is bounded below instead.
        if level != IblLevel::MonteCarlo(64) {
            assert!(
                metal_hi < 1.01 && metal_lo > 0.99,
                "{}: white metal in [{metal_lo}, {metal_hi}], not 1 at every roughness",
                level.name()
            );
        }
        let metal_bound = if level == IblLevel::MonteCarlo(64) {
            0.05
        } else {
            0.02
        };
        assert!(
            metal_rel < metal_bound,
            "{}: metal {metal_rel}",
            level.name()
        );

        // Fabric: the CPU quadrature of the same BRDF under the same environment is its
        // directional albedo at each pixel.
        let o = options(&env, level, 0.0);
        let frame = renderer.render(&cloth, &o).expect("render");
        let g = renderer.read_gbuffer().unwrap();
        let (surf, eye) = surfaces(&g, &cloth, &o);
        let (mut sum_err, mut sum_ref, mut n) = (0f64, 0f64, 0usize);
        for (i, s) in surf.iter().filter(|(_, s)| s.fabric.is_some()).step_by(7) {
            let want = luminance(q.reflected(s, eye));
            let got = luminance([0, 1, 2].map(|c| frame.hdr[i * 4 + c] as f64));
            sum_err += (got - want).abs();
            sum_ref += want;
            n += 1;
        }
        let rel = sum_err / sum_ref;
        println!(
            "{}: fabric furnace, {n} pixels, mean |GPU - CPU| / mean CPU = {rel:.4}",
            level.name()
        );
        // Diffuse: the irradiance of a uniform environment is exact. Specular: approx and fis:16
        // take the lobes' albedo from the exact table (measured 0.0040 both; approx was 0.12
        // while it took Schlick's Fresnel at n·v), mc:64 estimates it by sampling (0.0061).
        // Bound ~1.3x-1.6x the measured.
        let bound = 0.01;
        assert!(n > 50 && rel < bound, "{}: {rel}", level.name());
    }
}

/// Every fabric parameter set under a uniform white environment against the CPU quadrature of the
/// same BRDF (its directional albedo): the environment path must keep every term the lamps keep.
/// Issue 31 found an `rs = 0` fabric 21-23 % too dark under the environment at every level (an
/// early exit dropped its Fresnel lobe, which is `(1 - c)^5`, not 0): the `rs = 0` sets here would
/// have caught it.
#[test]
fn fabric_furnace_every_parameter_set() {
    use weft::fabric::{FabricParams, WeavePattern};
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let env = Arc::new(Environment::uniform([1.0; 3]));
    let q = EnvQuadrature::new(&env, 0.0, 1.0, 1);
    let base = FabricParams::default();
    let sets: Vec<(&str, FabricParams)> = vec![
        ("default", base.clone()),
        (
            "rs 0",
            FabricParams {
                rs: 0.0,
                ..base.clone()
            },
        ),
        (
            "rs 0, coupled diffuse",
            FabricParams {
                rs: 0.0,
                coupled_diffuse: true,
                ..base.clone()
            },
        ),
        (
            "rs 0.5",
            FabricParams {
                rs: 0.5,
                ..base.clone()
            },
        ),
        // Lobes only (black threads): all the light is the specular lobes', so dropping them is
        // a 100 % error, not the few % it is under a white diffuse.
        (
            "rs 0, lobes only",
            FabricParams {
                rs: 0.0,
                rd_warp: [0.0; 3],
                rd_weft: [0.0; 3],
                ..base.clone()
            },
        ),
        (
            "rs 0.04, lobes only",
            FabricParams {
                rd_warp: [0.0; 3],
                rd_weft: [0.0; 3],
                ..base.clone()
            },
        ),
        (
            "no gaps, no shadowing",
            FabricParams {
                gap: 0.0,
                shadow_strength: 0.0,
                ..base.clone()
            },
        ),
        (
            "wide lobes, coloured",
            FabricParams {
                e_along: 20.0,
                e_across: 2.0,
                rd_warp: [0.8, 0.2, 0.1],
                rd_weft: [0.1, 0.3, 0.9],
                ..base.clone()
            },
        ),
        (
            "satin, narrow lobes",
            FabricParams {
                pattern: WeavePattern::satin(),
                e_along: 2000.0,
                e_across: 40.0,
                ..base.clone()
            },
        ),
    ];
    let mut failures = Vec::new();
    for (name, params) in &sets {
        let mut cloth = cloth();
        for m in cloth.materials.iter_mut().filter(|m| m.fabric.is_some()) {
            m.fabric = Some(params.clone());
        }
        for level in [
            IblLevel::Approx,
            IblLevel::Fis(16),
            IblLevel::MonteCarlo(64),
        ] {
            let o = options(&env, level, 0.0);
            let frame = renderer.render(&cloth, &o).expect("render");
            let g = renderer.read_gbuffer().unwrap();
            let (surf, eye) = surfaces(&g, &cloth, &o);
            let (mut sum_err, mut sum_got, mut sum_ref, mut n) = (0f64, 0f64, 0f64, 0usize);
            for (i, s) in surf.iter().filter(|(_, s)| s.fabric.is_some()).step_by(5) {
                let want = luminance(q.reflected(s, eye));
                let got = luminance([0, 1, 2].map(|c| frame.hdr[i * 4 + c] as f64));
                assert!(got.is_finite(), "{name}, {}: not finite", level.name());
                sum_err += (got - want).abs();
                sum_got += got;
                sum_ref += want;
                n += 1;
            }
            let rel = sum_err / sum_ref;
            let bias = sum_got / sum_ref - 1.0;
            println!(
                "{name:>24}, {:>6}: {n} pixels, mean |GPU - CPU| / mean CPU = {rel:.4}, mean bias {bias:+.4}",
                level.name()
            );
            // The bounds of `white_furnace` (0.16 approx, 0.03 sampled: ~1.3x the default
            // cloth's measured error), and the mean bias within them too.
            //
            // Lobes only (black threads), measured on lavapipe: rs 0 approx and fis:16 0.041
            // (bias -0.031), mc:64 0.058 (-0.042); rs 0.04 approx and fis:16 0.012, mc:64 0.023.
            // approx and fis take each lobe's albedo from the exact table (session 23) and are
            // left with its interpolation and this coarse map's quadrature; mc:64 is few samples
            // of a peaked integrand. Before the table approx took a lobe's albedo as Schlick's
            // Fresnel at n·v (1.21, bias +1.17, at rs 0; 0.52 at rs 0.04) and fis:16 its
            // samples' own estimate (0.19 and 0.080): bound 0.06 catches a return to either.
            // Bounds ~1.3x-1.5x the measured; and every level's mean bias above -0.5, which
            // dropping the lobes (-1.0, as the early exit did) cannot pass.
            //
            // The other sets, approx and fis:16: 0.0007 to 0.0078 (satin's narrow lobes), bound
            // 0.012 (before the table: 0.16 approx, 0.03 fis); mc:64 up to 0.0079, bound 0.03.
            let lobes_only = params.rd_warp == [0.0; 3] && params.rd_weft == [0.0; 3];
            let ok = if lobes_only {
                let bound = match level {
                    IblLevel::MonteCarlo(_) => 0.09,
                    _ => 0.06,
                };
                bias > -0.5 && rel < bound
            } else {
                let bound = match level {
                    IblLevel::MonteCarlo(_) => 0.03,
                    _ => 0.012,
                };
                rel < bound && bias.abs() < bound
            };
            if !(n > 50 && ok) {
                failures.push(format!(
                    "{name}, {}: {rel:.4} (bias {bias:+.4})",
                    level.name()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "fabric furnace failures: {failures:?}");
}

#[test]
fn real_hdr_matches_the_cpu_ground_truth() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let env = Arc::new(lebombo());
    let rotation: f32 = std::env::var("WEFT_ROT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(60.0);
    let q = EnvQuadrature::new(&env, rotation, 1.0, 1);
    let q2 = EnvQuadrature::new(&env, rotation, 1.0, 2);
    let mut flips = Vec::new();
    let mut failures = Vec::new();
    let mut errors = Vec::new();
    for (name, scene) in [("spheres", spheres()), ("cloth", cloth())] {
        let levels = [
            IblLevel::Approx,
            IblLevel::Fis(4),
            IblLevel::Fis(8),
            IblLevel::Fis(16),
            IblLevel::Fis(64),
            IblLevel::MonteCarlo(512),
        ];
        let mut reference: Option<Vec<(usize, [f64; 3])>> = None;
        // Every covered pixel's reference, for FLIP over the whole image (quadrature over 2 x 2
        // map pixels merged: 0.7°, finer than any lobe of these scenes but the steel ball's).
        let mut full: Option<Vec<Option<[f64; 3]>>> = None;
        for level in levels {
            let o = options(&env, level, rotation);
            let frame = renderer.render(&scene, &o).expect("render");
            let refs = reference.get_or_insert_with(|| {
                let g = renderer.read_gbuffer().unwrap();
                let (surf, eye) = surfaces(&g, &scene, &o);
                surf.iter()
                    .filter(|(_, s)| name != "cloth" || s.fabric.is_some())
                    // Very smooth spheres are sharper than the map's pixels can resolve.
                    .filter(|(_, s)| s.fabric.is_some() || s.roughness > 0.2)
                    .step_by(5)
                    .map(|(i, s)| (*i, q.reflected(s, eye)))
                    .collect()
            });
            let (mut sum_err, mut sum_ref) = (0f64, 0f64);
            let mut by_material = std::collections::BTreeMap::<usize, (f64, f64, f64)>::new();
            let g = renderer.read_gbuffer().unwrap();
            for (i, want) in refs.iter() {
                let got = [0, 1, 2].map(|c| frame.hdr[i * 4 + c] as f64);
                sum_err += (luminance(got) - luminance(*want)).abs();
                sum_ref += luminance(*want);
                let m = g.surface[i * 4 + 1].round() as usize;
                let e = by_material.entry(m).or_default();
                e.0 += luminance(got);
                e.1 += luminance(*want);
                e.2 += 1.0;
            }
            if std::env::var("WEFT_IBL_DEBUG").is_ok() {
                for (m, (g, w, n)) in &by_material {
                    println!(
                        "  material {m}: GPU mean {:.4}, CPU mean {:.4} ({n} px)",
                        g / n,
                        w / n
                    );
                }
            }
            let rel = sum_err / sum_ref;
            let full = full.get_or_insert_with(|| {
                let (surf, eye) = surfaces(&g, &scene, &o);
                let mut out = vec![None; (W * H) as usize];
                for (i, s) in &surf {
                    out[*i] = Some(q2.reflected(s, eye));
                }
                out
            });
            let ldr = |c: [f32; 3]| {
                weft::reference::shading::tonemap(c, 1.0).map(weft::reference::shading::srgb_encode)
            };
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for (i, r) in full.iter().enumerate() {
                let got = [0, 1, 2].map(|c| frame.hdr[i * 4 + c]);
                let want = r.map(|r| r.map(|x| x as f32)).unwrap_or(got);
                a.extend(ldr(want));
                b.extend(ldr(got));
            }
            let flip = common::flip_mean(W, H, &a, &b);
            println!(
                "{name} {}: {} pixels, mean relative error {rel:.4}; FLIP mean over the image {flip:.4}",
                level.name(),
                refs.len()
            );
            flips.push(flip);
            // Bounds, each about 1.3x the worst of the two scenes as measured on lavapipe (the
            // table is in docs/fabric-model.md §6). What they bound: the irradiance (the specular
            // cube's roughness-1 level, an exact sum since 2026-12-06), the split sum of the glTF
            // spheres (3.42 % at every
            // level: the level changes only the fabric), and for the cloth the estimator of each
            // level: approx takes one look-up per lobe (16.1 %); FIS, its samples pooled over
            // 3 x 3 pixels and more of them at grazing views, 3.42 %, 3.56 %, 2.09 %, 0.56 % at
            // 4, 8, 16, 64 (2026-12-06; 3.47, 3.65, 2.19, 0.68 % with the sampled irradiance
            // level; it was 16.4 %, 7.6 %, 5.7 %, 2.3 % before the exact lobe
            // albedo and the pooling, when these bounds were 0.215, 0.10, 0.075 and 0.05), so
            // every FIS level is bounded by the spheres' split sum; Monte Carlo with 512 samples
            // is unbiased, its noise averages to ~1 %. The convergence is asserted below.
            let bound = match level {
                IblLevel::Approx => 0.21,
                IblLevel::Fis(8) => 0.048,
                IblLevel::Fis(_) => 0.046,
                IblLevel::MonteCarlo(_) => 0.016,
            };
            errors.push(rel);
            if rel >= bound {
                failures.push(format!("{name} {}: {rel} >= {bound}", level.name()));
            }
        }
    }
    // FLIP over the whole 96 x 54 image (sRGB after the same tone curve), measured on lavapipe:
    // spheres 0.074 at every split-sum level (the smooth balls, which the 0.7° reference blurs,
    // and the split sum), 0.025 at mc:512; cloth 0.049, 0.044, 0.039, 0.039, 0.036 (approx, fis:4,
    // 8, 16, 64), 0.0098 (mc:512). Bounds ~1.3x those; what bounds them is as for the relative
    // error above.
    let flip_bounds = [
        0.095, 0.095, 0.095, 0.095, 0.095, 0.035, // spheres
        0.064, 0.057, 0.051, 0.051, 0.047, 0.013, // cloth
    ];
    for (k, (f, b)) in flips.iter().zip(flip_bounds).enumerate() {
        if *f > b {
            failures.push(format!("FLIP of case {k}: {f} > {b}"));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
    // On the cloth, FIS converges to the Monte Carlo answer: approx is the farthest, each 4x the
    // samples closer (fis:4, 16, 64). fis:8 lies between approx and
    // fis:16; against fis:4 it is not ordered on this 140-pixel image (3.56 % against 3.42 %,
    // FLIP 0.0336 against 0.0342: the two sets of pooled samples differ by less than the image's
    // noise), while `weft bench --ibl` at 480x270 has fis:8 closer on every view (close up 3.7 %
    // against 5.1 %).
    let cloth = &errors[errors.len() - 6..];
    let [approx, fis4, fis8, fis16, fis64, mc] = [0, 1, 2, 3, 4, 5].map(|i| cloth[i]);
    // Monte Carlo is closer than fis:16; against fis:64 it is not ordered since the irradiance
    // is an exact sum (2026-12-06): fis:64's remaining bias, 0.56 %, is below mc:512's noise,
    // 0.62 %.
    assert!(
        approx > fis4.max(fis8) && fis16 < fis4.min(fis8) && fis64 < fis16 && mc < fis16,
        "cloth errors do not shrink (approx, fis:4, 8, 16, 64, mc:512): {cloth:?}"
    );
}

#[test]
fn rotating_the_environment_turns_the_light() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let env = Arc::new(lebombo());
    let scene = spheres();
    let a = renderer
        .render(&scene, &options(&env, IblLevel::Fis(16), 0.0))
        .unwrap();
    let b = renderer
        .render(&scene, &options(&env, IblLevel::Fis(16), 90.0))
        .unwrap();
    let c = renderer
        .render(&scene, &options(&env, IblLevel::Fis(16), 360.0))
        .unwrap();
    let diff = |x: &[f32], y: &[f32]| -> f64 {
        x.iter()
            .zip(y)
            .map(|(p, q)| (p - q).abs() as f64)
            .sum::<f64>()
            / x.len() as f64
    };
    assert!(
        diff(&a.hdr, &b.hdr) > 1e-3,
        "a quarter turn changes the image"
    );
    assert!(
        diff(&a.hdr, &c.hdr) < 1e-4,
        "a full turn does not: {}",
        diff(&a.hdr, &c.hdr)
    );
    for f in [&a, &b, &c] {
        assert!(f.hdr.iter().all(|v| v.is_finite()));
    }
}
