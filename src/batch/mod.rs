//! Frame sequences and the batch contract (docs/batch.md): what a render farm's stateless task
//! needs from `weft render`.
//!
//! - [`FrameRange`]: `--frames-range A..B`, both ends included (as Blender's `-s/-e` and Slurm's
//!   `--array=A-B`).
//! - [`Sweep`]: `--sweep KEY=V1,V2,...`, a parameter varied over the jobs.
//! - [`TaskSpec`]: which share of the jobs this process renders, from `--task/--tasks` or the
//!   variables the engines set ([`TaskSpec::from_env`]), split by [`Split`].
//! - [`OutputPattern`]: `out_%04d.png`, the file of each job.
//! - [`ExitClass`]: the exit code that tells a scheduler whether to retry.
//!
//! Nothing here touches the GPU: every flag is checked before a device is opened. The frame loop
//! itself is in [`sequence`].

pub mod sequence;

use std::path::{Path, PathBuf};

use crate::Error;

/// An inclusive range of frame numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    pub first: u32,
    pub last: u32,
}

/// The most frames one range may hold (a typo such as `1..10000000` fails as bad input instead
/// of planning ten million jobs).
pub const MAX_FRAMES: u32 = 1_000_000;

impl FrameRange {
    /// Parses `A..B` (A <= B, both included) or a single frame `N`.
    pub fn parse(text: &str) -> crate::Result<FrameRange> {
        let bad = |why: &str| {
            Error::input(format!(
                "--frames-range '{text}' {why}: give FIRST..LAST, both included (e.g. 1..240), or one frame number"
            ))
        };
        let num = |s: &str| {
            s.trim()
                .parse::<u32>()
                .map_err(|_| bad("is not two whole numbers >= 0"))
        };
        let (first, last) = match text.split_once("..") {
            Some((a, b)) => {
                if b.starts_with('=') {
                    return Err(bad("uses '..=': the range is always inclusive, write A..B"));
                }
                (num(a)?, num(b)?)
            }
            None => {
                let n = num(text)?;
                (n, n)
            }
        };
        if first > last {
            return Err(bad("ends before it starts"));
        }
        let range = FrameRange { first, last };
        if range.len() > MAX_FRAMES as u64 {
            return Err(bad(&format!("holds more than {MAX_FRAMES} frames")));
        }
        Ok(range)
    }

    pub fn len(&self) -> u64 {
        u64::from(self.last - self.first) + 1
    }

    pub fn is_empty(&self) -> bool {
        false
    }

    pub fn frames(&self) -> impl Iterator<Item = u32> {
        self.first..=self.last
    }
}

/// How the jobs are dealt to tasks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Split {
    /// Task i gets one contiguous run of jobs: jobs [floor(i n / N), floor((i+1) n / N)). Each
    /// task's frames play in order (a task's output is a clip; caches stay warm).
    #[default]
    Contiguous,
    /// Task i gets jobs i, i + N, i + 2N, ...: early frames of the whole sequence come first, so
    /// a preview fills in evenly while the farm works.
    Strided,
}

impl Split {
    pub fn parse(text: &str) -> crate::Result<Split> {
        match text {
            "contiguous" => Ok(Split::Contiguous),
            "strided" => Ok(Split::Strided),
            _ => Err(Error::input(format!(
                "unknown --split '{text}': choose contiguous or strided"
            ))),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Split::Contiguous => "contiguous",
            Split::Strided => "strided",
        }
    }
}

/// This process's share: task `index` of `count` (0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TaskSpec {
    pub index: u32,
    pub count: u32,
    /// Where the numbers came from (for messages and the metrics): `--task/--tasks`, or the
    /// variable(s) read.
    pub source: &'static str,
}

impl Default for TaskSpec {
    fn default() -> Self {
        TaskSpec::SINGLE
    }
}

/// The environment variables [`TaskSpec::from_env`] reads, by engine, for docs and `--help`.
pub const TASK_ENV_VARS: &[(&str, &str)] = &[
    (
        "Slurm job arrays",
        "SLURM_ARRAY_TASK_ID with SLURM_ARRAY_TASK_COUNT, or SLURM_ARRAY_TASK_MIN/MAX (and _STEP)",
    ),
    (
        "Kubernetes indexed jobs",
        "JOB_COMPLETION_INDEX; the count from --tasks or WEFT_TASKS",
    ),
    (
        "AWS Batch array jobs",
        "AWS_BATCH_JOB_ARRAY_INDEX; the count from --tasks or WEFT_TASKS",
    ),
    (
        "anything else (Dask, Deadline, OpenCue, shell loops)",
        "WEFT_TASK and WEFT_TASKS, or the flags",
    ),
];

