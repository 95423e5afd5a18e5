//! The environment light's estimators (`glsl/include/env_light.glsl`) and the shadow maps' PCF
//! (`glsl/include/shadows.glsl`) against their Rust twins (`weft::reference::env_light`), through
//! `glsl/env_probe.comp` on a Vulkan device (lavapipe by default, or WEFT_DEVICE) with
//! validation on. Both sides read the same closed-form stand-ins for the textures, so the
//! comparison is of the estimators' own arithmetic: the samples, their weights and mip levels, the
//! split sum's terms, the layering, the PCF's taps.
//!
//! Inputs: every level (approx, fis:1..32, mc:1..32 with random rotations), glTF surfaces with
//! and without sheen, anisotropy, iridescence, transmission, metals and dielectrics from mirror
//! to rough, fabrics from plain A–S exponents (1..1000, equal and 100:1) with rs from 0 to 0.5,
//! coupled and Lambert diffuse, sheets and not; views from grazing (n·v 0.02) to normal; shadow
//! records with and without PCF, orthographic and perspective, points inside, outside and behind
//! the map.
//!
//! The bound. Every estimator here is a sum of non-negative terms (radiance ≥ 0 times non-negative
//! weights), so an error relative to each term is relative to the sum: each output must lie within
//! `REL·|twin| + ABS` of the twin. `REL` = 2e-4 absorbs, per sample, the Vulkan precision of the
//! built-ins in the chain (each of pow, exp, log2, inversesqrt, division: ≤ 3 + 2|x| ulp, about
//! 1.6e-5 relative for a chain of ten; `pow(1 − v·h, 5)` and the A–S `hn^E` reach 1e-4 at
//! exponents near 1000, where ProbeBound::GPU's `x_rel` of 1e-5 per unit of the exponent's value
//! is what the fabric probe allows) and the twin's own f32 rounding (the same again);
//! `ABS` = 1e-5 covers the PCF's ramp (slope 8 over ndc computed with a 2.5-ulp division) and
//! values near 0. The exact outputs are exact: `pixel_random` (integer hash, 24-bit conversions)
//! bit for bit, `ibl_sample` to 2 ulp of 1 (the division i/n). Measured on lavapipe: see the
//! printed worst ratio (|gpu − twin| / bound); `a_real_change_is_outside_the_bound` shows the
//! bound is narrow enough to see an environment 0.1 % brighter.

mod common;

use weft::fabric::{FabricParams, GpuFabric, FLAG_SHEET};
use weft::records::GpuShadow;
use weft::reference::env_light::{
    env_probe_cpu, env_probe_eval, stand_in_compare, EnvLookup, EnvProbeInput, EnvProbeOutput,
    StandIn, ENV_PROBE_OUTPUT_NAMES,
};
use weft::reference::probe::XorShift;
use weft::vk::shaders;

const REL: f64 = 2e-4;
const ABS: f64 = 1e-7;
const ABS_PCF: f64 = 1e-5;

fn run(ctx: &weft::vk::Context, inputs: &[EnvProbeInput]) -> Vec<EnvProbeOutput> {
    let size = std::mem::size_of::<EnvProbeOutput>();
    let bytes = common::run_probe_shader(ctx, &shaders::ENV_PROBE_COMP, inputs, size);
    bytes
        .chunks_exact(size)
        .map(|c| *bytemuck::from_bytes::<EnvProbeOutput>(c))
        .collect()
}

