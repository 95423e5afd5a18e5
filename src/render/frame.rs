//! The frame: what must exist before it (pipelines, the environment, targets), its per-frame
//! buffers, then the passes the plan lists, each recorded by its own struct from named inputs
//! (render/passes/), then one submission and the readback.
//!
//! A frame is one queue submission: every pass with a timestamp between each two, then the
//! readback copies. `Submission::PerPass` (what `weft render --timings` and `weft bench` use)
//! submits each pass alone between two timestamps and waits for it, so that a pass's time is its
//! own: within one submission a GPU may overlap consecutive passes, and an earlier lavapipe setup
//! read timestamps around a render pass that follows another far too short. On this machine's
//! lavapipe both give the same frame time (`weft bench --submission`, docs/performance.md).

use std::sync::OnceLock;
use std::time::Instant;

use glam::Mat4;

use crate::scene::{ColorSpace, Scene, TextureSlot};
use crate::vk::{
    Attachment, Buffer, BufferLocation, BufferUsageFlags, Cmd, Context, DescriptorPool,
    DescriptorSet, Filter, Image, ImageDesc, ImageUsageFlags, InFlight, Load, Pipeline, QueryPool,
    Resource, Sampler, Topology, Usage,
};

use super::gpu::{FrameData, GpuShadow, TonemapPush};
use super::passes::antialias::{AntialiasInputs, AntialiasPass};
use super::passes::environment::{EnvPasses, GpuEnvironment};
use super::passes::gbuffer::{GBufferInputs, GBufferPass, Kind};
use super::passes::lighting::{LightingInputs, LightingPass, LightingVariant};
use super::passes::occlusion::{OcclusionInputs, OcclusionPass, OcclusionPush};
use super::passes::shadow::{ShadowInputs, ShadowPass};
use super::passes::tonemap::{TonemapInputs, TonemapPass};
use super::passes::transparent::{TransparentInputs, TransparentPass};
use super::passes::weave::WeavePass;
use super::passes::{Recorded, SceneLighting, VariantKey};
use super::plan::{Pass, Plan};
use super::readback::f16_to_f32;
use super::targets::*;
use super::upload::{solid, upload_texture, GpuScene};
use super::{RenderOptions, Submission, WeavePrecision};

/// Wall-clock and GPU time of one pass.
#[derive(Clone, Debug)]
pub struct PassTiming {
    pub name: &'static str,
    /// GPU time between the pass's two timestamps, when the device has timestamps.
    pub gpu_ms: Option<f64>,
    /// CPU time from recording to the end of the wait for the GPU: only when the pass was
    /// submitted alone (`Submission::PerPass`, and the readback's host copy); a pass inside the
    /// frame's one submission has no wall time of its own (the "submission" entry has the whole).
    pub wall_ms: Option<f64>,
}

/// What the frame actually did.
#[derive(Clone, Debug, Default)]
pub struct FrameStats {
    pub passes: Vec<&'static str>,
    pub draws: usize,
    pub triangles: usize,
    pub pipelines: Vec<String>,
    /// Weave textures of the scene (built by the weave pass at upload) and the pass's dispatches.
    pub weave_textures: usize,
    pub weave_dispatches: u32,
    /// Shadow maps rendered, and the caster draws into them.
    pub shadow_maps: usize,
    pub shadow_draws: usize,
    /// alphaMode BLEND draws the transparent pass drew.
    pub blend_draws: usize,
    /// Slices of view distance of the frame's light lists (1: a list per 16 x 16-pixel tile;
    /// render::tiles).
    pub light_slices: u32,
    /// Queue submissions the frame made (the passes and the readback; not the environment's
    /// preprocessing or other work done once before the first frame that needs it).
    pub submissions: u64,
    /// This frame prepared its environment from weft's cache on disk (crate::cache) instead of
    /// preprocessing it.
    pub environment_from_disk: bool,
    /// Whether this frame's world light was read from weft's cache on disk (render::world_light).
    pub world_light_from_disk: bool,
}

/// A rendered frame, read back.
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// Display-referred RGBA8, sRGB-encoded, rows top to bottom.
    pub ldr: Vec<u8>,
    /// Linear HDR radiance (before exposure), RGBA f32, rows top to bottom.
    pub hdr: Vec<f32>,
    pub timings: Vec<PassTiming>,
    pub stats: FrameStats,
    pub plan: Plan,
}

/// The renderer: a device, each pass with its pipelines, what the passes share, and the targets
/// and environments kept between frames.
pub struct Renderer {
    /// The last overlapped frame ([`Renderer::render_frame_overlapped`]), submitted and not yet
    /// waited for. First, so that the renderer's drop waits for it before anything else goes.
    in_flight: Option<FrameInFlight>,
    pub(crate) ctx: Context,
    gbuffer: GBufferPass,
    shadow: ShadowPass,
    occlusion: OcclusionPass,
    lighting: LightingPass,
    transparent: TransparentPass,
    tonemap: TonemapPass,
    antialias: AntialiasPass,
    pub(crate) weave: WeavePass,
    /// Environment preprocessing and its fixed resources (Pass::Environment).
    env: EnvPasses,
    /// Preprocessed environments, newest last (a few are kept, found by content hash).
    env_cache: Vec<GpuEnvironment>,
    /// The skinning pass (render::deform), made on the first scene that deforms.
    pub(crate) skin_pass: OnceLock<super::deform::SkinPass>,
    pub(crate) defaults: Defaults,
    /// The shadow atlas of the last frame that had shadows (kept while the size stays).
    shadow_atlas: Option<Image>,
    pub(crate) targets: Option<Targets>,
}

/// Samplers and stand-in images the passes share.
pub(crate) struct Defaults {
    /// Trilinear, repeating: material textures without a glTF sampler, the weave.
    pub(crate) linear: Sampler,
    /// Bilinear, clamped: the anti-aliasing pass's reads between texels.
    pub(crate) linear_clamp: Sampler,
    /// The G-buffer's per-pixel fetches.
    pub(crate) nearest: Sampler,
    /// Depth comparison for the shadow atlas.
    pub(crate) shadow: Sampler,
    /// 1 x 1 stand-ins for a material's missing textures.
    pub(crate) white: Image,
    pub(crate) flat_normal: Image,
    /// A 1 x 1 shadow atlas at depth 0 (everything lit), bound when no shadow map is rendered.
    pub(crate) no_shadows: Image,
    /// One zeroed lobe albedo table, bound when a frame reads none (binding 17).
    pub(crate) no_lobe_albedo: Buffer,
}

impl Defaults {
    fn new(ctx: &Context) -> crate::Result<Defaults> {
        let no_shadows = ctx.create_image(
            &ImageDesc::new_2d("no shadows", SHADOW_FORMAT, 1, 1)
                .usage(ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | ImageUsageFlags::SAMPLED),
        )?;
        ctx.submit(|cmd| {
            cmd.transition(&no_shadows, Usage::Undefined, Usage::DepthAttachment, None);
            cmd.begin_rendering(
                &[],
                Some(Attachment {
                    image: &no_shadows,
                    load: Load::Clear([0.0; 4]),
                }),
            );
            cmd.end_rendering();
            cmd.transition(
                &no_shadows,
                Usage::DepthAttachment,
                Usage::FragmentRead,
                None,
            );
        })?;
        Ok(Defaults {
            linear: ctx.create_sampler(Filter::LinearRepeat)?,
            linear_clamp: ctx.create_sampler(Filter::LinearClamp)?,
            nearest: ctx.create_sampler(Filter::NearestClamp)?,
            shadow: ctx.create_sampler(Filter::ShadowCompare)?,
            white: upload_texture(
                ctx,
                &solid("default white", [255, 255, 255, 255], ColorSpace::Srgb),
            )?,
            flat_normal: upload_texture(
                ctx,
                &solid("default normal", [128, 128, 255, 255], ColorSpace::Linear),
            )?,
            no_shadows,
            no_lobe_albedo: ctx.create_buffer_with(
                "no lobe albedo",
                BufferUsageFlags::STORAGE_BUFFER,
                &crate::env::lobe_albedo::records(&[]),
            )?,
        })
    }
}

