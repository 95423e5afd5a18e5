//! The CPU reference of the fabric model against the model page (docs/fabric-model.md), item by
//! item of its §5, and the f32 path (the GLSL's twin) against the f64 reference.
//!
//! `cargo test --release --test fabric_reference -- --nocapture` prints the furnace figures and
//! the f32-vs-f64 error ratios.

use proptest::prelude::*;
use std::f64::consts::PI;
use weft::fabric::{weave_level_size, weave_texels_cpu, FabricParams, WeavePattern};
use weft::reference::brdf::{double, sampling, single};
use weft::reference::furnace::{
    diffuse_albedo, fabric_albedo, fabric_albedo_quadrature, lobe_albedo,
};
use weft::reference::probe::{
    probe_check, probe_cpu_f32, probe_cpu_f64, probe_hard_cases, probe_random, probe_tolerance,
    ProbeBound, PROBE_OUTPUTS, PROBE_OUTPUT_NAMES,
};
use weft::reference::weave::{self as weave_ref, double as wd, single as ws};

fn unit(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / l, v[1] / l, v[2] / l]
}

fn to32(v: [f64; 3]) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

fn mat(e_along: f64, e_across: f64, rs: f64, coupled: bool) -> double::FabricMaterial {
    double::FabricMaterial {
        rd_warp: [1.0; 3],
        rd_weft: [1.0; 3],
        rs,
        e_along,
        e_across,
        coupled,
        threads: false,
        sheet: None,
    }
}

// ---------------------------------------------------------------------------------------------
// §5.1, 5.2, 5.3, 5.4, 5.5, 5.10, 5.11: every probe input, hard and random, is finite in both
// precisions, and the f32 path meets its stated bound.

