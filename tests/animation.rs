//! glTF animation: the Khronos skinning and morph samples load with their animations and pose;
//! the GPU's skinned and morphed vertices (glsl/skin.comp) match the CPU twin
//! (`Scene::deformed_vertices`) on the same inputs, tangents included; bad animation data is an
//! error or a warning, never a panic. The sampling arithmetic itself is unit-tested in
//! src/scene/animation.rs against hand-computed values.

mod common;

use std::path::Path;

use glam::{Mat4, Vec3};
use weft::render::Renderer;
use weft::scene::{self, Scene};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

const RIGGED_SIMPLE: &str = "tests/data/khronos/RiggedSimple/glTF-Binary/RiggedSimple.glb";
const SIMPLE_SKIN: &str = "tests/data/khronos/SimpleSkin/glTF/SimpleSkin.gltf";
const MORPH_CUBE: &str = "tests/data/khronos/AnimatedMorphCube/glTF-Binary/AnimatedMorphCube.glb";
const SKINNED_CLOTH: &str = "assets/scenes/skinned_cloth.glb";

fn load(path: &str) -> Scene {
    scene::load(&root().join(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

#[test]
fn khronos_samples_list_their_animations() {
    // Durations: the last keyframe time of each file's input accessors ("max" in the files).
    for (path, name, duration) in [
        (RIGGED_SIMPLE, "animation 0", 2.083_333),
        (SIMPLE_SKIN, "animation 0", 5.5),
        (MORPH_CUBE, "Square", 4.199_997),
        (SKINNED_CLOTH, "bend", 2.0),
    ] {
        let s = load(path);
        let a = s.animations();
        assert_eq!(a.len(), 1, "{path}");
        assert_eq!(a[0].name, name, "{path}");
        assert!(
            (a[0].duration - duration).abs() < 1e-4,
            "{path}: {}",
            a[0].duration
        );
        assert!(
            !s.warnings
                .iter()
                .any(|w| w.0.contains("skin") || w.0.contains("morph")),
            "{path}: {:?}",
            s.warnings
        );
    }
}

#[test]
fn pose_is_a_function_of_the_time_alone() {
    let mut s = load(SKINNED_CLOTH);
    let rest = s.deformed_vertices(0).expect("the strip is skinned");
    s.pose(0, 1.0).unwrap();
    let bent = s.deformed_vertices(0).unwrap();
    s.pose(0, 0.3).unwrap();
    s.pose(0, 1.0).unwrap();
    assert_eq!(bent, s.deformed_vertices(0).unwrap());
    // At t = 0 every rotation is the identity: the rest pose, which is the bind pose.
    s.pose(0, 0.0).unwrap();
    let zero = s.deformed_vertices(0).unwrap();
    for (a, b) in zero.iter().zip(&rest) {
        for k in 0..3 {
            assert!((a.position[k] - b.position[k]).abs() < 1e-6);
        }
    }
    // Clamped outside [0, duration]: before 0 as at 0, after 2 s as at 2 s.
    s.pose(0, -5.0).unwrap();
    assert_eq!(zero, s.deformed_vertices(0).unwrap());
    s.pose(0, 2.0).unwrap();
    let end = s.deformed_vertices(0).unwrap();
    s.pose(0, 100.0).unwrap();
    assert_eq!(end, s.deformed_vertices(0).unwrap());
    assert!(s.pose(1, 0.0).is_err(), "there is only animation 0");
    assert!(s.pose(0, f32::NAN).is_err());
    assert_eq!(s.find_animation("bend").unwrap(), 0);
    assert_eq!(s.find_animation("0").unwrap(), 0);
    let e = s.find_animation("wave").unwrap_err().to_string();
    assert!(e.contains("0 'bend'"), "{e}");
}

#[test]
fn the_skinned_strip_bends_as_its_joints_turn() {
    // At t = 1 the middle joint (x = 0) has turned 50 degrees about z: a vertex at x = 0.3 (well
    // past the blend zone [-0.1, 0.1] and before the last joint's [0.3, 0.5]) is carried by it
    // alone, to (0.3 cos 50°, 0.3 sin 50°, z).
    let mut s = load(SKINNED_CLOTH);
    s.pose(0, 1.0).unwrap();
    let rest = &s.meshes[s.draws[0].mesh].vertices;
    let posed = s.deformed_vertices(0).unwrap();
    let a = 50f32.to_radians();
    let mut checked = 0;
    for (r, p) in rest.iter().zip(&posed) {
        if (r.position[0] - 0.275).abs() < 0.03 {
            let x = r.position[0];
            let expect = Vec3::new(x * a.cos(), x * a.sin(), r.position[2]);
            assert!(
                (Vec3::from(p.position) - expect).length() < 1e-5,
                "{:?}",
                p.position
            );
            // The thread direction (tangent, +x at rest) turns with it.
            let t = Vec3::new(p.tangent[0], p.tangent[1], p.tangent[2]);
            assert!(
                (t - Vec3::new(a.cos(), a.sin(), 0.0)).length() < 1e-5,
                "{t}"
            );
            assert_eq!(p.tangent[3], r.tangent[3]);
            checked += 1;
        }
    }
    assert!(checked >= 9, "{checked} vertices near x = 0.275");
}

#[test]
fn morph_weights_follow_the_animation() {
    let mut s = load(MORPH_CUBE);
    let b = s
        .rig
        .binding(0)
        .expect("the cube is placed by a node")
        .clone();
    assert_eq!(b.weights, [0.0, 0.0], "the mesh's default weights");
    // The deformed positions are the base plus the weighted deltas (by hand from the rig data).
    for t in [0.5f32, 1.7, 3.3] {
        s.pose(0, t).unwrap();
        let w = s.rig.binding(0).unwrap().weights.clone();
        assert!(w.iter().any(|&x| x > 0.01), "t = {t}: {w:?}");
        let deform = &s.rig.meshes[&s.draws[0].mesh];
        let posed = s.deformed_vertices(0).unwrap();
        for (i, (v, p)) in s.meshes[s.draws[0].mesh]
            .vertices
            .iter()
            .zip(&posed)
            .enumerate()
        {
            let mut expect = Vec3::from(v.position);
            for (k, target) in deform.targets.iter().enumerate() {
                expect += Vec3::from(target.positions[i]) * w[k];
            }
            assert!((Vec3::from(p.position) - expect).length() < 1e-7);
        }
    }
}

/// Largest differences between the GPU's posed vertices and the CPU twin's: position (relative
/// to the draw's size), normal and tangent (as lengths of the difference of unit vectors), and
/// whether every handedness agrees.
fn gpu_against_cpu(renderer: &Renderer, scene: &Scene, draw: usize) -> (f32, f32, f32, bool) {
    let mut gpu = renderer.upload(scene).expect("upload");
    renderer.update_pose(&mut gpu, scene).expect("update_pose");
    let posed = gpu.posed_vertices(draw).unwrap().expect("a deforming draw");
    let cpu = scene.deformed_vertices(draw).unwrap();
    assert_eq!(posed.len(), cpu.len());
    let size = cpu
        .iter()
        .map(|v| Vec3::from(v.position).length())
        .fold(0.0f32, f32::max)
        .max(1e-6);
    let (mut dp, mut dn, mut dt, mut w) = (0f32, 0f32, 0f32, true);
    for (g, c) in posed.iter().zip(&cpu) {
        let v3 = |a: &[f32]| Vec3::new(a[0], a[1], a[2]);
        dp = dp.max((v3(&g[0..3]) - Vec3::from(c.position)).length() / size);
        dn = dn.max((v3(&g[3..6]) - Vec3::from(c.normal)).length());
        dt = dt.max((v3(&g[6..9]) - v3(&c.tangent)).length());
        w &= g[9] == c.tangent[3];
        // The parts the pass does not touch are the mesh's.
        assert_eq!(&g[10..12], &c.uv);
    }
    (dp, dn, dt, w)
}

#[test]
fn gpu_skinning_and_morphing_match_the_cpu_twin() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let cases: [(&str, &[f32]); 4] = [
        (SKINNED_CLOTH, &[0.5, 1.0, 1.6]),
        (RIGGED_SIMPLE, &[0.4, 1.2]),
        (SIMPLE_SKIN, &[1.0, 3.5]),
        (MORPH_CUBE, &[1.0, 3.0]),
    ];
    for (path, times) in cases {
        let mut s = load(path);
        let draw = (0..s.draws.len())
            .find(|&d| s.deformed_vertices(d).is_some())
            .expect("a deforming draw");
        for &t in times {
            s.pose(0, t).unwrap();
            let (dp, dn, dt, w) = gpu_against_cpu(&renderer, &s, draw);
            println!(
                "{path} t = {t}: position {dp:.2e} (relative), normal {dn:.2e}, tangent {dt:.2e}"
            );
            // Bounds: both sides compute the same f32 expressions in the same order (weighted sum
            // of four matrices, then matrix × vector); what differs is fused multiply-adds and the
            // GPU's inverse square root, a few ulps per operation over ~20 operations: 1e-5 is
            // ~80 ulps of a unit vector, far below a visible error (an 8-bit debug view resolves
            // 4e-3) and far above f32 noise.
            assert!(dp < 1e-5, "{path} t = {t}: positions differ by {dp}");
            assert!(dn < 1e-5, "{path} t = {t}: normals differ by {dn}");
            assert!(dt < 1e-5, "{path} t = {t}: tangents differ by {dt}");
            assert!(w, "{path} t = {t}: a handedness differs");
        }
    }
    // A pose on an uploaded scene re-uploads only the pose: the same GpuScene, posed twice,
    // holds the second pose.
    let mut s = load(SKINNED_CLOTH);
    let mut gpu = renderer.upload(&s).unwrap();
    s.pose(0, 1.6).unwrap();
    renderer.update_pose(&mut gpu, &s).unwrap();
    s.pose(0, 0.7).unwrap();
    renderer.update_pose(&mut gpu, &s).unwrap();
    let posed = gpu.posed_vertices(0).unwrap().unwrap();
    let cpu = s.deformed_vertices(0).unwrap();
    for (g, c) in posed.iter().zip(&cpu) {
        assert!((Vec3::new(g[0], g[1], g[2]) - Vec3::from(c.position)).length() < 1e-5);
    }
    // And the frame renders it without validation messages.
    let options = weft::render::RenderOptions {
        width: 64,
        height: 36,
        ..Default::default()
    };
    renderer.render_frame(&s, &gpu, &options).expect("frame");
}

#[test]
fn rendered_thread_directions_follow_the_skin() {
    // The G-buffer's tangent at pixels of the bent strip against the CPU-skinned tangent of the
    // strip part under that pixel: where a joint carries the strip alone (x in [0.15, 0.25] at
    // rest), the tangent must be (cos 50°, sin 50°, 0) at t = 1, not the rest pose's +x.
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let mut s = load(SKINNED_CLOTH);
    s.pose(0, 1.0).unwrap();
    let (w, h) = (256u32, 144u32);
    let options = weft::render::RenderOptions {
        width: w,
        height: h,
        ..Default::default()
    };
    let camera = s.camera(None).unwrap();
    let frame_data = weft::render::gpu::FrameData::new(&camera, w, h);
    let view_proj = Mat4::from_cols_array_2d(&frame_data.view_proj);
    renderer.render(&s, &options).expect("frame");
    let g = renderer.read_gbuffer().unwrap();
    let a = 50f32.to_radians();
    let expect = Vec3::new(a.cos(), a.sin(), 0.0);
    let rest = &s.meshes[s.draws[0].mesh].vertices;
    let posed = s.deformed_vertices(0).unwrap();
    let mut checked = 0;
    let mut worst = 0f32;
    for (r, p) in rest.iter().zip(&posed) {
        if !(0.15..=0.25).contains(&r.position[0]) || r.position[2].abs() > 0.15 {
            continue;
        }
        let clip = view_proj * Vec3::from(p.position).extend(1.0);
        let ndc = clip.truncate() / clip.w;
        let (x, y) = (
            ((ndc.x * 0.5 + 0.5) * w as f32) as usize,
            ((ndc.y * 0.5 + 0.5) * h as f32) as usize,
        );
        if x >= w as usize || y >= h as usize {
            continue;
        }
        let i = y * w as usize + x;
        if g.depth[i] <= 0.0 {
            continue;
        }
        let t = weft::reference::shading::oct_decode([g.frame[4 * i + 2], g.frame[4 * i + 3]]);
        worst = worst.max((Vec3::from(t) - expect).length());
        checked += 1;
    }
    println!("{checked} pixels, worst tangent difference {worst:.2e}");
    assert!(checked >= 6, "only {checked} pixels checked");
    // Bound: the G-buffer stores the tangent as a 16-bit octahedral pair (a quantum of 3e-5 rad),
    // interpolated across a triangle whose three vertices have this same tangent (the region is
    // rigidly carried): 1e-3 covers the encoding; the rest pose's +x would be off by 0.85.
    assert!(
        worst < 1e-3,
        "rendered tangent off the skinned one by {worst}"
    );
}

// --- bad animation data ---------------------------------------------------------------------------

/// A glTF binary buffer built accessor by accessor: each `push` appends a 4-byte aligned buffer
/// view holding `bytes` and an accessor on it (`acc` without its bufferView), and returns the
/// accessor's index.
#[derive(Default)]
struct Buffer {
    bin: Vec<u8>,
    views: Vec<serde_json::Value>,
    accessors: Vec<serde_json::Value>,
}

impl Buffer {
    fn push(&mut self, bytes: &[u8], mut acc: serde_json::Value) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        self.views.push(
            serde_json::json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}),
        );
        self.bin.extend_from_slice(bytes);
        acc["bufferView"] = serde_json::json!(self.views.len() - 1);
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// The triangle (0,0,0), (1,0,0), (0,1,0)'s POSITION accessor.
    fn triangle(&mut self) -> usize {
        self.push(
            &f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            serde_json::json!({"componentType": 5126, "count": 3, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}),
        )
    }
}

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A minimal .gltf: one triangle skinned to `joints` joints (all at the origin), with vertex 0
/// bound to joint `bound`, and one animation channel on joint 0's rotation with `times` and
/// `values` (raw f32s; `rotations` quaternions).
fn skinned_gltf(joints: usize, bound: u16, times: &[f32], rotations: usize) -> Vec<u8> {
    let mut b = Buffer::default();
    let pos = b.triangle();
    let j: Vec<u8> = [bound, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let joints_acc = b.push(
        &j,
        serde_json::json!({"componentType": 5123, "count": 3, "type": "VEC4"}),
    );
    let weights = b.push(
        &f32s(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]),
        serde_json::json!({"componentType": 5126, "count": 3, "type": "VEC4"}),
    );
    let input = b.push(
        &f32s(times),
        serde_json::json!({"componentType": 5126, "count": times.len(), "type": "SCALAR",
            "min": [times.iter().copied().fold(f32::INFINITY, f32::min)],
            "max": [times.iter().copied().fold(f32::NEG_INFINITY, f32::max)]}),
    );
    let q: Vec<f32> = (0..rotations).flat_map(|_| [0.0, 0.0, 0.0, 1.0]).collect();
    let output = b.push(
        &f32s(&q),
        serde_json::json!({"componentType": 5126, "count": rotations, "type": "VEC4"}),
    );
    let mut nodes = vec![serde_json::json!({"mesh": 0, "skin": 0})];
    nodes.extend((0..joints).map(|_| serde_json::json!({})));
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": (0..=joints).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "JOINTS_0": joints_acc, "WEIGHTS_0": weights}}]}],
        "skins": [{"joints": (1..=joints).collect::<Vec<_>>()}],
        "animations": [{"channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}],
                        "samplers": [{"input": input, "output": output}]}],
        "buffers": [{"byteLength": b.bin.len()}],
        "bufferViews": b.views,
        "accessors": b.accessors,
    });
    // A .glb: header, JSON chunk (space-padded), BIN chunk (zero-padded).
    common::glb(&serde_json::to_vec(&doc).unwrap(), &b.bin)
}

