//! `weft view`: an interactive window on the same [`Renderer`] and passes as `weft render`, with
//! an orbit camera and a panel of live controls (docs/viewer.md).
//!
//! Each frame: the panel (egui) is laid out, its edits are applied to the scene and the render
//! options, [`Renderer::render_frame_overlapped`] records the passes, waits for the previous
//! frame and submits this one without waiting for it, and
//! [`Presenter::present`](crate::vk::Presenter::present) copies the tonemapped image into the
//! window and draws the panel over it, with up to [`FRAMES_IN_FLIGHT`] presents in flight. So the
//! CPU lays out the panel and records frame N+1 while the device runs frame N; the passes' GPU
//! times a frame reports (the panel's, `--bench-frames`') are the previous frame's, read when
//! its fence was waited for: one frame late.

pub mod controls;
pub mod orbit;
mod panel;
pub mod playback;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::bench::median;
use crate::env::{EnvLighting, Environment, LightsMode};
use crate::render::{GpuScene, PassTiming, RenderOptions, Renderer};
use crate::scene::Scene;
use crate::vk::{Context, ContextOptions, PanelDraw, Presenter, FRAMES_IN_FLIGHT};
use crate::Error;

pub use orbit::Orbit;

/// Where the scene came from (to load it again for another variant).
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSource {
    Builtin,
    File(PathBuf),
}

/// Everything `weft view` is started with.
pub struct ViewOptions {
    /// The scene, already loaded and staged (lights, ground) as `weft render` does.
    pub scene: Scene,
    pub source: SceneSource,
    /// How a scene loaded later (a variant, a dropped file) is staged.
    pub lights: LightsMode,
    /// The environment is the user's own (`--env FILE`): this file.
    pub env_file: Option<String>,
    /// The first frame's options (size = the window's inner size; camera as for render).
    pub options: RenderOptions,
    pub context: ContextOptions,
    /// Write the window's content (panel included unless `panel` is false) after `after`
    /// presented frames, then exit.
    pub screenshot: Option<(PathBuf, u32)>,
    /// Show the panel (Tab toggles it).
    pub panel: bool,
    /// Time this many frames after a warm-up, print the table, exit.
    pub bench_frames: Option<u32>,
    /// The scene's animation clock (None: the scene has no animations).
    pub playback: Option<playback::Playback>,
}

/// The frame loop's figures of `--bench-frames` (medians over the timed frames, ms).
#[derive(Clone, Debug, Default)]
pub struct BenchReport {
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub frame_ms: f64,
    pub ui_ms: f64,
    pub render_ms: f64,
    pub passes_wall_ms: f64,
    /// Of it, the wait for the previous frame's submission (overlapped frames).
    pub frame_wait_ms: f64,
    /// GPU time of each pass: the previous frame's, read when the renderer waited for it (one
    /// frame late; the same passes, so the medians are the same frames' figures).
    pub passes_gpu_ms: Vec<(&'static str, f64)>,
    pub copy_ms: f64,
    pub slot_wait_ms: f64,
    pub present_ms: f64,
    /// Median over frames of (pass submissions' wall time + copy + slot wait) / frame time. Not
    /// the present call: on lavapipe (Mesa 22.3) vkQueuePresentKHR itself waits for the queue to
    /// drain, which is where an overlapped frame's wait for the device went (docs/performance.md).
    pub cpu_wait_fraction: f64,
}

impl BenchReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "weft view frame loop, {}x{}, {} frames after warm-up (medians)\n",
            self.width, self.height, self.frames
        );
        s += "| what | ms |\n|---|---:|\n";
        s += &format!(
            "| frame (start to start) | {:.2} ({:.1} fps) |\n",
            self.frame_ms,
            1e3 / self.frame_ms
        );
        s += &format!("| panel layout + tessellation | {:.2} |\n", self.ui_ms);
        s += &format!("| render_frame (all passes) | {:.2} |\n", self.render_ms);
        s += &format!(
            "| of it, pass submissions (record + wait) | {:.2} |\n",
            self.passes_wall_ms
        );
        s += &format!(
            "| of that, wait for the previous frame | {:.2} |\n",
            self.frame_wait_ms
        );
        for (name, ms) in &self.passes_gpu_ms {
            s += &format!("| GPU: {name} | {ms:.2} |\n");
        }
        s += &format!("| copy of the tonemapped image | {:.2} |\n", self.copy_ms);
        s += &format!(
            "| wait for a free frame slot | {:.2} |\n",
            self.slot_wait_ms
        );
        s += &format!("| present call (whole) | {:.2} |\n", self.present_ms);
        s += &format!(
            "| CPU blocked on the device (render, copy, slot waits; not the present call) | {:.0} % of the frame |\n",
            self.cpu_wait_fraction * 100.0
        );
        s
    }
}

