//! Environment lighting on the CPU: equirectangular HDR images (loaded from Radiance `.hdr` or
//! OpenEXR through `image`, or the built-in procedural studio), their direction mapping, the
//! spherical-harmonic irradiance projection, and the split-sum DFG table of the GGX lobe.
//!
//! Convention (shared with `glsl/include/ibl.glsl`): row 0 of the image looks straight up (+y);
//! the centre column looks along -z (where a default glTF camera looks); u grows towards +x.
//! `dir = (sin θ sin φ, cos θ, -sin θ cos φ)` with `θ = π v`, `φ = 2π (u - 1/2)`.
//! A rotation of the environment by `r` degrees turns it about +y (counter-clockwise seen from
//! above); shaders look it up with `env_from_world`.
//!
//! [`quadrature`] is the ground truth of environment lighting: f64 quadrature over every pixel of
//! the map with the reference BRDFs.

pub use crate::reference::lobe_albedo;
pub mod quadrature;

use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;

use sha2::{Digest, Sha256};

use crate::Error;

/// The largest environment image side weft loads (larger maps: downscale them first).
pub const MAX_ENV_SIDE: u32 = 16384;

/// Linear radiance values are clamped to this, the largest half float: the GPU keeps the
/// environment in RGBA16F (linear filtering of it is guaranteed by Vulkan; of 32-bit floats it is
/// not). Of the maps in `../shared/environments`, only the Mondello sun (peak 7.1e4) is clipped.
pub const MAX_RADIANCE: f32 = 65504.0;

/// An equirectangular environment: linear RGB radiance, rows top (up) to bottom.
#[derive(Clone)]
pub struct Environment {
    /// Where it came from (a path, or "built-in studio").
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<f32>,
    /// What loading repaired, for the user (non-finite texels replaced by 0).
    pub warnings: Vec<String>,
    hash: [u8; 32],
}

impl std::fmt::Debug for Environment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Environment({}, {}x{})",
            self.name, self.width, self.height
        )
    }
}

impl Environment {
    /// An environment from linear RGB pixels; non-finite or negative values become 0 and values
    /// above [`MAX_RADIANCE`] are clamped.
    pub fn from_rgb(
        name: impl Into<String>,
        width: u32,
        height: u32,
        mut rgb: Vec<f32>,
    ) -> crate::Result<Environment> {
        let name = name.into();
        if width == 0 || height == 0 || width > MAX_ENV_SIDE || height > MAX_ENV_SIDE {
            return Err(Error::input(format!(
                "environment '{name}' is {width}x{height}: each side must be 1 to {MAX_ENV_SIDE} pixels (downscale the map)"
            )));
        }
        if rgb.len() != width as usize * height as usize * 3 {
            return Err(Error::input(format!(
                "environment '{name}' has {} values, expected {} for {width}x{height} RGB",
                rgb.len(),
                width as usize * height as usize * 3
            )));
        }
        for v in &mut rgb {
            if !(*v >= 0.0) {
                *v = 0.0; // NaN and negatives
            } else if *v > MAX_RADIANCE {
                *v = MAX_RADIANCE;
            }
        }
        let mut h = Sha256::new();
        h.update(width.to_le_bytes());
        h.update(height.to_le_bytes());
        h.update(bytemuck::cast_slice::<f32, u8>(&rgb));
        Ok(Environment {
            name,
            width,
            height,
            rgb,
            warnings: Vec::new(),
            hash: h.finalize().into(),
        })
    }

