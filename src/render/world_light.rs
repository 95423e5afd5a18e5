//! The world light (issue 28): what each vertex of the scene sees of the rest of it, baked on the
//! CPU by rays against the scene's triangles, for the environment's light that a screen cannot
//! account for. The occlusion pass (GTAO) knows only what the depth buffer shows: the seat of a
//! chair seen level with it hides its top, whose light is what brightens the backrest above it.
//!
//! Each receiving vertex casts [`RAYS`] cosine-distributed rays over its normal's hemisphere (a
//! Hammersley set turned by a hash of the vertex) against a BVH of the scene's opaque triangles
//! (`obvhs`). A ray that escapes sees the environment; one that hits a surface sees that surface's
//! diffuse light: its albedo (base colour factor × texture × vertex colour, less its metallic
//! share) times the environment's irradiance at its normal (the order-2 SH of the map,
//! `Environment::sh9`, as the glTF BRDF's diffuse takes it), times that surface's own share of
//! the sky (a first pass's), plus what it emits. Per vertex the bake keeps
//!
//! - a: the share of its rays that escape (the cosine-weighted visibility of the environment);
//! - rgb: the mean of the hit surfaces' radiance over all its rays (irradiance/π from the scene's
//!   surfaces: one bounce of the environment's diffuse light, and what they emit).
//!
//! A hit nearer the vertex than the longest edge of its triangles counts in proportion to its
//! distance ([`reach`]): what is that near hides a different share of the sky at each point of a
//! triangle, which the corners cannot carry; the screen's occlusion has it.
//!
//! The G-buffer pass interpolates them over each triangle into its specular target (which the
//! plan gives the world light only where no material needs KHR_materials_specular's data), and
//! the lighting pass takes, per pixel, the smaller of the screen's visibility and the world's and
//! the larger of the two bounces (lighting_main.glsl, OCCLUSION's bit 2). Planned only for a static
//! scene lit by an environment, with the occlusion pass's bounce, and within [`MAX_RAYS`]
//! (`Plan::occlusion`'s `world`).

use crate::scene::{ColorSpace, Draw, Material, Scene, Texture, TextureSlot, Topology};
use glam::{Mat3, Vec3, Vec3A};
use obvhs::{
    cwbvh::builder::build_cwbvh_from_tris,
    ray::{Ray, RayHit},
    triangle::Triangle,
    BvhBuildParams,
};

/// Rays per vertex.
pub const RAYS: u32 = 64;

/// The most rays a scene's bake casts (receiving vertices × [`RAYS`]; each ray's hit, 8 bytes,
/// is kept for the second pass): beyond it the plan leaves the world light off and says why. On
/// two cores a bake traces about 4 million rays a second (docs/performance.md).
pub const MAX_RAYS: u64 = 4_000_000;

/// The environment's diffuse light as the bake takes it: irradiance/π at a world normal.
#[derive(Clone, Debug)]
pub struct SkyLight {
    /// `Environment::sh9` of the map (env space).
    pub sh: [[f32; 3]; 9],
    /// `--env-rotation` in degrees.
    pub rotation: f32,
    /// `--env-intensity`.
    pub intensity: f32,
}

impl SkyLight {
    /// Irradiance/π at world normal n.
    fn at(&self, n: Vec3) -> Vec3 {
        let r = crate::env::env_from_world(self.rotation);
        let e = [
            r[0][0] * n.x + r[0][1] * n.y + r[0][2] * n.z,
            r[1][0] * n.x + r[1][1] * n.y + r[1][2] * n.z,
            r[2][0] * n.x + r[2][1] * n.y + r[2][2] * n.z,
        ];
        Vec3::from(crate::env::sh_eval(&self.sh, e)) * self.intensity
    }
}

/// Whether draw `d` takes the world light: drawn by the G-buffer pass as triangles.
pub fn receives(scene: &Scene, d: &Draw) -> bool {
    let Some(mesh) = scene.meshes.get(d.mesh) else {
        return false;
    };
    d.visible
        && mesh.topology == Topology::Triangles
        && mesh.indices.len() >= 3
        && scene.mesh_material(mesh).is_none_or(|m| !m.needs_forward())
}

/// Whether draw `d` hides the environment from others: opaque (or cut out) triangles; glass and
/// blended surfaces let the light through.
pub fn occludes(scene: &Scene, d: &Draw) -> bool {
    let Some(mesh) = scene.meshes.get(d.mesh) else {
        return false;
    };
    d.visible
        && mesh.topology == Topology::Triangles
        && mesh.indices.len() >= 3
        && scene.mesh_material(mesh).is_none_or(|m| {
            !m.blended() && m.transmission.is_none() && m.diffuse_transmission.is_none()
        })
}

/// The vertices that receive and the triangles that occlude: what a bake costs.
pub fn extent(scene: &Scene) -> (usize, usize) {
    let vertices = scene
        .draws
        .iter()
        .filter(|d| receives(scene, d))
        .map(|d| scene.meshes[d.mesh].vertices.len())
        .sum();
    let triangles = scene
        .draws
        .iter()
        .filter(|d| occludes(scene, d))
        .map(|d| scene.meshes[d.mesh].indices.len() / 3)
        .sum();
    (vertices, triangles)
}