/// No display to open a window on: the message `weft view` exits with.
fn no_display(detail: &str) -> Error {
    Error::device(format!(
        "no display: use weft render ({detail}; weft view opens an X11 window: set DISPLAY, or run it under xvfb-run for an off-screen one)"
    ))
}

/// Opens the window and runs until it is closed (or the screenshot / bench is done).
pub fn run(options: ViewOptions) -> crate::Result<Option<BenchReport>> {
    let display_set = |v: &str| std::env::var_os(v).is_some_and(|s| !s.is_empty());
    if !display_set("DISPLAY") {
        return Err(no_display(if display_set("WAYLAND_DISPLAY") {
            "WAYLAND_DISPLAY is set but DISPLAY is not: weft view needs Xwayland"
        } else {
            "DISPLAY is not set"
        }));
    }
    // winit's error names its own source file, not the display: say which display failed.
    let event_loop = EventLoop::new().map_err(|_| {
        no_display(&format!(
            "cannot connect to the X server at DISPLAY={}",
            std::env::var("DISPLAY").unwrap_or_default()
        ))
    })?;
    event_loop.set_control_flow(ControlFlow::Wait);
    let mut app = App::new(options);
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::device(format!("the window's event loop failed: {e}")))?;
    match app.error.take() {
        Some(e) => Err(e),
        None => Ok(app.report.take()),
    }
}

/// Which camera is shown.
#[derive(Clone, Copy, Debug, PartialEq)]
enum CameraMode {
    /// A camera of the scene exactly as `weft render --camera` would use it (None: its first, or
    /// the automatic framing).
    Scene(Option<usize>),
    /// Moved by the user.
    Orbit,
}

/// One frame's figures.
#[derive(Clone, Debug, Default)]
struct FrameFigures {
    frame_ms: f64,
    ui_ms: f64,
    render_ms: f64,
    passes: Vec<PassTiming>,
    copy_ms: f64,
    slot_wait_ms: f64,
    present_ms: f64,
}

struct Running {
    window: Arc<Window>,
    renderer: Renderer,
    presenter: Presenter,
    gpu: GpuScene,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
}

struct App {
    scene: Scene,
    source: SceneSource,
    lights: LightsMode,
    own_env: bool,
    options: RenderOptions,
    context: ContextOptions,
    screenshot: Option<(PathBuf, u32)>,
    bench_frames: Option<u32>,
    running: Option<Running>,
    ui: panel::UiState,
    camera: CameraMode,
    orbit: Orbit,
    /// Mouse state for the camera.
    cursor: Option<(f64, f64)>,
    rotating: bool,
    panning: bool,
    shift: bool,
    /// Presented frames so far, and figures of each.
    presented: u32,
    figures: Vec<FrameFigures>,
    last_frame: Option<Instant>,
    /// A screenshot asked for by key or button: written to this path at the next frame.
    pending_shot: Option<PathBuf>,
    shots: u32,
    dirty: bool,
    error: Option<Error>,
    report: Option<BenchReport>,
    /// Ctrl is held (ctrl+click picks the material under the cursor).
    ctrl: bool,
    /// Where the scene's image starts in the window (right of the panel), and its width.
    scene_x0: u32,
    scene_width: u32,
    /// What the panel wove or changed, as `weft fabric` requests on the source file: the scene
    /// is the source with these applied, and "save woven file" writes it.
    requests: Vec<crate::assets::Request>,
    /// The animation playing (or paused), if the scene has any.
    playback: Option<playback::Playback>,
}

