//! The GLSL of image-based lighting (`glsl/include/ibl.glsl`, `glsl/include/cube.glsl`) against
//! its Rust twins (`weft::reference::ibl_twin`, which `env::sh_eval`, `env::hammersley` and
//! `render::environment::cube_texel_dir` instantiate), through `glsl/ibl_probe.comp` on a Vulkan device
//! (lavapipe by default, or WEFT_DEVICE) with validation on.
//!
//! The inputs: hard cases (xi at 0, at the quadrant boundaries of `as_sample_h` and just below 1;
//! A–S exponents from 0 to 1e6, equal and very unequal; GGX alpha 0 to 1; normals and directions
//! along the axes, the equirect seam and poles; pdf 0, negative, tiny and huge; Hammersley indices
//! past 2^24; cube texels at face corners and centres) and seeded random ones.
//!
//! The bound of each output is an interval that `ibl_twin::ibl_probe_bounds` computes for the
//! input by interval arithmetic under a model of the arithmetic (the module docs there say what
//! bounds each output):
//! - `Vulkan`: the Vulkan spec's precision rules (sin/cos 2^-11 absolute, atan 4096 ulp, exp2
//!   3 + 2|x| ulp, log2 3 ulp or 2^-21 absolute, division 2.5 ulp, inversesqrt 2 ulp, the rest
//!   inherited): the GPU's results must lie in it;
//! - `CpuF32`: IEEE f32 rounded to nearest with libm within 2 ulp: the f32 twin must lie in it,
//!   and so must the f64 formula and the f64 references (`brdf::sampling::sample_h`,
//!   `env::dir_to_uv`, `env::sh_basis`). The GPU's distance from the twin is also reported as a
//!   fraction of this tight bound (not asserted: a GPU may use all the spec allows).
//!
//! The GPU is asserted to lie inside its Vulkan interval. The reported "ratio" is |got − twin| as a
//! fraction of the interval's width (the largest difference two values inside it can have).

#![allow(clippy::needless_range_loop)] // Outputs are indexed by component number throughout.

mod common;

use weft::env::{dir_to_uv, env_from_world, sh_basis, Environment};
use weft::fabric::{FabricParams, GpuFabric};
use weft::reference::brdf::sampling::sample_h;
use weft::reference::ibl_twin::{
    bound_fraction, ibl_probe_bounds, ibl_probe_cpu, ibl_probe_eval, in_bound, CpuF32,
    IblProbeInput, IblProbeOutput, Iv, Model, Vulkan, IBL_PROBE_CIRCULAR, IBL_PROBE_OUTPUTS,
    IBL_PROBE_OUTPUT_NAMES,
};
use weft::reference::probe::XorShift;
use weft::vk::shaders;

/// A named input.
struct Case {
    name: String,
    input: IblProbeInput,
}

/// The f32 just below `x > 0`.
fn below(x: f32) -> f32 {
    f32::from_bits(x.to_bits() - 1)
}

/// The f32 just above `x > 0`.
fn above(x: f32) -> f32 {
    f32::from_bits(x.to_bits() + 1)
}

/// A unit vector rounded to f32 (a direction as a renderer would give it).
fn unit(v: [f64; 3]) -> [f32; 4] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [(v[0] / l) as f32, (v[1] / l) as f32, (v[2] / l) as f32, 0.0]
}

fn rows(degrees: f32) -> [[f32; 4]; 3] {
    env_from_world(degrees).map(|r| [r[0], r[1], r[2], 0.0])
}

fn sh4(sh: [[f32; 3]; 9]) -> [[f32; 4]; 9] {
    sh.map(|c| [c[0], c[1], c[2], 0.0])
}

fn fabric(rs: f32, coupled: bool) -> GpuFabric {
    FabricParams {
        rs,
        coupled_diffuse: coupled,
        ..Default::default()
    }
    .to_gpu()
}