fn unit(v: [f64; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [(v[0] / l) as f32, (v[1] / l) as f32, (v[2] / l) as f32]
}

fn v4(v: [f32; 3], w: f32) -> [f32; 4] {
    [v[0], v[1], v[2], w]
}

/// A direction about `n` (unit) with cosine `c` to it, at azimuth `phi` about a perpendicular.
fn about(n: [f64; 3], c: f64, phi: f64) -> [f64; 3] {
    let a = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let dot = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
    let t = unit([a[0] - dot * n[0], a[1] - dot * n[1], a[2] - dot * n[2]]).map(f64::from);
    let b = [
        n[1] * t[2] - n[2] * t[1],
        n[2] * t[0] - n[0] * t[2],
        n[0] * t[1] - n[1] * t[0],
    ];
    let s = (1.0 - c * c).max(0.0).sqrt();
    [0, 1, 2].map(|k| c * n[k] + s * (phi.cos() * t[k] + phi.sin() * b[k]))
}

/// A perspective or orthographic shadow record looking down −z from above the origin, its tile
/// at (0.25, 0.5) of size 0.25 in a 1024-texel atlas.
fn shadow(perspective: bool, radius: f32) -> GpuShadow {
    let m = if perspective {
        // x/(−z), y/(−z), reversed-Z depth near 0.1: z_ndc = 0.1/(−z) with w = −z.
        [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, -1.0],
            [0.0, 0.0, 0.1, 0.0],
        ]
    } else {
        [
            [0.5, 0.0, 0.0, 0.0],
            [0.0, 0.5, 0.0, 0.0],
            [0.0, 0.0, 0.1, 0.0],
            [0.0, 0.0, 0.5, 1.0],
        ]
    };
    GpuShadow {
        clip_from_world: m,
        tile: [0.25, 0.5, 0.25, 0.25],
        params: [0.01, perspective as u32 as f32, radius, 1.0 / 1024.0],
    }
}

fn inputs(seed: u64, count: usize) -> Vec<EnvProbeInput> {
    let mut rng = XorShift::new(seed);
    let mut out = Vec::with_capacity(count);
    for i in 0..count {
        let r = &mut rng;
        let n = unit(r.unit());
        let nf = n.map(f64::from);
        // n·v from grazing to normal.
        let nv = [0.02, 0.1, 0.5, 0.9, 1.0][i % 5] * r.range(0.9, 1.0);
        let v = unit(about(nf, nv, r.range(0.0, 6.28)));
        let t = unit(about(nf, 0.0, r.range(0.0, 6.28)));
        let roughness = [0.0, 0.05, 0.3, 0.6, 1.0][(i / 5) % 5] as f32;
        let metallic = [0.0, 1.0, 0.5][i % 3];
        let sheen = if i % 4 == 1 {
            [r.range(0.1, 1.0) as f32, r.range(0.0, 1.0) as f32, 0.3]
        } else {
            [0.0; 3]
        };
        let mode = [1u32, 2, 2, 3][i % 4];
        let samples = [1u32, 2, 4, 8, 16, 32][(i / 4) % 6];
        // The Monte Carlo truth evaluates gltf_brdf_cos at sampled directions: below roughness
        // 0.3 a rounding of n·h moves GGX's D by 4/α² ulp (4 % at roughness 0.05), which
        // pbr_probe_gpu bounds per input for gltf_brdf_cos itself; here mc takes rougher
        // surfaces, where the loop around it is what is measured.
        let roughness = if mode == 3 && roughness < 0.3 {
            roughness + 0.3
        } else {
            roughness
        };
        let e_along = r.log_range(1.0, 1000.0) as f32;
        let e_across = if i % 3 == 0 {
            e_along
        } else {
            r.log_range(1.0, 1000.0) as f32
        };
        let mut fabric: GpuFabric = FabricParams {
            rs: [0.0, 0.04, 0.2, 0.5][i % 4],
            coupled_diffuse: i % 2 == 0,
            ..Default::default()
        }
        .to_gpu();
        fabric.e_along = e_along;
        fabric.e_across = e_across;
        fabric.rd_warp = [0.8, 0.3, 0.1];
        fabric.rd_weft = [0.1, 0.5, 0.9];
        if i % 5 == 2 {
            fabric.flags |= FLAG_SHEET;
            fabric.transmission = 0.4;
        }
        let fn_ = unit(r.unit());
        let ft = unit(r.unit());
        let k2 = unit(about([0.0, 0.0, 1.0], nv, r.range(0.0, 6.28)));
        let c_warp = r.range(0.0, 1.0) as f32;
        let c_weft = (1.0 - c_warp) * r.range(0.0, 1.0) as f32;
        let pcf = [0.0f32, 1.0, 1.5][i % 3];
        // Points over the tile (inside), past its edge (outside: 1) and behind the light.
        let p = [
            r.range(-1.2, 1.2) as f32,
            r.range(-1.2, 1.2) as f32,
            -r.range(0.5, 3.0) as f32,
        ];
        out.push(EnvProbeInput {
            n: v4(n, r.range(0.0, 1.0) as f32),
            v: v4(
                v,
                if sheen[0] > 0.0 {
                    r.range(0.0, 0.6) as f32
                } else {
                    0.0
                },
            ),
            base_metallic: [
                r.range(0.0, 1.0) as f32,
                r.range(0.0, 1.0) as f32,
                r.range(0.0, 1.0) as f32,
                metallic,
            ],
            f0_specular: [0.04, 0.05, 0.06, [1.0, 0.5][i % 2]],
            sheen: v4(sheen, r.range(0.05, 1.0) as f32),
            t_anisotropy: v4(
                t,
                if i % 3 == 2 {
                    r.range(0.1, 1.0) as f32
                } else {
                    0.0
                },
            ),
            surface: [
                roughness,
                if i % 7 == 3 { 0.6 } else { 0.0 },
                r.range(0.3, 1.0) as f32,
                [256.0, 64.0][i % 2],
            ],
            film: [if i % 6 == 5 { 0.8 } else { 0.0 }, 1.3, 400.0, 0.0],
            bounce: [1.0, 0.9, 1.1, nv as f32],
            frame_t: v4(ft, if i % 2 == 0 { 1.0 } else { -1.0 }),
            frame_n: v4(fn_, r.range(0.0, 1.0) as f32),
            k2: v4(k2, 0.0),
            coverage: [c_warp, c_weft, 0.8 * c_warp, 0.7 * c_weft],
            rot: [
                r.range(0.0, 1.0) as f32,
                r.range(0.0, 1.0) as f32,
                r.range(0.0, 1.0) as f32,
                r.range(0.0, 1.0) as f32,
            ],
            mode: [
                mode,
                samples,
                (r.next_u64() % 4096) as u32,
                (r.next_u64() % 4096) as u32,
            ],
            fabric,
            shadow: shadow(i % 2 == 1, pcf),
            light_pos: [0.0, 0.0, 0.0, if i % 5 == 2 { 1.0 } else { 0.0 }],
            p: v4(p, 0.0),
            pn: v4(unit(r.unit()), 0.0),
            // The occluders' bounced light: none, then two colours.
            indirect: [
                0.3 * (i % 3) as f32,
                0.2 * (i % 3) as f32,
                0.05 * (i % 3) as f32,
                0.0,
            ],
        });
    }
    out
}