/// The longest edge of any triangle of a receiving draw, in world units: the vertices' spacing,
/// below which the world light cannot hold what changes across a triangle ([`reach`]). Each
/// vertex moved to world space once, the edges compared squared (the plan asks every frame:
/// SheenCloth under its staged ground 0.60 ms on this project's two cores, 0.88 ms with three
/// transforms per triangle). An edge too long for an f32 square counts as infinite; the edges
/// of a vertex that is not a number, not at all.
pub fn longest_receiving_edge(scene: &Scene) -> f32 {
    let mut longest = 0f32;
    let mut world = Vec::new();
    for d in scene.draws.iter().filter(|d| receives(scene, d)) {
        let mesh = &scene.meshes[d.mesh];
        world.clear();
        world.extend(
            mesh.vertices
                .iter()
                .map(|v| d.world.transform_point3(Vec3::from(v.position))),
        );
        for t in mesh.indices.chunks_exact(3) {
            let at = |k: usize| world.get(t[k] as usize).copied();
            if let (Some(a), Some(b), Some(c)) = (at(0), at(1), at(2)) {
                let e = a
                    .distance_squared(b)
                    .max(b.distance_squared(c))
                    .max(c.distance_squared(a));
                if !e.is_nan() {
                    longest = longest.max(e);
                }
            }
        }
    }
    longest.sqrt()
}

/// A scene's baked world light.
pub struct Bake {
    /// Per receiving vertex, draw after draw: rgb the scene's surfaces' light over its
    /// hemisphere (irradiance/π), a the environment's cosine-weighted visibility.
    pub texels: Vec<[f32; 4]>,
    /// Per scene draw, where its vertices' entries begin (None: the draw does not receive).
    pub base: Vec<Option<u32>>,
}

/// One occluding draw, in world space.
struct Occluder {
    /// Its index in `Scene::draws`.
    index: usize,
    normal_matrix: Mat3,
}

/// Each occluder's cut-out, as bits: alphaMode MASK's cutoff and its base colour factor's alpha
/// (what [`Tracer::opaque_at`] reads besides the textures, which an upload fixes).
fn cutouts(scene: &Scene, occluders: &[Occluder]) -> Vec<(u32, u32)> {
    occluders
        .iter()
        .map(|o| {
            o.material(scene)
                .and_then(|m| Some((m.alpha_cutoff?.to_bits(), m.base_color[3].to_bits())))
                .unwrap_or((u32::MAX, 0))
        })
        .collect()
}

impl Occluder {
    fn draw<'s>(&self, scene: &'s Scene) -> &'s Draw {
        &scene.draws[self.index]
    }

    fn material<'s>(&self, scene: &'s Scene) -> Option<&'s Material> {
        scene.mesh_material(&scene.meshes[self.draw(scene).mesh])
    }
}

/// A vertex that receives: where it is, its normal, and the longest edge of its triangles.
struct Receiver {
    p: Vec3,
    n: Vec3,
    edge: f32,
}

/// Bakes the scene's world light under `sky` (see the module's documentation): its rays
/// traced ([`trace`]), then their hits shaded under the sky ([`shade`]).
pub fn bake(scene: &Scene, sky: &SkyLight) -> Bake {
    shade(&trace(scene), scene, sky)
}

/// The half of a bake that does not depend on the sky: the scene's triangles in a BVH, each
/// receiving vertex's rays traced to their nearest hits and its visibility. A renderer traces it
/// while its pipelines compile, before the environment's SH is known, and keeps it for the
/// scene's next sky (a viewer turning the environment shades again without tracing). It holds
/// for the scene it was traced from: the same draws, meshes and materials' cut-outs.
pub struct Traced {
    occluders: Vec<Occluder>,
    tris: Vec<Triangle>,
    owner: Vec<(u32, u32)>,
    /// None where nothing occludes or nothing receives.
    bvh: Option<obvhs::cwbvh::CwBvh>,
    eps: f32,
    receivers: Vec<Receiver>,
    base: Vec<Option<u32>>,
    /// Per receiver, per ray: the nearest triangle (u32::MAX: escapes) and its distance.
    hits: Vec<Vec<(u32, f32)>>,
    visibility: Vec<f32>,
    /// The occluders' cut-outs as traced ([`cutouts`]).
    cutouts: Vec<(u32, u32)>,
}

impl Traced {
    /// Whether these rays hold for `scene` (the scene they were traced from, its materials
    /// perhaps rewritten since, `Renderer::update_material_records`): the same occluders with
    /// the same cut-outs. Colours may change: [`shade`] reads them.
    pub fn holds_for(&self, scene: &Scene) -> bool {
        self.occluders
            .iter()
            .all(|o| scene.draws.get(o.index).is_some_and(|d| occludes(scene, d)))
            && cutouts(scene, &self.occluders) == self.cutouts
    }