/// SH sets: a uniform environment (exactly one band-0 term), a strongly directional one whose
/// order-2 fit rings below zero (the clamp at 0 acts), zero, and a made-up coloured one.
fn sh_sets() -> Vec<(&'static str, [[f32; 3]; 9])> {
    let uniform = Environment::uniform([1.0, 0.5, 2.0]).sh9();
    let mut sun = [[0f32; 3]; 9];
    for (k, c) in sun.iter_mut().enumerate() {
        let v = [0.6, 1.1, 0.8, 0.9, 0.7, 0.8, 0.6, 0.9, 0.5][k];
        *c = [v * 30.0, v * 28.0, v * 25.0];
    }
    let mut coloured = [[0f32; 3]; 9];
    for (k, c) in coloured.iter_mut().enumerate() {
        let s = if k % 2 == 0 { 1.0 } else { -1.0 };
        *c = [0.9 - 0.08 * k as f32, s * 0.13 * k as f32, 0.3 + s * 0.05];
    }
    vec![
        ("uniform", uniform),
        ("sun", sun),
        ("zero", [[0.0; 3]; 9]),
        ("coloured", coloured),
    ]
}

fn hard_cases() -> Vec<Case> {
    let xs = [
        0.0,
        1e-7,
        0.125,
        below(0.25),
        0.25,
        above(0.25),
        below(0.5),
        0.5,
        0.3,
        below(0.75),
        0.75,
        0.875,
        below(1.0),
    ];
    let ys = [0.0, 1e-7, 0.5, 0.9, below(1.0)];
    let lobes: [(f32, f32); 10] = [
        (0.0, 0.0),
        (1.0, 1.0),
        (1.0, 1e4),
        (1e4, 1.0),
        (1e4, 1e4),
        (10.0, 1000.0),
        (1e6, 1.0),
        (1.0, 1e6),
        (100.0, 100.0),
        (0.1, 50.0),
    ];
    let alphas = [0.0, 1e-3, 0.04, 0.5, 1.0];
    let axes: [[f64; 3]; 7] = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
        [1.0, 1.0, 1.0],
    ];
    let degrees = [0.0, 90.0, 180.0, -45.0, 30.0, 1e5, 0.001];
    let shs = sh_sets();
    let pdfs = [0.0, -1.0, 1e-30, 1e-20, 1e-3, 0.159, 1.0, 1e4, 1e8, 1e30];
    let ns = [1u32, 8, 16, 64, 4096];
    let sizes = [1.0, 16.0, 128.0, 512.0];
    let nvs = [0.0, 1e-4, 0.3, below(1.0), 1.0];
    let aos = [0.0, 0.5, 1.0];
    let roughs = [0.0, 0.5, 1.0];
    let nk2s = [-0.5, 0.0, 1e-7, 0.3, 1.0, 1.5];
    let rss = [0.0, 0.04, 1.0];
    // gtao_arc: (n, h0, h1) at the limits the occlusion pass keeps them in (h0 in
    // [n - π/2, 0], h1 in [0, n + π/2], n in [-π/2, π/2]); gtao_multibounce: v and albedo.
    let half = std::f32::consts::FRAC_PI_2;
    let arcs: [[f32; 4]; 9] = [
        [-half, half, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0],
        [-half, 0.0, 0.0, 0.0],
        [-std::f32::consts::PI, 0.0, -half, 0.0],
        [0.0, std::f32::consts::PI, half, 0.0],
        [-0.3, 0.2, 0.1, 0.0],
        [-1.0, below(1.0), -0.5, 0.0],
        [-1e-7, 1e-7, 1e-7, 0.0],
        [-0.9, 1.8, 0.4, 0.0],
    ];
    let bounces: [(f32, f32); 7] = [
        (0.0, 0.0),
        (1.0, 1.0),
        (0.5, 0.5),
        (1.0, 0.0),
        (0.0, 1.0),
        (0.2, 0.9),
        (below(1.0), 0.04),
    ];
    let hams: [(u32, u32); 11] = [
        (0, 1),
        (0, 16),
        (15, 16),
        (1, 2),
        (4095, 4096),
        (1, 4096),
        ((1 << 24) - 1, 1 << 24),
        (u32::MAX, u32::MAX),
        (12345, 1_000_000),
        (1, 1),
        (7, 3),
    ];
    let texels: [(u32, u32, u32); 10] = [
        (0, 0, 1),
        (0, 0, 16),
        (15, 15, 16),
        (0, 15, 16),
        (7, 8, 16),
        (0, 0, 512),
        (511, 511, 512),
        (255, 256, 512),
        (1, 1, 3),
        (0, 1, 2),
    ];
    let dirs: [[f32; 4]; 16] = [
        [1.0, 0.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [-0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, -1.0, 0.0],
        [1e-20, 0.0, 1.0, 0.0],
        [-1e-20, 0.0, 1.0, 0.0],
        [1e-4, below(1.0), 0.0, 0.0],
        [0.0, -below(1.0), 1e-4, 0.0],
        [1e-7, 1.000_000_1, 0.0, 0.0],
        [0.0, -1.000_000_1, 1e-7, 0.0],
        [0.6, 0.0, -0.8, 0.0],
        [-0.6, 0.0, 0.8, 0.0],
        unit([0.3, -0.5, 0.2]),
    ];

    let mut cases = Vec::new();
    let mut k = 0usize;
    for &(eu, ev) in &lobes {
        for &x in &xs {
            for &y in &ys {
                // The other functions' inputs cycle through their own hard lists.
                let c = |n: usize| k % n;
                let d = |n: usize, m: usize| (k / m) % n;
                let (sh_name, sh) = shs[d(shs.len(), axes.len())];
                let (pdf, n_fis, size) = (
                    pdfs[c(pdfs.len())],
                    ns[d(ns.len(), pdfs.len())],
                    sizes[d(sizes.len(), pdfs.len() * ns.len())],
                );
                let (nv, ao, rough) = (
                    nvs[c(nvs.len())],
                    aos[d(aos.len(), nvs.len())],
                    roughs[d(roughs.len(), nvs.len() * aos.len())],
                );
                let (nk2, rs, coupled) = (
                    nk2s[c(nk2s.len())],
                    rss[d(rss.len(), nk2s.len())],
                    d(2, nk2s.len() * rss.len()) == 1,
                );
                let (hi, hn) = hams[c(hams.len())];
                let face = d(6, texels.len()) as u32;
                let (tx, ty, ts) = texels[c(texels.len())];
                let alpha = alphas[d(alphas.len(), xs.len() * ys.len())];
                let dir = dirs[c(dirs.len())];
                let world = unit(axes[c(axes.len())]);
                let deg = degrees[d(degrees.len(), axes.len())];
                let normal = unit(axes[d(axes.len(), 3)]);
                let arc = arcs[c(arcs.len())];
                let (vis, albedo) = bounces[d(bounces.len(), arcs.len())];
                cases.push(Case {
                    name: format!(
                        "hard {k}: xi ({x:e}, {y:e}) eu {eu} ev {ev} alpha {alpha}; world {world:?} rot {deg}°; \
                         normal {normal:?} sh {sh_name}; pdf {pdf:e} n {n_fis} size {size}; nv {nv} ao {ao} \
                         roughness {rough}; nk2 {nk2} rs {rs} coupled {coupled}; hammersley ({hi}, {hn}); \
                         cube face {face} ({tx}, {ty}) of {ts}; dir {dir:?}; arc {arc:?}; \
                         multibounce ({vis}, {albedo})"
                    ),
                    input: IblProbeInput {
                        world,
                        rot: rows(deg),
                        normal,
                        sh: sh4(sh),
                        xi: [x, y, 0.0, 0.0],
                        lobe: [alpha, eu, ev, 0.0],
                        lod: [pdf, size, nv, ao],
                        misc: [rough, nk2, vis, albedo],
                        counts: [hi, hn, n_fis, 0],
                        cube: [face, tx, ty, ts],
                        dir,
                        fabric: fabric(rs, coupled),
                        arc,
                    },
                });
                k += 1;
            }
        }
    }
    cases
}