/// Makes the intermediates a frame of `options` writes that `targets` lacks: the tone-mapped
/// image before anti-aliasing, the occlusion pass' targets, the fabric lobes' sums, the backdrop
/// of transmissive draws.
fn make_targets(
    ctx: &Context,
    targets: &mut Targets,
    options: &RenderOptions,
    plan: &Plan,
) -> crate::Result<()> {
    let (width, height) = (options.width, options.height);
    if !plan.tone_in_lighting {
        targets.make_hdr(ctx)?;
    }
    if plan.runs(Pass::Antialias) && targets.tonemapped.is_none() {
        targets.tonemapped = Some(
            ctx.create_image(
                &ImageDesc::new_2d("tone-mapped", LDR_FORMAT, width, height)
                    .usage(ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::SAMPLED)
                    .alias(LDR_ENCODED_FORMAT),
            )?,
        );
    }
    if plan.runs(Pass::Occlusion) && targets.occlusion.is_none() {
        targets.occlusion = Some(OcclusionTargets::new(ctx, width, height)?);
    }
    if plan.pool_code(options) > 0 && targets.lobes.is_none() {
        targets.lobes = Some(
            ctx.create_image(
                &ImageDesc::new_2d("fabric lobe sums", LOBES_FORMAT, width, height)
                    .usage(ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::SAMPLED),
            )?,
        );
    }
    if plan.transmission_draws > 0 && targets.backdrop.is_none() {
        targets.backdrop = Some(
            ctx.create_image(
                &ImageDesc::new_2d("backdrop", HDR_FORMAT, width, height)
                    .full_mips()
                    .usage(
                        ImageUsageFlags::SAMPLED
                            | ImageUsageFlags::TRANSFER_DST
                            | ImageUsageFlags::TRANSFER_SRC,
                    ),
            )?,
        );
    }
    Ok(())
}

/// One pipeline (or the fixed passes' few) that a frame lacks, made by [`Renderer::prepare`]'s
/// threads.
enum Job<'v> {
    Shade(&'v LightingVariant),
    Lobes(&'v LightingVariant),
    GBuffer(Topology, Kind),
    Forward(bool),
    /// The G-buffer's depth pre-pass', the tone map's, FXAA's and the occlusion pass'
    /// pipelines, each made once.
    Fixed,
}

/// What a [`Job`] made.
enum Made {
    Shade(LightingVariant, Pipeline),
    Lobes(LightingVariant, Option<Pipeline>),
    GBuffer(Topology, Kind, Pipeline),
    Forward(bool, Pipeline),
    Fixed,
}

/// Whether the lighting pass shades each kind of pixel with a pipeline of its own, over the
/// G-buffer's stencil (`passes::lighting`): where the device has the depth-stencil format, the
/// plan splits the kinds and no debug view shows the G-buffer instead.
fn split_lighting(ctx: &Context, options: &RenderOptions, plan: &Plan) -> bool {
    ctx.info().depth_stencil && plan.material_kinds && options.debug_view == super::DebugView::None
}

/// Whether the anti-aliasing pass runs its edge search only on the blocks with an edge, over the
/// G-buffer's stencil (`passes::antialias`): as the plan says, where the device has the
/// depth-stencil format.
fn antialias_edge_blocks(ctx: &Context, plan: &Plan) -> bool {
    ctx.info().depth_stencil && plan.antialias_edge_blocks
}

/// The pipeline variants a frame records with, and its environment's index in the cache.
struct FrameKeys {
    gbuffer: VariantKey,
    lighting: Vec<LightingVariant>,
    forward: Option<VariantKey>,
    env: Option<usize>,
    /// The environment was prepared for this frame, from the cache on disk.
    env_from_disk: bool,
}

/// The frame's own buffers: its uniform, the tile light lists, the shadow maps' records and
/// tiles, the lamps with their maps' indices, and white vertex colours when forced.
struct FrameBuffers {
    frame: Buffer,
    /// The projection the frame uniform holds (jittered if the frame is).
    proj: Mat4,
    tile_lights: Buffer,
    /// The light lists' slices of view distance.
    light_slices: u32,
    shadows: Buffer,
    /// Per map: its tile (x, y, side) in the atlas and the light's clip-from-world.
    shadow_tiles: Vec<(u32, u32, u32, Mat4)>,
    /// The lamps with each caster's map index (None: the scene's own records serve).
    lights: Option<Buffer>,
    forced_colors: Option<Buffer>,
    /// The world light when the plan has it (the scene's, kept while this frame is in flight),
    /// and how long its bake took when this frame baked it (and whether it came from weft's
    /// cache on disk).
    world_light: Option<std::sync::Arc<super::upload::WorldLightGpu>>,
    world_light_ms: Option<WorldLightTiming>,
}

/// What a world light in memory was made under (`WorldLightGpu::key`): the environment's map,
/// its rotation and intensity.
fn world_light_key(env: &crate::env::EnvLighting) -> ([u8; 32], u32, u32) {
    (
        env.env.hash(),
        env.rotation.to_bits(),
        env.intensity.to_bits(),
    )
}

/// Where a frame's world light comes from (Renderer::world_light_start).
enum WorldStart {
    /// Baked for this scene and environment before, in memory.
    Ready(std::sync::Arc<super::upload::WorldLightGpu>),
    /// Read from weft's cache on disk (the bake, the milliseconds its key and read took).
    Disk(super::world_light::Bake, f64),
    /// To be traced and shaded (the key to keep it under on disk, when there is a cache).
    Trace(Option<Vec<u8>>),
    /// Traced for this scene before (under another sky): to be shaded only.
    Shade(std::sync::Arc<super::world_light::Traced>, Option<Vec<u8>>),
}

/// What a frame's world light cost when this frame made it.
#[derive(Clone, Copy, Debug)]
enum WorldLightTiming {
    /// Read from weft's cache on disk and uploaded, in milliseconds.
    Disk(f64),
    /// Its rays traced (beside the pipelines), then shaded and uploaded after them.
    Traced { rays_ms: f64, shade_ms: f64 },
    /// The rays traced for an earlier sky shaded again, and uploaded.
    Shaded(f64),
}

/// The world light a frame reads, and what it cost when this frame made it.
type WorldLightFrame = (
    std::sync::Arc<super::upload::WorldLightGpu>,
    Option<WorldLightTiming>,
);

/// An overlapped frame on the device: its submission, and what its commands read that is its
/// own (the descriptor pool, the per-frame buffers, the timestamp queries), moved here once the
/// recorded passes that borrowed them were consumed. What it reads that the renderer keeps (the
/// targets, pipelines, environments, defaults) or the caller owns (the `GpuScene`) is waited for
/// before it is recreated or dropped: by `Renderer::settle` where the renderer replaces it, and in
/// any case by every resource's Drop (`vk::InFlight`).
struct FrameInFlight {
    /// First: dropped (and so waited for) before what it reads.
    submission: InFlight,
    _pool: DescriptorPool,
    _buffers: FrameBuffers,
    queries: Option<QueryPool>,
    /// The passes between the timestamps.
    names: Vec<&'static str>,
}

impl FrameInFlight {
    /// Waits for the frame, then adds its passes' GPU times to `timings`: each pass's, and the
    /// whole as "submission (previous frame)".
    fn wait(self, timings: &mut Vec<PassTiming>) -> crate::Result<()> {
        self.submission.wait()?;
        if let Some(q) = &self.queries {
            let stamps = q.read_ns(self.names.len() as u32 + 1)?;
            let between = |a: usize, b: usize| Some((stamps[b] - stamps[a]) / 1e6);
            for (i, name) in self.names.iter().enumerate() {
                timings.push(PassTiming {
                    name,
                    gpu_ms: between(i, i + 1),
                    wall_ms: None,
                });
            }
            timings.push(PassTiming {
                name: "submission (previous frame)",
                gpu_ms: between(0, self.names.len()),
                wall_ms: None,
            });
        }
        Ok(())
    }
}

/// Where a frame's image goes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Output {
    /// Read back to the host (`render_frame`).
    Readback,
    /// Left on the device, the submission waited for (`render_frame_to_target`).
    Target,
    /// Left on the device, the submission in flight until the next frame's
    /// (`render_frame_overlapped`).
    Overlapped,
}

/// Preprocessed environments a renderer keeps.
const ENV_CACHE: usize = 2;