/// Hard cases: grazing views, the mirror (roughness 0), rs = 0 fabrics (their lobes under the
/// environment: issue 31 item 2), coverage all warp / all weft / none, huge and equal exponents.
fn hard() -> Vec<EnvProbeInput> {
    let mut out = Vec::new();
    let base = inputs(7, 1)[0];
    for (k, &(e_along, e_across, rs)) in [
        (1.0f32, 1.0f32, 0.0f32),
        (1000.0, 1000.0, 0.0),
        (1000.0, 10.0, 0.04),
        (10.0, 1000.0, 0.5),
        (200.0, 10.0, 0.04),
    ]
    .iter()
    .enumerate()
    {
        for &nv in &[0.02f64, 0.3, 1.0] {
            for (c, coverage) in [[1.0f32, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 1.0], [0.0; 4]]
                .iter()
                .enumerate()
            {
                for &(mode, samples) in &[(1u32, 1u32), (2, 8), (3, 16)] {
                    let mut inp = base;
                    inp.fabric.e_along = e_along;
                    inp.fabric.e_across = e_across;
                    inp.fabric.rs = rs;
                    inp.k2 = v4(unit(about([0.0, 0.0, 1.0], nv, 0.7 * k as f64)), 0.0);
                    inp.coverage = *coverage;
                    inp.mode = [mode, samples, c as u32, k as u32];
                    inp.surface[0] = [0.0, 1.0, 0.5][c];
                    let n = [inp.n[0] as f64, inp.n[1] as f64, inp.n[2] as f64];
                    inp.v = v4(unit(about(n, nv, 1.0)), 0.0);
                    out.push(inp);
                }
            }
        }
    }
    out
}

