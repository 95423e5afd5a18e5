//! Sequences and the batch contract (docs/batch.md): range parsing, the task split (every job
//! exactly once over all tasks), the engines' variables, output patterns, exit codes (bad input
//! without touching the GPU), resume, metrics, sweeps, the temporal bench on a tiny
//! configuration, and the Dask fan-out when dask.distributed is installed.
//!
//! GPU runs go through lavapipe (or WEFT_DEVICE) with `--validate`: any validation message fails
//! the render, hence the test.

mod common;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use weft::batch::{
    self, sequence, ExitClass, FrameRange, Job, OutputPattern, Split, Sweep, SweepKey, TaskSpec,
};

/// `common::weft`: no engine variable of the machine running the tests leaks into a task.
fn weft() -> Command {
    let mut c = common::weft();
    for k in [
        "SLURM_ARRAY_TASK_ID",
        "SLURM_ARRAY_TASK_COUNT",
        "SLURM_ARRAY_TASK_MIN",
        "SLURM_ARRAY_TASK_MAX",
        "SLURM_ARRAY_TASK_STEP",
        "JOB_COMPLETION_INDEX",
        "AWS_BATCH_JOB_ARRAY_INDEX",
        "WEFT_TASK",
        "WEFT_TASKS",
    ] {
        c.env_remove(k);
    }
    c
}

/// [`weft`] with no Vulkan driver (`common::weft_without_gpu`).
fn weft_without_gpu() -> Command {
    common::without_gpu(weft())
}

#[test]
fn frame_ranges_parse_inclusive_and_refuse_nonsense() {
    assert_eq!(
        FrameRange::parse("1..240").unwrap(),
        FrameRange {
            first: 1,
            last: 240
        }
    );
    assert_eq!(FrameRange::parse("1..240").unwrap().len(), 240);
    assert_eq!(FrameRange::parse("7").unwrap().len(), 1);
    assert_eq!(FrameRange::parse(" 3 .. 3 ").unwrap().len(), 1);
    for bad in [
        "",
        "a..b",
        "5..1",
        "-1..3",
        "1..=4",
        "1...4",
        "1..",
        "0..2000000",
    ] {
        assert!(FrameRange::parse(bad).is_err(), "{bad:?} should be refused");
    }
}

/// Every job exactly once over all tasks, for both splits, over many sizes; contiguous shares
/// are runs in order with sizes that differ by at most one.
#[test]
fn the_task_split_covers_every_job_exactly_once() {
    for jobs in [0u64, 1, 2, 5, 7, 24, 97, 240] {
        for count in [1u32, 2, 3, 4, 7, 16, 300] {
            for split in [Split::Contiguous, Split::Strided] {
                let mut seen = vec![0u32; jobs as usize];
                let mut sizes = Vec::new();
                for index in 0..count {
                    let spec = TaskSpec {
                        index,
                        count,
                        source: "test",
                    };
                    let share = spec.share(jobs, split);
                    assert!(share.windows(2).all(|w| w[0] < w[1]), "in order");
                    if split == Split::Contiguous {
                        assert!(share.windows(2).all(|w| w[1] == w[0] + 1), "a run");
                    }
                    sizes.push(share.len());
                    for j in share {
                        seen[j as usize] += 1;
                    }
                }
                assert!(
                    seen.iter().all(|&n| n == 1),
                    "{jobs} jobs over {count} tasks, {split:?}: {seen:?}"
                );
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(hi - lo <= 1, "{jobs}/{count} {split:?}: sizes {sizes:?}");
            }
        }
    }
    // The documented examples (docs/batch.md).
    let t = |index| TaskSpec {
        index,
        count: 3,
        source: "test",
    };
    assert_eq!(t(0).share(10, Split::Contiguous), vec![0, 1, 2]);
    assert_eq!(t(1).share(10, Split::Contiguous), vec![3, 4, 5]);
    assert_eq!(t(2).share(10, Split::Contiguous), vec![6, 7, 8, 9]);
    assert_eq!(t(1).share(10, Split::Strided), vec![1, 4, 7]);
}

fn env(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
    let map: HashMap<String, String> = pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    move |k| map.get(k).cloned()
}