impl Renderer {
    pub fn new(ctx: Context) -> crate::Result<Renderer> {
        // The environment's pipelines and DFG table on a thread of their own while the passes'
        // fixed pipelines compile here (drivers compile pipelines on the CPU).
        let (env, rest) = std::thread::scope(|scope| {
            let env = scope.spawn(|| EnvPasses::new(&ctx));
            let rest = (|| -> crate::Result<_> {
                Ok((
                    WeavePass::new(&ctx)?,
                    TonemapPass::new(&ctx)?,
                    ShadowPass::new(&ctx)?,
                    Defaults::new(&ctx)?,
                ))
            })();
            let env = env
                .join()
                .expect("the environment set-up thread does not panic");
            (env, rest)
        });
        let (weave, tonemap, shadow, defaults) = rest?;
        Ok(Renderer {
            in_flight: None,
            env: env?,
            env_cache: Vec::new(),
            gbuffer: GBufferPass::new(&ctx)?,
            occlusion: OcclusionPass::new(&ctx)?,
            lighting: LightingPass::new(&ctx)?,
            transparent: TransparentPass::new(&ctx)?,
            antialias: AntialiasPass::new(&ctx)?,
            weave,
            tonemap,
            shadow,
            defaults,
            shadow_atlas: None,
            targets: None,
            skin_pass: OnceLock::new(),
            ctx,
        })
    }

    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// Waits for the overlapped frame in flight, if any, and returns its passes' GPU times (see
    /// [`Renderer::render_frame_overlapped`]); then checks the validation layer's messages.
    pub fn finish(&mut self) -> crate::Result<Vec<PassTiming>> {
        let mut timings = Vec::new();
        if let Some(f) = self.in_flight.take() {
            f.wait(&mut timings)?;
        }
        self.ctx.check_validation()?;
        Ok(timings)
    }

    /// Waits for the overlapped frame in flight, if any: before anything it reads is replaced.
    fn settle(&mut self) -> crate::Result<()> {
        match self.in_flight.take() {
            Some(f) => f.wait(&mut Vec::new()),
            None => Ok(()),
        }
    }

    /// Every pipeline the renderer has made so far (the default variants at least), with its
    /// shaders, set layouts, push-constant size and specialization constants.
    pub fn pipelines(&mut self) -> crate::Result<Vec<&Pipeline>> {
        let options = RenderOptions::default();
        self.prepare(
            &options,
            &Plan::new(&Scene::default(), &options),
            None,
            false,
        )?;
        // The default scene's cloth under an environment at the default level: the lighting
        // variants that pool the fabric lobes' samples, with their lobe sums draw.
        let lit = RenderOptions {
            environment: Some(crate::env::EnvLighting::new(std::sync::Arc::new(
                crate::env::Environment::uniform([1.0; 3]),
            ))),
            ..RenderOptions::default()
        };
        let cloth = crate::scene::default_scene();
        self.prepare(&lit, &Plan::new(&cloth, &lit), None, false)?;
        // The transparent pass's default variant: a scene with one blended draw.
        let blended = Scene {
            meshes: vec![crate::scene::Mesh {
                name: "blended".into(),
                vertices: Vec::new(),
                indices: Vec::new(),
                material: 0,
                colors: Vec::new(),
                topology: crate::scene::Topology::Triangles,
            }],
            draws: vec![crate::scene::Draw::new(0, glam::Mat4::IDENTITY)],
            materials: vec![crate::scene::Material {
                blend: true,
                ..Default::default()
            }],
            ..Default::default()
        };
        self.prepare(&options, &Plan::new(&blended, &options), None, false)?;
        // And blended fabric: forward.frag with the woven model (forward_gltf.frag above).
        let mut woven = blended.clone();
        woven.materials[0].fabric = Some(Default::default());
        self.prepare(&options, &Plan::new(&woven, &options), None, false)?;
        // A debug view: one lighting pipeline shades every kind of pixel (lighting.frag, where
        // the stencil-split frame shades each kind with its own module).
        let debug = RenderOptions {
            debug_view: super::DebugView::Albedo,
            ..RenderOptions::default()
        };
        self.prepare(&debug, &Plan::new(&Scene::default(), &debug), None, false)?;
        if self.skin_pass.get().is_none() {
            let _ = self.skin_pass.set(super::deform::SkinPass::new(&self.ctx)?);
        }
        self.antialias.make(&self.ctx, false)?;
        if self.ctx.info().depth_stencil {
            self.antialias.make(&self.ctx, true)?;
        }
        for bounce in [false, true] {
            self.occlusion.make(&self.ctx, true, bounce)?;
        }
        self.shadow.make_mask(&self.ctx, false)?;
        let mut all = vec![self.weave.pipeline()];
        all.extend(self.tonemap.pipelines());
        all.extend(self.shadow.pipelines());
        all.extend(self.env.pipelines());
        all.extend(self.gbuffer.pipelines());
        all.extend(self.lighting.pipelines());
        all.extend(self.transparent.pipelines());
        all.extend(self.skin_pass.get().map(|s| s.pipeline()));
        all.extend(self.antialias.pipelines());
        all.extend(self.occlusion.pipelines());
        Ok(all)
    }