/// The direction error the bound allows the GPU before its arithmetic starts: ProbeBound::GPU's
/// `dir` (4e-6 per component: the Vulkan precision of `normalize` and the products that make a
/// direction, doubled).
const DIR: f64 = 4e-6;

/// See [`spread`]: a film's phase error as a relative error of its thickness.
const FILM_REL: f64 = 1e-4;

/// ProbeBound::GPU's `x_rel`: the relative error of the exponent's value in the A–S `hn^E`.
const X_REL: f64 = 1e-5;

/// How much each output moves when every direction of the input moves by [`DIR`] and the A–S
/// exponents by [`X_REL`] and a film's thickness by [`FILM_REL`]: twice the
/// largest change over eight random moves (twice: a sample of eight moves finds less than the
/// worst, and the GPU rounds both the directions it is given and those it derives) (each vector plus DIR times a random unit vector, renormalised
/// where it is a direction). Where an estimator is ill-conditioned — a mirror-like GGX (α = 10⁻³,
/// where a unit error of n·h changes D by 4/α² ulp), a thin film's phase at 400 nm, a grazing
/// view — this is what a conforming GPU's rounding of the directions it derives may do; where it is
/// well-conditioned it is negligible beside REL.
fn spread(inp: &EnvProbeInput, rng: &mut XorShift) -> [f64; 28] {
    let base = env_probe_cpu(inp).to_array();
    let mut out = [0f64; 28];
    for _ in 0..8 {
        let mut q = *inp;
        let mut nudge = |a: &mut [f32; 4], renorm: bool| {
            let u = rng.unit();
            let mut b = [0f64; 3];
            for k in 0..3 {
                b[k] = a[k] as f64 + DIR * u[k];
            }
            let b = if renorm { unit(b) } else { b.map(|x| x as f32) };
            a[..3].copy_from_slice(&b);
        };
        nudge(&mut q.n, true);
        nudge(&mut q.v, true);
        nudge(&mut q.t_anisotropy, true);
        nudge(&mut q.frame_t, true);
        nudge(&mut q.frame_n, true);
        nudge(&mut q.k2, true);
        nudge(&mut q.pn, true);
        nudge(&mut q.p, false);
        // The A–S exponents by a relative X_REL: hn^E = exp(−X) moves by X_REL·X, what
        // ProbeBound::GPU allows the value of the exponent X = −ln hn^E.
        q.fabric.e_along *= 1.0 + (X_REL * (2.0 * rng.next_f64() - 1.0)) as f32;
        q.fabric.e_across *= 1.0 + (X_REL * (2.0 * rng.next_f64() - 1.0)) as f32;
        // A thin film's thickness by a relative FILM_REL: its phases (about ten radians at
        // 400 nm) move by about 2^-11 rad, the absolute precision Vulkan allows `cos`.
        q.film[2] *= 1.0 + (FILM_REL * (2.0 * rng.next_f64() - 1.0)) as f32;
        let moved = env_probe_cpu(&q).to_array();
        for k in 0..28 {
            let d = (moved[k] as f64 - base[k] as f64).abs();
            if d.is_finite() {
                out[k] = out[k].max(2.0 * d);
            }
        }
    }
    out
}

/// |got − want| as a fraction of the bound of output `k` (NaN and Inf on either side: ∞), with
/// `cond` the output's [`spread`].
fn ratio(k: usize, want: f32, got: f32, cond: f64) -> f64 {
    if !want.is_finite() || !got.is_finite() {
        return if want.to_bits() == got.to_bits() {
            0.0
        } else {
            f64::INFINITY
        };
    }
    let (want, got) = (want as f64, got as f64);
    let name = ENV_PROBE_OUTPUT_NAMES[k];
    if name.starts_with("pixel_random") {
        return if want == got { 0.0 } else { f64::INFINITY };
    }
    if name.starts_with("ibl_sample") {
        return (got - want).abs() / (2.0 * f32::EPSILON as f64);
    }
    let abs = if name == "shadow_pcf" { ABS_PCF } else { ABS };
    (got - want).abs() / (REL * want.abs() + abs + cond)
}