fn random_cases(seed: u64, count: usize) -> Vec<Case> {
    let mut rng = XorShift::new(seed);
    let mut out = Vec::with_capacity(count);
    for i in 0..count {
        let f = |rng: &mut XorShift| rng.next_f64() as f32;
        // xi in [0, 1) as f32 (rounding to f32 could reach 1.0: keep below).
        let xi = |rng: &mut XorShift| (rng.next_f64() as f32).min(below(1.0));
        let exponent = |rng: &mut XorShift| {
            if rng.next_f64() < 0.1 {
                0.0
            } else {
                rng.log_range(0.1, 1e6) as f32
            }
        };
        let mut sh = [[0f32; 4]; 9];
        for (k, c) in sh.iter_mut().enumerate() {
            let scale = if k == 0 { 4.0 } else { 2.0 };
            for x in c.iter_mut().take(3) {
                *x = (rng.range(if k == 0 { 0.0 } else { -1.0 }, 1.0) * scale) as f32;
            }
        }
        let n = 1 + (rng.next_u64() % 4096) as u32;
        let size = 1u32 << (rng.next_u64() % 10);
        let size = if rng.next_f64() < 0.2 {
            1 + (rng.next_u64() % 1024) as u32
        } else {
            size
        };
        let input = IblProbeInput {
            world: unit(rng.unit()),
            rot: rows(rng.range(-720.0, 720.0) as f32),
            normal: unit(rng.unit()),
            sh,
            xi: [xi(&mut rng), xi(&mut rng), 0.0, 0.0],
            lobe: [
                f(&mut rng) * f(&mut rng),
                exponent(&mut rng),
                exponent(&mut rng),
                0.0,
            ],
            lod: [
                rng.log_range(1e-6, 1e8) as f32,
                [16.0, 64.0, 128.0, 256.0, 512.0][(rng.next_u64() % 5) as usize],
                f(&mut rng),
                f(&mut rng),
            ],
            misc: [
                f(&mut rng),
                rng.range(-0.2, 1.2) as f32,
                f(&mut rng),
                f(&mut rng),
            ],
            counts: [(rng.next_u64() % n as u64) as u32, n, n, 0],
            cube: [
                (rng.next_u64() % 6) as u32,
                (rng.next_u64() % size as u64) as u32,
                (rng.next_u64() % size as u64) as u32,
                size,
            ],
            dir: unit(rng.unit()),
            fabric: fabric(f(&mut rng), rng.next_f64() < 0.5),
            arc: {
                let half = std::f64::consts::FRAC_PI_2;
                let n = rng.range(-half, half);
                [
                    rng.range(n - half, 0.0) as f32,
                    rng.range(0.0, n + half) as f32,
                    n as f32,
                    0.0,
                ]
            },
        };
        out.push(Case {
            name: format!("random {i} (seed {seed:#x})"),
            input,
        });
    }
    out
}