#[test]
fn task_numbers_come_from_the_flags_or_the_engines_variables() {
    let spec = |task, tasks, vars: &[(&str, &str)]| TaskSpec::resolve(task, tasks, env(vars));
    let got = |task, tasks, vars: &[(&str, &str)]| {
        let s = spec(task, tasks, vars).unwrap();
        (s.index, s.count)
    };
    assert_eq!(got(None, None, &[]), (0, 1));
    assert_eq!(got(Some(2), Some(5), &[]), (2, 5));
    // Slurm: --array=0-9 sets COUNT; --array=1-10 MIN/MAX; --array=0-20:5 a STEP.
    let slurm = [
        ("SLURM_ARRAY_TASK_ID", "3"),
        ("SLURM_ARRAY_TASK_COUNT", "10"),
    ];
    assert_eq!(got(None, None, &slurm), (3, 10));
    assert_eq!(
        got(
            None,
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "4"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_MAX", "10")
            ]
        ),
        (3, 10)
    );
    assert_eq!(
        got(
            None,
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "15"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_MAX", "20"),
                ("SLURM_ARRAY_TASK_STEP", "5")
            ]
        ),
        (3, 5)
    );
    // Flags win over the variables.
    assert_eq!(got(Some(1), Some(2), &slurm), (1, 2));
    // Kubernetes and AWS Batch give the index only.
    assert_eq!(got(None, Some(4), &[("JOB_COMPLETION_INDEX", "3")]), (3, 4));
    assert_eq!(
        got(
            None,
            None,
            &[("JOB_COMPLETION_INDEX", "3"), ("WEFT_TASKS", "8")]
        ),
        (3, 8)
    );
    assert_eq!(
        got(None, Some(6), &[("AWS_BATCH_JOB_ARRAY_INDEX", "5")]),
        (5, 6)
    );
    assert_eq!(
        got(None, None, &[("WEFT_TASK", "1"), ("WEFT_TASKS", "2")]),
        (1, 2)
    );
    // Refused, each with a message naming the fix.
    // (--task, --tasks, variables, a fragment of the message)
    type Case<'a> = (Option<u32>, Option<u32>, &'a [(&'a str, &'a str)], &'a str);
    let refused: &[Case] = &[
        (Some(4), Some(4), &[], "does not exist"),
        (Some(0), Some(0), &[], "at least 1"),
        (Some(1), None, &[], "--task needs --tasks"),
        (None, Some(3), &[], "without --task"),
        (None, None, &[("JOB_COMPLETION_INDEX", "1")], "--tasks N"),
        (
            None,
            None,
            &[("SLURM_ARRAY_TASK_ID", "1")],
            "SLURM_ARRAY_TASK_COUNT",
        ),
        (
            None,
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "x"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
            "whole number",
        ),
        (
            None,
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "12"),
                ("SLURM_ARRAY_TASK_COUNT", "10"),
            ],
            "does not exist",
        ),
        (
            None,
            None,
            &[
                ("SLURM_ARRAY_TASK_ID", "3"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_MAX", "20"),
                ("SLURM_ARRAY_TASK_STEP", "5"),
            ],
            "not on the array",
        ),
    ];
    for (task, tasks, vars, expect) in refused {
        let e = spec(*task, *tasks, vars).expect_err(expect).to_string();
        assert!(e.contains(expect), "{vars:?}: {e}");
        assert_eq!(
            ExitClass::of_error(&spec(*task, *tasks, vars).unwrap_err()),
            ExitClass::BadInput
        );
    }
}

#[test]
fn sweeps_parse_and_multiply_the_jobs() {
    let s = Sweep::parse("exposure=-1,0,1.5").unwrap();
    assert_eq!(s.key, SweepKey::Exposure);
    assert_eq!(s.values, ["-1", "0", "1.5"]);
    let a = Sweep::parse("accuracy=nearest,mixture,supersampled:4").unwrap();
    let mut o = weft::render::RenderOptions::default();
    a.apply(2, &mut o).unwrap();
    assert_eq!(o.accuracy, weft::render::Accuracy::Supersampled(4));
    for bad in [
        "exposure",
        "gamma=1,2",
        "exposure=1,,2",
        "exposure=1,1",
        "exposure=1,x",
        "exposure=100",
        "accuracy=best",
        "env-intensity=-1",
    ] {
        assert!(Sweep::parse(bad).is_err(), "{bad:?} should be refused");
    }
    // Frame-major: frame 3's values, then frame 4's; every (frame, value) once over the tasks.
    let range = FrameRange { first: 3, last: 4 };
    let all = batch::jobs(range, Some(&s));
    assert_eq!(all.len(), 6);
    assert_eq!(
        all[..4],
        [
            Job {
                frame: 3,
                sweep: Some(0)
            },
            Job {
                frame: 3,
                sweep: Some(1)
            },
            Job {
                frame: 3,
                sweep: Some(2)
            },
            Job {
                frame: 4,
                sweep: Some(0)
            },
        ]
    );
    let mut seen = std::collections::HashSet::new();
    for index in 0..4 {
        let t = TaskSpec {
            index,
            count: 4,
            source: "test",
        };
        for j in t.share(all.len() as u64, Split::Strided) {
            assert!(seen.insert(all[j as usize]));
        }
    }
    assert_eq!(seen.len(), 6);
}