#[test]
fn every_probe_output_is_finite_and_f32_meets_its_bound() {
    let mut cases = probe_hard_cases();
    let hard = cases.len();
    cases.extend(probe_random(0x5eed, 20_000));
    let mut failures = Vec::new();
    let mut worst = vec![0.0f64; PROBE_OUTPUTS];
    for c in &cases {
        let r64 = probe_cpu_f64(&c.input);
        let r32 = probe_cpu_f32(&c.input);
        for (k, (a, b)) in r64.to_array().iter().zip(r32.to_array().iter()).enumerate() {
            assert!(
                a.is_finite() && b.is_finite(),
                "{}: {} not finite: f64 {a}, f32 {b}",
                c.name,
                PROBE_OUTPUT_NAMES[k]
            );
        }
        let msgs = probe_check(&c.input, &r64, &r32, &ProbeBound::CPU_F32);
        if !msgs.is_empty() {
            failures.push(format!("{}:\n  {}", c.name, msgs.join("\n  ")));
        }
        // Per-output worst ratio, for the printout.
        let tol = probe_tolerance(&c.input, &ProbeBound::CPU_F32).to_array();
        let (a, b) = (r64.to_array(), r32.to_array());
        for k in 0..PROBE_OUTPUTS {
            let d = (a[k] as f64 - b[k] as f64).abs();
            if d > 0.0 && tol[k] > 0.0 {
                worst[k] = worst[k].max(d / tol[k] as f64);
            }
        }
    }
    println!(
        "f32 vs f64 over {} inputs ({hard} hard cases): worst |diff|/tolerance per output:",
        cases.len()
    );
    for k in 0..PROBE_OUTPUTS {
        println!("  {:18} {:.3}", PROBE_OUTPUT_NAMES[k], worst[k]);
    }
    assert!(
        failures.is_empty(),
        "{} inputs out of bound:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn gpu_bound_is_wider_than_cpu_bound() {
    for c in probe_hard_cases().iter().chain(probe_random(7, 500).iter()) {
        let a = probe_tolerance(&c.input, &ProbeBound::CPU_F32).to_array();
        let b = probe_tolerance(&c.input, &ProbeBound::GPU).to_array();
        for k in 0..PROBE_OUTPUTS {
            assert!(b[k] >= a[k], "{}: {}", c.name, PROBE_OUTPUT_NAMES[k]);
        }
    }
}

// §5.1: hn = 1 exactly gives the finite closed-form peak.
#[test]
fn peak_at_hn_1_is_the_closed_form() {
    for &(eu, ev) in &[
        (0.0f64, 0.0f64),
        (0.1, 0.1),
        (200.0, 10.0),
        (1e4, 1e4),
        (1e6, 1e6),
        (1e6, 1.0),
        (1.0, 1e6),
        (0.0, 1e6),
    ] {
        for &rs in &[0.0f64, 0.04, 0.5, 1.0] {
            let n = [0.0, 0.0, 1.0];
            let closed = ((eu + 1.0) * (ev + 1.0)).sqrt() / (8.0 * PI) * rs;
            let got = double::as_lobe(n, n, eu, ev, rs);
            assert!(
                (got - closed).abs() <= 1e-14 * closed,
                "f64 ({eu},{ev},{rs}): {got} vs {closed}"
            );
            let g32 = single::as_lobe(
                [0.0, 0.0, 1.0],
                [0.0, 0.0, 1.0],
                eu as f32,
                ev as f32,
                rs as f32,
            ) as f64;
            assert!(
                (g32 - closed).abs() <= 1e-6 * closed,
                "f32 ({eu},{ev},{rs}): {g32} vs {closed}"
            );
            assert_eq!(double::as_power(0.0, 0.0, 1.0, eu, ev), 1.0);
            assert_eq!(single::as_power(0.0, 0.0, 1.0, eu as f32, ev as f32), 1.0);
            // D at the peak: sqrt((eu+1)(ev+1))/(2π).
            let d = double::as_d(n, eu, ev);
            let d_closed = ((eu + 1.0) * (ev + 1.0)).sqrt() / (2.0 * PI);
            assert!(
                (d - d_closed).abs() <= 1e-14 * d_closed,
                "D {d} vs {d_closed}"
            );
            // §5.2: |k| slightly above 1, h·n > 1 after rounding: still the peak, Fresnel clamped.
            let k = [0.0f32, 0.0, 1.000_000_2];
            let g = single::as_lobe(k, k, eu as f32, ev as f32, rs as f32) as f64;
            assert!(
                g.is_finite() && (g - closed).abs() <= 1e-6 * closed.max(1e-30),
                "|k|>1: {g} vs {closed}"
            );
        }
    }
}

// §5.2: hu² + hv² underflowing while the exponent is huge; h·n rounding to 1.
#[test]
fn tiny_tangential_components_are_harmless() {
    for &(hu, hv) in &[
        (1e-23f32, 1e-23f32),
        (1e-20, 0.0),
        (0.0, 1e-30),
        (1e-38, 1e-38),
        (1e-45, 0.0),
    ] {
        for &(eu, ev) in &[(1e6f32, 0.0f32), (0.0, 1e6), (1e6, 1e6), (1e4, 0.1)] {
            let p = single::as_power(hu, hv, 1.0, eu, ev);
            assert!(
                p.is_finite() && (p - 1.0).abs() < 1e-6,
                "as_power({hu},{hv}) = {p}"
            );
            let e = single::as_exponent(hu, hv, eu, ev);
            assert!(
                e.is_finite() && e >= eu.min(ev) && e <= eu.max(ev),
                "E = {e}"
            );
            let e64 = double::as_exponent(hu as f64, hv as f64, eu as f64, ev as f64);
            assert!(
                (e as f64 - e64).abs() <= 1e-6 * e64.max(1.0),
                "E f32 {e} vs f64 {e64}"
            );
        }
    }
    // E is never formed as 0/0.
    assert_eq!(single::as_exponent(0.0, 0.0, 3.0, 5.0), 4.0);
    assert_eq!(double::as_exponent(0.0, -0.0, 1e6, 0.0), 5e5);
}

// The series branch of as_power matches hn^E computed plainly in f64 where that is accurate.
#[test]
fn as_power_matches_pow() {
    for k in 0..2000 {
        let t = k as f64 / 2000.0 * 1.5;
        let phi = k as f64 * 0.7;
        let h = [t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos()];
        for &(eu, ev) in &[(0.0, 0.0), (1.0, 3.0), (50.0, 5.0), (1000.0, 2.0)] {
            let e = double::as_exponent(h[0], h[1], eu, ev);
            let want = h[2].powf(e);
            let got = double::as_power(h[0], h[1], h[2], eu, ev);
            assert!(
                (got - want).abs() <= 1e-12 * want + 1e-300,
                "θ {t} E {e}: {got} vs {want}"
            );
        }
    }
}

// §5.4: back-facing and grazing give exactly 0; k1 = -k2 gives 0.
proptest! {
    #[test]
    fn back_facing_is_exactly_zero(
        a in prop::array::uniform3(-1.0f64..1.0), b in prop::array::uniform3(-1.0f64..1.0),
        eu in 0.0f64..1e6, ev in 0.0f64..1e6, rs in 0.0f64..1.0, which in 0usize..3,
    ) {
        let mut k1 = unit([a[0], a[1], a[2] + 1e-9]);
        let mut k2 = unit([b[0], b[1], b[2] + 1e-9]);
        match which {
            0 => k1[2] = -k1[2].abs(),
            1 => k2[2] = -k2[2].abs(),
            _ => { k1[2] = -k1[2].abs(); k2[2] = -k2[2].abs(); }
        }
        let m = double::FabricMaterial { rd_warp: [0.5; 3], rd_weft: [0.5; 3], rs, e_along: eu, e_across: ev, coupled: which == 1, threads: false, sheet: None };
        prop_assert_eq!(double::as_lobe(k1, k2, eu, ev, rs), 0.0);
        prop_assert_eq!(double::fabric_brdf(k1, k2, [0.5, 0.5, 0.3, 0.4], &m), [0.0; 3]);
        prop_assert_eq!(single::as_lobe(to32(k1), to32(k2), eu as f32, ev as f32, rs as f32), 0.0);
        let m32 = single::FabricMaterial { rd_warp: [0.5; 3], rd_weft: [0.5; 3], rs: rs as f32, e_along: eu as f32, e_across: ev as f32, coupled: which == 1, threads: false, sheet: None };
        prop_assert_eq!(single::fabric_brdf(to32(k1), to32(k2), [0.5, 0.5, 0.3, 0.4], &m32), [0.0; 3]);
        // Grazing exactly: n·k = 0.
        let g = unit([a[0] + 1e-9, a[1], 0.0]);
        let g = [g[0], g[1], 0.0];
        prop_assert_eq!(double::as_lobe(g, unit([0.1, 0.2, 0.9]), eu, ev, rs), 0.0);
        // k1 = -k2.
        let k = unit([a[0], a[1], a[2].abs() + 0.1]);
        prop_assert_eq!(double::as_lobe(k, [-k[0], -k[1], -k[2]], eu, ev, rs), 0.0);
    }
}

// §5.6, 5.7: reciprocity (bit for bit), the swap identity, mirrored UVs.
proptest! {
    #[test]
    fn reciprocity_swap_and_mirror(
        a in prop::array::uniform3(-1.0f64..1.0), b in prop::array::uniform3(-1.0f64..1.0),
        eu in 0.0f64..1e4, ev in 0.0f64..1e4, rs in 0.0f64..1.0, coupled in any::<bool>(),
        cov in prop::array::uniform4(0.0f64..0.5),
    ) {
        let k1 = unit([a[0], a[1], a[2].abs() + 0.05]);
        let k2 = unit([b[0], b[1], b[2].abs() + 0.05]);
        let m = double::FabricMaterial { rd_warp: [0.2, 0.5, 0.9], rd_weft: [0.7, 0.1, 0.3], rs, e_along: eu, e_across: ev, coupled, threads: false, sheet: None };
        let cov = [cov[0], cov[1], cov[2].min(cov[0]), cov[3].min(cov[1])];
        // Reciprocity, exact in both precisions.
        prop_assert_eq!(double::as_lobe(k1, k2, eu, ev, rs), double::as_lobe(k2, k1, eu, ev, rs));
        prop_assert_eq!(double::fabric_brdf(k1, k2, cov, &m), double::fabric_brdf(k2, k1, cov, &m));
        let (a32, b32) = (to32(k1), to32(k2));
        prop_assert_eq!(single::as_lobe(a32, b32, eu as f32, ev as f32, rs as f32), single::as_lobe(b32, a32, eu as f32, ev as f32, rs as f32));
        // Swap identity ρs(eu, ev; t, b) = ρs(ev, eu; b, -t): in the frame (b, -t, n) a local
        // vector (x, y, z) reads (y, -x, z). Exact.
        let rot = |k: [f64; 3]| [k[1], -k[0], k[2]];
        prop_assert_eq!(double::as_lobe(k1, k2, eu, ev, rs), double::as_lobe(rot(k1), rot(k2), ev, eu, rs));
        let rot32 = |k: [f32; 3]| [k[1], -k[0], k[2]];
        prop_assert_eq!(single::as_lobe(a32, b32, eu as f32, ev as f32, rs as f32), single::as_lobe(rot32(a32), rot32(b32), ev as f32, eu as f32, rs as f32));
        // The same through fabric_frame with world vectors: tangent b instead of t.
        let n = unit([0.2, -0.3, 0.9]);
        let t = unit([1.0, 0.1, 0.0]);
        let f1 = double::fabric_frame(n, t, 1.0);
        let f2 = double::fabric_frame(n, f1[1], 1.0);
        let w1 = [f1[0], f1[1], f1[2]];
        let world = |l: [f64; 3]| {
            let mut v = [0.0; 3];
            for c in 0..3 { v[c] = l[0] * w1[0][c] + l[1] * w1[1][c] + l[2] * w1[2][c]; }
            v
        };
        let (kw1, kw2) = (world(k1), world(k2));
        let l1 = double::fabric_local(kw1, f1);
        let l2 = double::fabric_local(kw2, f1);
        let m1 = double::fabric_local(kw1, f2);
        let m2 = double::fabric_local(kw2, f2);
        let x = double::as_lobe(l1, l2, eu, ev, rs);
        let y = double::as_lobe(m1, m2, ev, eu, rs);
        prop_assert!((x - y).abs() <= 1e-9 * x.max(1e-300) + 1e-300, "swap via frames: {} vs {}", x, y);
        // Mirrored UVs: tangent -t with w = -1 keeps b; the local x flips sign; the lobe and the
        // fabric model are unchanged.
        let f3 = double::fabric_frame(n, [-t[0], -t[1], -t[2]], -1.0);
        for c in 0..3 { prop_assert!((f3[1][c] - f1[1][c]).abs() < 1e-12); }
        let n1 = double::fabric_local(kw1, f3);
        let n2 = double::fabric_local(kw2, f3);
        let z = double::as_lobe(n1, n2, eu, ev, rs);
        prop_assert!((x - z).abs() <= 1e-9 * x.max(1e-300) + 1e-300, "mirror: {} vs {}", x, z);
    }
}

// The orientation the model page pins: a thread along t (the weft, eu = e_along large) has its
// highlight stretched ACROSS the thread: ρs falls off faster when h tilts toward t than toward b.
#[test]
fn highlight_is_stretched_across_the_thread() {
    let m = mat(200.0, 10.0, 0.04, false);
    for &deg in &[2.0f64, 5.0, 10.0, 20.0] {
        let th = deg.to_radians();
        let toward_t = [th.sin(), 0.0, th.cos()];
        let toward_b = [0.0, th.sin(), th.cos()];
        // Retro-reflection: k1 = k2 = h.
        let weft_t = double::as_lobe(toward_t, toward_t, m.e_along, m.e_across, m.rs);
        let weft_b = double::as_lobe(toward_b, toward_b, m.e_along, m.e_across, m.rs);
        let factor = if deg >= 10.0 { 0.5 } else { 1.0 };
        assert!(
            weft_t < factor * weft_b,
            "weft at {deg}°: toward t {weft_t}, toward b {weft_b}"
        );
        // The warp (thread along b) is the other way round.
        let warp_t = double::as_lobe(toward_t, toward_t, m.e_across, m.e_along, m.rs);
        let warp_b = double::as_lobe(toward_b, toward_b, m.e_across, m.e_along, m.rs);
        assert!(warp_b < factor * warp_t, "warp at {deg}°");
        // And through the full model with the weave point's coverage.
        let weft_point = [0.0, 1.0, 0.0, 1.0];
        let f_t = double::fabric_brdf(toward_t, toward_t, weft_point, &m)[0];
        let f_b = double::fabric_brdf(toward_b, toward_b, weft_point, &m)[0];
        assert!(f_t < f_b, "fabric weft at {deg}°");
    }
    // The weft is the thread along t: in a weft-up cell the point classifier says weft.
    let p = FabricParams {
        gap: 0.0,
        ..Default::default()
    };
    let c = weave_ref::weave_point_uv(
        &p,
        0.25 * p.repeat as f64 / 2.0,
        0.5 * p.repeat as f64 / 2.0,
    );
    assert_eq!((c[0], c[1]), (0.0, 1.0));
}

// ---------------------------------------------------------------------------------------------
// §5.8: the weave.

fn plain(repeat: f32, gap: f32) -> FabricParams {
    FabricParams {
        repeat,
        gap,
        ..Default::default()
    }
}

/// Class at a point: 0 gap, 1 warp, 2 weft.
fn class(c: [f64; 4]) -> u8 {
    if c[0] > 0.5 {
        1
    } else if c[1] > 0.5 {
        2
    } else {
        0
    }
}

// Eq. 2 of the model page, literally: δ = ũ·ṽ; δ < 0 → warp, δ > 0 → weft.
proptest! {
    #[test]
    fn plain_reproduces_eq_2(u in -50.0f64..50.0, v in -50.0f64..50.0, sp in 0.01f64..3.0) {
        let p = plain(sp as f32, 0.0);
        let sp = p.repeat as f64;
        let ut = u.rem_euclid(sp) - sp / 2.0;
        let vt = v.rem_euclid(sp) - sp / 2.0;
        let delta = ut * vt;
        // Away from the lines where δ changes sign (rounding could put the point on either side).
        prop_assume!(ut.abs() > 1e-9 * sp && vt.abs() > 1e-9 * sp && (ut.abs() - sp / 2.0).abs() > 1e-9 * sp && (vt.abs() - sp / 2.0).abs() > 1e-9 * sp);
        let c = weave_ref::weave_point_uv(&p, u, v);
        prop_assert_eq!(class(c), if delta > 0.0 { 2 } else { 1 });
    }
}

#[test]
fn borders_are_gap() {
    let p = plain(0.5, 0.0);
    let w = weave_ref::weave_of(&p);
    // δ = 0: ũ = 0 or ṽ = 0 (the middle lines of the repeat), and every other cell border.
    for &(x, y) in &[
        (1.0, 0.5),
        (0.5, 1.0),
        (1.0, 1.0),
        (0.0, 0.3),
        (0.7, 0.0),
        (2.0, 0.5),
        (-1.0, 0.5),
        (0.5, -3.0),
        (1e6, 0.25),
    ] {
        assert_eq!(wd::weave_point(&w, x, y), [0.0; 4], "({x}, {y})");
        assert_eq!(
            ws::weave_point(&ws::Weave::from_gpu(&p.to_gpu()), x as f32, y as f32),
            [0.0; 4]
        );
    }
    // In texture units: ũ = 0 ⇔ u = s_p/2 (mod s_p).
    assert_eq!(weave_ref::weave_point_uv(&p, 0.25, 0.1), [0.0; 4]);
    assert_eq!(weave_ref::weave_point_uv(&p, 0.1, -0.25), [0.0; 4]);
}

// The weaves weft builds in (plain, twill, satin).
fn built_in_patterns() -> [WeavePattern; 3] {
    [
        WeavePattern::plain(),
        WeavePattern::twill(),
        WeavePattern::satin(),
    ]
}

#[test]
fn huge_and_negative_coordinates_keep_the_pattern() {
    // A dyadic repeat, so shifting by whole repeats is exact in f64.
    for pattern in built_in_patterns() {
        let p = FabricParams {
            pattern,
            repeat: 0.0625,
            gap: 0.004,
            ..Default::default()
        };
        let [ru, rv] = p.repeat_uv();
        let w32 = ws::Weave::from_gpu(&p.to_gpu());
        let mut rng = weft::reference::probe::XorShift::new(11);
        let mut naive_wrong = 0;
        for _ in 0..2000 {
            let u = rng.range(0.0, ru);
            let v = rng.range(0.0, rv);
            let here = weave_ref::weave_point_uv(&p, u, v);
            for &(ku, kv) in &[
                (1e8, -3e7),
                (-1e9, 1e9),
                (-1.0, -2.0),
                (160_000_000.0, 160_000_000.0),
            ] {
                let (uu, vv) = (u + ku * ru, v + kv * rv);
                assert_eq!(
                    weave_ref::weave_point_uv(&p, uu, vv),
                    here,
                    "f64 at ({uu}, {vv})"
                );
                // The f32 path, given coordinates reduced per repeat in f64, agrees unless the
                // point is within f32 rounding of a region border.
                let [x, y] = weave_ref::reduce_to_repeat(&p, uu, vv);
                let got = ws::weave_point(&w32, x, y);
                let got = got.map(|x| x as f64);
                if class(got) != class(here) {
                    let [cx, cy] = weave_ref::uv_to_cells(&p, u, v);
                    let near = [cx.fract(), cy.fract()].iter().any(|a| {
                        let g = (p.gap / p.repeat) as f64;
                        [0.0, 1.0, g, 1.0 - g].iter().any(|b| (a - b).abs() < 1e-5)
                    });
                    assert!(
                        near,
                        "f32 reduced ({x}, {y}) class {} vs f64 {}",
                        class(got),
                        class(here)
                    );
                }
                // Without the reduction, f32 has lost the pattern at 1e7 texture units.
                if ku.abs() >= 1e8 {
                    let [nx, ny] = [
                        (uu as f32) * (2.0 / p.repeat),
                        (vv as f32) * (2.0 / p.repeat),
                    ];
                    if class(ws::weave_point(&w32, nx, ny).map(|x| x as f64)) != class(here) {
                        naive_wrong += 1;
                    }
                }
            }
        }
        assert!(
            naive_wrong > 1000,
            "f32 without reduction should lose the pattern ({naive_wrong})"
        );
    }
    // Negative coordinates: floor-modulo, not truncation.
    let p = plain(0.5, 0.0);
    assert_eq!(class(weave_ref::weave_point_uv(&p, -0.1, -0.1)), 2); // cell (1,1) of the repeat: weft
    assert_eq!(class(weave_ref::weave_point_uv(&p, -0.1, 0.1)), 1);
}

/// The analytic coverage of one whole repeat, by counting neighbours (independent of the code
/// under test): per cell, the top thread covers (1 - 2g) and is darkened over `dive` at each end
/// whose neighbour along the thread is of the other kind; the under thread shows in two strips of
/// width g, darkened over (g - q) each.
fn analytic_repeat(p: &FabricParams) -> [f64; 5] {
    let pat = p.pattern;
    let g = (p.gap / p.repeat) as f64;
    let d = p.shadow_width as f64 / 2.0;
    let dive = (d - g).clamp(0.0, 0.5);
    let q = (g - d).max(0.0);
    let (mut warp, mut weft, mut dark_warp, mut dark_weft) = (0.0, 0.0, 0.0, 0.0);
    for (i, j) in pat.cells() {
        let (i, j) = (i as isize, j as isize);
        let weft_up = pat.is_weft_up(i, j);
        let opposite = if weft_up {
            (!pat.is_weft_up(i - 1, j)) as u32 + (!pat.is_weft_up(i + 1, j)) as u32
        } else {
            pat.is_weft_up(i, j - 1) as u32 + pat.is_weft_up(i, j + 1) as u32
        };
        let top = 1.0 - 2.0 * g;
        let under = 2.0 * g * (1.0 - 2.0 * g);
        let top_dark = opposite as f64 * dive * (1.0 - 2.0 * g);
        let under_dark = 2.0 * (g - q) * (1.0 - 2.0 * g);
        if weft_up {
            weft += top;
            warp += under;
            dark_weft += top_dark;
            dark_warp += under_dark;
        } else {
            warp += top;
            weft += under;
            dark_warp += top_dark;
            dark_weft += under_dark;
        }
    }
    let cells = (pat.cols() * pat.rows()) as f64;
    let s = p.shadow_strength as f64;
    [
        warp / cells,
        weft / cells,
        (warp - s * dark_warp) / cells,
        (weft - s * dark_weft) / cells,
        1.0 - (warp + weft) / cells,
    ]
}

#[test]
fn whole_repeat_coverage_is_analytic() {
    let mut rng = weft::reference::probe::XorShift::new(3);
    let mut patterns = vec![
        WeavePattern::plain(),
        WeavePattern::twill(),
        WeavePattern::satin(),
    ];
    for _ in 0..20 {
        let (c, r) = (
            1 + (rng.next_u64() % 8) as usize,
            1 + (rng.next_u64() % 8) as usize,
        );
        let bits = rng.next_u64();
        patterns.push(WeavePattern::from_fn(c, r, |i, j| {
            bits >> (8 * j + i) & 1 == 1
        }));
    }
    for pattern in patterns {
        for &(gap, sw, ss) in &[
            (0.0, 0.25, 0.5),
            (0.005, 0.25, 0.5),
            (0.01, 0.05, 1.0),
            (0.02, 1.0, 0.3),
            (0.025, 0.5, 0.5),
            (0.0125, 0.0, 1.0),
        ] {
            let p = FabricParams {
                pattern,
                repeat: 0.05,
                gap,
                shadow_width: sw,
                shadow_strength: ss,
                ..Default::default()
            };
            let want = analytic_repeat(&p);
            let [ru, rv] = p.repeat_uv();
            // One repeat, an offset repeat, and 1000 × 700 repeats far from the origin.
            for &(u0, v0, nu, nv) in &[
                (0.0, 0.0, 1.0, 1.0),
                (-0.013, 0.021, 1.0, 1.0),
                (-3e5, 2e6, 1000.0, 700.0),
            ] {
                let c = weave_ref::weave_box_uv(&p, u0, u0 + nu * ru, v0, v0 + nv * rv);
                for k in 0..4 {
                    assert!(
                        (c[k] - want[k]).abs() < 1e-9,
                        "{} gap {gap} sw {sw}: {c:?} vs {want:?}",
                        pattern.name()
                    );
                }
            }
            if pattern == WeavePattern::plain() {
                // The closed form of docs/fabric-model.md.
                let g = (gap / 0.05) as f64;
                let sh = 1.0 - 4.0 * g * g - ss as f64 * sw as f64 * (1.0 - 2.0 * g);
                assert!(
                    (want[0] - (1.0 - 4.0 * g * g) / 2.0).abs() < 1e-12
                        && (want[2] + want[3] - sh).abs() < 1e-6
                        && (want[2] - want[3]).abs() < 1e-12,
                    "{want:?}"
                );
            }
            // The weave texture's last level is the same average.
            let t = weave_texels_cpu(&p.weave_push(1, 1));
            for k in 0..4 {
                assert!(
                    (t[0][k] as f64 - want[k]).abs() < 2e-6,
                    "texel {t:?} vs {want:?}"
                );
            }
        }
    }
}

/// Case `case` of the weave tests: plain, twill and satin in turn, with a random gap and
/// thread shadow.
fn random_weave(rng: &mut weft::reference::probe::XorShift, case: usize) -> FabricParams {
    FabricParams {
        pattern: [
            WeavePattern::plain(),
            WeavePattern::twill(),
            WeavePattern::satin(),
        ][case % 3],
        repeat: 0.05,
        gap: rng.range(0.0, 0.025) as f32,
        shadow_width: rng.next_f64() as f32,
        shadow_strength: rng.next_f64() as f32,
        ..Default::default()
    }
}

// Coverage over a box equals the mean of point samples: on an N × N midpoint grid the integrand
// is constant in every grid cell that no region border crosses, so the error is at most
// (number of border lines crossing the box) / N.
#[test]
fn box_coverage_is_the_mean_of_point_samples() {
    let mut rng = weft::reference::probe::XorShift::new(99);
    let n = 400usize;
    let mut worst = 0.0f64;
    for case in 0..60 {
        let p = random_weave(&mut rng, case);
        let w = weave_ref::weave_of(&p);
        let x0 = rng.range(-20.0, 20.0);
        let y0 = rng.range(-20.0, 20.0);
        let wx = rng.log_range(0.05, 3.0);
        let wy = rng.log_range(0.05, 3.0);
        let exact = wd::weave_box(&w, x0, y0, x0 + wx, y0 + wy);
        let mut mean = [0.0; 4];
        for i in 0..n {
            for j in 0..n {
                let x = x0 + wx * (i as f64 + 0.5) / n as f64;
                let y = y0 + wy * (j as f64 + 0.5) / n as f64;
                let c = wd::weave_point(&w, x, y);
                for k in 0..4 {
                    mean[k] += c[k] / (n * n) as f64;
                }
            }
        }
        // Border lines: at most 8 per cell crossed (0, g, 1-g, q, 1-q, dive, 1-dive, and 1), per axis.
        let lines = 8.0 * ((wx.ceil() + 1.0) + (wy.ceil() + 1.0));
        let bound = lines / n as f64;
        for k in 0..4 {
            let err = (exact[k] - mean[k]).abs();
            worst = worst.max(err / bound);
            assert!(
                err <= bound,
                "box ({x0},{y0}) {wx}x{wy}: exact {exact:?} vs mean {mean:?} (bound {bound})"
            );
        }
    }
    println!("box coverage vs {n}x{n} point samples: worst error / bound = {worst:.3}");
}

// The summed-area table (`--weave-precision sat`) against the exact f64 box coverage: boxes whose
// corners lie on the table's texel grid are exact (f32 rounding only), at any size and place,
// across repeat borders and over many repeats; any other box is off by at most the texels its
// border cuts (the table is exact for the texel-averaged weave), measured and bounded by that band.
#[test]
fn summed_area_table_gives_box_coverage() {
    use weft::fabric::{weave_level0_size, WeaveSat};
    let mut rng = weft::reference::probe::XorShift::new(1234);
    let (mut worst_aligned, mut worst_band) = (0.0f64, 0.0f64);
    for case in 0..90 {
        let p = random_weave(&mut rng, case);
        let (nw, nh) = weave_level0_size(&p.pattern);
        let push = p.weave_push(nw, nh);
        let sat = WeaveSat::new(&push);
        let w = wd::Weave::from_push(&push);
        let (cols, rows) = (push.cols as f64, push.rows as f64);
        let exact = |lo: [f64; 2], hi: [f64; 2]| {
            wd::weave_box(&w, lo[0] * cols, lo[1] * rows, hi[0] * cols, hi[1] * rows)
        };
        // Texel-aligned boxes, from one texel to three repeats, anywhere in [-4, 4] repeats.
        for _ in 0..20 {
            let snap = |x: f64, n: u32| (x * n as f64).round() / n as f64;
            let lo = [
                snap(rng.range(-4.0, 4.0), nw),
                snap(rng.range(-4.0, 4.0), nh),
            ];
            let ext = [
                snap(rng.log_range(1.0 / nw as f64, 3.0), nw).max(1.0 / nw as f64),
                snap(rng.log_range(1.0 / nh as f64, 3.0), nh).max(1.0 / nh as f64),
            ];
            let hi = [lo[0] + ext[0], lo[1] + ext[1]];
            let got = sat.box_mean([lo[0] as f32, lo[1] as f32], [hi[0] as f32, hi[1] as f32]);
            let want = exact(lo, hi);
            for k in 0..4 {
                let err = (got[k] as f64 - want[k]).abs();
                worst_aligned = worst_aligned.max(err);
                // f32: table values of order a cell's area, a one-texel box 1/(nw nh) of a repeat.
                assert!(
                    err < 2e-3,
                    "aligned box {lo:?}+{ext:?} of {}: table {got:?} vs exact {want:?}",
                    p.pattern.name()
                );
            }
        }
        // Any box: within the band of texels its border cuts.
        for _ in 0..20 {
            let lo = [rng.range(-4.0, 4.0), rng.range(-4.0, 4.0)];
            let ext = [rng.log_range(0.02, 3.0), rng.log_range(0.02, 3.0)];
            let hi = [lo[0] + ext[0], lo[1] + ext[1]];
            let got = sat.box_mean([lo[0] as f32, lo[1] as f32], [hi[0] as f32, hi[1] as f32]);
            let want = exact(lo, hi);
            let band = (2.0 * ext[1] / nw as f64 + 2.0 * ext[0] / nh as f64) / (ext[0] * ext[1]);
            for k in 0..4 {
                let err = (got[k] as f64 - want[k]).abs();
                worst_band = worst_band.max(err / band);
                assert!(
                    err <= band + 2e-3,
                    "box {lo:?}+{ext:?} of {}: table {got:?} vs exact {want:?} (band {band})",
                    p.pattern.name()
                );
            }
        }
    }
    println!(
        "summed-area table: texel-aligned boxes worst error {worst_aligned:.2e}; other boxes worst error / border band {worst_band:.3}"
    );
}

// The G-buffer takes the summed-area table's whole-table terms once per pixel, for the first
// piece only (surface.glsl): that is exact only if no piece of a footprint cut into several
// (`weave_pieces`) reaches past the table, wherever it lies. Random footprints of up to eight cells
// (cut ones are under four), every rotation and aspect, on every built-in weave: every piece of a
// cut footprint has a zero whole-table part; footprints taken whole still reach past it.
#[test]
fn summed_area_table_pieces_lie_inside_the_table() {
    use weft::fabric::{weave_level0_size, WeaveSat};
    let mut rng = weft::reference::probe::XorShift::new(4321);
    let (mut cut, mut whole_taken) = (0usize, 0usize);
    for pattern in built_in_patterns() {
        let p = FabricParams {
            pattern,
            ..Default::default()
        };
        let (nw, nh) = weave_level0_size(&p.pattern);
        let push = p.weave_push(nw, nh);
        let sat = WeaveSat::new(&push);
        let r = WeaveSat::repeats_for(push.cols, push.rows);
        assert_eq!(sat.repeats(), r as f32);
        assert!(r as f32 >= 1.0 + 4.0 / push.cols.min(push.rows) as f32);
        let cells = [push.cols as f32, push.rows as f32];
        for _ in 0..4000 {
            // A footprint's edges in cells: length 0.05 to 8, any direction.
            let edge = |rng: &mut weft::reference::probe::XorShift| {
                let (len, a) = (rng.log_range(0.05, 8.0), rng.range(0.0, 2.0 * PI));
                [(len * a.cos()) as f32, (len * a.sin()) as f32]
            };
            let (dx, dy) = (edge(&mut rng), edge(&mut rng));
            let k = ws::weave_pieces(dx, dy, 2 + (rng.next_f64() * 2.0) as u32);
            // In repeats, as the shader has them; the centre anywhere in the first repeat.
            let (sdx, sdy) = (
                [dx[0] / cells[0], dx[1] / cells[1]],
                [dy[0] / cells[0], dy[1] / cells[1]],
            );
            let half = ws::weave_piece_half(sdx, sdy, k);
            let c = [rng.next_f64() as f32, rng.next_f64() as f32];
            for n in 0..k[0] * k[1] {
                let pc = ws::weave_piece_centre(c, sdx, sdy, k, n);
                let lo = [pc[0] - half[0], pc[1] - half[1]];
                let hi = [pc[0] + half[0], pc[1] + half[1]];
                let w = sat.box_whole(lo, hi);
                if k == [1, 1] {
                    whole_taken += w.iter().any(|x| *x != 0.0) as usize;
                    continue;
                }
                cut += 1;
                assert_eq!(
                    w,
                    [0.0; 4],
                    "piece {n} of {k:?} at {c:?}, edges {dx:?} {dy:?} cells, of {}: past the table ({r} repeats)",
                    p.pattern.name()
                );
            }
        }
    }
    println!("{cut} pieces of cut footprints inside the table; {whole_taken} whole footprints used the whole-table part");
    assert!(
        cut > 1000 && whole_taken > 100,
        "the cases must cover both: {cut} cut pieces, {whole_taken} whole"
    );
}

#[test]
fn gap_limits() {
    // s_g = 0: no gap anywhere but on borders; a whole repeat has no gap.
    let p = plain(0.05, 0.0);
    let mut rng = weft::reference::probe::XorShift::new(5);
    for _ in 0..10_000 {
        let c = weave_ref::weave_point_uv(&p, rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        assert_eq!(c[0] + c[1], 1.0);
    }
    let c = weave_ref::weave_box_uv(&p, 0.0, 0.05, 0.0, 0.05);
    assert!((c[0] + c[1] - 1.0).abs() < 1e-12);
    // s_g = s_p/2: everything is gap. s_g → s_p/2: the thread area → 0 continuously.
    let p = plain(0.05, 0.025);
    for _ in 0..10_000 {
        assert_eq!(
            weave_ref::weave_point_uv(&p, rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)),
            [0.0; 4]
        );
    }
    assert_eq!(weave_ref::weave_box_uv(&p, 0.0, 0.05, 0.0, 0.05), [0.0; 4]);
    for eps in [1e-2f32, 1e-4, 1e-6] {
        let p = plain(0.05, 0.025 * (1.0 - eps));
        let c = weave_ref::weave_box_uv(&p, 0.0, 0.05, 0.0, 0.05);
        let g = (p.gap / p.repeat) as f64;
        assert!(
            (c[0] + c[1] - (1.0 - 4.0 * g * g)).abs() < 1e-9 && c[0] + c[1] < 3.0 * eps as f64,
            "{eps}: {c:?}"
        );
    }
    // Loading clamps s_g > s_p/2 with a warning.
    let mut w = Vec::new();
    let q = FabricParams::from_gltf_extension(
        &serde_json::json!({"repeat": 0.05, "gap": 0.1}),
        "m",
        &mut w,
    )
    .unwrap();
    assert_eq!(q.gap, 0.025);
    assert_eq!(w.len(), 1);
}

#[test]
fn repeat_to_zero() {
    // s_p → 0 (clamped at 1e-6 on load): a footprint of one texture unit covers 10^12 repeats and
    // its coverage is the repeat average; points still classify.
    let mut w = Vec::new();
    let p = FabricParams::from_gltf_extension(
        &serde_json::json!({"repeat": 0.0, "gap": 0.0}),
        "m",
        &mut w,
    )
    .unwrap();
    assert_eq!(p.repeat, 1e-6);
    assert_eq!(w.len(), 1);
    let p = FabricParams { gap: 1e-7, ..p };
    let want = analytic_repeat(&p);
    let c = weave_ref::weave_box_uv(&p, -0.3, 0.7, 0.2, 1.2);
    for k in 0..4 {
        assert!((c[k] - want[k]).abs() < 1e-6, "{c:?} vs {want:?}");
    }
    let c = weave_ref::weave_point_uv(&p, 0.123456789, 0.987654321);
    assert!(c.iter().all(|x| x.is_finite()));
    // Tiny footprints far away are still exact (reduced per repeat in f64 before subtracting).
    let p = plain(0.05, 0.005);
    let a = weave_ref::weave_box_uv(&p, 0.0101, 0.0102, 0.0301, 0.0302);
    let b = weave_ref::weave_box_uv(
        &p,
        0.0101 + 0.05 * 2e7,
        0.0102 + 0.05 * 2e7,
        0.0301 - 0.05 * 3e7,
        0.0302 - 0.05 * 3e7,
    );
    for k in 0..4 {
        assert!((a[k] - b[k]).abs() < 1e-4, "{a:?} vs {b:?}");
    }
}

// Mirrored UVs on the weave: the pattern at -u is the column-mirrored pattern at u.
#[test]
fn mirrored_uvs_mirror_the_pattern() {
    let mut rng = weft::reference::probe::XorShift::new(17);
    for pattern in [
        WeavePattern::plain(),
        WeavePattern::twill(),
        WeavePattern::satin(),
        WeavePattern::from_rows(&["--|", "|-|"]).unwrap(),
    ] {
        let p = FabricParams {
            pattern,
            repeat: 0.5,
            gap: 0.03,
            shadow_width: 0.6,
            ..Default::default()
        };
        let m = FabricParams {
            pattern: pattern.mirrored_u(),
            ..p.clone()
        };
        let (wp, wm) = (weave_ref::weave_of(&p), weave_ref::weave_of(&m));
        for _ in 0..5000 {
            let x = rng.range(-30.0, 30.0);
            let y = rng.range(-30.0, 30.0);
            assert_eq!(
                wd::weave_point(&wp, -x, y),
                wd::weave_point(&wm, x, y),
                "({x}, {y})"
            );
            let (w, h) = (rng.range(0.01, 3.0), rng.range(0.01, 3.0));
            let a = wd::weave_box(&wp, -x - w, y, -x, y + h);
            let b = wd::weave_box(&wm, x, y, x + w, y + h);
            for k in 0..4 {
                assert!((a[k] - b[k]).abs() < 1e-12);
            }
        }
    }
}

// The weave texture: every level's texels are the exact coverage of their footprints (the f32
// path against f64), and the texels of a level partition the repeat.
#[test]
fn weave_texture_levels_are_exact() {
    for pattern in [
        WeavePattern::plain(),
        WeavePattern::twill(),
        WeavePattern::satin(),
        WeavePattern::from_rows(&["--|", "|-|"]).unwrap(),
    ] {
        let p = FabricParams {
            pattern,
            ..Default::default()
        };
        let level0 = weft::fabric::weave_level0_size(&pattern);
        let w64 = weave_ref::weave_of(&p);
        let avg = analytic_repeat(&p);
        for level in 0..weft::fabric::weave_mip_count(level0) {
            let (w, h) = weave_level_size(level0, level);
            let texels = weave_texels_cpu(&p.weave_push(w, h));
            assert_eq!(texels.len(), (w * h) as usize);
            let mut mean = [0.0; 4];
            let (cols, rows) = (pattern.cols() as f64, pattern.rows() as f64);
            for y in 0..h {
                for x in 0..w {
                    let t = texels[(y * w + x) as usize];
                    let e = wd::weave_box(
                        &w64,
                        x as f64 * cols / w as f64,
                        y as f64 * rows / h as f64,
                        (x + 1) as f64 * cols / w as f64,
                        (y + 1) as f64 * rows / h as f64,
                    );
                    for k in 0..4 {
                        assert!(
                            (t[k] as f64 - e[k]).abs() < 1e-4,
                            "level {level} texel ({x},{y}): {t:?} vs {e:?}"
                        );
                        mean[k] += t[k] as f64 / (w * h) as f64;
                    }
                }
            }
            for k in 0..4 {
                assert!(
                    (mean[k] - avg[k]).abs() < 1e-5,
                    "level {level} mean {mean:?} vs {avg:?}"
                );
            }
        }
    }
}

// No NaN or Inf from any function, for wild (but sanitised) inputs.
proptest! {
    #[test]
    fn nothing_is_ever_nan(
        a in prop::array::uniform3(-2.0f32..2.0), b in prop::array::uniform3(-2.0f32..2.0),
        scale in prop::sample::select(vec![0.0f32, 1e-30, 1e-7, 1.0, 1e7]),
        eu in prop::sample::select(vec![0.0f32, 0.1, 1.0, 1e4, 1e6]), ev in 0.0f32..1e6,
        rs in 0.0f32..=1.0, cov in prop::array::uniform4(0.0f32..=1.0), coupled in any::<bool>(),
        x in -1e4f32..1e4, y in -1e4f32..1e4, wx in prop::sample::select(vec![0.0f32, 1e-6, 0.01, 1.0, 300.0]),
    ) {
        let k1 = [a[0] * scale, a[1] * scale, a[2]];
        let k2 = [b[0], b[1] * scale, b[2] * scale];
        let m = single::FabricMaterial { rd_warp: [1.0; 3], rd_weft: [0.5; 3], rs, e_along: eu, e_across: ev, coupled, threads: false, sheet: None };
        let f = single::fabric_brdf(k1, k2, cov, &m);
        prop_assert!(f.iter().all(|v| v.is_finite() && *v >= 0.0), "{:?}", f);
        let (h, kh) = single::fabric_half(k1, k2);
        prop_assert!(single::as_d(h, eu, ev).is_finite() && kh.is_finite());
        prop_assert!(single::as_exponent(h[0], h[1], eu, ev).is_finite());
        let fr = single::fabric_frame(k1, k2, a[0]);
        prop_assert!(fr.iter().flatten().all(|v| v.is_finite()));
        let p = FabricParams { gap: (cov[0] * 0.025).min(0.025), shadow_width: cov[1], ..Default::default() };
        let w = ws::Weave::from_gpu(&p.to_gpu());
        let c = ws::weave_point(&w, x, y);
        prop_assert!(c.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)));
        let [rx, ry] = [ws::weave_wrap(x, 2.0), ws::weave_wrap(y, 2.0)];
        let c = ws::weave_box(&w, rx, ry, rx + wx, ry + wx * 0.5);
        prop_assert!(c.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)), "{:?}", c);
        prop_assert!(c[2] <= c[0] + 1e-6 && c[3] <= c[1] + 1e-6);
    }
}

