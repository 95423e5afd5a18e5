//! The SPIR-V shader package (`weft::package`): every module passes `spirv-val`, the reflected
//! manifest agrees with the pipelines the renderer builds and with an independent disassembly,
//! the package is byte-for-byte reproducible, and the manifest's content is complete.
//!
//! `spirv-val` and `spirv-dis` come from the `spirv-tools` package (tools/setup installs it); a
//! missing tool fails the test, it does not skip it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

use weft::package::{self, DescriptorKind, Manifest, ModuleEntry};
use weft::render::Renderer;
use weft::vk::{shaders, BindingKind, Context, ContextOptions, DeviceChoice, Stage, Stages};

/// Modules no renderer pipeline uses: they exist for other programs and for tests.
const STANDALONE: &[&str] = &[
    "env_probe.comp",
    "fabric_probe.comp",
    "ibl_probe.comp",
    "pbr_probe.comp",
];

fn write_temp() -> (tempfile::TempDir, Manifest) {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let manifest = package::write_package(dir.path()).expect("write the package");
    (dir, manifest)
}

/// Runs a spirv-tools binary; a missing one fails with what to install.
fn spirv_tool(tool: &str, args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(tool).args(args).output().unwrap_or_else(|e| {
        panic!("cannot run `{tool}` ({e}): install the spirv-tools package with tools/setup (or `sudo apt-get install spirv-tools`)")
    })
}

