//! Thread-by-thread colours (stripes, checks, tartans; `warp_colours` / `weft_colours` of
//! `WEFT_materials_fabric`, a draft's `[WARP COLORS]` / `[WEFT COLORS]`): the colour table against
//! the exact footprint colour in f64, and on lavapipe (validation on) the G-buffer's thread colour
//! up close (each thread exactly its colour) and far away (the right mean).

mod common;

use glam::Vec3;
use weft::fabric::{FabricParams, ThreadColourTable, WeavePattern};
use weft::reference::shading::srgb_decode;
use weft::reference::weave::{double, weave_of};
use weft::render::{RenderOptions, Renderer};
use weft::scene::{Light, LightKind, Scene};

const RED: [f32; 3] = [0.8, 0.05, 0.05];
const GREEN: [f32; 3] = [0.05, 0.6, 0.1];
const BLUE: [f32; 3] = [0.05, 0.1, 0.7];
const CREAM: [f32; 3] = [0.9, 0.85, 0.7];
const BLACK: [f32; 3] = [0.02, 0.02, 0.02];

/// A 2/2 twill (4 x 4 cells) with three warp colours and two weft colours: the colours repeat
/// every lcm(4, 3) = 12 warp threads and lcm(4, 2) = 4 picks.
fn striped(repeat: f32) -> FabricParams {
    FabricParams {
        pattern: WeavePattern::by_name("twill").expect("twill"),
        repeat,
        gap: 0.1 * repeat / 2.0,
        warp_colours: vec![RED, GREEN, BLUE],
        weft_colours: vec![CREAM, BLACK],
        ..Default::default()
    }
}

/// The exact shadow-weighted thread colour over the box [x0, x1] x [y0, y1] of cells (f64):
/// each cell's part of the box has one warp and one weft thread.
fn exact_colour(p: &FabricParams, x0: f64, y0: f64, x1: f64, y1: f64) -> [f64; 3] {
    let w = weave_of(p);
    let (mut sum, mut s) = ([0.0f64; 3], 0.0f64);
    for j in y0.floor() as i64..y1.ceil() as i64 {
        let (ya, yb) = ((j as f64).max(y0), ((j + 1) as f64).min(y1));
        for i in x0.floor() as i64..x1.ceil() as i64 {
            let (xa, xb) = ((i as f64).max(x0), ((i + 1) as f64).min(x1));
            if xb <= xa || yb <= ya {
                continue;
            }
            let a = (xb - xa) * (yb - ya);
            let c = double::weave_box(&w, xa, ya, xb, yb);
            let cw = p.thread_colour(true, i.rem_euclid(1 << 20) as usize);
            let cf = p.thread_colour(false, j.rem_euclid(1 << 20) as usize);
            for k in 0..3 {
                sum[k] += a * (c[2] * cw[k] as f64 + c[3] * cf[k] as f64);
            }
            s += a * (c[2] + c[3]);
        }
    }
    sum.map(|v| v / s)
}