// ---------------------------------------------------------------------------------------------
// §5.6: the white furnace, and the sampler's pdf.

#[test]
fn importance_sampling_pdf_integrates_to_one() {
    // ∫ D(h) dω_h = 1, by quadrature in φ and in t = -ln(cos θ) (step scaled per φ to the lobe).
    for &(eu, ev) in &[
        (0.0f64, 0.0f64),
        (1.0, 10.0),
        (10.0, 100.0),
        (200.0, 10.0),
        (1e4, 1e4),
        (1e4, 0.1),
        (1e6, 1.0),
    ] {
        // Fine enough in φ for the narrowest lobe: its width in φ is sqrt(min/max) of (e + 1).
        let ratio = (eu.max(ev) + 1.0) / (eu.min(ev) + 1.0);
        let nphi = (2048.0 * (ratio.sqrt() / 30.0).max(1.0)) as usize;
        let mut total = 0.0;
        for i in 0..nphi {
            let phi = 2.0 * PI * (i as f64 + 0.5) / nphi as f64;
            let e = eu * phi.cos().powi(2) + ev * phi.sin().powi(2);
            let tmax = 60.0 / (e + 1.0);
            let nt = 400;
            let dt = tmax / nt as f64;
            let mut inner = 0.0;
            for k in 0..nt {
                let t = (k as f64 + 0.5) * dt;
                let mu: f64 = (-t).exp();
                let st = (1.0 - mu * mu).max(0.0).sqrt();
                let h = [st * phi.cos(), st * phi.sin(), mu];
                // dω = dμ dφ = μ dt dφ.
                inner += double::as_d(h, eu, ev) * mu * dt;
            }
            total += inner * 2.0 * PI / nphi as f64;
        }
        assert!(
            (total - 1.0).abs() < 2e-3,
            "∫D dω = {total} for ({eu},{ev})"
        );
    }
    // The sampler draws h with pdf D: E[g(h)] over samples = ∫ g D dω (quadrature, moderate e).
    for &(eu, ev) in &[(2.0, 30.0), (50.0, 5.0)] {
        let g = |h: [f64; 3]| 1.0 + h[0] * h[0] * 3.0 + 0.5 * h[1] + h[0] * h[1];
        let n = 512;
        let mut mc = 0.0;
        for i in 0..n {
            for j in 0..n {
                let h = sampling::sample_h(
                    eu,
                    ev,
                    (i as f64 + 0.5) / n as f64,
                    (j as f64 + 0.5) / n as f64,
                );
                mc += g(h) / (n * n) as f64;
            }
        }
        let mut quad = 0.0;
        let (nm, nphi) = (2000, 512);
        for i in 0..nm {
            let mu = (i as f64 + 0.5) / nm as f64;
            let st = (1.0 - mu * mu).sqrt();
            for j in 0..nphi {
                let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
                let h = [st * phi.cos(), st * phi.sin(), mu];
                quad += g(h) * double::as_d(h, eu, ev) / nm as f64 * 2.0 * PI / nphi as f64;
            }
        }
        assert!(
            (mc - quad).abs() < 2e-3 * quad,
            "sampler E[g] {mc} vs ∫gD {quad}"
        );
    }
    // pdf(k2) integrates to the fraction of samples that land above the surface.
    for &(eu, ev, th) in &[
        (10.0f64, 100.0f64, 0.3f64),
        (5.0, 5.0, 1.2),
        (100.0, 1.0, 1.45),
    ] {
        let k1 = [th.sin(), 0.0, th.cos()];
        let n = 400;
        let mut valid = 0usize;
        for i in 0..n {
            for j in 0..n {
                if sampling::sample_k2(
                    k1,
                    eu,
                    ev,
                    (i as f64 + 0.5) / n as f64,
                    (j as f64 + 0.5) / n as f64,
                )
                .is_some()
                {
                    valid += 1;
                }
            }
        }
        let frac = valid as f64 / (n * n) as f64;
        let (nm, nphi) = (2000, 1024);
        let mut integral = 0.0;
        for i in 0..nm {
            let mu = (i as f64 + 0.5) / nm as f64;
            let st = (1.0 - mu * mu).sqrt();
            for j in 0..nphi {
                let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
                integral += sampling::pdf_k2(k1, [st * phi.cos(), st * phi.sin(), mu], eu, ev)
                    / nm as f64
                    * 2.0
                    * PI
                    / nphi as f64;
            }
        }
        assert!(
            integral <= 1.0 + 1e-3 && (integral - frac).abs() < 5e-3,
            "θ {th}: ∫pdf {integral} vs valid fraction {frac}"
        );
    }
}

