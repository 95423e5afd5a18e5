//! Skinning and morph targets on the GPU: the data [`Renderer::upload`] adds for draws that
//! deform, and [`Renderer::update_pose`], which re-uploads what a pose changes (draw transforms,
//! lights, joint matrices, morph weights) and runs glsl/skin.comp to rewrite the posed vertices.
//!
//! Why a compute pass and not skinning in gbuffer.vert / shadow.vert: the posed vertices are
//! computed once per pose and read by the G-buffer pass and by every shadow-map tile, the vertex
//! stages and their pipelines stay as they are, and the posed buffer can be read back and
//! compared with the CPU twin (`Scene::deformed_vertices`, tests/animation.rs).
//!
//! Each deforming draw gets its own posed copy of its mesh's vertices at the end of the vertex
//! buffer (two nodes may pose one mesh differently); its `DrawRange` points at the copy. Joint
//! matrices are world-from-bind-pose, so a skinned draw's world matrix is the identity.

use bytemuck::{Pod, Zeroable};

use crate::scene::animation::{MeshDeform, VertexSkin};
use crate::scene::Scene;
use crate::vk::{
    shaders, Binding, BindingKind, Buffer, BufferUsageFlags, ComputeDesc, Context, Pipeline,
    Resource, SetLayout, Stages,
};
use crate::Error;

use super::frame::Renderer;
use super::gpu::GpuLight;
use super::upload::{DrawRange, GpuScene};

/// Push constants of glsl/skin.comp (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct SkinPush {
    pub src: u32,
    pub dst: u32,
    pub count: u32,
    pub skin: u32,
    pub joint: u32,
    pub joint_count: u32,
    pub morph: u32,
    pub target_count: u32,
    pub weight: u32,
    pub pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<SkinPush>() == 48);

const NONE: u32 = u32::MAX;

/// glsl/skin.comp's VertexSkin (std430, 32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuVertexSkin {
    joints: [u32; 4],
    weights: [f32; 4],
}

/// One deforming draw.
pub(crate) struct DeformJob {
    /// Index into `Scene::draws`.
    scene_draw: usize,
    /// Index into `Scene::rig.skins`, when skinned.
    skin: Option<usize>,
    push: SkinPush,
}

/// What a scene's deformation keeps on the GPU.
pub(crate) struct GpuDeform {
    skins: Buffer,
    morphs: Buffer,
    /// Every skin's joint matrices, rewritten by each pose.
    joints: Buffer,
    /// Every deforming draw's morph weights, rewritten by each pose.
    weights: Buffer,
    /// First joint matrix of each skin in `joints`.
    joint_offsets: Vec<u32>,
    joint_total: usize,
    weight_total: usize,
    jobs: Vec<DeformJob>,
}