impl TaskSpec {
    pub const SINGLE: TaskSpec = TaskSpec {
        index: 0,
        count: 1,
        source: "single process",
    };

    /// The share from the flags, else from the environment (`env` looks a variable up; pass
    /// `|k| std::env::var(k).ok()`). Flags win over variables; among the variables, the first
    /// engine of [`TASK_ENV_VARS`] that is present wins. With neither, the one task of one.
    pub fn resolve(
        task: Option<u32>,
        tasks: Option<u32>,
        env: impl Fn(&str) -> Option<String>,
    ) -> crate::Result<TaskSpec> {
        let count_env = || -> crate::Result<Option<u32>> {
            match tasks {
                Some(n) => Ok(Some(n)),
                None => env("WEFT_TASKS")
                    .map(|v| parse_env_u32("WEFT_TASKS", &v))
                    .transpose(),
            }
        };
        let spec = if let Some(index) = task {
            let count = count_env()?.ok_or_else(|| {
                Error::input(
                    "--task needs --tasks N (or WEFT_TASKS): how many tasks share the work",
                )
            })?;
            TaskSpec {
                index,
                count,
                source: "--task/--tasks",
            }
        } else if let Some(id) = env("SLURM_ARRAY_TASK_ID") {
            let id = parse_env_u32("SLURM_ARRAY_TASK_ID", &id)?;
            let get = |k: &str| env(k).map(|v| parse_env_u32(k, &v)).transpose();
            let min = get("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let step = get("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1);
            if step == 0 {
                return Err(Error::input(
                    "SLURM_ARRAY_TASK_STEP is 0: an array's step is at least 1 (unset it for 1)",
                ));
            }
            let count = match (tasks, get("SLURM_ARRAY_TASK_COUNT")?, get("SLURM_ARRAY_TASK_MAX")?) {
                (Some(n), _, _) => n,
                (None, Some(n), _) => n,
                // In u64: MAX = 4294967295 with MIN 0 and STEP 1 is 2^32 tasks, one more than
                // u32 holds (it wrapped to 0).
                (None, None, Some(max)) if max >= min => {
                    let n = u64::from(max - min) / u64::from(step) + 1;
                    u32::try_from(n).map_err(|_| {
                        Error::input(format!(
                            "SLURM_ARRAY_TASK_MIN/MAX/STEP ({min}, {max}, {step}) make an array of {n} tasks, more than weft can count ({}): pass --tasks N",
                            u32::MAX
                        ))
                    })?
                }
                (None, None, Some(max)) => {
                    return Err(Error::input(format!(
                        "SLURM_ARRAY_TASK_MAX {max} is below SLURM_ARRAY_TASK_MIN {min}: pass --tasks N"
                    )))
                }
                _ => {
                    return Err(Error::input(
                        "SLURM_ARRAY_TASK_ID is set but neither SLURM_ARRAY_TASK_COUNT nor SLURM_ARRAY_TASK_MAX: pass --tasks N",
                    ))
                }
            };
            if id < min || (id - min) % step != 0 {
                return Err(Error::input(format!(
                    "SLURM_ARRAY_TASK_ID {id} is not on the array MIN + k STEP ({min} + k {step})"
                )));
            }
            TaskSpec {
                index: (id - min) / step,
                count,
                source: "SLURM_ARRAY_TASK_*",
            }
        } else if let Some((var, id)) = ["JOB_COMPLETION_INDEX", "AWS_BATCH_JOB_ARRAY_INDEX"]
            .iter()
            .find_map(|k| env(k).map(|v| (*k, v)))
        {
            let index = parse_env_u32(var, &id)?;
            let count = count_env()?.ok_or_else(|| {
                Error::input(format!(
                    "{var} is set but not how many tasks there are: pass --tasks N or set WEFT_TASKS (the job's completions / array size)"
                ))
            })?;
            TaskSpec {
                index,
                count,
                source: if var == "JOB_COMPLETION_INDEX" {
                    "JOB_COMPLETION_INDEX"
                } else {
                    "AWS_BATCH_JOB_ARRAY_INDEX"
                },
            }
        } else if let Some(id) = env("WEFT_TASK") {
            let index = parse_env_u32("WEFT_TASK", &id)?;
            let count = count_env()?
                .ok_or_else(|| Error::input("WEFT_TASK is set but not WEFT_TASKS (or --tasks)"))?;
            TaskSpec {
                index,
                count,
                source: "WEFT_TASK/WEFT_TASKS",
            }
        } else if let Some(count) = tasks {
            return Err(Error::input(format!(
                "--tasks {count} without --task I (or an engine's task variable such as SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX): which task is this?"
            )));
        } else {
            TaskSpec::SINGLE
        };
        spec.check()?;
        Ok(spec)
    }

