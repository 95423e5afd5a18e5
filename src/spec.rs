//! What to render, as every command gives it: a scene file (or the built-in default scene), its
//! variant and `--fabric` requests, the environment, the lights and the options of a frame.
//! [`SceneSpec::load`] is the one way from such a description to a loaded, staged [`Scene`] and
//! its [`RenderOptions`]: `weft render`, `plan`, `compare`, `sheet`, `view`, the batch renders and
//! the benches all come through it (the command line only turns its flags into a `SceneSpec`).
//!
//! Nothing here prints: the loader's warnings stay in `scene.warnings`, what `--fabric` applied
//! is returned, and the caller says what it wants to say.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use glam::Vec3;

use crate::assets::Applied;
use crate::env::{Background, EnvLighting, Environment, IblLevel, LightsMode};
use crate::render::{
    Accuracy, DebugView, Footprint, Occlusion, RenderOptions, Shading, WeavePrecision,
};
use crate::scene::{LoadOptions, Scene};
use crate::{Result, Warning};

/// Where environment light comes from.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum EnvSource {
    /// None: lamps and a fixed ambient only.
    None,
    /// The built-in procedural studio.
    #[default]
    Studio,
    /// An equirectangular `.hdr` or `.exr` file.
    File(PathBuf),
}

impl EnvSource {
    /// `none`, `studio`, or a path.
    pub fn parse(text: &str) -> EnvSource {
        match text {
            "none" => EnvSource::None,
            "studio" => EnvSource::Studio,
            path => EnvSource::File(PathBuf::from(path)),
        }
    }

    /// The file, when the environment is the user's own.
    pub fn file(&self) -> Option<&Path> {
        match self {
            EnvSource::File(p) => Some(p),
            _ => None,
        }
    }
}

/// The built-in studio, generated once per process (`weft sheet` lights every file with it).
pub fn studio() -> Arc<Environment> {
    static STUDIO: OnceLock<Arc<Environment>> = OnceLock::new();
    STUDIO
        .get_or_init(|| Arc::new(Environment::studio()))
        .clone()
}

/// A scene and how to render it. [`Default`] is `weft render` with no flags: the built-in scene
/// under the studio, the default accuracy, occlusion and lights.
#[derive(Clone, Debug)]
pub struct SceneSpec {
    /// A `.gltf` or `.glb` file; the built-in default scene when None.
    pub scene: Option<PathBuf>,
    /// KHR_materials_variants: the variant whose materials to load.
    pub variant: Option<String>,
    /// Which of the file's glTF scenes to draw, by index or name (None: the file's default).
    pub gltf_scene: Option<String>,
    /// `weft render --fabric` requests (`MATERIAL=PRESET...`, [`crate::assets`]).
    pub fabric: Vec<String>,
    /// Output size; the caller's default size when None.
    pub size: Option<(u32, u32)>,
    /// Index of the scene's camera (None: its first, or automatic framing).
    pub camera: Option<usize>,
    /// A camera at the first point looking at the second, instead of the scene's.
    pub look_at: Option<(Vec3, Vec3)>,
    /// The vertical field of view of `look_at`'s camera, in degrees.
    pub fov_degrees: f32,
    pub accuracy: Accuracy,
    pub weave_precision: WeavePrecision,
    pub footprint: Footprint,
    pub debug_view: DebugView,
    pub shading: Shading,
    pub env: EnvSource,
    /// The environment's turn about the vertical axis, in degrees.
    pub env_rotation: f32,
    /// A scale on the environment's radiance.
    pub env_intensity: f32,
    pub background: Background,
    pub ibl: IblLevel,
    /// The fabric lobes' pooling radius at fis ([`EnvLighting::pool`]).
    pub ibl_pool: u32,
    pub occlusion: Occlusion,
    pub lights: LightsMode,
}

impl Default for SceneSpec {
    fn default() -> SceneSpec {
        SceneSpec {
            scene: None,
            variant: None,
            gltf_scene: None,
            fabric: Vec::new(),
            size: None,
            camera: None,
            look_at: None,
            fov_degrees: 40.0,
            accuracy: Accuracy::default(),
            weave_precision: WeavePrecision::default(),
            footprint: Footprint::default(),
            debug_view: DebugView::None,
            shading: Shading::default(),
            env: EnvSource::Studio,
            env_rotation: 0.0,
            env_intensity: 1.0,
            background: Background::Env { blur: 0.0 },
            ibl: crate::env::DEFAULT_IBL,
            ibl_pool: crate::env::DEFAULT_POOL,
            occlusion: Occlusion::DEFAULT,
            lights: LightsMode::Auto,
        }
    }
}