/// Adds a posed copy of the vertices of each deforming draw to `vertices` (the G-buffer layout,
/// `floats` per vertex), points the draws at them, and uploads joint influences and morph deltas.
/// None when nothing deforms.
pub(crate) fn upload<const N: usize>(
    ctx: &Context,
    scene: &Scene,
    vertices: &mut Vec<[f32; N]>,
    mesh_ranges: &[(u32, u32, i32)],
    draws: &mut [DrawRange],
) -> crate::Result<Option<GpuDeform>> {
    let rig = &scene.rig;
    let mut skins: Vec<GpuVertexSkin> = Vec::new();
    let mut morphs: Vec<[f32; 4]> = Vec::new();
    // Per mesh: (first VertexSkin or NONE, first morph delta), once uploaded.
    let mut mesh_data: std::collections::HashMap<usize, (u32, u32)> = Default::default();
    let mut joint_offsets = Vec::new();
    let mut joint_total = 0usize;
    for s in &rig.skins {
        joint_offsets.push(joint_total as u32);
        joint_total += s.joints.len();
    }
    let mut weight_total = 0usize;
    let mut jobs = Vec::new();
    let too_big = |what: &str| {
        Error::input(format!(
            "{}: the {what} of the deforming meshes exceed what one GPU buffer indexes (2^32 elements); deform fewer or smaller meshes",
            scene.source
        ))
    };
    for draw in draws.iter_mut() {
        let Some(b) = rig.binding(draw.scene_draw) else {
            continue;
        };
        let mesh_index = scene.draws[draw.scene_draw].mesh;
        if !rig.deforms(mesh_index, b) {
            continue;
        }
        let empty = MeshDeform::default();
        let deform = rig.meshes.get(&mesh_index).unwrap_or(&empty);
        let count = scene.meshes[mesh_index].vertices.len();
        let (skin_at, morph_at) = *mesh_data.entry(mesh_index).or_insert_with(|| {
            let skin_at = if deform.skin.len() == count {
                let at = skins.len() as u32;
                skins.extend(deform.skin.iter().map(|s: &VertexSkin| GpuVertexSkin {
                    joints: s.joints,
                    weights: s.weights,
                }));
                at
            } else {
                NONE
            };
            let morph_at = morphs.len() as u32;
            for t in &deform.targets {
                for v in 0..count {
                    let d = |list: &Vec<[f32; 3]>| {
                        let x = list.get(v).copied().unwrap_or([0.0; 3]);
                        [x[0], x[1], x[2], 0.0]
                    };
                    morphs.push(d(&t.positions));
                    morphs.push(d(&t.normals));
                    morphs.push(d(&t.tangents));
                }
            }
            (skin_at, morph_at)
        });
        if skins.len() > u32::MAX as usize || morphs.len() > u32::MAX as usize {
            return Err(too_big("joint influences or morph deltas"));
        }
        let first = mesh_ranges[mesh_index].2 as usize;
        let dst = vertices.len();
        if dst + count > i32::MAX as usize {
            return Err(too_big("posed vertices"));
        }
        vertices.extend_from_within(first..first + count);
        draw.vertex_offset = dst as i32;
        let skin = b.skin.filter(|_| skin_at != NONE);
        jobs.push(DeformJob {
            scene_draw: draw.scene_draw,
            skin,
            push: SkinPush {
                src: first as u32,
                dst: dst as u32,
                count: count as u32,
                skin: if skin.is_some() { skin_at } else { NONE },
                joint: skin.map_or(0, |s| joint_offsets[s]),
                joint_count: skin.map_or(0, |s| rig.skins[s].joints.len() as u32),
                morph: morph_at,
                target_count: deform.targets.len() as u32,
                weight: weight_total as u32,
                pad: [0; 3],
            },
        });
        weight_total += deform.targets.len();
    }
    if jobs.is_empty() {
        return Ok(None);
    }
    // Storage buffers cannot be empty.
    let or_one = |n: usize| n.max(1);
    skins.resize(or_one(skins.len()), GpuVertexSkin::zeroed());
    morphs.resize(or_one(morphs.len()), [0.0; 4]);
    Ok(Some(GpuDeform {
        skins: ctx.create_buffer_with(
            "joint influences",
            BufferUsageFlags::STORAGE_BUFFER,
            &skins,
        )?,
        morphs: ctx.create_buffer_with(
            "morph deltas",
            BufferUsageFlags::STORAGE_BUFFER,
            &morphs,
        )?,
        joints: ctx.create_buffer_with(
            "joint matrices",
            BufferUsageFlags::STORAGE_BUFFER,
            &vec![[0f32; 16]; or_one(joint_total)],
        )?,
        weights: ctx.create_buffer_with(
            "morph weights",
            BufferUsageFlags::STORAGE_BUFFER,
            &vec![0f32; or_one(weight_total)],
        )?,
        joint_offsets,
        joint_total,
        weight_total,
        jobs,
    }))
}

/// The skinning pass's set layout and pipeline, made on the first scene that deforms.
pub(crate) struct SkinPass {
    layout: SetLayout,
    pipeline: Pipeline,
}

impl SkinPass {
    /// The pass's pipeline (for `Renderer::pipelines`).
    pub(crate) fn pipeline(&self) -> &Pipeline {
        &self.pipeline
    }

    pub(crate) fn new(ctx: &Context) -> crate::Result<SkinPass> {
        let layout = ctx.create_set_layout(
            &(0..5)
                .map(|binding| Binding {
                    binding,
                    kind: BindingKind::StorageBuffer,
                    stages: Stages::COMPUTE,
                })
                .collect::<Vec<_>>(),
        )?;
        let pipeline = ctx.create_compute_pipeline(&ComputeDesc {
            name: "skin",
            shader: &shaders::SKIN_COMP,
            set_layouts: &[&layout],
            push_constant_size: std::mem::size_of::<SkinPush>() as u32,
            constants: &[],
        })?;
        Ok(SkinPass { layout, pipeline })
    }
}

