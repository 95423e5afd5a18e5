//! The frame loop of `weft render --frames-range`: the scene is uploaded once, and per frame only
//! what the frame's time changes is set and re-uploaded ([`pose_frame`]: the animation's pose,
//! the camera), then the frame is rendered and written
//! atomically (a killed task leaves either a complete frame or none under the frame's name).

use std::path::PathBuf;
use std::time::Instant;

use glam::{Mat4, Vec3};

use super::{FrameRange, Job, OutputPattern, Split, Sweep, TaskSpec};
use crate::render::{GpuScene, RenderOptions, Renderer};
use crate::scene::{Camera, Scene};
use crate::Error;

/// How the camera moves over a sequence. Both parts may be on at once: the dolly moves the eye
/// along its view direction, then the orbit turns the result about the vertical axis through
/// `center`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraMotion {
    /// Degrees per second about the vertical (+Y) axis through `center`; positive turns the
    /// camera counter-clockwise seen from above.
    pub orbit_degrees_per_second: f32,
    /// World units per second along the camera's view direction (positive: towards what it
    /// looks at).
    pub dolly_per_second: f32,
    /// The orbit's centre: the centre of the scene's bounds (see [`CameraMotion::centered`]).
    pub center: Vec3,
}

impl CameraMotion {
    /// The motion with its centre at the centre of `scene`'s bounds (the origin for an empty
    /// scene). Refuses non-finite speeds.
    pub fn centered(scene: &Scene, orbit: f32, dolly: f32) -> crate::Result<CameraMotion> {
        CameraMotion::check_speeds(orbit, dolly)?;
        let center = scene
            .bounds()
            .map(|b| (b.min + b.max) * 0.5)
            .filter(|c| c.is_finite())
            .unwrap_or(Vec3::ZERO);
        Ok(CameraMotion {
            orbit_degrees_per_second: orbit,
            dolly_per_second: dolly,
            center,
        })
    }

    /// Refuses non-finite or absurd speeds (before any scene is loaded).
    pub fn check_speeds(orbit: f32, dolly: f32) -> crate::Result<()> {
        if !orbit.is_finite() || orbit.abs() > 1e6 {
            return Err(Error::input(format!(
                "--orbit {orbit} is out of range: give degrees per second, a finite number"
            )));
        }
        if !dolly.is_finite() || dolly.abs() > 1e9 {
            return Err(Error::input(format!(
                "--dolly {dolly} is out of range: give world units per second, a finite number"
            )));
        }
        Ok(())
    }

    pub fn is_still(&self) -> bool {
        self.orbit_degrees_per_second == 0.0 && self.dolly_per_second == 0.0
    }

    /// `base` moved to time `t` seconds.
    pub fn camera_at(&self, base: &Camera, t: f32) -> crate::Result<Camera> {
        if self.is_still() {
            return Ok(base.clone());
        }
        let world_from_camera = base.view.inverse();
        let forward = world_from_camera.transform_vector3(Vec3::NEG_Z).normalize();
        let dolly = self.dolly_per_second * t;
        let moved = Mat4::from_translation(forward * dolly) * world_from_camera;
        let angle = (self.orbit_degrees_per_second * t).to_radians();
        let turned = Mat4::from_translation(self.center)
            * Mat4::from_rotation_y(angle)
            * Mat4::from_translation(-self.center)
            * moved;
        let view = turned.inverse();
        if !view.is_finite() {
            return Err(Error::input(format!(
                "the camera at t = {t} s left the range of 32-bit floating point: choose a slower --dolly"
            )));
        }
        let mut camera = base.clone();
        camera.view = view;
        // A dolly away from the scene must not push it past the far plane.
        camera.zfar = camera.zfar.map(|f| f + dolly.abs());
        Ok(camera)
    }
}

