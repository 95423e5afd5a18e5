//! The exact directional albedo of the fabric's A–S lobes, tabulated per fabric (issue 31 item 1):
//! what the environment estimator of the lobes (`fabric_env_lobes` in glsl/include/env_light.glsl)
//! multiplies its samples' weighted mean radiance by, in place of the samples' own estimate of the
//! lobe's albedo. With eight fixed samples of a lobe 4.5 times longer than wide that estimate was
//! the larger half of the estimator's error: 7 % low for a lobe sampled alone, and over half low
//! for one sampled with weight 0.5 of the two lobes' mixture (examples/ibl_lobe_estimators.rs).
//!
//! One table per fabric record: the albedo of the weft lobe (exponent `e_along` along the tangent,
//! `e_across` along the bitangent) for a view `k2` at `LOBE_ALBEDO_MU` cosines `n·k2 = i/(MU−1)`
//! (the first evaluated at 0.005, a view at the horizon) and `LOBE_ALBEDO_PHI` azimuths
//! `φ = j/(PHI−1)·π/2` of the view from the tangent, folded into the first quadrant (the lobe is
//! symmetric under t → −t and b → −b). The warp lobe is the weft lobe turned by 90°: the same table
//! at the view's azimuth from the bitangent. Schlick's Fresnel is linear in rs, so each entry is
//! two albedos, at rs = 0 and at rs = 1: the albedo at rs is `mix(a0, a1, rs)`.
//!
//! Each entry is [`crate::reference::furnace::lobe_albedo`]'s estimate (the reference's f64 A–S
//! sampler on a 32 x 32 stratified grid: every sample's weight F·(n·k1)/max(n·k1, n·k2) is at
//! most 1, so the grid converges fast), both albedos from one set of samples; `tests` hold the
//! table and its interpolation against an independent quadrature over directions, and the entries
//! against `lobe_albedo` itself.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use crate::fabric::GpuFabric;

/// Nodes in n·k2 (0 to 1).
pub const LOBE_ALBEDO_MU: usize = 24;
/// Nodes in the view's azimuth from the tangent (0 to π/2).
pub const LOBE_ALBEDO_PHI: usize = 12;
/// Entries of one fabric's table (`[a0, a1]` each, the n·k2 index fastest).
pub const LOBE_ALBEDO_LEN: usize = LOBE_ALBEDO_MU * LOBE_ALBEDO_PHI;
/// The stratified grid of each entry's integral (per side).
const STRATA: usize = 32;

/// The view of entry (i, j): unit, local frame (t, b, n).
pub fn node_view(i: usize, j: usize) -> [f64; 3] {
    let mu = (i as f64 / (LOBE_ALBEDO_MU - 1) as f64).max(0.005);
    let phi = j as f64 / (LOBE_ALBEDO_PHI - 1) as f64 * std::f64::consts::FRAC_PI_2;
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    [s * phi.cos(), s * phi.sin(), mu]
}

/// One fabric's table: `[albedo at rs 0, albedo at rs 1]` per entry, computed on the machine's
/// cores (about 10 ms here, two cores), and kept for the process (keyed by the exponents' bits: a scene's
/// fabrics mostly share presets, and `weft view` asks again after every edit).
///
/// A second caller for the same exponents while the first computes (the renderer starts the
/// tables on a thread beside the pipelines, and its upload may ask before they are done) waits
/// for that one's table.
pub fn table(e_along: f32, e_across: f32) -> Arc<Vec<[f32; 2]>> {
    type Tables = HashMap<(u32, u32), Arc<OnceLock<Arc<Vec<[f32; 2]>>>>>;
    static CACHE: OnceLock<Mutex<Tables>> = OnceLock::new();
    let key = (e_along.to_bits(), e_across.to_bits());
    let cell = CACHE
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .entry(key)
        .or_default()
        .clone();
    cell.get_or_init(|| Arc::new(compute(e_along as f64, e_across as f64)))
        .clone()
}

