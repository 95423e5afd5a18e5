//! The thread texture over the weave (docs/fabric-model.md §3, "Textures"): what the renderer
//! computes (the product of two filtered look-ups: the texture's mean over the pixel footprint
//! times the weave's diffuse albedo over it, "product of the mips") against what is exact (the
//! footprint mean of the product, "mip of the product"), on the CPU in f64, for textures of three
//! kinds. Run with `--nocapture` for the table the docs quote.

use weft::fabric::{FabricParams, WeavePattern};
use weft::reference::weave::{double, weave_of};

/// A texture as a renderer sees it: piecewise constant on a grid of texels `h` cells wide
/// (texel (i, j) covers [i·h, (i+1)·h) × [j·h, (j+1)·h)), values in [0, 1].
struct Texture {
    name: &'static str,
    h: f64,
    value: fn(i: i64, j: i64) -> f64,
}

/// The weave: cotton-plain-like (plain, 12 % gap, the default shadow), two thread colours; one
/// cell per UV unit so that cells are texture units.
fn weave() -> (double::Weave, [f64; 3], [f64; 3]) {
    let p = FabricParams {
        pattern: WeavePattern::plain(),
        repeat: 2.0,
        gap: 0.12,
        rd_warp: [0.8, 0.25, 0.1],
        rd_weft: [0.15, 0.3, 0.7],
        ..Default::default()
    };
    (weave_of(&p), [0.8, 0.25, 0.1], [0.15, 0.3, 0.7])
}

/// Exact (mip of the product) and renderer's (product of the mips) footprint means of
/// texture × diffuse albedo over the box [x0, x0 + side]², per rgb channel.
fn footprint(t: &Texture, x0: f64, y0: f64, side: f64) -> ([f64; 3], [f64; 3]) {
    let (w, warp, weft) = weave();
    let (x1, y1) = (x0 + side, y0 + side);
    let albedo = |c: [f64; 4]| -> [f64; 3] { [0, 1, 2].map(|k| c[2] * warp[k] + c[3] * weft[k]) };
    let (i0, i1) = ((x0 / t.h).floor() as i64, (x1 / t.h).ceil() as i64);
    let (j0, j1) = ((y0 / t.h).floor() as i64, (y1 / t.h).ceil() as i64);
    let area = side * side;
    let (mut exact, mut mean_t) = ([0.0; 3], 0.0);
    for j in j0..j1 {
        let (ya, yb) = ((j as f64 * t.h).max(y0), ((j + 1) as f64 * t.h).min(y1));
        if yb <= ya {
            continue;
        }
        for i in i0..i1 {
            let (xa, xb) = ((i as f64 * t.h).max(x0), ((i + 1) as f64 * t.h).min(x1));
            if xb <= xa {
                continue;
            }
            let a = (xb - xa) * (yb - ya);
            let v = (t.value)(i, j);
            // The texel is constant over its part of the footprint: exact.
            let al = albedo(double::weave_box(&w, xa, ya, xb, yb));
            for k in 0..3 {
                exact[k] += v * a * al[k];
            }
            mean_t += v * a;
        }
    }
    let whole = albedo(double::weave_box(&w, x0, y0, x1, y1));
    (exact.map(|e| e / area), whole.map(|a| mean_t / area * a))
}

/// Largest and mean |product − exact| / exact (the worst rgb channel of each footprint) over `n`
/// footprints of side `side` at pseudo-random positions.
fn error(t: &Texture, side: f64, n: usize) -> (f64, f64) {
    let mut rng = weft::reference::probe::XorShift::new(0x7e47 + (side * 64.0) as u64);
    let (mut worst, mut sum) = (0.0f64, 0.0);
    for _ in 0..n {
        let x0 = rng.range(-50.0, 50.0);
        let y0 = rng.range(-50.0, 50.0);
        let (exact, product) = footprint(t, x0, y0, side);
        let e = (0..3)
            .map(|k| {
                if exact[k] > 1e-9 {
                    (product[k] - exact[k]).abs() / exact[k]
                } else {
                    0.0
                }
            })
            .fold(0.0f64, f64::max);
        worst = worst.max(e);
        sum += e;
    }
    (worst, sum / n as f64)
}