#[test]
fn the_colour_table_gives_the_footprint_colour() {
    let p = striped(0.1);
    let t = ThreadColourTable::new(&p)
        .expect("valid")
        .expect("has colours");
    assert_eq!(t.repeat_cells, [12, 4]);
    let (cols, rows) = (4u32, 4u32);
    let mut rng = weft::reference::probe::XorShift::new(0xc01045);
    let w32 = weft::reference::weave::single::Weave::from_gpu(&p.to_gpu());
    let (mut worst_in_cell, mut worst_ratio) = (0.0f64, 0.0f64);
    for case in 0..3000 {
        // Boxes from a tenth of a cell to four cells, anywhere in the colour repeat.
        let side = [0.1f64, 0.4, 0.9, 1.7, 4.0][case % 5];
        let x0 = rng.range(0.0, 12.0);
        let y0 = rng.range(0.0, 4.0);
        let (wx, wy) = (side * rng.range(0.5, 1.0), side * rng.range(0.5, 1.0));
        let (x1, y1) = (x0 + wx, y0 + wy);
        let want = exact_colour(&p, x0, y0, x1, y1);
        // The twin in st (weave repeats), with the box's coverage as the shader has it.
        let st = |x: f64, n: u32| (x / n as f64) as f32;
        let (lo, hi) = ([st(x0, cols), st(y0, rows)], [st(x1, cols), st(y1, rows)]);
        let cov = weft::reference::weave::single::weave_box(
            &w32, x0 as f32, y0 as f32, x1 as f32, y1 as f32,
        );
        let coverage = |a: [f32; 2], b: [f32; 2]| {
            weft::reference::weave::single::weave_box(
                &w32,
                a[0] * 4.0,
                a[1] * 4.0,
                b[0] * 4.0,
                b[1] * 4.0,
            )
        };
        let got = t.colour(cols, rows, lo, hi, cov, &coverage, [1.0; 3]);
        let err = (0..3)
            .map(|k| (got[k] as f64 - want[k]).abs())
            .fold(0.0, f64::max);
        let near = x1.ceil() - 1.0 - x0.floor() <= 1.0 && y1.ceil() - 1.0 - y0.floor() <= 1.0;
        if near {
            // Exact: each cell's two colours weighted by its part's own coverage (f32).
            worst_in_cell = worst_in_cell.max(err);
            assert!(
                err < 2e-4,
                "box [{x0}, {x1}] x [{y0}, {y1}]: {got:?} against {want:?}"
            );
        } else {
            // The table resolves an eighth of a cell here (texels per cell): only the texels the
            // box's border cuts are averaged. Their share of the box, times the largest colour
            // step (1) over the threads' share of it (at least 0.7 here), bounds the error.
            let c = t.texels_per_cell as f64;
            let band = ((2.0 / c) * (wx + wy) / (wx * wy)).min(1.0);
            let bound = band / 0.7 + 1e-4;
            worst_ratio = worst_ratio.max(err / bound);
            assert!(
                err <= bound,
                "box [{x0}, {x1}] x [{y0}, {y1}]: {got:?} against {want:?} (bound {bound})"
            );
        }
    }
    println!(
        "up to 2 x 2 cells: worst {worst_in_cell:.2e}; larger boxes: worst {worst_ratio:.3} of the border-band bound"
    );
    // The far field's albedo (`weft fabric`'s fallback colour), summed cell by cell, is the
    // table's mean.
    let far = weft::assets::far_field_albedo(&p);
    let mean = t.table.texels[t.table.width as usize - 1];
    for k in 0..3 {
        assert!(
            (far[k] - mean[k] as f64).abs() < 1e-6,
            "{far:?} against {mean:?}"
        );
    }
    // Whole colour repeats: the table's mean is the far field's colour.
    let want = exact_colour(&p, 0.0, 0.0, 12.0, 4.0);
    let none = |_: [f32; 2], _: [f32; 2]| [0.0f32; 4];
    let got = t.colour(
        cols,
        rows,
        [0.0, 0.0],
        [3.0, 1.0],
        [0.0; 4],
        &none,
        [1.0; 3],
    );
    for k in 0..3 {
        assert!(
            (got[k] as f64 - want[k]).abs() < 1e-5,
            "{got:?} against {want:?}"
        );
    }
}

