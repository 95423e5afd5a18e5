//! The ground truth of environment lighting: the reflected radiance of a surface point under an
//! equirectangular environment, by quadrature over **every pixel of the original map** in f64
//! (each pixel's radiance times its solid angle times the BRDF and cosine at its centre
//! direction).
//!
//! It shares none of the GPU's approximations: no cube resampling, no mips, no SH, no split sum,
//! no importance sampling. The BRDFs are the project's one Rust copy: the fabric mixture of
//! [`crate::reference::brdf::double`] (f64) and the glTF metallic-roughness BRDF of [`crate::reference::shading`]
//! (f32, accumulated in f64). A map pixel spans 0.35° on a 1024-wide map: lobes narrower than a
//! few pixels (A–S exponents above ~10⁴, GGX roughness below ~0.05) are under-resolved here.

use super::{pixel_dir, world_from_env, Environment};
use crate::reference::brdf::double as fd;
use crate::reference::shading::{gltf_brdf_cos, sheen_albedo, GltfSurface, Surface};

/// The environment as a list of world-space directions with radiance × solid angle.
pub struct EnvQuadrature {
    /// World direction, and radiance times the pixel's solid angle (rgb).
    pub points: Vec<([f64; 3], [f64; 3])>,
}

impl EnvQuadrature {
    /// Every pixel of `env`, turned by `rotation` degrees, scaled by `intensity`; pixels `step`
    /// apart are merged into one point (1 = every pixel) with their summed weight.
    pub fn new(env: &Environment, rotation: f32, intensity: f32, step: u32) -> EnvQuadrature {
        let (w, h) = (env.width, env.height);
        let step = step.max(1);
        let d_phi = 2.0 * std::f64::consts::PI / w as f64;
        let d_theta = std::f64::consts::PI / h as f64;
        let mut points = Vec::new();
        for j0 in (0..h).step_by(step as usize) {
            for i0 in (0..w).step_by(step as usize) {
                let mut sum = [0f64; 3];
                let mut dir = [0f64; 3];
                for j in j0..(j0 + step).min(h) {
                    let theta = (j as f64 + 0.5) * d_theta;
                    let d_omega = d_phi * d_theta * theta.sin();
                    for i in i0..(i0 + step).min(w) {
                        let p = env.pixel(i, j);
                        for c in 0..3 {
                            sum[c] += p[c] as f64 * d_omega * intensity as f64;
                        }
                        let e = pixel_dir(i, j, w, h);
                        for c in 0..3 {
                            dir[c] += e[c] * d_omega;
                        }
                    }
                }
                let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
                if !(len > 0.0) {
                    continue;
                }
                let world = world_from_env(rotation, dir.map(|x| x / len));
                points.push((world, sum));
            }
        }
        EnvQuadrature { points }
    }

    /// Σ L(ω) dω · g(ω) over the environment, g being BRDF × cosine (0 below the surface).
    pub fn integrate(&self, mut g: impl FnMut([f64; 3]) -> [f64; 3]) -> [f64; 3] {
        let mut out = [0f64; 3];
        for (dir, l) in &self.points {
            let f = g(*dir);
            for c in 0..3 {
                out[c] += l[c] * f[c];
            }
        }
        out
    }