    fn check(&self) -> crate::Result<()> {
        if self.count == 0 {
            return Err(Error::input(format!(
                "{}: the task count must be at least 1",
                self.source
            )));
        }
        if self.index >= self.count {
            return Err(Error::input(format!(
                "{}: task {} of {} does not exist: the index counts from 0 and must be below the count",
                self.source, self.index, self.count
            )));
        }
        Ok(())
    }

    /// The indices (into a list of `jobs` jobs) this task renders, in order.
    pub fn share(&self, jobs: u64, split: Split) -> Vec<u64> {
        let (i, n) = (u64::from(self.index), u64::from(self.count));
        match split {
            Split::Contiguous => (i * jobs / n..(i + 1) * jobs / n).collect(),
            Split::Strided => (i..jobs).step_by(n as usize).collect(),
        }
    }
}

fn parse_env_u32(name: &str, value: &str) -> crate::Result<u32> {
    value.trim().parse().map_err(|_| {
        Error::input(format!(
            "the environment variable {name}='{value}' is not a whole number >= 0"
        ))
    })
}

/// A parameter varied over the jobs: every frame is rendered once per value.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub key: SweepKey,
    /// The values as written (they name the output files), each checked to parse.
    pub values: Vec<String>,
}

/// What `--sweep` can vary: render options that need no re-upload of the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SweepKey {
    /// EV, as `--exposure`.
    Exposure,
    /// As `--accuracy`.
    Accuracy,
    /// As `--env-intensity`.
    EnvIntensity,
    /// Degrees, as `--env-rotation`.
    EnvRotation,
}

impl SweepKey {
    pub const ALL: [SweepKey; 4] = [
        SweepKey::Exposure,
        SweepKey::Accuracy,
        SweepKey::EnvIntensity,
        SweepKey::EnvRotation,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SweepKey::Exposure => "exposure",
            SweepKey::Accuracy => "accuracy",
            SweepKey::EnvIntensity => "env-intensity",
            SweepKey::EnvRotation => "env-rotation",
        }
    }
}

impl Sweep {
    /// Parses `KEY=V1,V2,...`.
    pub fn parse(text: &str) -> crate::Result<Sweep> {
        let keys = || {
            SweepKey::ALL
                .iter()
                .map(|k| k.name())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (key, values) = text.split_once('=').ok_or_else(|| {
            Error::input(format!(
                "--sweep '{text}' is not KEY=V1,V2,... (e.g. exposure=-1,0,1); keys: {}",
                keys()
            ))
        })?;
        let key = SweepKey::ALL
            .iter()
            .copied()
            .find(|k| k.name() == key.trim())
            .ok_or_else(|| {
                Error::input(format!(
                    "--sweep: unknown key '{}': choose one of {}",
                    key.trim(),
                    keys()
                ))
            })?;
        let values: Vec<String> = values.split(',').map(|v| v.trim().to_string()).collect();
        let sweep = Sweep { key, values };
        let mut probe = crate::render::RenderOptions {
            environment: Some(crate::env::EnvLighting::new(std::sync::Arc::new(
                crate::env::Environment::uniform([1.0; 3]),
            ))),
            ..Default::default()
        };
        for (i, v) in sweep.values.iter().enumerate() {
            if v.is_empty() || sweep.values[..i].contains(v) {
                return Err(Error::input(format!(
                    "--sweep {}: value {} is {}: give distinct values separated by commas",
                    key.name(),
                    i + 1,
                    if v.is_empty() { "empty" } else { "repeated" }
                )));
            }
            sweep.apply(i, &mut probe)?;
            probe.validate()?;
        }
        Ok(sweep)
    }

    /// Sets value `i` in `options`.
    pub fn apply(&self, i: usize, options: &mut crate::render::RenderOptions) -> crate::Result<()> {
        let text = &self.values[i];
        let number = || {
            text.parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    Error::input(format!(
                        "--sweep {}: '{text}' is not a finite number",
                        self.key.name()
                    ))
                })
        };
        match self.key {
            SweepKey::Exposure => options.exposure = number()?,
            SweepKey::Accuracy => options.accuracy = crate::render::Accuracy::parse(text)?,
            SweepKey::EnvIntensity | SweepKey::EnvRotation => {
                let v = number()?;
                let env = options.environment.as_mut().ok_or_else(|| {
                    Error::input(format!(
                        "--sweep {} needs environment light: leave out --env none",
                        self.key.name()
                    ))
                })?;
                if self.key == SweepKey::EnvIntensity {
                    env.intensity = v;
                } else {
                    env.rotation = v;
                }
            }
        }
        Ok(())
    }
}