/// Poses the scene at time `t` (seconds) for the frame about to be rendered, and returns the
/// frame's options. With `animation`, the glTF animation is sampled at `t` ([`Scene::pose`]) and
/// only what it changed goes to the GPU ([`Renderer::update_pose`]: world matrices, lights,
/// joint matrices and morph weights, and material records that KHR_animation_pointer drives;
/// meshes and textures stay as uploaded). Then the
/// camera: the scene's own (an animated camera node is already at `t`) or `--eye/--target`,
/// moved by `motion`.
pub fn pose_frame(
    scene: &mut Scene,
    renderer: &Renderer,
    gpu: &mut GpuScene,
    base: &RenderOptions,
    motion: &CameraMotion,
    animation: Option<usize>,
    t: f32,
) -> crate::Result<RenderOptions> {
    if let Some(index) = animation {
        scene.pose(index, t)?;
        renderer.update_pose(gpu, scene)?;
    }
    let camera = match &base.camera_override {
        Some(c) => c.clone(),
        None => {
            scene.camera_for_aspect(base.camera, base.width as f32 / base.height.max(1) as f32)?
        }
    };
    let mut options = base.clone();
    if !motion.is_still() || animation.is_some() {
        options.camera_override = Some(motion.camera_at(&camera, t)?);
    }
    Ok(options)
}

/// Everything a sequence render is asked for.
#[derive(Clone, Debug)]
pub struct SequenceSpec {
    pub range: FrameRange,
    pub fps: f32,
    pub motion: CameraMotion,
    /// The glTF animation played (index into [`Scene::animations`]), None for none.
    pub animation: Option<usize>,
    pub sweep: Option<Sweep>,
    pub task: TaskSpec,
    pub split: Split,
    pub output: OutputPattern,
    pub exr: Option<OutputPattern>,
    /// Skip jobs whose outputs are all there (complete images of the frame's size).
    pub resume: bool,
}

impl SequenceSpec {
    /// Checks what can be checked without a device: fps, the output patterns against the range
    /// and sweep.
    pub fn check(&self) -> crate::Result<()> {
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= 1e4) {
            return Err(Error::input(format!(
                "--fps {} is out of range: give frames per second, above 0 and at most 10000",
                self.fps
            )));
        }
        self.output.check(self.range, self.sweep.as_ref())?;
        if let Some(exr) = &self.exr {
            exr.check(self.range, self.sweep.as_ref())?;
        }
        Ok(())
    }

    /// Every file this task's jobs write (the PNG, and the EXR with `--exr`), named for
    /// messages: what `render::check_outputs` checks before any rendering (against the inputs
    /// and each other: directories that exist, names the file system takes, no two jobs or
    /// patterns on one file).
    pub fn outputs(&self) -> Vec<crate::render::OutputPath> {
        let mut out = Vec::new();
        for job in self.my_jobs() {
            let of = match self.sweep_value(&job) {
                Some(v) => format!(
                    " of frame {} at {} {v}",
                    job.frame,
                    self.sweep.as_ref().map_or("", |s| s.key.name())
                ),
                None => format!(" of frame {}", job.frame),
            };
            out.push(crate::render::OutputPath::new(
                format!("-o{of}"),
                self.png_path(&job),
            ));
            if let Some(path) = self.exr_path(&job) {
                out.push(crate::render::OutputPath::new(format!("--exr{of}"), path));
            }
        }
        out
    }

    /// Whether every output of `job` is already there, complete and `width` x `height` (what
    /// `--resume` skips): the PNG, and the EXR when one is asked for. A job with a missing or
    /// truncated EXR is rendered again, even if its PNG is whole.
    pub fn job_done(&self, job: &Job, width: u32, height: u32) -> bool {
        frame_done(&self.png_path(job), width, height)
            && self
                .exr_path(job)
                .is_none_or(|exr| frame_done(&exr, width, height))
    }

    fn exr_path(&self, job: &Job) -> Option<PathBuf> {
        Some(self.exr.as_ref()?.path(job.frame, self.sweep_value(job)))
    }

    /// The jobs of this task, in the order they are rendered.
    pub fn my_jobs(&self) -> Vec<Job> {
        let all = super::jobs(self.range, self.sweep.as_ref());
        self.task
            .share(all.len() as u64, self.split)
            .into_iter()
            .map(|i| all[i as usize])
            .collect()
    }

    /// The seconds at which `frame` is posed: frame / fps.
    pub fn time(&self, frame: u32) -> f32 {
        (f64::from(frame) / f64::from(self.fps)) as f32
    }

    fn sweep_value(&self, job: &Job) -> Option<&str> {
        Some(self.sweep.as_ref()?.values[job.sweep?].as_str())
    }

    pub fn png_path(&self, job: &Job) -> PathBuf {
        self.output.path(job.frame, self.sweep_value(job))
    }
}