#[test]
fn white_furnace() {
    let angles = [0.0f64, 30.0, 60.0, 80.0, 89.0];
    let lobes = [
        (1.0, 1.0),
        (10.0, 1.0),
        (200.0, 10.0),
        (1e4, 10.0),
        (1e6, 1e6),
    ];
    let n = 256;
    println!(
        "White furnace: albedo ∫ f (n·k2) dω2 of a weft-covered point (c_weft = 1, s = 1), Rd = 1."
    );
    println!(
        "{:>8} {:>12} {:>5} | {:>8} {:>8} | {:>14} {:>14}",
        "θ1 (°)", "e_along/ac", "Rs", "lobe", "coupled", "Lambert+lobe", "coupled+lobe"
    );
    let mut worst_coupled: f64 = 0.0;
    for &rs in &[0.0, 0.04, 0.5, 1.0] {
        for &(ea, ec) in &lobes {
            for &deg in &angles {
                let th = deg.to_radians();
                let k1 = [th.sin(), 0.0, th.cos()];
                let lobe = lobe_albedo(k1, ea, ec, rs, n);
                let dc = diffuse_albedo(k1[2], rs, true);
                let lambert =
                    fabric_albedo(k1, &mat(ea, ec, rs, false), [0.0, 1.0, 0.0, 1.0], n)[0];
                let coupled = fabric_albedo(k1, &mat(ea, ec, rs, true), [0.0, 1.0, 0.0, 1.0], n)[0];
                assert!(lobe <= 1.0 + 1e-9, "lobe albedo {lobe}");
                assert!((lambert - (1.0 + lobe)).abs() < 1e-9);
                assert!((coupled - (dc + lobe)).abs() < 1e-9);
                worst_coupled = worst_coupled.max(coupled);
                println!(
                    "{deg:>8.0} {:>12} {rs:>5} | {lobe:>8.4} {dc:>8.4} | {lambert:>14.4} {coupled:>14.4}",
                    format!("{ea}/{ec}")
                );
            }
        }
    }
    println!("largest albedo with the coupled diffuse: {worst_coupled:.4}");
    assert!(
        worst_coupled <= 1.0 + 2e-3,
        "coupled diffuse + lobe exceeds 1: {worst_coupled}"
    );
    // Mixed coverage and shadow only lower it: a texel of a real weave.
    let p = FabricParams {
        coupled_diffuse: true,
        rd_warp: [1.0; 3],
        rd_weft: [1.0; 3],
        ..Default::default()
    };
    let cov = weave_ref::weave_box_uv(&p, 0.0, 0.05, 0.0, 0.05);
    let m = double::FabricMaterial::from_gpu(&p.to_gpu());
    let a = fabric_albedo([0.5f64.sin(), 0.0, 0.5f64.cos()], &m, cov, n)[0];
    assert!(a <= 1.0, "{a}");
}