fn all_cases() -> Vec<Case> {
    let mut v = hard_cases();
    v.extend(random_cases(0x1b1, 4000));
    v
}

/// The inputs an output depends on, for messages.
fn describe(inp: &IblProbeInput, k: usize) -> String {
    match k / 4 {
        0 => format!("world {:?} rows {:?}", inp.world, inp.rot),
        1 => format!("normal {:?} sh {:?}", inp.normal, inp.sh),
        2 => format!("xi {:?} alpha {:e}", &inp.xi[..2], inp.lobe[0]),
        3 => format!(
            "xi ({:e}, {:e}) eu {:e} ev {:e}",
            inp.xi[0], inp.xi[1], inp.lobe[1], inp.lobe[2]
        ),
        4 => format!("xi {:?}", &inp.xi[..2]),
        5 => format!("cube {:?}", inp.cube),
        6 if k % 4 < 2 => format!("hammersley ({}, {})", inp.counts[0], inp.counts[1]),
        6 => format!("dir {:?}", inp.dir),
        8 if k % 4 == 0 => format!(
            "arc h0 {:e} h1 {:e} n {:e}",
            inp.arc[0], inp.arc[1], inp.arc[2]
        ),
        8 => format!("multibounce v {:e} albedo {:e}", inp.misc[2], inp.misc[3]),
        9 => format!(
            "dominant_dir n {:?} r {:?} roughness {:e}",
            &inp.normal[..3],
            &inp.dir[..3],
            inp.misc[0]
        ),
        _ => match k % 4 {
            0 => format!(
                "pdf {:e} n {} size {}",
                inp.lod[0], inp.counts[2], inp.lod[1]
            ),
            1 => format!(
                "nv {:e} ao {} roughness {}",
                inp.lod[2], inp.lod[3], inp.misc[0]
            ),
            _ => format!(
                "nk2 {:e} rs {} flags {}",
                inp.misc[1], inp.fabric.rs, inp.fabric.flags
            ),
        },
    }
}

/// Per output: the worst ratio, the case it was met in, and the largest |difference|.
struct Worst {
    ratio: [f64; IBL_PROBE_OUTPUTS],
    case: [String; IBL_PROBE_OUTPUTS],
    diff: [f64; IBL_PROBE_OUTPUTS],
}

