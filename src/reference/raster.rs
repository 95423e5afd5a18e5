//! A small CPU rasterizer: whole reference images of a [`Scene`] with the reference shading
//! ([`super::shading::shade`]), to compare with the GPU's frames (tests/regression.rs).
//!
//! It does what the G-buffer pass does, without its storage formats: the same camera and
//! projection ([`FrameData::new`]: reversed-Z, infinite far plane, Y flipped), triangles clipped at
//! the near plane, back faces culled unless the material is double-sided (whose back faces get
//! the flipped normal), a depth test per pixel centre, perspective-correct interpolation, and the
//! shading frame of `gbuffer.frag` (normal, tangent made orthogonal to it, handedness sign).
//!
//! Where it differs on purpose, it is the more exact of the two:
//! - **Weave coverage** is the exact box coverage ([`weave_box_uv`], f64) of the pixel's footprint
//!   in texture space: the parallelogram spanned by the UV derivatives, which come from the
//!   triangle's plane (central differences of the perspective-correct interpolation one pixel
//!   either side). The parallelogram is cut into `subdivisions²` pieces, each replaced by its
//!   axis-aligned bounding box. The GPU instead samples a trilinear-filtered f16 texture with an
//!   isotropic footprint (anisotropic filtering is off on lavapipe).
//! - Nothing is quantised: no RGBA8 base colour, no f16 octahedral normals or coverages, no
//!   8-bit normal-map texel (the GPU's flat default normal is 128/255, not exactly 0.5).
//!
//! Textures are not sampled: a material with any texture is refused with an error (the
//! reference scenes have none).

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

use super::shading::{self, GltfSurface, Surface};
use super::weave::weave_box_uv;
use crate::fabric::FabricParams;
use crate::records::{FrameData, GpuLight};
use crate::scene::{Camera, Material, Scene};
use crate::Error;

/// What to render.
#[derive(Clone, Debug)]
pub struct RasterOptions {
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    /// Exposure in EV, as `RenderOptions::exposure`.
    pub exposure: f32,
    /// The pixel footprint is cut into `subdivisions²` parallelograms for the weave coverage (1 =
    /// the bounding box of the whole footprint; 0 = no footprint: the weave at the pixel centre,
    /// as the samples of [`render_pixel_integrated`] take it).
    pub subdivisions: u32,
    /// Instead of `subdivisions` when not 0: the G-buffer pass's own footprint filter
    /// (`render::Footprint::Parallelogram(pieces)`) through its f64 twin
    /// (`reference::weave::double::weave_parallelogram`), so that the GPU's is checked against it.
    pub pieces: u32,
    /// How fabric is shaded (`RenderOptions::shading`); Gouraud lights fabric vertices as
    /// gbuffer.vert does and interpolates the result.
    pub shading: crate::records::Shading,
}

/// A CPU-rendered image, laid out as `render::Frame`.
pub struct RasterImage {
    pub width: u32,
    pub height: u32,
    /// Display-referred RGBA8, sRGB-encoded, rows top to bottom.
    pub ldr: Vec<u8>,
    /// Linear HDR radiance before exposure, RGBA f32, rows top to bottom.
    pub hdr: Vec<f32>,
    /// Whether a surface covers the pixel.
    pub covered: Vec<bool>,
}

/// A vertex after the vertex stage: clip position and the attributes the fragment stage reads.
#[derive(Clone, Copy, Debug)]
struct ClipVertex {
    clip: Vec4,
    world: Vec3,
    normal: Vec3,
    tangent: Vec4,
    uv: Vec2,
    /// Per-vertex lighting (Gouraud shading of fabric), else zero.
    gouraud: Vec3,
}

impl ClipVertex {
    fn lerp(a: &ClipVertex, b: &ClipVertex, t: f32) -> ClipVertex {
        ClipVertex {
            clip: a.clip.lerp(b.clip, t),
            world: a.world.lerp(b.world, t),
            normal: a.normal.lerp(b.normal, t),
            tangent: a.tangent.lerp(b.tangent, t),
            uv: a.uv.lerp(b.uv, t),
            gouraud: a.gouraud.lerp(b.gouraud, t),
        }
    }
}

/// What a drawn triangle needs besides its vertices.
struct DrawMaterial<'a> {
    material: &'a Material,
    /// The sanitised fabric parameters (for the weave) and the GPU record (for shading).
    fabric: Option<(FabricParams, crate::fabric::GpuFabric)>,
}