fn textures() -> [Texture; 3] {
    [
        // A print or dye that varies slowly: a product of sines of periods 37 and 29 cells,
        // texels half a cell wide.
        Texture {
            name: "smooth print (periods 37 x 29 cells)",
            h: 0.5,
            value: |i, j| {
                let (x, y) = ((i as f64 + 0.5) * 0.5, (j as f64 + 0.5) * 0.5);
                0.55 + 0.4
                    * (2.0 * std::f64::consts::PI * x / 37.0).sin()
                    * (2.0 * std::f64::consts::PI * y / 29.0).sin()
            },
        },
        // A damask-like two-tone motif with sharp edges, at SheenChair's scale (its 512² base
        // colour texture over 224 cotton-plain cells: 0.44 cell per texel).
        Texture {
            name: "two-tone motif (0.44 cell texels)",
            h: 0.44,
            value: |i, j| {
                let (x, y) = ((i as f64 + 0.5) * 0.44, (j as f64 + 0.5) * 0.44);
                let phase = 2.0 * std::f64::consts::PI * x / 23.0
                    + 2.0 * (2.0 * std::f64::consts::PI * y / 17.0).sin();
                if phase.sin() > 0.0 {
                    0.9
                } else {
                    0.35
                }
            },
        },
        // The worst case: a texture drawn thread by thread, in step with the weave (one texel per
        // cell, bright and dark columns alternating like the plain weave's own columns).
        Texture {
            name: "thread-aligned checks (1 cell texels)",
            h: 1.0,
            value: |i, j| if (i + j).rem_euclid(2) == 0 { 1.0 } else { 0.2 },
        },
    ]
}

const SIDES: [f64; 5] = [0.25, 1.0, 4.0, 16.0, 64.0];

#[test]
fn product_of_mips_against_mip_of_product() {
    println!(
        "footprint side (cells) | {}",
        SIDES.map(|s| format!("{s:>14}")).join(" | ")
    );
    let mut table = Vec::new();
    for t in textures() {
        let row: Vec<(f64, f64)> = SIDES.iter().map(|&s| error(&t, s, 60)).collect();
        println!(
            "{:<40} | {}",
            t.name,
            row.iter()
                .map(|(w, m)| format!("{:>5.2}% ({:>4.2}%)", 100.0 * w, 100.0 * m))
                .collect::<Vec<_>>()
                .join(" | ")
        );
        table.push(row);
    }
    println!("(worst (mean) |product of mips - mip of product| / mip of product, worst rgb channel, 60 footprints each)");
    // A slowly varying print: within 6 % in the worst channel of the worst footprint and 1.5 %
    // on average at every size, and within 0.5 % once the footprint spans 16 cells (the texture
    // and the weave average out independently).
    for (k, (worst, mean)) in table[0].iter().enumerate() {
        assert!(
            *worst < 0.06 && *mean < 0.015,
            "smooth print, side {}: {worst} {mean}",
            SIDES[k]
        );
        if SIDES[k] >= 16.0 {
            assert!(*worst < 0.005, "smooth print, side {}: {worst}", SIDES[k]);
        }
    }
    // A sharp motif at the asset's scale: worst where a footprint of about a cell straddles a
    // motif edge (up to 30 % in one channel of one footprint, 2 % on average), within 1 % (0.3 %
    // on average) from 16 cells on.
    for (k, (worst, mean)) in table[1].iter().enumerate() {
        assert!(
            *worst < 0.30 && *mean < 0.02,
            "motif, side {}: {worst} {mean}",
            SIDES[k]
        );
        if SIDES[k] >= 16.0 {
            assert!(
                *worst < 0.01 && *mean < 0.003,
                "motif, side {}: {worst} {mean}",
                SIDES[k]
            );
        }
    }
    // A texture in step with the threads is where the two differ: the texture and the weave's
    // albedo are correlated over every footprint of a cell or more, and the product of the mips
    // misses their covariance at every distance (the measure is sensitive, and the docs give the
    // figure).
    for (k, (worst, mean)) in table[2].iter().enumerate() {
        if SIDES[k] >= 1.0 {
            assert!(
                *mean > 0.2 && *worst > 0.2,
                "checks, side {}: {mean} {worst}",
                SIDES[k]
            );
        }
    }
}

/// Within a texel (the footprint smaller than the texture's features and inside one texel) the
/// two are the same number: the near field is exact.
#[test]
fn within_a_texel_the_product_is_exact() {
    let t = &textures()[1];
    let mut rng = weft::reference::probe::XorShift::new(11);
    for _ in 0..200 {
        // A footprint of 1/20 texel inside one texel.
        let (i, j) = (
            rng.range(-100.0, 100.0).floor(),
            rng.range(-100.0, 100.0).floor(),
        );
        let side = t.h / 20.0;
        let x0 = (i + rng.range(0.0, 0.9)) * t.h;
        let y0 = (j + rng.range(0.0, 0.9)) * t.h;
        let (exact, product) = footprint(t, x0, y0, side);
        for k in 0..3 {
            assert!(
                (exact[k] - product[k]).abs() <= 1e-12 * exact[k].max(1e-12),
                "{exact:?} {product:?}"
            );
        }
    }
}