impl Renderer {
    /// Re-uploads what [`Scene::pose`] changed: the draws' world matrices (push constants), the
    /// lights, the material records where KHR_animation_pointer drives materials, and, for
    /// skinned and morphed draws, the joint matrices and morph weights, then rewrites their posed
    /// vertices on the GPU. Meshes and textures are not touched.
    /// `scene` must be the scene `gpu` was uploaded from.
    pub fn update_pose(&self, gpu: &mut GpuScene, scene: &Scene) -> crate::Result<()> {
        let mismatch = || {
            Error::input(format!(
                "update_pose was given a scene ({}) that is not the one uploaded: its draws or lights differ in number; upload it instead",
                scene.source
            ))
        };
        for d in &mut gpu.draws {
            let posed = scene.draws.get(d.scene_draw).ok_or_else(mismatch)?;
            d.world = posed.world;
            d.visible = posed.visible;
        }
        if scene.lights.len() != gpu.light_count as usize {
            return Err(mismatch());
        }
        if !scene.rig.lights.is_empty() {
            for (r, l) in gpu.light_records.iter_mut().zip(&scene.lights) {
                *r = GpuLight::new(l);
            }
            gpu.lights.write(0, &gpu.light_records)?;
        }
        // KHR_animation_pointer drives material factors: their records again (the textures,
        // weaves and plan stay: a pose changes values, never which extensions a material has).
        if scene
            .rig
            .pointed
            .as_ref()
            .is_some_and(|p| !p.materials.is_empty())
        {
            self.update_material_records(scene, gpu)?;
        }
        let Some(deform) = gpu.deform.as_mut() else {
            return Ok(());
        };
        let mut joints = vec![[0f32; 16]; deform.joint_total.max(1)];
        for (s, skin) in scene.rig.skins.iter().enumerate() {
            let at = deform.joint_offsets.get(s).copied().ok_or_else(mismatch)? as usize;
            for (k, m) in skin.joint_matrices.iter().enumerate() {
                if let Some(slot) = joints.get_mut(at + k) {
                    *slot = m.to_cols_array();
                }
            }
        }
        deform.joints.write(0, &joints)?;
        let mut weights = vec![0f32; deform.weight_total.max(1)];
        for job in &deform.jobs {
            let b = scene.rig.binding(job.scene_draw).ok_or_else(mismatch)?;
            let n = job.push.target_count as usize;
            let at = job.push.weight as usize;
            for (k, w) in b.weights.iter().take(n).enumerate() {
                weights[at + k] = *w;
            }
            if job.skin != b.skin && job.push.skin != NONE {
                return Err(mismatch());
            }
        }
        deform.weights.write(0, &weights)?;

        let pass = match self.skin_pass.get() {
            Some(p) => p,
            None => {
                let _ = self.skin_pass.set(SkinPass::new(&self.ctx)?);
                self.skin_pass.get().expect("just set")
            }
        };
        let deform = gpu.deform.as_ref().expect("checked above");
        let pool = self.ctx.create_descriptor_pool(1)?;
        let set = pool.set(
            &pass.layout,
            &[
                (0, Resource::Storage(&gpu.vertices)),
                (1, Resource::Storage(&deform.skins)),
                (2, Resource::Storage(&deform.morphs)),
                (3, Resource::Storage(&deform.joints)),
                (4, Resource::Storage(&deform.weights)),
            ],
        )?;
        self.ctx.submit(|cmd| {
            cmd.vertex_reads_before_compute();
            cmd.bind_pipeline(&pass.pipeline);
            cmd.bind_sets(&pass.pipeline, 0, &[set]);
            for job in &deform.jobs {
                cmd.push_constants(&pass.pipeline, &job.push);
                cmd.dispatch(job.push.count.div_ceil(64), 1, 1);
            }
            cmd.compute_writes_before_vertex_reads();
        })?;
        self.ctx.check_validation()
    }
}

impl GpuScene {
    /// The posed vertices of scene draw `draw` as the GPU last wrote them (after
    /// [`Renderer::update_pose`]), in the vertex buffer's 16-float layout; None for a draw that
    /// does not deform.
    pub fn posed_vertices(&self, draw: usize) -> crate::Result<Option<Vec<[f32; 16]>>> {
        let Some(deform) = &self.deform else {
            return Ok(None);
        };
        let Some(job) = deform.jobs.iter().find(|j| j.scene_draw == draw) else {
            return Ok(None);
        };
        let bytes = self.vertices.read()?;
        let floats: &[f32] = bytemuck::cast_slice(bytes);
        let start = job.push.dst as usize * 16;
        let end = start + job.push.count as usize * 16;
        Ok(floats.get(start..end).map(|f| {
            f.chunks_exact(16)
                .map(|c| {
                    let mut v = [0f32; 16];
                    v.copy_from_slice(c);
                    v
                })
                .collect()
        }))
    }
}