#[test]
fn sequences_are_checked_where_they_are_read() {
    let mut warnings = Vec::new();
    let bad = [
        (serde_json::json!({"warp_colours": []}), "1 to 256 colours"),
        (
            serde_json::json!({"warp_colours": [[0.1, 0.2]]}),
            "warp_colours[0]",
        ),
        (serde_json::json!({"weft_colours": "red"}), "weft_colours"),
        // A 7-colour warp on a 5-harness satin and a 103-colour weft on it: 35 x 515 cells.
        (
            serde_json::json!({"pattern": "satin", "warp_colours": vec![[0.5; 3]; 7], "weft_colours": vec![[0.5; 3]; 103]}),
            "repeat every 35 x 515 cells",
        ),
    ];
    for (v, says) in bad {
        let e = FabricParams::from_gltf_extension(&v, "plaid", &mut warnings)
            .err()
            .unwrap_or_else(|| panic!("{v} was accepted"));
        let e = e.to_string();
        assert!(e.contains("material 'plaid'") && e.contains(says), "{e}");
    }
    let p = FabricParams::from_gltf_extension(
        &serde_json::json!({"warp_colours": [[1.5, 0.0, 0.0], 0.25], "weft_colours": [[0.0, 0.0, 1.0]]}),
        "plaid",
        &mut warnings,
    )
    .expect("valid");
    assert_eq!(p.warp_colours, vec![[1.0, 0.0, 0.0], [0.25; 3]]);
    assert_eq!(p.weft_colours, vec![[0.0, 0.0, 1.0]]);
    assert!(
        warnings.iter().any(|w| w.0.contains("warp_colours[0][0]")),
        "{warnings:?}"
    );
    // Written out by `weft fabric` and read back the same.
    let json = weft::assets::extension_json(&p);
    let back = FabricParams::from_gltf_extension(&json, "plaid", &mut Vec::new()).expect("reads");
    assert_eq!(
        (back.warp_colours, back.weft_colours),
        (p.warp_colours, p.weft_colours)
    );
}

#[test]
fn a_tartan_draft_gives_its_colour_sequences() {
    let d = weft::fabric::draft::Draft::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/drafts/tartan-twill.wif"
    )))
    .expect("the draft reads");
    let mut o = weft::assets::Overrides::default();
    let warnings = o.apply_draft(&d);
    assert!(warnings.is_empty(), "{warnings:?}");
    let warp = o.warp_colours.expect("the warp is striped");
    let weft = o.weft_colours.expect("the weft is striped");
    // The draft spells the sett out twice; the sequence is the sett once: 6 green, 2 black,
    // 2 red, 2 black.
    assert_eq!((warp.len(), weft.len()), (12, 12));
    assert_eq!(warp[0], warp[5]);
    assert_ne!(warp[5], warp[6]);
    assert_eq!(warp[8], warp[9]);
    assert_eq!(warp[6], warp[10]);
    assert_eq!(warp, weft);
    assert!(warp[8][0] > 0.5 && warp[0][1] > warp[0][0], "{warp:?}");
}

/// `common::fabric_patch` under a lamp straight above.
fn patch(fabric: FabricParams) -> Scene {
    common::fabric_patch(
        fabric,
        [0.0, 0.0],
        Light {
            name: "lamp".into(),
            kind: LightKind::Directional,
            color: [1.0; 3],
            intensity: 2.0,
            range: None,
            position: Vec3::ZERO,
            direction: Vec3::NEG_Y,
            shadow: None,
        },
    )
}

/// Renders the patch from straight above at `height` (90° field of view, 128 x 128: the image
/// spans x, z in [-height, height]; screen x is -X, screen y is -Z) and returns the G-buffer.
fn top_view(renderer: &mut Renderer, scene: &Scene, height: f32) -> weft::render::GBufferReadback {
    let camera = scene
        .look_at_camera(Vec3::new(0.0, height, 0.0), Vec3::ZERO, 90f32.to_radians())
        .unwrap();
    let options = RenderOptions {
        width: 128,
        height: 128,
        camera_override: Some(camera),
        ..Default::default()
    };
    renderer.render(scene, &options).expect("render");
    renderer.read_gbuffer().expect("gbuffer")
}

