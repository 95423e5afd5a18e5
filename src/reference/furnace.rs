//! White-furnace integrators: the directional albedo `∫ f(k1, k2) (n·k2) dω2` of the lobe, of the
//! diffuse terms and of the whole fabric model, in f64, deterministic (stratified samples, fixed
//! quadrature), for tests and for the documentation's figures.

use super::brdf::double::{
    as_lobe, coupled_diffuse, fabric_brdf, lambert, Coverage, FabricMaterial, Vec3,
};
use super::brdf::sampling::sample_k2;
use std::f64::consts::PI;

/// Albedo of one A–S lobe for light from `k1` (local frame, unit, above the surface), by
/// importance sampling `h` on an `n × n` stratified grid. The weight of a sample is
/// `ρs·(n·k2)/pdf = F·(n·k2)/max(n·k1, n·k2) ≤ 1`, so the estimate converges quickly at any
/// exponent.
pub fn lobe_albedo(k1: Vec3, eu: f64, ev: f64, rs: f64, n: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let xi1 = (i as f64 + 0.5) / n as f64;
            let xi2 = (j as f64 + 0.5) / n as f64;
            if let Some((k2, pdf)) = sample_k2(k1, eu, ev, xi1, xi2) {
                if pdf > 0.0 {
                    sum += as_lobe(k1, k2, eu, ev, rs) * k2[2] / pdf;
                }
            }
        }
    }
    sum / (n * n) as f64
}

/// Albedo of the diffuse term (without Rd): 1 for Lambert; for the coupled diffuse,
/// `2π ∫₀¹ ρd(n·k1, μ) μ dμ` by the midpoint rule on 4096 intervals (the integrand is a degree-6
/// polynomial in μ: error < 1e-8).
pub fn diffuse_albedo(nk1: f64, rs: f64, coupled: bool) -> f64 {
    if !coupled {
        return lambert() * PI;
    }
    let n = 4096;
    let mut sum = 0.0;
    for i in 0..n {
        let mu = (i as f64 + 0.5) / n as f64;
        sum += coupled_diffuse(rs, nk1, mu) * mu;
    }
    2.0 * PI * sum / n as f64
}

/// Albedo of the full model (per colour channel) for light from `k1` with the weave `coverage`
/// (`c_warp, c_weft, s_warp, s_weft`): linear in the terms, so each lobe is importance-sampled on
/// its own.
pub fn fabric_albedo(k1: Vec3, m: &FabricMaterial, coverage: Coverage, n: usize) -> Vec3 {
    let [c_warp, c_weft, s_warp, s_weft] = coverage;
    let spec = c_weft * lobe_albedo(k1, m.e_along, m.e_across, m.rs, n)
        + c_warp * lobe_albedo(k1, m.e_across, m.e_along, m.rs, n);
    let d = diffuse_albedo(k1[2], m.rs, m.coupled);
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        *o = spec + d * (s_warp * m.rd_warp[c] + s_weft * m.rd_weft[c]);
    }
    out
}

/// The same albedo by brute force, for checking the sampler: the midpoint rule over the hemisphere
/// in `(cos θ, φ)` on `n × 4n` cells. Only accurate for lobes wider than a cell (exponents ≲ n²/10).
pub fn fabric_albedo_quadrature(
    k1: Vec3,
    m: &FabricMaterial,
    coverage: Coverage,
    n: usize,
) -> Vec3 {
    let mut out = [0.0; 3];
    let nphi = 4 * n;
    for i in 0..n {
        let mu = (i as f64 + 0.5) / n as f64;
        let st = (1.0 - mu * mu).sqrt();
        for j in 0..nphi {
            let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
            let k2 = [st * phi.cos(), st * phi.sin(), mu];
            let f = fabric_brdf(k1, k2, coverage, m);
            for c in 0..3 {
                out[c] += f[c] * mu;
            }
        }
    }
    let cell = (1.0 / n as f64) * (2.0 * PI / nphi as f64);
    out.map(|x| x * cell)
}
