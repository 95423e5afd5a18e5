//! The manifest: each embedded module reflected from its SPIR-V into a [`ModuleEntry`], and
//! `manifest.json`'s text.

use sha2::{Digest, Sha256};

use super::{
    binding_comment, spirv, Access, DescriptorKind, InterfaceVariable, PushConstantRange,
    SpecConstant, SpecValue, WorkgroupSize, FORMAT_VERSION, INCLUDES, SPEC_MEANINGS,
    SPEC_MEANINGS_OF,
};
use crate::vk::{shaders, Shader, Stage};
use crate::Error;

/// The package's table of contents: what `manifest.json` holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    pub format_version: u32,
    /// The compiler that made the modules (`weft::vk::shaders::COMPILER`).
    pub compiler: String,
    pub weft_version: String,
    /// Sorted by name.
    pub modules: Vec<ModuleEntry>,
    /// The files under `include/`, sorted.
    pub includes: Vec<FileEntry>,
}

/// One shader module, as reflected from its SPIR-V.
#[derive(Clone, Debug, PartialEq)]
pub struct ModuleEntry {
    /// The source file name, e.g. `lighting.frag`.
    pub name: String,
    /// The file in the package, e.g. `lighting.frag.spv`.
    pub file: String,
    pub stage: Stage,
    pub entry_point: String,
    /// SPIR-V version, e.g. "1.6".
    pub spirv_version: String,
    pub capabilities: Vec<String>,
    pub extensions: Vec<String>,
    /// Sorted by (set, binding).
    pub bindings: Vec<BindingEntry>,
    pub push_constants: Option<PushConstantRange>,
    /// Sorted by id.
    pub spec_constants: Vec<SpecEntry>,
    pub workgroup_size: Option<WorkgroupSize>,
    pub inputs: Vec<InterfaceVariable>,
    pub outputs: Vec<InterfaceVariable>,
    /// Lower-case hex SHA-256 of the .spv file.
    pub sha256: String,
    pub size: u64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct BindingEntry {
    pub set: u32,
    pub binding: u32,
    pub kind: DescriptorKind,
    /// Descriptors in the binding (array size); 0 = runtime-sized.
    pub count: u32,
    pub access: Access,
    pub image_format: Option<&'static str>,
    pub block_size: Option<u32>,
    pub runtime_array_stride: Option<u32>,
    /// The comment at the binding's GLSL declaration ([`binding_comment`]); None when it has none.
    pub meaning: Option<String>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct SpecEntry {
    pub constant: SpecConstant,
    /// From [`SPEC_MEANINGS`]; None when the table has no entry.
    pub meaning: Option<&'static str>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileEntry {
    /// Path inside the package, `/`-separated.
    pub file: String,
    pub sha256: String,
    pub size: u64,
}

/// Lower-case hex SHA-256.
pub fn sha256_hex(bytes: &[u8]) -> String {
    format!("{:x}", Sha256::digest(bytes))
}

pub fn stage_name(stage: Stage) -> &'static str {
    match stage {
        Stage::Vertex => "vertex",
        Stage::Fragment => "fragment",
        Stage::Compute => "compute",
    }
}

/// The `VkShaderStageFlagBits` value of a stage.
pub fn stage_vk_bit(stage: Stage) -> u32 {
    match stage {
        Stage::Vertex => 0x1,
        Stage::Fragment => 0x10,
        Stage::Compute => 0x20,
    }
}

/// The SPIR-V execution model a stage's module must have.
fn execution_model(stage: Stage) -> u32 {
    match stage {
        Stage::Vertex => 0,
        Stage::Fragment => 4,
        Stage::Compute => 5,
    }
}

/// Reflects one embedded module into its manifest entry.
pub fn reflect_module(shader: &Shader) -> crate::Result<ModuleEntry> {
    let bad = |what: String| {
        Error::device(format!(
            "embedded SPIR-V of {} cannot be reflected: {what}",
            shader.name
        ))
    };
    let r = spirv::reflect(shader.spirv).map_err(|e| bad(e.to_string()))?;
    if r.execution_model != execution_model(shader.stage) {
        return Err(bad(format!(
            "its entry point is a {} shader, the build table says {}",
            spirv::execution_model_name(r.execution_model),
            stage_name(shader.stage)
        )));
    }
    let name = shader.name;
    let bindings = r
        .bindings
        .into_iter()
        .map(|b| BindingEntry {
            meaning: binding_comment(shader, b.set, b.binding),
            set: b.set,
            binding: b.binding,
            kind: b.kind,
            count: b.count,
            access: b.access,
            image_format: b.image_format,
            block_size: b.block_size,
            runtime_array_stride: b.runtime_array_stride,
        })
        .collect();
    let spec_constants = r
        .spec_constants
        .into_iter()
        .map(|c| SpecEntry {
            meaning: SPEC_MEANINGS
                .iter()
                .find(|(m, id, _)| {
                    let of = SPEC_MEANINGS_OF.iter().find(|o| o.0 == name).map(|o| o.1);
                    (*m == name || Some(*m) == of) && *id == c.id
                })
                .map(|e| e.2),
            constant: c,
        })
        .collect();
    Ok(ModuleEntry {
        name: name.to_string(),
        file: format!("{name}.spv"),
        stage: shader.stage,
        entry_point: r.entry_point,
        spirv_version: format!("{}.{}", r.version.0, r.version.1),
        capabilities: r.capabilities,
        extensions: r.extensions,
        bindings,
        push_constants: r.push_constants,
        spec_constants,
        workgroup_size: r.workgroup_size,
        inputs: r.inputs,
        outputs: r.outputs,
        sha256: sha256_hex(shader.spirv),
        size: shader.spirv.len() as u64,
    })
}

/// The manifest of every embedded module, without writing anything.
pub fn manifest() -> crate::Result<Manifest> {
    let mut shaders: Vec<&Shader> = shaders::ALL.iter().collect();
    shaders.sort_by_key(|s| s.name);
    let modules = shaders
        .into_iter()
        .map(reflect_module)
        .collect::<crate::Result<Vec<_>>>()?;
    let mut includes: Vec<FileEntry> = INCLUDES
        .iter()
        .map(|(name, text)| FileEntry {
            file: format!("include/{name}"),
            sha256: sha256_hex(text.as_bytes()),
            size: text.len() as u64,
        })
        .collect();
    includes.sort_by(|a, b| a.file.cmp(&b.file));
    Ok(Manifest {
        format_version: FORMAT_VERSION,
        compiler: shaders::COMPILER.to_string(),
        weft_version: env!("CARGO_PKG_VERSION").to_string(),
        modules,
        includes,
    })
}

/// A JSON value with every object's keys in sorted order, whatever serde_json's map keeps.
fn sorted(v: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Object(map) => {
            let mut entries: Vec<(String, Value)> = map.into_iter().collect();
            entries.sort_by(|a, b| a.0.cmp(&b.0));
            Value::Object(entries.into_iter().map(|(k, v)| (k, sorted(v))).collect())
        }
        Value::Array(items) => Value::Array(items.into_iter().map(sorted).collect()),
        other => other,
    }
}