/// One unit of work: a frame, at one sweep value (None without a sweep).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Job {
    pub frame: u32,
    pub sweep: Option<usize>,
}

/// Every job of a range and sweep, in their canonical order: frame-major (all of frame A's
/// values, then frame A+1's...), so a contiguous share of a sweep over one frame is a run of
/// values.
pub fn jobs(range: FrameRange, sweep: Option<&Sweep>) -> Vec<Job> {
    let values = sweep.map(|s| s.values.len());
    range
        .frames()
        .flat_map(|frame| match values {
            None => vec![Job { frame, sweep: None }],
            Some(n) => (0..n)
                .map(|v| Job {
                    frame,
                    sweep: Some(v),
                })
                .collect(),
        })
        .collect()
}

/// The output path of each job: `%d` or `%0Nd` (printf style, as ffmpeg reads it) for the frame
/// number, `{sweep}` for the sweep value, `%%` for a literal `%`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputPattern {
    pattern: String,
    has_frame: bool,
    has_sweep: bool,
}

impl OutputPattern {
    pub fn parse(path: &Path) -> crate::Result<OutputPattern> {
        let pattern = path.to_str().ok_or_else(|| {
            Error::input(format!(
                "output pattern '{}' is not valid UTF-8",
                path.display()
            ))
        })?;
        let mut has_frame = false;
        let mut chars = pattern.chars().peekable();
        while let Some(c) = chars.next() {
            if c != '%' {
                continue;
            }
            match chars.next() {
                Some('%') => {}
                Some('d') => has_frame = true,
                Some('0') => {
                    let mut width = String::new();
                    while let Some(d) = chars.peek().filter(|d| d.is_ascii_digit()) {
                        width.push(*d);
                        chars.next();
                    }
                    if chars.next() != Some('d') || width.is_empty() || width.len() > 1 {
                        return Err(bad_pattern(pattern));
                    }
                    has_frame = true;
                }
                _ => return Err(bad_pattern(pattern)),
            }
        }
        Ok(OutputPattern {
            pattern: pattern.to_string(),
            has_frame,
            has_sweep: pattern.contains("{sweep}"),
        })
    }

    /// Refuses a pattern under which two jobs would write one file.
    pub fn check(&self, range: FrameRange, sweep: Option<&Sweep>) -> crate::Result<()> {
        if range.len() > 1 && !self.has_frame {
            return Err(Error::input(format!(
                "-o '{}' has no frame number, so every frame of --frames-range would overwrite one file: put %04d in it (e.g. -o out_%04d.png)",
                self.pattern
            )));
        }
        if sweep.is_some_and(|s| s.values.len() > 1) && !self.has_sweep {
            return Err(Error::input(format!(
                "-o '{}' has no {{sweep}}, so every value of --sweep would overwrite one file: put {{sweep}} in it (e.g. -o out_{{sweep}}_%04d.png)",
                self.pattern
            )));
        }
        Ok(())
    }