#[test]
fn env_probe_matches_the_twins() {
    let ctx = common::context();
    let mut cases = hard();
    cases.extend(inputs(0xe11, 6000));
    let got = run(&ctx, &cases);
    let mut failures = Vec::new();
    let mut worst = vec![(0f64, 0usize); 28];
    let mut rng = XorShift::new(0xc0d);
    for (i, (inp, g)) in cases.iter().zip(&got).enumerate() {
        let want = env_probe_cpu(inp).to_array();
        let cond = spread(inp, &mut rng);
        let g = g.to_array();
        for k in 0..28 {
            let r = ratio(k, want[k], g[k], cond[k]);
            if r > worst[k].0 {
                worst[k] = (r, i);
            }
            if r > 1.0 && failures.len() < 20 {
                failures.push(format!(
                    "input {i} ({}: mode {} samples {}): gpu {} twin {} ({r:.2} of the bound)",
                    ENV_PROBE_OUTPUT_NAMES[k], inp.mode[0], inp.mode[1], g[k], want[k]
                ));
            }
        }
    }
    println!(
        "env probe on {}: {} inputs; worst |gpu - twin| / bound per output:",
        ctx.info().name,
        cases.len()
    );
    for (k, (r, i)) in worst.iter().enumerate() {
        println!("  {:24} {r:.4} (input {i})", ENV_PROBE_OUTPUT_NAMES[k]);
    }
    assert!(
        failures.is_empty(),
        "outside the bound:\n{}",
        failures.join("\n")
    );
}

/// The bound sees a real change: the twin over an environment 0.1 % brighter (every radiance
/// and prefiltered look-up × 1.001) is outside it for most inputs whose output is not 0.
#[test]
fn a_real_change_is_outside_the_bound() {
    struct Brighter(StandIn);
    impl EnvLookup for Brighter {
        fn radiance(&self, d: [f32; 3], lod: f32) -> [f32; 3] {
            self.0.radiance(d, lod).map(|x| x * 1.001)
        }
        fn prefiltered(&self, d: [f32; 3], r: f32) -> [f32; 3] {
            self.0.prefiltered(d, r).map(|x| x * 1.001)
        }
        fn dfg(&self, c: f32, r: f32) -> [f32; 3] {
            self.0.dfg(c, r)
        }
        fn face_size(&self) -> f32 {
            self.0.face_size()
        }
    }
    let ctx = common::context();
    let cases = inputs(0xe12, 500);
    let got = run(&ctx, &cases);
    let (mut seen, mut nonzero) = (0, 0);
    let mut rng = XorShift::new(0xc0e);
    for (inp, g) in cases.iter().zip(&got) {
        let cond = spread(inp, &mut rng);
        let env = Brighter(StandIn {
            face_size: inp.surface[3],
        });
        let want = env_probe_eval(inp, &env, stand_in_compare).pbr;
        let g = g.pbr;
        for k in 0..3 {
            if want[k].abs() > 1e-3 {
                nonzero += 1;
                if ratio(k, want[k], g[k], cond[k]) > 1.0 {
                    seen += 1;
                }
            }
        }
    }
    println!("a 0.1 % brighter environment: {seen} of {nonzero} pbr_env values outside the bound");
    assert!(
        nonzero > 1000 && seen as f64 > 0.95 * nonzero as f64,
        "{seen} of {nonzero}"
    );
}

/// The hard fabric cases hold what they promise: an rs = 0 cloth keeps its lobes at every level.
#[test]
fn an_rs_zero_fabric_keeps_its_lobes() {
    // (Square on, n·k2 = 1, Schlick's F is rs itself: 0 at every level.)
    for inp in hard()
        .iter()
        .filter(|c| c.fabric.rs == 0.0 && c.coverage[1] == 1.0 && c.k2[2] < 0.99)
    {
        let o = env_probe_cpu(inp);
        assert!(
            o.weft[0] > 0.0,
            "rs = 0, mode {}: weft lobe {:?}",
            inp.mode[0],
            o.weft
        );
    }
}