    /// The pipeline variants `options` and `plan` need, and the environment `env` preprocessed
    /// if it is not cached, made concurrently: the pipelines as a list of jobs taken by one
    /// thread per core (this one among them; a CPU driver makes them one at a time, behind
    /// `Context`'s compile lock, a GPU's at once), the environment on a thread of its own, and
    /// with `fresh_targets` the frame's targets ([`Targets::new`] and [`make_targets`]) on
    /// another (on a CPU device their first page faults take the core the one-at-a-time compiler
    /// leaves). Then the shadow pass's cut-out pipeline when the plan has one.
    fn prepare(
        &mut self,
        options: &RenderOptions,
        plan: &Plan,
        env: Option<(&crate::env::Environment, &mut Vec<PassTiming>)>,
        fresh_targets: bool,
    ) -> crate::Result<FrameKeys> {
        let weave_source = match options.weave_precision {
            WeavePrecision::Analytic => 1,
            // The summed-area table, filtered by the sampler where the device can filter RGBA32F
            // (2), else fetched (3).
            WeavePrecision::Sat if self.ctx.info().rgba32f_linear && !options.force.sat_fetch => 2,
            WeavePrecision::Sat => 3,
            _ => 0,
        };
        let light_types = if options.force.light_types {
            7
        } else {
            plan.light_types_mask()
        };
        let gbuffer_key = GBufferPass::key(options, plan, weave_source, light_types);
        let lighting_variants = LightingPass::variants(
            options,
            plan,
            light_types,
            split_lighting(&self.ctx, options, plan),
        );
        // (The transparent pass takes the lighting constants every variant shares.)
        let forward_key = plan.runs(Pass::Transparent).then(|| {
            TransparentPass::key(&gbuffer_key, &lighting_variants[0].0, light_types, plan)
        });
        let need_gbuffer = self.gbuffer.missing(&gbuffer_key, plan);
        let need_lighting: Vec<LightingVariant> = lighting_variants
            .iter()
            .filter(|v| !self.lighting.has(v))
            .cloned()
            .collect();
        let need_forward = match &forward_key {
            Some(k) => self.transparent.missing(k, plan),
            None => Vec::new(),
        };
        let (env, timings) = match env {
            Some((e, t)) => (Some(e), Some(t)),
            None => (None, None),
        };
        let cached_env = env.and_then(|e| self.env_cache.iter().position(|g| g.hash == e.hash()));
        let need_env = env.filter(|_| cached_env.is_none());
        let (ctx, gbuffer, lighting, transparent, env_passes) = (
            &self.ctx,
            &self.gbuffer,
            &self.lighting,
            &self.transparent,
            &self.env,
        );
        let (occlusion, tonemap, antialias) = (&self.occlusion, &self.tonemap, &self.antialias);
        // Every pipeline the frame lacks is one job, the costliest kinds first; the jobs go to as
        // many threads as the machine has cores (this one among them), each taking the next job
        // when it finishes one. The environment's preprocessing waits on the queue (which a CPU
        // driver shares with its compiler) on a thread of its own.
        let mut jobs: Vec<Job> = Vec::new();
        jobs.extend(need_lighting.iter().map(Job::Shade));
        jobs.extend(
            need_lighting
                .iter()
                .filter(|v| LightingPass::pools(&v.0))
                .map(Job::Lobes),
        );
        jobs.extend(need_gbuffer.iter().map(|&(t, k)| Job::GBuffer(t, k)));
        jobs.extend(need_forward.iter().map(|&b| Job::Forward(b)));
        jobs.push(Job::Fixed);
        let curve = TonemapPass::curve(options);
        let run = |job: &Job| -> crate::Result<Made> {
            Ok(match *job {
                Job::Shade(v) => Made::Shade(v.clone(), lighting.make_shade(ctx, v)?),
                Job::Lobes(v) => Made::Lobes(v.clone(), lighting.make_lobes(ctx, v)?),
                Job::GBuffer(t, k) => Made::GBuffer(
                    t,
                    k,
                    gbuffer.make(ctx, &gbuffer_key, t, k, plan.depth_prepass > 0)?,
                ),
                Job::Forward(b) => {
                    let key = forward_key.as_ref().expect("needed only with a key");
                    Made::Forward(b, transparent.make(ctx, key, b)?)
                }
                Job::Fixed => {
                    if plan.depth_prepass > 0 {
                        gbuffer.make_depth(ctx)?;
                    }
                    if plan.runs(Pass::Tonemap) {
                        tonemap.make(ctx, curve)?;
                    }
                    if plan.runs(Pass::Antialias) {
                        antialias.make(ctx, antialias_edge_blocks(ctx, plan))?;
                    }
                    if plan.runs(Pass::Occlusion) {
                        occlusion.make(
                            ctx,
                            plan.occlusion.as_ref().is_some_and(|o| !o.covered_only),
                            plan.occlusion.as_ref().is_some_and(|o| o.bounce),
                        )?;
                    }
                    Made::Fixed
                }
            })
        };
        let next = std::sync::atomic::AtomicUsize::new(0);
        let work = || {
            let mut made = Vec::new();
            loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(job) = jobs.get(i) else {
                    return made;
                };
                made.push(run(job));
            }
        };
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(jobs.len());
        let (made, built_env, targets) = std::thread::scope(|scope| {
            let env = need_env.map(|e| scope.spawn(|| env_passes.build(ctx, e)));
            let targets = fresh_targets.then(|| {
                scope.spawn(|| {
                    let mut t = Targets::new(ctx, options.width, options.height)?;
                    make_targets(ctx, &mut t, options, plan)?;
                    Ok::<_, crate::Error>(t)
                })
            });
            let helpers: Vec<_> = (1..threads).map(|_| scope.spawn(work)).collect();
            let mut made = work();
            for h in helpers {
                made.extend(h.join().expect("a pipeline thread does not panic"));
            }
            let built_env = env
                .map(|h| h.join().expect("the environment's thread does not panic"))
                .transpose();
            let targets = targets
                .map(|h| h.join().expect("the targets' thread does not panic"))
                .transpose();
            (made, built_env, targets)
        });
        if let Some(t) = targets? {
            self.targets = Some(t);
        }
        let mut shades = Vec::new();
        let mut lobes = Vec::new();
        for m in made {
            match m? {
                Made::Shade(v, p) => shades.push((v, p)),
                Made::Lobes(v, p) => lobes.push((v, p)),
                Made::GBuffer(t, k, p) => {
                    self.gbuffer
                        .insert(gbuffer_key.clone(), t, k, plan.depth_prepass > 0, p)
                }
                Made::Forward(b, p) => {
                    let k = forward_key.as_ref().expect("made only with a key");
                    self.transparent.insert(k.clone(), b, p);
                }
                Made::Fixed => {}
            }
        }
        for (v, shade) in shades {
            let l = lobes
                .iter()
                .position(|(w, _)| *w == v)
                .and_then(|i| lobes.swap_remove(i).1);
            self.lighting.insert(v, (shade, l));
        }
        let mut env_from_disk = false;
        let env_index = match built_env? {
            Some(built) => {
                env_from_disk = built.from_cache;
                if let Some(t) = timings {
                    t.push(PassTiming {
                        name: "environment",
                        gpu_ms: None,
                        wall_ms: Some(built.build_ms),
                    });
                }
                if self.env_cache.len() >= ENV_CACHE {
                    self.settle()?;
                    self.env_cache.remove(0);
                }
                self.env_cache.push(built);
                Some(self.env_cache.len() - 1)
            }
            None => cached_env,
        };
        // The cut-out shadow pipeline only when a MASK material casts into a shadow map.
        if plan.mask_casters > 0 && plan.runs(Pass::Shadow) {
            self.shadow.make_mask(&self.ctx, plan.vertex_colors)?;
        }
        Ok(FrameKeys {
            gbuffer: gbuffer_key,
            lighting: lighting_variants,
            forward: forward_key,
            env: env_index,
            env_from_disk,
        })
    }

    /// Renders a scene: upload, then one frame.
    pub fn render(&mut self, scene: &Scene, options: &RenderOptions) -> crate::Result<Frame> {
        let gpu = self.upload(scene)?;
        self.render_frame(scene, &gpu, options)
    }

    /// Renders one frame of an uploaded scene.
    pub fn render_frame(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
    ) -> crate::Result<Frame> {
        let n = options.supersample();
        if n > 1 {
            return self.render_supersampled(scene, gpu, options, n);
        }
        self.render_frame_impl(scene, gpu, options, Output::Readback)
    }

    /// `--aa ssN`: N x N frames, each at the centre of its cell of an N x N grid over the pixel
    /// and without FXAA, averaged: the 8-bit images in linear display light (decoded from sRGB,
    /// averaged, encoded: a multisampled target's resolve after tone mapping, so a bright edge
    /// blends as the eye sees it), the HDR in radiance. The timings are the frames' sums; the
    /// plan is the one asked for.
    fn render_supersampled(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
        n: u32,
    ) -> crate::Result<Frame> {
        use crate::reference::shading::{srgb_decode, srgb_encode};
        options.validate()?;
        let pixels = options.width as usize * options.height as usize;
        let mut ldr = vec![0f64; pixels * 4];
        let mut hdr = vec![0f64; if options.read_hdr { pixels * 4 } else { 0 }];
        let mut timings: Vec<PassTiming> = Vec::new();
        let mut last = None;
        for j in 0..n {
            for i in 0..n {
                let offset = |k: u32| (k as f32 + 0.5) / n as f32 - 0.5;
                let o = RenderOptions {
                    antialias: super::Antialias::None,
                    jitter: [offset(i), offset(j)],
                    ..options.clone()
                };
                let f = self.render_frame_impl(scene, gpu, &o, Output::Readback)?;
                for (acc, px) in ldr.chunks_exact_mut(4).zip(f.ldr.chunks_exact(4)) {
                    for c in 0..3 {
                        acc[c] += srgb_decode(px[c] as f32 / 255.0) as f64;
                    }
                    acc[3] += px[3] as f64 / 255.0;
                }
                for (acc, v) in hdr.iter_mut().zip(&f.hdr) {
                    *acc += *v as f64;
                }
                for t in &f.timings {
                    match timings.iter_mut().find(|s| s.name == t.name) {
                        Some(s) => {
                            s.wall_ms = s.wall_ms.zip(t.wall_ms).map(|(a, b)| a + b);
                            s.gpu_ms = s.gpu_ms.zip(t.gpu_ms).map(|(a, b)| a + b);
                        }
                        None => timings.push(t.clone()),
                    }
                }
                last = Some(f);
            }
        }
        let mut frame = last.expect("n >= 2 frames");
        let scale = 1.0 / (n * n) as f64;
        frame.ldr = ldr
            .chunks_exact(4)
            .flat_map(|p| {
                let rgb = |c: usize| srgb_encode((p[c] * scale) as f32);
                [rgb(0), rgb(1), rgb(2), (p[3] * scale * 255.0 + 0.5) as u8]
            })
            .collect();
        frame.hdr = hdr.iter().map(|v| (v * scale) as f32).collect();
        frame.timings = timings;
        frame.plan = Plan::new(scene, options);
        Ok(frame)
    }

    /// As [`Renderer::render_frame`], without the readback: the tonemapped image stays on the
    /// device, returned in `ColorAttachment` usage (`weft view` copies it to the window). The
    /// returned frame's `ldr` and `hdr` are empty.
    pub fn render_frame_to_target(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
    ) -> crate::Result<(Frame, &Image)> {
        self.render_to_target(scene, gpu, options, Output::Target)
    }

    /// As [`Renderer::render_frame_to_target`], but the frame's submission is not waited for: the
    /// CPU records the next frame while the device runs this one (`weft view`). The next
    /// overlapped frame records its passes first, then waits for this one before it submits
    /// (they share the targets: waiting keeps one frame on the device at a time, and the
    /// presenter's copy of the image, submitted between the two, is ordered before the next
    /// frame's writes by its own barriers). Anything that replaces what the frame reads waits
    /// for it first (targets of another size, an environment evicted from the cache, a new
    /// shadow atlas; [`Renderer::render_frame`] and [`Renderer::render_frame_to_target`] wait
    /// before they start; dropping the renderer, or any resource, waits too).
    ///
    /// The returned frame's timings are the CPU's for this frame (its "submission" wall time,
    /// recording and submitting, and "wait for the previous frame") and the GPU's for the
    /// previous frame, read when its fence was waited for: pass times arrive one frame late.
    /// [`Renderer::finish`] waits for the last frame and returns its GPU times. With
    /// `Submission::PerPass` the frame is waited for, as `render_frame_to_target` does.
    pub fn render_frame_overlapped(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
    ) -> crate::Result<(Frame, &Image)> {
        self.render_to_target(scene, gpu, options, Output::Overlapped)
    }

    fn render_to_target(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
        output: Output,
    ) -> crate::Result<(Frame, &Image)> {
        if options.supersample() > 1 {
            return Err(crate::Error::input(format!(
                "--aa {} renders {} frames per image, for still renders (weft render); a live view takes fxaa or none",
                options.antialias.name(),
                options.antialias.frames_per_side().pow(2)
            )));
        }
        let frame = self.render_frame_impl(scene, gpu, options, output)?;
        let ldr = &self
            .targets
            .as_ref()
            .expect("render_frame_impl made them")
            .ldr;
        Ok((frame, ldr))
    }

    /// Makes what a frame of `options` reads beyond its pipelines: the weaves' RGBA8 copies or
    /// summed-area tables (first frame that asks for that precision), the targets of its size,
    /// and the intermediates its passes write (the tone-mapped image before anti-aliasing, the
    /// backdrop of transmissive draws).
    fn prepare_targets(
        &mut self,
        gpu: &GpuScene,
        options: &RenderOptions,
        plan: &Plan,
    ) -> crate::Result<()> {
        // The weave pass: the mip chains, for every precision but the summed-area table's.
        if options.weave_precision != WeavePrecision::Sat && gpu.weaves.get().is_none() {
            let weaves = gpu
                .weave_params
                .iter()
                .map(|f| self.build_weave(f))
                .collect::<crate::Result<Vec<_>>>()?;
            let _ = gpu.weaves.set(weaves);
        }
        if options.weave_precision == WeavePrecision::Rgba8 && gpu.weaves8.get().is_none() {
            let copies = gpu
                .weaves
                .get()
                .expect("built above")
                .iter()
                .map(|w| self.weave_rgba8(w))
                .collect::<crate::Result<Vec<_>>>()?;
            let _ = gpu.weaves8.set(copies);
        }
        // The fabric lobes' exact albedo, for the approx and fis levels of environment light.
        let tables = plan
            .environment
            .as_ref()
            .map_or(0, |e| e.lobe_albedo_tables);
        if tables > 0 && gpu.lobe_albedo.get().is_none() {
            let records = crate::env::lobe_albedo::records(&gpu.fabric_records);
            let buffer = self.ctx.create_buffer_with(
                "fabric lobe albedo",
                BufferUsageFlags::STORAGE_BUFFER,
                &records,
            )?;
            let _ = gpu.lobe_albedo.set(buffer);
        }
        if options.weave_precision == WeavePrecision::Sat && gpu.weaves_sat.get().is_none() {
            let tables = gpu
                .weave_params
                .iter()
                .map(|f| self.weave_sat(f))
                .collect::<crate::Result<Vec<_>>>()?;
            let _ = gpu.weaves_sat.set(tables);
        }
        let targets = self
            .targets
            .as_mut()
            .expect("made by prepare, at the frame's size");
        make_targets(&self.ctx, targets, options, plan)
    }

    /// Where this frame's world light comes from (render::world_light), decided before its
    /// pipelines are made: the one in memory when its environment is this frame's, else the one
    /// on disk under the same key, else it is to be traced (beside the pipelines) and shaded.
    /// None where the plan has no world light.
    fn world_light_start(
        &self,
        scene: &Scene,
        gpu: &GpuScene,
        plan: &Plan,
        options: &RenderOptions,
    ) -> Option<WorldStart> {
        plan.occlusion.as_ref()?.world.as_ref()?;
        plan.environment.as_ref()?;
        let env = options.environment.as_ref()?;
        let key = world_light_key(env);
        let cached = gpu
            .world_light
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(w) = cached.as_ref().filter(|w| w.key == key) {
            return Some(WorldStart::Ready(w.clone()));
        }
        let start = Instant::now();
        let disk_key = crate::cache::dir().map(|_| {
            super::world_light::cache_key(
                gpu.world_scene_hash
                    .get_or_init(|| super::world_light::scene_hash(scene)),
                &super::passes::environment::EnvPasses::cache_key(&self.ctx, &env.env),
                env.rotation,
                env.intensity,
            )
        });
        if let Some(bake) = disk_key
            .as_deref()
            .and_then(|k| super::world_light::read_cached(scene, k))
        {
            return Some(WorldStart::Disk(bake, start.elapsed().as_secs_f64() * 1e3));
        }
        let traced = gpu
            .world_traced
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .clone()
            .filter(|t| t.holds_for(scene));
        Some(match traced {
            Some(t) => WorldStart::Shade(t, disk_key),
            None => WorldStart::Trace(disk_key),
        })
    }

    /// The frame's world light from where [`Renderer::world_light_start`] found it: the rays
    /// `traced` shaded under the frame's environment (whose SH `sh` the preprocessing left) and
    /// kept on disk, or the bake read from there; uploaded and kept in memory for the next frame.
    fn world_light(
        &self,
        scene: &Scene,
        gpu: &GpuScene,
        start: WorldStart,
        traced: Option<(super::world_light::Traced, f64)>,
        env: &crate::env::EnvLighting,
        sh: [[f32; 3]; 9],
    ) -> crate::Result<WorldLightFrame> {
        let began = Instant::now();
        let sky = super::world_light::SkyLight {
            sh,
            rotation: env.rotation,
            intensity: env.intensity,
        };
        let shade = |traced: &super::world_light::Traced, disk_key: &Option<Vec<u8>>| {
            let bake = super::world_light::shade(traced, scene, &sky);
            if let Some(k) = disk_key {
                super::world_light::write_cached(k, &bake);
            }
            bake
        };
        let (bake, timing) = match (start, traced) {
            (WorldStart::Ready(w), _) => return Ok((w, None)),
            (WorldStart::Disk(bake, ms), _) => (bake, WorldLightTiming::Disk(ms)),
            (WorldStart::Shade(traced, disk_key), _) => {
                (shade(&traced, &disk_key), WorldLightTiming::Shaded(0.0))
            }
            (WorldStart::Trace(disk_key), Some((traced, rays_ms))) => {
                let bake = shade(&traced, &disk_key);
                // Kept for the scene's next sky (`GpuScene::world_traced`).
                *gpu.world_traced
                    .lock()
                    .unwrap_or_else(|poisoned| poisoned.into_inner()) =
                    Some(std::sync::Arc::new(traced));
                (
                    bake,
                    WorldLightTiming::Traced {
                        rays_ms,
                        shade_ms: 0.0,
                    },
                )
            }
            (WorldStart::Trace(_), None) => {
                unreachable!("a frame that traces joins its tracing thread before it shades")
            }
        };
        let mut texels = bake.texels;
        if texels.is_empty() {
            texels.push([0.0, 0.0, 0.0, 1.0]); // a storage buffer cannot be empty
        }
        let buffer = self.ctx.create_buffer_with(
            "world light",
            BufferUsageFlags::STORAGE_BUFFER,
            &texels,
        )?;
        let w = std::sync::Arc::new(super::upload::WorldLightGpu {
            key: world_light_key(env),
            buffer,
            base: bake.base,
        });
        *gpu.world_light
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner()) = Some(w.clone());
        let ms = began.elapsed().as_secs_f64() * 1e3;
        let timing = match timing {
            WorldLightTiming::Disk(read) => WorldLightTiming::Disk(read + ms),
            WorldLightTiming::Traced { rays_ms, .. } => WorldLightTiming::Traced {
                rays_ms,
                shade_ms: ms,
            },
            WorldLightTiming::Shaded(_) => WorldLightTiming::Shaded(ms),
        };
        Ok((w, Some(timing)))
    }

    /// The frame's own buffers (see [`FrameBuffers`]); makes the shadow atlas of the plan's size.
    fn frame_buffers(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        plan: &Plan,
        options: &RenderOptions,
        camera: &crate::scene::Camera,
        env_index: Option<usize>,
        world: Option<WorldStart>,
        traced: Option<(super::world_light::Traced, f64)>,
    ) -> crate::Result<FrameBuffers> {
        let ctx = &self.ctx.clone();
        let mut frame_data =
            FrameData::new(camera, options.width, options.height).jittered(options.jitter);
        if let (Some(i), Some(e)) = (env_index, &options.environment) {
            let g = &self.env_cache[i];
            let rot = crate::env::env_from_world(e.rotation);
            for r in 0..3 {
                frame_data.env_rot[r] = [rot[r][0], rot[r][1], rot[r][2], 0.0];
            }
            let radiance_last = (g.radiance_levels() - 1) as f32;
            frame_data.env_params = [
                e.intensity,
                (super::environment::SPECULAR_LEVELS - 1) as f32,
                g.radiance_size() as f32,
                radiance_last,
            ];
            for k in 0..9 {
                frame_data.sh[k] = [g.sh[k][0], g.sh[k][1], g.sh[k][2], 0.0];
            }
            frame_data.env_background = match e.background {
                crate::env::Background::Env { blur } => [0.0, blur * radiance_last, 0.0, 0.0],
                crate::env::Background::Color(c) => {
                    frame_data.background = [c[0], c[1], c[2], 0.0];
                    [1.0, 0.0, 0.0, 0.0]
                }
                crate::env::Background::None => [2.0, 0.0, 0.0, 0.0],
            };
        }
        frame_data.light_count = gpu.light_count;
        frame_data.material_count = gpu.material_count;
        frame_data.debug_view = options.debug_view as u32;
        // The exposure, for the lighting pass where it tone-maps (TONE_CURVE).
        frame_data.ambient_sky[3] = 2f32.powf(options.exposure);
        let (lists, clusters) = super::tiles::tile_lights(
            &frame_data,
            &gpu.light_records[..gpu.light_count as usize],
            plan.range_culling,
            plan.light_slices,
        );
        frame_data.clusters = clusters;
        let frame =
            ctx.create_buffer_with("frame", BufferUsageFlags::UNIFORM_BUFFER, &[frame_data])?;
        let tile_lights = ctx.create_buffer_with(
            "light cluster lists",
            BufferUsageFlags::STORAGE_BUFFER,
            &lists,
        )?;

        // Shadow maps: the atlas, one record per map, and the lights with their map's index.
        // The maps cover what casts (a ground that only receives does not thin them out).
        let maps = match &plan.caster_bounds {
            Some(b) if !plan.shadows.is_empty() => {
                let layout = super::shadow::AtlasLayout::new(&plan.shadows);
                let size = layout.size();
                if self.shadow_atlas.as_ref().map(|a| a.extent()) != Some((size, size)) {
                    self.settle()?;
                    self.shadow_atlas = None;
                    self.shadow_atlas = Some(ctx.create_image(
                        &ImageDesc::new_2d("shadow atlas", SHADOW_FORMAT, size, size).usage(
                            ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | ImageUsageFlags::SAMPLED,
                        ),
                    )?);
                }
                super::shadow::shadow_records(&plan.shadows, &scene.lights, b, &layout)
                    .into_iter()
                    .enumerate()
                    .map(|(i, (record, m))| {
                        let (x, y) = layout.origin(i);
                        (record, (x, y, plan.shadows[i].resolution, m))
                    })
                    .collect::<Vec<_>>()
            }
            _ => Vec::new(),
        };
        let mut records: Vec<GpuShadow> = maps.iter().map(|s| s.0).collect();
        let lights = if maps.is_empty() {
            None
        } else {
            let mut lights = gpu.light_records.clone();
            for (i, s) in plan.shadows.iter().enumerate() {
                if let Some(r) = lights.get_mut(s.light) {
                    r.spot[2] = i as f32 + 1.0;
                }
            }
            Some(ctx.create_buffer_with(
                "lights with shadows",
                BufferUsageFlags::STORAGE_BUFFER,
                &lights,
            )?)
        };
        if records.is_empty() {
            records.push(bytemuck::Zeroable::zeroed()); // a storage buffer cannot be empty
        }
        let shadows =
            ctx.create_buffer_with("shadows", BufferUsageFlags::STORAGE_BUFFER, &records)?;
        // Vertex colours compiled in (forced) for a scene that has none: every vertex reads white.
        let forced_colors = if plan.vertex_colors && !gpu.has_colors {
            Some(ctx.create_buffer_with(
                "vertex colours (white)",
                BufferUsageFlags::STORAGE_BUFFER,
                &vec![[1.0f32; 4]; gpu.vertex_count.max(1)],
            )?)
        } else {
            None
        };
        let (world_light, world_light_ms) = match (world, &options.environment, env_index) {
            (Some(start), Some(env), Some(i)) => {
                let sh = self.env_cache[i].sh;
                let (w, ms) = self.world_light(scene, gpu, start, traced, env, sh)?;
                (Some(w), ms)
            }
            _ => (None, None),
        };
        Ok(FrameBuffers {
            world_light,
            world_light_ms,
            frame,
            proj: Mat4::from_cols_array_2d(&frame_data.proj),
            tile_lights,
            light_slices: clusters[0] as u32,
            shadows,
            shadow_tiles: maps.into_iter().map(|(_, tile)| tile).collect(),
            lights,
            forced_colors,
        })
    }

    /// Each material's textures as a set of `layout` (the G-buffer pass's set 1, or the
    /// transparent pass's, which adds the slots only it reads): the material's texture and
    /// sampler per slot, a 1 x 1 stand-in where it has none, and its weave in the precision the
    /// frame asks for.
    fn material_sets<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        gpu: &'s GpuScene,
        options: &RenderOptions,
        layout: &crate::vk::SetLayout,
    ) -> crate::Result<Vec<DescriptorSet<'s>>> {
        let d = &self.defaults;
        (0..gpu.material_count as usize)
            .map(|m| {
                let tex = gpu
                    .material_textures
                    .get(m)
                    .copied()
                    .unwrap_or([None; TextureSlot::COUNT]);
                let samplers = gpu.material_samplers.get(m).copied();
                // A slot's own sampler where it has a texture; the default (trilinear, repeat)
                // for the stand-ins.
                let slot = |slot: usize| -> Resource<'s> {
                    let sampler = match (tex[slot], samplers) {
                        (Some(_), Some(s)) => gpu.samplers.get(s[slot]).unwrap_or(&d.linear),
                        _ => &d.linear,
                    };
                    let image = match tex[slot].and_then(|i| gpu.textures.get(i)) {
                        Some(t) => t,
                        None if slot == TextureSlot::Normal as usize
                            || slot == TextureSlot::ClearcoatNormal as usize =>
                        {
                            &d.flat_normal
                        }
                        None => &d.white,
                    };
                    Resource::Sampled(image, sampler)
                };
                let weave = match gpu.material_weave.get(m).copied().flatten() {
                    Some(w) if options.weave_precision == WeavePrecision::Rgba8 => {
                        &gpu.weaves8.get().expect("made for RGBA8 frames")[w]
                    }
                    Some(w) if options.weave_precision == WeavePrecision::Sat => {
                        &gpu.weaves_sat.get().expect("made for summed-area frames")[w]
                    }
                    Some(w) => &gpu.weaves.get().expect("made for mip-chain frames")[w],
                    None => &d.white,
                };
                // Binding 4 is the weave; the texture slots take the bindings around it.
                let bindings: Vec<(u32, Resource<'s>)> =
                    std::iter::once((4, Resource::Sampled(weave, &d.linear)))
                        .chain((0..TextureSlot::COUNT).map(|s| {
                            let binding = if s < 4 { s } else { s + 1 } as u32;
                            (binding, slot(s))
                        }))
                        .filter(|(b, _)| layout.bindings.iter().any(|l| l.binding == *b))
                        .collect();
                pool.set(layout, &bindings)
            })
            .collect()
    }

    fn render_frame_impl(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
        output: Output,
    ) -> crate::Result<Frame> {
        options.validate()?;
        // Only the one-submission frame overlaps; every other waits for the one in flight first.
        let overlapped = output == Output::Overlapped && options.submission == Submission::Frame;
        if !overlapped {
            self.settle()?;
        }
        let readback = output == Output::Readback;
        let plan = Plan::new(scene, options);
        let mut timings = Vec::new();
        // Before the frame: pipelines and the environment (Pass::Environment: preprocessed on
        // first use, then from the cache), made concurrently; the weaves' forms; the targets.
        let env = match (&plan.environment, &options.environment) {
            (Some(_), Some(e)) => Some((e.env.as_ref(), &mut timings)),
            _ => None,
        };
        // Targets of another size are dropped here, once the device is done with them, and made
        // while the pipelines compile.
        let (width, height) = (options.width, options.height);
        let fresh_targets = self.targets.as_ref().map(|t| t.ldr.extent()) != Some((width, height));
        if fresh_targets {
            self.settle()?;
            self.targets = None;
            check_target_memory(
                self.ctx.info(),
                host_available_bytes(),
                width,
                height,
                options.read_hdr,
            )?;
        }
        // The world light's rays, when this frame must trace them, on a thread of their own
        // while the pipelines are made (they need no environment; its SH shades them after).
        let world = self.world_light_start(scene, gpu, &plan, options);
        let lobe_tables = plan
            .environment
            .as_ref()
            .is_some_and(|e| e.lobe_albedo_tables > 0)
            && gpu.lobe_albedo.get().is_none();
        let (keys, traced) = std::thread::scope(|s| {
            let tracing = matches!(world, Some(WorldStart::Trace(_))).then(|| {
                s.spawn(|| {
                    let start = Instant::now();
                    let traced = super::world_light::trace(scene);
                    (traced, start.elapsed().as_secs_f64() * 1e3)
                })
            });
            // The fabric lobes' albedo tables (CPU work, kept for the process) while the
            // pipelines are made; prepare_targets uploads them.
            if lobe_tables {
                s.spawn(|| crate::env::lobe_albedo::records(&gpu.fabric_records));
            }
            let keys = self
                .prepare(options, &plan, env, fresh_targets)
                .and_then(|keys| self.prepare_targets(gpu, options, &plan).map(|()| keys));
            let traced =
                tracing.map(|h| h.join().expect("the world light's thread does not panic"));
            (keys, traced)
        });
        let keys = keys?;
        let camera = match &options.camera_override {
            Some(c) => c.clone(),
            // An automatic framing fills this image's aspect ratio.
            None => scene.camera_for_aspect(
                options.camera,
                options.width as f32 / options.height.max(1) as f32,
            )?,
        };
        let buffers =
            self.frame_buffers(scene, gpu, &plan, options, &camera, keys.env, world, traced)?;
        match buffers.world_light_ms {
            Some(WorldLightTiming::Disk(ms) | WorldLightTiming::Shaded(ms)) => {
                timings.push(PassTiming {
                    name: "world light",
                    gpu_ms: None,
                    wall_ms: Some(ms),
                })
            }
            Some(WorldLightTiming::Traced { rays_ms, shade_ms }) => {
                timings.push(PassTiming {
                    name: "world rays",
                    gpu_ms: None,
                    wall_ms: Some(rays_ms),
                });
                timings.push(PassTiming {
                    name: "world light",
                    gpu_ms: None,
                    wall_ms: Some(shade_ms),
                });
            }
            None => {}
        }
        // The frame in flight (overlapped frames): waited for after this one is recorded.
        let previous = self.in_flight.take();

        // The passes, in the plan's order, each from its named inputs.
        let ctx = self.ctx.clone();
        let submissions = ctx.submissions();
        let pool = ctx.create_descriptor_pool(14 + 3 * gpu.material_count)?;
        let targets = self.targets.as_ref().expect("made by prepare_targets");
        let d = &self.defaults;
        let colors = buffers.forced_colors.as_ref().unwrap_or(&gpu.colors);
        let atlas = match (&self.shadow_atlas, buffers.shadow_tiles.is_empty()) {
            (Some(a), false) => a,
            _ => &d.no_shadows,
        };
        let (env_radiance, env_specular) = match keys.env {
            Some(i) => (&self.env_cache[i].radiance, &self.env_cache[i].specular),
            None => (&self.env.black, &self.env.black),
        };
        let lighting = || SceneLighting {
            frame: &buffers.frame,
            lights: buffers.lights.as_ref().unwrap_or(&gpu.lights),
            shadow_atlas: atlas,
            shadow_sampler: &d.shadow,
            shadows: &buffers.shadows,
            tile_lights: &buffers.tile_lights,
            env_radiance,
            env_specular,
            env_dfg: &self.env.dfg,
            env_sampler: &self.env.sampler,
            lobe_albedo: gpu.lobe_albedo.get().unwrap_or(&d.no_lobe_albedo),
        };
        let mut stats = FrameStats {
            draws: gpu.draws.len(),
            triangles: gpu.triangles,
            environment_from_disk: keys.env_from_disk,
            world_light_from_disk: matches!(
                buffers.world_light_ms,
                Some(WorldLightTiming::Disk(_))
            ),
            light_slices: buffers.light_slices,
            ..Default::default()
        };
        // Where the output goes, and a timestamp before and after each pass.
        let out = readback
            .then(|| Readback::new(&ctx, targets, options.read_hdr))
            .transpose()?;
        let queries = ctx.create_query_pool(plan.passes.len() as u32 + 1)?;
        let mut recorded: Vec<Recorded> = Vec::new();
        for pass in &plan.passes {
            match pass {
                // Preprocessed before the frame (prepare), or found in the cache.
                Pass::Environment => {}
                // The weaves' forms were made before the frame (prepare_targets) by the first
                // frame that reads them: the summed-area tables on the CPU, the mip chains by the
                // weave pass (once per distinct weave, one dispatch per mip level); later frames
                // reuse them. The counts: distinct weaves, and the weave pass's dispatches so far
                // (0 while only summed-area tables were read).
                Pass::Weave => {
                    stats.weave_textures = gpu.weave_params.len();
                    stats.weave_dispatches = gpu
                        .weaves
                        .get()
                        .map_or(0, |w| w.iter().map(|w| w.desc.mip_levels).sum());
                }
                Pass::GBuffer => recorded.push(self.gbuffer.record(
                    &pool,
                    &keys.gbuffer,
                    GBufferInputs {
                        scene: gpu,
                        frame: &buffers.frame,
                        lights: &gpu.lights,
                        colors,
                        material_sets: self.material_sets(
                            &pool,
                            gpu,
                            options,
                            &self.gbuffer.material_layout,
                        )?,
                        targets,
                        material_kinds: plan.material_kinds,
                        fabric_as_pbr: options.fabric_as_pbr,
                        depth_prepass: plan.depth_prepass > 0,
                        world_light: buffers.world_light.as_deref(),
                    },
                )?),
                Pass::Shadow if buffers.shadow_tiles.is_empty() => {}
                Pass::Shadow => {
                    let (pass, draws) = self.shadow.record(
                        &pool,
                        ShadowInputs {
                            scene: gpu,
                            atlas,
                            tiles: buffers.shadow_tiles.clone(),
                            mask_casters: plan.mask_casters > 0,
                            vertex_colors: plan.vertex_colors,
                            colors,
                            white: &d.white,
                            sampler: &d.linear,
                        },
                    )?;
                    stats.shadow_maps = buffers.shadow_tiles.len();
                    stats.shadow_draws = draws;
                    recorded.push(pass);
                }
                Pass::Occlusion => recorded.push(self.occlusion.record(
                    &pool,
                    OcclusionInputs {
                        frame: &buffers.frame,
                        push: OcclusionPush::new(
                            buffers.proj,
                            plan.occlusion.as_ref().map_or(1.0, |o| o.radius),
                        ),
                        targets,
                        nearest: &d.nearest,
                        covered_only: plan.occlusion.as_ref().is_none_or(|o| o.covered_only),
                        bounce: plan.occlusion.as_ref().is_some_and(|o| o.bounce),
                        materials: &gpu.materials,
                        fabrics: &gpu.fabrics,
                        env_specular,
                        env_sampler: &self.env.sampler,
                    },
                )?),
                Pass::Lighting => recorded.push(self.lighting.record(
                    &pool,
                    &keys.lighting,
                    LightingInputs {
                        scene: gpu,
                        lighting: lighting(),
                        targets,
                        nearest: &d.nearest,
                        occlusion: match &targets.occlusion {
                            Some(o) if plan.runs(Pass::Occlusion) => &o.visibility,
                            _ => &d.white,
                        },
                        bounce: match &targets.occlusion {
                            Some(o) if plan.runs(Pass::Occlusion) => &o.bounce,
                            _ => &d.white,
                        },
                        lobes: targets.lobes.as_ref(),
                        // The 8-bit image where the lighting tone-maps, as the tonemap pass
                        // would write it.
                        output: if plan.tone_in_lighting {
                            targets.tone_mapped_target(plan.runs(Pass::Antialias))
                        } else {
                            targets.hdr()
                        },
                    },
                )?),
                Pass::Transparent => {
                    let (pass, blended) = self.transparent.record(
                        &pool,
                        keys.forward
                            .as_ref()
                            .expect("prepare makes the key when the plan has the pass"),
                        TransparentInputs {
                            scene: gpu,
                            lighting: lighting(),
                            colors,
                            material_sets: self.material_sets(
                                &pool,
                                gpu,
                                options,
                                &self.transparent.material_layout,
                            )?,
                            targets,
                            backdrop: targets
                                .backdrop
                                .as_ref()
                                .filter(|_| plan.transmission_draws > 0)
                                .map(|b| (b, &self.env.sampler)),
                            white: (&d.white, &d.linear),
                            view: camera.view,
                            opaque_back_faces_first: options.force.back_faces_first,
                        },
                    )?;
                    stats.blend_draws = blended;
                    recorded.push(pass);
                }
                Pass::Tonemap => recorded.push(self.tonemap.record(
                    &pool,
                    TonemapInputs {
                        targets,
                        nearest: &d.nearest,
                        push: TonemapPush {
                            exposure: 2f32.powf(options.exposure),
                        },
                        curve: TonemapPass::curve(options),
                        antialiased: plan.runs(Pass::Antialias),
                    },
                )?),
                Pass::Antialias => recorded.push(self.antialias.record(
                    &pool,
                    AntialiasInputs {
                        targets,
                        sampler: &d.linear_clamp,
                        edge_blocks: antialias_edge_blocks(&self.ctx, &plan),
                    },
                )?),
            }
            stats.passes.push(pass.name());
        }
        for pass in &recorded {
            stats.pipelines.extend(pass.pipelines.iter().cloned());
        }

        // One submission (or one per pass), then the readback; or, overlapped, this frame
        // recorded, the previous one waited for, this one submitted and kept in flight.
        if overlapped {
            let names: Vec<&'static str> = recorded.iter().map(|p| p.name).collect();
            let start = Instant::now();
            let recording =
                ctx.record(|cmd| record_frame(cmd, recorded, queries.as_ref(), None))?;
            let record_ms = start.elapsed().as_secs_f64() * 1e3;
            let wait = Instant::now();
            if let Some(p) = previous {
                p.wait(&mut timings)?;
            }
            let wait_ms = wait.elapsed().as_secs_f64() * 1e3;
            let submit = Instant::now();
            let submission = recording.submit()?;
            timings.push(PassTiming {
                name: "submission",
                gpu_ms: None,
                wall_ms: Some(record_ms + submit.elapsed().as_secs_f64() * 1e3),
            });
            timings.push(PassTiming {
                name: "wait for the previous frame",
                gpu_ms: None,
                wall_ms: Some(wait_ms),
            });
            self.in_flight = Some(FrameInFlight {
                submission,
                _pool: pool,
                _buffers: buffers,
                queries,
                names,
            });
            stats.submissions = ctx.submissions() - submissions;
            ctx.check_validation()?;
            return Ok(Frame {
                width: options.width,
                height: options.height,
                ldr: Vec::new(),
                hdr: Vec::new(),
                timings,
                stats,
                plan,
            });
        }
        drop(previous);
        submit(
            &ctx,
            recorded,
            out.as_ref(),
            queries.as_ref(),
            options.submission,
            &mut timings,
        )?;
        let (ldr, hdr) = match out {
            Some(out) => {
                let start = Instant::now();
                let images = out.read()?;
                match timings.iter_mut().find(|t| t.name == "readback") {
                    Some(t) => {
                        *t.wall_ms.get_or_insert(0.0) += start.elapsed().as_secs_f64() * 1e3;
                    }
                    None => timings.push(PassTiming {
                        name: "readback",
                        gpu_ms: None,
                        wall_ms: Some(start.elapsed().as_secs_f64() * 1e3),
                    }),
                }
                images
            }
            None => (Vec::new(), Vec::new()),
        };
        stats.submissions = ctx.submissions() - submissions;
        drop(pool);
        ctx.check_validation()?;
        Ok(Frame {
            width: options.width,
            height: options.height,
            ldr,
            hdr,
            timings,
            stats,
            plan,
        })
    }
}

