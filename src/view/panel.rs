//! The panel (egui): render options edited in place, everything else returned as [`Action`]s
//! that the viewer applies through the same functions the tests call (`controls`).

use crate::fabric::{FabricParams, WeavePattern};
use crate::render::{
    Accuracy, DebugView, Footprint, Occlusion, RenderOptions, Shading, WeavePrecision,
};
use crate::scene::Scene;

use super::FrameFigures;

/// An edit the viewer applies after the panel is laid out.
#[derive(Clone, Debug)]
pub enum Action {
    Frame,
    Camera(Option<usize>),
    Screenshot,
    Variant(Option<String>),
    Environment(EnvChoice),
    /// New fabric parameters for a material.
    Fabric(usize, FabricParams),
    /// Weave a material with a preset (by name) and optionally a draft file: what `weft fabric
    /// --material M --preset P [--draft F]` does, the scene reloaded with it.
    Weave {
        material: usize,
        preset: String,
        draft: Option<String>,
    },
    /// Write the file `weft fabric` would write for every material woven or changed here.
    SaveFabric,
}

#[derive(Clone, Debug, PartialEq)]
pub enum EnvChoice {
    None,
    Studio,
    File(String),
}

/// The panel's own state (what is not in the render options or the scene).
pub struct UiState {
    pub show: bool,
    /// The last message: text, and whether it is an error.
    pub status: Option<(String, bool)>,
    material: Option<usize>,
    /// The panel's "weave a material": which, with which preset and draft.
    weave_material: usize,
    weave_preset: usize,
    draft_path: String,
    pub env: EnvChoice,
    env_path: String,
    samples: u32,
    keys: Vec<Action>,
}

pub struct Stats<'a> {
    pub figures: Option<&'a FrameFigures>,
    pub fps: f64,
}

impl UiState {
    /// `env_file`: the environment's file when it is not the built-in studio.
    pub fn new(
        show: bool,
        scene: &Scene,
        options: &RenderOptions,
        env_file: Option<String>,
    ) -> UiState {
        let env = match (&options.environment, env_file) {
            (None, _) => EnvChoice::None,
            (Some(_), Some(f)) => EnvChoice::File(f),
            (Some(_), None) => EnvChoice::Studio,
        };
        let mut s = UiState {
            show,
            status: None,
            material: None,
            weave_material: 0,
            weave_preset: 0,
            draft_path: String::new(),
            env,
            env_path: String::new(),
            samples: options.accuracy.samples().max(4),
            keys: Vec::new(),
        };
        s.scene_changed(scene);
        s
    }

    pub fn scene_changed(&mut self, scene: &Scene) {
        self.material = super::controls::fabric_materials(scene)
            .first()
            .map(|m| m.0);
    }

    /// Selects material `material` in the fabric editor (after it was woven) and as the one
    /// to weave (a ctrl+click on it).
    pub fn select(&mut self, material: usize) {
        self.material = Some(material);
        self.weave_material = material;
    }

    pub fn take_key_actions(&mut self) -> Vec<Action> {
        std::mem::take(&mut self.keys)
    }
}

fn combo<T: PartialEq + Copy>(
    ui: &mut egui::Ui,
    label: &str,
    value: &mut T,
    choices: &[(T, String)],
) -> bool {
    let before = *value;
    let current = choices
        .iter()
        .find(|c| c.0 == *value)
        .map(|c| c.1.clone())
        .unwrap_or_default();
    egui::ComboBox::from_label(label)
        .selected_text(current)
        .show_ui(ui, |ui| {
            for (v, name) in choices {
                ui.selectable_value(value, *v, name.as_str());
            }
        });
    *value != before
}

/// What the window shows of the scene besides its options: the camera (Some(the scene camera
/// shown), or None when orbiting) and the animation clock.
pub struct Showing<'a> {
    pub camera: Option<Option<usize>>,
    pub playback: &'a mut Option<super::playback::Playback>,
}