impl Worst {
    fn new() -> Self {
        Worst {
            ratio: [0.0; IBL_PROBE_OUTPUTS],
            case: std::array::from_fn(|_| String::new()),
            diff: [0.0; IBL_PROBE_OUTPUTS],
        }
    }
    fn add(&mut self, k: usize, ratio: f64, diff: f64, case: &str) {
        if ratio > self.ratio[k] || (self.case[k].is_empty() && ratio >= 0.0) {
            self.ratio[k] = ratio;
            self.case[k] = case.to_string();
        }
        self.diff[k] = self.diff[k].max(diff);
    }
    fn overall(&self) -> (f64, usize) {
        (0..IBL_PROBE_OUTPUTS)
            .map(|k| (self.ratio[k], k))
            .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a })
    }
    fn print(&self, title: &str) {
        println!("{title}");
        for k in 0..IBL_PROBE_OUTPUTS {
            if (k % 4 == 3 && k / 4 < 6) || k == 31 || k == 34 || k == 35 || k == 39 {
                continue; // the zero padding
            }
            println!(
                "  {:<24} worst ratio {:>9.3e}   max |diff| {:>9.3e}   ({})",
                IBL_PROBE_OUTPUT_NAMES[k],
                self.ratio[k],
                self.diff[k],
                self.case[k].split(':').next().unwrap_or("")
            );
        }
    }
}

/// |a − b|, modulo 1 for the circular component.
fn diff(k: usize, a: f64, b: f64) -> f64 {
    if k == IBL_PROBE_CIRCULAR {
        let d = (a - b).rem_euclid(1.0);
        d.min(1.0 - d)
    } else {
        (a - b).abs()
    }
}

fn fraction<M: Model>(k: usize, b: Iv<M>, twin: f64, got: f64) -> f64 {
    bound_fraction(b, twin, got, k == IBL_PROBE_CIRCULAR)
}