fn load_bytes(bytes: &[u8]) -> weft::Result<Scene> {
    scene::load_slice(bytes, "test.glb", None)
}

#[test]
fn a_well_formed_skin_loads_and_poses() {
    let mut s = load_bytes(&skinned_gltf(2, 1, &[0.0, 1.0], 2)).expect("valid file");
    assert!(
        s.warnings.iter().all(|w| !w.0.contains("animation")),
        "{:?}",
        s.warnings
    );
    assert_eq!(s.animations()[0].duration, 1.0);
    s.pose(0, 0.5).unwrap();
}

#[test]
fn sampler_count_mismatch_is_a_warning_and_the_channel_is_dropped() {
    let s = load_bytes(&skinned_gltf(2, 1, &[0.0, 1.0, 2.0], 2)).expect("the scene still loads");
    let w: Vec<_> = s.warnings.iter().map(|w| w.0.as_str()).collect();
    assert!(
        w.iter()
            .any(|w| w.contains("animation 'animation 0' channel 0")
                && w.contains("3 keyframe times but 2 output values")
                && w.contains("ignored")),
        "{w:?}"
    );
    assert_eq!(s.animations()[0].duration, 0.0, "no usable channel left");
}

#[test]
fn non_increasing_times_are_a_warning() {
    let s = load_bytes(&skinned_gltf(2, 1, &[0.0, 1.0, 1.0], 3)).expect("the scene still loads");
    assert!(
        s.warnings.iter().any(|w| w.0.contains("do not increase")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn joint_index_out_of_range_is_an_error() {
    let e = load_bytes(&skinned_gltf(2, 5, &[0.0, 1.0], 2))
        .expect_err("vertex bound to joint 5 of 2")
        .to_string();
    assert!(
        e.contains("bound to joint 5") && e.contains("only 2 joint(s)"),
        "{e}"
    );
}

#[test]
fn too_many_joints_is_an_error() {
    let e = load_bytes(&skinned_gltf(
        weft::scene::animation::MAX_JOINTS + 1,
        0,
        &[0.0],
        1,
    ))
    .expect_err("65537 joints")
    .to_string();
    assert!(
        e.contains("65537 joints") && e.contains("limit of 65536"),
        "{e}"
    );
}

// --- bad animation data, round two (project issue 30) -----------------------------------------

fn malformed(name: &str) -> std::path::PathBuf {
    root().join("tests/malformed").join(name)
}

/// A channel whose target node does not exist made the gltf crate panic while weft walked the
/// animation; weft turned the panic into an error, but printed its text and a backtrace first.
/// Now the channel is checked before the crate sees it, and dropped with a warning naming it,
/// as every other bad channel is. `weft plan` and `weft render` print no panic text.
#[test]
fn a_channel_to_a_missing_node_is_dropped_with_a_warning_naming_it() {
    let path = malformed("animation-target-missing-node.gltf");
    let s = scene::load(&path).expect("the scene still loads");
    assert!(
        s.warnings.iter().any(
            |w| w.0.contains("animation 'broken' channel 0 targets node 99")
                && w.0.contains("only 2 node(s)")
                && w.0.contains("ignored")
        ),
        "{:?}",
        s.warnings
    );
    assert_eq!(s.animations()[0].duration, 0.0, "no usable channel left");
    let dir = tempfile::tempdir().unwrap();
    for args in [
        vec!["plan".to_string()],
        vec![
            "render".to_string(),
            "--size".into(),
            "16x9".into(),
            "-o".into(),
            dir.path().join("o.png").display().to_string(),
        ],
    ] {
        let o = common::weft()
            .args(&args)
            .arg(&path)
            .env("RUST_BACKTRACE", "1")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert!(
            err.contains("warning: ") && err.contains("targets node 99"),
            "{err}"
        );
        assert!(
            !err.contains("panicked") && !err.contains("backtrace") && !err.contains("unwrap"),
            "{args:?}: {err}"
        );
    }
}

/// A zero-length rotation keyframe drops the channel with a warning (LINEAR failed the whole
/// render, blaming "an animated scale or translation"; STEP collapsed the node): posed anywhere,
/// the node stays at rest.
#[test]
fn zero_length_rotation_keyframes_drop_the_channel() {
    for file in [
        "animation-zero-rotation-linear.gltf",
        "animation-zero-rotation-step.gltf",
    ] {
        let mut s = scene::load(&malformed(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(
            s.warnings.iter().any(|w| w.0.contains("channel 0 rotates by the quaternion [0.0, 0.0, 0.0, 0.0] at keyframe 1, which has zero length")),
            "{file}: {:?}",
            s.warnings
        );
        let rest = s.draws[0].world;
        for t in [0.0, 0.5, 1.0, 2.0] {
            s.pose(0, t)
                .unwrap_or_else(|e| panic!("{file} at {t}: {e}"));
            assert_eq!(s.draws[0].world, rest, "{file} at {t}");
        }
    }
    // A usable rotation that is not unit length is normalised, not applied as a scale.
    let c = weft::scene::animation::Channel::new(
        0,
        weft::scene::animation::Path::Rotation,
        weft::scene::animation::Interpolation::Step,
        vec![0.0],
        vec![0.0, 0.0, 0.0, 2.0],
        4,
    )
    .unwrap();
    assert_eq!(c.sampler.values, [0.0, 0.0, 0.0, 1.0]);
}

/// A weights channel's count mismatch is reported in the accessor's own units: 2 keyframes of 2
/// targets need 4 scalars; the file has 3 (the message said "1 output values": 3 / 2).
#[test]
fn a_weights_channel_counts_its_scalars() {
    let s = scene::load(&malformed("animation-weights-count-mismatch.gltf")).unwrap();
    assert!(
        s.warnings.iter().any(|w| w.0.contains(
            "2 keyframe times but 3 output values; Linear interpolation needs 2 value(s) per keyframe (4 in all)"
        )),
        "{:?}",
        s.warnings
    );
}

/// Finite weights times finite deltas can overflow; so can finite joint matrices. Each product
/// is checked where it is made: at load (the rest pose) and at every pose, with an error naming
/// the mesh, instead of a mesh that vanishes.
#[test]
fn deformations_that_overflow_are_errors_naming_the_mesh() {
    for (file, fragment) in [
        (
            "skin-joint-matrix-overflow.gltf",
            "skin 'huge': the matrix of joint 0",
        ),
        (
            "morph-weight-overflow.gltf",
            "mesh 'quad' (node 0): its morph targets (weights [3e38]",
        ),
    ] {
        let e = scene::load(&malformed(file)).expect_err(file).to_string();
        assert!(e.contains(fragment) && e.contains(file), "{file}: {e}");
    }
    // At rest the animated weight is 0: the scene loads; half way it is 1.5e38 on a 3e38 delta.
    let mut s = scene::load(&malformed("animation-morph-weight-overflow.gltf")).unwrap();
    s.pose(0, 0.0).unwrap();
    let e = s
        .pose(0, 0.5)
        .expect_err("overflows at t = 0.5")
        .to_string();
    assert!(
        e.contains("mesh 'quad' (node 0): its morph targets")
            && e.contains("out of the range of 32-bit floating point in this pose"),
        "{e}"
    );
}

// --- more than four joint influences -------------------------------------------------------------

/// One triangle skinned to 6 joints through JOINTS_0/WEIGHTS_0 and JOINTS_1/WEIGHTS_1, the
/// given (joint, weight) lists per set for every vertex.
fn eight_influence_gltf(set0: [(u16, f32); 4], set1: [(u16, f32); 4]) -> Vec<u8> {
    let mut b = Buffer::default();
    let pos = b.triangle();
    let mut attributes = serde_json::json!({"POSITION": pos});
    for (k, set) in [set0, set1].iter().enumerate() {
        let joints: Vec<u8> = (0..3)
            .flat_map(|_| set.iter().flat_map(|(j, _)| j.to_le_bytes()))
            .collect();
        let weights: Vec<f32> = (0..3).flat_map(|_| set.map(|(_, w)| w)).collect();
        attributes[format!("JOINTS_{k}")] = serde_json::json!(b.push(
            &joints,
            serde_json::json!({"componentType": 5123, "count": 3, "type": "VEC4"})
        ));
        attributes[format!("WEIGHTS_{k}")] = serde_json::json!(b.push(
            &f32s(&weights),
            serde_json::json!({"componentType": 5126, "count": 3, "type": "VEC4"})
        ));
    }
    let mut nodes = vec![serde_json::json!({"mesh": 0, "skin": 0})];
    nodes.extend((0..6).map(|_| serde_json::json!({})));
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": (0..=6).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": attributes}]}],
        "skins": [{"joints": (1..=6).collect::<Vec<_>>()}],
        "buffers": [{"byteLength": b.bin.len()}],
        "bufferViews": b.views,
        "accessors": b.accessors,
    });
    common::glb(&serde_json::to_vec(&doc).unwrap(), &b.bin)
}