    /// Loads an equirectangular (2:1) Radiance `.hdr` or OpenEXR file.
    pub fn load(path: &Path) -> crate::Result<Environment> {
        let shown = path.display();
        if !path.exists() {
            return Err(Error::input(format!(
                "environment map '{shown}' does not exist: give the path of an equirectangular .hdr or .exr file (a relative path starts at the current directory)"
            )));
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        if ext != "hdr" && ext != "exr" {
            return Err(Error::input(format!(
                "environment map '{shown}' is not a .hdr or .exr file: weft reads equirectangular Radiance HDR and OpenEXR maps"
            )));
        }
        let reader = image::ImageReader::open(path)
            .map_err(|e| Error::input(format!("cannot open environment map '{shown}': {e}")))?
            .with_guessed_format()
            .map_err(|e| Error::input(format!("cannot read environment map '{shown}': {e}")))?;
        // By what the bytes are, not what the name says: a PNG renamed .hdr would decode, and
        // its sRGB bytes would be taken for radiance.
        match reader.format() {
            Some(image::ImageFormat::Hdr | image::ImageFormat::OpenExr) => {}
            other => {
                return Err(Error::input(format!(
                    "environment map '{shown}' is named .{ext} but {}: weft reads equirectangular Radiance HDR and OpenEXR maps (linear radiance); convert it to one of those",
                    match other {
                        Some(f) => format!("holds a {} image", format!("{f:?}").to_uppercase()),
                        None => "is neither a Radiance HDR nor an OpenEXR file".into(),
                    }
                )))
            }
        }
        let mut reader = reader;
        // The environment is at most MAX_ENV_SIDE square in f32 RGB(A).
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_ENV_SIDE);
        limits.max_image_height = Some(MAX_ENV_SIDE);
        limits.max_alloc = Some(4 << 30);
        reader.limits(limits);
        let img = reader.decode().map_err(|e| {
            Error::input(format!(
                "cannot decode environment map '{shown}': {e} (weft reads equirectangular Radiance .hdr and OpenEXR through the image crate; re-save the map, e.g. as .hdr)"
            ))
        })?;
        let rgb = img.into_rgb32f();
        let (w, h) = rgb.dimensions();
        // An equirectangular map spans 360 by 180 degrees: twice as wide as high. Anything else
        // (a cube cross, a strip, a photo) would be stretched over the sphere.
        if w.abs_diff(2 * h) > (w / 100).max(1) {
            return Err(Error::input(format!(
                "environment map '{shown}' is {w}x{h}, not an equirectangular (latitude-longitude) map, which is twice as wide as high (e.g. 2048x1024); convert it to one"
            )));
        }
        let rgb = rgb.into_raw();
        let texels = rgb.len() / 3;
        let bad = rgb
            .chunks_exact(3)
            .filter(|t| !t.iter().all(|v| v.is_finite()))
            .count();
        if bad == texels {
            return Err(Error::input(format!(
                "environment map '{shown}' has no finite texel ({w}x{h}, every one NaN or infinite), so it holds no light: re-export it"
            )));
        }
        let mut env = Environment::from_rgb(shown.to_string(), w, h, rgb)?;
        if bad > 0 {
            env.warnings.push(format!(
                "environment map '{shown}': {bad} of its {texels} texels are NaN or infinite; they are taken as black"
            ));
        }
        Ok(env)
    }

    /// A uniform environment of radiance `value` (the white furnace).
    pub fn uniform(value: [f32; 3]) -> Environment {
        let (w, h) = (64, 32);
        let rgb = (0..w * h).flat_map(|_| value).collect();
        Environment::from_rgb(format!("uniform {value:?}"), w, h, rgb).expect("valid size")
    }