#[test]
fn twins_reuse_the_existing_functions_and_meet_the_f64_references() {
    let cases = all_cases();
    let mut failures = Vec::new();
    let mut worst_twin = Worst::new();
    // The r ≤ 0.9999999 clamp's effect (xi.y > 0), and |twin - sample_h(unclamped xi)| with
    // xi.y > 0 and at xi.y = 0 (where the 1e-30 clamp acts).
    let mut r_clamp_effect = 0f64;
    let mut as_vs_sample_h = (0f64, String::new());
    let mut at_xi_y_zero = 0f64;
    for c in &cases {
        let inp = &c.input;
        let sh: [[f32; 3]; 9] = std::array::from_fn(|k| [inp.sh[k][0], inp.sh[k][1], inp.sh[k][2]]);
        let n = [inp.normal[0], inp.normal[1], inp.normal[2]];
        let bounds = ibl_probe_bounds::<CpuF32>(inp);
        let vk = ibl_probe_bounds::<Vulkan>(inp);
        let twin = ibl_probe_cpu(inp).to_array();
        let exact = ibl_probe_eval::<f64>(inp);
        for k in 0..IBL_PROBE_OUTPUTS {
            let circ = k == IBL_PROBE_CIRCULAR;
            if !in_bound(bounds[k], twin[k] as f64, circ, 0.0) {
                failures.push(format!(
                    "{}: twin {} = {:e} outside its CpuF32 bound [{:e}, {:e}] ({})",
                    c.name,
                    IBL_PROBE_OUTPUT_NAMES[k],
                    twin[k],
                    bounds[k].lo,
                    bounds[k].hi,
                    describe(inp, k)
                ));
            }
            if !in_bound(vk[k], twin[k] as f64, circ, 0.0) {
                failures.push(format!(
                    "{}: twin {} = {:e} outside its Vulkan bound [{:e}, {:e}]",
                    c.name, IBL_PROBE_OUTPUT_NAMES[k], twin[k], vk[k].lo, vk[k].hi
                ));
            }
            if !in_bound(bounds[k], exact[k], circ, 1e-12) {
                failures.push(format!(
                    "{}: f64 formula {} = {:e} outside the CpuF32 bound [{:e}, {:e}] ({})",
                    c.name,
                    IBL_PROBE_OUTPUT_NAMES[k],
                    exact[k],
                    bounds[k].lo,
                    bounds[k].hi,
                    describe(inp, k)
                ));
            }
            // The twin's distance from the exact formula, as a fraction of the tight bound.
            let r = fraction(k, bounds[k], exact[k], twin[k] as f64);
            worst_twin.add(k, r, diff(k, twin[k] as f64, exact[k]), &c.name);
        }

        // Independent f64 references.
        // as_sample_h: brdf::sampling::sample_h at the xi the GLSL's clamps make (r ≤ 0.9999999,
        // xi.y ≥ 1e-30); the clamps' own effect is measured against the unclamped xi.
        let (x0, x1) = (inp.xi[0] as f64, inp.xi[1] as f64);
        let q = (4.0 * x0).floor().clamp(0.0, 3.0);
        let r = (4.0 * x0 - q).min(0.999_999_9f32 as f64);
        let clamped = [(q + r) / 4.0, x1.max(1e-30f32 as f64)];
        let (eu, ev) = (inp.lobe[1] as f64, inp.lobe[2] as f64);
        let h = sample_h(eu, ev, clamped[0], clamped[1]);
        let h_free = sample_h(eu, ev, x0, x1);
        for j in 0..3 {
            let k = 12 + j;
            // sample_h turns φ = π − φ0 etc. into sin and cos with π rounded to f64: at a quadrant
            // boundary it gives 1.2e-16 where the exact value (and the GLSL's, which never forms
            // φ) is 0.
            let hj = if j < 2 && h[j].abs() < 1e-15 {
                0.0
            } else {
                h[j]
            };
            if !in_bound(bounds[k], hj, false, 1e-12) {
                failures.push(format!(
                    "{}: sample_h {} = {:e} outside the CpuF32 bound [{:e}, {:e}] ({})",
                    c.name,
                    IBL_PROBE_OUTPUT_NAMES[k],
                    h[j],
                    bounds[k].lo,
                    bounds[k].hi,
                    describe(inp, k)
                ));
            }
            let d = (twin[k] as f64 - h_free[j]).abs();
            if x1 > 0.0 {
                r_clamp_effect = r_clamp_effect.max((h[j] - h_free[j]).abs());
                if d > as_vs_sample_h.0 {
                    as_vs_sample_h = (
                        d,
                        format!(
                            "{} ({})",
                            c.name.split(':').next().unwrap_or(""),
                            describe(inp, k)
                        ),
                    );
                }
            } else {
                at_xi_y_zero = at_xi_y_zero.max(d);
            }
        }
        // equirect_uv: env::dir_to_uv (u wrapped to [0, 1), compared modulo 1).
        let d = [inp.dir[0] as f64, inp.dir[1] as f64, inp.dir[2] as f64];
        let (u, v) = dir_to_uv(d);
        let pole = inp.dir[0] == 0.0 && inp.dir[2] == 0.0;
        for (k, x) in [(26, u), (27, v)] {
            if (k == 27 || !pole) && !in_bound(bounds[k], x, k == 26, 1e-12) {
                failures.push(format!(
                    "{}: dir_to_uv {} = {:e} outside the CpuF32 bound [{:e}, {:e}] ({})",
                    c.name,
                    IBL_PROBE_OUTPUT_NAMES[k],
                    x,
                    bounds[k].lo,
                    bounds[k].hi,
                    describe(inp, k)
                ));
            }
        }
        // sh_irradiance: the f64 SH basis of env::sh_basis.
        let basis = sh_basis([n[0] as f64, n[1] as f64, n[2] as f64]);
        for ch in 0..3 {
            let e: f64 = (0..9)
                .map(|k| sh[k][ch] as f64 * basis[k])
                .sum::<f64>()
                .max(0.0);
            let k = 4 + ch;
            if !in_bound(bounds[k], e, false, 1e-12) {
                failures.push(format!(
                    "{}: sh_basis sum {} = {:e} outside the CpuF32 bound [{:e}, {:e}]",
                    c.name, IBL_PROBE_OUTPUT_NAMES[k], e, bounds[k].lo, bounds[k].hi
                ));
            }
        }
    }
    worst_twin.print(&format!(
        "f32 twins vs the f64 formulas on {} inputs, |twin - f64| as a fraction of the CpuF32 bound's width:",
        cases.len()
    ));
    println!(
        "as_sample_h vs brdf::sampling::sample_h (f64) at the unclamped xi, xi.y > 0: worst |difference| {:.3e} ({}); \
         the r <= 0.9999999 clamp alone moves sample_h by at most {:.3e}; at xi.y = 0 the 1e-30 clamp moves h by up to {:.3e} \
         (sample_h gives the horizon, the GLSL the 1e-30 quantile of the lobe)",
        as_vs_sample_h.0, as_vs_sample_h.1, r_clamp_effect, at_xi_y_zero
    );
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures[..failures.len().min(60)].join("\n")
    );
}