/// The nearest surface found so far at one pixel.
#[derive(Clone, Copy)]
struct Fragment {
    depth: f32,
    surface: Surface,
}

/// Renders `scene` on the CPU.
pub fn render(scene: &Scene, options: &RasterOptions) -> crate::Result<RasterImage> {
    let (width, height) = (options.width, options.height);
    if width == 0
        || height == 0
        || width > crate::records::MAX_SIZE
        || height > crate::records::MAX_SIZE
    {
        return Err(Error::input(format!(
            "reference image size {width}x{height} is out of range"
        )));
    }
    let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::new).collect();
    let mut frame = FrameData::new(&options.camera, width, height);
    frame.light_count = lights.len() as u32;
    frame.material_count = scene.materials.len().max(1) as u32;
    let view_proj = Mat4::from_cols_array_2d(&frame.view_proj);
    let eye = Vec3::new(frame.eye[0], frame.eye[1], frame.eye[2]);

    let default_material = Material::default();
    let materials: Vec<DrawMaterial> = scene
        .materials
        .iter()
        .map(|m| {
            // Occlusion darkens only environment light, which the rasterizer does not compute.
            if m.textures()
                .iter()
                .enumerate()
                .any(|(k, t)| k != crate::scene::TextureSlot::Occlusion as usize && t.is_some())
            {
                return Err(Error::input(format!(
                    "material '{}' of {} has textures: the CPU reference rasterizer does not sample textures",
                    m.name, scene.source
                )));
            }
            Ok(DrawMaterial { material: m, fabric: m.fabric.as_ref().map(|f| (f.sanitized(), f.to_gpu())) })
        })
        .collect::<crate::Result<_>>()?;
    let fallback = DrawMaterial {
        material: &default_material,
        fabric: None,
    };

    let mut fragments: Vec<Option<Fragment>> = vec![None; (width * height) as usize];
    // Fabric sheets (light through the weave) are kept apart, the nearest per pixel, and put
    // over the opaque surface behind them by their thread coverage, as the transparent pass
    // blends them (one sheet deep: a sheet behind another is not seen through it).
    let mut sheets: Vec<Option<Fragment>> = vec![None; (width * height) as usize];
    let raster = Raster {
        width,
        height,
        subdivisions: options.subdivisions,
        pieces: options.pieces,
    };
    for draw in scene.draws.iter().filter(|d| d.visible) {
        let mesh = &scene.meshes[draw.mesh];
        let dm = materials.get(mesh.material).unwrap_or(&fallback);
        let world3 = Mat3::from_mat4(draw.world);
        let det = world3.determinant();
        let normal_matrix = if det.abs() > 1e-30 {
            world3.inverse().transpose()
        } else {
            Mat3::IDENTITY
        };
        let tangent_sign = if det < 0.0 { -1.0 } else { 1.0 };
        let vertices: Vec<ClipVertex> = mesh
            .vertices
            .iter()
            .map(|v| {
                let world = draw.world.transform_point3(Vec3::from(v.position));
                let t = world3 * Vec3::new(v.tangent[0], v.tangent[1], v.tangent[2]);
                let normal = normal_matrix * Vec3::from(v.normal);
                let tangent = t.extend(v.tangent[3] * tangent_sign);
                let gouraud = match &dm.fabric {
                    Some((_, gpu)) if options.shading == crate::records::Shading::Gouraud => {
                        Vec3::from(shading::gouraud_vertex(
                            &frame,
                            &lights,
                            world.to_array(),
                            normal.to_array(),
                            tangent.to_array(),
                            gpu,
                        ))
                    }
                    _ => Vec3::ZERO,
                };
                ClipVertex {
                    clip: view_proj * world.extend(1.0),
                    world,
                    normal,
                    tangent,
                    uv: Vec2::from(v.uv),
                    gouraud,
                }
            })
            .collect();
        if mesh.topology != crate::scene::Topology::Triangles {
            // Points and lines: the CPU reference rasterizes triangles only.
            continue;
        }
        for tri in mesh.indices.chunks_exact(3) {
            let Some(v) = tri
                .iter()
                .map(|&i| vertices.get(i as usize).copied())
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            // glTF front faces are counter-clockwise as seen by the viewer; a mirroring world
            // transform reverses the winding.
            let face = (v[1].world - v[0].world).cross(v[2].world - v[0].world);
            let front = (face.dot(eye - v[0].world) > 0.0) == (det >= 0.0);
            if !front && !dm.material.double_sided {
                continue;
            }
            let polygon = clip_near(&[v[0], v[1], v[2]]);
            let target = if dm.material.is_sheet() {
                &mut sheets
            } else {
                &mut fragments
            };
            for k in 1..polygon.len().saturating_sub(1) {
                raster.triangle(
                    [&polygon[0], &polygon[k], &polygon[k + 1]],
                    front,
                    dm,
                    target,
                );
            }
        }
    }

    let exposure = 2f32.powf(options.exposure);
    let background = [
        frame.background[0],
        frame.background[1],
        frame.background[2],
    ];
    let mut image = RasterImage {
        width,
        height,
        ldr: Vec::with_capacity(fragments.len() * 4),
        hdr: Vec::with_capacity(fragments.len() * 4),
        covered: fragments
            .iter()
            .zip(&sheets)
            .map(|(f, s)| f.is_some() || s.is_some())
            .collect(),
    };
    for (fragment, sheet) in fragments.iter().zip(&sheets) {
        let behind = match fragment {
            Some(f) => shading::shade_with(&frame, &lights, &f.surface, options.shading),
            None => background,
        };
        let hdr = match sheet {
            // The woven model draws a sheet over what is behind it by its thread coverage (the
            // comparison models, as forward.frag, draw it opaque).
            Some(s)
                if options.shading == crate::records::Shading::Fabric
                    && fragment.is_none_or(|f| s.depth > f.depth) =>
            {
                // The sheet's threads (their light already weighted by their coverage, their
                // emission too), and the light behind through its gaps. At a sample of
                // render_pixel_integrated the coverage is the weave's at that point: thread or
                // gap, 1 or 0.
                let cover = crate::reference::brdf::single::fabric_thread_cover(s.surface.coverage);
                let mut surface = s.surface;
                surface.emissive = surface.emissive.map(|e| e * cover);
                let front = shading::shade_with(&frame, &lights, &surface, options.shading);
                std::array::from_fn(|c| front[c] + (1.0 - cover) * behind[c])
            }
            Some(s) if fragment.is_none_or(|f| s.depth > f.depth) => {
                shading::shade_with(&frame, &lights, &s.surface, options.shading)
            }
            _ => behind,
        };
        image.hdr.extend_from_slice(&[hdr[0], hdr[1], hdr[2], 1.0]);
        image
            .ldr
            .extend_from_slice(&shading::display_rgba8(hdr, exposure));
    }
    Ok(image)
}