/// Entry for view `k2`: [`crate::reference::furnace::lobe_albedo`]'s estimate at rs 0 and rs 1
/// from one set of samples. A sample's weight ρs·(n·k1)/pdf is F(k·h)·(n·k1)/max(n·k1, n·k2) in
/// closed form (the lobe's and the sampler's hn^E and normalisation cancel), and Schlick's F is
/// (1 − k·h)^5 at rs 0 and 1 at rs 1.
fn entry(k2: [f64; 3], eu: f64, ev: f64) -> [f32; 2] {
    use crate::reference::brdf::sampling::sample_h;
    let (mut a0, mut a1) = (0.0f64, 0.0f64);
    for i in 0..STRATA {
        for j in 0..STRATA {
            let xi1 = (i as f64 + 0.5) / STRATA as f64;
            let xi2 = (j as f64 + 0.5) / STRATA as f64;
            let h = sample_h(eu, ev, xi1, xi2);
            let kh = k2[0] * h[0] + k2[1] * h[1] + k2[2] * h[2];
            let k1z = 2.0 * kh * h[2] - k2[2];
            if !(kh > 0.0 && k1z > 0.0) {
                continue;
            }
            let w = k1z / k1z.max(k2[2]);
            let x = (1.0 - kh.min(1.0)).powi(5);
            a1 += w;
            a0 += w * x;
        }
    }
    let n = (STRATA * STRATA) as f64;
    [(a0 / n) as f32, (a1 / n) as f32]
}

fn compute(eu: f64, ev: f64) -> Vec<[f32; 2]> {
    let entry = |k: usize| entry(node_view(k % LOBE_ALBEDO_MU, k / LOBE_ALBEDO_MU), eu, ev);
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .clamp(1, 16);
    let mut out = vec![[0.0f32; 2]; LOBE_ALBEDO_LEN];
    let chunk = LOBE_ALBEDO_LEN.div_ceil(threads);
    std::thread::scope(|s| {
        for (c, part) in out.chunks_mut(chunk).enumerate() {
            s.spawn(move || {
                for (o, v) in part.iter_mut().enumerate() {
                    *v = entry(c * chunk + o);
                }
            });
        }
    });
    out
}