    /// The built-in neutral studio, generated procedurally (no image file, so no licence):
    /// a grey floor and walls brightening towards the ceiling, one large overhead soft box, a
    /// key soft box in front above the left (where the default key light comes from, see
    /// [`STUDIO_KEY_DIRECTION`]), and two tall strip lights at the sides. Achromatic, peak about 8.
    pub fn studio() -> Environment {
        let (w, h) = (512u32, 256u32);
        let mut rgb = Vec::with_capacity((w * h * 3) as usize);
        let key = glam::Vec3::from(STUDIO_KEY_DIRECTION).normalize();
        for j in 0..h {
            for i in 0..w {
                let d = pixel_dir(i, j, w, h);
                let y = d[1] as f32;
                // Floor (below the horizon), walls, ceiling.
                let smooth = |e0: f32, e1: f32, x: f32| {
                    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
                    t * t * (3.0 - 2.0 * t)
                };
                let mut l = 0.12 + 0.10 * smooth(-0.15, 0.05, y) + 0.25 * smooth(0.1, 0.9, y);
                // A soft-edged box: radiance `r` within angular half-sizes around a direction.
                let dv = glam::Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32);
                let mut panel = |centre: glam::Vec3, half: f32, r: f32| {
                    let c = dv.dot(centre);
                    let a = c.clamp(-1.0, 1.0).acos();
                    l += r * (1.0 - smooth(half * 0.7, half, a));
                };
                panel(glam::Vec3::Y, 0.45, 1.8);
                panel(key, 0.22, 8.0);
                // Strip lights: narrow in azimuth, tall in elevation, at the sides.
                for side in [-1.0f32, 1.0] {
                    let az = dv.x.atan2(-dv.z);
                    let target = side * 1.75;
                    let da = (az - target).abs();
                    if y > -0.05 && y < 0.75 {
                        l += 3.0
                            * (1.0 - smooth(0.06, 0.1, da))
                            * smooth(-0.05, 0.05, y)
                            * (1.0 - smooth(0.65, 0.75, y));
                    }
                }
                rgb.extend_from_slice(&[l, l, l]);
            }
        }
        Environment::from_rgb("built-in studio", w, h, rgb).expect("valid size")
    }

    /// A content hash (dimensions and pixels): preprocessing is cached by it.
    pub fn hash(&self) -> [u8; 32] {
        self.hash
    }

    /// The radiance of pixel (i, j).
    pub fn pixel(&self, i: u32, j: u32) -> [f32; 3] {
        let k = (j as usize * self.width as usize + i as usize) * 3;
        [self.rgb[k], self.rgb[k + 1], self.rgb[k + 2]]
    }

    /// The order-2 spherical-harmonic projection of the radiance (f64 sums over every pixel,
    /// weighted by its solid angle), pre-multiplied by the clamped-cosine convolution and 1/π:
    /// evaluating it at n ([`sh_eval`]) gives irradiance/π, the radiance of a white Lambertian
    /// surface (Ramamoorthi & Hanrahan 2001). Pixels are in env space.
    pub fn sh9(&self) -> [[f32; 3]; 9] {
        let mut c = [[0f64; 3]; 9];
        let (w, h) = (self.width, self.height);
        let d_phi = 2.0 * PI / w as f64;
        let d_theta = PI / h as f64;
        for j in 0..h {
            let theta = (j as f64 + 0.5) * d_theta;
            let d_omega = d_phi * d_theta * theta.sin();
            for i in 0..w {
                let d = pixel_dir(i, j, w, h);
                let y = sh_basis(d);
                let p = self.pixel(i, j);
                for (k, yk) in y.iter().enumerate() {
                    for ch in 0..3 {
                        c[k][ch] += p[ch] as f64 * yk * d_omega;
                    }
                }
            }
        }
        let band = [PI, 2.0 * PI / 3.0, PI / 4.0];
        let mut out = [[0f32; 3]; 9];
        for k in 0..9 {
            let l = if k == 0 {
                0
            } else if k < 4 {
                1
            } else {
                2
            };
            for ch in 0..3 {
                out[k][ch] = (c[k][ch] * band[l] / PI) as f32;
            }
        }
        out
    }
}

/// The direction the built-in studio's key soft box is in, and the default key light comes from
/// (world space, before `--env-rotation`): above, in front (towards +z, the default camera side)
/// and to the left.
pub const STUDIO_KEY_DIRECTION: [f32; 3] = [-0.55, 0.95, 0.75];

/// The centre direction of pixel (i, j) of a `w` x `h` equirectangular image.
pub fn pixel_dir(i: u32, j: u32, w: u32, h: u32) -> [f64; 3] {
    uv_to_dir((i as f64 + 0.5) / w as f64, (j as f64 + 0.5) / h as f64)
}

/// Equirectangular (u, v) to a unit direction.
pub fn uv_to_dir(u: f64, v: f64) -> [f64; 3] {
    let theta = PI * v;
    let phi = 2.0 * PI * (u - 0.5);
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    [st * sp, ct, -st * cp]
}

/// A unit direction to equirectangular (u, v), u in [0, 1).
pub fn dir_to_uv(d: [f64; 3]) -> (f64, f64) {
    let u = 0.5 + d[0].atan2(-d[2]) / (2.0 * PI);
    let v = d[1].clamp(-1.0, 1.0).acos() / PI;
    (u.rem_euclid(1.0), v)
}