/// Clips a triangle to the near plane. With the reversed-Z infinite projection clip z is the near
/// distance and w the view depth, so the visible side is `w - z ≥ 0` (depth ≤ 1); there is no far
/// plane, and x and y need no clipping since only pixels inside the image are visited.
fn clip_near(tri: &[ClipVertex; 3]) -> Vec<ClipVertex> {
    let d = |v: &ClipVertex| v.clip.w - v.clip.z;
    let mut out = Vec::with_capacity(4);
    for i in 0..3 {
        let (a, b) = (&tri[i], &tri[(i + 1) % 3]);
        let (da, db) = (d(a), d(b));
        if da >= 0.0 {
            out.push(*a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            out.push(ClipVertex::lerp(a, b, da / (da - db)));
        }
    }
    out
}

struct Raster {
    width: u32,
    height: u32,
    subdivisions: u32,
    pieces: u32,
}

/// A triangle in screen space: pixel coordinates (x right, y down), NDC depth and 1/w per vertex.
struct ScreenTriangle {
    p: [Vec2; 3],
    depth: [f32; 3],
    inv_w: [f32; 3],
    area: f32,
}

impl ScreenTriangle {
    /// Perspective-correct barycentric weights at pixel position `q` (also outside the triangle:
    /// the plane's extension, for derivatives), and the screen-linear ones (for depth).
    fn weights(&self, q: Vec2) -> ([f32; 3], [f32; 3]) {
        let e = edge_weights(&self.p, q, self.area);
        let pw = [
            e[0] * self.inv_w[0],
            e[1] * self.inv_w[1],
            e[2] * self.inv_w[2],
        ];
        let s = pw[0] + pw[1] + pw[2];
        ([pw[0] / s, pw[1] / s, pw[2] / s], e)
    }
}

/// Screen-space barycentric weights of `q` in the triangle `p` of signed area `area`.
fn edge_weights(p: &[Vec2; 3], q: Vec2, area: f32) -> [f32; 3] {
    [
        edge(p[1], p[2], q) / area,
        edge(p[2], p[0], q) / area,
        edge(p[0], p[1], q) / area,
    ]
}

fn edge(a: Vec2, b: Vec2, q: Vec2) -> f32 {
    (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x)
}

/// The top-left rule (as Vulkan implementations and D3D use it) for the edge a -> b of a
/// triangle of positive area (`edge(p0, p1, p2) > 0`, interior where every `edge` is positive:
/// clockwise on screen) in y-down pixel coordinates: a pixel centre exactly on an edge belongs
/// to the triangle only if the edge is a top edge (horizontal, the interior below it: it runs
/// towards +x in this winding) or a left edge (the interior to its right: it runs towards -y),
/// so a centre on an edge shared by two triangles is drawn once. (This used to be the
/// bottom-right rule: `d.y > 0` and a horizontal edge towards -x.)
fn owns_edge(a: Vec2, b: Vec2) -> bool {
    let d = b - a;
    (d.y == 0.0 && d.x > 0.0) || d.y < 0.0
}

/// Whether pixel centre `q` is inside the triangle `p` (positive area), centres on an edge
/// decided by the top-left rule.
fn covers(p: &[Vec2; 3], owns: &[bool; 3], q: Vec2) -> bool {
    let e = [
        edge(p[1], p[2], q),
        edge(p[2], p[0], q),
        edge(p[0], p[1], q),
    ];
    (0..3).all(|i| e[i] > 0.0 || (e[i] == 0.0 && owns[i]))
}

impl Raster {
    fn triangle(
        &self,
        v: [&ClipVertex; 3],
        front: bool,
        dm: &DrawMaterial,
        fragments: &mut [Option<Fragment>],
    ) {
        let (w, h) = (self.width as f32, self.height as f32);
        let to_screen =
            |c: Vec4| Vec2::new((c.x / c.w * 0.5 + 0.5) * w, (c.y / c.w * 0.5 + 0.5) * h);
        let mut v = v;
        let mut p = [
            to_screen(v[0].clip),
            to_screen(v[1].clip),
            to_screen(v[2].clip),
        ];
        let mut area = edge(p[0], p[1], p[2]);
        if !(area.abs() > 0.0) || !area.is_finite() {
            return;
        }
        if area < 0.0 {
            v.swap(1, 2);
            p.swap(1, 2);
            area = -area;
        }
        let tri = ScreenTriangle {
            p,
            depth: [
                v[0].clip.z / v[0].clip.w,
                v[1].clip.z / v[1].clip.w,
                v[2].clip.z / v[2].clip.w,
            ],
            inv_w: [1.0 / v[0].clip.w, 1.0 / v[1].clip.w, 1.0 / v[2].clip.w],
            area,
        };
        let min = p[0].min(p[1]).min(p[2]);
        let max = p[0].max(p[1]).max(p[2]);
        let x0 = (min.x - 0.5).ceil().max(0.0) as u32;
        let y0 = (min.y - 0.5).ceil().max(0.0) as u32;
        let x1 = ((max.x - 0.5).floor().min(w - 1.0)).max(-1.0) as i64;
        let y1 = ((max.y - 0.5).floor().min(h - 1.0)).max(-1.0) as i64;
        let owns = [
            owns_edge(p[1], p[2]),
            owns_edge(p[2], p[0]),
            owns_edge(p[0], p[1]),
        ];
        for y in y0 as i64..=y1 {
            for x in x0 as i64..=x1 {
                let q = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                if !covers(&p, &owns, q) {
                    continue;
                }
                let (_, lin) = tri.weights(q);
                let depth = lin[0] * tri.depth[0] + lin[1] * tri.depth[1] + lin[2] * tri.depth[2];
                let index = (y as u32 * self.width + x as u32) as usize;
                // Reversed-Z: greater is nearer (the pipeline's compare op is GREATER).
                if fragments[index].is_some_and(|f| !(depth > f.depth)) || !(depth > 0.0) {
                    continue;
                }
                let surface = self.surface(&tri, &v, q, front, dm);
                fragments[index] = Some(Fragment { depth, surface });
            }
        }
    }

    /// The surface at pixel centre `q`, as gbuffer.frag computes it (less its quantisation).
    fn surface(
        &self,
        tri: &ScreenTriangle,
        v: &[&ClipVertex; 3],
        q: Vec2,
        front: bool,
        dm: &DrawMaterial,
    ) -> Surface {
        let (b, _) = tri.weights(q);
        let mix3 =
            |f: &dyn Fn(&ClipVertex) -> Vec3| f(v[0]) * b[0] + f(v[1]) * b[1] + f(v[2]) * b[2];
        let position = mix3(&|c| c.world);
        let mut n = mix3(&|c| c.normal);
        if !(n.length_squared() > 1e-20) {
            n = (v[1].world - v[0].world).cross(v[2].world - v[0].world);
        }
        n = if n.length_squared() > 1e-30 {
            n.normalize()
        } else {
            Vec3::Y
        };
        if !front {
            n = -n;
        }
        let t_in = mix3(&|c| c.tangent.truncate());
        let sign_in = v[0].tangent.w * b[0] + v[1].tangent.w * b[1] + v[2].tangent.w * b[2];
        let t = t_in - n * n.dot(t_in);
        let t = if t.length_squared() > 1e-20 {
            t.normalize()
        } else {
            any_tangent(n)
        };
        let m = dm.material;
        let mut surface = Surface {
            position: position.to_array(),
            normal: n.to_array(),
            tangent: t.to_array(),
            sign: if sign_in < 0.0 { -1.0 } else { 1.0 },
            base_color: [
                m.base_color[0].clamp(0.0, 1.0),
                m.base_color[1].clamp(0.0, 1.0),
                m.base_color[2].clamp(0.0, 1.0),
            ],
            metallic: m.metallic.clamp(0.0, 1.0),
            roughness: m.roughness.clamp(0.0, 1.0),
            emissive: {
                // gbuffer.frag adds the interpolated vertex lighting (Gouraud) to the emission.
                let g = mix3(&|c| c.gouraud);
                [
                    (m.emissive[0] + g.x).max(0.0),
                    (m.emissive[1] + g.y).max(0.0),
                    (m.emissive[2] + g.z).max(0.0),
                ]
            },
            coverage: [0.0; 4],
            fabric: None,
            gltf: None,
        };
        if dm.fabric.is_none() {
            // The material's extensions, as gbuffer.frag writes them (factors only: the CPU
            // rasterizer refuses textured materials).
            let sign = if sign_in < 0.0 { -1.0 } else { 1.0 };
            let (anisotropy, dir) = match &m.anisotropy {
                Some(a) => {
                    let b = n.cross(t) * sign;
                    let d = t * a.rotation.cos() + b * a.rotation.sin();
                    let d = (d - n * n.dot(d)).normalize_or_zero();
                    if d == Vec3::ZERO {
                        (0.0, t)
                    } else {
                        (a.strength, d)
                    }
                }
                None => (0.0, t),
            };
            let f0 = m.specular.f0_from_ior();
            surface.gltf = Some(GltfSurface {
                base: surface.base_color,
                metallic: surface.metallic,
                roughness: surface.roughness,
                specular: m.specular.factor.clamp(0.0, 1.0),
                f0: m.specular.color.map(|c| (f0 * c).min(1.0)),
                sheen: m
                    .sheen
                    .as_ref()
                    .map_or([0.0; 3], |s| s.color.map(|c| c.clamp(0.0, 1.0))),
                sheen_roughness: m
                    .sheen
                    .as_ref()
                    .map_or(0.0, |s| s.roughness.clamp(0.0, 1.0)),
                t: dir.to_array(),
                anisotropy,
                // The CPU reference has no backdrop: transmissive materials are not among the
                // scenes it renders (their transmission is the forward pass's, tests/transparency.rs).
                transmission: 0.0,
                // KHR_materials_iridescence: without a thickness texture the film is the
                // maximum thick.
                iridescence: m
                    .iridescence
                    .as_ref()
                    .map_or(0.0, |i| i.factor.clamp(0.0, 1.0)),
                film_ior: m.iridescence.as_ref().map_or(1.3, |i| i.ior),
                film_thickness: m
                    .iridescence
                    .as_ref()
                    .map_or(0.0, |i| i.thickness_max.max(0.0)),
            });
        }
        if let Some((params, gpu)) = &dm.fabric {
            let uv_at = |q: Vec2| {
                let (b, _) = tri.weights(q);
                v[0].uv * b[0] + v[1].uv * b[1] + v[2].uv * b[2]
            };
            let uv = uv_at(q);
            // Derivatives of the UV along the pixel grid, from the triangle's plane.
            let dx = (uv_at(q + Vec2::X) - uv_at(q - Vec2::X)) * 0.5;
            let dy = (uv_at(q + Vec2::Y) - uv_at(q - Vec2::Y)) * 0.5;
            surface.coverage = if self.pieces > 0 {
                use super::weave::{double, uv_to_cells, weave_of};
                let w = weave_of(params);
                let [x, y] = uv_to_cells(params, uv.x as f64, uv.y as f64);
                let c = [
                    double::weave_wrap(x, w.cols as f64),
                    double::weave_wrap(y, w.rows as f64),
                ];
                let dxc = uv_to_cells(params, dx.x as f64, dx.y as f64);
                let dyc = uv_to_cells(params, dy.x as f64, dy.y as f64);
                let k = double::weave_pieces(dxc, dyc, self.pieces);
                double::weave_parallelogram(&w, c, dxc, dyc, k).map(|x| x as f32)
            } else if self.subdivisions == 0 {
                let c = super::weave::weave_point_uv(params, uv.x as f64, uv.y as f64);
                c.map(|x| x as f32)
            } else {
                footprint_coverage(params, uv, dx, dy, self.subdivisions)
            };
            surface.fabric = Some(*gpu);
            // gbuffer.frag's albedo of a fabric pixel: the thread texture, white here (the CPU
            // rasterizer refuses textured materials).
            surface.base_color = [1.0; 3];
        }
        surface
    }
}

/// `any_tangent` of frame.glsl: a unit vector orthogonal to n.
fn any_tangent(n: Vec3) -> Vec3 {
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    a.cross(n).normalize()
}

/// A ground truth that integrates each pixel: the scene rendered at `n` x the size with the weave
/// evaluated exactly at each sample point (no footprint), the linear HDR box-filtered down to
/// `options.width` x `options.height` (`n`² regular samples per pixel), then tone-mapped. Shares
/// no footprint approximation with the GPU's filters; `covered` is true where every sample hit a
/// surface. `options.subdivisions` is ignored.
pub fn render_pixel_integrated(
    scene: &Scene,
    options: &RasterOptions,
    n: u32,
) -> crate::Result<RasterImage> {
    let n = n.max(1);
    let fine = render(
        scene,
        &RasterOptions {
            width: options.width * n,
            height: options.height * n,
            subdivisions: 0,
            pieces: 0,
            ..options.clone()
        },
    )?;
    let (w, h) = (options.width as usize, options.height as usize);
    let fw = w * n as usize;
    let exposure = 2f32.powf(options.exposure);
    let mut image = RasterImage {
        width: options.width,
        height: options.height,
        ldr: Vec::with_capacity(w * h * 4),
        hdr: Vec::with_capacity(w * h * 4),
        covered: Vec::with_capacity(w * h),
    };
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0.0f64; 3];
            let mut all = true;
            for sy in 0..n as usize {
                for sx in 0..n as usize {
                    let i = (y * n as usize + sy) * fw + x * n as usize + sx;
                    for (c, s) in sum.iter_mut().enumerate() {
                        *s += fine.hdr[4 * i + c] as f64;
                    }
                    all &= fine.covered[i];
                }
            }
            let hdr = sum.map(|s| (s / (n * n) as f64) as f32);
            image.hdr.extend_from_slice(&[hdr[0], hdr[1], hdr[2], 1.0]);
            image
                .ldr
                .extend_from_slice(&shading::display_rgba8(hdr, exposure));
            image.covered.push(all);
        }
    }
    Ok(image)
}