#[test]
fn up_close_each_thread_has_its_colour_and_far_away_the_mean() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    // Up close: cells 0.125 wide, 16 pixels each.
    let p = striped(0.25);
    let g = top_view(&mut renderer, &patch(p.clone()), 0.5);
    let w = weave_of(&p);
    let cell = |x: f64| x * 2.0 / 0.25;
    let (mut checked, mut seen) = (0usize, std::collections::BTreeSet::new());
    for py in 0..128usize {
        for px in 0..128usize {
            // The pixel's footprint in cells (x = u, v = -z; a pixel is 1/128 m). Looking down
            // with +Z up on the screen, screen x is world -X and screen y (down) world -Z.
            let x = |dx: f64| cell(-((px as f64 + 0.5 + dx) / 64.0 - 1.0) * 0.5);
            let y = |dy: f64| cell(((py as f64 + 0.5 + dy) / 64.0 - 1.0) * 0.5);
            let corners = [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)]
                .map(|(dx, dy)| double::weave_point(&w, x(dx), y(dy)));
            let (i, j) = (x(0.0).floor() as i64, y(0.0).floor() as i64);
            let same_cell = [(-0.5, -0.5), (0.5, 0.5)]
                .iter()
                .all(|&(dx, dy)| x(dx).floor() as i64 == i && y(dy).floor() as i64 == j);
            let want = if same_cell && corners.iter().all(|c| c[0] == 1.0) {
                p.thread_colour(true, i.rem_euclid(3) as usize)
            } else if same_cell && corners.iter().all(|c| c[1] == 1.0) {
                p.thread_colour(false, j.rem_euclid(2) as usize)
            } else {
                continue;
            };
            let k = (py * 128 + px) * 4;
            // The mapping above is right: the G-buffer's coverage is the thread's alone.
            let on_top = if corners[0][0] == 1.0 { 0 } else { 1 };
            assert!(
                g.fabric[k + on_top] > 0.99,
                "pixel ({px}, {py}): coverage {:?}",
                &g.fabric[k..k + 4]
            );
            let got = [g.albedo[k], g.albedo[k + 1], g.albedo[k + 2]];
            let want8 = want.map(weft::reference::shading::srgb_encode);
            for c in 0..3 {
                assert!(
                    (got[c] as i32 - want8[c] as i32).abs() <= 1,
                    "pixel ({px}, {py}), cell ({i}, {j}): albedo {got:?}, the thread's colour {want8:?}"
                );
            }
            seen.insert(want8);
            checked += 1;
        }
    }
    println!(
        "up close: {checked} pixels inside one thread, {} colours",
        seen.len()
    );
    assert!(
        checked > 2000 && seen.len() == 5,
        "{checked} pixels, colours {seen:?}"
    );

    // Far away: 8 cells a pixel (the colours repeat every 12 x 4 cells). The mean of the
    // G-buffer's thread colour over the patch is the repeat's Σ s·colour / Σ s.
    let p = striped(0.004);
    let g = top_view(&mut renderer, &patch(p.clone()), 1.0);
    let want = exact_colour(&p, 0.0, 0.0, 12.0, 4.0);
    let mut mean = [0.0f64; 3];
    let pixels = 128 * 128;
    for i in 0..pixels {
        for c in 0..3 {
            mean[c] += srgb_decode(g.albedo[i * 4 + c] as f32 / 255.0) as f64 / pixels as f64;
        }
    }
    println!("far away: mean thread colour {mean:?}, exact {want:?}");
    for c in 0..3 {
        // 8-bit sRGB storage of each pixel (0.4 % at these levels) and the pixels' partial
        // repeats, which average out over 16384 pixels: 1.5 %.
        assert!(
            (mean[c] - want[c]).abs() <= 0.015 * want[c] + 2e-3,
            "channel {c}: mean {mean:?} against {want:?}"
        );
    }
}