/// Warm-up frames of `--bench-frames` (the first pays the shader JIT and pipeline creation).
const BENCH_WARMUP: u32 = 3;

impl App {
    fn new(o: ViewOptions) -> App {
        let camera = CameraMode::Scene(o.options.camera);
        let cam = o
            .scene
            .camera(o.options.camera)
            .unwrap_or_else(|_| o.scene.auto_camera());
        let orbit = Orbit::from_camera(&cam, &o.scene);
        let own_env = o.env_file.is_some();
        let ui = panel::UiState::new(o.panel, &o.scene, &o.options, o.env_file);
        App {
            scene: o.scene,
            source: o.source,
            lights: o.lights,
            own_env,
            options: o.options,
            context: o.context,
            screenshot: o.screenshot,
            bench_frames: o.bench_frames,
            running: None,
            ui,
            camera,
            orbit,
            cursor: None,
            rotating: false,
            panning: false,
            shift: false,
            presented: 0,
            figures: Vec::new(),
            last_frame: None,
            pending_shot: None,
            shots: 0,
            dirty: true,
            error: None,
            report: None,
            requests: Vec::new(),
            ctrl: false,
            scene_x0: 0,
            scene_width: 0,
            playback: o.playback,
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: Error) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        event_loop.exit();
    }

    fn start(&mut self, event_loop: &ActiveEventLoop) -> crate::Result<()> {
        let (w, h) = (self.options.width, self.options.height);
        let attrs = Window::default_attributes()
            .with_title(format!("weft view: {}", self.scene.source))
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| no_display(&format!("the window could not be made: {e}")))?,
        );
        let display = raw_window_handle::HasDisplayHandle::display_handle(&*window)
            .map_err(|e| no_display(&e.to_string()))?
            .as_raw();
        let ctx = Context::new_for_display(&self.context, Some(display))?;
        let renderer = Renderer::new(ctx.clone())?;
        let size = window.inner_size();
        let presenter = Presenter::new(&ctx, window.clone(), size.width, size.height)?;
        let gpu = renderer.upload(&self.scene)?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &*window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        self.running = Some(Running {
            window,
            renderer,
            presenter,
            gpu,
            egui_ctx,
            egui_state,
        });
        Ok(())
    }

    /// The scene's camera, or the orbit's.
    fn frame_options(&self, width: u32, height: u32) -> crate::Result<RenderOptions> {
        let mut o = self.options.clone();
        o.width = width;
        o.height = height;
        o.read_hdr = false;
        match self.camera {
            CameraMode::Scene(i) => {
                o.camera = i;
                o.camera_override = None;
            }
            CameraMode::Orbit => o.camera_override = Some(self.orbit.camera(&self.scene)?),
        }
        Ok(o)
    }

    fn switch_to_orbit(&mut self) {
        if let CameraMode::Scene(i) = self.camera {
            if let Ok(cam) = self.scene.camera(i) {
                self.orbit = Orbit::from_camera(&cam, &self.scene);
            }
            self.camera = CameraMode::Orbit;
        }
    }

    /// Loads `source` (with `variant`) and stages it as the first scene was; on success it
    /// replaces the scene, on failure the old scene stays and the error is returned.
    fn open(&mut self, source: SceneSource, variant: Option<String>) -> crate::Result<()> {
        let rotation = self
            .options
            .environment
            .as_ref()
            .map(|e| e.rotation)
            .unwrap_or(0.0);
        let new_file = source != self.source;
        // The same file keeps the glTF scene it shows; another opens at its own default.
        let options = crate::scene::LoadOptions {
            variant,
            scene: if new_file {
                None
            } else {
                self.scene.gltf_scene.map(|i| i.to_string())
            },
        };
        let scene = if new_file || self.requests.is_empty() {
            controls::load(&source, options, self.lights, rotation, self.own_env)?
        } else {
            // The same file (another variant, a weave): with what the panel wove.
            controls::load_woven(
                &source,
                options,
                &self.requests,
                self.lights,
                rotation,
                self.own_env,
            )?
            .0
        };
        if let Some(r) = &self.running {
            let gpu = r.renderer.upload(&scene)?;
            self.running.as_mut().expect("checked").gpu = gpu;
        }
        if new_file {
            // The panel's requests were for the old file.
            self.requests.clear();
        }
        self.scene = scene;
        self.source = source;
        // The same file keeps its clock (another variant); another file plays its first
        // animation from the start.
        let keep = !new_file
            && self
                .playback
                .as_ref()
                .is_some_and(|p| p.index < self.scene.animations().len());
        if !keep {
            self.playback = playback::Playback::for_scene(&self.scene, None, None)?;
        } else if let Some(p) = self.playback.as_mut() {
            p.repose();
        }
        if new_file {
            self.camera = CameraMode::Scene(None);
            let cam = self
                .scene
                .camera(None)
                .unwrap_or_else(|_| self.scene.auto_camera());
            self.orbit = Orbit::from_camera(&cam, &self.scene);
        }
        self.ui.scene_changed(&self.scene);
        Ok(())
    }

    /// Moves the animation clock on by `dt` seconds and, where the pose changed, poses the
    /// scene and brings the GPU's copy up to date (after the frame in flight, which reads what
    /// `update_pose` writes, has finished).
    fn animate(&mut self, dt: f32) -> crate::Result<()> {
        let Some(p) = self.playback.as_mut() else {
            return Ok(());
        };
        let duration = self
            .scene
            .animations()
            .get(p.index)
            .map_or(0.0, |a| a.duration);
        p.advance(dt, duration);
        if !p.needs_pose() {
            return Ok(());
        }
        let Some(r) = self.running.as_mut() else {
            return Ok(());
        };
        r.renderer.finish()?;
        self.scene.pose(p.index, p.time)?;
        r.renderer.update_pose(&mut r.gpu, &self.scene)?;
        p.posed();
        Ok(())
    }

    /// Ctrl+click: the material under the cursor becomes the panel's choice (to weave, and in
    /// the fabric editor when it is a fabric).
    fn pick(&mut self) {
        let (Some((x, y)), Some(r)) = (self.cursor, self.running.as_ref()) else {
            return;
        };
        let x = x as i64 - self.scene_x0 as i64;
        let picked = if x < 0 || y < 0.0 {
            Ok(None)
        } else {
            r.renderer.read_gbuffer().map(|g| {
                controls::material_at(&g, self.scene_width, x as u32, y as u32, &self.scene)
            })
        };
        self.ui.status = Some(match picked {
            Ok(Some(m)) if m < self.scene.file_materials => {
                self.ui.select(m);
                let name = &self.scene.materials[m].name;
                (format!("picked material {m} '{name}'"), false)
            }
            Ok(Some(m)) => {
                let name = &self.scene.materials[m].name;
                (
                    format!("'{name}' is not a material of the file (the loader or the staging made it): nothing to weave"),
                    false,
                )
            }
            Ok(None) => (
                "no surface under the cursor (or one the transparent pass draws)".into(),
                false,
            ),
            Err(e) => (e.to_string(), true),
        });
    }

    /// Weaves material `material` with `preset` (and a draft file): the request replaces any
    /// earlier one for that material and the scene is loaded again with all of them.
    fn weave(
        &mut self,
        material: usize,
        preset: &str,
        draft: Option<&str>,
    ) -> crate::Result<Option<String>> {
        let (request, warnings) = controls::weave_request(material, preset, draft.map(Path::new))?;
        let before = self.requests.clone();
        controls::replace_request(&mut self.requests, request);
        let variant = self.scene.variant.clone();
        if let Err(e) = self.open(self.source.clone(), variant) {
            self.requests = before;
            return Err(e);
        }
        self.ui.select(material);
        let name = self
            .scene
            .materials
            .get(material)
            .map_or(String::new(), |m| m.name.clone());
        let mut msg = format!("wove material {material} '{name}' with {preset}");
        if let Some(d) = draft {
            msg.push_str(&format!(" and {d}"));
        }
        for w in warnings {
            msg.push_str(&format!("; {w}"));
        }
        Ok(Some(msg))
    }

    fn set_environment(&mut self, choice: &panel::EnvChoice) -> crate::Result<()> {
        let env = match choice {
            panel::EnvChoice::None => None,
            panel::EnvChoice::Studio => Some(crate::spec::studio()),
            panel::EnvChoice::File(path) => Some(Arc::new(Environment::load(Path::new(path))?)),
        };
        self.options.environment = env.map(|e| {
            let mut l = match &self.options.environment {
                Some(old) => EnvLighting {
                    env: e.clone(),
                    ..old.clone()
                },
                None => EnvLighting::new(e.clone()),
            };
            l.env = e;
            l
        });
        Ok(())
    }

    fn apply(&mut self, actions: Vec<panel::Action>) {
        for a in actions {
            let result: crate::Result<Option<String>> = match a {
                panel::Action::Frame => {
                    self.switch_to_orbit();
                    self.orbit = self.orbit.framed(&self.scene);
                    Ok(None)
                }
                panel::Action::Camera(i) => {
                    self.camera = CameraMode::Scene(i);
                    Ok(None)
                }
                panel::Action::Screenshot => {
                    self.shots += 1;
                    self.pending_shot =
                        Some(PathBuf::from(format!("weft-view-{}.png", self.shots)));
                    Ok(None)
                }
                panel::Action::Variant(v) => self
                    .open(self.source.clone(), v.clone())
                    .map(|_| Some(format!("variant {}", v.as_deref().unwrap_or("(default)")))),
                panel::Action::Environment(choice) => self.set_environment(&choice).map(|_| {
                    self.ui.env = choice;
                    None
                }),
                panel::Action::Weave {
                    material,
                    preset,
                    draft,
                } => self.weave(material, &preset, draft.as_deref()),
                panel::Action::SaveFabric => controls::save_woven(&self.source, &self.requests)
                    .map(|(path, applied)| {
                        Some(format!(
                            "saved {} ({} material(s) woven, as weft fabric writes them)",
                            path.display(),
                            applied.len()
                        ))
                    }),
                panel::Action::Fabric(material, params) => {
                    // Kept as the request that writes these parameters, for "save" (an error
                    // here, a mesh without UVs, only means it cannot be saved).
                    let kept =
                        controls::exact_request(&self.scene, &self.requests, material, &params)
                            .map(|r| controls::replace_request(&mut self.requests, r));
                    match controls::set_fabric(&mut self.scene, material, &params)
                        .and_then(|u| kept.map(|_| u))
                    {
                        Ok(update) => match &mut self.running {
                            Some(r) => {
                                controls::apply(&r.renderer, &self.scene, &mut r.gpu, update).map(
                                    |_| match update {
                                        controls::MaterialUpdate::Weave => {
                                            Some("weave rebuilt".to_string())
                                        }
                                        _ => None,
                                    },
                                )
                            }
                            None => Ok(None),
                        },
                        Err(e) => Err(e),
                    }
                }
            };
            match result {
                Ok(Some(msg)) => self.ui.status = Some((msg, false)),
                Ok(None) => {}
                Err(e) => self.ui.status = Some((e.to_string(), true)),
            }
        }
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> crate::Result<()> {
        let start = Instant::now();
        let frame_ms = self
            .last_frame
            .map(|t| (start - t).as_secs_f64() * 1e3)
            .unwrap_or(0.0);
        self.last_frame = Some(start);

        // The panel, and what it changed.
        let (full, mut actions, left) = {
            let r = self.running.as_mut().expect("started");
            let raw = r.egui_state.take_egui_input(&r.window);
            let mut actions = Vec::new();
            let stats = panel::Stats {
                figures: self.figures.last(),
                fps: fps(&self.figures),
            };
            let ui = &mut self.ui;
            let options = &mut self.options;
            let scene = &self.scene;
            let playback = &mut self.playback;
            let camera = match self.camera {
                CameraMode::Scene(i) => Some(i),
                CameraMode::Orbit => None,
            };
            let mut left = 0.0;
            let full = r.egui_ctx.run(raw, |ctx| {
                let showing = panel::Showing {
                    camera,
                    playback: &mut *playback,
                };
                left = panel::show(ctx, ui, options, scene, showing, &stats, &mut actions)
            });
            r.egui_state
                .handle_platform_output(&r.window, full.platform_output.clone());
            (full, actions, left)
        };
        actions.append(&mut self.ui.take_key_actions());
        self.apply(actions);
        self.animate((frame_ms / 1e3) as f32)?;
        let r = self.running.as_mut().expect("started");
        let primitives = r.egui_ctx.tessellate(full.shapes, full.pixels_per_point);
        let ui_ms = start.elapsed().as_secs_f64() * 1e3;

        // The scene is rendered in the part of the window right of the panel.
        let (w, h) = r.presenter.extent();
        let x0 = ((left * full.pixels_per_point).round().max(0.0) as u32).min(w.saturating_sub(1));
        let options = self.frame_options(w - x0, h)?;
        (self.scene_x0, self.scene_width) = (x0, w - x0);
        let r = self.running.as_mut().expect("started");
        let t = Instant::now();
        // Not waited for: the next frame waits for it once recorded. Its timings carry the
        // previous frame's GPU times (one frame late).
        let (frame, ldr) = r
            .renderer
            .render_frame_overlapped(&self.scene, &r.gpu, &options)?;
        let render_ms = t.elapsed().as_secs_f64() * 1e3;

        let after = self.screenshot.as_ref().map(|s| s.1);
        let auto_shot = after.is_some_and(|n| self.presented + 1 >= n);
        let shot = auto_shot || self.pending_shot.is_some();
        let no_shapes: &[egui::ClippedPrimitive] = &[];
        let panel = PanelDraw {
            primitives: if self.ui.show { &primitives } else { no_shapes },
            textures: &full.textures_delta,
            pixels_per_point: full.pixels_per_point,
        };
        let t = Instant::now();
        let presented = r.presenter.present(ldr, x0, Some(panel), shot)?;
        let present_ms = t.elapsed().as_secs_f64() * 1e3;
        if !presented.presented {
            let size = r.window.inner_size();
            if size.width > 0 && size.height > 0 {
                r.presenter.resize(size.width, size.height)?;
            }
        }
        if let Some((sw, sh, pixels)) = presented.screenshot {
            let path = if auto_shot {
                self.screenshot.as_ref().map(|s| s.0.clone())
            } else {
                self.pending_shot.take()
            };
            if let Some(path) = path {
                crate::render::write_png(&path, sw, sh, &pixels)?;
                self.ui.status = Some((format!("wrote {}", path.display()), false));
                if auto_shot {
                    eprintln!(
                        "weft view: wrote {} ({sw}x{sh}; the scene {}x{sh} from x {x0})",
                        path.display(),
                        w - x0
                    );
                    event_loop.exit();
                }
            }
        }
        self.presented += 1;
        self.figures.push(FrameFigures {
            frame_ms,
            ui_ms,
            render_ms,
            passes: frame.timings,
            copy_ms: presented.copy_ms,
            slot_wait_ms: presented.slot_wait_ms,
            present_ms,
        });
        if self.figures.len() > 240 && self.bench_frames.is_none() {
            self.figures.drain(..120);
        }
        if let Some(n) = self.bench_frames {
            if self.presented >= BENCH_WARMUP + n {
                let timed = &self.figures[self.figures.len() - n as usize..];
                self.report = Some(bench_report(timed, w - x0, h));
                event_loop.exit();
            }
        }
        Ok(())
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, key: &Key) {
        match key {
            Key::Named(NamedKey::Tab) => self.ui.show = !self.ui.show,
            Key::Named(NamedKey::F12) => self.apply(vec![panel::Action::Screenshot]),
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Named(NamedKey::Space) => {
                if let Some(p) = self.playback.as_mut() {
                    p.playing = !p.playing;
                }
            }
            Key::Character(c) => match c.as_str() {
                "f" | "F" => self.apply(vec![panel::Action::Frame]),
                "c" | "C" => {
                    let n = self.scene.cameras.len();
                    let next = match self.camera {
                        CameraMode::Scene(Some(i)) if i + 1 < n => CameraMode::Scene(Some(i + 1)),
                        CameraMode::Scene(Some(_)) => CameraMode::Orbit,
                        CameraMode::Scene(None) if n > 1 => CameraMode::Scene(Some(1)),
                        CameraMode::Scene(None) => CameraMode::Orbit,
                        CameraMode::Orbit => CameraMode::Scene(if n > 0 { Some(0) } else { None }),
                    };
                    if next == CameraMode::Orbit {
                        self.switch_to_orbit();
                    }
                    self.camera = next;
                }
                "p" | "P" => self.apply(vec![panel::Action::Screenshot]),
                _ => {}
            },
            _ => {}
        }
    }
}