/// The weave coverage `(c_warp, c_weft, s_warp, s_weft)` of the pixel footprint `{uv + a·dx + b·dy : a, b in
/// [-1/2, 1/2]}`: the mean of the exact box coverages of the bounding boxes of its `k × k` pieces
/// (equal areas, and every coverage is an area fraction, so the mean is the footprint's).
pub fn footprint_coverage(params: &FabricParams, uv: Vec2, dx: Vec2, dy: Vec2, k: u32) -> [f32; 4] {
    let k = k.max(1);
    let (uv, dx, dy) = (uv.as_dvec2(), dx.as_dvec2(), dy.as_dvec2());
    let half =
        glam::DVec2::new(dx.x.abs() + dy.x.abs(), dx.y.abs() + dy.y.abs()) * (0.5 / k as f64);
    let mut sum = [0.0f64; 4];
    for j in 0..k {
        for i in 0..k {
            let a = (i as f64 + 0.5) / k as f64 - 0.5;
            let b = (j as f64 + 0.5) / k as f64 - 0.5;
            let c = uv + dx * a + dy * b;
            let cov = weave_box_uv(
                params,
                c.x - half.x,
                c.x + half.x,
                c.y - half.y,
                c.y + half.y,
            );
            for (s, v) in sum.iter_mut().zip(cov) {
                *s += v;
            }
        }
    }
    let n = (k * k) as f64;
    sum.map(|s| (s / n) as f32)
}