/// The nine real SH basis functions at unit direction d (bands 0..2), in f64: the one Rust copy
/// of the basis is [`crate::reference::ibl_twin::formula::sh_basis`].
pub fn sh_basis(d: [f64; 3]) -> [f64; 9] {
    crate::reference::ibl_twin::formula::sh_basis(d)
}

/// `sh_irradiance` of glsl/include/ibl.glsl: irradiance/π at env-space normal n from
/// [`Environment::sh9`], clamped at 0 (order-2 SH ring below zero opposite a sun).
pub fn sh_eval(sh: &[[f32; 3]; 9], n: [f32; 3]) -> [f32; 3] {
    crate::reference::ibl_twin::formula::sh_irradiance(sh, n)
}

/// The world direction of env-space direction `e` under `--env-rotation degrees` (the transpose
/// of [`env_from_world`]).
pub fn world_from_env(rotation_degrees: f32, e: [f64; 3]) -> [f64; 3] {
    let r = env_from_world(rotation_degrees).map(|row| row.map(|x| x as f64));
    [
        r[0][0] * e[0] + r[1][0] * e[1] + r[2][0] * e[2],
        r[0][1] * e[0] + r[1][1] * e[1] + r[2][1] * e[2],
        r[0][2] * e[0] + r[1][2] * e[1] + r[2][2] * e[2],
    ]
}

/// The environment-from-world rotation for `--env-rotation degrees` (about +y), as rows.
pub fn env_from_world(rotation_degrees: f32) -> [[f32; 3]; 3] {
    // World direction w is env direction R(θ) e; so e = R(-θ) w.
    let (s, c) = (-rotation_degrees.to_radians()).sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// What is shown where no surface is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Background {
    /// The environment, blurred by `blur` (0 sharp, 1 the coarsest level).
    Env { blur: f32 },
    /// A constant linear colour.
    Color([f32; 3]),
    /// Transparent (alpha 0 in the PNG).
    None,
}

impl Background {
    /// `env`, `env:BLUR`, `color`, `color:R,G,B` (linear), `none`.
    pub fn parse(text: &str) -> crate::Result<Background> {
        let bad = || {
            Error::input(format!(
                "unknown background '{text}': choose env, env:BLUR (0..1), color, color:R,G,B (linear) or none"
            ))
        };
        match text {
            "env" => Ok(Background::Env { blur: 0.0 }),
            "color" => Ok(Background::Color(DEFAULT_BACKGROUND)),
            "none" => Ok(Background::None),
            _ => {
                if let Some(b) = text.strip_prefix("env:") {
                    let blur: f32 = b.parse().map_err(|_| bad())?;
                    if (0.0..=1.0).contains(&blur) {
                        return Ok(Background::Env { blur });
                    }
                    return Err(bad());
                }
                if let Some(c) = text.strip_prefix("color:") {
                    let v = crate::parse::parse_vec3("background colour", c)?;
                    if v.min_element() < 0.0 || v.max_element() > 1e4 {
                        return Err(bad());
                    }
                    return Ok(Background::Color(v.into()));
                }
                Err(bad())
            }
        }
    }
}

/// The name of the ground material [`stage`] adds (not a material of the file).
pub const GROUND_MATERIAL: &str = "default ground";

/// The colour background's default (linear): the dark blue-grey weft has always used.
pub const DEFAULT_BACKGROUND: [f32; 3] = [0.010, 0.012, 0.016];

/// How the environment's light is integrated (the IBL accuracy levels, model page §6).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IblLevel {
    /// Fabric lobes: the radiance at the mirror direction, blurred to the lobe's width, times
    /// Fresnel; glTF materials: the split sum.
    Approx,
    /// Fabric lobes: filtered importance sampling with N samples (Křivánek & Colbert 2008) from
    /// the lobes' own A–S sampler; glTF materials: the split sum.
    Fis(u32),
    /// Ground truth: brute-force Monte Carlo with N samples per pixel (BRDF sampling of every lobe
    /// and cosine sampling of the diffuse, the unfiltered environment, per-pixel random rotation).
    MonteCarlo(u32),
}