/// A loaded scene, staged, with the options of its frame.
pub struct Loaded {
    pub scene: Scene,
    pub options: RenderOptions,
    /// What `--fabric` did to each material it named.
    pub applied: Vec<Applied>,
}

impl SceneSpec {
    /// The scene alone: the file (or the built-in scene) with its variant and `--fabric`
    /// requests, not staged (the viewer stages what it loads itself).
    pub fn load_unstaged(&self) -> Result<(Scene, Vec<Applied>)> {
        let load_options = LoadOptions {
            variant: self.variant.clone(),
            scene: self.gltf_scene.clone(),
        };
        Ok(match (&self.scene, self.fabric.is_empty()) {
            (Some(path), true) => (crate::scene::load_with(path, &load_options)?, Vec::new()),
            (path, false) => {
                crate::assets::load_with_fabric(path.as_deref(), &self.fabric, &load_options)?
            }
            (None, true) if self.variant.is_some() || self.gltf_scene.is_some() => (
                crate::scene::load_slice_with(
                    crate::scene::DEFAULT_SCENE_GLB,
                    "built-in default scene",
                    None,
                    &load_options,
                )?,
                Vec::new(),
            ),
            (None, true) => (crate::scene::default_scene(), Vec::new()),
        })
    }

    /// [`SceneSpec::load_unstaged`], staged as every command stages it (`env::stage`: the
    /// default key light and ground when it has no lights and no environment of the user's own).
    pub fn load_scene(&self) -> Result<(Scene, Vec<Applied>)> {
        let (mut scene, applied) = self.load_unstaged()?;
        crate::env::stage(
            &mut scene,
            self.lights,
            self.env_rotation,
            self.env.file().is_some(),
        );
        Ok((scene, applied))
    }

    /// The environment's lighting (None for [`EnvSource::None`]), loaded and checked, and the
    /// map's own warnings.
    pub fn environment(&self) -> Result<(Option<EnvLighting>, Vec<Warning>)> {
        let (env, warnings) = match &self.env {
            EnvSource::None => (None, Vec::new()),
            EnvSource::Studio => (Some(studio()), Vec::new()),
            EnvSource::File(path) => {
                let env = Environment::load(path)?;
                let warnings = env.warnings.iter().cloned().map(Warning).collect();
                (Some(Arc::new(env)), warnings)
            }
        };
        let lighting = env.map(|e| {
            let mut l = EnvLighting::new(e);
            l.rotation = self.env_rotation;
            l.intensity = self.env_intensity;
            l.background = self.background;
            l.level = self.ibl;
            l.pool = self.ibl_pool;
            l
        });
        if let Some(l) = &lighting {
            l.validate()?;
        }
        Ok((lighting, warnings))
    }

    /// The scene, staged, and the options of its frame at `self.size` or `default_size`. Fails
    /// before any GPU work on a bad option or a camera index the scene does not have.
    pub fn load(&self, default_size: (u32, u32)) -> Result<Loaded> {
        let (mut scene, applied) = self.load_scene()?;
        let (environment, warnings) = self.environment()?;
        scene.warnings.extend(warnings);
        let (width, height) = self.size.unwrap_or(default_size);
        let mut options = RenderOptions {
            width,
            height,
            camera: self.camera,
            debug_view: self.debug_view,
            accuracy: self.accuracy,
            weave_precision: self.weave_precision,
            footprint: self.footprint,
            shading: self.shading,
            environment,
            occlusion: self.occlusion,
            ..Default::default()
        };
        options.validate()?;
        if let Some((eye, target)) = self.look_at {
            options.camera_override =
                Some(scene.look_at_camera(eye, target, self.fov_degrees.to_radians())?);
        }
        scene.camera(options.camera)?;
        Ok(Loaded {
            scene,
            options,
            applied,
        })
    }

    /// The files a command reads, which none of its outputs may be: the scene file, the buffers
    /// and images it refers to, and the environment map.
    pub fn inputs(&self, scene: &Scene) -> Vec<PathBuf> {
        let mut inputs: Vec<PathBuf> = self.scene.iter().cloned().collect();
        inputs.extend(scene.files.iter().cloned());
        inputs.extend(self.env.file().map(Path::to_path_buf));
        inputs
    }
}