    fn tracer<'a>(&'a self, scene: &'a Scene) -> Option<Tracer<'a>> {
        Some(Tracer {
            scene,
            occluders: &self.occluders,
            tris: &self.tris,
            owner: &self.owner,
            bvh: self.bvh.as_ref()?,
            eps: self.eps,
        })
    }
}

/// Traces the scene's rays (the sky-independent half of [`bake`]).
pub fn trace(scene: &Scene) -> Traced {
    // The occluders' triangles, in world space, and which draw and triangle each is.
    let occluders: Vec<Occluder> = scene
        .draws
        .iter()
        .enumerate()
        .filter(|(_, d)| occludes(scene, d))
        .map(|(index, d)| Occluder {
            index,
            normal_matrix: normal_matrix(d),
        })
        .collect();
    let mut tris = Vec::new();
    let mut owner: Vec<(u32, u32)> = Vec::new();
    for (o, occ) in occluders.iter().enumerate() {
        let draw = occ.draw(scene);
        let mesh = &scene.meshes[draw.mesh];
        let pos = |i: u32| -> Vec3A {
            let v = mesh
                .vertices
                .get(i as usize)
                .map_or([0.0; 3], |v| v.position);
            draw.world.transform_point3(Vec3::from(v)).into()
        };
        for (t, idx) in mesh.indices.chunks_exact(3).enumerate() {
            let tri = Triangle {
                v0: pos(idx[0]),
                v1: pos(idx[1]),
                v2: pos(idx[2]),
            };
            if !(tri.v0.is_finite() && tri.v1.is_finite() && tri.v2.is_finite()) {
                continue;
            }
            tris.push(tri);
            owner.push((o as u32, t as u32));
        }
    }
    // The receivers' vertices, draw after draw.
    let mut receivers = Vec::new();
    let mut base = vec![None; scene.draws.len()];
    for (i, d) in scene.draws.iter().enumerate() {
        if !receives(scene, d) {
            continue;
        }
        base[i] = Some(receivers.len() as u32);
        let m = normal_matrix(d);
        let mesh = &scene.meshes[d.mesh];
        let first = receivers.len();
        receivers.extend(mesh.vertices.iter().map(|v| Receiver {
            p: d.world.transform_point3(Vec3::from(v.position)),
            n: (m * Vec3::from(v.normal)).normalize_or_zero(),
            edge: 0.0,
        }));
        for t in mesh.indices.chunks_exact(3) {
            let at = |k: usize| receivers.get(first + t[k] as usize).map(|r| r.p);
            let (Some(a), Some(b), Some(c)) = (at(0), at(1), at(2)) else {
                continue;
            };
            let longest = a.distance(b).max(b.distance(c)).max(c.distance(a));
            for &k in t {
                if let Some(r) = receivers.get_mut(first + k as usize) {
                    r.edge = r.edge.max(longest);
                }
            }
        }
    }
    if tris.is_empty() || receivers.is_empty() {
        let visibility = vec![1.0; receivers.len()];
        return Traced {
            cutouts: cutouts(scene, &occluders),
            occluders,
            tris,
            owner,
            bvh: None,
            eps: 0.0,
            receivers,
            base,
            hits: Vec::new(),
            visibility,
        };
    }
    let bvh = build_cwbvh_from_tris(
        &tris,
        BvhBuildParams::medium_build(),
        &mut std::time::Duration::default(),
    );
    // How far a ray starts from its vertex and ignores hits: a ten-thousandth of the scene.
    let (lo, hi) = tris.iter().fold(
        (Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN)),
        |(lo, hi), t| {
            (
                lo.min(t.v0.min(t.v1.min(t.v2))),
                hi.max(t.v0.max(t.v1.max(t.v2))),
            )
        },
    );
    let eps = ((hi - lo).length() * 1e-4).max(1e-6);
    let tracer = Tracer {
        scene,
        occluders: &occluders,
        tris: &tris,
        owner: &owner,
        bvh: &bvh,
        eps,
    };
    // First pass: each vertex's visibility (the hit surfaces' own, in the second, comes from
    // it: the light a surface sends on is what reaches it).
    // Each ray once: its nearest hit (the triangle and distance; u32::MAX where it escapes),
    // kept for the second pass, and the vertex's visibility from them.
    let hits: Vec<Vec<(u32, f32)>> = parallel_map(&receivers, |i, r| {
        (0..RAYS)
            .map(|k| tracer.nearest(r, i, k).unwrap_or((u32::MAX, 0.0)))
            .collect()
    });
    let visibility: Vec<f32> = receivers
        .iter()
        .zip(&hits)
        .map(|(r, h)| {
            let hidden: f32 = h
                .iter()
                .filter(|(p, _)| *p != u32::MAX)
                .map(|(_, t)| reach(r, *t))
                .sum();
            1.0 - hidden / RAYS as f32
        })
        .collect();
    Traced {
        cutouts: cutouts(scene, &occluders),
        occluders,
        tris,
        owner,
        bvh: Some(bvh),
        eps,
        receivers,
        base,
        hits,
        visibility,
    }
}