/// Sequences of one colour each (the threads' own `rd_warp`, `rd_weft`) render as the fabric
/// without sequences, near and far: the G-buffer's thread colour, taken as both threads' albedo,
/// gives back Σ s·colour exactly. Only a scene with sequences compiles their code in.
#[test]
fn one_colour_sequences_render_as_no_sequences() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let plain = FabricParams {
        pattern: WeavePattern::by_name("twill").expect("twill"),
        rd_warp: RED,
        rd_weft: CREAM,
        ..Default::default()
    };
    let striped = FabricParams {
        warp_colours: vec![RED],
        weft_colours: vec![CREAM],
        ..plain.clone()
    };
    for (repeat, height) in [(0.25f32, 0.5f32), (0.004, 1.0)] {
        let mut images = Vec::new();
        for p in [&plain, &striped] {
            let p = FabricParams {
                repeat,
                gap: 0.05 * repeat,
                ..p.clone()
            };
            let scene = patch(p.clone());
            let camera = scene
                .look_at_camera(Vec3::new(0.3, height, 0.2), Vec3::ZERO, 70f32.to_radians())
                .unwrap();
            let options = RenderOptions {
                width: 96,
                height: 96,
                camera_override: Some(camera),
                ..Default::default()
            };
            let f = renderer.render(&scene, &options).expect("render");
            assert_eq!(f.plan.features.thread_colours, p.has_thread_colours());
            let compiled = format!("thread_colours={}", p.has_thread_colours() as u32);
            assert!(
                f.stats
                    .pipelines
                    .iter()
                    .any(|n| n.starts_with("gbuffer[") && n.contains(&compiled)),
                "{:?}",
                f.stats.pipelines
            );
            images.push(f.hdr);
        }
        let (mut worst, mut sum, mut n) = (0f32, 0f64, 0usize);
        for (a, b) in images[0].chunks_exact(4).zip(images[1].chunks_exact(4)) {
            for c in 0..3 {
                if a[c] > 1e-3 {
                    let e = (a[c] - b[c]).abs() / a[c];
                    worst = worst.max(e);
                    sum += e as f64;
                    n += 1;
                }
            }
        }
        println!(
            "repeat {repeat}: one-colour sequences against none: worst {:.3} %, mean {:.4} %",
            100.0 * worst,
            100.0 * sum / n.max(1) as f64
        );
        // The thread colour passes through the 8-bit sRGB albedo target, where the plain
        // fabric's is white (exact): half a step is 1.9 % at these colours' darkest channel
        // (0.05 linear, byte 63), and lavapipe decodes it up to 0.74 % off the formula
        // (tests/fabric_render_gpu.rs): 3 % (measured worst 2.45 % up close).
        assert!(worst < 0.03, "worst {worst}");
        assert!(
            sum / (n.max(1) as f64) < 0.005,
            "mean {}",
            sum / n.max(1) as f64
        );
    }
}

/// The transparent pass draws striped fabric too (a gauze or lace under alphaMode BLEND): at
/// alpha 1 over nothing, the blended patch shows what the deferred passes show of the opaque one.
#[test]
fn blended_striped_fabric_is_drawn_as_the_opaque_one() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let mut images = Vec::new();
    for blend in [false, true] {
        let mut scene = patch(striped(0.25));
        scene.materials[0].blend = blend;
        let camera = scene
            .look_at_camera(Vec3::new(0.3, 0.6, 0.2), Vec3::ZERO, 70f32.to_radians())
            .unwrap();
        let options = RenderOptions {
            width: 96,
            height: 96,
            camera_override: Some(camera),
            ..Default::default()
        };
        let f = renderer.render(&scene, &options).expect("render");
        if blend {
            assert!(
                f.stats
                    .pipelines
                    .iter()
                    .any(|n| n.starts_with("forward[blend") && n.contains("thread_colours=1")),
                "{:?}",
                f.stats.pipelines
            );
        }
        images.push(f.hdr);
    }
    let (mut worst, mut covered) = (0f32, 0usize);
    for (a, b) in images[0].chunks_exact(4).zip(images[1].chunks_exact(4)) {
        if a[3] > 0.5 {
            covered += 1;
            for c in 0..3 {
                worst = worst.max((a[c] - b[c]).abs() / a[c].max(1e-2));
            }
        }
    }
    println!(
        "blended against opaque: {covered} pixels, worst {:.3} %",
        100.0 * worst
    );
    // The same shading code on the same surface values; the G-buffer's targets round what the
    // forward pass keeps in registers: the 8-bit sRGB albedo (half a step, 1.9 % at the 0.05
    // channels) and lavapipe's decode of it (0.74 %), half-float coverage and normals (< 0.5 %):
    // 3.2 % at most; measured 2.9 %. Bound 5 %; a wrong thread's colour is off by tens of %.
    assert!(
        covered > 96 * 96 / 2 && worst < 0.05,
        "{covered} pixels, worst {worst}"
    );
}