impl SpecValue {
    fn json(&self) -> serde_json::Value {
        match *self {
            SpecValue::Bool(b) => b.into(),
            SpecValue::Int(i) => i.into(),
            SpecValue::UInt(u) => u.into(),
            SpecValue::Float(f) => f.into(),
        }
    }
}

impl std::fmt::Display for SpecValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SpecValue::Bool(b) => write!(f, "{b}"),
            SpecValue::Int(i) => write!(f, "{i}"),
            SpecValue::UInt(u) => write!(f, "{u}"),
            SpecValue::Float(x) => write!(f, "{x:?}"),
        }
    }
}

impl ModuleEntry {
    fn json(&self) -> serde_json::Value {
        use serde_json::json;
        let bindings: Vec<_> = self
            .bindings
            .iter()
            .map(|b| {
                let mut v = json!({
                    "set": b.set,
                    "binding": b.binding,
                    "type": b.kind.name(),
                    "vk_descriptor_type": b.kind.vk_value(),
                    "count": b.count,
                    "access": b.access.name(),
                    "meaning": b.meaning,
                });
                if let Some(f) = b.image_format {
                    v["image_format"] = f.into();
                }
                if let Some(s) = b.block_size {
                    v["block_size"] = s.into();
                }
                if let Some(s) = b.runtime_array_stride {
                    v["runtime_array_stride"] = s.into();
                }
                v
            })
            .collect();
        let spec: Vec<_> = self
            .spec_constants
            .iter()
            .map(|c| json!({"id": c.constant.id, "type": c.constant.ty, "default": c.constant.default.json(), "meaning": c.meaning}))
            .collect();
        let io = |vars: &[InterfaceVariable]| -> Vec<serde_json::Value> {
            vars.iter()
                .map(|v| json!({"location": v.location, "type": v.ty}))
                .collect()
        };
        let mut v = json!({
            "name": self.name,
            "file": self.file,
            "stage": stage_name(self.stage),
            "vk_shader_stage": stage_vk_bit(self.stage),
            "entry_point": self.entry_point,
            "spirv_version": self.spirv_version,
            "capabilities": self.capabilities,
            "extensions": self.extensions,
            "descriptor_bindings": bindings,
            "push_constants": self.push_constants.map(|p| json!({"offset": p.offset, "size": p.size})),
            "specialization_constants": spec,
            "inputs": io(&self.inputs),
            "outputs": io(&self.outputs),
            "sha256": self.sha256,
            "size": self.size,
        });
        if let Some(w) = self.workgroup_size {
            v["workgroup_size"] = json!(w.size);
            if w.spec_ids.iter().any(Option::is_some) {
                v["workgroup_size_spec_ids"] = json!(w.spec_ids);
            }
        }
        v
    }
}

impl Manifest {
    /// `manifest.json`'s text: pretty-printed, keys sorted, ending in a newline.
    pub fn to_json(&self) -> String {
        use serde_json::json;
        let v = json!({
            "format": "weft-spirv-package",
            "format_version": self.format_version,
            "compiler": self.compiler,
            "weft_version": self.weft_version,
            "modules": self.modules.iter().map(ModuleEntry::json).collect::<Vec<_>>(),
            "includes": self.includes.iter().map(|f| json!({"file": f.file, "sha256": f.sha256, "size": f.size})).collect::<Vec<_>>(),
        });
        let mut text =
            serde_json::to_string_pretty(&sorted(v)).expect("a JSON value always serialises");
        text.push('\n');
        text
    }

    pub fn module(&self, name: &str) -> Option<&ModuleEntry> {
        self.modules.iter().find(|m| m.name == name)
    }
}