impl IblLevel {
    pub const MAX_SAMPLES: u32 = 4096;

    pub fn name(self) -> String {
        match self {
            IblLevel::Approx => "approx".into(),
            IblLevel::Fis(n) => format!("fis:{n}"),
            IblLevel::MonteCarlo(n) => format!("mc:{n}"),
        }
    }

    pub fn parse(text: &str) -> crate::Result<IblLevel> {
        let bad = || {
            Error::input(format!(
                "unknown IBL level '{text}': choose approx, fis:N or mc:N (N from 1 to {})",
                IblLevel::MAX_SAMPLES
            ))
        };
        if text == "approx" {
            return Ok(IblLevel::Approx);
        }
        let (kind, n) = text.split_once(':').ok_or_else(bad)?;
        let n: u32 = n.parse().map_err(|_| bad())?;
        if !(1..=IblLevel::MAX_SAMPLES).contains(&n) {
            return Err(bad());
        }
        match kind {
            "fis" => Ok(IblLevel::Fis(n)),
            "mc" => Ok(IblLevel::MonteCarlo(n)),
            _ => Err(bad()),
        }
    }

    /// The IBL specialization constant of lighting.frag (0 is "no environment").
    pub fn code(self) -> u32 {
        match self {
            IblLevel::Approx => 1,
            IblLevel::Fis(_) => 2,
            IblLevel::MonteCarlo(_) => 3,
        }
    }

    pub fn samples(self) -> u32 {
        match self {
            IblLevel::Approx => 1,
            IblLevel::Fis(n) | IblLevel::MonteCarlo(n) => n,
        }
    }
}

/// The default IBL level.
pub const DEFAULT_IBL: IblLevel = IblLevel::Fis(8);

/// The default radius of the fabric lobes' pooling ([`EnvLighting::pool`]): a 3 x 3 window.
pub const DEFAULT_POOL: u32 = 1;

/// The largest radius the pooling takes (a 5 x 5 window).
pub const MAX_POOL: u32 = 2;

/// A scene lit by an environment: which, turned how far, how bright, and what the background
/// shows.
#[derive(Clone, Debug)]
pub struct EnvLighting {
    pub env: Arc<Environment>,
    /// Degrees about +y.
    pub rotation: f32,
    /// Radiance scale.
    pub intensity: f32,
    pub background: Background,
    pub level: IblLevel,
    /// At fis, the deferred lighting pools the woven model's lobe samples over the pixels within
    /// this radius whose surface agrees (fabric_lobes.frag and lighting.frag's POOL; default
    /// [`DEFAULT_POOL`]). 0: each pixel estimates its lobes alone, as the forward pass does
    /// (`weft bench --ibl` measures both).
    pub pool: u32,
}

impl EnvLighting {
    pub fn new(env: Arc<Environment>) -> EnvLighting {
        EnvLighting {
            env,
            rotation: 0.0,
            intensity: 1.0,
            background: Background::Env { blur: 0.0 },
            level: DEFAULT_IBL,
            pool: DEFAULT_POOL,
        }
    }

    pub fn validate(&self) -> crate::Result<()> {
        if self.pool > MAX_POOL {
            return Err(Error::input(format!(
                "--ibl-pool {} is out of range: give 0 (each pixel alone), 1 (3x3 pixels, the default) or {MAX_POOL} (5x5)",
                self.pool
            )));
        }
        if !self.rotation.is_finite() || self.rotation.abs() > 1e6 {
            return Err(Error::input(format!(
                "--env-rotation {} is out of range: give degrees, a finite number",
                self.rotation
            )));
        }
        if !(self.intensity >= 0.0 && self.intensity <= 1e6) {
            return Err(Error::input(format!(
                "--env-intensity {} is out of range: give a number from 0 to 1e6",
                self.intensity
            )));
        }
        Ok(())
    }
}