/// The hits of `traced` (traced from `scene`) shaded under `sky` (the second half of [`bake`]).
pub fn shade(traced: &Traced, scene: &Scene, sky: &SkyLight) -> Bake {
    let Some(tracer) = traced.tracer(scene) else {
        return Bake {
            texels: vec![[0.0, 0.0, 0.0, 1.0]; traced.receivers.len()],
            base: traced.base.clone(),
        };
    };
    let (occluders, receivers, hits, visibility, base) = (
        &traced.occluders,
        &traced.receivers,
        &traced.hits,
        &traced.visibility,
        &traced.base,
    );
    let texels = parallel_map(receivers, |i, r| {
        let mut light = Vec3::ZERO;
        for (k, &(p, t)) in hits[i].iter().enumerate() {
            if p == u32::MAX {
                continue;
            }
            let Hit {
                occluder: o,
                indices: idx,
                bary,
                dir,
                t,
            } = tracer.hit(r, i, k as u32, p as usize, t);
            let occ = &occluders[o as usize];
            let mesh = &scene.meshes[occ.draw(scene).mesh];
            // The hit surface's own visibility, interpolated as the G-buffer would.
            // (Where the occluding draw does not receive, its visibility is taken as 1.)
            let vis = base[occ.index].map_or(1.0, |b| {
                (0..3)
                    .map(|j| {
                        visibility
                            .get((b + idx[j]) as usize)
                            .copied()
                            .unwrap_or(1.0)
                            * bary[j]
                    })
                    .sum::<f32>()
            });
            light += tracer.radiance(occ, mesh, idx, bary, dir, sky, vis) * reach(r, t);
        }
        let l = light / RAYS as f32;
        let v = visibility[i];
        let finite = |x: f32| if x.is_finite() { x.max(0.0) } else { 0.0 };
        [finite(l.x), finite(l.y), finite(l.z), finite(v).min(1.0)]
    });
    Bake {
        texels,
        base: base.clone(),
    }
}

/// The bake of `key` ([`cache_key`]) from weft's cache on disk (src/cache.rs), when it holds one
/// that fits `scene`'s draws.
pub fn read_cached(scene: &Scene, key: &[u8]) -> Option<Bake> {
    let bake = crate::cache::read(CACHE_KIND, key).and_then(|p| decode(&p))?;
    // Each draw's vertices within the texels (the shader indexes them unchecked).
    let fits = bake.base.len() == scene.draws.len()
        && scene.draws.iter().zip(&bake.base).all(|(d, b)| {
            b.is_none_or(|b| {
                let n = scene.meshes.get(d.mesh).map_or(0, |m| m.vertices.len());
                b as usize + n <= bake.texels.len()
            })
        });
    fits.then_some(bake)
}

/// Keeps `bake` in weft's cache on disk under `key` (best effort).
pub fn write_cached(key: &[u8], bake: &Bake) {
    crate::cache::write(CACHE_KIND, key, &encode(bake));
}

const CACHE_KIND: &str = "world-light";

/// The key of a scene's bake under a sky: the scene's part ([`scene_hash`]), then the sky:
/// `env_key`, the environment's own key in the cache (its map's content, the preprocessing
/// shaders, the device and driver: what fixes the SH the frame takes), with the rotation and
/// intensity. Known before the SH is computed, so a renderer can look the bake up before it
/// starts tracing.
pub fn cache_key(scene_hash: &[u8; 32], env_key: &[u8], rotation: f32, intensity: f32) -> Vec<u8> {
    let mut key = b"world light ".to_vec();
    key.extend_from_slice(scene_hash);
    key.extend_from_slice(&rotation.to_le_bytes());
    key.extend_from_slice(&intensity.to_le_bytes());
    key.extend_from_slice(env_key);
    key
}

