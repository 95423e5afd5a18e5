//! Cross-checks weft's SPIR-V reader (`weft::package::spirv::reflect`, which the shader package's
//! manifest is made from) against spirq, an independent reflection library, on every shipped
//! module in glsl/spirv/: entry point, execution model, descriptor bindings (set, binding, kind,
//! array size, uniform block size), push constant size, specialization constant ids and the
//! user interface locations must agree. (spirq 1.3 cannot read lighting.frag, lighting_woven.frag,
//! forward.frag or forward_gltf.frag: it fails to evaluate an OpSpecConstantOp comparison; those
//! modules are compared against spirv-dis by tests/package.rs instead.)

use std::collections::BTreeSet;
use std::path::Path;

use spirq::ty::DescriptorType;
use spirq::var::Variable;
use weft::package::spirv::{reflect, DescriptorKind};

fn kind(t: &DescriptorType) -> DescriptorKind {
    match t {
        DescriptorType::Sampler() => DescriptorKind::Sampler,
        DescriptorType::CombinedImageSampler() => DescriptorKind::CombinedImageSampler,
        DescriptorType::SampledImage() => DescriptorKind::SampledImage,
        DescriptorType::StorageImage(_) => DescriptorKind::StorageImage,
        DescriptorType::UniformTexelBuffer() => DescriptorKind::UniformTexelBuffer,
        DescriptorType::StorageTexelBuffer(_) => DescriptorKind::StorageTexelBuffer,
        DescriptorType::UniformBuffer() => DescriptorKind::UniformBuffer,
        DescriptorType::StorageBuffer(_) => DescriptorKind::StorageBuffer,
        DescriptorType::InputAttachment(_) => DescriptorKind::InputAttachment,
        DescriptorType::AccelStruct() => DescriptorKind::AccelerationStructure,
    }
}

#[test]
fn weft_and_spirq_agree_on_every_shipped_module() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl/spirv");
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "spv"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 10, "only {} modules", paths.len());
    let mut unreadable = Vec::new();
    for path in &paths {
        let name = path.file_name().unwrap().to_string_lossy();
        let bytes = std::fs::read(path).unwrap();
        let ours = reflect(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        let theirs = match spirq::ReflectConfig::new()
            .spv(bytes.as_slice())
            .ref_all_rscs(true)
            .reflect()
        {
            Ok(t) => t,
            // spirq 1.3 cannot evaluate an OpSpecConstantOp comparison (a bool result):
            // include/shade.glsl has one where a module's code keeps it: lighting.frag,
            // lighting_woven.frag, forward.frag and forward_gltf.frag. Only that failure is let
            // through, for those four modules only.
            Err(e) if e.to_string().starts_with("cannot evaluate") => {
                println!("{name}: spirq cannot read it ({e}); not compared");
                unreadable.push(name.to_string());
                continue;
            }
            Err(e) => panic!("{name}: spirq: {e}"),
        };
        assert_eq!(theirs.len(), 1, "{name}: one entry point");
        let ep = &theirs[0];
        assert_eq!(ours.entry_point, ep.name, "{name}");
        assert_eq!(ours.execution_model, ep.exec_model as u32, "{name}");

        let mut bindings = BTreeSet::new();
        let mut push = None;
        let mut spec_ids = BTreeSet::new();
        let (mut inputs, mut outputs) = (BTreeSet::new(), BTreeSet::new());
        for var in &ep.vars {
            match var {
                Variable::Descriptor {
                    desc_bind,
                    desc_ty,
                    ty,
                    nbind,
                    ..
                } => {
                    let size = match desc_ty {
                        DescriptorType::UniformBuffer() => ty.nbyte().map(|n| n as u32),
                        _ => None,
                    };
                    bindings.insert((
                        desc_bind.set(),
                        desc_bind.bind(),
                        kind(desc_ty),
                        *nbind,
                        size,
                    ));
                }
                Variable::PushConstant { ty, .. } => push = ty.nbyte().map(|n| n as u32),
                Variable::SpecConstant { spec_id, .. } => {
                    spec_ids.insert(*spec_id);
                }
                Variable::Input { location, .. } => {
                    inputs.insert(location.loc());
                }
                Variable::Output { location, .. } => {
                    outputs.insert(location.loc());
                }
            }
        }
        let our_bindings: BTreeSet<_> = ours
            .bindings
            .iter()
            .map(|b| {
                let size = (b.kind == DescriptorKind::UniformBuffer)
                    .then_some(b.block_size)
                    .flatten();
                (b.set, b.binding, b.kind, b.count, size)
            })
            .collect();
        assert_eq!(our_bindings, bindings, "{name}: descriptor bindings");
        assert_eq!(
            ours.push_constants.map(|p| p.offset + p.size),
            push,
            "{name}: push constant size"
        );
        let our_specs: BTreeSet<u32> = ours.spec_constants.iter().map(|s| s.id).collect();
        assert_eq!(our_specs, spec_ids, "{name}: specialization constants");
        let our_in: BTreeSet<u32> = ours.inputs.iter().map(|v| v.location).collect();
        let our_out: BTreeSet<u32> = ours.outputs.iter().map(|v| v.location).collect();
        assert_eq!(our_in, inputs, "{name}: inputs");
        assert_eq!(our_out, outputs, "{name}: outputs");
        println!(
            "{name}: {} bindings, push {:?}, {} spec constants, {} in, {} out: agree",
            bindings.len(),
            push,
            spec_ids.len(),
            inputs.len(),
            outputs.len()
        );
    }
    assert!(
        unreadable.iter().all(|n| [
            "lighting.frag.spv",
            "lighting_woven.frag.spv",
            "forward.frag.spv",
            "forward_gltf.frag.spv"
        ]
        .contains(&n.as_str())),
        "spirq read too few modules to be a check: it could not read {unreadable:?}"
    );
}