/// The split-sum DFG table of the GGX lobe with the height-correlated Smith visibility of
/// `glsl/include/pbr.glsl`: for n·v = (i + 1/2)/size and roughness = (j + 1/2)/size,
/// `(A, B)` with `∫ f·cos = F0·A + B` (Karis 2013), by 1024-sample Hammersley quadrature of the
/// GGX half-vector distribution in f64, and third the sheen's directional albedo E at sheen
/// roughness = (j + 1/2)/size ([`crate::reference::shading::sheen_albedo`]). Row-major, j
/// (roughness) major.
pub fn dfg_table(size: u32) -> Vec<[f32; 3]> {
    let mut out = Vec::with_capacity((size * size) as usize);
    for j in 0..size {
        let roughness = (j as f64 + 0.5) / size as f64;
        for i in 0..size {
            let nv = (i as f64 + 0.5) / size as f64;
            let [a, b] = dfg(nv, roughness, 1024).map(|x| x as f32);
            let e = crate::reference::shading::sheen_albedo(nv, roughness as f32, 24) as f32;
            out.push([a, b, e]);
        }
    }
    out
}

pub use crate::reference::shading::{dfg_table_kept, DFG_SIZE};

/// The DFG integral at one (n·v, roughness): see [`dfg_table`]. The BRDF is the project's one
/// Rust copy of the glTF BRDF ([`crate::reference::shading::pbr_brdf_cos`], f32, accumulated in
/// f64): with metallic 1, F0 = base, so B = ∫ f·cos at base 0 and A + B at base 1.
pub fn dfg(nv: f64, roughness: f64, samples: u32) -> [f64; 2] {
    use crate::reference::shading::{ggx_d, pbr_brdf_cos};
    let r = roughness as f32;
    let alpha = (roughness * roughness).max(1e-3);
    let v = [(1.0 - nv * nv).max(0.0).sqrt(), 0.0, nv];
    let vf = v.map(|x| x as f32);
    let (mut ab, mut b) = (0.0, 0.0);
    for s in 0..samples {
        let (x1, x2) = hammersley(s, samples);
        // GGX half vector (ibl.glsl's ggx_sample_h): pdf D(h)·(n·h).
        let h = crate::reference::ibl_twin::formula::ggx_sample_h::<f64>([x1, x2], alpha);
        let cos_t = h[2];
        let vh = v[0] * h[0] + v[2] * h[2];
        let l = [
            2.0 * vh * h[0] - v[0],
            2.0 * vh * h[1] - v[1],
            2.0 * vh * h[2] - v[2],
        ];
        if l[2] <= 0.0 || vh <= 0.0 {
            continue;
        }
        // pdf of l: D·(n·h)/(4 v·h).
        let pdf = ggx_d(cos_t as f32, alpha as f32) as f64 * cos_t / (4.0 * vh);
        let lf = l.map(|x| x as f32);
        let n = [0.0, 0.0, 1.0];
        ab += pbr_brdf_cos(n, vf, lf, [1.0; 3], 1.0, r)[0] as f64 / pdf;
        b += pbr_brdf_cos(n, vf, lf, [0.0; 3], 1.0, r)[0] as f64 / pdf;
    }
    let n = samples as f64;
    [(ab - b) / n, b / n]
}

/// The Hammersley point i of n in [0, 1)²: (i/n, radical inverse of i in base 2).
pub fn hammersley(i: u32, n: u32) -> (f64, f64) {
    let [x, y] = crate::reference::ibl_twin::formula::hammersley::<f64>(i, n);
    (x, y)
}

#[cfg(test)]
mod kept_dfg {
    use super::*;