/// Lays out the panel and returns the left edge, in points, of the area it leaves for the scene
/// (0 when hidden).
pub fn show(
    ctx: &egui::Context,
    state: &mut UiState,
    options: &mut RenderOptions,
    scene: &Scene,
    showing: Showing,
    stats: &Stats,
    actions: &mut Vec<Action>,
) -> f32 {
    let Showing { camera, playback } = showing;
    if !state.show {
        return 0.0;
    }
    egui::SidePanel::left("weft-panel")
        .resizable(false)
        .default_width(270.0)
        .show(ctx, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                ui.heading("weft view");
                ui.label(&scene.source);
                timings(ui, stats);
                ui.separator();
                render_controls(ui, state, options);
                ui.separator();
                environment(ui, state, options, actions);
                ui.separator();
                camera_controls(ui, scene, camera, actions);
                if let Some(p) = playback.as_mut() {
                    animation(ui, scene, p);
                }
                if !scene.variants.is_empty() {
                    let mut v = scene.variant.clone();
                    let before = v.clone();
                    egui::ComboBox::from_label("variant")
                        .selected_text(v.clone().unwrap_or_else(|| "(default)".into()))
                        .show_ui(ui, |ui| {
                            ui.selectable_value(&mut v, None, "(default)");
                            for name in &scene.variants {
                                ui.selectable_value(&mut v, Some(name.clone()), name);
                            }
                        });
                    if v != before {
                        actions.push(Action::Variant(v));
                    }
                }
                ui.separator();
                fabric(ui, state, scene, actions);
                ui.separator();
                weave(ui, state, scene, actions);
                ui.separator();
                // Last, so that a message appearing does not move the controls under the cursor.
                if let Some((msg, error)) = &state.status {
                    let color = if *error {
                        egui::Color32::from_rgb(255, 110, 110)
                    } else {
                        egui::Color32::from_rgb(150, 220, 150)
                    };
                    ui.colored_label(color, msg);
                    ui.separator();
                }
                ui.small("drag: orbit · shift/right drag: pan · wheel: zoom · F: frame · C: next camera · Tab: panel · P/F12: screenshot · ctrl+click: pick a material · drop a .gltf/.glb to open");
            });
        });
    ctx.available_rect().left()
}

fn timings(ui: &mut egui::Ui, stats: &Stats) {
    ui.label(format!("{:.1} fps", stats.fps));
    if let Some(f) = stats.figures {
        egui::Grid::new("timings").striped(true).show(ui, |ui| {
            ui.label("pass");
            ui.label("GPU ms");
            ui.end_row();
            // The GPU times are the previous frame's (the renderer reads a frame's timestamps
            // when the next frame waits for it: Renderer::render_frame_overlapped), so the panel
            // shows them one frame late.
            for p in &f.passes {
                if let Some(ms) = p.gpu_ms {
                    ui.label(p.name);
                    ui.label(format!("{ms:.2}"));
                    ui.end_row();
                }
            }
            ui.label("frame");
            ui.label(format!("{:.1}", f.frame_ms));
            ui.end_row();
        });
    }
}

fn render_controls(ui: &mut egui::Ui, state: &mut UiState, o: &mut RenderOptions) {
    #[derive(Clone, Copy, PartialEq)]
    enum A {
        Nearest,
        Filtered,
        Mixture,
        Super,
    }
    let mut a = match o.accuracy {
        Accuracy::Nearest => A::Nearest,
        Accuracy::FilteredParams => A::Filtered,
        Accuracy::Mixture => A::Mixture,
        Accuracy::Supersampled(_) => A::Super,
    };
    combo(
        ui,
        "accuracy",
        &mut a,
        &[
            (A::Nearest, "nearest".into()),
            (A::Filtered, "filtered-params".into()),
            (A::Mixture, "mixture".into()),
            (A::Super, "supersampled:N".into()),
        ],
    );
    if a == A::Super {
        ui.add(egui::Slider::new(&mut state.samples, 1..=Accuracy::MAX_SAMPLES).text("N"));
    }
    o.accuracy = match a {
        A::Nearest => Accuracy::Nearest,
        A::Filtered => Accuracy::FilteredParams,
        A::Mixture => Accuracy::Mixture,
        A::Super => Accuracy::Supersampled(state.samples),
    };
    combo(
        ui,
        "weave precision",
        &mut o.weave_precision,
        &WeavePrecision::ALL.map(|p| (p, p.name().to_string())),
    );
    combo(
        ui,
        "footprint",
        &mut o.footprint,
        &[
            Footprint::Box,
            Footprint::Parallelogram(1),
            Footprint::Parallelogram(2),
            Footprint::Parallelogram(3),
            Footprint::Parallelogram(4),
        ]
        .map(|f| (f, f.name())),
    );
    combo(
        ui,
        "debug view",
        &mut o.debug_view,
        &DebugView::ALL.map(|d| (d, d.name().to_string())),
    );
    combo(
        ui,
        "shading",
        &mut o.shading,
        &Shading::ALL.map(|s| (s, s.label().to_string())),
    );
    ui.add(egui::Slider::new(&mut o.exposure, -8.0..=8.0).text("exposure (EV)"));
}