#[test]
fn every_module_passes_spirv_val_for_vulkan_1_3() {
    let (dir, manifest) = write_temp();
    let mut failures = Vec::new();
    for m in &manifest.modules {
        let path = dir.path().join(&m.file);
        let out = spirv_tool(
            "spirv-val",
            &[
                "--target-env".as_ref(),
                "vulkan1.3".as_ref(),
                path.as_os_str(),
            ],
        );
        if !out.status.success() {
            failures.push(format!(
                "{}: {}{}",
                m.file,
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "spirv-val rejected:\n{}",
        failures.join("\n")
    );
}

/// What `spirv-dis` says of a module: (set, binding) of every decorated variable, LocalSize, and
/// the SPIR-V version: an oracle independent of weft's reader.
fn disassembled(path: &Path) -> (BTreeSet<(u32, u32)>, Option<[u32; 3]>, String) {
    let out = spirv_tool("spirv-dis", &["--raw-id".as_ref(), path.as_os_str()]);
    assert!(
        out.status.success(),
        "spirv-dis {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("UTF-8 disassembly");
    let mut sets: BTreeMap<String, u32> = BTreeMap::new();
    let mut bindings: BTreeMap<String, u32> = BTreeMap::new();
    let mut local_size = None;
    let mut version = String::new();
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["OpDecorate", id, "DescriptorSet", n] => {
                sets.insert(id.to_string(), n.parse().expect("a set number"));
            }
            ["OpDecorate", id, "Binding", n] => {
                bindings.insert(id.to_string(), n.parse().expect("a binding number"));
            }
            ["OpExecutionMode", _, "LocalSize", x, y, z] => {
                local_size = Some([x.parse().unwrap(), y.parse().unwrap(), z.parse().unwrap()]);
            }
            [";", "Version:", v] => version = v.to_string(),
            _ => {}
        }
    }
    let pairs = bindings
        .iter()
        .map(|(id, b)| (*sets.get(id).expect("a binding without a set"), *b))
        .collect();
    (pairs, local_size, version)
}

#[test]
fn reflection_agrees_with_the_disassembler() {
    let (dir, manifest) = write_temp();
    for m in &manifest.modules {
        let (pairs, local_size, version) = disassembled(&dir.path().join(&m.file));
        let reflected: BTreeSet<(u32, u32)> =
            m.bindings.iter().map(|b| (b.set, b.binding)).collect();
        assert_eq!(reflected, pairs, "{}: descriptor bindings", m.name);
        assert_eq!(
            m.workgroup_size.map(|w| w.size),
            local_size,
            "{}: LocalSize",
            m.name
        );
        assert_eq!(m.spirv_version, version, "{}: SPIR-V version", m.name);
    }
}

fn binding_kind(kind: DescriptorKind) -> Option<BindingKind> {
    match kind {
        DescriptorKind::UniformBuffer => Some(BindingKind::UniformBuffer),
        DescriptorKind::StorageBuffer => Some(BindingKind::StorageBuffer),
        // weft's SampledImage is a combined image sampler.
        DescriptorKind::CombinedImageSampler => Some(BindingKind::SampledImage),
        DescriptorKind::StorageImage => Some(BindingKind::StorageImage),
        _ => None,
    }
}

/// The stages a weft `Stages` value holds (the flag bits are private to weft::vk).
fn stages_of(s: Stages) -> Vec<Stage> {
    if s == Stages::VERTEX {
        vec![Stage::Vertex]
    } else if s == Stages::FRAGMENT {
        vec![Stage::Fragment]
    } else if s == Stages::COMPUTE {
        vec![Stage::Compute]
    } else if s == Stages::GRAPHICS {
        vec![Stage::Vertex, Stage::Fragment]
    } else {
        panic!("a binding's stages are none of the named Stages constants: {s:?}")
    }
}

#[test]
fn manifest_matches_the_renderers_pipelines() {
    let manifest = package::manifest().expect("reflect the embedded modules");
    let ctx = Context::new(&ContextOptions {
        validate: true,
        device: DeviceChoice::Cpu,
    })
    .expect("a lavapipe device with the validation layer (run tools/setup)");
    let mut renderer = Renderer::new(ctx).expect("renderer");
    let mut used = BTreeSet::new();
    for p in renderer.pipelines().expect("the default pipeline variants") {
        let modules: Vec<&ModuleEntry> = p
            .shaders
            .iter()
            .map(|s| {
                manifest.module(s).unwrap_or_else(|| {
                    panic!("pipeline {} uses {s}, which the manifest lacks", p.name)
                })
            })
            .collect();
        used.extend(p.shaders.iter().copied());

        // The union of the modules' bindings, by (set, binding), with the stages that use each.
        let mut reflected: BTreeMap<(u32, u32), (BindingKind, Vec<Stage>)> = BTreeMap::new();
        for m in &modules {
            for b in &m.bindings {
                let kind = binding_kind(b.kind).unwrap_or_else(|| {
                    panic!(
                        "{} set {} binding {}: {:?} has no weft BindingKind",
                        m.name, b.set, b.binding, b.kind
                    )
                });
                let entry = reflected
                    .entry((b.set, b.binding))
                    .or_insert((kind, Vec::new()));
                assert_eq!(
                    entry.0, kind,
                    "pipeline {}: modules disagree on set {} binding {}",
                    p.name, b.set, b.binding
                );
                entry.1.push(m.stage);
            }
        }
        let layout: BTreeMap<(u32, u32), (BindingKind, Vec<Stage>)> = p
            .sets
            .iter()
            .enumerate()
            .flat_map(|(set, bindings)| {
                bindings
                    .iter()
                    .map(move |b| ((set as u32, b.binding), (b.kind, stages_of(b.stages))))
            })
            .collect();
        let kinds = |m: &BTreeMap<(u32, u32), (BindingKind, Vec<Stage>)>| -> Vec<((u32, u32), BindingKind)> {
            m.iter().map(|(k, v)| (*k, v.0)).collect()
        };
        if kinds(&layout) != kinds(&reflected) {
            // A module compiled from another's body with one constant fixed may be bound with
            // that module's set layouts: then they are exactly the parent's, and the module's
            // own bindings are among them.
            let parents: Vec<&str> = p
                .shaders
                .iter()
                .map(|s| {
                    package::SPEC_MEANINGS_OF
                        .iter()
                        .find(|o| o.0 == *s)
                        .map_or(*s, |o| o.1)
                })
                .collect();
            let mut of_parents: BTreeMap<(u32, u32), BindingKind> = BTreeMap::new();
            for name in &parents {
                let m = manifest.module(name).expect("the parent module");
                for b in &m.bindings {
                    of_parents.insert((b.set, b.binding), binding_kind(b.kind).unwrap());
                }
            }
            assert_eq!(
                kinds(&layout),
                of_parents.into_iter().collect::<Vec<_>>(),
                "pipeline {}: set layouts (left) vs the bindings reflected from its modules {:?} or the modules they are compiled from {parents:?} (right)",
                p.name,
                p.shaders
            );
            for (key, kind) in kinds(&reflected) {
                assert_eq!(
                    layout.get(&key).map(|l| l.0),
                    Some(kind),
                    "pipeline {}: set {} binding {} is not in its layouts as {kind:?}",
                    p.name,
                    key.0,
                    key.1
                );
            }
        }
        for (key, (_, stages)) in &reflected {
            let visible = &layout[key].1;
            assert!(
                stages.iter().all(|s| visible.contains(s)),
                "pipeline {}: set {} binding {} is used by {stages:?} but visible only to {visible:?}",
                p.name,
                key.0,
                key.1
            );
        }

        let push_end = modules
            .iter()
            .filter_map(|m| m.push_constants.map(|r| r.offset + r.size))
            .max()
            .unwrap_or(0);
        assert_eq!(
            p.push_constant_size, push_end,
            "pipeline {}: push-constant size vs reflected",
            p.name
        );

        let declared: BTreeSet<u32> = modules
            .iter()
            .flat_map(|m| m.spec_constants.iter().map(|c| c.constant.id))
            .collect();
        for (id, _) in &p.constants {
            assert!(
                declared.contains(id),
                "pipeline {} specialises constant {id}, which its modules do not declare",
                p.name
            );
        }
    }
    let unused: Vec<&str> = manifest
        .modules
        .iter()
        .map(|m| m.name.as_str())
        .filter(|n| !used.contains(n))
        .collect();
    assert_eq!(
        unused, STANDALONE,
        "modules no pipeline uses (checked only by the package consumer)"
    );
}

/// Every file under `dir`, relative, sorted.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("readable package directory") {
            let p = e.expect("a directory entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

#[test]
fn two_writes_are_byte_identical() {
    let (a, ma) = write_temp();
    let (b, mb) = write_temp();
    assert_eq!(ma, mb);
    let (fa, fb) = (files(a.path()), files(b.path()));
    assert_eq!(fa, fb, "the two packages hold different files");
    for f in &fa {
        let (x, y) = (
            std::fs::read(a.path().join(f)).unwrap(),
            std::fs::read(b.path().join(f)).unwrap(),
        );
        assert!(x == y, "{} differs between two writes", f.display());
    }
    // Writing again over a package changes nothing either.
    package::write_package(a.path()).expect("rewrite");
    for f in &fa {
        assert_eq!(
            std::fs::read(a.path().join(f)).unwrap(),
            std::fs::read(b.path().join(f)).unwrap(),
            "{}",
            f.display()
        );
    }
}

/// Checks that every JSON object's keys are in sorted order as written.
fn keys_sorted(v: &serde_json::Value, at: &str) {
    match v {
        serde_json::Value::Object(map) => {
            let keys: Vec<&String> = map.keys().collect();
            let mut s = keys.clone();
            s.sort();
            assert_eq!(keys, s, "keys of {at} are not sorted");
            for (k, x) in map {
                keys_sorted(x, &format!("{at}.{k}"));
            }
        }
        serde_json::Value::Array(items) => items
            .iter()
            .enumerate()
            .for_each(|(i, x)| keys_sorted(x, &format!("{at}[{i}]"))),
        _ => {}
    }
}

#[test]
fn manifest_lists_every_module_with_correct_hashes_and_sizes() {
    let (dir, manifest) = write_temp();
    let text = std::fs::read_to_string(dir.path().join("manifest.json")).expect("manifest.json");
    assert_eq!(text, manifest.to_json());
    let json: serde_json::Value = serde_json::from_str(&text).expect("manifest.json is JSON");
    keys_sorted(&json, "manifest");
    assert_eq!(json["format_version"], package::FORMAT_VERSION);
    assert_eq!(json["compiler"], shaders::COMPILER);
    assert_eq!(json["weft_version"], env!("CARGO_PKG_VERSION"));

    let mut names: Vec<&str> = shaders::ALL.iter().map(|s| s.name).collect();
    names.sort();
    let listed: Vec<&str> = manifest.modules.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(listed, names, "the manifest must list every module, sorted");
    let json_names: Vec<&str> = json["modules"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(json_names, names);

    let readme = std::fs::read_to_string(dir.path().join("README.md")).expect("README.md");
    let mut embedded: Vec<_> = shaders::ALL.iter().collect();
    embedded.sort_by_key(|s| s.name);
    for (m, shader) in manifest.modules.iter().zip(embedded) {
        let bytes =
            std::fs::read(dir.path().join(&m.file)).unwrap_or_else(|e| panic!("{}: {e}", m.file));
        assert_eq!(m.file, format!("{}.spv", m.name));
        assert_eq!(bytes, shader.spirv, "{} is not the embedded module", m.file);
        assert_eq!(m.sha256, package::sha256_hex(&bytes), "{}: hash", m.name);
        assert_eq!(m.size, bytes.len() as u64, "{}: size", m.name);
        assert_eq!(m.sha256.len(), 64);
        assert_eq!(m.stage, shader.stage);
        assert_eq!(m.entry_point, "main");
        assert!(
            m.capabilities.iter().any(|c| c == "Shader"),
            "{}: {:?}",
            m.name,
            m.capabilities
        );
        assert_eq!(
            m.workgroup_size.is_some(),
            m.stage == Stage::Compute,
            "{}: a workgroup size exactly for compute",
            m.name
        );
        assert!(
            readme.contains(&format!("### {}", m.name)),
            "README.md has no section for {}",
            m.name
        );
        assert!(
            package::module_notes(&m.name).is_some(),
            "{}: no entry in package::MODULE_NOTES",
            m.name
        );
        for b in &m.bindings {
            assert!(
                b.meaning.is_some(),
                "{} set {} binding {}: no comment at its GLSL declaration (package::binding_comment)",
                m.name,
                b.set,
                b.binding
            );
            assert!(
                b.count >= 1,
                "{}: binding {} count {}",
                m.name,
                b.binding,
                b.count
            );
        }
        for c in &m.spec_constants {
            assert!(
                c.meaning.is_some(),
                "{} constant {}: no entry in package::SPEC_MEANINGS",
                m.name,
                c.constant.id
            );
        }
    }
    let weave = manifest.module("weave.comp").expect("weave.comp");
    assert_eq!(weave.workgroup_size.unwrap().size, [8, 8, 1]);
    assert_eq!(
        weave.push_constants.map(|p| (p.offset, p.size)),
        Some((0, std::mem::size_of::<weft::fabric::WeavePush>() as u32))
    );
    let b = &weave.bindings[0];
    assert_eq!(
        (
            weave.bindings.len(),
            b.set,
            b.binding,
            b.kind,
            b.image_format
        ),
        (1, 0, 0, DescriptorKind::StorageImage, Some("rgba16f"))
    );
    let probe = manifest
        .module("fabric_probe.comp")
        .expect("fabric_probe.comp");
    assert_eq!(probe.workgroup_size.unwrap().size, [64, 1, 1]);
    assert_eq!(
        probe.push_constants.map(|p| (p.offset, p.size)),
        Some((0, 4))
    );
    let strides: Vec<_> = probe
        .bindings
        .iter()
        .map(|b| (b.binding, b.kind, b.runtime_array_stride))
        .collect();
    assert_eq!(
        strides,
        vec![
            (
                0,
                DescriptorKind::StorageBuffer,
                Some(std::mem::size_of::<weft::reference::ProbeInput>() as u32)
            ),
            (
                1,
                DescriptorKind::StorageBuffer,
                Some(std::mem::size_of::<weft::reference::ProbeOutput>() as u32)
            ),
        ]
    );

    // The prose states numbers the code owns: keep them in step.
    let notes = package::module_notes("weave.comp").unwrap();
    for needle in [
        format!(
            "{} texels per weave cell",
            weft::fabric::WEAVE_TEXELS_PER_CELL
        ),
        format!("{}-byte `WeavePush`", weave.push_constants.unwrap().size),
        format!(
            "ceil(width / {}) × ceil(height / {})",
            weave.workgroup_size.unwrap().size[0],
            weave.workgroup_size.unwrap().size[1]
        ),
    ] {
        assert!(
            notes.contains(&needle),
            "MODULE_NOTES of weave.comp should say \"{needle}\""
        );
    }
    let notes = package::module_notes("fabric_probe.comp").unwrap();
    for needle in [
        format!(
            "{}-byte `ProbeInput`",
            std::mem::size_of::<weft::reference::ProbeInput>()
        ),
        format!(
            "{}-byte `ProbeOutput`",
            std::mem::size_of::<weft::reference::ProbeOutput>()
        ),
        format!("ceil(count / {})", probe.workgroup_size.unwrap().size[0]),
    ] {
        assert!(
            notes.contains(&needle),
            "MODULE_NOTES of fabric_probe.comp should say \"{needle}\""
        );
    }

    // The hand-written tables name only what exists.
    for (name, _) in package::MODULE_NOTES {
        assert!(
            manifest.module(name).is_some(),
            "MODULE_NOTES names {name}, which is not a module"
        );
    }
    // Binding prose comes from the comment at each GLSL declaration: the module's own (lighting.frag
    // declares its G-buffer reads) and an include's (surface.glsl declares the material textures
    // gbuffer.frag and forward.frag both bind).
    let meaning = |module: &str, set: u32, binding: u32| {
        manifest
            .module(module)
            .and_then(|m| {
                m.bindings
                    .iter()
                    .find(|b| b.set == set && b.binding == binding)
            })
            .and_then(|b| b.meaning.clone())
            .unwrap_or_default()
    };
    assert!(meaning("lighting.frag", 0, 25).contains("depth (D32)"));
    assert!(meaning("gbuffer.frag", 1, 0).contains("base colour texture"));
    assert_eq!(meaning("gbuffer.frag", 1, 4), meaning("forward.frag", 1, 4));
    // A block over several lines: the comment on its member line.
    assert!(meaning("fabric_probe.comp", 0, 1).starts_with("the outputs"));
    for (name, id, _) in package::SPEC_MEANINGS {
        let m = manifest
            .module(name)
            .unwrap_or_else(|| panic!("SPEC_MEANINGS names {name}, which is not a module"));
        assert!(
            m.spec_constants.iter().any(|c| c.constant.id == *id),
            "SPEC_MEANINGS names {name} constant {id}, which it lacks"
        );
    }
}

#[test]
fn includes_are_the_projects_glsl_include_directory() {
    let (dir, manifest) = write_temp();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl/include");
    let mut expected: Vec<String> = std::fs::read_dir(&src)
        .unwrap()
        .map(|e| format!("include/{}", e.unwrap().file_name().to_string_lossy()))
        .collect();
    expected.sort();
    let listed: Vec<&str> = manifest.includes.iter().map(|f| f.file.as_str()).collect();
    assert_eq!(
        listed, expected,
        "package::INCLUDES must list every file of glsl/include/"
    );
    for f in &manifest.includes {
        let shipped = std::fs::read(dir.path().join(&f.file)).unwrap();
        let source = std::fs::read(src.join(f.file.trim_start_matches("include/"))).unwrap();
        assert!(shipped == source, "{} differs from glsl/{}", f.file, f.file);
        assert_eq!(f.sha256, package::sha256_hex(&shipped));
        assert_eq!(f.size, shipped.len() as u64);
    }
}

#[test]
fn rewriting_removes_modules_an_older_package_listed_and_nothing_else() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let d = &dir.path().join("package");
    package::write_package(d).expect("write the package");
    // Pretend an older package had a module that no longer exists, and a hostile entry.
    let mut old: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("manifest.json")).unwrap()).unwrap();
    old["modules"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"name": "gone.comp", "file": "gone.comp.spv"}));
    old["modules"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"name": "evil", "file": "../outside.spv"}));
    std::fs::write(d.join("manifest.json"), old.to_string()).unwrap();
    std::fs::write(d.join("gone.comp.spv"), b"old").unwrap();
    std::fs::write(d.join("notes.txt"), b"mine").unwrap();
    std::fs::write(dir.path().join("outside.spv"), b"not the package's").unwrap();
    package::write_package(d).expect("rewrite");
    assert!(
        !d.join("gone.comp.spv").exists(),
        "a module the old manifest listed was left behind"
    );
    assert!(
        d.join("notes.txt").exists(),
        "a file the package never wrote was removed"
    );
    assert!(
        dir.path().join("outside.spv").exists(),
        "a path outside the package was removed"
    );
}

