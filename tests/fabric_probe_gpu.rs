//! The GLSL twins against the CPU reference, on a Vulkan device (lavapipe by default, or
//! WEFT_DEVICE), with validation on: `glsl/fabric_probe.comp` on every hard case of the model
//! page's §5 plus random inputs, under `ProbeBound::GPU`; `glsl/weave.comp` texel by texel against
//! `weave_texels_cpu` under `WEAVE_TEXEL_TOLERANCE`.

mod common;

use weft::fabric::{
    weave_level0_size, weave_level_size, weave_mip_count, weave_texels_cpu, FabricParams,
    WeavePattern, WEAVE_TEXEL_TOLERANCE,
};
use weft::reference::probe::{
    probe_check, probe_cpu_f64, probe_inputs, probe_worst_ratio, ProbeBound, ProbeInput,
    ProbeOutput,
};
use weft::vk::shaders;

/// Runs fabric_probe.comp on `inputs`.
fn run_probe(ctx: &weft::vk::Context, inputs: &[ProbeInput]) -> Vec<ProbeOutput> {
    let size = std::mem::size_of::<ProbeOutput>();
    let bytes = common::run_probe_shader(ctx, &shaders::FABRIC_PROBE_COMP, inputs, size);
    (0..inputs.len())
        .map(|i| ProbeOutput::from_bytes(&bytes[i * size..(i + 1) * size]))
        .collect()
}

#[test]
fn probe_matches_the_cpu_reference() {
    let ctx = common::context();
    let cases = probe_inputs(0xfab, 20_000);
    let inputs: Vec<ProbeInput> = cases.iter().map(|c| c.input).collect();
    let got = run_probe(&ctx, &inputs);
    let mut failures = Vec::new();
    let mut worst = (0.0, "", String::new());
    for (c, g) in cases.iter().zip(&got) {
        let reference = probe_cpu_f64(&c.input);
        let msgs = probe_check(&c.input, &reference, g, &ProbeBound::GPU);
        if !msgs.is_empty() {
            failures.push(format!("{}:\n  {}", c.name, msgs.join("\n  ")));
        }
        let (r, name) = probe_worst_ratio(&c.input, &reference, g, &ProbeBound::GPU);
        if r > worst.0 {
            worst = (r, name, c.name.clone());
        }
    }
    println!(
        "probe on {}: {} inputs, worst |gpu - f64|/tolerance = {:.3} ({} of {})",
        ctx.info().name,
        cases.len(),
        worst.0,
        worst.1,
        worst.2
    );
    assert!(
        failures.is_empty(),
        "{} of {} probe inputs out of bound:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

#[test]
fn weave_texture_matches_the_cpu_texels() {
    let renderer = weft::render::Renderer::new(common::context()).unwrap();
    for pattern in [
        WeavePattern::plain(),
        WeavePattern::twill(),
        WeavePattern::satin(),
        WeavePattern::from_rows(&["--|", "|-|"]).unwrap(),
    ] {
        let p = FabricParams {
            pattern,
            gap: 0.004,
            shadow_width: 0.4,
            ..Default::default()
        };
        let image = renderer.build_weave(&p).unwrap();
        let level0 = weave_level0_size(&pattern);
        let mut worst = 0.0f32;
        for level in 0..weave_mip_count(level0) {
            let (w, h) = weave_level_size(level0, level);
            let gpu = renderer.read_weave(&image, level).unwrap();
            let cpu = weave_texels_cpu(&p.weave_push(w, h));
            // A readback buffer has at least 16 bytes, so a 1×1 level comes back with padding.
            assert!(gpu.len() >= cpu.len() * 4);
            for (i, c) in cpu.iter().enumerate() {
                for k in 0..4 {
                    let d = (gpu[4 * i + k] - c[k]).abs();
                    worst = worst.max(d);
                    assert!(
                        d <= WEAVE_TEXEL_TOLERANCE,
                        "{} level {level} texel ({}, {}) channel {k}: gpu {} cpu {}",
                        pattern.name(),
                        i as u32 % w,
                        i as u32 / w,
                        gpu[4 * i + k],
                        c[k]
                    );
                }
            }
        }
        println!(
            "weave texture {}: worst |gpu - cpu| = {worst:e}",
            pattern.name()
        );
        // The RGBA8 copy: every texel of every level the RGBA16F value rounded to the nearest
        // 1/255 (exactly: so no bias but the values' own), where a converting blit rounding
        // toward zero costs up to a whole step (lavapipe's did: the far field 0.28 % dark).
        let image8 = renderer.weave_rgba8(&image).unwrap();
        for level in 0..weave_mip_count(level0) {
            let (w, h) = weave_level_size(level0, level);
            let f = renderer.read_weave(&image, level).unwrap();
            let b = renderer.read_weave_rgba8(&image8, level).unwrap();
            let n = (w * h * 4) as usize;
            let mut bias = 0.0f64;
            for i in 0..n {
                let want = (f[i].clamp(0.0, 1.0) * 255.0).round() as u8;
                assert_eq!(
                    b[i],
                    want,
                    "{} level {level} component {i}: {} from {}",
                    pattern.name(),
                    b[i],
                    f[i]
                );
                bias += (b[i] as f64 / 255.0 - f[i] as f64) / n as f64;
            }
            if level + 1 == weave_mip_count(level0) {
                println!("  rgba8, last level: mean error {bias:e} (half a step is 1.96e-3)");
            }
        }
    }
    renderer.context().check_validation().unwrap();
}