#[test]
fn output_patterns_number_the_frames_and_refuse_collisions() {
    let p = OutputPattern::parse(Path::new("out/f_%04d.png")).unwrap();
    assert_eq!(p.path(7, None), Path::new("out/f_0007.png"));
    assert_eq!(p.path(12345, None), Path::new("out/f_12345.png"));
    let p = OutputPattern::parse(Path::new("x%d_{sweep}_100%%.png")).unwrap();
    assert_eq!(p.path(3, Some("-1.5")), Path::new("x3_-1.5_100%.png"));
    assert_eq!(
        p.path(3, Some("supersampled:4")),
        Path::new("x3_supersampled_4_100%.png")
    );
    for bad in ["a%s.png", "a%.png", "a%012d.png", "a%0d.png"] {
        assert!(OutputPattern::parse(Path::new(bad)).is_err(), "{bad}");
    }
    let range = FrameRange { first: 0, last: 9 };
    let still = OutputPattern::parse(Path::new("still.png")).unwrap();
    assert!(still
        .check(range, None)
        .unwrap_err()
        .to_string()
        .contains("%04d"));
    assert!(still.check(FrameRange { first: 5, last: 5 }, None).is_ok());
    let sweep = Sweep::parse("exposure=0,1").unwrap();
    let frames = OutputPattern::parse(Path::new("f%04d.png")).unwrap();
    assert!(frames
        .check(range, Some(&sweep))
        .unwrap_err()
        .to_string()
        .contains("{sweep}"));
}

#[test]
fn errors_map_to_the_documented_exit_codes() {
    use weft::Error;
    let io = |kind| Error::Io {
        context: "x".into(),
        source: std::io::Error::from(kind),
    };
    let cases = [
        (Error::input("bad"), 2),
        (Error::NoVulkan("none".into()), 69),
        (Error::device("out of memory"), 75),
        (
            Error::Vulkan {
                what: "vkQueueSubmit",
                result: ash::vk::Result::ERROR_DEVICE_LOST,
            },
            75,
        ),
        (
            Error::Vulkan {
                what: "vkCreateImage",
                result: ash::vk::Result::ERROR_OUT_OF_DEVICE_MEMORY,
            },
            75,
        ),
        (
            Error::Vulkan {
                what: "vkCreateSampler",
                result: ash::vk::Result::ERROR_FORMAT_NOT_SUPPORTED,
            },
            70,
        ),
        (Error::Validation(vec!["msg".into()]), 70),
        (io(std::io::ErrorKind::NotFound), 2),
        (io(std::io::ErrorKind::PermissionDenied), 2),
        (io(std::io::ErrorKind::StorageFull), 75),
    ];
    for (e, code) in cases {
        let what = format!("{e:?}");
        assert_eq!(ExitClass::of_error(&e).code(), code, "{what}");
        // Through an anyhow chain with context, as main sees it.
        let chained = anyhow::Error::from(e).context("rendering frame 3");
        assert_eq!(ExitClass::of(&chained).code(), code, "{what}");
    }
    assert_eq!(ExitClass::of(&anyhow::anyhow!("other")).code(), 70);
}