/// The frame's shaders give each resource of set 0 one number (issue 24): a block or sampler of
/// the same name has the same binding in every shader that declares it, and no binding holds two
/// different resources.
#[test]
fn one_number_per_resource_in_the_frames_shaders() {
    // The G-buffer's and the lighting pass's declarations are in their modules' shared bodies.
    let include = |name: &str| {
        package::INCLUDES
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("include/{name}"))
            .1
    };
    let lighting_main = include("lighting_main.glsl");
    let frame_shaders = [
        (shaders::GBUFFER_VERT.name, shaders::GBUFFER_VERT.source),
        ("include/gbuffer_main.glsl", include("gbuffer_main.glsl")),
        ("include/forward_main.glsl", include("forward_main.glsl")),
        ("include/lighting_main.glsl", lighting_main),
        (
            shaders::SHADOW_MASK_VERT.name,
            shaders::SHADOW_MASK_VERT.source,
        ),
        (
            shaders::SHADOW_MASK_FRAG.name,
            shaders::SHADOW_MASK_FRAG.source,
        ),
    ];
    let mut by_name: BTreeMap<String, (u32, &str)> = BTreeMap::new();
    let mut by_number: BTreeMap<u32, (String, &str)> = BTreeMap::new();
    let mut declarations = 0;
    for (shader_name, source) in frame_shaders {
        for line in source.lines() {
            let code = line.split("//").next().unwrap_or("").trim();
            let Some(rest) = code.strip_prefix("layout(set = 0, binding = ") else {
                continue;
            };
            let number: u32 = rest
                .split(|c: char| !c.is_ascii_digit())
                .next()
                .and_then(|n| n.parse().ok())
                .unwrap_or_else(|| panic!("{}: unreadable binding in `{code}`", shader_name));
            // The block's name (`buffer Lights {`), else the variable's (`sampler2D gb_depth;`).
            let after = &rest[rest.find(')').expect("layout(...)") + 1..];
            let words: Vec<&str> = after
                .split(|c: char| c.is_whitespace() || c == ';')
                .filter(|w| !w.is_empty())
                .collect();
            let name = match words.iter().position(|w| *w == "{") {
                Some(brace) => words[brace - 1],
                None => words[words.len() - 1],
            }
            .to_string();
            declarations += 1;
            if let Some((n, other)) = by_name.get(&name) {
                assert_eq!(
                    *n, number,
                    "{name} is binding {n} in {other} and {number} in {}",
                    shader_name
                );
            }
            if let Some((other_name, other)) = by_number.get(&number) {
                assert_eq!(
                    *other_name, name,
                    "set 0 binding {number} is {other_name} in {other} and {name} in {}",
                    shader_name
                );
            }
            by_name.insert(name.clone(), (number, shader_name));
            by_number.insert(number, (name, shader_name));
        }
    }
    assert!(
        declarations >= 30,
        "only {declarations} set-0 declarations read"
    );
    assert_eq!(by_name["Lights"].0, 3);
    assert_eq!(by_name["Materials"].0, 1);
    assert_eq!(by_name["Fabrics"].0, 2);
}