#[test]
fn a_second_set_of_joints_keeps_each_vertex_four_strongest_influences() {
    // Joint 2 appears in both sets (0.1 + 0.2 = 0.3, the strongest); the two weakest (joints 3
    // and 5, 0.05 and 0.02) are left out, and the four kept are scaled to sum to 1.
    let s = load_bytes(&eight_influence_gltf(
        [(0, 0.2), (2, 0.1), (3, 0.05), (4, 0.15)],
        [(1, 0.25), (2, 0.2), (5, 0.02), (0, 0.0)],
    ))
    .expect("valid file");
    let deform = &s.rig.meshes[&0];
    let kept = 0.3 + 0.25 + 0.2 + 0.15;
    for v in &deform.skin {
        assert_eq!(v.joints, [2, 1, 0, 4]);
        for (w, want) in v.weights.iter().zip([0.3, 0.25, 0.2, 0.15]) {
            assert!((w - want / kept).abs() < 1e-6, "{:?}", v.weights);
        }
    }
    // 0.05 of a total 0.97 left out: the warning names the share and a vertex.
    assert!(
        s.warnings
            .iter()
            .any(|w| w.0.contains("2 sets of JOINTS/WEIGHTS") && w.0.contains("5 % of vertex 0")),
        "{:?}",
        s.warnings
    );

    // Four influences in all, spread over the two sets: nothing is left out, no warning.
    let s = load_bytes(&eight_influence_gltf(
        [(0, 0.5), (1, 0.0), (0, 0.0), (0, 0.0)],
        [(3, 0.25), (5, 0.125), (4, 0.125), (0, 0.0)],
    ))
    .expect("valid file");
    for v in &s.rig.meshes[&0].skin {
        assert_eq!(v.joints, [0, 3, 4, 5]);
        assert_eq!(v.weights, [0.5, 0.25, 0.125, 0.125]);
    }
    assert!(
        s.warnings.iter().all(|w| !w.0.contains("JOINTS")),
        "{:?}",
        s.warnings
    );
}