fn environment(
    ui: &mut egui::Ui,
    state: &mut UiState,
    o: &mut RenderOptions,
    actions: &mut Vec<Action>,
) {
    // Edited as a copy: the viewer sets `state.env` once the environment has loaded.
    let mut choice = state.env.clone();
    let label = |c: &EnvChoice| match c {
        EnvChoice::None => "none".to_string(),
        EnvChoice::Studio => "studio".to_string(),
        EnvChoice::File(p) => p.clone(),
    };
    egui::ComboBox::from_label("environment")
        .selected_text(label(&state.env))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut choice, EnvChoice::Studio, "studio");
            ui.selectable_value(&mut choice, EnvChoice::None, "none");
        });
    ui.horizontal(|ui| {
        ui.add(egui::TextEdit::singleline(&mut state.env_path).hint_text(".hdr / .exr path"));
        if ui.button("load").clicked() && !state.env_path.trim().is_empty() {
            choice = EnvChoice::File(state.env_path.trim().to_string());
        }
    });
    if choice != state.env {
        actions.push(Action::Environment(choice));
    }
    if let Some(e) = o.environment.as_mut() {
        ui.add(egui::Slider::new(&mut e.rotation, 0.0..=360.0).text("rotation (°)"));
        ui.add(egui::Slider::new(&mut e.intensity, 0.0..=4.0).text("intensity"));
        // The occlusion pass (`--occlusion`): on with GTAO's default radius, or off.
        let mut on = o.occlusion != Occlusion::None;
        if ui.checkbox(&mut on, "occlusion (GTAO)").changed() {
            o.occlusion = if on {
                Occlusion::DEFAULT
            } else {
                Occlusion::None
            };
        }
    }
}

/// The animation playing: which, play / pause (Space), and the time (dragging it seeks).
fn animation(ui: &mut egui::Ui, scene: &Scene, p: &mut super::playback::Playback) {
    let list = scene.animations();
    let name = |i: usize| {
        list.get(i)
            .map(|a| format!("{i}: {}", a.name))
            .unwrap_or_default()
    };
    ui.horizontal(|ui| {
        let before = p.index;
        egui::ComboBox::from_label("animation")
            .selected_text(name(p.index))
            .show_ui(ui, |ui| {
                for i in 0..list.len() {
                    ui.selectable_value(&mut p.index, i, name(i));
                }
            });
        if p.index != before {
            p.time = 0.0;
        }
    });
    let duration = list.get(p.index).map_or(0.0, |a| a.duration);
    ui.horizontal(|ui| {
        ui.checkbox(&mut p.playing, "play (Space)");
        ui.add(
            egui::Slider::new(&mut p.time, 0.0..=duration.max(0.0))
                .suffix(" s")
                .max_decimals(2),
        );
    });
}

fn camera_controls(
    ui: &mut egui::Ui,
    scene: &Scene,
    camera: Option<Option<usize>>,
    actions: &mut Vec<Action>,
) {
    let current = match camera {
        Some(None) => "scene (first / automatic)".to_string(),
        Some(Some(i)) => scene
            .cameras
            .get(i)
            .map(|c| format!("{i}: {}", c.name))
            .unwrap_or_default(),
        None => "orbit".to_string(),
    };
    ui.horizontal(|ui| {
        egui::ComboBox::from_label("camera")
            .selected_text(current)
            .show_ui(ui, |ui| {
                if ui
                    .selectable_label(camera == Some(None), "scene (first / automatic)")
                    .clicked()
                {
                    actions.push(Action::Camera(None));
                }
                for (i, c) in scene.cameras.iter().enumerate() {
                    let name = format!("{i}: {}", c.name);
                    if ui.selectable_label(camera == Some(Some(i)), name).clicked() {
                        actions.push(Action::Camera(Some(i)));
                    }
                }
            });
        if ui.button("frame").clicked() {
            actions.push(Action::Frame);
        }
        if ui.button("screenshot").clicked() {
            actions.push(Action::Screenshot);
        }
    });
}