/// What happened to one job.
#[derive(Clone, Debug)]
pub struct JobReport {
    pub job: Job,
    pub time: f32,
    pub output: PathBuf,
    /// Already there (--resume): not rendered.
    pub skipped: bool,
    /// Per pass: (name, GPU ms when the device has timestamps, wall ms).
    pub passes: Vec<(&'static str, Option<f64>, Option<f64>)>,
    /// Posing (the animation sampled and its pose sent to the GPU, the camera moved).
    pub pose_ms: f64,
    /// Posing, rendering and reading back.
    pub render_ms: f64,
    /// Encoding and writing the PNG (and EXR).
    pub write_ms: f64,
    /// How the linear image became the PNG's pixels: tone curve and exposure
    /// (`render::display_note`, also in the PNG's text).
    pub display: String,
}

impl JobReport {
    /// The `--metrics-json` line.
    pub fn json(&self, spec: &SequenceSpec) -> String {
        let passes: serde_json::Map<String, serde_json::Value> = self
            .passes
            .iter()
            .map(|(name, gpu, wall)| {
                (
                    name.to_string(),
                    serde_json::json!({"gpu_ms": gpu, "wall_ms": wall}),
                )
            })
            .collect();
        serde_json::json!({
            "frame": self.job.frame,
            "time": self.time,
            "sweep": spec.sweep.as_ref().zip(self.job.sweep).map(|(s, i)| serde_json::json!({
                "key": s.key.name(), "value": s.values[i],
            })),
            "task": spec.task.index,
            "tasks": spec.task.count,
            "output": self.output.display().to_string(),
            "display": self.display,
            "status": if self.skipped { "skipped" } else { "rendered" },
            "passes": passes,
            "pose_ms": self.pose_ms,
            "render_ms": self.render_ms,
            "write_ms": self.write_ms,
            "wall_ms": self.render_ms + self.write_ms,
        })
        .to_string()
    }
}

/// Whether `path` already holds a complete `width` x `height` image (what `--resume` skips). A
/// file of another size, or one that does not decode, is rendered again.
pub fn frame_done(path: &std::path::Path, width: u32, height: u32) -> bool {
    match image::ImageReader::open(path).and_then(|r| r.with_guessed_format()) {
        Ok(reader) => match reader.decode() {
            Ok(img) => img.width() == width && img.height() == height,
            Err(_) => false,
        },
        Err(_) => false,
    }
}

/// Renders this task's jobs of `spec`. `report` is called after each job (done or skipped).
pub fn run(
    renderer: &mut Renderer,
    scene: &mut Scene,
    gpu: &mut GpuScene,
    base: &RenderOptions,
    spec: &SequenceSpec,
    mut report: impl FnMut(&JobReport),
) -> crate::Result<Vec<JobReport>> {
    spec.check()?;
    let mut done = Vec::new();
    for job in spec.my_jobs() {
        let time = spec.time(job.frame);
        let output = spec.png_path(&job);
        if spec.resume && spec.job_done(&job, base.width, base.height) {
            let r = JobReport {
                job,
                time,
                output,
                skipped: true,
                passes: Vec::new(),
                pose_ms: 0.0,
                render_ms: 0.0,
                write_ms: 0.0,
                display: crate::render::display_note(base),
            };
            report(&r);
            done.push(r);
            continue;
        }
        let start = Instant::now();
        let mut options = pose_frame(
            scene,
            renderer,
            gpu,
            base,
            &spec.motion,
            spec.animation,
            time,
        )?;
        let pose_ms = start.elapsed().as_secs_f64() * 1e3;
        if let (Some(s), Some(i)) = (&spec.sweep, job.sweep) {
            s.apply(i, &mut options)?;
        }
        options.read_hdr = spec.exr.is_some();
        let frame = renderer.render_frame(scene, gpu, &options)?;
        let render_ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        // All of the frame or none of it; the PNG is renamed into place last.
        crate::render::write_frame(
            &output,
            spec.exr_path(&job).as_deref(),
            frame.width,
            frame.height,
            &frame.ldr,
            &frame.hdr,
            &options,
        )?;
        let r = JobReport {
            job,
            time,
            output,
            skipped: false,
            passes: frame
                .timings
                .iter()
                .map(|t| (t.name, t.gpu_ms, t.wall_ms))
                .collect(),
            pose_ms,
            render_ms,
            write_ms: start.elapsed().as_secs_f64() * 1e3,
            display: crate::render::display_note(&options),
        };
        report(&r);
        done.push(r);
    }
    Ok(done)
}

/// The ffmpeg command that turns the frames of `spec` into `video` (its image2 demuxer reads the
/// same %0Nd pattern; the codec is ffmpeg's default for the file's extension).
pub fn video_command(spec: &SequenceSpec, video: &std::path::Path) -> std::process::Command {
    let mut c = std::process::Command::new("ffmpeg");
    c.args(["-y", "-loglevel", "error", "-framerate"])
        .arg(format!("{}", spec.fps))
        .arg("-start_number")
        .arg(spec.range.first.to_string())
        .arg("-i")
        .arg(spec.output.as_str())
        .arg("-frames:v")
        .arg(spec.range.len().to_string())
        .args(["-pix_fmt", "yuv420p"])
        .arg(video);
    c
}

/// Whether an executable `name` is on PATH.
pub fn on_path(name: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|paths| {
        std::env::split_paths(&paths).any(|dir| {
            let p = dir.join(name);
            p.is_file()
                && std::fs::metadata(&p)
                    .map(|m| {
                        use std::os::unix::fs::PermissionsExt;
                        m.permissions().mode() & 0o111 != 0
                    })
                    .unwrap_or(false)
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbit_keeps_the_distance_and_turns_by_the_angle() {
        let scene = crate::scene::default_scene();
        let base = scene.camera(None).unwrap();
        let motion = CameraMotion {
            orbit_degrees_per_second: 90.0,
            dolly_per_second: 0.0,
            center: Vec3::ZERO,
        };
        let eye = |c: &Camera| c.view.inverse().transform_point3(Vec3::ZERO);
        let moved = motion.camera_at(&base, 1.0).unwrap();
        let (a, b) = (eye(&base), eye(&moved));
        assert!((a.length() - b.length()).abs() < 1e-4, "{a} {b}");
        assert!((a.y - b.y).abs() < 1e-5);
        // A quarter turn about +Y: the horizontal parts are perpendicular, same length.
        let (ha, hb) = (Vec3::new(a.x, 0.0, a.z), Vec3::new(b.x, 0.0, b.z));
        assert!(ha.dot(hb).abs() < 1e-3 * ha.length_squared(), "{ha} {hb}");
        // At t = 0 the camera is the base one.
        let still = motion.camera_at(&base, 0.0).unwrap();
        assert!((eye(&still) - a).length() < 1e-5);
    }

    #[test]
    fn dolly_moves_along_the_view_direction() {
        let scene = crate::scene::default_scene();
        let base = scene.camera(None).unwrap();
        let motion = CameraMotion {
            orbit_degrees_per_second: 0.0,
            dolly_per_second: 0.5,
            center: Vec3::ZERO,
        };
        let w = base.view.inverse();
        let forward = w.transform_vector3(Vec3::NEG_Z).normalize();
        let moved = motion.camera_at(&base, 2.0).unwrap();
        let d = moved.view.inverse().transform_point3(Vec3::ZERO) - w.transform_point3(Vec3::ZERO);
        assert!((d - forward).length() < 1e-4, "{d} {forward}");
    }
}