    /// The environment light reflected towards the viewer at `eye` by surface point `s` (its
    /// fabric mixture with its coverage, or the glTF BRDF). Ambient occlusion is not modelled
    /// (the reference scenes have none).
    pub fn reflected(&self, s: &Surface, eye: [f32; 3]) -> [f64; 3] {
        let p = s.position.map(|x| x as f64);
        let v = {
            let d = [
                eye[0] as f64 - p[0],
                eye[1] as f64 - p[1],
                eye[2] as f64 - p[2],
            ];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            d.map(|x| x / l)
        };
        match &s.fabric {
            Some(f) => {
                let m = fd::fabric_tinted(
                    &fd::FabricMaterial::from_gpu(f),
                    s.base_color.map(|x| x as f64),
                );
                let tbn = fd::fabric_frame(
                    s.normal.map(|x| x as f64),
                    s.tangent.map(|x| x as f64),
                    s.sign as f64,
                );
                let k2 = fd::fabric_local(v, tbn);
                let cov = s.coverage.map(|x| x as f64);
                self.integrate(|l| {
                    let k1 = fd::fabric_local(l, tbn);
                    if k1[2] <= 0.0 {
                        return [0.0; 3];
                    }
                    let b = fd::fabric_brdf(k1, k2, cov, &m);
                    b.map(|x| x * k1[2])
                })
            }
            None => {
                let vf = v.map(|x| x as f32);
                let n = s.normal;
                // The material with its extensions; the sheen's albedo by its own quadrature
                // (shading::sheen_albedo), not the GPU's table.
                let gs = s
                    .gltf
                    .unwrap_or_else(|| GltfSurface::core(s.base_color, s.metallic, s.roughness));
                let has_sheen = gs.sheen.iter().any(|&c| c > 0.0);
                let table = if has_sheen {
                    sheen_albedo_curve(gs.sheen_roughness)
                } else {
                    std::sync::Arc::new(Vec::new())
                };
                let albedo = |c: f32| {
                    if table.is_empty() {
                        return 0.0;
                    }
                    let x = (c.clamp(0.0, 1.0) as f64) * (table.len() - 1) as f64;
                    let i = (x.floor() as usize).min(table.len() - 2);
                    let f = x - i as f64;
                    (table[i] * (1.0 - f) + table[i + 1] * f) as f32
                };
                let nv = n[0] * vf[0] + n[1] * vf[1] + n[2] * vf[2];
                let e_v = albedo(nv);
                // The GGX lobe's directional albedo for its energy compensation, by its own
                // quadrature (crate::env::dfg, 1024 Hammersley samples in f64), not the GPU's
                // table.
                let [a, b] = super::dfg(nv.clamp(1e-4, 1.0) as f64, gs.roughness as f64, 1024);
                let ess = (a + b) as f32;
                self.integrate(|l| {
                    let lf = l.map(|x| x as f32);
                    let nl = n[0] * lf[0] + n[1] * lf[1] + n[2] * lf[2];
                    if nl <= 0.0 {
                        return [0.0; 3];
                    }
                    gltf_brdf_cos(n, vf, lf, &gs, [e_v, albedo(nl)], ess).map(|x| x as f64)
                })
            }
        }
    }
}

/// The sheen's directional albedo at roughness `r` on 257 cosines in [0, 1] (each by
/// [`sheen_albedo`]'s own quadrature, 48 cells), computed once per roughness and kept: the
/// reference interpolates it linearly (8x finer than the GPU's 32-entry table).
fn sheen_albedo_curve(r: f32) -> std::sync::Arc<Vec<f64>> {
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex, OnceLock};
    static CACHE: OnceLock<Mutex<HashMap<u32, Arc<Vec<f64>>>>> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(t) = cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .get(&r.to_bits())
    {
        return t.clone();
    }
    let t = Arc::new(
        (0..=256)
            .map(|i| sheen_albedo(i as f64 / 256.0, r, 48))
            .collect::<Vec<_>>(),
    );
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(r.to_bits(), t.clone());
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_environment_on_white_lambert_is_one() {
        // Quadrature of the cosine over the sphere: the solid angles sum to 4π (the midpoint rule
        // over 32 rows of sin θ is 4e-4 high) and a white Lambertian surface under radiance 1
        // reflects 1.
        let q = EnvQuadrature::new(&Environment::uniform([1.0; 3]), 30.0, 1.0, 1);
        let total: f64 = q.points.iter().map(|(_, l)| l[0]).sum();
        let four_pi = 4.0 * std::f64::consts::PI;
        assert!((total - four_pi).abs() < 1e-3 * four_pi, "{total}");
        let n = [0.0, 0.6, 0.8];
        let e = q.integrate(|l| {
            let c = (n[0] * l[0] + n[1] * l[1] + n[2] * l[2]).max(0.0);
            [c / std::f64::consts::PI; 3]
        });
        assert!((e[0] - 1.0).abs() < 2e-3, "{e:?}");
    }
}

#[cfg(test)]
mod sh_check {
    use super::*;

    /// Order-2 SH irradiance against the quadrature of the clamped cosine, on the real interior
    /// map of the tests: the SH's known band-limiting error, measured.
    #[test]
    fn sh_irradiance_error_on_lebombo() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/env/lebombo_1k.hdr");
        let env = Environment::load(&path).unwrap();
        let sh = env.sh9();
        let q = EnvQuadrature::new(&env, 0.0, 1.0, 2);
        let mut worst = 0f64;
        for n in [
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [-0.6, 0.0, -0.8],
        ] {
            let want = q.integrate(|l| {
                let c = (n[0] * l[0] + n[1] * l[1] + n[2] * l[2]).max(0.0) / std::f64::consts::PI;
                [c; 3]
            });
            let got = crate::env::sh_eval(&sh, n.map(|x| x as f32));
            let rel = (got[1] as f64 - want[1]).abs() / want[1];
            println!(
                "n {n:?}: SH {:.4}, quadrature {:.4}, rel {rel:.4}",
                got[1], want[1]
            );
            worst = worst.max(rel);
        }
        assert!(worst < 0.1, "{worst}");
    }
}