/// A frame's output on its way to the host: the 8-bit target and (for EXR output, tests and the
/// bench) the HDR target, copied into host-visible buffers by the frame's last commands.
struct Readback<'t> {
    ldr: (&'t Image, Buffer),
    hdr: Option<(&'t Image, Buffer)>,
}

impl<'t> Readback<'t> {
    fn new(ctx: &Context, targets: &'t Targets, read_hdr: bool) -> crate::Result<Readback<'t>> {
        let buffer = |image: &Image, texel: u64| {
            let (w, h) = image.extent();
            ctx.create_buffer(
                &format!("readback of {}", image.desc.name),
                u64::from(w) * u64::from(h) * texel,
                BufferUsageFlags::TRANSFER_DST,
                BufferLocation::Readback,
            )
        };
        Ok(Readback {
            ldr: (&targets.ldr, buffer(&targets.ldr, 4)?),
            hdr: if read_hdr {
                Some((targets.hdr(), buffer(targets.hdr(), 8)?))
            } else {
                None
            },
        })
    }

    /// The copies: the 8-bit target from the colour attachment the last pass left it as, the
    /// HDR target from fragment reads; each left as it was.
    fn record<'s>(&'s self, cmd: &mut Cmd<'s>) {
        let copies = [Some((&self.ldr, Usage::ColorAttachment))]
            .into_iter()
            .chain([self.hdr.as_ref().map(|h| (h, Usage::FragmentRead))]);
        for ((image, buffer), from) in copies.flatten() {
            cmd.transition(image, from, Usage::TransferSrc, Some((0, 1)));
            cmd.copy_image_to_buffer(image, 0, buffer);
            cmd.transition(image, Usage::TransferSrc, from, Some((0, 1)));
        }
        cmd.buffer_barrier();
    }

    /// The 8-bit image and the HDR radiance as f32 (empty without `read_hdr`).
    fn read(&self) -> crate::Result<(Vec<u8>, Vec<f32>)> {
        let ldr = self.ldr.1.read()?.to_vec();
        let hdr = match &self.hdr {
            Some((_, b)) => b
                .read()?
                .chunks_exact(2)
                .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
                .collect(),
            None => Vec::new(),
        };
        Ok((ldr, hdr))
    }
}

/// A one-submission frame's commands: the passes with a timestamp before the first and after
/// each, then the readback copies.
fn record_frame<'s>(
    cmd: &mut Cmd<'s>,
    passes: Vec<Recorded<'s>>,
    queries: Option<&'s QueryPool>,
    readback: Option<&'s Readback<'s>>,
) {
    if let Some(q) = queries {
        cmd.reset_queries(q);
        cmd.timestamp(q, 0);
    }
    for (i, pass) in passes.into_iter().enumerate() {
        (pass.commands)(cmd);
        if let Some(q) = queries {
            cmd.timestamp(q, i as u32 + 1);
        }
    }
    if let Some(r) = readback {
        r.record(cmd);
    }
}