#[cfg(test)]
mod edge_rule_tests {
    use super::*;

    /// The pixel centres of a `w` x `h` grid that triangle `p` (either winding) covers.
    fn coverage(p: [Vec2; 3], w: u32, h: u32) -> Vec<bool> {
        let mut p = p;
        if edge(p[0], p[1], p[2]) < 0.0 {
            p.swap(1, 2);
        }
        let owns = [
            owns_edge(p[1], p[2]),
            owns_edge(p[2], p[0]),
            owns_edge(p[0], p[1]),
        ];
        (0..w * h)
            .map(|i| {
                let q = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
                covers(&p, &owns, q)
            })
            .collect()
    }

    /// A right triangle whose top, left and hypotenuse edges run through pixel centres: the
    /// centres on its top and left edges are its own, those on the bottom-right edge are not.
    #[test]
    fn a_pixel_centre_on_an_edge_follows_the_top_left_rule() {
        let v = |x: f32, y: f32| Vec2::new(x, y);
        // Corners (0.5, 0.5), (4.5, 0.5), (0.5, 4.5): top edge y = 0.5, left edge x = 0.5,
        // hypotenuse x + y = 5 through the centres (1.5, 3.5), (2.5, 2.5), (3.5, 1.5).
        let c = coverage([v(0.5, 0.5), v(4.5, 0.5), v(0.5, 4.5)], 6, 6);
        let at = |x: u32, y: u32| c[(y * 6 + x) as usize];
        assert!(at(2, 0), "a centre on the top edge belongs to the triangle");
        assert!(
            at(0, 2),
            "a centre on the left edge belongs to the triangle"
        );
        assert!(at(0, 0), "the top-left corner: on a top and a left edge");
        assert!(at(1, 1), "inside");
        assert!(
            !at(2, 2) && !at(1, 3) && !at(3, 1),
            "centres on the bottom-right edge do not"
        );
        assert!(
            !at(4, 0) && !at(0, 4),
            "the corners of the bottom-right edge do not"
        );
        // The same with the other winding.
        assert_eq!(c, coverage([v(0.5, 0.5), v(0.5, 4.5), v(4.5, 0.5)], 6, 6));
        // A triangle with a horizontal bottom edge through centres: not its own.
        let b = coverage([v(0.5, 0.0), v(4.5, 3.5), v(0.5, 3.5)], 6, 6);
        assert!(!b[(3 * 6 + 1) as usize] && b[(2 * 6 + 1) as usize]);
    }

    /// Two triangles sharing an edge through pixel centres (a square cut along a diagonal, and
    /// along a vertical line): every centre is drawn exactly once.
    #[test]
    fn a_shared_edge_is_drawn_once() {
        let v = |x: f32, y: f32| Vec2::new(x, y);
        for (a, b) in [
            (
                [v(0.5, 0.5), v(4.5, 0.5), v(0.5, 4.5)],
                [v(4.5, 0.5), v(4.5, 4.5), v(0.5, 4.5)],
            ),
            (
                [v(0.5, 0.5), v(2.5, 0.5), v(2.5, 4.5)],
                [v(2.5, 0.5), v(4.5, 4.5), v(2.5, 4.5)],
            ),
        ] {
            let (ca, cb) = (coverage(a, 6, 6), coverage(b, 6, 6));
            let both = ca.iter().zip(&cb).filter(|(x, y)| **x && **y).count();
            assert_eq!(both, 0, "no centre is drawn twice");
        }
    }
}