fn fps(figures: &[FrameFigures]) -> f64 {
    let recent: Vec<f64> = figures
        .iter()
        .rev()
        .take(30)
        .map(|f| f.frame_ms)
        .filter(|&ms| ms > 0.0)
        .collect();
    if recent.is_empty() {
        0.0
    } else {
        1e3 * recent.len() as f64 / recent.iter().sum::<f64>()
    }
}

fn bench_report(timed: &[FrameFigures], width: u32, height: u32) -> BenchReport {
    let m = |f: &dyn Fn(&FrameFigures) -> f64| median(timed.iter().map(f).collect());
    let mut names: Vec<&'static str> = Vec::new();
    for f in timed {
        for p in &f.passes {
            if p.gpu_ms.is_some() && !names.contains(&p.name) {
                names.push(p.name);
            }
        }
    }
    let passes_gpu_ms = names
        .iter()
        .map(|n| {
            let v = timed
                .iter()
                .filter_map(|f| {
                    f.passes
                        .iter()
                        .find(|p| p.name == *n)
                        .and_then(|p| p.gpu_ms)
                })
                .collect();
            (*n, median(v))
        })
        .collect();
    let wall = |f: &FrameFigures| f.passes.iter().filter_map(|p| p.wall_ms).sum::<f64>();
    BenchReport {
        width,
        height,
        frames: timed.len(),
        frame_ms: m(&|f| f.frame_ms),
        ui_ms: m(&|f| f.ui_ms),
        render_ms: m(&|f| f.render_ms),
        passes_wall_ms: m(&wall),
        frame_wait_ms: m(&|f| {
            f.passes
                .iter()
                .filter(|p| p.name == "wait for the previous frame")
                .filter_map(|p| p.wall_ms)
                .sum()
        }),
        passes_gpu_ms,
        copy_ms: m(&|f| f.copy_ms),
        slot_wait_ms: m(&|f| f.slot_wait_ms),
        present_ms: m(&|f| f.present_ms),
        cpu_wait_fraction: m(&|f| {
            if f.frame_ms > 0.0 {
                (wall(f) + f.copy_ms + f.slot_wait_ms) / f.frame_ms
            } else {
                0.0
            }
        }),
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_none() {
            if let Err(e) = self.start(event_loop) {
                self.fail(event_loop, e);
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else {
            return;
        };
        let response = r.egui_state.on_window_event(&r.window, &event);
        let egui_pointer = r.egui_ctx.wants_pointer_input() || r.egui_ctx.is_pointer_over_area();
        let egui_keys = r.egui_ctx.wants_keyboard_input();
        if response.repaint {
            self.dirty = true;
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if size.width > 0 && size.height > 0 {
                    if let Err(e) = r.presenter.resize(size.width, size.height) {
                        self.fail(event_loop, e);
                    }
                }
                self.dirty = true;
            }
            WindowEvent::RedrawRequested => {
                if r.window.inner_size().width == 0 {
                    return;
                }
                self.dirty = false;
                if let Err(e) = self.redraw(event_loop) {
                    self.fail(event_loop, e);
                }
            }
            WindowEvent::DroppedFile(path) => {
                match self.open(SceneSource::File(path.clone()), None) {
                    Ok(()) => self.ui.status = Some((format!("opened {}", path.display()), false)),
                    Err(e) => self.ui.status = Some((format!("{}: {e}", path.display()), true)),
                }
                self.dirty = true;
            }
            WindowEvent::ModifiersChanged(m) => {
                self.shift = m.state().shift_key();
                self.ctrl = m.state().control_key();
            }
            WindowEvent::MouseInput { state, button, .. } if !response.consumed => {
                let down = state == ElementState::Pressed;
                if down && egui_pointer {
                    return;
                }
                if down && self.ctrl && button == MouseButton::Left {
                    self.pick();
                    self.dirty = true;
                    return;
                }
                match button {
                    MouseButton::Left if self.shift => self.panning = down,
                    MouseButton::Left => self.rotating = down,
                    MouseButton::Right | MouseButton::Middle => self.panning = down,
                    _ => {}
                }
                if !down {
                    self.rotating = false;
                    self.panning = false;
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (x, y) = (position.x, position.y);
                if let Some((px, py)) = self.cursor {
                    let (dx, dy) = ((x - px) as f32, (y - py) as f32);
                    let h = r.window.inner_size().height as f32;
                    if self.rotating || self.panning {
                        self.switch_to_orbit();
                        if self.rotating {
                            self.orbit.rotate(dx, dy, h);
                        } else {
                            self.orbit.pan(dx, dy, h);
                        }
                        self.dirty = true;
                    }
                }
                self.cursor = Some((x, y));
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } if !egui_pointer => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.switch_to_orbit();
                self.orbit.zoom(steps);
                self.dirty = true;
            }
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed && !egui_keys && !response.consumed =>
            {
                self.key(event_loop, &event.logical_key);
                self.dirty = true;
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(r) = self.running.as_ref() else {
            return;
        };
        // Continuous frames only while something needs them: a bench, a pending screenshot, the
        // first frames, or an input / panel change (egui asks for a repaint after animations).
        let busy = self.bench_frames.is_some()
            || self.playback.as_ref().is_some_and(|p| p.playing)
            || self.screenshot.is_some()
            || self.pending_shot.is_some()
            || self.presented < FRAMES_IN_FLIGHT as u32 + 1;
        let egui_wants = r.egui_ctx.has_requested_repaint();
        if self.dirty || busy || egui_wants {
            r.window.request_redraw();
        }
        event_loop.set_control_flow(ControlFlow::Wait);
    }
}
