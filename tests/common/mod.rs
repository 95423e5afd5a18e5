//! Shared by the integration tests: a context on lavapipe (or WEFT_DEVICE) with validation always
//! on, the G-buffer read as the lighting pass reads it, the probe shaders' runner, a test fabric
//! patch and the FLIP of two images; the `weft` binary ([`cli`]), temporary directories
//! ([`temp`]) and the fuzz driver ([`fuzz`]).
#![allow(dead_code)]

pub mod cli;
pub mod fuzz;
pub mod temp;

// Each test binary uses some of these: the rest are unused there.
#[allow(unused_imports)]
pub use cli::{device, weft, weft_without_gpu, without_gpu, WEFT};
#[allow(unused_imports)]
pub use fuzz::Rng;
#[allow(unused_imports)]
pub use temp::{temp_dir, TempDir};

use weft::vk::{Context, ContextOptions, DeviceChoice};

pub fn context() -> Context {
    let device = match std::env::var("WEFT_DEVICE") {
        Ok(v) => DeviceChoice::parse(&v),
        Err(_) => DeviceChoice::Cpu,
    };
    Context::new(&ContextOptions {
        validate: true,
        device,
    })
    .expect("a Vulkan device with the validation layer (run tools/setup)")
}

/// Mean FLIP error (Andersson et al. 2020, the `nv-flip` crate's pool) of the packed sRGB RGB8
/// image `test` against `reference`, both `width` x `height`.
pub fn flip_mean(width: u32, height: u32, reference: &[u8], test: &[u8]) -> f32 {
    let error = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(width, height, reference),
        nv_flip::FlipImageRgb8::with_data(width, height, test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    nv_flip::FlipPool::from_image(&error).mean()
}

/// The surface the lighting pass sees at pixel `i` of a read-back G-buffer of a `width` x
/// `height` frame (`inv_view_proj` of its FrameData), with the emitted radiance; None where no
/// surface was drawn.
pub fn gbuffer_surface(
    g: &weft::render::GBufferReadback,
    scene: &weft::scene::Scene,
    inv_view_proj: glam::Mat4,
    (width, height): (u32, u32),
    i: usize,
) -> Option<weft::reference::shading::Surface> {
    use weft::reference::shading::oct_decode;
    let depth = g.depth[i];
    if depth <= 0.0 {
        return None;
    }
    let (x, y) = (i % width as usize, i / width as usize);
    let ndc = [
        (x as f32 + 0.5) / width as f32 * 2.0 - 1.0,
        (y as f32 + 0.5) / height as f32 * 2.0 - 1.0,
    ];
    let hp = inv_view_proj * glam::Vec4::new(ndc[0], ndc[1], depth, 1.0);
    let p = hp.truncate() / hp.w;
    let px = |v: &[f32], c: usize| v[i * 4 + c];
    let material = px(&g.surface, 1).round() as usize;
    let fabric = scene
        .materials
        .get(material)
        .and_then(|m| m.fabric.as_ref())
        .map(|f| f.to_gpu());
    let normal = oct_decode([px(&g.frame, 0), px(&g.frame, 1)]);
    let tangent = oct_decode([px(&g.frame, 2), px(&g.frame, 3)]);
    let base_color = [0, 1, 2]
        .map(|c| weft::reference::shading::srgb_decode(g.albedo[i * 4 + c] as f32 / 255.0));
    let metallic = g.albedo[i * 4 + 3] as f32 / 255.0;
    let roughness = px(&g.surface, 0);
    // Non-fabric: the extensions' channels (gbuffer.frag), the tangent orthogonalised as the
    // lighting pass does.
    let gltf = fabric.is_none().then(|| {
        let t = glam::Vec3::from(tangent);
        let nn = glam::Vec3::from(normal);
        let t = (t - nn * nn.dot(t)).normalize_or(glam::Vec3::X);
        weft::reference::shading::GltfSurface {
            base: base_color,
            metallic,
            roughness,
            specular: px(&g.specular, 3),
            f0: [px(&g.specular, 0), px(&g.specular, 1), px(&g.specular, 2)],
            sheen: [px(&g.fabric, 0), px(&g.fabric, 1), px(&g.fabric, 2)],
            sheen_roughness: px(&g.fabric, 3),
            t: t.to_array(),
            anisotropy: px(&g.surface, 2),
            // The G-buffer holds no transmissive surface.
            transmission: 0.0,
            // Nor any thin film.
            ..weft::reference::shading::GltfSurface::core([0.0; 3], 0.0, 0.0)
        }
    });
    Some(weft::reference::shading::Surface {
        position: p.into(),
        normal,
        tangent,
        sign: px(&g.surface, 2),
        base_color,
        metallic,
        roughness,
        emissive: [px(&g.emissive, 0), px(&g.emissive, 1), px(&g.emissive, 2)],
        coverage: [
            px(&g.fabric, 0),
            px(&g.fabric, 1),
            px(&g.fabric, 2),
            px(&g.fabric, 3),
        ],
        fabric,
        gltf,
    })
}

/// Runs a probe compute shader (binding 0: the inputs, binding 1: the outputs, push constant: the
/// count, 64 invocations per group) on `inputs` and returns the output buffer's bytes
/// (`out_size` bytes per input); validation is checked after.
pub fn run_probe_shader<T: bytemuck::Pod>(
    ctx: &Context,
    shader: &weft::vk::Shader,
    inputs: &[T],
    out_size: usize,
) -> Vec<u8> {
    use weft::vk::{
        Binding, BindingKind, BufferLocation, BufferUsageFlags, ComputeDesc, Resource, Stages,
    };
    let count = inputs.len() as u32;
    let input = ctx
        .create_buffer_with("probe inputs", BufferUsageFlags::STORAGE_BUFFER, inputs)
        .unwrap();
    let output = ctx
        .create_buffer(
            "probe outputs",
            (inputs.len() * out_size) as u64,
            BufferUsageFlags::STORAGE_BUFFER,
            BufferLocation::Readback,
        )
        .unwrap();
    let storage = |binding| Binding {
        binding,
        kind: BindingKind::StorageBuffer,
        stages: Stages::COMPUTE,
    };
    let layout = ctx.create_set_layout(&[storage(0), storage(1)]).unwrap();
    let pipeline = ctx
        .create_compute_pipeline(&ComputeDesc {
            name: shader.name,
            shader,
            set_layouts: &[&layout],
            push_constant_size: 4,
            constants: &[],
        })
        .unwrap();
    let pool = ctx.create_descriptor_pool(1).unwrap();
    let set = pool
        .set(
            &layout,
            &[
                (0, Resource::Storage(&input)),
                (1, Resource::Storage(&output)),
            ],
        )
        .unwrap();
    ctx.submit(|cmd| {
        cmd.bind_pipeline(&pipeline);
        cmd.bind_sets(&pipeline, 0, &[set]);
        cmd.push_constants(&pipeline, &count);
        cmd.dispatch(count.div_ceil(64), 1, 1);
        cmd.buffer_barrier();
    })
    .unwrap();
    ctx.wait_idle().unwrap();
    let bytes = output.read().unwrap().to_vec();
    ctx.check_validation().unwrap();
    bytes
}

/// A flat 2 m fabric patch in the XZ plane (normal +Y), u along +X, v along -Z so that the
/// bitangent n × t = +Y × +X = -Z is +v.
pub fn fabric_patch(
    fabric: weft::fabric::FabricParams,
    uv_origin: [f32; 2],
    lamp: weft::scene::Light,
) -> weft::scene::Scene {
    let mut vertices = Vec::new();
    for (x, z) in [(-1.0f32, -1.0f32), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        vertices.push(weft::scene::Vertex {
            position: [x, 0.0, z],
            normal: [0.0, 1.0, 0.0],
            tangent: [1.0, 0.0, 0.0, 1.0],
            uv: [uv_origin[0] + x, uv_origin[1] - z],
            uv1: [0.0; 2],
        });
    }
    weft::scene::Scene {
        source: "test patch".into(),
        meshes: vec![weft::scene::Mesh {
            name: "patch".into(),
            vertices,
            indices: vec![0, 2, 1, 0, 3, 2],
            material: 0,
            colors: Vec::new(),
            topology: weft::scene::Topology::Triangles,
        }],
        draws: vec![weft::scene::Draw::new(0, glam::Mat4::IDENTITY)],
        materials: vec![weft::scene::Material {
            name: "cloth".into(),
            metallic: 0.0,
            double_sided: true,
            fabric: Some(fabric),
            ..Default::default()
        }],
        lights: vec![lamp],
        ..Default::default()
    }
}

/// A binary glTF container: `json` (padded with spaces) and `bin` (padded with zeros) as its two
/// chunks.
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut text = json.to_vec();
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let mut out = Vec::with_capacity(12 + 8 + text.len() + 8 + bin.len());
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + 8 + text.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// Standard base64 (with padding) of `bytes`: glTF data: URIs in hand-built test files.
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}