/// "Weave a material": any material of the file, a preset, a draft, and saving the result.
fn weave(ui: &mut egui::Ui, state: &mut UiState, scene: &Scene, actions: &mut Vec<Action>) {
    ui.label("weave a material (as weft fabric)");
    let materials = super::controls::file_materials(scene);
    if materials.is_empty() {
        ui.label("the file has no materials");
        return;
    }
    if !materials.iter().any(|(i, _)| *i == state.weave_material) {
        state.weave_material = materials[0].0;
    }
    combo(ui, "material", &mut state.weave_material, &materials);
    let presets: Vec<(usize, String)> = crate::fabric::presets::PRESETS
        .iter()
        .enumerate()
        .map(|(i, p)| (i, p.name.to_string()))
        .chain(std::iter::once((
            crate::fabric::presets::PRESETS.len(),
            "from-sheen".to_string(),
        )))
        .collect();
    combo(ui, "preset", &mut state.weave_preset, &presets);
    ui.horizontal(|ui| {
        ui.label("draft (.wif)");
        ui.text_edit_singleline(&mut state.draft_path);
    });
    ui.horizontal(|ui| {
        if ui.button("weave").clicked() {
            let preset = presets
                .iter()
                .find(|(i, _)| *i == state.weave_preset)
                .map_or("cotton-plain".to_string(), |(_, n)| n.clone());
            let draft = state.draft_path.trim();
            actions.push(Action::Weave {
                material: state.weave_material,
                preset,
                draft: (!draft.is_empty()).then(|| draft.to_string()),
            });
            state.material = Some(state.weave_material);
        }
        if ui.button("save woven file").clicked() {
            actions.push(Action::SaveFabric);
        }
    });
}

fn fabric(ui: &mut egui::Ui, state: &mut UiState, scene: &Scene, actions: &mut Vec<Action>) {
    let materials = super::controls::fabric_materials(scene);
    if materials.is_empty() {
        ui.label("no fabric material in this scene: weave one below");
        return;
    }
    // The selection may be a material that is not (yet) a fabric (a ctrl+click picks any).
    let mut selected = state
        .material
        .filter(|m| materials.iter().any(|(i, _)| i == m))
        .unwrap_or(materials[0].0);
    combo(
        ui,
        "fabric material",
        &mut selected,
        &materials
            .iter()
            .map(|(i, n)| (*i, n.clone()))
            .collect::<Vec<_>>(),
    );
    state.material = Some(selected);
    let Some(old) = scene.materials.get(selected).and_then(|m| m.fabric.clone()) else {
        return;
    };
    let mut p = old.clone();
    let mut pattern = WeavePattern::NAMES
        .iter()
        .position(|n| WeavePattern::by_name(n) == Some(p.pattern))
        .unwrap_or(usize::MAX);
    let names: Vec<(usize, String)> = WeavePattern::NAMES
        .iter()
        .enumerate()
        .map(|(i, n)| (i, n.to_string()))
        .chain((pattern == usize::MAX).then(|| (usize::MAX, p.pattern.name())))
        .collect();
    if combo(ui, "pattern", &mut pattern, &names) {
        if let Some(pat) = WeavePattern::NAMES
            .get(pattern)
            .and_then(|n| WeavePattern::by_name(n))
        {
            p.pattern = pat;
        }
    }
    ui.add(
        egui::Slider::new(&mut p.repeat, 1e-4..=1.0)
            .logarithmic(true)
            .text("pitch s_p (uv)"),
    );
    let max_gap = p.repeat / 2.0;
    ui.add(egui::Slider::new(&mut p.gap, 0.0..=max_gap).text("gap s_g (uv)"));
    ui.add(
        egui::Slider::new(&mut p.e_along, 0.0..=2000.0)
            .logarithmic(true)
            .text("exponent along"),
    );
    ui.add(
        egui::Slider::new(&mut p.e_across, 0.0..=2000.0)
            .logarithmic(true)
            .text("exponent across"),
    );
    ui.add(egui::Slider::new(&mut p.shadow_width, 0.0..=1.0).text("shadow width"));
    ui.add(egui::Slider::new(&mut p.shadow_strength, 0.0..=1.0).text("shadow strength"));
    ui.add(egui::Slider::new(&mut p.rs, 0.0..=1.0).text("specular rs"));
    ui.horizontal(|ui| {
        ui.label("warp (linear)");
        ui.color_edit_button_rgb(&mut p.rd_warp);
        ui.label("weft");
        ui.color_edit_button_rgb(&mut p.rd_weft);
    });
    // A single sheet: light through the gaps and, by τ, through the threads.
    let mut sheet = p.transmission.is_some();
    if ui
        .checkbox(&mut sheet, "single sheet (light through the weave)")
        .changed()
    {
        p.transmission = sheet.then_some(0.3);
    }
    if let Some(t) = p.transmission.as_mut() {
        ui.add(egui::Slider::new(t, 0.0..=1.0).text("thread transmittance"));
    }
    if p != old {
        actions.push(Action::Fabric(selected, p));
    }
}