    /// The path of `frame` at sweep value `sweep` (used as written, e.g. `-1` or `mixture`).
    pub fn path(&self, frame: u32, sweep: Option<&str>) -> PathBuf {
        let mut out = String::new();
        let mut chars = self.pattern.chars().peekable();
        while let Some(c) = chars.next() {
            if c != '%' {
                out.push(c);
                continue;
            }
            match chars.next() {
                Some('%') => out.push('%'),
                Some('d') => out.push_str(&frame.to_string()),
                Some('0') => {
                    let width: usize =
                        chars.next().and_then(|d| d.to_digit(10)).unwrap_or(1) as usize;
                    chars.next(); // the 'd'
                    out.push_str(&format!("{frame:0width$}"));
                }
                _ => {}
            }
        }
        if let Some(v) = sweep {
            // A value names a file: keep it to characters every file system takes.
            let safe: String = v
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || matches!(c, '-' | '.' | '_') {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            out = out.replace("{sweep}", &safe);
        }
        PathBuf::from(out)
    }

    /// The pattern as ffmpeg's image2 demuxer reads it (the same printf syntax).
    pub fn as_str(&self) -> &str {
        &self.pattern
    }
}

fn bad_pattern(pattern: &str) -> Error {
    Error::input(format!(
        "output pattern '{pattern}': a '%' must start %d, %0Nd (N from 1 to 9) or %%"
    ))
}

/// What a failed task's exit code tells the scheduler (docs/batch.md, `weft render --help`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExitClass {
    /// 2: the input is wrong (a flag, the scene file, the output path): the same command fails
    /// again anywhere. Do not retry.
    BadInput,
    /// 69 (EX_UNAVAILABLE): no usable Vulkan driver or device on this node. Retry on another
    /// node.
    Unavailable,
    /// 75 (EX_TEMPFAIL): the device was lost or ran out of memory, or the disk failed to take a
    /// frame: retry (with --resume only the missing frames are rendered).
    TempFail,
    /// 70 (EX_SOFTWARE): a bug in weft (a validation message, an unexpected Vulkan error).
    /// Retry at most once, then report it.
    Software,
}

impl ExitClass {
    pub const ALL: [ExitClass; 4] = [
        ExitClass::BadInput,
        ExitClass::Unavailable,
        ExitClass::TempFail,
        ExitClass::Software,
    ];

    pub fn code(self) -> u8 {
        match self {
            ExitClass::BadInput => 2,
            ExitClass::Unavailable => 69,
            ExitClass::TempFail => 75,
            ExitClass::Software => 70,
        }
    }

    /// Classifies an error (the first `weft::Error` in an anyhow chain; anything else is a bug).
    pub fn of(error: &anyhow::Error) -> ExitClass {
        match error.chain().find_map(|e| e.downcast_ref::<Error>()) {
            Some(e) => ExitClass::of_error(e),
            None => ExitClass::Software,
        }
    }

    pub fn of_error(error: &Error) -> ExitClass {
        use ash::vk::Result as R;
        match error {
            Error::Input(_) => ExitClass::BadInput,
            Error::NoVulkan(_) => ExitClass::Unavailable,
            // Out of memory, or a limit of this device (a size it cannot hold): another try,
            // later or on a larger device, can succeed.
            Error::Device(_) => ExitClass::TempFail,
            Error::Vulkan { result, .. }
                if matches!(
                    *result,
                    R::ERROR_DEVICE_LOST
                        | R::ERROR_OUT_OF_DEVICE_MEMORY
                        | R::ERROR_OUT_OF_HOST_MEMORY
                        | R::TIMEOUT
                ) =>
            {
                ExitClass::TempFail
            }
            Error::Vulkan { .. } | Error::Validation(_) => ExitClass::Software,
            // A missing directory or a read-only one stays so; a full disk or a failing
            // network file system may not.
            Error::Io { source, .. } => match source.kind() {
                std::io::ErrorKind::NotFound
                | std::io::ErrorKind::PermissionDenied
                | std::io::ErrorKind::ReadOnlyFilesystem
                | std::io::ErrorKind::IsADirectory
                | std::io::ErrorKind::NotADirectory
                | std::io::ErrorKind::InvalidFilename
                | std::io::ErrorKind::InvalidInput => ExitClass::BadInput,
                _ => ExitClass::TempFail,
            },
        }
    }

    /// One line per code, for `--help` and docs/batch.md.
    pub fn table() -> String {
        let mut t = String::from(
            "0: every job of this task is done (rendered, or already there with --resume)\n",
        );
        for c in ExitClass::ALL {
            let what = match c {
                ExitClass::BadInput => "bad input (flag, scene, output path): do not retry",
                ExitClass::Unavailable => "no usable Vulkan device on this node: retry elsewhere",
                ExitClass::TempFail => {
                    "device lost, out of memory, or a failed write: retry (with --resume)"
                }
                ExitClass::Software => "a bug in weft: retry at most once, then report it",
            };
            t.push_str(&format!("{}: {what}\n", c.code()));
        }
        t
    }
}