/// Runs ibl_probe.comp on `inputs`.
fn run_probe(ctx: &weft::vk::Context, inputs: &[IblProbeInput]) -> Vec<IblProbeOutput> {
    let size = std::mem::size_of::<IblProbeOutput>();
    let bytes = common::run_probe_shader(ctx, &shaders::IBL_PROBE_COMP, inputs, size);
    (0..inputs.len())
        .map(|i| IblProbeOutput::from_bytes(&bytes[i * size..(i + 1) * size]))
        .collect()
}

#[test]
fn ibl_probe_matches_the_twins_within_the_vulkan_bounds() {
    let ctx = common::context();
    let cases = all_cases();
    let inputs: Vec<IblProbeInput> = cases.iter().map(|c| c.input).collect();
    let got = run_probe(&ctx, &inputs);
    let mut failures = Vec::new();
    let mut worst_vk = Worst::new();
    let mut worst_tight = Worst::new();
    // Outputs whose Vulkan bound spans more than 1 (the spec does not pin them down).
    let mut loose = [0usize; IBL_PROBE_OUTPUTS];
    for (c, g) in cases.iter().zip(&got) {
        let inp = &c.input;
        let twin = ibl_probe_cpu(inp).to_array();
        let g = g.to_array();
        let vk = ibl_probe_bounds::<Vulkan>(inp);
        let tight = ibl_probe_bounds::<CpuF32>(inp);
        for k in 0..IBL_PROBE_OUTPUTS {
            let (t, x) = (twin[k] as f64, g[k] as f64);
            let r = fraction(k, vk[k], t, x);
            let d = diff(k, x, t);
            if !in_bound(vk[k], x, k == IBL_PROBE_CIRCULAR, 0.0) {
                failures.push(format!(
                    "{}: {} gpu {:e}, twin {:e}, |diff| {:e}, Vulkan bound [{:e}, {:e}] ({})",
                    c.name.split(':').next().unwrap_or(""),
                    IBL_PROBE_OUTPUT_NAMES[k],
                    g[k],
                    twin[k],
                    d,
                    vk[k].lo,
                    vk[k].hi,
                    describe(inp, k)
                ));
            }
            if vk[k].width() > 1.0 {
                // Unconstrained by the spec (as_sample_h near r = 1, equirect u at the poles):
                // counted, left out of the statistics.
                loose[k] += 1;
                continue;
            }
            worst_vk.add(k, r, d, &c.name);
            worst_tight.add(k, fraction(k, tight[k], t, x), d, &c.name);
        }
    }
    let info = ctx.info().name.clone();
    worst_vk.print(&format!(
        "ibl probe on {info}: {} inputs, |gpu - twin| as a fraction of the Vulkan bound's width (every output asserted inside its bound):",
        cases.len()
    ));
    worst_tight.print(
        "the same as a fraction of the CpuF32 bound's width (information only: > 1 means less accurate than a good f32 libm):",
    );
    for (k, n) in loose.iter().enumerate() {
        if *n > 0 {
            println!(
                "  {}: the Vulkan bound is wider than 1 on {n} inputs (left out above)",
                IBL_PROBE_OUTPUT_NAMES[k]
            );
        }
    }
    let (r, k) = worst_vk.overall();
    let (rt, kt) = worst_tight.overall();
    println!(
        "worst: {r:.3e} of the Vulkan bound ({}, {}); {rt:.3e} of the CpuF32 bound ({}, {})",
        IBL_PROBE_OUTPUT_NAMES[k],
        worst_vk.case[k].split(':').next().unwrap_or(""),
        IBL_PROBE_OUTPUT_NAMES[kt],
        worst_tight.case[kt].split(':').next().unwrap_or("")
    );
    assert!(
        failures.is_empty(),
        "{} outputs outside their Vulkan bound:\n{}",
        failures.len(),
        failures[..failures.len().min(60)].join("\n")
    );
}
