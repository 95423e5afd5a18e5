//! The passes of a frame, one file each, in the order a frame runs them (the plan's
//! [`crate::render::Pass`] list; `Renderer::render_frame` in frame.rs records them in this order).
//! Each pass is a struct that owns its pipelines and set layouts (`XPass::new(ctx)`, the layouts
//! reflected from its shaders' SPIR-V) and records itself from named inputs
//! (`record(pool, XInputs { .. })`), returning a [`Recorded`] the frame submits:
//!
//! 1. [`environment`]: once per environment, cached: radiance cube, GGX-prefiltered cube, SH;
//! 2. weave (`Renderer::build_weave`, by the first frame that reads them): the coverage mip
//!    chains of each distinct weave (a default frame reads the summed-area tables instead);
//! 3. [`gbuffer`]: every draw into the G-buffer;
//! 4. [`shadow`]: casters into the shadow atlas;
//! 5. [`occlusion`] (with an environment, `--occlusion gtao`): how open each pixel's hemisphere
//!    is, from the depth buffer, for the environment's light;
//! 6. [`lighting`]: lamps and the environment from the G-buffer into HDR (where the woven model
//!    pools its environment samples at fis, a first draw writes each woven pixel's lobe sums:
//!    fabric_lobes.frag);
//! 7. [`transparent`]: alphaMode BLEND draws, forward-lit, back to front over HDR;
//! 8. [`tonemap`]: exposure and tone curve into the 8-bit target;
//! 9. [`antialias`] (`--aa fxaa`): edge anti-aliasing of the tone-mapped image into the 8-bit
//!    target (the tone-map pass then writes an intermediate one).
//!
//! Adding a pass: its GLSL, one file here, one line in the plan's pass list, one call in the
//! frame (docs/architecture.md, "Adding a pass").

pub mod antialias;
pub mod environment;
pub mod gbuffer;
pub mod lighting;
pub mod occlusion;
pub mod shadow;
pub mod tonemap;
pub mod transparent;
pub mod weave;

/// The body of a fullscreen pass (lighting, tone map, anti-aliasing): `target` from undefined to
/// a colour attachment, `pipeline` with `set` (and `push`, if any) over one fullscreen triangle.
pub(crate) fn fullscreen<'s, P: bytemuck::Pod>(
    cmd: &mut crate::vk::Cmd<'s>,
    pipeline: &'s crate::vk::Pipeline,
    set: crate::vk::DescriptorSet<'s>,
    push: Option<&P>,
    target: &'s crate::vk::Image,
) {
    fullscreen_into(
        cmd,
        pipeline,
        set,
        push,
        target,
        crate::vk::Load::Keep,
        None,
    );
}

/// [`fullscreen`] with the target started from `load`, and a depth attachment (the pipeline's
/// depth test, e.g. a triangle at the far plane drawn where a surface is).
pub(crate) fn fullscreen_into<'s, P: bytemuck::Pod>(
    cmd: &mut crate::vk::Cmd<'s>,
    pipeline: &'s crate::vk::Pipeline,
    set: crate::vk::DescriptorSet<'s>,
    push: Option<&P>,
    target: &'s crate::vk::Image,
    load: crate::vk::Load,
    depth: Option<crate::vk::Attachment<'s>>,
) {
    let color = crate::vk::Attachment {
        image: target,
        load,
    };
    fullscreen_targets(cmd, pipeline, set, push, &[color], depth);
}

/// [`fullscreen_into`] with several colour targets (the pipeline's colour attachments, in order),
/// each started from its own load.
pub(crate) fn fullscreen_targets<'s, P: bytemuck::Pod>(
    cmd: &mut crate::vk::Cmd<'s>,
    pipeline: &'s crate::vk::Pipeline,
    set: crate::vk::DescriptorSet<'s>,
    push: Option<&P>,
    colors: &[crate::vk::Attachment<'s>],
    depth: Option<crate::vk::Attachment<'s>>,
) {
    use crate::vk::Usage;
    for color in colors {
        cmd.transition(color.image, Usage::Undefined, Usage::ColorAttachment, None);
    }
    cmd.begin_rendering(colors, depth);
    cmd.bind_pipeline(pipeline);
    cmd.bind_sets(pipeline, 0, &[set]);
    if let Some(push) = push {
        cmd.push_constants(pipeline, push);
    }
    cmd.draw(3);
    cmd.end_rendering();
}