/// The scene's part of a bake's key: a SHA-256 of everything [`bake`] reads (the receiving and
/// occluding draws' transforms, their meshes' vertices, indices and colours, their materials'
/// base colour, metal, emission, cut-out and sides, the textures those read), the rays per
/// vertex and weft's version. The same under every sky: a renderer hashes it once per uploaded
/// scene.
pub fn scene_hash(scene: &Scene) -> [u8; 32] {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    let f = |h: &mut Sha256, v: &[f32]| {
        for x in v {
            h.update(x.to_le_bytes());
        }
    };
    h.update(b"weft world light 3 ");
    h.update(env!("CARGO_PKG_VERSION"));
    h.update(RAYS.to_le_bytes());
    let mut meshes = std::collections::BTreeSet::new();
    let mut textures = std::collections::BTreeSet::new();
    for (i, d) in scene.draws.iter().enumerate() {
        let (r, o) = (receives(scene, d), occludes(scene, d));
        if !(r || o) {
            continue;
        }
        h.update((i as u64).to_le_bytes());
        h.update([r as u8, o as u8]);
        f(&mut h, &d.world.to_cols_array());
        h.update((d.mesh as u64).to_le_bytes());
        meshes.insert(d.mesh);
    }
    for m in meshes {
        let mesh = &scene.meshes[m];
        h.update((m as u64).to_le_bytes());
        h.update((mesh.vertices.len() as u64).to_le_bytes());
        for v in &mesh.vertices {
            f(&mut h, &v.position);
            f(&mut h, &v.normal);
            f(&mut h, &v.uv);
            f(&mut h, &v.uv1);
        }
        h.update((mesh.indices.len() as u64).to_le_bytes());
        for i in &mesh.indices {
            h.update(i.to_le_bytes());
        }
        h.update((mesh.colors.len() as u64).to_le_bytes());
        for c in &mesh.colors {
            f(&mut h, c);
        }
        match scene.mesh_material(mesh) {
            None => h.update([0u8]),
            Some(mat) => {
                h.update([1u8]);
                f(&mut h, &mat.base_color);
                f(&mut h, &[mat.metallic, mat.alpha_cutoff.unwrap_or(-1.0)]);
                f(&mut h, &mat.emissive);
                h.update([mat.unlit as u8, mat.double_sided as u8]);
                for (slot, tex) in [
                    (TextureSlot::BaseColor, mat.base_color_texture),
                    (TextureSlot::Emissive, mat.emissive_texture),
                ] {
                    let map = &mat.uv[slot as usize];
                    h.update(map.set.to_le_bytes());
                    f(&mut h, &map.m[0]);
                    f(&mut h, &map.m[1]);
                    h.update(tex.map_or(u64::MAX, |t| t as u64).to_le_bytes());
                    if let Some(t) = tex {
                        textures.insert(t);
                    }
                }
            }
        }
    }
    for t in textures {
        if let Some(tex) = scene.textures.get(t) {
            h.update((t as u64).to_le_bytes());
            h.update(tex.width.to_le_bytes());
            h.update(tex.height.to_le_bytes());
            h.update([matches!(tex.color_space, ColorSpace::Srgb) as u8]);
            h.update((tex.rgba8.len() as u64).to_le_bytes());
            h.update(&tex.rgba8);
        }
    }
    h.finalize().into()
}

/// A bake as the cache's payload: the texel count, the texels (4 f32 each), the draw count, each
/// draw's base (u32::MAX: none); little-endian.
fn encode(b: &Bake) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + b.texels.len() * 16 + b.base.len() * 4);
    out.extend_from_slice(&(b.texels.len() as u64).to_le_bytes());
    for t in &b.texels {
        for x in t {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    out.extend_from_slice(&(b.base.len() as u64).to_le_bytes());
    for x in &b.base {
        out.extend_from_slice(&x.unwrap_or(u32::MAX).to_le_bytes());
    }
    out
}

/// [`encode`]'s payload back, if it is whole and its values are in range.
fn decode(p: &[u8]) -> Option<Bake> {
    let word = |at: usize| -> Option<u64> {
        Some(u64::from_le_bytes(p.get(at..at + 8)?.try_into().ok()?))
    };
    let n = usize::try_from(word(0)?).ok()?;
    let texel_bytes = n.checked_mul(16)?;
    let body = p.get(8..8usize.checked_add(texel_bytes)?)?;
    let texels: Vec<[f32; 4]> = body
        .chunks_exact(16)
        .map(|c| {
            std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))
        })
        .collect();
    if !texels.iter().flatten().all(|x| x.is_finite() && *x >= 0.0) {
        return None;
    }
    let at = 8 + texel_bytes;
    let m = usize::try_from(word(at)?).ok()?;
    let rest = p.get(at + 8..)?;
    if rest.len() != m.checked_mul(4)? {
        return None;
    }
    let base = rest
        .chunks_exact(4)
        .map(|c| {
            let x = u32::from_le_bytes(c.try_into().unwrap());
            (x != u32::MAX).then_some(x)
        })
        .collect::<Vec<_>>();
    // Every draw's vertices within the texels.
    if base.iter().flatten().any(|&b| b as usize > texels.len()) {
        return None;
    }
    Some(Bake { texels, base })
}

/// The inverse transpose of a draw's 3 x 3 part (the identity where it is singular).
fn normal_matrix(d: &Draw) -> Mat3 {
    let m = Mat3::from_mat4(d.world);
    if m.determinant().abs() > 1e-30 {
        m.inverse().transpose()
    } else {
        Mat3::IDENTITY
    }
}

/// Maps `f` over `items` (with each one's index) on every core.
fn parallel_map<T: Sync, R: Send + Default + Clone>(
    items: &[T],
    f: impl Fn(usize, &T) -> R + Sync,
) -> Vec<R> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = items.len().div_ceil(threads).max(1);
    let mut out = vec![R::default(); items.len()];
    std::thread::scope(|s| {
        for (c, (part, dst)) in items.chunks(chunk).zip(out.chunks_mut(chunk)).enumerate() {
            let f = &f;
            s.spawn(move || {
                for (j, (item, d)) in part.iter().zip(dst.iter_mut()).enumerate() {
                    *d = f(c * chunk + j, item);
                }
            });
        }
    });
    out
}