/// Submits the recorded passes and the readback copies: as one submission with a timestamp
/// between each two passes (`Submission::Frame`; a "submission" timing has its wall time), or
/// one submission per pass between two timestamps, the readback last (`Submission::PerPass`).
fn submit<'s>(
    ctx: &'s Context,
    passes: Vec<Recorded<'s>>,
    readback: Option<&'s Readback<'s>>,
    queries: Option<&'s crate::vk::QueryPool>,
    submission: Submission,
    timings: &mut Vec<PassTiming>,
) -> crate::Result<()> {
    let ms = |start: Instant| start.elapsed().as_secs_f64() * 1e3;
    match submission {
        Submission::Frame => {
            let names: Vec<&'static str> = passes.iter().map(|p| p.name).collect();
            let start = Instant::now();
            ctx.submit(|cmd| record_frame(cmd, passes, queries, readback))?;
            let wall = ms(start);
            let stamps = queries
                .map(|q| q.read_ns(names.len() as u32 + 1))
                .transpose()?;
            let between = |a: usize, b: usize| stamps.as_ref().map(|t| (t[b] - t[a]) / 1e6);
            for (i, name) in names.iter().enumerate() {
                timings.push(PassTiming {
                    name,
                    gpu_ms: between(i, i + 1),
                    wall_ms: None,
                });
            }
            timings.push(PassTiming {
                name: "submission",
                gpu_ms: between(0, names.len()),
                wall_ms: Some(wall),
            });
        }
        Submission::PerPass => {
            for pass in passes {
                let start = Instant::now();
                let name = pass.name;
                ctx.submit(|cmd| {
                    if let Some(q) = queries {
                        cmd.reset_queries(q);
                        cmd.timestamp(q, 0);
                    }
                    (pass.commands)(cmd);
                    if let Some(q) = queries {
                        cmd.timestamp(q, 1);
                    }
                })?;
                let gpu_ms = match queries {
                    Some(q) => {
                        let t = q.read_ns(2)?;
                        Some((t[1] - t[0]) / 1e6)
                    }
                    None => None,
                };
                timings.push(PassTiming {
                    name,
                    gpu_ms,
                    wall_ms: Some(ms(start)),
                });
            }
            if let Some(r) = readback {
                let start = Instant::now();
                ctx.submit(|cmd| r.record(cmd))?;
                timings.push(PassTiming {
                    name: "readback",
                    gpu_ms: None,
                    wall_ms: Some(ms(start)),
                });
            }
        }
    }
    Ok(())
}