    #[test]
    fn kept_dfg_table_matches_a_fresh_computation() {
        let size = DFG_SIZE;
        let fresh: Vec<[half::f16; 3]> = dfg_table(size)
            .iter()
            .map(|t| t.map(half::f16::from_f32))
            .collect();
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/reference/dfg_table.f16");
        if std::env::var_os("WEFT_WRITE_DFG").is_some() {
            let bytes: Vec<u8> = fresh
                .iter()
                .flat_map(|t| t.iter().flat_map(|h| h.to_bits().to_le_bytes()))
                .collect();
            std::fs::write(&path, bytes).unwrap();
            return;
        }
        let kept = dfg_table_kept();
        assert_eq!(
            kept.len(),
            fresh.len(),
            "src/reference/dfg_table.f16 has the wrong size: rewrite it (WEFT_WRITE_DFG=1)"
        );
        // Within one f16 step: the computation is deterministic, but libm's last bit may differ
        // between platforms.
        for (i, (k, f)) in kept.iter().zip(&fresh).enumerate() {
            for c in 0..3 {
                let d = (k[c].to_bits() as i32 - f[c].to_bits() as i32).abs();
                assert!(d <= 1, "entry {i} channel {c}: kept {} fresh {}: rewrite src/reference/dfg_table.f16 with WEFT_WRITE_DFG=1", k[c], f[c]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_round_trip_and_convention() {
        let (u, v) = dir_to_uv([0.0, 0.0, -1.0]);
        assert!((u - 0.5).abs() < 1e-12 && (v - 0.5).abs() < 1e-12);
        let (u, _) = dir_to_uv([1.0, 0.0, 0.0]);
        assert!((u - 0.75).abs() < 1e-12);
        let (_, v) = dir_to_uv([0.0, 1.0, 0.0]);
        assert!(v.abs() < 1e-12);
        for (u, v) in [(0.1, 0.2), (0.7, 0.9), (0.5, 0.5)] {
            let (u2, v2) = dir_to_uv(uv_to_dir(u, v));
            assert!((u - u2).abs() < 1e-9 && (v - v2).abs() < 1e-9);
        }
    }

    #[test]
    fn sh_of_a_uniform_environment_is_its_radiance() {
        // A white Lambertian surface under uniform radiance L reflects L in every direction.
        let env = Environment::uniform([1.0, 0.5, 2.0]);
        let sh = env.sh9();
        for n in [[0.0, 1.0, 0.0], [0.6, 0.0, 0.8], [0.0, -1.0, 0.0]] {
            let e = sh_eval(&sh, n);
            for (c, want) in e.iter().zip([1.0, 0.5, 2.0]) {
                assert!((c - want).abs() < 2e-3 * want, "{e:?} at {n:?}");
            }
        }
    }

    #[test]
    fn dfg_of_a_white_metal_is_about_one_when_smooth() {
        // F0 = 1: A + B is the single-scattering albedo, 1 for a smooth mirror, less when rough
        // (energy lost to multiple scattering).
        let [a, b] = dfg(0.9, 0.05, 1024);
        assert!((a + b - 1.0).abs() < 0.01, "{}", a + b);
        let [a, b] = dfg(0.5, 1.0, 4096);
        assert!(a + b > 0.4 && a + b < 0.9, "{}", a + b);
    }

    #[test]
    fn backgrounds_and_levels_parse() {
        assert_eq!(
            Background::parse("env:0.5").unwrap(),
            Background::Env { blur: 0.5 }
        );
        assert_eq!(Background::parse("none").unwrap(), Background::None);
        assert!(Background::parse("env:2").is_err());
        assert!(Background::parse("colour").is_err());
        for l in [
            IblLevel::Approx,
            IblLevel::Fis(16),
            IblLevel::MonteCarlo(256),
        ] {
            assert_eq!(IblLevel::parse(&l.name()).unwrap(), l);
        }
        for bad in ["fis:0", "mc:x", "fis", "exact", "fis:5000"] {
            assert!(IblLevel::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn bad_values_are_cleaned() {
        let e = Environment::from_rgb(
            "t",
            2,
            1,
            vec![f32::NAN, -1.0, f32::INFINITY, 1.0, 2.0, 3.0],
        )
        .unwrap();
        assert_eq!(&e.rgb[..3], &[0.0, 0.0, MAX_RADIANCE]);
        assert!(Environment::from_rgb("t", 0, 1, vec![]).is_err());
    }
}

/// Which punctual lights light the scene (`--lights`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightsMode {
    /// The file's lights when it has any; otherwise the default key light and ground, unless an
    /// environment of the user's own (`--env FILE`) lights the scene.
    Auto,
    /// No punctual lights at all (the environment only).
    None,
    /// The file's lights only (none if it has none).
    File,
    /// The default key light (with a shadow map) and a shadow-catching ground, instead of the
    /// file's lights.
    Default,
}

impl LightsMode {
    pub fn parse(text: &str) -> crate::Result<LightsMode> {
        match text {
            "auto" => Ok(LightsMode::Auto),
            "none" => Ok(LightsMode::None),
            "file" => Ok(LightsMode::File),
            "default" => Ok(LightsMode::Default),
            _ => Err(Error::input(format!(
                "unknown --lights '{text}': choose auto, none, file or default"
            ))),
        }
    }
}

/// Illuminance of the default key light (lux, KHR_lights_punctual units).
pub const KEY_LIGHT_LUX: f32 = 2.0;

/// Lights `scene` as `mode` says: removes the file's lights (`none`, `default`), or adds the
/// default key light, a directional light from the studio's key soft box (turned with the
/// environment by `rotation` degrees) that casts a shadow map, and a ground under the scene that
/// receives shadows but casts none, so objects sit on something. `own_env`: the user gave an
/// environment map (then `auto` adds nothing to a file without lights). Returns whether the
/// default key light was added.
///
/// A scene without cameras gets its automatic framing as a camera first, so the ground does not
/// change what the camera frames.
pub fn stage(
    scene: &mut crate::scene::Scene,
    mode: LightsMode,
    rotation: f32,
    own_env: bool,
) -> bool {
    use crate::scene::{Draw, Light, LightKind, Material, Mesh, Shadow, Vertex};
    let add_default = match mode {
        LightsMode::Auto => scene.lights.is_empty() && !own_env,
        LightsMode::Default => true,
        LightsMode::None | LightsMode::File => false,
    };
    if matches!(mode, LightsMode::None | LightsMode::Default) {
        scene.lights.clear();
    }
    if !add_default {
        return false;
    }
    let Some(bounds) = scene.bounds() else {
        return false;
    };
    // The key light stays where it is for the camera: when automatic framing looks from
    // another side (the one a single-sided sheet faces), the light turns with it.
    let mut turn = 0.0;
    if scene.cameras.is_empty() {
        let camera = scene.auto_camera();
        scene.cameras.push(camera);
        turn = scene.framing_azimuth();
    }
    let k = glam::Vec3::from(STUDIO_KEY_DIRECTION)
        .normalize()
        .as_dvec3();
    let to_light = glam::DVec3::from(world_from_env(rotation + turn, k.into())).as_vec3();
    scene.lights.push(Light {
        name: "default key light".into(),
        kind: LightKind::Directional,
        color: [1.0, 0.98, 0.95],
        intensity: KEY_LIGHT_LUX,
        range: None,
        position: glam::Vec3::ZERO,
        direction: -to_light,
        shadow: Some(Shadow {
            resolution: 2048,
            filter_radius: 2.0,
            bias: 1.5,
        }),
    });
    // The ground: a square 12 scene radii across, just under the lowest point.
    let center = (bounds.min + bounds.max) * 0.5;
    let radius = ((bounds.max - bounds.min).length() * 0.5).max(1e-3);
    let half = radius * 6.0;
    let y = bounds.min.y - radius * 1e-3;
    let corner = |x: f32, z: f32, u: f32, v: f32| Vertex {
        position: [center.x + x * half, y, center.z + z * half],
        normal: [0.0, 1.0, 0.0],
        tangent: [1.0, 0.0, 0.0, 1.0],
        uv: [u, v],
        uv1: [0.0; 2],
    };
    let material = scene.materials.len();
    scene.materials.push(Material {
        name: GROUND_MATERIAL.into(),
        base_color: [0.3, 0.3, 0.3, 1.0],
        metallic: 0.0,
        roughness: 0.85,
        ..Material::default()
    });
    scene.meshes.push(Mesh {
        name: "default ground".into(),
        vertices: vec![
            corner(-1.0, -1.0, 0.0, 0.0),
            corner(-1.0, 1.0, 0.0, 1.0),
            corner(1.0, 1.0, 1.0, 1.0),
            corner(1.0, -1.0, 1.0, 0.0),
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
        colors: Vec::new(),
        topology: crate::scene::Topology::Triangles,
    });
    scene.draws.push(Draw {
        mesh: scene.meshes.len() - 1,
        world: glam::Mat4::IDENTITY,
        cast_shadows: false,
        receive_shadows: true,
        visible: true,
    });
    true
}