struct Tracer<'a> {
    scene: &'a Scene,
    occluders: &'a [Occluder],
    tris: &'a [Triangle],
    owner: &'a [(u32, u32)],
    bvh: &'a obvhs::cwbvh::CwBvh,
    eps: f32,
}

/// A ray's nearest surface.
struct Hit {
    /// Which occluder, the triangle's vertex indices, the point's barycentric weights.
    occluder: u32,
    indices: [u32; 3],
    bary: [f32; 3],
    /// The ray's direction and the distance to the hit.
    dir: Vec3,
    t: f32,
}

/// How much a hit at distance `t` from receiving vertex `r` counts: fully from as far as the
/// longest edge of the vertex's triangles, less in proportion nearer. An occluder nearer than the
/// mesh's own spacing hides a different share of the sky at each point of a triangle, which
/// values at its corners cannot hold (the four corners of a recessed panel see its rim; its
/// middle does not): such occlusion is the screen's, which the occlusion pass measures at every
/// pixel, and the world light keeps what its vertices can represent.
fn reach(r: &Receiver, t: f32) -> f32 {
    if r.edge > 0.0 {
        (t / r.edge).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

impl Tracer<'_> {
    /// Ray `k` of receiver `i` (vertex `r`): where it starts and where it goes.
    fn ray(&self, r: &Receiver, i: usize, k: u32) -> (Vec3, Vec3) {
        (r.p + r.n * self.eps, cosine_direction(r.n, i as u32, k))
    }

    /// Ray `k` of receiver `i` (vertex `r`): the nearest triangle it hits (its index in `tris`)
    /// and how far, if any.
    fn nearest(&self, r: &Receiver, i: usize, k: u32) -> Option<(u32, f32)> {
        if r.n == Vec3::ZERO {
            return None;
        }
        let (origin, dir) = self.ray(r, i, k);
        let ray = Ray::new(origin.into(), dir.into(), self.eps, f32::INFINITY);
        let mut hit = RayHit::none();
        let found = self.bvh.ray_traverse(ray, &mut hit, |ray, id| {
            let p = self.bvh.primitive_indices[id] as usize;
            let t = self.tris[p].intersect(ray);
            if t.is_finite() && !self.opaque_at(p, ray, t) {
                return f32::INFINITY;
            }
            t
        });
        found.then(|| (self.bvh.primitive_indices[hit.primitive_id as usize], hit.t))
    }

    /// The hit of ray `k` of receiver `i` on triangle `p` at distance `t` ([`Tracer::nearest`]'s).
    fn hit(&self, r: &Receiver, i: usize, k: u32, p: usize, t: f32) -> Hit {
        let (origin, dir) = self.ray(r, i, k);
        let (o, tri) = self.owner[p];
        Hit {
            occluder: o,
            indices: self.indices(o, tri),
            bary: barycentric(&self.tris[p], origin + dir * t),
            dir,
            t,
        }
    }

    fn indices(&self, o: u32, t: u32) -> [u32; 3] {
        let mesh = &self.scene.meshes[self.occluders[o as usize].draw(self.scene).mesh];
        let i = 3 * t as usize;
        [mesh.indices[i], mesh.indices[i + 1], mesh.indices[i + 2]]
    }

    /// Whether triangle `p` is there where `ray` meets it at `t`: alphaMode MASK cuts it out
    /// where its alpha is under the cutoff.
    fn opaque_at(&self, p: usize, ray: &Ray, t: f32) -> bool {
        let (o, tri) = self.owner[p];
        let occ = &self.occluders[o as usize];
        let material = occ.material(self.scene);
        let Some(cutoff) = material.and_then(|m| m.alpha_cutoff) else {
            return true;
        };
        let at = Vec3::from(ray.origin + ray.direction * t);
        let bary = barycentric(&self.tris[p], at);
        let mesh = &self.scene.meshes[occ.draw(self.scene).mesh];
        let idx = self.indices(o, tri);
        base_colour(self.scene, material, mesh, idx, bary)[3] >= cutoff
    }

    /// The light a hit surface sends back along `dir`: its diffuse albedo times the sky's
    /// irradiance/π at its normal times its own visibility `vis`, plus what it emits (black from
    /// behind a single-sided surface: the inside of what it closes).
    #[allow(clippy::too_many_arguments)]
    fn radiance(
        &self,
        occ: &Occluder,
        mesh: &crate::scene::Mesh,
        idx: [u32; 3],
        bary: [f32; 3],
        dir: Vec3,
        sky: &SkyLight,
        vis: f32,
    ) -> Vec3 {
        let mut n = Vec3::ZERO;
        for j in 0..3 {
            let v = mesh
                .vertices
                .get(idx[j] as usize)
                .map_or([0.0; 3], |v| v.normal);
            n += Vec3::from(v) * bary[j];
        }
        let mut n = (occ.normal_matrix * n).normalize_or_zero();
        let material = occ.material(self.scene);
        let double_sided = material.is_some_and(|m| m.double_sided);
        if n.dot(dir) > 0.0 {
            if !double_sided {
                return Vec3::ZERO;
            }
            n = -n;
        }
        let c = base_colour(self.scene, material, mesh, idx, bary);
        let Some(m) = material else {
            return Vec3::new(c[0], c[1], c[2]) * sky.at(n) * vis;
        };
        let albedo = Vec3::new(c[0], c[1], c[2]);
        if m.unlit {
            return albedo;
        }
        let mut emitted = Vec3::from(m.emissive);
        if emitted != Vec3::ZERO {
            if let Some(t) = m.emissive_texture.and_then(|t| self.scene.textures.get(t)) {
                let uv = slot_uv(m, TextureSlot::Emissive, mesh, idx, bary);
                let e = texel(t, uv);
                emitted *= Vec3::new(e[0], e[1], e[2]);
            }
        }
        albedo * (1.0 - m.metallic.clamp(0.0, 1.0)) * sky.at(n) * vis + emitted
    }
}

/// The base colour (linear RGBA) at a point of a triangle: factor × texture × vertex colour.
fn base_colour(
    scene: &Scene,
    material: Option<&Material>,
    mesh: &crate::scene::Mesh,
    idx: [u32; 3],
    bary: [f32; 3],
) -> [f32; 4] {
    let mut c = material.map_or([1.0; 4], |m| m.base_color);
    if let Some(m) = material {
        if let Some(t) = m.base_color_texture.and_then(|t| scene.textures.get(t)) {
            let uv = slot_uv(m, TextureSlot::BaseColor, mesh, idx, bary);
            let s = texel(t, uv);
            for k in 0..4 {
                c[k] *= s[k];
            }
        }
    }
    if !mesh.colors.is_empty() {
        let mut vc = [0.0f32; 4];
        for j in 0..3 {
            let col = mesh
                .colors
                .get(idx[j] as usize)
                .copied()
                .unwrap_or([1.0; 4]);
            for k in 0..4 {
                vc[k] += col[k] * bary[j];
            }
        }
        for k in 0..4 {
            c[k] *= vc[k];
        }
    }
    c
}

/// The texture coordinate texture slot `slot` of material `m` reads at a point of a triangle.
fn slot_uv(
    m: &Material,
    slot: TextureSlot,
    mesh: &crate::scene::Mesh,
    idx: [u32; 3],
    bary: [f32; 3],
) -> [f32; 2] {
    let map = &m.uv[slot as usize];
    let mut uv = [0.0f32; 2];
    for j in 0..3 {
        let v = mesh.vertices.get(idx[j] as usize);
        let w = v.map_or([0.0; 2], |v| if map.set == 1 { v.uv1 } else { v.uv });
        uv[0] += w[0] * bary[j];
        uv[1] += w[1] * bary[j];
    }
    map.apply(uv)
}

/// The texel nearest `uv` (repeating), linear RGBA (an sRGB texture's colour decoded).
fn texel(t: &Texture, uv: [f32; 2]) -> [f32; 4] {
    let (w, h) = (t.width as usize, t.height as usize);
    if w == 0 || h == 0 || t.rgba8.len() < w * h * 4 || !(uv[0].is_finite() && uv[1].is_finite()) {
        return [1.0; 4];
    }
    let x = ((uv[0] - uv[0].floor()) * w as f32) as usize;
    let y = ((uv[1] - uv[1].floor()) * h as f32) as usize;
    let i = 4 * (y.min(h - 1) * w + x.min(w - 1));
    let b = &t.rgba8[i..i + 4];
    let decode = |v: u8| match t.color_space {
        ColorSpace::Srgb => srgb_table()[v as usize],
        ColorSpace::Linear => v as f32 / 255.0,
    };
    [
        decode(b[0]),
        decode(b[1]),
        decode(b[2]),
        b[3] as f32 / 255.0,
    ]
}

/// sRGB bytes decoded, once (`color::srgb_decode`).
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| crate::color::srgb_decode(i as f32 / 255.0)))
}