// The importance-sampled furnace agrees with brute-force quadrature where quadrature works.
#[test]
fn furnace_integrators_agree() {
    for &(ea, ec, rs, coupled, th) in &[
        (1.0, 1.0, 0.04, false, 0.3),
        (10.0, 2.0, 0.5, true, 1.0),
        (20.0, 5.0, 1.0, false, 0.0),
    ] {
        let k1 = [f64::sin(th), 0.0, f64::cos(th)];
        let m = mat(ea, ec, rs, coupled);
        let cov = [0.3, 0.6, 0.25, 0.55];
        let is = fabric_albedo(k1, &m, cov, 400)[0];
        let q = fabric_albedo_quadrature(k1, &m, cov, 1000)[0];
        assert!(
            (is - q).abs() < 5e-3 * q.max(0.1),
            "IS {is} vs quadrature {q}"
        );
    }
}

// The filtered-params level (one lobe, averaged exponents) equals the mixture at a point and not
// over a footprint that holds both threads: that is the error the accuracy levels measure.
#[test]
fn averaged_exponents_only_agree_at_a_point() {
    let m = mat(200.0, 10.0, 0.04, false);
    let k1 = unit([0.3, 0.05, 0.9]);
    let k2 = unit([-0.25, 0.2, 0.9]);
    for cov in [[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 0.5], [0.0; 4]] {
        assert_eq!(
            double::fabric_brdf_averaged(k1, k2, cov, &m),
            double::fabric_brdf(k1, k2, cov, &m)
        );
    }
    // The specular part alone (Rd = 0).
    let m = double::FabricMaterial {
        rd_warp: [0.0; 3],
        rd_weft: [0.0; 3],
        ..m
    };
    let cov = [0.5, 0.5, 0.5, 0.5];
    let mut worst: f64 = 0.0;
    for deg in [5.0f64, 10.0, 20.0] {
        for phi in [0.0f64, 45.0, 90.0] {
            let (th, ph) = (deg.to_radians(), phi.to_radians());
            let h = [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()];
            let a = double::fabric_brdf_averaged(h, h, cov, &m)[0];
            let b = double::fabric_brdf(h, h, cov, &m)[0];
            worst = worst.max((a - b).abs() / b);
        }
    }
    assert!(
        worst > 0.5,
        "averaged exponents should differ from the mixture: {worst}"
    );
}