/// Bad input to a batch render exits 2, and the message is the input's, not "No Vulkan driver"
/// (no driver is findable here). Flags are checked before a device is opened; a missing scene
/// file is found while the device opens on another thread, and its error is the one reported.
#[test]
fn batch_bad_input_exits_2_without_touching_the_gpu() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f_%04d.png");
    let cases: &[(&[&str], &str)] = &[
        (&["--frames-range", "9..2"], "ends before it starts"),
        (&["--frames-range", "0..3", "-o", "one.png"], "%04d"),
        (&["--frames-range", "0..3", "--fps", "0"], "--fps"),
        (
            &["--frames-range", "0..3", "--sweep", "gamma=1"],
            "unknown key",
        ),
        (
            &["--frames-range", "0..3", "--sweep", "exposure=0,1"],
            "{sweep}",
        ),
        (
            &["--frames-range", "0..3", "--task", "3", "--tasks", "3"],
            "does not exist",
        ),
        (
            &["--frames-range", "0..3", "--tasks", "3"],
            "without --task",
        ),
        (
            &["--frames-range", "0..3", "--split", "random"],
            "contiguous or strided",
        ),
        (
            &["--frames-range", "0..3", "--size", "0x5"],
            "between 1 and",
        ),
        (&["--frames-range", "0..3", "--orbit", "inf"], "--orbit"),
        (
            &[
                "--frames-range",
                "0..3",
                "--video",
                "v.mp4",
                "--task",
                "0",
                "--tasks",
                "2",
            ],
            "--video",
        ),
        (
            &["/nonexistent/scene.gltf", "--frames-range", "0..3"],
            "/nonexistent/scene.gltf",
        ),
        (
            &["--frames-range", "0..3", "-o", "/nonexistent/dir/f%d.png"],
            "does not exist",
        ),
    ];
    for (args, expect) in cases {
        let mut c = weft_without_gpu();
        c.arg("render").args(*args);
        if !args.contains(&"-o") {
            c.arg("-o").arg(&out);
        }
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(
            !err.contains("Vulkan"),
            "{args:?} reached the device: {err}"
        );
    }
    // An engine variable out of range is bad input too.
    let o = weft_without_gpu()
        .args(["render", "--frames-range", "0..3", "-o"])
        .arg(&out)
        .env("SLURM_ARRAY_TASK_ID", "7")
        .env("SLURM_ARRAY_TASK_COUNT", "4")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    // Good input on a node without a driver: 69, retry elsewhere.
    let o = weft_without_gpu()
        .args(["render", "--frames-range", "0..3", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(69), "{err}");
    assert!(err.contains("No Vulkan driver"), "{err}");
    // A task whose share is empty (task 0 of 3 over 2 frames: jobs floor(0)..floor(2/3)) is
    // done at once, without a device.
    let o = weft_without_gpu()
        .args([
            "render",
            "--frames-range",
            "0..1",
            "--task",
            "0",
            "--tasks",
            "3",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("nothing to do"), "{err}");
    // A single render keeps its exit code 1 on bad input (tests/cli.rs).
    let o = weft_without_gpu()
        .args(["render", "--size", "0x5", "-o", "x.png"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(
        dir.path().read_dir().unwrap().next().is_none(),
        "nothing written"
    );
}

fn metrics(stdout: &[u8]) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

fn run_ok(c: &mut Command) -> std::process::Output {
    let o = c.output().unwrap();
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// A sequence in one process: one metrics line per frame, every frame written; --resume skips
/// what is complete and renders again what is missing or broken; the orbit moves the picture and
/// a still camera gives identical frames.
#[test]
fn sequence_writes_every_frame_and_resume_renders_only_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let pattern = dir.path().join("f_%04d.png");
    let render = |extra: &[&str]| {
        let mut c = weft();
        c.args([
            "render",
            "--validate",
            "--size",
            "48x27",
            "--frames-range",
            "2..5",
        ])
        .args(["--fps", "4", "--metrics-json", "-o"])
        .arg(&pattern)
        .args(extra);
        c
    };
    let o = run_ok(&mut render(&["--orbit", "20"]));
    let lines = metrics(&o.stdout);
    assert_eq!(lines.len(), 4);
    for (i, m) in lines.iter().enumerate() {
        let frame = 2 + i as u64;
        assert_eq!(m["frame"], frame);
        assert_eq!(m["time"].as_f64().unwrap(), frame as f64 / 4.0);
        assert_eq!(m["status"], "rendered");
        assert_eq!(m["tasks"], 1);
        let path = m["output"].as_str().unwrap();
        assert!(path.ends_with(&format!("f_{frame:04}.png")), "{path}");
        // One submission per frame: the passes have GPU times between their timestamps, no wall
        // time of their own; the submission has the wall time of all of them.
        assert!(m["passes"]["gbuffer"]["gpu_ms"].as_f64().unwrap() > 0.0);
        assert!(m["passes"]["gbuffer"]["wall_ms"].is_null());
        assert!(m["passes"]["lighting"].is_object());
        assert!(m["passes"]["submission"]["wall_ms"].as_f64().unwrap() > 0.0);
        assert_eq!(m["display"], "tonemap pbr-neutral, exposure 0 EV, aa fxaa");
        assert!(m["wall_ms"].as_f64().unwrap() >= m["render_ms"].as_f64().unwrap());
        assert!(m["render_ms"].as_f64().unwrap() >= m["pose_ms"].as_f64().unwrap());
        assert!(sequence::frame_done(Path::new(path), 48, 27));
    }
    let file = |n: u32| dir.path().join(format!("f_{n:04}.png"));
    assert_ne!(
        std::fs::read(file(2)).unwrap(),
        std::fs::read(file(5)).unwrap(),
        "the orbit turned the camera"
    );

    // Frame 3 missing, frame 4 cut short (what a non-atomic writer killed midway leaves).
    std::fs::remove_file(file(3)).unwrap();
    let whole = std::fs::read(file(4)).unwrap();
    std::fs::write(file(4), &whole[..whole.len() / 2]).unwrap();
    let before2 = std::fs::metadata(file(2)).unwrap().modified().unwrap();
    let o = run_ok(&mut render(&["--orbit", "20", "--resume"]));
    let status: Vec<_> = metrics(&o.stdout)
        .iter()
        .map(|m| m["status"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(status, ["skipped", "rendered", "rendered", "skipped"]);
    assert_eq!(
        std::fs::metadata(file(2)).unwrap().modified().unwrap(),
        before2
    );
    assert_eq!(
        std::fs::read(file(4)).unwrap(),
        whole,
        "re-rendered the same"
    );
    // No temporary file is left by a run that finished.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");

    // A still camera: every frame the same picture.
    let still = tempfile::tempdir().unwrap();
    run_ok(
        weft()
            .args(["render", "--size", "48x27", "--frames-range", "0..1", "-o"])
            .arg(still.path().join("s%d.png")),
    );
    assert_eq!(
        std::fs::read(still.path().join("s0.png")).unwrap(),
        std::fs::read(still.path().join("s1.png")).unwrap()
    );
}

/// Tasks given by flags and by the engines' variables write every frame once between them; a
/// sweep writes a file per value, brighter with the exposure.
#[test]
fn tasks_share_the_frames_and_a_sweep_writes_each_value() {
    let dir = tempfile::tempdir().unwrap();
    let pattern = dir.path().join("t_%02d.png");
    let mut rendered = Vec::new();
    let vars: [&[(&str, &str)]; 3] = [
        &[
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_MAX", "3"),
        ],
        &[("JOB_COMPLETION_INDEX", "1"), ("WEFT_TASKS", "3")],
        &[("WEFT_TASK", "2"), ("WEFT_TASKS", "3")],
    ];
    for (i, vars) in vars.iter().enumerate() {
        let mut c = weft();
        c.args([
            "render",
            "--size",
            "32x18",
            "--frames-range",
            "0..6",
            "--split",
            "strided",
        ])
        .args(["--metrics-json", "-o"])
        .arg(&pattern);
        for (k, v) in *vars {
            c.env(k, v);
        }
        let o = run_ok(&mut c);
        for m in metrics(&o.stdout) {
            assert_eq!(m["task"], i as u64);
            assert_eq!(m["tasks"], 3);
            rendered.push(m["frame"].as_u64().unwrap());
        }
    }
    rendered.sort();
    assert_eq!(rendered, (0..=6).collect::<Vec<_>>());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 7);

    let o = run_ok(
        weft()
            .args(["render", "--size", "32x18", "--frames-range", "4"])
            .args(["--sweep", "exposure=-2,0,2", "--metrics-json", "-o"])
            .arg(dir.path().join("e_{sweep}_%d.png")),
    );
    let lines = metrics(&o.stdout);
    assert_eq!(lines.len(), 3);
    assert_eq!(lines[0]["sweep"]["key"], "exposure");
    let mean = |v: &str| {
        let img = image::open(dir.path().join(format!("e_{v}_4.png")))
            .unwrap()
            .to_rgba8();
        weft::sheet::mean_srgb(img.as_raw())
    };
    let (dark, mid, bright) = (mean("-2"), mean("0"), mean("2"));
    assert!(dark < mid && mid < bright, "{dark} {mid} {bright}");
}

/// --video runs ffmpeg with the frames' pattern, rate and first number (a stand-in ffmpeg on
/// PATH records its arguments: this machine has no ffmpeg).
#[test]
fn video_hands_the_pattern_to_ffmpeg() {
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path().join("bin");
    std::fs::create_dir(&bin).unwrap();
    let fake = bin.join("ffmpeg");
    std::fs::write(
        &fake,
        "#!/bin/sh\nprintf '%s\\n' \"$@\" > \"$(dirname \"$0\")/args\"\nfor a; do last=$a; done\n: > \"$last\"\n",
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let video = dir.path().join("v.mp4");
    run_ok(
        weft()
            .args([
                "render",
                "--size",
                "32x18",
                "--frames-range",
                "3..5",
                "--fps",
                "30",
            ])
            .arg("-o")
            .arg(dir.path().join("v_%03d.png"))
            .arg("--video")
            .arg(&video)
            .env("PATH", &path),
    );
    let args = std::fs::read_to_string(bin.join("args")).unwrap();
    let args: Vec<&str> = args.lines().collect();
    let after = |flag: &str| args[args.iter().position(|a| *a == flag).unwrap() + 1];
    assert_eq!(after("-framerate"), "30");
    assert_eq!(after("-start_number"), "3");
    assert_eq!(after("-frames:v"), "3");
    assert!(after("-i").ends_with("v_%03d.png"));
    assert!(video.exists());
    // Without ffmpeg: bad input, said before rendering anything.
    let o = weft_without_gpu()
        .args([
            "render",
            "--frames-range",
            "0..1",
            "-o",
            "x%d.png",
            "--video",
            "v.mp4",
        ])
        .env("PATH", "/nonexistent")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("ffmpeg"));
}

/// The temporal bench on a tiny configuration: a row per level and view, the ground truth's
/// ratio 1, and every level's flicker within the triangle-inequality bound it reports (which
/// holds for any images: a failure means the measure and the bound do not use the same pixels or
/// denominators).
#[test]
fn tiny_temporal_bench_reports_every_level_within_its_bound() {
    use weft::bench::temporal::{self, TemporalConfig};
    use weft::render::{Accuracy, WeavePrecision};
    let out = tempfile::tempdir().unwrap();
    let config = TemporalConfig {
        views: vec![weft::bench::View::Mid, weft::bench::View::Far],
        variants: vec![
            (Accuracy::Nearest, WeavePrecision::Rgba16f),
            (Accuracy::Mixture, WeavePrecision::Rgba16f),
        ],
        ground_truth: Accuracy::Supersampled(4),
        size: (96, 54),
        frames: 3,
        degrees_per_frame: 0.5,
        out: out.path().to_path_buf(),
    };
    let mut renderer = weft::render::Renderer::new(common::context()).unwrap();
    let report = temporal::run(&mut renderer, &config).unwrap();
    assert_eq!(report.rows.len(), 2 * 3);
    for r in &report.rows {
        assert!(r.flicker.is_finite() && r.flip.is_finite() && r.error.is_finite());
        let truth = report
            .rows
            .iter()
            .find(|t| t.view == r.view && t.level.is_none())
            .unwrap();
        assert!(
            truth.flicker > 0.0,
            "the camera moved: the ground truth changed"
        );
        // 1e-9: f64 sums of f32 terms in a different order.
        assert!(
            r.flicker <= r.bound(truth.flicker) + 1e-9,
            "{:?}: {} > {}",
            r.level,
            r.flicker,
            r.bound(truth.flicker)
        );
        if r.level.is_none() {
            assert_eq!(r.ratio, 1.0);
            assert_eq!(r.error, 0.0);
        }
    }
    assert!(report.table().contains("mixture rgba16f"));
    assert!(out.path().join("temporal.csv").exists());
    assert!(out.path().join("bench-temporal.png").exists());
}

/// The Dask fan-out end to end (tools/dask-render), when dask.distributed is installed: every
/// frame produced and complete after one task is SIGKILLed midway and retried by Dask, and a bad
/// input not retried. Skipped (and says so) without Dask: `pip install dask distributed`.
#[test]
fn dask_fans_out_retries_a_killed_task_and_not_bad_input() {
    let has_dask = Command::new("python3")
        .args(["-c", "import dask.distributed"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_dask {
        eprintln!("SKIPPED: dask.distributed is not installed (pip install dask distributed)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/dask-render");
    let run = |extra: &[&str], weft_args: &[&str]| {
        let o = Command::new(&tool)
            .args(["--weft", env!("CARGO_BIN_EXE_weft"), "--out"])
            .arg(dir.path())
            .args(["--fresh"])
            .args(extra)
            .arg("--")
            .args(weft_args)
            .env(
                "WEFT_DEVICE",
                std::env::var("WEFT_DEVICE").unwrap_or_else(|_| "cpu".into()),
            )
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
        let summary: serde_json::Value = stdout
            .lines()
            .last()
            .and_then(|l| serde_json::from_str(l).ok())
            .unwrap_or_else(|| {
                panic!(
                    "no summary: {stdout}\n{}",
                    String::from_utf8_lossy(&o.stderr)
                )
            });
        (o.status.code(), summary)
    };
    // One worker, two tasks of 12 frames: a task is running 1 s in (each takes seconds).
    let (code, s) = run(
        &[
            "--frames",
            "0..23",
            "--tasks",
            "2",
            "--workers",
            "1",
            "--kill-one",
            "1.0",
        ],
        &["--size", "160x90", "--orbit", "10"],
    );
    assert_eq!(code, Some(0), "{s}");
    assert_eq!(s["frames_complete"], 24, "{s}");
    assert_eq!(s["missing"].as_array().unwrap().len(), 0, "{s}");
    assert_eq!(s["broken"].as_array().unwrap().len(), 0, "{s}");
    let killed = s["killed"]["task"]
        .as_u64()
        .unwrap_or_else(|| panic!("no task was running to kill: {s}"));
    assert!(
        s["attempts"][killed.to_string()].as_u64().unwrap() >= 2,
        "Dask retried the killed task: {s}"
    );
    // Bad input: exit 2 from weft, not retried.
    let (code, s) = run(
        &["--frames", "0..3", "--tasks", "2", "--workers", "1"],
        &["--size", "0x9"],
    );
    assert_eq!(code, Some(1), "{s}");
    assert_eq!(s["codes"], serde_json::json!([2, 2]), "{s}");
    assert_eq!(s["attempts"], serde_json::json!({"0": 1, "1": 1}), "{s}");
}

/// A sequence of an animated file plays its animation: frame f of the sequence is the picture of
/// a single `weft render --time f/fps` (posed once and uploaded, against posed per frame on the
/// scene uploaded once), and the frames differ as the skin bends.
#[test]
fn a_sequence_plays_the_animation_as_single_renders_pose_it() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/RiggedSimple/glTF-Binary/RiggedSimple.glb");
    let dir = tempfile::tempdir().unwrap();
    run_ok(
        weft()
            .arg("render")
            .arg(&scene)
            .args([
                "--validate",
                "--size",
                "64x48",
                "--frames-range",
                "0..3",
                "--fps",
                "2",
            ])
            .arg("-o")
            .arg(dir.path().join("r%d.png")),
    );
    let frame = |n: u32| std::fs::read(dir.path().join(format!("r{n}.png"))).unwrap();
    assert_ne!(frame(0), frame(2), "the animation moved the skin");
    for (n, t) in [(0u32, "0"), (3, "1.5")] {
        let single = dir.path().join(format!("single{n}.png"));
        run_ok(
            weft()
                .arg("render")
                .arg(&scene)
                .args(["--validate", "--size", "64x48", "--time", t, "-o"])
                .arg(&single),
        );
        assert_eq!(
            std::fs::read(&single).unwrap(),
            frame(n),
            "frame {n} = --time {t}"
        );
    }
}

/// Slurm's numbers at their limits: an array up to 4294967295 has one task more than u32 holds
/// (the count wrapped to 0), and a step of 0 is no array (it was read as 1).
#[test]
fn slurm_arrays_at_the_limits_are_counted_or_refused() {
    let spec = |vars: &[(&str, &str)]| TaskSpec::resolve(None, None, env(vars));
    let e = spec(&[
        ("SLURM_ARRAY_TASK_ID", "7"),
        ("SLURM_ARRAY_TASK_MAX", "4294967295"),
    ])
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("4294967296 tasks") && e.contains("--tasks"),
        "{e}"
    );
    let s = spec(&[
        ("SLURM_ARRAY_TASK_ID", "7"),
        ("SLURM_ARRAY_TASK_MAX", "4294967294"),
    ])
    .unwrap();
    assert_eq!((s.index, s.count), (7, u32::MAX));
    let s = spec(&[
        ("SLURM_ARRAY_TASK_ID", "4294967295"),
        ("SLURM_ARRAY_TASK_MIN", "1"),
        ("SLURM_ARRAY_TASK_MAX", "4294967295"),
    ])
    .unwrap();
    assert_eq!((s.index, s.count), (u32::MAX - 1, u32::MAX));
    let e = spec(&[
        ("SLURM_ARRAY_TASK_ID", "0"),
        ("SLURM_ARRAY_TASK_MAX", "9"),
        ("SLURM_ARRAY_TASK_STEP", "0"),
    ])
    .unwrap_err()
    .to_string();
    assert!(e.contains("SLURM_ARRAY_TASK_STEP is 0"), "{e}");
    let e = spec(&[
        ("SLURM_ARRAY_TASK_ID", "5"),
        ("SLURM_ARRAY_TASK_MIN", "5"),
        ("SLURM_ARRAY_TASK_MAX", "2"),
    ])
    .unwrap_err()
    .to_string();
    assert!(e.contains("below SLURM_ARRAY_TASK_MIN"), "{e}");
}

/// A batch's outputs are checked as a single render's, before any frame (project issue 30):
/// against the inputs, against each other, and for names no file system takes. Each is bad
/// input (exit 2, not 75: a farm would retry a 300-byte name forever), on a node without a
/// driver too, and nothing is written.
#[test]
fn batch_outputs_are_checked_before_any_frame() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = dir.path().join("s_0.glb");
    std::fs::copy(root.join("assets/scenes/spheres.glb"), &scene).unwrap();
    let original = std::fs::read(&scene).unwrap();
    let long = format!("f_%d_{}.png", "n".repeat(300));
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["s_0.glb", "--frames-range", "0..2", "-o", "s_%d.glb"],
            "-o of frame 0 's_0.glb' is 's_0.glb', a file this command reads",
        ),
        (
            vec![
                "--frames-range",
                "0..2",
                "-o",
                "f_%d.png",
                "--exr",
                "f_%d.png",
            ],
            "--exr of frame 0 'f_0.png' and -o of frame 0 'f_0.png' are the same file",
        ),
        (vec!["--frames-range", "0..1", "-o", &long], "at most 255"),
        // Across jobs: frame 10's PNG is frame 0's EXR.
        (
            vec![
                "--frames-range",
                "0..12",
                "-o",
                "x_%d.png",
                "--exr",
                "x_1%d.png",
            ],
            "-o of frame 10 'x_10.png' and --exr of frame 0 'x_10.png' are the same file",
        ),
    ];
    for (args, expect) in &cases {
        let o = weft_without_gpu()
            .current_dir(dir.path())
            .arg("render")
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(!err.contains("Vulkan"), "{args:?}: {err}");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["s_0.glb"], "{args:?}");
    }
    assert_eq!(std::fs::read(&scene).unwrap(), original);
}

/// `--resume` skips a job only when all its outputs are there (defect 5): a frame whose PNG is
/// whole but whose requested EXR is missing or cut short is rendered again.
#[test]
fn resume_renders_a_frame_again_when_its_exr_is_missing_or_truncated() {
    let dir = tempfile::tempdir().unwrap();
    let render = |extra: &[&str]| {
        let mut c = weft();
        c.current_dir(dir.path())
            .args([
                "render",
                "--size",
                "32x18",
                "--frames-range",
                "0..2",
                "--metrics-json",
            ])
            .args(["-o", "f_%d.png"])
            .args(extra);
        c
    };
    run_ok(&mut render(&[]));
    let exr = |n: u32| dir.path().join(format!("f_{n}.exr"));
    // The job again with --exr added: every EXR is missing, so every frame is rendered.
    let o = run_ok(&mut render(&["--exr", "f_%d.exr", "--resume"]));
    let status: Vec<_> = metrics(&o.stdout)
        .iter()
        .map(|m| m["status"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(status, ["rendered", "rendered", "rendered"]);
    for n in 0..3 {
        assert!(sequence::frame_done(&exr(n), 32, 18), "frame {n}'s EXR");
    }
    // One EXR cut short, one removed: those two frames again, the third skipped.
    let whole = std::fs::read(exr(0)).unwrap();
    std::fs::write(exr(0), &whole[..whole.len() / 2]).unwrap();
    std::fs::remove_file(exr(2)).unwrap();
    let o = run_ok(&mut render(&["--exr", "f_%d.exr", "--resume"]));
    let status: Vec<_> = metrics(&o.stdout)
        .iter()
        .map(|m| m["status"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(status, ["rendered", "skipped", "rendered"]);
    assert_eq!(std::fs::read(exr(0)).unwrap(), whole);
    assert!(sequence::frame_done(&exr(2), 32, 18));
}