/// Barycentric weights of point `p` (on the triangle's plane) for v0, v1, v2.
fn barycentric(t: &Triangle, p: Vec3) -> [f32; 3] {
    let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
    let (e0, e1, e2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let (d20, d21) = (e2.dot(e0), e2.dot(e1));
    let den = d00 * d11 - d01 * d01;
    if den.abs() <= 0.0 || den.is_nan() {
        return [1.0 / 3.0; 3];
    }
    let v = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

/// Ray `k` of [`RAYS`] of vertex `i`: a cosine-distributed direction about n, from the
/// Hammersley set turned by a hash of the vertex (so neighbouring vertices' rays differ).
fn cosine_direction(n: Vec3, i: u32, k: u32) -> Vec3 {
    let h = hash(i);
    let shift = ((h & 0xffff) as f32 / 65536.0, (h >> 16) as f32 / 65536.0);
    let (a, b) = crate::env::hammersley(k, RAYS);
    let xi = [(a as f32 + shift.0).fract(), (b as f32 + shift.1).fract()];
    let [x, y, z] = crate::reference::ibl_twin::cosine_sample(xi);
    let (t, bt) = n.any_orthonormal_pair();
    (t * x + bt * y + n * z).normalize()
}

/// A 32-bit integer hash (lowbias32).
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Mesh, Vertex};
    use glam::Mat4;

    fn quad(y: f32, half: f32, up: bool) -> Mesh {
        let n = if up {
            [0.0, 1.0, 0.0]
        } else {
            [0.0, -1.0, 0.0]
        };
        let v = |x: f32, z: f32| Vertex {
            position: [x, y, z],
            normal: n,
            tangent: [1.0, 0.0, 0.0, 1.0],
            uv: [0.0, 0.0],
            uv1: [0.0, 0.0],
        };
        let indices = if up {
            vec![0, 2, 1, 0, 3, 2]
        } else {
            vec![0, 1, 2, 0, 2, 3]
        };
        Mesh {
            vertices: vec![
                v(-half, -half),
                v(half, -half),
                v(half, half),
                v(-half, half),
            ],
            indices,
            ..Mesh::default()
        }
    }

    /// The longest receiving edge is the quad's diagonal in world units (the draw's scale
    /// applied), a hidden draw does not count, an edge whose square overflows counts as
    /// infinite, and the edges of a vertex that is not a number are left out.
    #[test]
    fn the_longest_receiving_edge_is_measured_in_world_units() {
        let mut scene = Scene::default();
        scene.materials = vec![Material::default()];
        scene.meshes = vec![quad(0.0, 1.0, true), quad(0.0, 10.0, true)];
        scene.draws = vec![
            Draw::new(0, Mat4::from_scale(glam::Vec3::splat(3.0))),
            Draw {
                visible: false,
                ..Draw::new(1, Mat4::IDENTITY)
            },
        ];
        let e = longest_receiving_edge(&scene);
        // The 2 x 2 quad scaled 3 times: diagonal 6·sqrt(2).
        assert!((e - 6.0 * 2f32.sqrt()).abs() < 1e-4, "{e}");
        scene.meshes[0].vertices[2].position = [f32::NAN, 0.0, 0.0];
        let e = longest_receiving_edge(&scene);
        // Both triangles pass through the NaN corner: its edges are left out, the sides
        // between the untouched corners (6 long) count.
        assert!((e - 6.0).abs() < 1e-4, "{e}");
        scene.meshes[0].vertices[2].position = [1e30, 0.0, 0.0];
        assert_eq!(longest_receiving_edge(&scene), f32::INFINITY);
    }

    /// A point under a wide grey ceiling: it sees the ceiling over (almost) all of its
    /// hemisphere, and the ceiling's underside sends back the grey times the light that reaches
    /// it; above the ceiling, a point sees all of the sky.
    #[test]
    fn a_floor_under_a_ceiling_sees_the_ceiling() {
        let mut scene = Scene::default();
        let mut floor = quad(0.0, 0.01, true);
        floor.material = 0;
        let mut ceiling = quad(0.1, 100.0, false);
        ceiling.material = 0;
        scene.meshes = vec![floor, ceiling];
        let mut m = Material::default();
        m.base_color = [0.5, 0.5, 0.5, 1.0];
        m.metallic = 0.0;
        m.double_sided = true;
        scene.materials = vec![m];
        scene.draws = vec![Draw::new(0, Mat4::IDENTITY), Draw::new(1, Mat4::IDENTITY)];
        // A uniform sky of radiance 1: irradiance/π is 1 at every normal.
        let sh = crate::env::Environment::uniform([1.0; 3]).sh9();
        let sky = SkyLight {
            sh,
            rotation: 0.0,
            intensity: 1.0,
        };
        let b = bake(&scene, &sky);
        let floor_base = b.base[0].unwrap() as usize;
        for t in &b.texels[floor_base..floor_base + 4] {
            // The rays that escape pass under a 100 m ceiling 0.1 m up: cosine-weighted,
            // 1 - sin²(atan(1000)) ≈ 1e-6.
            assert!(t[3] < 0.02, "visibility {t:?}");
            // The ceiling's underside: grey 0.5 times its own sky, which the floor's tiny quad
            // hides from almost none of it (its visibility is about 1 - 1e-6, double-sided).
            for c in &t[..3] {
                assert!((c - 0.5).abs() < 0.03, "bounce {t:?}");
            }
        }
        let ceiling_base = b.base[1].unwrap() as usize;
        // The ceiling's vertices face down at the floor's corners 100 m away (the floor is
        // 2 cm wide): they see the sky under them.
        for t in &b.texels[ceiling_base..ceiling_base + 4] {
            assert!(t[3] > 0.99, "{t:?}");
        }
    }
}