// §5.10 as the BRDF sees it: NaN, infinite, zero and parallel normals and tangents give a finite
// orthonormal frame (the CPU twin; on the GPU NaN must not arrive, see reference::probe).
#[test]
fn degenerate_frames_are_finite_and_orthonormal() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let cases: [([f32; 3], [f32; 3], f32); 8] = [
        ([nan, 0.0, 1.0], [1.0, 0.0, 0.0], 1.0),
        ([inf, 0.0, 0.0], [1.0, 0.0, 0.0], 1.0),
        ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], -1.0),
        ([0.0, 0.0, 1.0], [0.0, 0.0, 0.0], 1.0),
        ([0.0, 0.0, 1.0], [0.0, 0.0, 3.0], 1.0),
        ([0.0, 0.0, 1.0], [nan, nan, nan], 1.0),
        ([0.0, 0.0, -1.0], [1.0, 0.0, 0.0], nan),
        ([0.0, 1e-20, 0.0], [1e-20, 0.0, 0.0], 0.0),
    ];
    for (n, t, s) in cases {
        let f = single::fabric_frame(n, t, s);
        for a in 0..3 {
            assert!(f[a].iter().all(|x| x.is_finite()), "{n:?} {t:?}: {f:?}");
            for b in 0..3 {
                let d = single::dot(f[a], f[b]);
                let want = if a == b { 1.0 } else { 0.0 };
                assert!(
                    (d - want).abs() < 1e-5,
                    "{n:?} {t:?}: frame not orthonormal {f:?}"
                );
            }
        }
    }
    // Boxes too small for f32 fall back to the centre point instead of dividing by ~0.
    let w = ws::Weave::from_gpu(&FabricParams::default().to_gpu());
    for (wx, wy) in [(1e-30f32, 1e-30f32), (1e-7, 1.0), (1.0, 0.0), (-1.0, 1.0)] {
        let c = ws::weave_box(&w, 0.3, 0.4, 0.3 + wx, 0.4 + wy);
        assert!(c.iter().all(|v| v.is_finite()), "{wx} {wy}: {c:?}");
    }
}