/// A pipeline variant's specialization constants, each with its id, its name and its value, in id
/// order: its key among the variants of one pass, and (as `name=value` pairs) its pipeline's name.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct VariantKey(pub Vec<(u32, &'static str, u32)>);

impl VariantKey {
    /// (id, value) pairs, as the pipeline is specialized.
    pub fn constants(&self) -> Vec<(u32, u32)> {
        self.0.iter().map(|&(id, _, v)| (id, v)).collect()
    }

    /// The value of constant `id` (0 when the key has none).
    pub fn value(&self, id: u32) -> u32 {
        self.0.iter().find(|c| c.0 == id).map_or(0, |c| c.2)
    }

    /// `name=value, ...` (pipeline names, `--stats`).
    pub fn describe(&self) -> String {
        self.0
            .iter()
            .map(|(_, n, v)| format!("{n}={v}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// One pass of a frame, recorded and waiting for the frame's submission: its name (the
/// timings' and `--stats`' name), the pipelines it binds, and its commands.
pub(crate) struct Recorded<'s> {
    pub name: &'static str,
    pub pipelines: Vec<String>,
    pub commands: Box<dyn FnOnce(&mut crate::vk::Cmd<'s>) + 's>,
}

impl<'s> Recorded<'s> {
    pub fn new(
        name: &'static str,
        pipelines: Vec<String>,
        commands: impl FnOnce(&mut crate::vk::Cmd<'s>) + 's,
    ) -> Recorded<'s> {
        Recorded {
            name,
            pipelines,
            commands: Box::new(commands),
        }
    }
}

/// What the lighting and transparent passes both read to light a surface, at the set-0 bindings
/// every shader gives them (one number per resource: glsl/lighting.frag, glsl/forward.frag).
pub(crate) struct SceneLighting<'s> {
    /// The frame's uniform (camera, environment rotation and SH, counts).
    pub frame: &'s crate::vk::Buffer,
    /// The lamps, with each shadow caster's map index.
    pub lights: &'s crate::vk::Buffer,
    /// The shadow atlas (a 1 x 1 lit one when no map is rendered), its comparison sampler, and
    /// one record per map.
    pub shadow_atlas: &'s crate::vk::Image,
    pub shadow_sampler: &'s crate::vk::Sampler,
    pub shadows: &'s crate::vk::Buffer,
    /// Per screen tile, the lamps whose range reaches it (render::tiles).
    pub tile_lights: &'s crate::vk::Buffer,
    /// The environment: radiance cube, GGX-prefiltered cube, DFG table (1 x 1 black cubes when
    /// there is none), and their sampler.
    pub env_radiance: &'s crate::vk::Image,
    pub env_specular: &'s crate::vk::Image,
    pub env_dfg: &'s crate::vk::Image,
    pub env_sampler: &'s crate::vk::Sampler,
    /// The fabric records' lobe albedo tables (weft::reference::lobe_albedo; one zeroed table when the
    /// frame reads none).
    pub lobe_albedo: &'s crate::vk::Buffer,
}

impl<'s> SceneLighting<'s> {
    /// The bindings of set 0 these resources have in every shader that reads them.
    pub fn bindings(&self) -> [(u32, crate::vk::Resource<'s>); 9] {
        use crate::vk::Resource;
        [
            (0, Resource::Uniform(self.frame)),
            (3, Resource::Storage(self.lights)),
            (
                10,
                Resource::Sampled(self.shadow_atlas, self.shadow_sampler),
            ),
            (11, Resource::Storage(self.shadows)),
            (12, Resource::Storage(self.tile_lights)),
            (13, Resource::Sampled(self.env_radiance, self.env_sampler)),
            (14, Resource::Sampled(self.env_specular, self.env_sampler)),
            (15, Resource::Sampled(self.env_dfg, self.env_sampler)),
            (17, Resource::Storage(self.lobe_albedo)),
        ]
    }
}