/// The tables of `fabrics`, one after another in record order (the GPU's `fabric_lobe_albedo`
/// buffer: record k's table at k·[`LOBE_ALBEDO_LEN`]).
pub fn records(fabrics: &[GpuFabric]) -> Vec<[f32; 2]> {
    let mut out = Vec::with_capacity(fabrics.len().max(1) * LOBE_ALBEDO_LEN);
    for f in fabrics {
        out.extend_from_slice(&table(f.e_along, f.e_across));
    }
    if out.is_empty() {
        out.resize(LOBE_ALBEDO_LEN, [0.0; 2]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::brdf::double as fd;

    /// The albedo of the lobe (exponents eu along t, ev along b, Fresnel rs) for view k2 by a
    /// quadrature over light directions, independent of the A–S sampler the table uses: the
    /// hemisphere in (θ, φ) of k1 about the mirror direction's... simply about n, on a grid fine
    /// enough for the narrow axis (θ steps of 0.0025 rad, φ steps of 2π/2048).
    fn quadrature(k2: [f64; 3], eu: f64, ev: f64, rs: f64) -> f64 {
        let (nt, np) = (628usize, 2048usize);
        let dt = std::f64::consts::FRAC_PI_2 / nt as f64;
        let dp = 2.0 * std::f64::consts::PI / np as f64;
        let mut sum = 0.0;
        for a in 0..nt {
            let th = (a as f64 + 0.5) * dt;
            let (st, ct) = th.sin_cos();
            for b in 0..np {
                let ph = (b as f64 + 0.5) * dp;
                let k1 = [st * ph.cos(), st * ph.sin(), ct];
                sum += fd::as_lobe(k1, k2, eu, ev, rs) * ct * st * dt * dp;
            }
        }
        sum
    }

    #[test]
    fn entries_match_a_quadrature_over_directions() {
        // The default cloth's exponents and a satin's; nodes from the horizon to normal incidence.
        for (eu, ev) in [(200.0f32, 10.0f32), (800.0, 40.0)] {
            let t = table(eu, ev);
            for (i, j) in [(1, 0), (4, 5), (12, 11), (23, 3), (8, 8)] {
                let k2 = node_view(i, j);
                for (c, rs) in [(0, 0.0), (1, 1.0)] {
                    let q = quadrature(k2, eu as f64, ev as f64, rs);
                    let got = t[j * LOBE_ALBEDO_MU + i][c] as f64;
                    assert!(
                        (got - q).abs() <= 0.005 * q + 1e-4,
                        "({eu}, {ev}) entry ({i}, {j}) rs {rs}: table {got}, quadrature {q}"
                    );
                }
            }
        }
    }

    /// Between the nodes: the twin's bilinear look-up (`fabric_lobe_albedo`, the GLSL's) at
    /// views off the nodes, both lobes, against the quadrature. Measured worst: 1.5 % (near the
    /// horizon, where the albedo turns fastest; 0.15 % at the nodes); the bound 2 % + 0.001.
    #[test]
    fn interpolated_albedo_matches_a_quadrature_between_the_nodes() {
        use crate::reference::env_light::{fabric_lobe_albedo, KeptDfg};
        let f = GpuFabric {
            e_along: 200.0,
            e_across: 10.0,
            rs: 0.04,
            ..Default::default()
        };
        let mut worst = 0.0f64;
        for (k, (mu, phi)) in [
            (0.08f64, 0.3f64),
            (0.31, 1.1),
            (0.55, 2.0),
            (0.77, 4.0),
            (0.93, 5.5),
            (0.2, 0.78),
        ]
        .into_iter()
        .enumerate()
        {
            let s = (1.0 - mu * mu).sqrt();
            let k2 = [s * phi.cos(), s * phi.sin(), mu];
            let k2f = k2.map(|x| x as f32);
            for warp in [false, true] {
                let (eu, ev) = if warp { (10.0, 200.0) } else { (200.0, 10.0) };
                let q = quadrature(k2, eu, ev, 0.04);
                let got = fabric_lobe_albedo(&KeptDfg, &f, k as u32, k2f, 0.04, warp) as f64;
                worst = worst.max((got - q).abs() / q);
                assert!(
                    (got - q).abs() <= 0.02 * q + 1e-3,
                    "view {k2:?} warp {warp}: interpolated {got}, quadrature {q}"
                );
            }
        }
        eprintln!("worst relative error between the nodes: {worst:.4}");
    }

    /// The one-pass entry is `furnace::lobe_albedo` at rs 0 and 1 (the same samples, the weight
    /// in closed form): equal to rounding.
    #[test]
    fn entries_are_the_furnace_albedo() {
        use crate::reference::furnace::lobe_albedo;
        for (i, j) in [(0, 0), (3, 7), (11, 2), (23, 11)] {
            let k2 = node_view(i, j);
            let e = entry(k2, 200.0, 10.0);
            for (c, rs) in [(0, 0.0), (1, 1.0)] {
                let want = lobe_albedo(k2, 200.0, 10.0, rs, STRATA);
                assert!(
                    (e[c] as f64 - want).abs() < 1e-6,
                    "({i}, {j}) rs {rs}: {} vs {want}",
                    e[c]
                );
            }
        }
    }

    #[test]
    fn records_hold_one_table_per_fabric_and_one_when_none() {
        assert_eq!(records(&[]).len(), LOBE_ALBEDO_LEN);
        let f = GpuFabric {
            e_along: 200.0,
            e_across: 10.0,
            ..Default::default()
        };
        let g = GpuFabric {
            e_along: 60.0,
            e_across: 8.0,
            ..Default::default()
        };
        let t0 = std::time::Instant::now();
        let r = records(&[f, g]);
        eprintln!("two tables: {:.1} ms", t0.elapsed().as_secs_f64() * 1e3);
        assert_eq!(r.len(), 2 * LOBE_ALBEDO_LEN);
        assert_eq!(&r[..LOBE_ALBEDO_LEN], &table(200.0, 10.0)[..]);
        assert_eq!(&r[LOBE_ALBEDO_LEN..], &table(60.0, 8.0)[..]);
        assert!(r
            .iter()
            .all(|[a, b]| a.is_finite() && b.is_finite() && *a >= 0.0 && *b <= 1.0 + 1e-6));
    }

    /// The GLSL's table constants are these (env_light.glsl).
    #[test]
    fn glsl_constants_match() {
        let src = include_str!("../../glsl/include/env_light.glsl");
        assert!(src.contains(&format!("const uint LOBE_ALBEDO_MU = {LOBE_ALBEDO_MU}u;")));
        assert!(src.contains(&format!("const uint LOBE_ALBEDO_PHI = {LOBE_ALBEDO_PHI}u;")));
    }
}
